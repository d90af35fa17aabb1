#include "app.hpp"

#include "microsim/io/output.hpp"

namespace microsim::cli {

namespace {
// A CLI::App that also owns the TBB limit set by --threads.
struct AppWithThreads : CLI::App {
  using CLI::App::App;
  std::unique_ptr<tbb::global_control> threads;
};
}  // namespace

std::unique_ptr<CLI::App> build_app(GlobalOptions& g) {
  auto owned = std::make_unique<AppWithThreads>(
      "microsim: explicit microsurface Monte Carlo simulator.\n"
      "Builds microgeometry, ray-traces it with Embree, measures D, G1 (and more) with "
      "standard errors beside the analytic Smith model.",
      "microsim");
  AppWithThreads& app = *owned;
  app.require_subcommand(1);
  app.fallthrough();  // --threads and --quiet are accepted after the subcommand too
  app.add_option("--threads", g.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  app.add_flag("--quiet,-q", g.quiet, "No progress display and no table on stdout");
  app.set_version_flag("--version", "microsim 0.1.0");
  // Runs before the subcommand callbacks.
  app.parse_complete_callback([&app, &g] {
    if (g.threads > 0)
      app.threads = std::make_unique<tbb::global_control>(
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
  return owned;
}

std::string unknown_command(const CLI::App& app, const std::vector<std::string>& args) {
  const CLI::App* level = &app;
  for (std::size_t k = 0; k < args.size() && !args[k].empty() && args[k][0] != '-' &&
                          !level->get_subcommands({}).empty();
       ++k) {
    std::string names;
    const CLI::App* next = nullptr;
    for (const auto* sub : level->get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      if (sub->get_name() == args[k]) next = sub;
    }
    if (!next)
      return std::string("unknown ") + (level->get_name() == "generate" ? "surface kind" : "command") +
             " '" + args[k] + "' (known: " + names + ")";
    level = next;
  }
  return "";
}

void run_app(CLI::App& app, const std::vector<std::string>& args) {
  // CLI11 takes the arguments in reverse order, without the program name.
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  OutputTransaction outputs;
  app.parse(reversed);
  outputs.commit();
}

}  // namespace microsim::cli
