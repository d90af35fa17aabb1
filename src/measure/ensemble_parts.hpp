// What the ensemble estimators (ensemble_g1.cpp, ensemble_g2_vndf.cpp, ensemble_bsdf.cpp) share:
// the equal-parts rule, a wall clock, and a point drawn on one facet of a part.
#pragma once
#include <chrono>
#include <string>

#include "microsim/common.hpp"
#include "microsim/trace/scene_ensemble.hpp"

namespace microsim {

inline void require_equal_parts(const SceneEnsemble& e, const char* what) {
  if (e.parts() == 0 || !e.equal_weights())
    throw UsageError(std::string(what) + ": the ensemble's parts must cover equal shares of the macro area");
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The point of ensemble facet j of part k drawn by rng (two draws), in the part's frame.
inline Vec3 draw_point(const Scene& scene, const SceneEnsemble::Part& p, std::size_t j, CounterRng& rng) {
  const double u = rng.uniform();
  const double w = rng.uniform();
  return scene.facet_point(j - p.first_facet, u, w);
}

}  // namespace microsim
