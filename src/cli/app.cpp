#include "app.hpp"

#include <chrono>
#include <iostream>

#include "microsim/version.hpp"
#include "microsim/io/output.hpp"
#include "option_checks.hpp"
#include "output_paths.hpp"

namespace microsim::cli {

MpiRanks& mpi_ranks() {
  static MpiRanks ranks;
  return ranks;
}

std::unique_ptr<MicrosimApp> build_app(GlobalOptions& g, TallyReplay* replay) {
  auto owned = std::make_unique<MicrosimApp>(
      "microsim: explicit microsurface Monte Carlo simulator.\n"
      "Builds microgeometry, ray-traces it with Embree, measures D, G1 (and more) with "
      "standard errors beside the analytic Smith model.",
      "microsim");
  MicrosimApp& app = *owned;
  const MpiRanks& mpi = mpi_ranks();
  app.require_subcommand(1);
  app.fallthrough();  // --threads and --quiet are accepted after the subcommand too
  app.add_option("--threads", g.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  app.add_flag("--quiet,-q", g.quiet, "No progress display and no table on stdout");
  app.add_option("--shard", app.shard_text,
                 "K/N: compute shard K of N of a measure g1|g2|vndf|bsdf or validate run and write "
                 "its partial record to OUTPUT.shard-K-of-N.json (microsim merge joins them)");
  app.set_version_flag("--version", std::string("microsim ") + version());
  // Runs before the subcommand callbacks.
  app.parse_complete_callback([&app, &g, &mpi, replay] {
    if (g.threads > 0)
      app.threads = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, g.threads);
    std::vector<std::string> words;
    for (const CLI::App* level = &app; !level->get_subcommands().empty();) {
      level = level->get_subcommands().front();
      words.push_back(level->get_name());
    }
    // Before any work: an output must not replace an input of the same run.
    refuse_outputs_naming_inputs(app, app.shard_text);
    if ((!app.shard_text.empty() || mpi.active) && !command_can_split(words))
      throw UsageError(std::string(mpi.active ? "mpirun" : "--shard") +
                       " applies to measure g1, g2, vndf, bsdf and validate");
    if (!app.shard_text.empty()) {
      if (mpi.active) throw UsageError("--shard and mpirun do not go together (ranks already share the work)");
      if (replay) throw UsageError("--shard: the parts of a merge are complete runs' shards");
      const auto [k, n] = parse_shard(app.shard_text);
      app.shard = std::make_unique<ShardRecorder>(k, n);
      g.split = app.shard.get();
      g.quiet = true;  // the shard's own table is partial
      g.partial = true;
    } else if (replay) {
      g.split = replay;
    } else if (mpi.active) {
      g.split = mpi.split.get();
      g.ranks = mpi.size;
      if (mpi.rank != 0) g.quiet = g.partial = true;
    }
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
  register_measure_albedo(*measure, g);
  register_render(app, g);
  register_merge(app, g);
  register_reference(app);
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
      if (!sub->get_group().empty())  // hidden commands (reference) are not offered
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

int run_cli(const std::vector<std::string>& args, TallyReplay* replay) {
  GlobalOptions g;
  const MpiRanks& mpi = mpi_ranks();
  const bool root = mpi.rank == 0;
  std::unique_ptr<MicrosimApp> app = build_app(g, replay);
  const std::string unknown = unknown_command(*app, args);
  if (!unknown.empty()) {
    if (root) std::cerr << "microsim: error: " << unknown << "\n";
    return 2;
  }
  // Every output of the command (main file, sidecar, tables) is renamed into place together once
  // the command has succeeded; an error or an interrupt leaves no file and no temporary behind.
  OutputTransaction outputs;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    {
      OutputTransaction command_outputs;
      app->parse(reversed);
      if (replay) replay->finish();
      // A shard's outputs are partial and MPI ranks other than 0 hold the same as rank 0: only
      // complete runs on rank 0 write them.
      if (!app->shard && root) command_outputs.commit();
    }
    if (app->shard) {
      const RunIdentity run = identify_run(args, version());
      if (run.output.empty()) throw UsageError("--shard needs the command's -o");
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      write_json(shard_path(run.output, app->shard->index(), app->shard->count()),
                 partial_json(run, *app->shard, seconds));
    }
    outputs.commit();
  } catch (const CLI::CallForHelp& e) {
    return root ? app->exit(e) : 0;
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app->exit(e) : 0;
  } catch (const CLI::CallForVersion& e) {
    return root ? app->exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    if (root) std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    if (root) std::cerr << "microsim: error: " << cli_message(e) << "\n";
    return 2;
  } catch (const CommandExit& e) {
    return e.code;
  } catch (const std::exception& e) {
    wait_if_interrupted();  // a failure caused by the interrupt's own cleanup is not reported
    std::cerr << "microsim: failed" << (mpi.active ? " (rank " + std::to_string(mpi.rank) + ")" : "")
              << ": " << e.what() << "\n";
    if (mpi.active) mpi_abort(1);  // the other ranks may wait in an exchange: end them all
    return 1;
  }
  return 0;
}

}  // namespace microsim::cli
