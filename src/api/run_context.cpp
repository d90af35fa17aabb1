#include "microsim/api/run_context.hpp"

#include <tbb/task_arena.h>

#include "microsim/io/output.hpp"
#include "microsim/version.hpp"

namespace microsim {

Json record_header(const std::string& command, const RunContext& ctx) {
  Json j = {{"command", command},
            {"microsim_version", version()},
            {"schema_version", kRecordSchemaVersion},
            {"threads", ctx.threads > 0 ? ctx.threads : tbb::this_task_arena::max_concurrency()}};
  if (ctx.ranks > 0) j["ranks"] = ctx.ranks;  // MPI processes that shared the work
  return j;
}

}  // namespace microsim
