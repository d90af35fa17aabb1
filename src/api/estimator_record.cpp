#include "microsim/api/estimator_record.hpp"

#include "microsim/api/request_checks.hpp"

namespace microsim {

Json estimator_record(const std::string& command, const std::vector<SurfaceInput>& surfaces, const RunContext& ctx) {
  Json j = record_header(command, ctx);
  j["file"] = surface_names(surfaces);
  return j;
}

const char* replicate_stderr_definition(bool ensemble) {
  return ensemble ? "between-surface standard error (sd over surfaces / sqrt(K)); the ray-count "
                    "one is *_stderr_rays; per_surface holds each surface's own rows"
                  : "ray-count standard error of this one surface: the rays are split into `replicates` "
                    "independent randomized replicates (each a stratified pass with its own random "
                    "stream) and the error is that of the replicate means, sqrt(var / replicates)";
}

void require_rays_and_replicates(long long rays, int replicates) {
  require_integer_in(rays, 1, kMaxRays, "rays");
  require_integer_in(replicates, 2, kMaxReplicates, "replicates");
}

}  // namespace microsim
