// Runs beyond one process (measure/shards.hpp): `--shard K/N` writes a partial record,
// `microsim merge` replays the command from the merged parts, and under MPI (mpirun/srun, when
// built with MPI) every rank takes its share and rank 0 writes the record.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "microsim/measure/shards.hpp"

namespace microsim::cli {

// Thrown by a command that already reported its outcome (merge: the replayed command's exit code).
struct CommandExit {
  int code;
};

// The whole command line (`args` without the program name). `replay` (merge): the command
// computes nothing and takes every estimator call's tallies from it.
int run_cli(const std::vector<std::string>& args, TallyReplay* replay = nullptr);

// Commands whose estimators take a share of the work (--shard, MPI): measure g1, g2, vndf, bsdf
// and validate. `words` are the subcommand names, outermost first.
bool command_can_split(const std::vector<std::string>& words);

void register_merge(CLI::App& app, const GlobalOptions& g);

// MPI (compiled with MICROSIM_MPI; otherwise these say "one process").
struct MpiRanks {
  int rank = 0, size = 1;
  bool active = false;  // launched by mpirun / srun and initialized
  std::unique_ptr<TallySplit> split;
};
// Initializes MPI when the process was launched by an MPI launcher (Open MPI or PMI variables).
MpiRanks mpi_start(int& argc, char**& argv);
void mpi_finish(const MpiRanks& s);
[[noreturn]] void mpi_abort(int code);

}  // namespace microsim::cli
