#include "microsim/api/albedo_request.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "microsim/api/angle_list.hpp"
#include "microsim/api/bsdf_request.hpp"
#include "microsim/api/estimator_record.hpp"
#include "microsim/api/record_file.hpp"
#include "microsim/api/request_checks.hpp"
#include "microsim/io/output.hpp"
#include "microsim/measure/albedo_measure.hpp"

namespace microsim {

namespace {

// The request as it is measured: its incidence angles sorted, without repeats.
AlbedoRequest normalized(const AlbedoRequest& r) {
  AlbedoRequest n = r;
  std::sort(n.theta_i_deg.begin(), n.theta_i_deg.end());
  n.theta_i_deg.erase(std::unique(n.theta_i_deg.begin(), n.theta_i_deg.end()), n.theta_i_deg.end());
  return n;
}

// `path` with the extension `ext` instead of its own (appended when it has none).
std::string beside(const std::string& path, const std::string& ext) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "." + ext;
  return path.substr(0, dot + 1) + ext;
}

}  // namespace

void AlbedoRequest::check() const {
  require_above_horizon(theta_i_deg, "theta_i");  // in the order given
  if (format != "json" && format != "csv" && format != "exr")
    throw UsageError("the output must be .json, .csv or .exr (got ." + format + ")");
  albedo_material(*this);
  if (theta_i_deg.empty()) require_integer_in(mu_nodes, kMinMuNodes, kMaxMuNodes, "mu_nodes");
  if (!std::isfinite(phi_i_deg) || std::abs(phi_i_deg) > 3600)
    throw ParameterError("{phi_i} must be a finite angle in degrees, |phi| <= 3600");
  require_integer_in(azimuths, 0, kMaxAlbedoAzimuths, "azimuths");
  require_integer_in(orders, 1, kMaxBsdfOrders, "orders");
  require_rays_and_replicates(rays, replicates);
  const long long runs = azimuths > 0 ? azimuths : 1;
  if (rays < runs * replicates)
    throw ParameterError("{rays} must be at least {replicates} per azimuth (" + std::to_string(runs * replicates) +
                         " here; got " + std::to_string(rays) + ")");
}

AlbedoRun run_albedo_request(const AlbedoRequest& request, const RunContext& ctx) {
  request.check();
  if (request.surfaces.empty()) throw UsageError("no surface given");
  const AlbedoRequest r = normalized(request);
  const auto t0 = std::chrono::steady_clock::now();
  auto measured = std::make_shared<std::vector<AlbedoSurface>>();
  const double n = static_cast<double>(r.surfaces.size());
  for (std::size_t i = 0; i < r.surfaces.size(); ++i) {
    const std::shared_ptr<const Microsurface> s = r.surfaces[i].get();
    measured->push_back(measure_albedo(*s, r.surfaces[i].name, r, [&](double f) {
      if (ctx.progress) ctx.progress((i + f) / n);
    }));
  }
  AlbedoRun run;
  run.surfaces = measured;
  run.record = record_header("measure albedo", ctx);
  put_albedo_record(run.record, r, *measured);
  run.record["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return run;
}

Json measure_albedo_record(const AlbedoRequest& r, const RunContext& ctx) { return run_albedo_request(r, ctx).record; }

std::string write_albedo_outputs(const std::string& output, const AlbedoRequest& request, const AlbedoRun& run) {
  const AlbedoRequest r = normalized(request);
  const std::string format = extension_of(output);
  if (format == "exr") {
    write_exr(output, albedo_lut_exr(r, *run.surfaces));
    write_record_file(beside(output, "csv"), run.record);
    write_record_file(beside(output, "json"), run.record);
    return output + ", " + beside(output, "csv") + " and " + beside(output, "json");
  }
  write_record_file(output, run.record);
  if (format != "csv") return output;
  write_record_file(beside(output, "json"), run.record);
  return output + " and " + beside(output, "json");
}

}  // namespace microsim
