// The surface spec (surface/surface_spec.hpp): presets, suite entries and command-line options
// give the same surface; the table's defaults are the generators' own; bad keys and values are
// refused with one clear line, and values just inside the ranges are accepted (power).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "../src/cli/option_checks.hpp"
#include "cli_helpers.hpp"
#include "microsim/common.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/surface_spec.hpp"
#include "microsim/validate/validate.hpp"

using namespace microsim;
using microsim::testing::Result;
using microsim::testing::slurp;
using microsim::testing::temp_path;

namespace {

const std::string kSurfaces = std::string(MICROSIM_SOURCE_DIR) + "/surfaces/";

std::string write(const std::string& name, const std::string& text) {
  const std::string p = temp_path("spec", name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

// The saved bytes of a surface (the file and, for meshes, its sidecar).
std::string saved(const Microsurface& s, const std::string& name) {
  const std::string p = temp_path("spec", name);
  save_surface(s, p);
  return slurp(p) + (extension_of(p) == "exr" ? "" : slurp(p + ".json"));
}

// `microsim ARGS` (parameterized test names hold '/', so the capture files are named here).
Result run(const std::string& args, const std::string& name) {
  const std::string err = temp_path("spec", name + "_stderr.txt");
  const int status = std::system((microsim::testing::binary() + " " + args + " >/dev/null 2>" + err).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, "", slurp(err)};
}

std::string saved_file(const std::string& p) { return slurp(p) + (extension_of(p) == "exr" ? "" : slurp(p + ".json")); }

// The message of the UsageError `f` throws as the command line prints it, its parameters named
// as options ("" when it does not throw).
template <class F>
std::string refusal(F f) {
  try {
    f();
  } catch (const UsageError& e) {
    return cli::cli_message(e);
  }
  return "";
}

struct Preset {
  std::string file, kind, ext;
  std::string shrink;  // options that keep the test fast (the same on every route)
};
std::ostream& operator<<(std::ostream& os, const Preset& p) { return os << p.file; }

class PresetRoutes : public ::testing::TestWithParam<Preset> {};

// A preset read by the library, the same preset through `generate KIND --config`, and its keys
// spelled as command-line options give byte-identical surfaces.
TEST_P(PresetRoutes, LibraryPresetEqualsCommandLine) {
  const Preset& p = GetParam();
  SurfaceRequest r{p.kind, {}};
  read_surface_preset(r, kSurfaces + p.file);
  ASSERT_FALSE(r.options.empty());
  std::string options;
  for (const auto& [key, value] : r.options)
    if (p.shrink.find("--" + key + " ") == std::string::npos) options += " --" + key + " " + value;
  std::istringstream shrink(p.shrink);
  for (std::string key, value; shrink >> key >> value;) set_surface_option(r, key.substr(2), value);
  const std::string base = p.file.substr(0, p.file.size() - 5);
  const std::string from_config = temp_path("spec", base + "-config." + p.ext),
                    from_options = temp_path("spec", base + "-options." + p.ext);
  auto a = run("-q generate " + p.kind + " --config " + kSurfaces + p.file + " " + p.shrink + " -o " + from_config, base);
  ASSERT_EQ(a.code, 0) << a.err;
  auto b = run("-q generate " + p.kind + options + " " + p.shrink + " -o " + from_options, base);
  ASSERT_EQ(b.code, 0) << options << "\n" << b.err;
  const std::string library = saved(generate_surface(r), base + "-library." + p.ext);
  EXPECT_EQ(library, saved_file(from_config));
  EXPECT_EQ(library, saved_file(from_options));
  // Power: the first numeric option with a value, changed, gives another surface.
  for (const SurfaceOption& o : surface_kind(p.kind).options) {
    const bool numeric = o.type == SurfaceOption::Type::Integer || o.type == SurfaceOption::Type::Number;
    const std::string v = r.options.count(o.name) ? r.options.at(o.name) : o.default_text;
    if (!numeric || v.empty()) continue;
    SurfaceRequest other = r;
    set_surface_option(other, o.name, std::to_string(std::stoi(v) + 1));
    EXPECT_NE(saved(generate_surface(other), base + "-other." + p.ext), library) << o.name;
    break;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Presets, PresetRoutes,
    ::testing::Values(Preset{"beckmann-0.5.toml", "gaussian", "exr", "--resolution 64 --correlation-length 0.0625 "},
                      Preset{"beckmann-1.0-converged.toml", "gaussian", "exr", "--resolution 64 --correlation-length 0.0625 "},
                      Preset{"beckmann-1.0-fine.toml", "gaussian", "exr", "--resolution 64 --correlation-length 0.0625 "},
                      Preset{"gaussian-ggx.toml", "gaussian-ggx", "exr", "--resolution 64 --correlation-length 0.03125 "},
                      Preset{"flat.toml", "flat", "exr", ""}, Preset{"box.toml", "box", "ply", ""},
                      Preset{"tiled-boxes.toml", "tiled-boxes", "ply", ""},
                      Preset{"square-wave.toml", "square-wave", "ply", ""}, Preset{"vgroove.toml", "vgroove", "exr", ""},
                      Preset{"vcavity.toml", "vcavity", "ply", "--grooves 64 "},
                      Preset{"parallelepiped.toml", "parallelepiped", "ply", ""},
                      Preset{"ellipsoid.toml", "ellipsoid", "ply", "--rings 16 --segments 64 "}),
    [](const ::testing::TestParamInfo<Preset>& i) {
      std::string n = i.param.file.substr(0, i.param.file.size() - 5);
      for (char& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return n;
    });

// Every shipped preset names a kind's options only (mesh-example needs an input, so it is read
// but not generated).
TEST(SurfaceSpec, EveryShippedPresetReads) {
  int read = 0;
  for (const auto& f : std::filesystem::directory_iterator(kSurfaces)) {
    if (f.path().extension() != ".toml") continue;
    std::string stem = f.path().stem().string(), kind = stem;
    if (stem.rfind("beckmann", 0) == 0) kind = "gaussian";
    if (stem == "mesh-example") kind = "mesh";
    SurfaceRequest r{kind, {}};
    EXPECT_NO_THROW(read_surface_preset(r, f.path().string())) << stem;
    ++read;
  }
  EXPECT_GE(read, 13);
}

// Every default the table shows passes its own check and is the generator's default: all of a
// kind's defaults given explicitly build the same surface as none given.
TEST(SurfaceSpec, TableDefaultsAreTheGeneratorsDefaults) {
  for (const SurfaceKind& kind : surface_kinds()) {
    if (kind.name == "mesh" || kind.name == "heightmap") continue;  // need an input file
    SurfaceRequest none{kind.name, {}}, all{kind.name, {}};
    for (const SurfaceOption& o : kind.options)
      if (!o.default_text.empty()) set_surface_option(all, o.name, o.default_text);
    // Cheap sizes on both sides (the defaults of these are checked by the comparison above).
    for (const char* small : {"resolution", "grooves"})
      if (kind.option(small)) {
        set_surface_option(none, small, "32");
        set_surface_option(all, small, "32");
      }
    if (kind.option("rings")) {
      for (auto* r : {&none, &all}) set_surface_option(*r, "rings", "8"), set_surface_option(*r, "segments", "32");
    }
    const std::string ext = kind.name == "gaussian" || kind.name == "gaussian-ggx" || kind.name == "flat" ||
                                    kind.name == "vgroove" ? "exr" : "ply";
    EXPECT_EQ(saved(generate_surface(all), kind.name + "-all." + ext), saved(generate_surface(none), kind.name + "-none." + ext))
        << kind.name;
  }
  // Power: a default shown wrongly (the box's height as 0.5) gives another surface.
  SurfaceRequest wrong{"box", {{"height", "0.5"}}}, right{"box", {}};
  EXPECT_NE(saved(generate_surface(wrong), "box-wrong.ply"), saved(generate_surface(right), "box-right.ply"));
}

TEST(SurfaceSpec, UnknownKeysAndBadValuesAreRefused) {
  SurfaceRequest r{"gaussian", {}};
  std::string m = refusal([&] { read_surface_preset(r, write("unknown.toml", "resolution = 64\nresolutionn = 32\n")); });
  EXPECT_NE(m.find("unknown.toml: line 2: unknown option 'resolutionn' for 'gaussian' (known: resolution, size,"),
            std::string::npos) << m;
  m = refusal([&] { read_surface_preset(r, write("range.toml", "alpha = -1\n")); });
  EXPECT_NE(m.find("range.toml: line 1: --alpha: must be a finite number in (0, 10] (got -1)"), std::string::npos) << m;
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("int.toml", "resolution = 32.5\n")); }).find("--resolution"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("seed.toml", "seed = -1\n")); }).find("--seed"), std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("array.toml", "alpha = [0.3, 0.4]\n")); }).find("array"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("twice.toml", "alpha = 0.3\nalpha = 0.4\n")); }).find("twice"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("section.toml", "[gaussian]\nalpha = 0.3\n")); }).find("sections"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("line.toml", "alpha 0.3\n")); }).find("key = value"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, write("bin.toml", std::string("\x7f" "ELF\0\0", 6))); }).find("control byte"),
            std::string::npos);
  EXPECT_NE(refusal([&] { read_surface_preset(r, temp_path("spec", "missing.toml")); }).find("no such preset"),
            std::string::npos);
  SurfaceRequest flag{"square-wave", {}};
  EXPECT_NE(refusal([&] { read_surface_preset(flag, write("flag.toml", "2d = 3\n")); }).find("--2d: expected true or false"),
            std::string::npos);
  EXPECT_NE(refusal([] { surface_kind("sphere"); }).find("unknown surface kind 'sphere' (known: gaussian, flat,"),
            std::string::npos);
  // Combinations are the generator's: --alpha with --alpha-x, --matrix with a shear.
  EXPECT_EQ(refusal([] { generate_surface({"gaussian", {{"alpha", "0.3"}, {"alpha-x", "0.2"}}}); }),
            "--alpha cannot be combined with --alpha-x/--alpha-y");
  EXPECT_EQ(refusal([] { generate_surface({"box", {}}, "box.exr"); }), "-o box.exr: this surface is a mesh; use .ply, .obj or .off");
  // A request built by hand is checked too.
  EXPECT_NE(refusal([] { generate_surface({"flat", {{"size", "0"}}}); }).find("--size: must be"), std::string::npos);
  EXPECT_NE(refusal([] { generate_surface({"flat", {{"bogus", "1"}}}); }).find("unknown option 'bogus'"), std::string::npos);

  // Power: the edges of the ranges are accepted, just outside is refused.
  SurfaceRequest ok{"gaussian", {}};
  EXPECT_NO_THROW(read_surface_preset(ok, write("edge.toml", "alpha = 10 # the largest\nresolution = 4\nseed = 18446744073709551615\n")));
  EXPECT_EQ(ok.options["alpha"], "10");
  EXPECT_NE(refusal([&] { set_surface_option(ok, "alpha", "10.000001"); }).find("--alpha"), std::string::npos);
  EXPECT_NE(refusal([&] { set_surface_option(ok, "resolution", "3"); }).find("--resolution"), std::string::npos);
  EXPECT_NE(refusal([&] { set_surface_option(ok, "seed", "18446744073709551616"); }).find("--seed"), std::string::npos);
  SurfaceRequest quoted{"vcavity", {}};
  EXPECT_NO_THROW(read_surface_preset(quoted, write("quoted.toml", "ndf = \"ggx\"  # quoted\n")));
  EXPECT_EQ(quoted.options["ndf"], "ggx");
  EXPECT_NE(refusal([&] { read_surface_preset(quoted, write("q2d.toml", "2d = true\n")); }).find("unknown option '2d'"),
            std::string::npos);
  SurfaceRequest two_d{"vgroove", {}};
  EXPECT_NO_THROW(read_surface_preset(two_d, write("v2d.toml", "2d = true\n")));
  EXPECT_EQ(generate_surface(two_d).kind(), Microsurface::Kind::Mesh);
}

