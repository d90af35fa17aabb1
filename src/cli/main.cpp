// microsim command line: CLI11 parsing; each command lives in src/cli/cmd_*.cpp and runs from
// its callback. Usage errors exit 2 with one line, runtime failures exit 1.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "microsim/io/output.hpp"

using namespace microsim;
using namespace microsim::cli;

namespace {
// An unknown command or surface kind names itself (CLI11 would only say that a subcommand is
// missing): walk the leading words down the command tree. Returns false after printing.
bool check_command_words(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  for (int k = 1; k < argc && argv[k][0] != '-' && !level->get_subcommands({}).empty(); ++k) {
    std::string names;
    const CLI::App* next = nullptr;
    for (const auto* sub : level->get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      if (sub->get_name() == argv[k]) next = sub;
    }
    if (!next) {
      std::cerr << "microsim: error: unknown "
                << (level->get_name() == "generate" ? "surface kind" : "command") << " '"
                << argv[k] << "' (known: " << names << ")\n";
      return false;
    }
    level = next;
  }
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"microsim: explicit microsurface Monte Carlo simulator.\n"
               "Builds microgeometry, ray-traces it with Embree, measures D, G1 (and more) with "
               "standard errors beside the analytic Smith model."};
  app.require_subcommand(1);
  app.fallthrough();  // --threads and --quiet are accepted after the subcommand too
  GlobalOptions g;
  std::unique_ptr<tbb::global_control> threads;
  app.add_option("--threads", g.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  app.add_flag("--quiet,-q", g.quiet, "No progress display and no table on stdout");
  app.set_version_flag("--version", "microsim 0.1.0");
  // Runs before the subcommand callbacks.
  app.parse_complete_callback([&] {
    if (g.threads > 0)
      threads = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, g.threads);
  });

  register_demo(app, g);
  register_generate(app, g);
  register_info(app, g);
  register_convert(app, g);
  auto* measure = app.add_subcommand("measure", "Measure a quantity on a surface");
  measure->require_subcommand(1);
  register_measure_ndf(*measure, g);
  register_measure_g1(*measure, g);
  register_measure_g2(*measure, g);
  register_measure_vndf(*measure, g);
  register_validate(app, g);
  register_measure_bsdf(*measure, g);
  register_render(app, g);

  if (!check_command_words(app, argc, argv)) return 2;
  // Every output of the command (main file, sidecar, tables) is renamed into place together once
  // the command has succeeded; an error or an interrupt leaves no file and no temporary behind.
  install_interrupt_cleanup();
  OutputTransaction outputs;
  try {
    app.parse(argc, argv);
    outputs.commit();
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "microsim: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
