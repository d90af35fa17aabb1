// Every input honoured or refused: presets apply (non-default values, command line wins), and a
// table of malformed options and files, each answered with exit 2, one line on stderr naming the
// option or file, and no output file; valid edge values give exit 0. Interrupts at random moments
// leave no output, temporary file or temporary folder behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <random>
#include <thread>
#include <tuple>

#include <nlohmann/json.hpp>

#include "cli_helpers.hpp"
#include "microsim/io/output.hpp"

extern char** environ;

namespace {
using namespace microsim::testing;
namespace fs = std::filesystem;
// Every file of this program in one private folder (removed at exit by cli_helpers.hpp), so that
// temporaries left behind are this program's own.
std::string folder() {
  static const std::string dir = [] {
    std::string d = temp_path("inputs", "files");
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}
std::string tmp(const std::string& name) { return folder() + "/" + name; }
const std::string kSrc = MICROSIM_SOURCE_DIR;

// AddressSanitizer reserves terabytes of shadow address space at start: no address-space limit
// can be set under it (its allocator refuses absurd requests by itself).
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

// Runs microsim under an 8 GiB address-space limit and a 60 s timeout, so that an input that is
// wrongly accepted fails this test instead of exhausting the machine.
Result run_limited(const std::string& args) {
  return run_microsim(args, kAddressSanitizer ? "timeout 60" : "ulimit -v 8388608; timeout 60");
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Files with one thing wrong each, made once for the whole program.
class Inputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    surface_ = tmp("s.exr");
    Result r = run_microsim("generate gaussian --resolution 16 --seed 2 -o " + surface_);
    ASSERT_EQ(r.code, 0) << r.err;
    mesh_ = tmp("el.ply");
    r = run_microsim("generate ellipsoid --alpha 0.5 --rings 4 --segments 16 -o " + mesh_);
    ASSERT_EQ(r.code, 0) << r.err;
    // Heightfield headers: macrosurface size 0, -1, 1e300; description alpha <= 0 or not a number;
    // a data window of 40000^2 in a small file.
    const microsim::ExrTable good = microsim::read_exr(surface_);
    auto with_macro = [&](const std::string& name, const std::string& key, const nlohmann::json& v) {
      microsim::ExrTable t = good;
      auto m = nlohmann::json::parse(t.attributes["microsim_macrosurface"].get<std::string>());
      m[key] = v;
      t.attributes["microsim_macrosurface"] = m.dump();
      microsim::write_exr(tmp(name), t);
    };
    with_macro("size0.exr", "size_x", 0.0);
    with_macro("sizeneg.exr", "size_y", -1.0);
    with_macro("sizehuge.exr", "size_x", 1e300);
    with_macro("area0.exr", "area", 0.0);
    auto with_description = [&](const std::string& name, const std::string& key, const nlohmann::json& v) {
      microsim::ExrTable t = good;
      auto d = nlohmann::json::parse(t.attributes["microsim_description"].get<std::string>());
      d[key] = v;
      t.attributes["microsim_description"] = d.dump();
      microsim::write_exr(tmp(name), t);
    };
    with_description("alphaneg.exr", "alpha_x", -0.5);
    with_description("alpha0.exr", "alpha_y", 0.0);
    with_description("alphastr.exr", "alpha_x", "abc");
    {
      microsim::ExrTable t = good;
      t.attributes = nlohmann::json::object();
      microsim::write_exr(tmp("plain.exr"), t);
    }
    {  // The data window (xmin, ymin, xmax, ymax as int32) patched to 40000 x 40000.
      std::ifstream f(surface_, std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      const std::string key = std::string("dataWindow") + '\0' + "box2i" + '\0';
      auto at = bytes.find(key);
      ASSERT_NE(at, std::string::npos);
      const std::size_t values = at + key.size() + 4;
      const std::int32_t box[4] = {0, 0, 39999, 39999};
      bytes.replace(values, 16, reinterpret_cast<const char*>(box), 16);
      write_file(tmp("window.exr"), bytes);
    }
    // Mesh headers declaring absurd counts, and sidecars with bad fields.
    const std::string ply_tail =
        "property float x\nproperty float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    write_file(tmp("huge.ply"), "ply\nformat ascii 1.0\nelement vertex 2000000000\n" + ply_tail);
    write_file(tmp("neg.ply"), "ply\nformat ascii 1.0\nelement vertex -3\n" + ply_tail);
    write_file(tmp("huge.off"), "OFF\n2000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    write_file(tmp("neg.off"), "OFF\n3 -1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    // Mesh bodies that OpenMesh's readers trust: a face list of 3e9 vertices, a comment where
    // a count belongs, a face naming a missing vertex, a file ending early, a token that is not
    // a number, counts on the OFF line, binary OFF, a binary PLY list count of 2^31 - 1.
    const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
    write_file(tmp("tri.off"), "OFF\n3 1 0\n" + tri + "3 0 1 2\n");
    write_file(tmp("list.off"), "OFF\n3 1 0\n" + tri + "3000000000 0 1 2\n");
    write_file(tmp("comment.off"), "OFF\n# made by hand\n3 1 0\n" + tri + "3 0 1 2\n");
    write_file(tmp("index.off"), "OFF\n3 1 0\n" + tri + "3 0 1 4\n");
    write_file(tmp("short.off"), "OFF\n3 2 0\n" + tri + "3 0 1 2\n");
    write_file(tmp("nan.off"), "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    write_file(tmp("oneline.off"), "OFF 3 1 0\n" + tri + "3 0 1 2\n");
    write_file(tmp("binary.off"), "OFF BINARY\n" + std::string(64, '\0'));
    const std::string ply_ascii =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    write_file(tmp("tri.ply"), ply_ascii + tri + "3 0 1 2\n");
    write_file(tmp("list.ply"), ply_ascii + tri + "200 0 1 2\n");
    write_file(tmp("token.ply"), ply_ascii + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n");
    write_file(tmp("version.ply"), "ply\nformat ascii one\nelement vertex 3\nend_header\n");
    {
      std::string b =
          "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
      const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
      const std::int32_t face[4] = {2147483647, 0, 1, 2};
      b.append(reinterpret_cast<const char*>(v), sizeof v);
      write_file(tmp("tri_bin.ply"), b + std::string("\3\0\0\0\0\0\0\0\1\0\0\0\2\0\0\0", 16));
      b.append(reinterpret_cast<const char*>(face), sizeof face);
      write_file(tmp("list_bin.ply"), b);
    }
    auto with_sidecar = [&](const std::string& name, const std::function<void(nlohmann::json&)>& edit) {
      fs::copy_file(mesh_, tmp(name), fs::copy_options::overwrite_existing);
      auto j = nlohmann::json::parse(slurp(mesh_ + ".json"));
      edit(j);
      write_file(tmp(name) + ".json", j.dump());
    };
    with_sidecar("alphastr.ply", [](nlohmann::json& j) { j["description"]["alpha_x"] = "abc"; });
    with_sidecar("area0.ply", [](nlohmann::json& j) { j["macrosurface"]["area"] = 0; });
    with_sidecar("normalnan.ply", [](nlohmann::json& j) { j["macrosurface"]["normal"] = {0, 0, "x"}; });
    with_sidecar("nomacro.ply", [](nlohmann::json& j) { j.erase("macrosurface"); });
    write_file(tmp("notjson.ply"), slurp(mesh_));
    write_file(tmp("notjson.ply") + ".json", "{\"macrosurface\": ");
    // Presets.
    write_file(tmp("p_unknown.toml"), "resolutionn = 32\n");
    write_file(tmp("p_type.toml"), "resolution = \"abc\"\n");
    write_file(tmp("p_float.toml"), "resolution = 32.5\n");
    write_file(tmp("p_bool.toml"), "alpha = true\n");
    write_file(tmp("p_alpha.toml"), "alpha = -1\n");
    write_file(tmp("p_nan.toml"), "size = nan\n");
    write_file(tmp("p_malformed.toml"), "resolution 32\n");
    write_file(tmp("p_empty_value.toml"), "resolution =\n");
    write_file(tmp("p_binary.toml"), std::string("\x7f" "ELF\x02\x01\x01\0\0\0", 10));
    write_file(tmp("p_section.toml"), "[gaussian]\nresolution = 32\n");
    write_file(tmp("p_twice.toml"), "alpha = 0.3\nalpha = 0.4\n");
    write_file(tmp("p_array.toml"), "alpha = [0.3, 0.4]\n");
    write_file(tmp("p_seed.toml"), "seed = -1\n");
    write_file(tmp("p_config.toml"), "config = \"other.toml\"\n");
    write_file(tmp("p_flag.toml"), "two-d = 3\n");
    // Suites whose entry names would escape or collide, and one with a bad argument.
    const std::string flat = "{\"generate\": \"flat\", \"preset\": \"" + kSrc + "/surfaces/flat.toml\"";
    write_file(tmp("suite_dotdot.json"), "{\"entries\": [" + flat + ", \"name\": \"../x\"}]}");
    write_file(tmp("suite_slash.json"), "{\"entries\": [" + flat + ", \"name\": \"a/b\"}]}");
    write_file(tmp("suite_twice.json"),
               "{\"entries\": [" + flat + ", \"name\": \"a\"}, " + flat + ", \"name\": \"a\"}]}");
    write_file(tmp("suite_alpha.json"),
               "{\"entries\": [{\"name\": \"g\", \"generate\": \"gaussian\", \"args\": "
               "{\"resolution\": 16, \"alpha\": -1}}]}");
    // JSON nested 100,000 levels deep in every place a JSON document is read, and a suite
    // larger than the size limit.
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    {
      microsim::ExrTable t = good;
      t.attributes["microsim_description"] = deep;
      microsim::write_exr(tmp("deepdesc.exr"), t);
      t = good;
      t.attributes["microsim_macrosurface"] = deep;
      microsim::write_exr(tmp("deepmacro.exr"), t);
    }
    with_sidecar("deep.ply", [&](nlohmann::json& j) { j["description"] = "x"; });
    write_file(tmp("deep.ply") + ".json", "{\"macrosurface\": " + deep + "}");
    write_file(tmp("suite_deep.json"), "{\"entries\": [" + flat + ", \"name\": \"a\", \"x\": " + deep + "}]}");
    write_file(tmp("suite_large.json"), "{\"entries\": []" + std::string(17 << 20, ' ') + "}");
    write_file(tmp("part_deep.json"), "{\"format\": " + deep + "}");
    // Special files where a file is read: a FIFO without a writer (opening it would block
    // forever) under every input's name, and a folder.
    for (const char* name : {"fifo.exr", "fifo.csv", "fifo.json", "fifo.toml", "fifo.ply"})
      ASSERT_EQ(mkfifo(tmp(name).c_str(), 0600), 0) << name;
    fs::create_directories(tmp("folder.exr"));
    // Text heightmaps 40 x 40: plain, with a UTF-8 byte order mark, with CRLF line ends, and
    // with one infinite height (inf, -inf, 1e999) at column 3, row 5.
    auto grid = [](const std::string& special, const std::string& eol) {
      std::string t;
      for (int j = 0; j < 40; ++j) {
        for (int i = 0; i < 40; ++i)
          t += (i ? "," : "") + (j == 5 && i == 3 && !special.empty()
                                     ? special
                                     : std::to_string(std::sin(0.3 * i) * std::cos(0.4 * j) + 0.01 * ((i * 7 + j * 13) % 11)));
        t += eol;
      }
      return t;
    };
    write_file(tmp("hm.csv"), grid("", "\n"));
    write_file(tmp("hm_bom.csv"), "\xEF\xBB\xBF" + grid("", "\n"));
    write_file(tmp("hm_crlf.csv"), grid("", "\r\n"));
    write_file(tmp("hm_bom_crlf.csv"), "\xEF\xBB\xBF" + grid("", "\r\n"));
    write_file(tmp("hm_inf.csv"), grid("inf", "\n"));
    write_file(tmp("hm_neginf.csv"), grid("-inf", "\n"));
    write_file(tmp("hm_1e999.csv"), grid("1e999", "\n"));
    write_file(tmp("hm_nan.csv"), grid("nan", "\n"));
    write_file(tmp("hm_100.csv"), grid("100", "\n"));
    // Presets naming the files of the run, and one heightmap preset whose key must apply.
    write_file(tmp("p_output.toml"), "output = \"elsewhere.exr\"\n");
    write_file(tmp("p_input.toml"), "input = \"elsewhere.csv\"\n");
    write_file(tmp("p_pixel.toml"), "pixel-size = 2\n");
    // Suites whose seeds or options are wrong in kind, not only in value.
    const std::string gauss = "{\"name\": \"g\", \"generate\": \"gaussian\", \"args\": {\"resolution\": 16}";
    write_file(tmp("suite_seedneg.json"), "{\"entries\": [" + gauss + ", \"seeds\": [-1]}]}");
    write_file(tmp("suite_seedfrac.json"), "{\"entries\": [" + gauss + ", \"seeds\": [1.5]}]}");
    write_file(tmp("suite_seedtwice.json"), "{\"entries\": [" + gauss + ", \"seeds\": [1, 2, 1]}]}");
    write_file(tmp("suite_seedbig.json"), "{\"entries\": [" + gauss + ", \"seeds\": [1e30]}]}");
    write_file(tmp("suite_thetastr.json"), "{\"entries\": [" + gauss + ", \"theta_deg\": [\"abc\"]}]}");
    write_file(tmp("suite_checksempty.json"), "{\"entries\": [" + gauss + ", \"checks\": []}]}");
    write_file(tmp("suite_phihuge.json"), "{\"entries\": [" + gauss + ", \"phi_deg\": [1e308]}]}");
    // The two parts of a sharded run, and copies of the first with one count (the ray-cast
    // hits of the first bin of replicate 0) changed to a negative, a fractional and an
    // overflowing value, and to more hits than the replicate has rays.
    const std::string shard = "measure g1 " + surface_ + " --theta 30 --rays 2000 -o " + tmp("sharded.json");
    ASSERT_EQ(run_microsim("--shard 1/2 " + shard).code, 0);
    ASSERT_EQ(run_microsim("--shard 2/2 " + shard).code, 0);
    const std::string part1 = tmp("sharded.json.shard-1-of-2.json");
    for (const auto& [name, value] : std::vector<std::pair<std::string, nlohmann::json>>{
             {"part_neg.json", -5}, {"part_frac.json", 1.5}, {"part_huge.json", 1e30},
             {"part_more.json", 1000000}}) {
      auto j = nlohmann::json::parse(slurp(part1));
      j["tallies"][0]["counts"][0] = value;
      write_file(tmp(name), j.dump());
    }
  }
  static std::string surface_, mesh_;
};
std::string Inputs::surface_, Inputs::mesh_;

// One row: arguments ({o} = a fresh output path with extension `ext`, {S} the heightfield, {M}
// the mesh, {T} the test folder prefix, {src} the source tree), the expected exit code and, for
// exit 2, a word the one-line message must contain (the option or file).
struct Case {
  std::string args;
  int code;
  std::string needle;
  std::string ext = "json";
};

std::string expand(std::string s, const std::string& out, const std::string& S, const std::string& M) {
  auto put = [&](const std::string& key, const std::string& value) {
    for (std::size_t at; (at = s.find(key)) != std::string::npos;) s.replace(at, key.size(), value);
  };
  put("{o}", out);
  put("{S}", S);
  put("{M}", M);
  put("{T}", tmp(""));
  put("{src}", kSrc);
  return s;
}

// Temporaries this process's children left in a folder (.tmp-PID-*).
int leftover_temporaries(const std::string& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    n += e.path().filename().string().rfind(".tmp-", 0) == 0;
  return n;
}

const std::vector<Case>& cases() {
  static const std::vector<Case> c = {
      // Global options.
      {"--threads -1 info {S}", 2, "--threads"},
      {"--threads 5000 info {S}", 2, "--threads"},
      // generate gaussian: every option, including the silent-default cases.
      {"generate gaussian --resolution 16 --alpha -1 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha 0 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha nan -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha inf -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha 11 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha abc -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha -1 --alpha-x 0.3 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha 0.5 --alpha-x 0.3 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --resolution 16 --alpha-x -1 -o {o}", 2, "--alpha-x", "exr"},
      {"generate gaussian --resolution 16 --alpha-y nan -o {o}", 2, "--alpha-y", "exr"},
      {"generate gaussian --resolution 0 -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --resolution 3 -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --resolution 40000 -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --resolution 50000 -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --resolution 16.5 -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --resolution 16 --size 0 -o {o}", 2, "--size", "exr"},
      {"generate gaussian --resolution 16 --size -1 -o {o}", 2, "--size", "exr"},
      {"generate gaussian --resolution 16 --size 1e300 -o {o}", 2, "--size", "exr"},
      {"generate gaussian --resolution 16 --size inf -o {o}", 2, "--size", "exr"},
      {"generate gaussian --resolution 16 --size nan -o {o}", 2, "--size", "exr"},
      {"generate gaussian --resolution 16 --correlation-length 0 -o {o}", 2, "--correlation-length", "exr"},
      {"generate gaussian --resolution 16 --correlation-length -1 -o {o}", 2, "--correlation-length", "exr"},
      {"generate gaussian --resolution 16 --correlation-length nan -o {o}", 2, "--correlation-length", "exr"},
      {"generate gaussian --resolution 16 --correlation-length 0.5 -o {o}", 2, "--correlation-length", "exr"},
      {"generate gaussian --resolution 16 --seed -1 -o {o}", 2, "--seed", "exr"},
      {"generate gaussian --resolution 16 --seed 18446744073709551616 -o {o}", 2, "--seed", "exr"},
      {"generate gaussian --resolution 16 --seed 1.5 -o {o}", 2, "--seed", "exr"},
      {"generate gaussian --resolution 16 --seed 18446744073709551615 -o {o}", 0, "", "exr"},
      {"generate gaussian --resolution 16 --size 1e6 --alpha 10 -o {o}", 0, "", "exr"},
      {"generate gaussian --resolution 16 -o {o}.xyz", 2, "-o", "exr"},
      // generate flat.
      {"generate flat --resolution 0 -o {o}", 2, "--resolution", "exr"},
      {"generate flat --resolution 5000 -o {o}", 2, "--resolution", "exr"},
      {"generate flat --size inf -o {o}", 2, "--size", "exr"},
      {"generate flat --size 0 -o {o}", 2, "--size", "exr"},
      {"generate flat --resolution 1 -o {o}", 0, "", "exr"},
      // Structured kinds.
      {"generate box --width 0 -o {o}", 2, "--width", "ply"},
      {"generate box --width nan -o {o}", 2, "--width", "ply"},
      {"generate box --depth -1 -o {o}", 2, "--depth", "ply"},
      {"generate box --height inf -o {o}", 2, "--height", "ply"},
      {"generate box --height 0.5 -o {o}", 2, "-o", "exr"},
      {"generate tiled-boxes --tiles 0 -o {o}", 2, "--tiles", "ply"},
      {"generate tiled-boxes --tiles 257 -o {o}", 2, "--tiles", "ply"},
      {"generate tiled-boxes --tiles -1 -o {o}", 2, "--tiles", "ply"},
      {"generate square-wave --duty 0 -o {o}", 2, "--duty", "ply"},
      {"generate square-wave --duty 1 -o {o}", 2, "--duty", "ply"},
      {"generate square-wave --duty nan -o {o}", 2, "--duty", "ply"},
      {"generate square-wave --period 0 -o {o}", 2, "--period", "ply"},
      {"generate square-wave --height -0.5 -o {o}", 2, "--height", "ply"},
      {"generate vgroove --facet-angle 0 -o {o}", 2, "--facet-angle", "exr"},
      {"generate vgroove --facet-angle 90 -o {o}", 2, "--facet-angle", "exr"},
      {"generate vgroove --facet-angle nan -o {o}", 2, "--facet-angle", "exr"},
      {"generate vgroove --period -1 -o {o}", 2, "--period", "exr"},
      {"generate vgroove --facet-angle 89.9 -o {o}", 0, "", "exr"},
      {"generate vcavity --alpha -1 --grooves 8 -o {o}", 2, "--alpha", "ply"},
      {"generate vcavity --alpha -1 --alpha-x 0.3 --grooves 8 -o {o}", 2, "--alpha", "ply"},
      {"generate vcavity --alpha-x 0 --grooves 8 -o {o}", 2, "--alpha-x", "ply"},
      {"generate vcavity --grooves 0 -o {o}", 2, "--grooves", "ply"},
      {"generate vcavity --ndf phong --grooves 8 -o {o}", 2, "--ndf", "ply"},
      {"generate vcavity --seed -1 --grooves 8 -o {o}", 2, "--seed", "ply"},
      {"generate parallelepiped --shear-x nan -o {o}", 2, "--shear-x", "ply"},
      {"generate parallelepiped --shear-y inf -o {o}", 2, "--shear-y", "ply"},
      {"generate parallelepiped --tiles 0 -o {o}", 2, "--tiles", "ply"},
      {"generate parallelepiped --matrix 1,0,0,0,1,0,0,0,0 -o {o}", 2, "--matrix", "ply"},
      {"generate parallelepiped --matrix abc -o {o}", 2, "--matrix", "ply"},
      {"generate ellipsoid --alpha -1 --rings 4 --segments 16 -o {o}", 2, "--alpha", "ply"},
      {"generate ellipsoid --alpha 0 --rings 4 --segments 16 -o {o}", 2, "--alpha", "ply"},
      {"generate ellipsoid --alpha -1 --alpha-x 0.5 --rings 4 --segments 16 -o {o}", 2, "--alpha", "ply"},
      {"generate ellipsoid --rings 1 -o {o}", 2, "--rings", "ply"},
      {"generate ellipsoid --segments 7 -o {o}", 2, "--segments", "ply"},
      {"generate gaussian-ggx --resolution 32 --alpha -1 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian-ggx --resolution 32 --alpha -1 --alpha-x 0.3 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian-ggx --resolution 32 --roughness-correlation-length -1 -o {o}", 2,
       "--roughness-correlation-length", "exr"},
      {"generate gaussian-ggx --resolution 32 --roughness-correlation-length nan -o {o}", 2,
       "--roughness-correlation-length", "exr"},
      {"generate gaussian-ggx --resolution 32 --roughness-correlation-length 0 -o {o}", 2,
       "--roughness-correlation-length", "exr"},
      {"generate gaussian-ggx --resolution 32 --correlation-length 0 -o {o}", 2, "--correlation-length", "exr"},
      {"generate gaussian-ggx --resolution 32 --tail-fraction 0 -o {o}", 2, "--tail-fraction", "exr"},
      {"generate gaussian-ggx --resolution 32 --tail-fraction 0.5 -o {o}", 2, "--tail-fraction", "exr"},
      {"generate gaussian-ggx --resolution 32 --size inf -o {o}", 2, "--size", "exr"},
      {"generate gaussian-ggx --resolution 32 --seed -1 -o {o}", 2, "--seed", "exr"},
      // generate mesh and mesh files.
      {"generate mesh --input {T}missing.ply -o {o}", 2, "missing.ply", "ply"},
      {"generate mesh --input {M} --area 0 -o {o}", 2, "--area", "ply"},
      {"generate mesh --input {M} --area -1 -o {o}", 2, "--area", "ply"},
      {"generate mesh --input {M} --area nan -o {o}", 2, "--area", "ply"},
      {"generate mesh --input {M} --normal 0,0,0 -o {o}", 2, "--normal", "ply"},
      {"generate mesh --input {M} --normal 0,0,nan -o {o}", 2, "--normal", "ply"},
      {"generate mesh --input {M} --periodic --tile-x 0 --tile-y 1 -o {o}", 2, "--tile-x", "ply"},
      {"generate mesh --input {M} --tile-x 1 -o {o}", 2, "--tile-x", "ply"},
      {"generate mesh --input {T}huge.ply -o {o}", 2, "huge.ply", "ply"},
      {"generate mesh --input {T}neg.ply -o {o}", 2, "neg.ply", "ply"},
      {"generate mesh --input {T}huge.off -o {o}", 2, "huge.off", "ply"},
      {"generate mesh --input {T}neg.off -o {o}", 2, "neg.off", "ply"},
      {"info {T}huge.ply --json {o}", 2, "huge.ply"},
      {"info {T}neg.off --json {o}", 2, "neg.off"},
      {"info {T}tri.off --json {o}", 0, ""},
      {"info {T}list.off --json {o}", 2, "list.off"},
      {"info {T}comment.off --json {o}", 2, "comment.off"},
      {"info {T}index.off --json {o}", 2, "index.off"},
      {"info {T}short.off --json {o}", 2, "short.off"},
      {"info {T}nan.off --json {o}", 2, "nan.off"},
      {"info {T}oneline.off --json {o}", 2, "oneline.off"},
      {"info {T}binary.off --json {o}", 2, "binary.off"},
      {"info {T}tri.ply --json {o}", 0, ""},
      {"info {T}tri_bin.ply --json {o}", 0, ""},
      {"info {T}list.ply --json {o}", 2, "list.ply"},
      {"info {T}token.ply --json {o}", 2, "token.ply"},
      {"info {T}version.ply --json {o}", 2, "version.ply"},
      {"generate mesh --input {T}list_bin.ply -o {o}", 2, "list_bin.ply", "ply"},
      {"info {T}alphastr.ply --json {o}", 2, "alpha_x"},
      {"info {T}area0.ply --json {o}", 2, "area"},
      {"info {T}normalnan.ply --json {o}", 2, "normal"},
      {"info {T}nomacro.ply --json {o}", 2, "macrosurface"},
      {"info {T}notjson.ply --json {o}", 2, "notjson.ply.json"},
      // Heightfield headers.
      {"info {T}size0.exr --json {o}", 2, "size_x"},
      {"info {T}sizeneg.exr --json {o}", 2, "size_y"},
      {"info {T}sizehuge.exr --json {o}", 2, "size_x"},
      {"info {T}area0.exr --json {o}", 2, "area"},
      {"info {T}alphaneg.exr --json {o}", 2, "alpha_x"},
      {"info {T}alpha0.exr --json {o}", 2, "alpha_y"},
      {"info {T}alphastr.exr --json {o}", 2, "alpha_x"},
      {"info {T}plain.exr --json {o}", 2, "plain.exr"},
      {"info {T}window.exr --json {o}", 2, "window.exr"},
      {"measure ndf {T}sizehuge.exr -o {o}", 2, "sizehuge.exr"},
      {"measure ndf {T}size0.exr -o {o}", 2, "size0.exr"},
      {"measure g1 {T}alphaneg.exr --rays 1000 -o {o}", 2, "alphaneg.exr"},
      {"convert {T}window.exr -o {o}", 2, "window.exr", "ply"},
      {"convert {S} -o {o}.xyz", 2, "-o"},
      {"info {S} --json {o}.txt", 2, "--json"},
      {"info {T}missing.exr", 2, "missing.exr"},
      // measure ndf.
      {"measure ndf {S} --theta-bins 0 -o {o}", 2, "--theta-bins"},
      {"measure ndf {S} --theta-bins 3601 -o {o}", 2, "--theta-bins"},
      {"measure ndf {S} --phi-bins 0 -o {o}", 2, "--phi-bins"},
      {"measure ndf {S} --theta-bins 3600 --phi-bins 7200 -o {o}", 2, "--theta-bins"},
      {"measure ndf {S} --theta-bins 1 --phi-bins 1 -o {o}", 0, ""},
      // measure g1.
      {"measure g1 {S} --rays 0 -o {o}", 2, "--rays"},
      {"measure g1 {S} --rays -1 -o {o}", 2, "--rays"},
      {"measure g1 {S} --rays 1e20 -o {o}", 2, "--rays"},
      {"measure g1 {S} --rays 99999999999999999999 -o {o}", 2, "--rays"},
      {"measure g1 {S} --rays 10000000000000 -o {o}", 2, "--rays"},
      {"measure g1 {S} --seed -1 --rays 100 -o {o}", 2, "--seed"},
      {"measure g1 {S} --seed 18446744073709551616 --rays 100 -o {o}", 2, "--seed"},
      {"measure g1 {S} --theta 90 --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --theta nan --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --theta 0:95:5 --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --phi inf --rays 100 -o {o}", 2, "--phi"},
      {"measure g1 {S} --phi abc --rays 100 -o {o}", 2, "--phi"},
      {"measure g1 {S} --rays 1 --theta 0 -o {o}", 0, ""},
      // measure g2.
      {"measure g2 {S} --theta-o 90 --theta-i 0 --rays 100 -o {o}", 2, "--theta-o"},
      {"measure g2 {S} --theta-o 0 --theta-i nan --rays 100 -o {o}", 2, "--theta-i"},
      {"measure g2 {S} --theta-o 0 --theta-i 0 --phi-i inf --rays 100 -o {o}", 2, "--phi-i"},
      {"measure g2 {S} --theta-o 0 --theta-i 0 --rays 0 -o {o}", 2, "--rays"},
      {"measure g2 {S} --theta-o 0 --theta-i 0 --seed -1 -o {o}", 2, "--seed"},
      // measure vndf.
      {"measure vndf {S} --rays 10000000000000 -o {o}", 2, "--rays"},
      {"measure vndf {S} --rays 0 -o {o}", 2, "--rays"},
      {"measure vndf {S} --theta-bins 0 -o {o}", 2, "--theta-bins"},
      {"measure vndf {S} --theta-bins 361 -o {o}", 2, "--theta-bins"},
      {"measure vndf {S} --phi-bins 721 -o {o}", 2, "--phi-bins"},
      {"measure vndf {S} --sampler-samples -1 -o {o}", 2, "--sampler-samples"},
      {"measure vndf {S} --seed -1 -o {o}", 2, "--seed"},
      {"measure vndf {S} --theta 90 -o {o}", 2, "--theta"},
      // measure bsdf.
      {"measure bsdf {S} --material gold --theta-i 0 --phi-i 0 --rays 100 -o {o}", 2, "--material"},
      {"measure bsdf {S} --material dielectric --eta 0 --theta-i 0 --phi-i 0 --rays 100 -o {o}", 2, "--eta"},
      {"measure bsdf {S} --material dielectric --eta nan --theta-i 0 --phi-i 0 --rays 100 -o {o}", 2, "--eta"},
      {"measure bsdf {S} --material conductor --eta 1 --k -1 --theta-i 0 --phi-i 0 --rays 100 -o {o}", 2, "--k"},
      {"measure bsdf {S} --material mirror --theta-i 90 --phi-i 0 --rays 100 -o {o}", 2, "--theta-i"},
      {"measure bsdf {S} --material mirror --theta-i nan --phi-i 0 --rays 100 -o {o}", 2, "--theta-i"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i inf --rays 100 -o {o}", 2, "--phi-i"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i 0 --orders 0 --rays 100 -o {o}", 2, "--orders"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i 0 --orders 65 --rays 100 -o {o}", 2, "--orders"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i 0 --rays 0 -o {o}", 2, "--rays"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i 0 --resolution 0 -o {o}", 2, "--resolution", "exr"},
      {"measure bsdf {S} --material mirror --theta-i 0 --phi-i 0 --seed -1 -o {o}", 2, "--seed"},
      {"measure bsdf {M} --material mirror --theta-i 0 --phi-i 0 --rays 100 -o {o}", 2, "periodic", "bsdf"},
      // demo: every option checked before anything is written.
      {"demo --resolution 16 --alpha -1 --out-dir {o}", 2, "--alpha", "d"},
      {"demo --resolution 16 --theta 95 --out-dir {o}", 2, "--theta", "d"},
      {"demo --resolution 16 --theta nan --out-dir {o}", 2, "--theta", "d"},
      {"demo --resolution 16 --rays 0 --out-dir {o}", 2, "--rays", "d"},
      {"demo --resolution 2 --out-dir {o}", 2, "--resolution", "d"},
      {"demo --resolution 16 --seed -1 --out-dir {o}", 2, "--seed", "d"},
      {"demo --resolution 16 --size inf --out-dir {o}", 2, "--size", "d"},
      {"demo --config {T}missing.toml --out-dir {o}", 2, "missing.toml", "d"},
      {"demo --config {T}p_alpha.toml --out-dir {o}", 2, "p_alpha.toml", "d"},
      // Presets: every failure names the file and the key.
      {"generate gaussian --config {T}missing.toml -o {o}", 2, "missing.toml", "exr"},
      {"generate gaussian --config {T}p_unknown.toml -o {o}", 2, "resolutionn", "exr"},
      {"generate gaussian --config {T}p_type.toml -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --config {T}p_float.toml -o {o}", 2, "--resolution", "exr"},
      {"generate gaussian --config {T}p_bool.toml -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --config {T}p_alpha.toml --resolution 16 -o {o}", 2, "--alpha", "exr"},
      {"generate gaussian --config {T}p_nan.toml --resolution 16 -o {o}", 2, "--size", "exr"},
      {"generate gaussian --config {T}p_malformed.toml -o {o}", 2, "p_malformed.toml", "exr"},
      {"generate gaussian --config {T}p_empty_value.toml -o {o}", 2, "p_empty_value.toml", "exr"},
      {"generate gaussian --config {T}p_binary.toml -o {o}", 2, "p_binary.toml", "exr"},
      {"generate gaussian --config {T}p_section.toml -o {o}", 2, "p_section.toml", "exr"},
      {"generate gaussian --config {T}p_twice.toml -o {o}", 2, "'alpha'", "exr"},
      {"generate gaussian --config {T}p_array.toml -o {o}", 2, "'alpha'", "exr"},
      {"generate gaussian --config {T}p_seed.toml -o {o}", 2, "--seed", "exr"},
      {"generate gaussian --config {T}p_config.toml -o {o}", 2, "'config'", "exr"},
      {"generate vgroove --config {T}p_flag.toml -o {o}", 2, "'two-d'", "ply"},
      {"generate box --config {T}p_alpha.toml -o {o}", 2, "'alpha'", "ply"},
      {"generate gaussian --config {T}p_alpha.toml --alpha 0.3 --resolution 16 -o {o}", 0, "", "exr"},
      // validate.
      {"validate {S} --rays 0 -o {o}", 2, "--rays"},
      {"validate {S} --seed -1 -o {o}", 2, "--seed"},
      {"validate {S} --significance 0 -o {o}", 2, "--significance"},
      {"validate {S} --significance 1 -o {o}", 2, "--significance"},
      {"validate {S} --significance nan -o {o}", 2, "--significance"},
      {"validate {S} --theta 90 -o {o}", 2, "--theta"},
      {"validate --suite {T}suite_dotdot.json -o {o}", 2, "../x"},
      {"validate --suite {T}suite_slash.json -o {o}", 2, "a/b"},
      {"validate --suite {T}suite_twice.json -o {o}", 2, "twice"},
      {"validate --suite {T}suite_alpha.json -o {o}", 2, "--alpha"},
      {"validate --suite {T}missing.json -o {o}", 2, "missing"},
      // JSON nested too deep or too large: refused naming the file.
      {"info {T}deepdesc.exr", 2, "deepdesc.exr header"},
      {"measure ndf {T}deepmacro.exr -o {o}", 2, "deepmacro.exr header"},
      {"measure ndf {T}deep.ply -o {o}", 2, "deep.ply.json"},
      {"validate --suite {T}suite_deep.json -o {o}", 2, "suite_deep.json"},
      {"validate --suite {T}suite_large.json -o {o}", 2, "suite_large.json"},
      {"merge {T}part_deep.json -o {o}", 2, "part_deep.json"},
      // Work sized by the options is checked against memory before it is allocated.
      {"measure g1 {S} --rays 1000000000000 -o {o}", 2, "--rays"},
      {"validate {S} --rays 1000000000000 -o {o}", 2, "--rays"},
      {"measure bsdf {S} --material mirror --theta-i 0:89:0.001 --resolution 1 --table-resolution 512 "
       "--rays 10 --no-models -o {o}", 2, "--table-resolution", "bsdf"},
      // Special files are refused before they are opened (a FIFO without a writer would block).
      {"info {T}fifo.exr", 2, "FIFO"},
      {"measure g1 {T}fifo.exr --rays 100 -o {o}", 2, "FIFO"},
      {"info {T}folder.exr", 2, "folder"},
      {"generate heightmap --input {T}fifo.csv --pixel-size 1 -o {o}", 2, "FIFO", "exr"},
      {"generate mesh --input {T}fifo.ply -o {o}", 2, "FIFO", "ply"},
      {"generate gaussian --config {T}fifo.toml -o {o}", 2, "FIFO", "exr"},
      {"validate --suite {T}fifo.json -o {o}", 2, "FIFO"},
      {"merge {T}fifo.json -o {o}", 2, "FIFO"},
      // Lists: an empty item anywhere is refused (a trailing comma as much as a leading one).
      {"measure g1 {S} --theta 10,20, --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --theta ,10,20 --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --theta 10,,20 --rays 100 -o {o}", 2, "--theta"},
      {"measure g1 {S} --theta 0:80: --rays 100 -o {o}", 2, "--theta"},
      {"measure g2 {S} --theta-o 30, --theta-i 30 --rays 100 -o {o}", 2, "--theta-o"},
      {"measure bsdf {S} --material mirror --theta-i 0,30, --rays 100 -o {o}", 2, "--theta-i"},
      {"generate parallelepiped --matrix 1,0,0,0,1,0,0,0,1, -o {o}", 2, "--matrix", "ply"},
      {"validate {S} --checks '' --rays 100 -o {o}", 2, "--checks"},
      {"validate {S} --checks g1, --rays 100 -o {o}", 2, "--checks"},
      // Azimuths: a value that makes no direction names its own option.
      {"measure g1 {S} --phi 1e308 --rays 100 -o {o}", 2, "--phi"},
      {"measure g2 {S} --theta-o 30 --theta-i 30 --phi-i 1e308 --rays 100 -o {o}", 2, "--phi-i"},
      {"measure g2 {S} --theta-o 30 --theta-i 30 --phi-o -1e308 --rays 100 -o {o}", 2, "--phi-o"},
      {"measure vndf {S} --phi 1e308 --rays 100 -o {o}", 2, "--phi"},
      {"validate {S} --phi 1e308 --rays 100 -o {o}", 2, "--phi"},
      {"measure g1 {S} --phi -3600,3600 --theta 30 --rays 100 -o {o}", 0, ""},
      // Sizes whose surface no reader would accept (an area of 0 or inf, facets without area).
      {"generate heightmap --input {T}hm.csv --pixel-size 1e-300 --periodic -o {o}", 2, "--pixel-size", "exr"},
      {"generate heightmap --input {T}hm.csv --pixel-size 1e200 --periodic -o {o}", 2, "--pixel-size", "exr"},
      {"generate square-wave --duty 1e-300 -o {o}", 2, "--duty", "ply"},
      {"generate square-wave --duty 1e-300 --2d -o {o}", 2, "--duty", "ply"},
      {"generate box --width 1e-300 -o {o}", 2, "--width", "ply"},
      {"generate heightmap --input {T}hm.csv --pixel-size 1e-3 --periodic -o {o}", 0, "", "exr"},
      // Heights: only NaN and --nodata are missing; an infinite one is refused where it is.
      {"generate heightmap --input {T}hm_inf.csv --pixel-size 1 -o {o}", 2, "row 5", "exr"},
      {"generate heightmap --input {T}hm_neginf.csv --pixel-size 1 -o {o}", 2, "row 5", "exr"},
      {"generate heightmap --input {T}hm_1e999.csv --pixel-size 1 -o {o}", 2, "row 5", "exr"},
      {"generate heightmap --input {T}hm_100.csv --pixel-size 1 --height-scale 1e307 -o {o}", 2, "--height-scale", "exr"},
      {"generate heightmap --input {T}hm_nan.csv --pixel-size 1 -o {o}", 0, "", "exr"},
      // Suites: seeds are distinct integers in [0, 2^64-1]; type errors name the entry and key.
      {"validate --suite {T}suite_seedneg.json -o {o}", 2, "entry g: seeds"},
      {"validate --suite {T}suite_seedfrac.json -o {o}", 2, "entry g: seeds"},
      {"validate --suite {T}suite_seedbig.json -o {o}", 2, "entry g: seeds"},
      {"validate --suite {T}suite_seedtwice.json -o {o}", 2, "twice"},
      {"validate --suite {T}suite_thetastr.json -o {o}", 2, "entry g: theta_deg"},
      {"validate --suite {T}suite_checksempty.json -o {o}", 2, "entry g: checks"},
      {"validate --suite {T}suite_phihuge.json -o {o}", 2, "entry g: phi_deg"},
      // Merge: counts are non-negative integers, named by part and field.
      {"merge {T}part_neg.json {T}sharded.json.shard-2-of-2.json -o {o}", 2, "part_neg.json"},
      {"merge {T}part_neg.json {T}sharded.json.shard-2-of-2.json -o {o}", 2, "counts[0]"},
      {"merge {T}part_frac.json {T}sharded.json.shard-2-of-2.json -o {o}", 2, "counts[0]"},
      {"merge {T}part_huge.json {T}sharded.json.shard-2-of-2.json -o {o}", 2, "counts[0]"},
      {"merge {T}part_more.json {T}sharded.json.shard-2-of-2.json -o {o}", 2, "hits exceed"},
      {"merge {T}sharded.json.shard-1-of-2.json {T}sharded.json.shard-2-of-2.json -o {o}", 0, ""},
      {"merge /dev/stdin {T}sharded.json.shard-2-of-2.json -o {o} < {T}sharded.json.shard-1-of-2.json", 0, ""},
      // Presets hold parameters, not the files of the run; a heightmap preset applies.
      {"generate gaussian --config {T}p_output.toml --resolution 16 -o {o}", 2, "'output'", "exr"},
      {"generate heightmap --config {T}p_input.toml --input {T}hm.csv --pixel-size 1 -o {o}", 2, "'input'", "exr"},
      {"generate heightmap --config {T}p_pixel.toml --input {T}hm.csv -o {o}", 0, "", "exr"},
  };
  return c;
}
}  // namespace

TEST_F(Inputs, EveryBadOptionOrFileIsRefusedWithOneLineAndNoOutput) {
  int failed = 0, n = 0;
  const std::string dir = folder();
  for (const Case& c : cases()) {
    const std::string out = tmp("case" + std::to_string(n++) + "." + c.ext);
    const std::string args = expand(c.args, out, surface_, mesh_);
    SCOPED_TRACE(args);
    Result r = run_limited(args);
    bool ok = r.code == c.code;
    EXPECT_EQ(r.code, c.code) << r.err;
    if (c.code == 2) {
      ok = ok && lines(r.err) == 1 && r.err.find(c.needle) != std::string::npos;
      EXPECT_EQ(lines(r.err), 1) << r.err;
      EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
      for (const std::string& p : {out, out + ".json", out + ".xyz", out + "/surface.exr", out + "/ndf.json"}) {
        EXPECT_FALSE(exists(p)) << p;
        ok = ok && !exists(p);
      }
    }
    EXPECT_EQ(leftover_temporaries(dir), 0);
    fs::remove_all(out);
    fs::remove(out + ".json");
    failed += !ok;
  }
  std::cout << "[ table    ] " << cases().size() << " cases, " << failed << " not as expected\n";
}

// A byte order mark and CRLF line ends change nothing: every variant gives the plain file's
// 40 x 40 grid and the same heights.
TEST_F(Inputs, TextHeightmapsReadTheSameWithByteOrderMarkAndCrlf) {
  auto grid_of = [&](const std::string& csv) {
    const std::string out = tmp(csv + ".exr"), info = tmp(csv + ".info.json");
    Result r = run_microsim("generate heightmap --input " + tmp(csv) + " --pixel-size 1 --periodic -o " + out);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(run_microsim("info " + out + " --json " + info).code, 0);
    const auto j = nlohmann::json::parse(slurp(info));
    return std::make_tuple(j["surface"]["resolution_x"].get<int>(), j["surface"]["resolution_y"].get<int>(),
                           j["surface"]["detrend_coefficients"].dump());
  };
  const auto plain = grid_of("hm.csv");
  EXPECT_EQ(std::get<0>(plain), 40);
  EXPECT_EQ(std::get<1>(plain), 40);
  for (const char* csv : {"hm_bom.csv", "hm_crlf.csv", "hm_bom_crlf.csv"}) {
    SCOPED_TRACE(csv);
    EXPECT_EQ(grid_of(csv), plain);
  }
}

// The ranges the help shows are the ranges the checks apply: a value at the help's upper end
// is accepted by the check (no "[1, 64]" in the help beside a check of [1, 16]).
TEST_F(Inputs, HelpRangesAreTheChecksRanges) {
  const Result help = run_microsim("measure bsdf --help");
  ASSERT_EQ(help.code, 0);
  for (const std::string& option : {std::string("--orders"), std::string("--resolution"), std::string("--table-resolution")}) {
    SCOPED_TRACE(option);
    const auto at = help.out.find(option + " INT:in [");
    ASSERT_NE(at, std::string::npos) << help.out;
    const auto comma = help.out.find(", ", at), close = help.out.find(']', at);
    const std::string hi = help.out.substr(comma + 2, close - comma - 2);
    Result r = run_microsim("measure bsdf " + surface_ + " --material mirror --theta-i 30 --rays 10 --no-models " +
                            option + " " + hi + " -o " + tmp("help_range.json"));
    EXPECT_EQ(r.code, 0) << r.err;
    r = run_microsim("measure bsdf " + surface_ + " --material mirror --theta-i 30 --rays 10 --no-models " +
                     option + " " + std::to_string(std::stoll(hi) + 1) + " -o " + tmp("help_range.json"));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
  }
  // render's light stays above the horizon: the help's interval is half-open like the check.
  const Result render = run_microsim("render --help");
  EXPECT_NE(render.out.find("--light-theta FLOAT:in [0, 90)"), std::string::npos) << render.out;
}

TEST_F(Inputs, PresetsApplyWithNonDefaultValuesAndTheCommandLineWins) {
  const std::string preset = tmp("p_good.toml"), out = tmp("preset.exr"), info = tmp("preset_info.json");
  write_file(preset, "# a preset\nresolution = 32\nalpha = 0.7\nseed = 5\nsize = 2.0\n"
                     "correlation-length = 0.125  # four cells\n");
  ASSERT_EQ(run_microsim("generate gaussian --config " + preset + " -o " + out).code, 0);
  ASSERT_EQ(run_microsim("info " + out + " --json " + info).code, 0);
  auto j = nlohmann::json::parse(slurp(info));
  EXPECT_EQ(j["surface"]["resolution"], 32);
  EXPECT_EQ(j["surface"]["alpha_x"], 0.7);
  EXPECT_EQ(j["surface"]["alpha_y"], 0.7);
  EXPECT_EQ(j["surface"]["seed"], 5);
  EXPECT_EQ(j["macrosurface"]["size_x"], 2.0);
  // The command line overrides the file, option by option.
  ASSERT_EQ(run_microsim("generate gaussian --config " + preset + " --alpha 0.3 --resolution 16 -o " + out).code, 0);
  ASSERT_EQ(run_microsim("info " + out + " --json " + info).code, 0);
  j = nlohmann::json::parse(slurp(info));
  EXPECT_EQ(j["surface"]["resolution"], 16);
  EXPECT_EQ(j["surface"]["alpha_x"], 0.3);
  EXPECT_EQ(j["surface"]["seed"], 5);
  // --alpha-x on the command line with --alpha in the preset: the two conflict, as on the
  // command line alone.
  EXPECT_EQ(run_microsim("generate gaussian --config " + preset + " --alpha-x 0.3 -o " + out).code, 2);
  // The box preset's height (0.5, not the default 1): the visible box reaches z = 0.5.
  const std::string box = tmp("box.ply"), boxinfo = tmp("box_info.json");
  ASSERT_EQ(run_microsim("generate box --config " + kSrc + "/surfaces/box.toml -o " + box).code, 0);
  ASSERT_EQ(run_microsim("info " + box + " --json " + boxinfo).code, 0);
  j = nlohmann::json::parse(slurp(boxinfo));
  EXPECT_EQ(j["surface"]["height"], 0.5);
  // demo takes the same presets.
  const std::string demo = tmp("demo");
  Result r = run_microsim("demo --config " + preset + " --resolution 16 --theta 30 --rays 2000 --out-dir " + demo);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("alpha (0.7, 0.7)"), std::string::npos) << r.out;
}

// Every shipped preset loads with its generator and gives its declared values.
TEST_F(Inputs, EveryShippedPresetLoadsAndGivesItsValues) {
  const std::vector<std::pair<std::string, std::string>> presets = {
      {"beckmann-0.5", "gaussian"}, {"box", "box"}, {"ellipsoid", "ellipsoid"}, {"flat", "flat"},
      {"gaussian-ggx", "gaussian-ggx"}, {"parallelepiped", "parallelepiped"},
      {"square-wave", "square-wave"}, {"tiled-boxes", "tiled-boxes"}, {"vcavity", "vcavity"},
      {"vgroove", "vgroove"}};
  for (const auto& [name, kind] : presets) {
    SCOPED_TRACE(name);
    const bool heightfield = kind == "gaussian" || kind == "gaussian-ggx" || kind == "flat" || kind == "vgroove";
    // Big presets are made small from the command line (which wins); the rest is the file's.
    std::string small = kind == "gaussian" ? " --resolution 32 --correlation-length 0.125"
                        : kind == "gaussian-ggx" ? " --resolution 64 --correlation-length 0.0625"
                        : kind == "ellipsoid" ? " --rings 8 --segments 32"
                        : kind == "vcavity" ? " --grooves 16" : "";
    const std::string out = tmp("preset_" + name + (heightfield ? ".exr" : ".ply"));
    const std::string info = tmp("preset_" + name + "_info.json");
    Result r = run_microsim("generate " + kind + " --config " + kSrc + "/surfaces/" + name + ".toml" + small +
                            " -o " + out);
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_EQ(run_microsim("info " + out + " --json " + info).code, 0);
    auto d = nlohmann::json::parse(slurp(info))["surface"];
    // Every key of the preset that the description records has the preset's value.
    std::ifstream f(kSrc + "/surfaces/" + name + ".toml");
    int compared = 0;
    for (std::string line; std::getline(f, line);) {
      if (line.empty() || line[0] == '#' || line.find('=') == std::string::npos) continue;
      std::string key = line.substr(0, line.find('=')), value = line.substr(line.find('=') + 1);
      key.erase(key.find_last_not_of(' ') + 1);
      value = value.substr(value.find_first_not_of(' '));
      if (small.find("--" + key + " ") != std::string::npos) continue;
      std::string field = key;
      for (char& ch : field) ch = ch == '-' ? '_' : ch;
      if (field == "two_d") field = "two_d";
      if (!d.contains(field)) continue;
      ++compared;
      if (d[field].is_number()) {
        EXPECT_DOUBLE_EQ(d[field].get<double>(), std::stod(value)) << key;
      } else if (d[field].is_string()) {
        EXPECT_EQ("\"" + d[field].get<std::string>() + "\"", value) << key;
      }
    }
    EXPECT_GT(compared, 0) << "no preset value recorded in the description of " << name;
  }
}

// Suites' presets apply: a suite entry's preset gives its values to the generated surface.
TEST_F(Inputs, SuitePresetsApply) {
  const std::string preset = tmp("p_suite.toml"), suite = tmp("suite_preset.json"), dir = tmp("suite_dir");
  write_file(preset, "resolution = 16\nalpha = 0.7\nseed = 9\n");
  write_file(suite, "{\"defaults\": {\"rays\": 1000, \"theta_deg\": [0], \"checks\": [\"d_identities\"]}, "
                    "\"entries\": [{\"name\": \"g\", \"generate\": \"gaussian\", \"preset\": \"" + preset + "\"}]}");
  Result r = run_microsim("validate --suite " + suite + " --surfaces-dir " + dir + " -o " + tmp("suite_out.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string info = tmp("suite_info.json");
  ASSERT_EQ(run_microsim("info " + dir + "/g.exr --json " + info).code, 0);
  auto j = nlohmann::json::parse(slurp(info));
  EXPECT_EQ(j["surface"]["resolution"], 16);
  EXPECT_EQ(j["surface"]["alpha_x"], 0.7);
  EXPECT_EQ(j["surface"]["seed"], 9);
}

// All outputs of a command or none: bsdf's table and summary, a mesh and its sidecar, when one of
// them cannot be written (its name is taken by a folder).
TEST_F(Inputs, AllOutputsOrNone) {
  const std::string mesh = tmp("pair.ply");
  fs::create_directories(mesh + ".json");  // the sidecar cannot be written
  Result r = run_microsim("generate box -o " + mesh);
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(exists(mesh));
  fs::remove_all(mesh + ".json");
  const std::string exr = tmp("pair.exr");
  const std::string summary = exr.substr(0, exr.size() - 4) + ".json";
  fs::create_directories(summary);
  r = run_microsim("measure bsdf " + surface_ + " --material mirror --theta-i 30 --phi-i 0 --rays 2000 -o " + exr);
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(exists(exr));
  fs::remove_all(summary);
  EXPECT_EQ(leftover_temporaries(folder()), 0);
}

namespace {
// Starts microsim with `args` (no shell), TMPDIR set to `tmpdir`; returns the child's pid.
pid_t spawn(const std::vector<std::string>& args, const std::string& tmpdir) {
  std::vector<std::string> env = {"TMPDIR=" + tmpdir};
  for (char** e = environ; *e; ++e)
    if (std::string(*e).rfind("TMPDIR=", 0) != 0) env.push_back(*e);
  std::vector<char*> argv, envp;
  static std::string bin;
  bin = binary();
  argv.push_back(bin.data());
  std::vector<std::string> a = args;
  for (auto& s : a) argv.push_back(s.data());
  argv.push_back(nullptr);
  for (auto& s : env) envp.push_back(s.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  posix_spawn(&pid, bin.c_str(), &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}
}  // namespace

// SIGINT at random moments of measure and validate runs: the process ends by the signal and
// leaves neither its output nor a temporary file or folder.
TEST_F(Inputs, InterruptsLeaveNothingBehind) {
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> delay_ms(20, 900);
  const std::string suite = tmp("suite_interrupt.json");
  write_file(suite, "{\"defaults\": {\"rays\": 400000, \"theta_deg\": [0, 60], \"checks\": [\"g1\"]}, "
                    "\"entries\": [{\"name\": \"g\", \"generate\": \"gaussian\", \"args\": "
                    "{\"resolution\": 32}, \"seeds\": [1, 2, 3, 4]}]}");
  int interrupted = 0;
  for (int k = 0; k < 6; ++k) {
    const std::string dir = tmp("interrupt" + std::to_string(k));
    fs::create_directories(dir);
    const std::string out = dir + "/out.json";
    std::vector<std::string> args;
    if (k % 2 == 0)
      args = {"measure", "g1", surface_, "--theta", "0:80:10", "--rays", "3000000", "-o", out};
    else
      args = {"validate", "--suite", suite, "-o", out};
    const int ms = delay_ms(rng);
    SCOPED_TRACE(args[0] + " interrupted after " + std::to_string(ms) + " ms");
    pid_t pid = spawn(args, dir);
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    kill(pid, SIGINT);
    // An interrupted run must end promptly: a cleanup that deadlocks (e.g. allocating inside a
    // signal handler while the interrupted thread holds the allocator's lock) fails here.
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        FAIL() << "still running 120 s after SIGINT";
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (WIFSIGNALED(status)) {
      ++interrupted;
      EXPECT_EQ(WTERMSIG(status), SIGINT);
      int left = 0;
      for (const auto& e : fs::directory_iterator(dir)) {
        ADD_FAILURE() << "left behind: " << e.path();
        ++left;
      }
      EXPECT_EQ(left, 0);
    } else {  // finished before the signal: then its output is complete
      EXPECT_EQ(WEXITSTATUS(status), 0);
      EXPECT_TRUE(nlohmann::json::accept(slurp(out)));
    }
    fs::remove_all(dir);
  }
  EXPECT_GE(interrupted, 4);
}

namespace {
// A copy of the 16^2 heightfield `from` whose header declares n x n pixels (data and display
// windows patched; the line offset table padded with zeros, i.e. no pixel data): what a tile
// of that size looks like to everything that reads the header before the pixels.
std::string declared_tile(const std::string& from, int n, const std::string& name) {
  std::ifstream f(from, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  for (const char* attr : {"dataWindow", "displayWindow"}) {
    const std::string key = std::string(attr) + '\0' + "box2i" + '\0';
    const auto at = bytes.find(key);
    if (at == std::string::npos) return "";
    const std::int32_t box[4] = {0, 0, n - 1, n - 1};
    bytes.replace(at + key.size() + 4, 16, reinterpret_cast<const char*>(box), 16);
  }
  bytes += std::string(8 * static_cast<std::size_t>(n), '\0');
  const std::string path = tmp(name);
  write_file(path, bytes);
  return path;
}

// ulimit -v in KiB (the address-space limit microsim reads as the memory it may use).
std::string limit_gib(int gib) {
  return "ulimit -v " + std::to_string(static_cast<long long>(gib) << 20) + "; timeout 60";
}
}  // namespace

// A tile that cannot fit is refused before anything is allocated: exit 2, one line naming the
// option or the file and the estimate, no output, at once. 16384^2 is estimated at about 5 GiB
// to generate and 10 GiB to trace (40 bytes per cell); the address-space limits below make both
// too large on any machine. Power checks: a size that fits under the same limit is not refused.
TEST_F(Inputs, TilesLargerThanTheMemoryAreRefusedBeforeAllocating) {
  if (kAddressSanitizer) GTEST_SKIP() << "no address-space limit under AddressSanitizer";
  const std::string out = tmp("big-tile.exr");
  auto t0 = std::chrono::steady_clock::now();
  Result r = run_microsim("generate gaussian --resolution 16384 -o " + out, limit_gib(4));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--resolution 16384 needs about"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(out));
  EXPECT_LT(seconds, 20.0);  // refused, not synthesized (a 16384^2 synthesis takes minutes)
  r = run_microsim("generate gaussian --resolution 256 -o " + out, limit_gib(4));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(exists(out));

  const std::string huge = declared_tile(surface_, 16384, "declared16384.exr");
  const std::string small = declared_tile(surface_, 256, "declared256.exr");
  ASSERT_FALSE(huge.empty());
  ASSERT_FALSE(small.empty());
  const std::string json = tmp("big-tile.json");
  for (const std::string& cmd : {"measure g1 {F} --theta 60 --rays 1000 -o " + json,
                                 "measure ndf {F} -o " + json,
                                 "measure bsdf {F} --material mirror --theta-i 30 --rays 1000 -o " + json,
                                 "info {F} --json " + json}) {
    const auto with = [&](const std::string& file) {
      std::string a = cmd;
      a.replace(a.find("{F}"), 3, file);
      return a;
    };
    SCOPED_TRACE(cmd);
    t0 = std::chrono::steady_clock::now();
    r = run_microsim(with(huge), limit_gib(8));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(huge + " (16384 x 16384 heightfield) needs about"), std::string::npos) << r.err;
    EXPECT_FALSE(exists(json));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
    // 256^2 fits: not refused for memory (it then fails on its missing pixels).
    r = run_microsim(with(small), limit_gib(8));
    EXPECT_EQ(r.err.find("needs about"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("declared256.exr"), std::string::npos) << r.err;
    fs::remove(json);
  }
}

// G2 holds its list of work units (32 bytes per 8192 points; a unit's counts only while its pass
// runs): 1e12 points are about 3.9 GB of units, refused under a 2 GiB address-space limit (1.6 GiB
// usable) before anything is traced; power: a small run under the same limit is not refused.
TEST_F(Inputs, G2RaysWhoseWorkUnitsCannotFitAreRefused) {
  if (kAddressSanitizer) GTEST_SKIP() << "no address-space limit under AddressSanitizer";
  const std::string json = tmp("g2-units.json");
  const std::string g2 = "measure g2 " + surface_ + " --theta-o 30 --theta-i 30 -o " + json + " --rays ";
  Result r = run_microsim(g2 + "1000000000000", limit_gib(2));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--rays 1000000000000 (122070368 work units, 144 normal bins) needs about"), std::string::npos)
      << r.err;
  EXPECT_FALSE(exists(json));
  r = run_microsim(g2 + "10000", limit_gib(2));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(exists(json));
}

// `info` on a non-periodic window holds its ACF zero-padded to 2 nx x 2 ny (complex doubles,
// 64 bytes per height, beside the 4 of the heights: metrology_bytes), more than the 40 bytes per
// cell of tracing it: a window whose metrology cannot fit is refused from its header, before
// any pixel is allocated. Under a 2 GiB address-space limit (1.6 GiB usable), a declared 5500^2
// window needs about 1.9 GiB and is refused; power: the same size as a periodic tile (about 1.1
// GiB) is not refused for memory, by `info` or by `measure g1` on the window.
TEST_F(Inputs, WindowsWhoseMetrologyCannotFitAreRefusedByInfo) {
  if (kAddressSanitizer) GTEST_SKIP() << "no address-space limit under AddressSanitizer";
  std::string csv;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 16; ++i) csv += std::to_string(std::sin(0.7 * i) * std::cos(0.4 * j + 0.1 * i)) + (i < 15 ? "," : "\n");
  write_file(tmp("window.csv"), csv);
  const std::string window = tmp("window16.exr");
  ASSERT_EQ(run_microsim("-q generate heightmap --input " + tmp("window.csv") + " --pixel-size 1 --guard-width 2 -o " + window).code, 0);
  const std::string big_window = declared_tile(window, 5500, "declared_window5500.exr");
  const std::string big_tile = declared_tile(surface_, 5500, "declared_tile5500.exr");
  ASSERT_FALSE(big_window.empty());
  ASSERT_FALSE(big_tile.empty());
  const std::string json = tmp("window-info.json");
  Result r = run_microsim("info " + big_window + " --json " + json, limit_gib(2));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(big_window + " (5500 x 5500 heightfield, a non-periodic window) needs about 1.9"),
            std::string::npos) << r.err;
  EXPECT_FALSE(exists(json));
  for (const std::string& cmd : {"info " + big_tile + " --json " + json,
                                 "measure g1 " + big_window + " --theta 60 --rays 1000 -o " + json}) {
    r = run_microsim(cmd, limit_gib(2));
    EXPECT_EQ(r.err.find("needs about"), std::string::npos) << cmd << "\n" << r.err;
    EXPECT_NE(r.err.find("declared_"), std::string::npos) << cmd << "\n" << r.err;  // its missing pixels
    fs::remove(json);
  }
}