// A suite entry: preset, then args, then the seed; refusals name the option.
TEST(SurfaceSpec, SuiteEntries) {
  validation::SuiteEntry e;
  e.generate = "gaussian";
  e.preset = kSurfaces + "beckmann-0.5.toml";
  e.args = {{"resolution", "32"}, {"correlation-length", "0.125"}};
  const SurfaceRequest r = validation::surface_request(e, 7);
  EXPECT_EQ(r.options.at("resolution"), "32");
  EXPECT_EQ(r.options.at("alpha"), "0.5");
  EXPECT_EQ(r.options.at("seed"), "7");
  const Microsurface s = generate_surface(r);
  EXPECT_EQ(s.description["seed"], 7);
  EXPECT_EQ(s.description["resolution"], 32);
  e.args.push_back({"tiles", "3"});
  EXPECT_NE(refusal([&] { validation::surface_request(e, std::nullopt); }).find("unknown option 'tiles' for 'gaussian'"),
            std::string::npos);
  e.args.back() = {"alpha", "0"};
  EXPECT_NE(refusal([&] { validation::surface_request(e, std::nullopt); }).find("--alpha: must be"), std::string::npos);
  e.generate = "box";
  e.preset.clear();
  e.args = {{"height", "0.5"}};
  EXPECT_NE(refusal([&] { validation::surface_request(e, 3); }).find("unknown option 'seed' for 'box'"), std::string::npos);
}

