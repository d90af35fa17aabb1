// The command tree of microsim, built the same way for the command-line program (main.cpp) and
// for embedders (the Python module), so that both parse the same options and write the same
// records.
#pragma once
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <memory>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "scaleout.hpp"

namespace microsim::cli {

// The command tree with what its global options own: the TBB limit set by --threads and the
// shard recorder set by --shard K/N.
struct MicrosimApp : CLI::App {
  using CLI::App::App;
  std::unique_ptr<tbb::global_control> threads;
  std::string shard_text;
  std::unique_ptr<ShardRecorder> shard;
};

// An App with every command registered on g. `replay` (merge): the command computes nothing and
// takes every estimator call's tallies from it. Under MPI (mpi_ranks()) the estimators share
// the work between ranks.
std::unique_ptr<MicrosimApp> build_app(GlobalOptions& g, TallyReplay* replay = nullptr);

// The process's MPI ranks (one process unless main started MPI under mpirun / srun).
MpiRanks& mpi_ranks();

// "unknown surface kind 'x' (known: ...)" or "unknown command ..." when the leading words of
// args (without the program name) do not name a command of the tree (CLI11 would only say that a
// subcommand is missing); empty when they do.
std::string unknown_command(const CLI::App& app, const std::vector<std::string>& args);

// Parses args (without the program name) and runs the command inside an output transaction:
// every file it writes is renamed into place once it has succeeded. Throws what the command
// throws: CLI::ParseError (and CLI11's help/version requests), UsageError, other exceptions.
void run_app(CLI::App& app, const std::vector<std::string>& args);

}  // namespace microsim::cli
