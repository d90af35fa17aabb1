#include "microsim/api/albedo_run.hpp"

#include <chrono>

#include "microsim/api/albedo_record.hpp"
#include "microsim/api/albedo_resolve.hpp"
#include "microsim/api/estimator_record.hpp"
#include "microsim/api/record_file.hpp"
#include "microsim/io/output.hpp"

namespace microsim {

namespace {
// `path` with the extension `ext` instead of its own (appended when it has none).
std::string beside(const std::string& path, const std::string& ext) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "." + ext;
  return path.substr(0, dot + 1) + ext;
}
}  // namespace

AlbedoRun run_albedo_request(const AlbedoRequest& request, const RunContext& ctx) {
  request.check();
  if (request.surfaces.empty()) throw UsageError("no surface given");
  const AlbedoRequest r = normalized_albedo_request(request);
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
  const AlbedoRequest r = normalized_albedo_request(request);
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
