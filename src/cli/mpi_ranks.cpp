// MPI ranks sharing one run (measure/shards.hpp). Built only when CMake found MPI
// (MICROSIM_MPI); otherwise every process is a whole run.
#include <cstdlib>
#include <iostream>

#include "scaleout.hpp"

#ifdef MICROSIM_MPI
#include <mpi.h>
#endif

namespace microsim::cli {

#ifdef MICROSIM_MPI
namespace {

// Rank r computes share r of every estimator call; the exchange sums the tallies of all ranks
// in place. Every row has exactly one contributing rank (the others hold zeros) and integer
// totals are exact, so the sums are the single-process tallies bit for bit. Allreduce, not
// Reduce: every rank then goes on with the same complete tallies, so all take the same path.
class MpiSplit : public TallySplit {
 public:
  MpiSplit(int rank, int size) : rank_(rank), size_(size) {}
  UnitRange share(std::uint64_t units) const override { return shard_range(units, rank_, size_); }
  void exchange(Tallies& t) override {
    sum(t.counts);
    sum(t.reals);
    sum(t.tail_counts);
    sum(t.tail_reals);
    t.covered = {0, t.units};
  }

 private:
  static void check(int rc) {
    if (rc != MPI_SUCCESS) throw RuntimeFailure("MPI_Allreduce failed (code " + std::to_string(rc) + ")");
  }
  // In pieces of at most 2^27 values (MPI counts are int).
  template <class T>
  static void sum(std::vector<T>& v) {
    const MPI_Datatype type = std::is_same<T, double>::value ? MPI_DOUBLE : MPI_UINT64_T;
    const std::size_t piece = std::size_t(1) << 27;
    for (std::size_t at = 0; at < v.size(); at += piece)
      check(MPI_Allreduce(MPI_IN_PLACE, v.data() + at, static_cast<int>(std::min(piece, v.size() - at)),
                          type, MPI_SUM, MPI_COMM_WORLD));
  }
  int rank_, size_;
};

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

}  // namespace

MpiRanks mpi_start(int& argc, char**& argv) {
  MpiRanks s;
  if (!launched_by_mpi()) return s;
  if (MPI_Init(&argc, &argv) != MPI_SUCCESS) {
    std::cerr << "microsim: failed: MPI_Init\n";
    std::exit(1);
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &s.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &s.size);
  s.active = true;
  s.split = std::make_unique<MpiSplit>(s.rank, s.size);
  return s;
}

void mpi_finish(const MpiRanks& s) {
  if (s.active) MPI_Finalize();
}

void mpi_abort(int code) {
  std::cerr.flush();
  MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

#else

MpiRanks mpi_start(int&, char**&) { return {}; }
void mpi_finish(const MpiRanks&) {}
void mpi_abort(int code) { std::exit(code); }

#endif

}  // namespace microsim::cli