// One preset text for a kind: a malformed one, or a good one with the options it must give.
struct PresetText {
  std::string kind, name, text;
  std::map<std::string, std::string> gives;
};

// The message up to an unknown key's list of known options (the command line lists its
// command's options, the library its kind's).
std::string before_known(const std::string& m) { return m.substr(0, m.find(" (known: ")); }

// Malformed presets, each refused by the command line (`generate KIND --config FILE`) and by
// the library (read_surface_preset) with the same one line: the reader's own (file, syntax) and
// the key's (unknown, bad value), the command line only prefixing --config. Before one reader
// served both, the command line took `alpha = [0.3]` as 0.3 and quoted keys, cut a "quoted #"
// value at the '#' and kept an unterminated quote, while the library took `normal = 0,0,1`.
TEST(PresetFile, CommandLineAndLibraryRefuseTheSameMalformedPresets) {
  const std::vector<PresetText> malformed = {
      {"gaussian", "binary", std::string("\x7f" "ELF\0\0", 6), {}},
      {"gaussian", "control", "alpha = 0.3\x01\n", {}},
      {"gaussian", "large", "# " + std::string(1 << 20, 'x') + "\n", {}},
      {"gaussian", "section", "[gaussian]\nalpha = 0.3\n", {}},
      {"gaussian", "array_of_tables", "[[gaussian]]\nalpha = 0.3\n", {}},
      {"gaussian", "dotted_key", "gaussian.alpha = 0.3\n", {}},
      {"gaussian", "no_equals", "alpha 0.3\n", {}},
      {"gaussian", "no_key", "= 0.3\n", {}},
      {"gaussian", "no_value", "alpha =\n", {}},
      {"gaussian", "comment_for_value", "alpha = # none\n", {}},
      {"gaussian", "empty_string", "alpha = \"\"\n", {}},
      {"gaussian", "quoted_key", "\"alpha\" = 0.3\n", {}},
      {"gaussian", "unterminated", "alpha = \"0.3\n", {}},
      {"gaussian", "after_string", "alpha = \"0.3\" 0.4\n", {}},
      {"gaussian", "array", "alpha = [0.3, 0.4]\n", {}},
      {"gaussian", "one_element_array", "alpha = [0.3]\n", {}},
      {"gaussian", "multiline_array", "alpha = [0.3,\n0.4]\n", {}},
      {"gaussian", "two_words", "alpha = 0.3 0.4\n", {}},
      {"gaussian", "comma_list", "alpha = 0.3,0.4\n", {}},
      {"gaussian", "twice_adjacent", "alpha = 0.3\nalpha = 0.4\n", {}},
      {"gaussian", "twice_apart", "alpha = 0.3\nseed = 2\nalpha = 0.4\n", {}},
      {"gaussian", "unknown", "resolution = 16\nresolutionn = 32\n", {}},
      {"gaussian", "config_key", "config = \"other.toml\"\n", {}},
      {"gaussian", "range", "resolution = 16\nalpha = -1\n", {}},
      {"gaussian", "not_integer", "resolution = 32.5\n", {}},
      {"gaussian", "not_number", "resolution = \"abc\"\n", {}},
      {"gaussian", "bool_for_number", "alpha = true\n", {}},
      {"gaussian", "nan", "size = nan\n", {}},
      {"gaussian", "negative_seed", "seed = -1\n", {}},
      {"square-wave", "flag_value", "2d = 3\n", {}},
      {"box", "other_kinds_key", "alpha = 0.3\n", {}},
      {"mesh", "unquoted_list", "normal = 0,0,1\n", {}},
  };
  for (const PresetText& p : malformed) {
    SCOPED_TRACE(p.name);
    const std::string file = write(p.name + ".toml", p.text);
    SurfaceRequest r{p.kind, {}};
    const std::string library = refusal([&] { read_surface_preset(r, file); });
    ASSERT_EQ(library.rfind(file + ": ", 0), 0u) << library;
    const std::string out = temp_path("spec", p.name + (p.kind == "gaussian" ? ".exr" : ".ply"));
    // mesh requires --input on the command line (the preset is read before the input).
    const std::string input = p.kind == "mesh" ? " --input " + file : "";
    const Result cli = run("-q generate " + p.kind + input + " --config " + file + " -o " + out, p.name);
    EXPECT_EQ(cli.code, 2);
    EXPECT_EQ(before_known(cli.err), before_known("microsim: error: --config " + library + "\n")) << cli.err;
    EXPECT_FALSE(microsim::testing::exists(out));
  }
  // A missing file, the same way.
  const std::string missing = temp_path("spec", "missing-preset.toml");
  SurfaceRequest r{"flat", {}};
  const std::string library = refusal([&] { read_surface_preset(r, missing); });
  EXPECT_EQ(library, missing + ": no such preset file");
  const Result cli = run("-q generate flat --config " + missing + " -o " + temp_path("spec", "missing.exr"), "missing");
  EXPECT_EQ(cli.code, 2);
  EXPECT_EQ(cli.err, "microsim: error: --config " + library + "\n");
}

