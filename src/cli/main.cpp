// microsim command line: CLI11 parsing; each command lives in src/cli/cmd_*.cpp and runs from
// its callback. Usage errors exit 2 with one line, runtime failures exit 1. Under MPI every rank
// runs the same command on its share (scaleout.hpp); only rank 0 speaks and writes.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "microsim/io/output.hpp"
#include "scaleout.hpp"

using namespace microsim;
using namespace microsim::cli;

namespace {
// An unknown command or surface kind names itself (CLI11 would only say that a subcommand is
// missing): walk the leading words down the command tree. Returns false after printing.
bool check_command_words(const CLI::App& app, const std::vector<std::string>& args, bool speak) {
  const CLI::App* level = &app;
  for (std::size_t k = 0; k < args.size() && args[k][0] != '-' && !level->get_subcommands({}).empty(); ++k) {
    std::string names;
    const CLI::App* next = nullptr;
    for (const auto* sub : level->get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      if (sub->get_name() == args[k]) next = sub;
    }
    if (!next) {
      if (speak)
        std::cerr << "microsim: error: unknown "
                  << (level->get_name() == "generate" ? "surface kind" : "command") << " '"
                  << args[k] << "' (known: " << names << ")\n";
      return false;
    }
    level = next;
  }
  return true;
}

// The process's MPI session (one process when not launched by mpirun / srun).
MpiSession g_mpi;
}  // namespace

namespace microsim::cli {

int run_cli(const std::vector<std::string>& args, TallyReplay* replay) {
  CLI::App app{"microsim: explicit microsurface Monte Carlo simulator.\n"
               "Builds microgeometry, ray-traces it with Embree, measures D, G1 (and more) with "
               "standard errors beside the analytic Smith model."};
  app.name("microsim");  // usage lines name the program (the words come without argv[0])
  app.require_subcommand(1);
  app.fallthrough();  // --threads and --quiet are accepted after the subcommand too
  GlobalOptions g;
  const bool root = g_mpi.rank == 0;
  std::unique_ptr<tbb::global_control> threads;
  std::unique_ptr<ShardRecorder> shard;
  std::string shard_text;
  app.add_option("--threads", g.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  app.add_flag("--quiet,-q", g.quiet, "No progress display and no table on stdout");
  app.add_option("--shard", shard_text,
                 "K/N: compute shard K of N of a measure g1|g2|vndf|bsdf or validate run and write "
                 "its partial record to OUTPUT.shard-K-of-N.json (microsim merge joins them)");
  app.set_version_flag("--version", "microsim 0.1.0");
  // Runs before the subcommand callbacks.
  app.parse_complete_callback([&] {
    if (g.threads > 0)
      threads = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, g.threads);
    std::vector<std::string> words;
    for (const CLI::App* level = &app; !level->get_subcommands().empty();) {
      level = level->get_subcommands().front();
      words.push_back(level->get_name());
    }
    if (!shard_text.empty() || g_mpi.active) {
      if (!command_can_split(words))
        throw UsageError(std::string(g_mpi.active ? "mpirun" : "--shard") +
                         " applies to measure g1, g2, vndf, bsdf and validate");
    }
    if (!shard_text.empty()) {
      if (g_mpi.active) throw UsageError("--shard and mpirun do not go together (ranks already share the work)");
      if (replay) throw UsageError("--shard: the parts of a merge are complete runs' shards");
      const auto [k, n] = parse_shard(shard_text);
      shard = std::make_unique<ShardRecorder>(k, n);
      g.split = shard.get();
      g.quiet = true;  // the shard's own table is partial
      g.partial = true;
    } else if (replay) {
      g.split = replay;
    } else if (g_mpi.active) {
      g.split = g_mpi.split.get();
      g.ranks = g_mpi.size;
      if (!root) g.quiet = g.partial = true;
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
  register_merge(app, g);

  if (!check_command_words(app, args, root)) return 2;
  // Every output of the command (main file, sidecar, tables) is renamed into place together once
  // the command has succeeded; an error or an interrupt leaves no file and no temporary behind.
  OutputTransaction outputs;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());
    {
      OutputTransaction command_outputs;
      app.parse(reversed);
      if (replay) replay->finish();
      // A shard's outputs are partial and MPI ranks other than 0 hold the same as rank 0: only
      // complete runs on rank 0 write them.
      if (!shard && root) command_outputs.commit();
    }
    if (shard) {
      const RunIdentity run = identify_run(args, "0.1.0");
      if (run.output.empty()) throw UsageError("--shard needs the command's -o");
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      write_json(shard_path(run.output, shard->index(), shard->count()),
                 partial_json(run, *shard, seconds));
    }
    outputs.commit();
  } catch (const CLI::CallForHelp& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::CallForVersion& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    if (root) std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    if (root) std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const CommandExit& e) {
    return e.code;
  } catch (const std::exception& e) {
    std::cerr << "microsim: failed" << (g_mpi.active ? " (rank " + std::to_string(g_mpi.rank) + ")" : "")
              << ": " << e.what() << "\n";
    if (g_mpi.active) mpi_abort(1);  // the other ranks may wait in an exchange: end them all
    return 1;
  }
  return 0;
}

}  // namespace microsim::cli

int main(int argc, char** argv) {
  g_mpi = mpi_start(argc, argv);
  install_interrupt_cleanup();
  const int code = run_cli(std::vector<std::string>(argv + 1, argv + argc));
  mpi_finish(g_mpi);
  return code;
}
