// The library's usage errors name domain parameters ("{theta_i}"); each front end spells them:
// the command line as its options (--theta-i, -o), Python as its keywords (theta_i). Text given
// by the user (paths, values) keeps its braces, and errors wrapped on their way out keep their
// parameters.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "../src/cli/option_checks.hpp"
#include "cli_helpers.hpp"
#include "microsim/api/bsdf_request.hpp"
#include "microsim/common.hpp"
#include "microsim/surface/surface_spec.hpp"

namespace {
using namespace microsim;
using microsim::testing::run_microsim;
using microsim::testing::temp_path;

// Python's spelling (python/src/module.cpp): the keyword argument of the same name.
std::string keyword(std::string_view parameter) { return std::string(parameter); }

template <class F>
ParameterError parameter_error(F f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ParameterError: " << e.what();
  }
  ADD_FAILURE() << "nothing thrown";
  return ParameterError("");
}

TEST(ParameterErrors, OptionsOnTheCommandLineKeywordsInPython) {
  EXPECT_EQ(spell_parameters("{theta_i} entries must be in [0, 90)", cli::option_spelling),
            "--theta-i entries must be in [0, 90)");
  EXPECT_EQ(spell_parameters("{theta_i} entries must be in [0, 90)", keyword), "theta_i entries must be in [0, 90)");
  EXPECT_EQ(spell_parameters("{height_scale} 0 and {rays}", cli::option_spelling), "--height-scale 0 and --rays");
  // The parameter whose option is not "--" and its name.
  EXPECT_EQ(cli::option_spelling("output"), "-o");
  EXPECT_EQ(spell_parameters("{output} x.exr", keyword), "output x.exr");
}

TEST(ParameterErrors, OnlyBracedParameterNamesArePlaceholders) {
  const auto cli = [](std::string_view m) { return spell_parameters(m, cli::option_spelling); };
  EXPECT_EQ(cli("{{rays}"), "{rays}");  // a doubled brace is one literal brace
  EXPECT_EQ(cli("{Rays} {a-b} {} { rays} {rays"), "{Rays} {a-b} {} { rays} {rays");
  EXPECT_EQ(cli("a}b{"), "a}b{");
  // User text inside a message comes back as given, braces and all.
  for (const std::string text : {"{rays}", "{\"theta\": {\"a\": 1}}", "{{", "}{x}{", "/tmp/{a_b}/x.exr", ""})
    EXPECT_EQ(cli("{input} " + literal_text(text)), "--input " + text) << text;
}

TEST(ParameterErrors, ALibraryMessageSpelledBothWays) {
  BsdfRequest r;
  r.material = "mirror";
  r.theta_i_deg = {95};
  r.phi_i_deg = {0};
  const ParameterError angle = parameter_error([&] { r.check(); });
  EXPECT_EQ(cli::cli_message(angle), "--theta-i must be in [0, 90) degrees (got 95.00)");
  EXPECT_EQ(spelled_message(angle, keyword), "theta_i must be in [0, 90) degrees (got 95.00)");

  r.theta_i_deg = {30};
  r.eta = 1.5;
  const ParameterError material = parameter_error([&] { bsdf_material(r); });
  EXPECT_EQ(cli::cli_message(material), "--eta and --k apply to --material conductor or dielectric, not mirror");
  EXPECT_EQ(spelled_message(material, keyword), "eta and k apply to material conductor or dielectric, not mirror");

  r.eta.reset();
  r.phi_i_deg = {0, 10};
  r.format = "binary";
  const ParameterError output = parameter_error([&] { r.check(); });
  EXPECT_EQ(cli::cli_message(output), "-o .binary: MERL tables are isotropic; give one --phi-i (got 2 azimuths)");
  EXPECT_EQ(spelled_message(output, keyword), "output .binary: MERL tables are isotropic; give one phi_i (got 2 azimuths)");
}

TEST(ParameterErrors, AWrappedErrorKeepsItsParametersAndTheFilesBraces) {
  // A preset whose path has braces: the file is named as it is, the key as a parameter.
  const std::string path = temp_path("params", "{alpha}.toml");
  std::ofstream(path) << "alpha = -1\n";
  SurfaceRequest r{"gaussian", {}};
  const ParameterError e = parameter_error([&] { read_surface_preset(r, path); });
  const std::string tail = ": line 1: ";
  EXPECT_EQ(cli::cli_message(e).rfind(path + tail + "--alpha: must be a finite number in (0, 10] (got -1)", 0), 0u)
      << cli::cli_message(e);
  EXPECT_EQ(spelled_message(e, keyword).rfind(path + tail + "alpha: must be", 0), 0u) << spelled_message(e, keyword);
}

TEST(ParameterErrors, OtherUsageErrorsArePrintedAsTheyAre) {
  EXPECT_EQ(cli::cli_message(UsageError("{rays} as written")), "{rays} as written");
  EXPECT_EQ(spelled_message(UsageError("{rays} as written"), keyword), "{rays} as written");
}

TEST(ParameterErrors, TheProgramPrintsOptionsAndTheValueAsGiven) {
  const std::string out = temp_path("params", "v.ply");
  const auto r = run_microsim("generate vcavity --ndf '{alpha}' -o " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "microsim: error: --ndf must be beckmann or ggx (got '{alpha}')\n");
}

}  // namespace
