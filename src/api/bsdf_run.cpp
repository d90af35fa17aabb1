#include "microsim/api/bsdf_run.hpp"

#include <chrono>

#include "microsim/api/bsdf_files.hpp"
#include "microsim/api/bsdf_record.hpp"
#include "microsim/api/bsdf_resolve.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/microsurface.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

std::string bsdf_record_path(const std::string& path) {
  if (extension_of(path) == "json") return path;
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + ".json";
  return path.substr(0, dot + 1) + "json";
}

BsdfRun run_bsdf_request(const BsdfRequest& request, const RunContext& ctx, const std::string& table_path) {
  BsdfRequest r = normalized_bsdf_request(request);
  r.threads = ctx.threads;
  r.check();
  if (!r.surface.get) throw UsageError("no surface given");
  const std::shared_ptr<const Microsurface> surface = r.surface.get();
  const Microsurface& s = *surface;
  check_bsdf_surface(r, s, r.surface.name);
  const auto t0 = std::chrono::steady_clock::now();
  BsdfTableOptions to = bsdf_table_options(r, s, ctx.split);  // shards and MPI ranks (scaleout)
  if (ctx.progress) to.progress = ctx.progress;
  const Tracer tracer(s);
  const BsdfTable table = measure_bsdf_table(tracer, to);

  BsdfRun run;
  run.nominal_ndf = s.nominal.has_value();
  run.seconds = table.seconds;
  run.record = record_header("measure bsdf", ctx);
  put_bsdf_record(run.record, r, table, s, r.surface.name);
  if (r.format != "json") write_bsdf_tables(table_path, r, table, s, run.record, bsdf_record_path(table_path));
  run.record["wall_seconds"] = seconds_since(t0);
  return run;
}

Json measure_bsdf_record(const BsdfRequest& r, const RunContext& ctx, const std::string& table_path) {
  return run_bsdf_request(r, ctx, table_path).record;
}

}  // namespace microsim
