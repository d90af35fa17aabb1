// microsim command line: CLI11 parsing; each command lives in src/cli/cmd_*.cpp and runs from
// its callback (the tree is built in app.cpp, run by run_cli). Usage errors exit 2 with one line,
// runtime failures exit 1. Under MPI every rank runs the same command on its share
// (scaleout.hpp); only rank 0 speaks and writes.
#include <string>
#include <vector>

#include "app.hpp"
#include "microsim/io/output.hpp"

using namespace microsim;
using namespace microsim::cli;

int main(int argc, char** argv) {
  install_interrupt_cleanup();  // first: threads started later (MPI, TBB) inherit its signal mask
  mpi_ranks() = mpi_start(argc, argv);
  const int status = run_cli(std::vector<std::string>(argv + 1, argv + argc));
  wait_if_interrupted();
  mpi_finish(mpi_ranks());
  return status;
}
