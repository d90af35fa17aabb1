// The counted events of a trace (Tracer, trace/tracer.hpp), apart from the tracer so that the
// tallies that carry them need not see Embree.
#pragma once
#include <cstdint>

#include "microsim/tally_fields.hpp"

namespace microsim {

// Events that a careful reader wants counted (docs/theory/numerics.md).
struct TraceCounters {
  std::uint64_t rays = 0;
  std::uint64_t border_crossings = 0;  // periodic wrap-arounds
  std::uint64_t lost_below = 0;        // left the surface's slab downward without a hit
  std::uint64_t backface_hits = 0;     // first hit on the unexpected side (a back face for a
                                       // Front ray, a front face for a Back ray)
  std::uint64_t unresolved = 0;        // still inside the slab after the wrap limit
  // Non-periodic heightfield windows (a measured patch): rays that leave the patch through a
  // side wall inside the slab (ended there: the rule of Tracer::first_hit), and rays from
  // above that enter the patch through a side wall.
  std::uint64_t side_exits = 0;
  std::uint64_t side_entries = 0;

  // Every field, once: the sum below, the exchange between processes (measure/shards.hpp) and
  // the records' `trace_counters` derive from this list (tally_fields.hpp).
  template <class F>
  static constexpr void for_each_field(F&& f) {
    f("rays", &TraceCounters::rays);
    f("border_crossings", &TraceCounters::border_crossings);
    f("lost_below", &TraceCounters::lost_below);
    f("backface_hits", &TraceCounters::backface_hits);
    f("unresolved", &TraceCounters::unresolved);
    f("side_exits", &TraceCounters::side_exits);
    f("side_entries", &TraceCounters::side_entries);
  }
  TraceCounters& operator+=(const TraceCounters& o) {
    add_fields(*this, o);
    return *this;
  }
};
// A field added above but not to the declaration would be neither summed nor exchanged.
static_assert(scalar_field_count<TraceCounters>() * sizeof(std::uint64_t) == sizeof(TraceCounters),
              "every field of TraceCounters is declared in TraceCounters::for_each_field");

}  // namespace microsim