// Good presets (comments, blank lines, tabs, CRLF, quotes of both kinds, a comment after quotes,
// no final newline, an empty file) give the same options through both and byte-identical
// surfaces; power: each option the library read, changed on the command line, changes the file.
TEST(PresetFile, CommandLineAndLibraryAcceptTheSameGoodPresets) {
  const std::vector<PresetText> good = {
      {"gaussian", "comments", "# a preset\n\nresolution = 16 # cells\nalpha = 0.7\n",
       {{"resolution", "16"}, {"alpha", "0.7"}}},
      {"gaussian", "tabs_crlf", "resolution\t=\t16\r\nalpha=0.7\r\n  seed = 18446744073709551615\r\n",
       {{"resolution", "16"}, {"alpha", "0.7"}, {"seed", "18446744073709551615"}}},
      {"gaussian", "quotes", "resolution = \"16\"\nalpha = '0.7'  # single\nsize = 2",
       {{"resolution", "16"}, {"alpha", "0.7"}, {"size", "2"}}},
      {"vcavity", "comment_after_quotes", "grooves = 16\nndf = \"ggx\" # a comment, \"quoted\" # twice\n",
       {{"grooves", "16"}, {"ndf", "ggx"}}},
      {"square-wave", "flag", "2d = true\nheight = 0.25\n", {{"2d", "true"}, {"height", "0.25"}}},
      {"flat", "empty", "", {}},
  };
  for (const PresetText& p : good) {
    SCOPED_TRACE(p.name);
    const std::string file = write(p.name + ".toml", p.text);
    SurfaceRequest r{p.kind, {}};
    ASSERT_EQ(refusal([&] { read_surface_preset(r, file); }), "");
    EXPECT_EQ(r.options, p.gives);
    const std::string ext = p.kind == "square-wave" || p.kind == "vcavity" ? "ply" : "exr";
    const std::string out = temp_path("spec", p.name + "-cli." + ext);
    const Result cli = run("-q generate " + p.kind + " --config " + file + " -o " + out, p.name);
    ASSERT_EQ(cli.code, 0) << cli.err;
    const std::string library = saved(generate_surface(r), p.name + "-library." + ext);
    EXPECT_EQ(saved_file(out), library);
    for (const auto& [key, value] : p.gives) {
      if (key == "2d" || key == "ndf") continue;  // not numbers
      const std::string other = temp_path("spec", p.name + "-" + key + "." + ext);
      const std::string changed = key == "resolution" ? "32" : key == "grooves" ? "8" : key == "seed" ? "3" : "0.5";
      ASSERT_EQ(run("-q generate " + p.kind + " --config " + file + " --" + key + " " + changed + " -o " + other, p.name).code, 0);
      EXPECT_NE(saved_file(other), library) << key;
    }
  }
}

}  // namespace
