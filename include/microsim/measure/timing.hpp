// The time a run (or one phase of it) took: wall-clock seconds and the processor seconds of
// every thread of the process over the same interval. Records keep their own field names for
// them (e.g. a BSDF record's `seconds` and `model_seconds` are wall times).
#pragma once
#include <chrono>
#include <ctime>

namespace microsim {

struct Timing {
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;
};

// Started at construction; elapsed() is the time since then.
class Stopwatch {
 public:
  Stopwatch() : wall0_(std::chrono::steady_clock::now()), cpu0_(std::clock()) {}
  Timing elapsed() const {
    return {std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count(),
            static_cast<double>(std::clock() - cpu0_) / CLOCKS_PER_SEC};
  }

 private:
  std::chrono::steady_clock::time_point wall0_;
  std::clock_t cpu0_;
};

}  // namespace microsim
