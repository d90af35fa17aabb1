// Audit of the mirror random walk on Gaussian heightfields (analysis, not a test; run
// analysis/walk_audit.sh). Question: are the paths of order >= 4 that `measure bsdf` counts on
// converged Beckmann tiles a property of the surface, or an artefact of the tracer?
//
// Per incidence angle, paths start above uniform points of a periodic tile and are traced twice
// from the same origin and direction:
//   (a) by the library's Embree tracer (Tracer::first_hit with the source-plane filter, exactly
//       the calls of measure/bsdf_walk.cpp; checked path by path against walk_bsdf_path), with
//       every hit recorded;
//   (b) by an independent tracer written here: double precision, no Embree, no offsets or
//       filters; a 2D digital differential analyser walks the cells of the infinite periodic
//       grid and intersects the two triangles of each cell as planes z = A + B u + C v
//       (Microsurface::facet's split), excluding only the facet the ray leaves (a ray leaving a
//       facet of a graph upward can never meet that plane again).
// The two order distributions are compared path by path. For each order class (1, 2, 3, 4+)
// the recorded hits of (a) give: segment lengths, same / edge- / vertex-adjacent consecutive
// facets, distance of the hit to the nearest facet edge (in cells), cos(normal, -direction),
// segments that cross a tile seam, hit heights over the mean plane (in units of the rms height),
// the heights' Laplacian at the hits (concave places), and per path the horizontal extent and
// the net travel along and across the incidence plane. Per reflection k = 1, 2, 3, 4+ of all
// paths: of the rays leaving upward, the fraction that meets the surface again, against Smith's
// masking for the same height and direction, 1 - C1(h)^Lambda(w) (the Smith walk's rule,
// models/smith_random_walk.hpp): where the surface keeps rays that Smith lets go.
// The Smith walk's own orders (nominal Beckmann NDF) are printed beside the traced ones.
// `--replay P` prints path P of every seed hit by hit from both tracers.
//
//   walk_audit --alpha 1 --cells-per-l 16 --lengths-per-tile 16 --paths 300000 --seeds 1,2
//              --theta 0,60,80 > out.md
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "microsim/measure/bsdf_walk.hpp"
#include "microsim/models/smith_random_walk.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/trace/tracer.hpp"
#include "../tests/reference_heightfield_tracer.hpp"
#include "arg_lists.hpp"

using namespace microsim;
using microsim::analysis::parse_list;

namespace {

struct Args {
  double alpha = 1.0;
  int cells_per_l = 16, lengths_per_tile = 16, max_events = 1000;
  std::uint64_t paths = 300000, smith_walks = 400000;
  std::vector<std::uint64_t> seeds{1};
  std::vector<double> thetas{0, 60, 80};
  int show_paths = 3;  // order >= 4 paths printed hit by hit, per angle
  long long replay = -1;  // only this path index (per seed), both tracers' hits printed
};

// ---------------------------------------------------------------------------------------------
// Geometry helpers for the diagnostics.
struct CellPos {
  long i, j;
  int half;
};
CellPos cell_of(const Microsurface& s, std::size_t f) {
  const std::size_t c = f / 2;
  return {static_cast<long>(c % s.nx()), static_cast<long>(c / s.nx()), static_cast<int>(f % 2)};
}
// The three vertices (grid indices) of a facet.
std::array<std::pair<long, long>, 3> verts_of(const Microsurface& s, std::size_t f) {
  CellPos c = cell_of(s, f);
  if (c.half == 0) return {{{c.i, c.j}, {c.i + 1, c.j}, {c.i, c.j + 1}}};
  return {{{c.i + 1, c.j}, {c.i + 1, c.j + 1}, {c.i, c.j + 1}}};
}
// 0 same facet, 1 share an edge, 2 share a vertex only, 3 otherwise (periodic indices).
int relation(const Microsurface& s, std::size_t a, std::size_t b) {
  if (a == b) return 0;
  auto va = verts_of(s, a), vb = verts_of(s, b);
  const long n = s.nx();
  int shared = 0;
  for (auto& p : va)
    for (auto& q : vb)
      if (((p.first - q.first) % n + n) % n == 0 && ((p.second - q.second) % n + n) % n == 0) ++shared;
  return shared >= 2 ? 1 : (shared == 1 ? 2 : 3);
}
// Distance (in cells) from a hit point to the nearest edge of its facet, in the xy plane.
double edge_distance(const Microsurface& s, std::size_t f, const Vec3& p) {
  CellPos c = cell_of(s, f);
  const double x0 = -0.5 * s.macro().size_x, y0 = -0.5 * s.macro().size_y;
  double u = (p.x() - x0) / s.dx() - c.i, v = (p.y() - y0) / s.dy() - c.j;
  // the hit point is the canonical copy; the facet's cell is inside the tile too, but at the
  // seam the point may sit on the other side: bring u, v near the cell
  const double n = s.nx();
  u -= n * std::round(u / n);
  v -= n * std::round(v / n);
  if (c.half == 0) return std::min({u, v, (1 - u - v) / std::sqrt(2.0)});
  return std::min({1 - u, 1 - v, (u + v - 1) / std::sqrt(2.0)});
}

// Log-spaced histogram with fixed edges.
struct Hist {
  std::vector<double> edges;
  std::vector<std::uint64_t> n;
  explicit Hist(std::vector<double> e) : edges(std::move(e)), n(edges.size() + 1, 0) {}
  void add(double x) {
    std::size_t k = 0;
    while (k < edges.size() && x >= edges[k]) ++k;
    ++n[k];
  }
  std::uint64_t total() const {
    std::uint64_t t = 0;
    for (auto c : n) t += c;
    return t;
  }
  std::string row() const {
    std::ostringstream o;
    const double t = std::max<std::uint64_t>(1, total());
    for (std::size_t k = 0; k < n.size(); ++k) {
      char b[32];
      std::snprintf(b, sizeof b, " %.4f |", n[k] / t);
      o << b;
    }
    return o.str();
  }
  std::string header(const char* unit) const {
    std::ostringstream o;
    for (std::size_t k = 0; k <= edges.size(); ++k) {
      char b[64];
      if (k == 0) std::snprintf(b, sizeof b, " < %g |", edges[0]);
      else if (k == edges.size()) std::snprintf(b, sizeof b, " >= %g |", edges[k - 1]);
      else std::snprintf(b, sizeof b, " %g-%g |", edges[k - 1], edges[k]);
      o << b;
    }
    (void)unit;
    return o.str();
  }
};

// Per order class (1, 2, 3, 4+): hit-level and path-level accumulators.
struct ClassStats {
  std::uint64_t paths = 0, hits = 0;
  Hist seg{{1e-6, 1e-3, 0.1, 1, 4, 16, 64}};      // segment length before the hit, cells
  Hist edge{{1e-6, 1e-4, 1e-2, 0.05, 0.1, 0.2}};  // distance to the facet's nearest edge, cells
  Hist cosv{{0.01, 0.05, 0.1, 0.3, 0.6}};         // cos(n, -d) at the hit
  Hist height{{-3, -2, -1, 0, 1, 2}};             // hit height / rms height
  Hist extent{{0.25, 0.5, 1, 2, 4, 8}};           // path: max horizontal distance from the first hit, l
  std::uint64_t rel[4] = {0, 0, 0, 0};             // consecutive facets: same, edge, vertex, other
  std::uint64_t seam_segments = 0, distinct_facets = 0, revisits = 0;
  double sum_h = 0, sum_along = 0, sum_across = 0;  // along/across: |net travel| per path, l
  // Walls parallel to the incidence plane: hits whose normal leans more across (y) than along
  // (x) it, and consecutive hits on opposite walls (n_y changes sign, both |n_y| > |n_x|).
  std::uint64_t side_walls = 0, alternations = 0;
  // Curvature of the heightfield at the hits (5-point Laplacian at the nearest vertex, over its
  // rms on the tile; > 0 concave, a valley) and the share of hits in concave places.
  double sum_lap = 0;
  std::uint64_t concave = 0;
};

// After the k-th reflection (k = 1, 2, 3, 4+) of any path: how many rays leave upward, how many
// of those meet the surface again, and how many Smith predicts for the same height and direction
// ([Heitz14, eq. 29-30] with Gaussian heights: G1(w, h) = C1(h)^Lambda(w), C1 the height CDF).
struct Continuation {
  std::uint64_t up = 0, up_hit = 0, down = 0;
  double smith_up_hit = 0;
};

// 5-point Laplacian of the heights at the grid vertex nearest to p.
double laplacian_at(const Microsurface& s, const Vec3& p) {
  const long i = std::lround((p.x() + 0.5 * s.macro().size_x) / s.dx());
  const long j = std::lround((p.y() + 0.5 * s.macro().size_y) / s.dy());
  const double dx2 = s.dx() * s.dx();
  return (s.height(i + 1, j) + s.height(i - 1, j) + s.height(i, j + 1) + s.height(i, j - 1) -
          4.0 * s.height(i, j)) / dx2;
}

int order_class(int order) { return std::min(order, 4) - 1; }

struct HitRec {
  Vec3 p, n, d, o;  // hit point (canonical copy), facet normal, arriving and leaving directions
  std::size_t facet;
  std::uint64_t crossings;  // tile seams crossed by the segment that ends here
};

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int k = 1; k < argc; ++k) {
    std::string o = argv[k];
    auto next = [&]() -> const char* {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", o.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (o == "--alpha") a.alpha = std::atof(next());
    else if (o == "--cells-per-l") a.cells_per_l = std::atoi(next());
    else if (o == "--lengths-per-tile") a.lengths_per_tile = std::atoi(next());
    else if (o == "--paths") a.paths = std::strtoull(next(), nullptr, 10);
    else if (o == "--smith-walks") a.smith_walks = std::strtoull(next(), nullptr, 10);
    else if (o == "--max-events") a.max_events = std::atoi(next());
    else if (o == "--show-paths") a.show_paths = std::atoi(next());
    else if (o == "--replay") a.replay = std::atoll(next());
    else if (o == "--theta") a.thetas = parse_list(next());
    else if (o == "--seeds") {
      a.seeds.clear();
      for (double v : parse_list(next())) a.seeds.push_back(static_cast<std::uint64_t>(v));
    } else {
      std::fprintf(stderr, "unknown option %s\n", o.c_str());
      return 2;
    }
  }
  const int n = a.cells_per_l * a.lengths_per_tile;
  const double ell = 1.0 / a.lengths_per_tile;
  std::printf("# Mirror walk audit: Beckmann alpha = %g, %d cells per l, L/l = %d (%d^2), %llu paths "
              "per angle and tile, seeds",
              a.alpha, a.cells_per_l, a.lengths_per_tile, n, static_cast<unsigned long long>(a.paths));
  for (auto s : a.seeds) std::printf(" %llu", static_cast<unsigned long long>(s));
  std::printf("\n\n");

  const char* names[4] = {"1", "2", "3", "4+"};
  for (double theta_deg : a.thetas) {
    const double th = theta_deg * kPi / 180.0;
    const Vec3 wi(std::sin(th), 0.0, std::cos(th));
    ClassStats cs[4];
    Continuation cont[4];
    const models::Ndf ndf = models::Ndf::beckmann(a.alpha, a.alpha);
    std::map<int, std::uint64_t> hist_ms, hist_ref;
    std::uint64_t same_order = 0, diff_order = 0, same_facets = 0, ms_lost = 0, ref_lost = 0,
                  ref_back = 0, ms_unterm = 0, walk_checked = 0, walk_mismatch = 0;
    std::uint64_t diff_to_ge4 = 0, diff_from_ge4 = 0;  // order >= 4 on one side only
    std::uint64_t lib_higher = 0, lib_lower = 0;
    Hist diff_edge{{1e-6, 1e-5, 1e-4, 1e-3, 1e-2}};  // first different hit: distance to an edge
    TraceCounters total_counters;
    std::vector<std::string> diff_examples, shown;
    double sigma_sum = 0;
    for (std::uint64_t seed : a.seeds) {
      GaussianParams gp;
      gp.resolution = n;
      gp.size = 1.0;
      gp.correlation_length = ell;
      gp.alpha_x = gp.alpha_y = a.alpha;
      gp.seed = seed;
      Microsurface s = generate_gaussian(gp);
      double mean = 0, var = 0;
      for (float h : s.heights()) mean += h;
      mean /= s.heights().size();
      for (float h : s.heights()) var += (h - mean) * (h - mean);
      const double sigma = std::sqrt(var / s.heights().size());
      double lap2 = 0;
      for (long j = 0; j < s.ny(); ++j)
        for (long i = 0; i < s.nx(); ++i) {
          const double l = laplacian_at(s, s.grid_point(i, j));
          lap2 += l * l;
        }
      const double lap_rms = std::sqrt(lap2 / s.heights().size());
      sigma_sum += sigma;
      Tracer tracer(s);
      ReferenceHeightfieldTracer ref(s);
      const models::Material mirror = models::Material::mirror();
      for (std::uint64_t p = 0; p < a.paths; ++p) {
        if (a.replay >= 0 && p != static_cast<std::uint64_t>(a.replay)) continue;
        CounterRng rng(seed, 0xA0D17ull + static_cast<std::uint64_t>(theta_deg * 1000), p);
        const double ox = rng.uniform() - 0.5, oy = rng.uniform() - 0.5;  // fixed draw order
        const Vec3 origin(ox, oy, tracer.z_top());
        // (a) the library's tracer, calls as in walk_bsdf_path, every hit kept.
        std::vector<HitRec> hits;
        Vec3 dir = -wi;
        TraceCounters c;
        TraceHit hit = tracer.first_hit(origin, dir, nullptr, c);
        int order = 0;
        bool lost = false;
        std::uint64_t crossings0 = 0;
        for (;; ++order) {
          if (!hit.hit) {
            lost = !(order > 0 && dir.z() > 0);
            break;
          }
          if (hit.backface || order + 1 > a.max_events) {
            lost = true;
            break;
          }
          const Vec3 arriving = dir;
          dir = models::reflect(-dir, hit.normal);
          dir.normalize();
          hits.push_back({hit.point, hit.normal, arriving, dir, hit.facet, c.border_crossings - crossings0});
          crossings0 = c.border_crossings;
          const SourcePlane plane = SourcePlane::of(s.facet(hit.facet));
          hit = tracer.first_hit(hit.point, dir, &plane, c);
        }
        total_counters += c;
        if (lost) {
          (order + 1 > a.max_events ? ms_unterm : ms_lost)++;
        }
        // The same path through walk_bsdf_path (what `measure bsdf` runs), on the first paths.
        if (p < 20000) {
          TraceCounters c2;
          std::uint64_t ev = 0;
          CounterRng r2(0, 0, 0);
          WalkEnd e = walk_bsdf_path(tracer, origin, -wi, mirror, r2, a.max_events, false, c2, ev);
          ++walk_checked;
          if (e.order != order || (e.kind == WalkEnd::Reflected) == lost) ++walk_mismatch;
        }
        // (b) the independent tracer.
        std::vector<std::size_t> rfacets;
        std::vector<ReferenceHeightfieldTracer::Hit> rhits;
        Vec3 rd = -wi, rp = origin;
        long skip = -1;
        int rorder = 0;
        bool rlost = false;
        for (;; ++rorder) {
          ReferenceHeightfieldTracer::Hit h = ref.first_hit(rp, rd, skip);
          if (!h.hit) {
            rlost = h.lost || rd.z() <= 0 || rorder == 0;
            break;
          }
          if (h.backface) {
            ++ref_back;
            rlost = true;
            break;
          }
          if (rorder + 1 > a.max_events) {
            rlost = true;
            break;
          }
          rfacets.push_back(h.facet);
          rhits.push_back(h);
          rd = rd - 2.0 * rd.dot(h.n) * h.n;
          rd.normalize();
          rp = h.p;
          skip = static_cast<long>(h.facet);
        }
        if (rlost) ++ref_lost;
        if (a.replay >= 0) {
          std::printf("replay seed %llu path %llu theta %g: origin (%.9f %.9f %.9f)\n",
                      static_cast<unsigned long long>(seed), static_cast<unsigned long long>(p), theta_deg,
                      origin.x(), origin.y(), origin.z());
          for (std::size_t k = 0; k < std::max(hits.size(), rhits.size()); ++k) {
            if (k < hits.size()) {
              const HitRec& r = hits[k];
              const CellPos c = cell_of(s, r.facet);
              std::printf("  library     hit %zu: facet (%ld,%ld,%d) p (%.9f %.9f %.9f) n (%+.6f %+.6f %+.6f) "
                          "edge %.3e cells, leaves (%+.6f %+.6f %+.6f)\n",
                          k + 1, c.i, c.j, c.half, r.p.x(), r.p.y(), r.p.z(), r.n.x(), r.n.y(), r.n.z(),
                          edge_distance(s, r.facet, r.p), r.o.x(), r.o.y(), r.o.z());
            }
            if (k < rhits.size()) {
              const ReferenceHeightfieldTracer::Hit& r = rhits[k];
              const CellPos c = cell_of(s, r.facet);
              std::printf("  independent hit %zu: facet (%ld,%ld,%d) p (%.9f %.9f %.9f) n (%+.6f %+.6f %+.6f) "
                          "edge %.3e cells\n",
                          k + 1, c.i, c.j, c.half, r.p.x(), r.p.y(), r.p.z(), r.n.x(), r.n.y(), r.n.z(),
                          edge_distance(s, r.facet, r.p));
            }
          }
        }
        if (!lost) ++hist_ms[order];
        if (!rlost) ++hist_ref[rorder];
        bool facets_equal = rfacets.size() == hits.size();
        for (std::size_t k = 0; facets_equal && k < hits.size(); ++k)
          facets_equal = rfacets[k] == hits[k].facet;
        if (facets_equal) ++same_facets;
        if (order == rorder && lost == rlost) {
          ++same_order;
        } else {
          ++diff_order;
          if (order >= 4 && rorder < 4) ++diff_from_ge4;
          if (rorder >= 4 && order < 4) ++diff_to_ge4;
          (order > rorder ? lib_higher : lib_lower)++;
          // The first hit where the two differ: the smaller distance to an edge of either
          // tracer's facet there (one of them may have no hit).
          std::size_t k = 0;
          while (k < hits.size() && k < rfacets.size() && rfacets[k] == hits[k].facet) ++k;
          double ed = std::numeric_limits<double>::infinity();
          if (k < hits.size()) ed = edge_distance(s, hits[k].facet, hits[k].p);
          if (k < rhits.size()) ed = std::min(ed, edge_distance(s, rhits[k].facet, rhits[k].p));
          diff_edge.add(ed);
          if (diff_examples.size() < 12) {
            char b[256];
            std::snprintf(b, sizeof b,
                          "seed %llu path %llu: order %d (lost %d) vs independent %d (lost %d); "
                          "first different hit #%zu, its distance to an edge %.2e cells",
                          static_cast<unsigned long long>(seed), static_cast<unsigned long long>(p),
                          order, int(lost), rorder, int(rlost), k + 1, ed);
            diff_examples.push_back(b);
          }
        }
        if (lost || order == 0) continue;
        // Diagnostics of (a)'s path by order class.
        ClassStats& st = cs[order_class(order)];
        ++st.paths;
        std::set<std::size_t> distinct;
        double ext = 0;
        Vec3 travel = Vec3::Zero();  // unwrapped net horizontal travel, first to last hit
        for (std::size_t k = 0; k < hits.size(); ++k) {
          const HitRec& r = hits[k];
          ++st.hits;
          distinct.insert(r.facet);
          st.edge.add(edge_distance(s, r.facet, r.p));
          st.cosv.add(-r.d.dot(r.n));
          const double hz = (r.p.z() - mean) / sigma;
          st.height.add(hz);
          st.sum_h += hz;
          const double lap = laplacian_at(s, r.p) / lap_rms;
          st.sum_lap += lap;
          if (lap > 0) ++st.concave;
          if (k > 0) {
            // Segment length from the height change (exact unless nearly horizontal), else from
            // the minimal periodic image.
            Vec3 dv = r.p - hits[k - 1].p;
            dv.x() -= std::round(dv.x());
            dv.y() -= std::round(dv.y());
            double len = std::abs(r.d.z()) > 1e-3 ? (r.p.z() - hits[k - 1].p.z()) / r.d.z() : dv.norm();
            st.seg.add(len / s.dx());
            travel += Vec3(r.d.x(), r.d.y(), 0) * len;
            st.rel[relation(s, hits[k - 1].facet, r.facet)]++;
            if (r.crossings) ++st.seam_segments;
            ext = std::max(ext, travel.norm());
          }
        }
        for (std::size_t k = 0; k < hits.size(); ++k) {
          const HitRec& r = hits[k];
          const bool wall = std::abs(r.n.y()) > std::abs(r.n.x());
          if (wall) ++st.side_walls;
          if (k > 0 && wall && std::abs(hits[k - 1].n.y()) > std::abs(hits[k - 1].n.x()) &&
              r.n.y() * hits[k - 1].n.y() < 0)
            ++st.alternations;
          Continuation& q = cont[std::min<std::size_t>(k, 3)];
          if (r.o.z() > 0) {
            ++q.up;
            if (k + 1 < hits.size()) ++q.up_hit;
            const double c1 = 0.5 * std::erfc(-(r.p.z() - mean) / (sigma * std::sqrt(2.0)));
            q.smith_up_hit += 1.0 - std::pow(c1, ndf.Lambda(r.o));
          } else {
            ++q.down;
          }
        }
        st.distinct_facets += distinct.size();
        st.revisits += hits.size() - distinct.size();
        st.extent.add(ext / ell);
        st.sum_along += std::abs(travel.x()) / ell;
        st.sum_across += std::abs(travel.y()) / ell;
        if (order >= 4 && static_cast<int>(shown.size()) < a.show_paths) {
          std::ostringstream o;
          o << "seed " << seed << " path " << p << ", order " << order << " (independent: " << rorder
            << "):\n";
          for (std::size_t k = 0; k < hits.size(); ++k) {
            const HitRec& r = hits[k];
            char b[256];
            std::snprintf(b, sizeof b,
                          "  hit %zu: x/l %+.3f y/l %+.3f z/sigma %+.2f, facet (%ld,%ld,%d), n (%+.2f %+.2f "
                          "%+.2f), cos %.3f, edge dist %.3f cells\n",
                          k + 1, r.p.x() / ell, r.p.y() / ell, (r.p.z() - mean) / sigma,
                          cell_of(s, r.facet).i, cell_of(s, r.facet).j, cell_of(s, r.facet).half,
                          r.n.x(), r.n.y(), r.n.z(), -r.d.dot(r.n), edge_distance(s, r.facet, r.p));
            o << b;
          }
          shown.push_back(o.str());
        }
      }
    }
    // Smith random walk of the nominal NDF for the same direction.
    std::map<int, std::uint64_t> hist_smith;
    {
      const models::SmithRandomWalk walk(ndf, models::Material::mirror(),
                                         models::HeightDistribution::Uniform, a.max_events);
      struct Rng {
        CounterRng c;
        double uniform() { return c.uniform(); }
      };
      for (std::uint64_t k = 0; k < a.smith_walks; ++k) {
        Rng r{CounterRng(7, 0x5A17ull + static_cast<std::uint64_t>(theta_deg * 1000), k)};
        models::WalkExit e = walk.walk(wi, r);
        if (!e.lost) ++hist_smith[e.order];
      }
    }
    const double N = static_cast<double>(a.paths * a.seeds.size());
    auto albedo = [](const std::map<int, std::uint64_t>& h, int lo, int hi, double tot) {
      std::uint64_t c = 0;
      for (auto& kv : h)
        if (kv.first >= lo && kv.first <= hi) c += kv.second;
      return c / tot;
    };
    std::printf("## theta_i = %g deg\n\n", theta_deg);
    std::printf("rms height sigma = %.4f l; %llu paths; library tracer: %llu lost, %llu unterminated "
                "(max %d events); counters: %llu seam crossings, %llu back-face first hits, %llu lost "
                "below, %llu unresolved, %llu side exits; walk_bsdf_path gives the same order on "
                "%llu of %llu paths checked\n\n",
                sigma_sum / a.seeds.size() / ell, static_cast<unsigned long long>(N),
                static_cast<unsigned long long>(ms_lost), static_cast<unsigned long long>(ms_unterm),
                a.max_events, static_cast<unsigned long long>(total_counters.border_crossings),
                static_cast<unsigned long long>(total_counters.backface_hits),
                static_cast<unsigned long long>(total_counters.lost_below),
                static_cast<unsigned long long>(total_counters.unresolved),
                static_cast<unsigned long long>(total_counters.side_exits),
                static_cast<unsigned long long>(walk_checked - walk_mismatch),
                static_cast<unsigned long long>(walk_checked));
    std::printf("Independent double-precision tracer on the same triangles and origins: same order "
                "on %llu paths, different on %llu (order >= 4 only in the library: %llu, only in the "
                "independent tracer: %llu); identical facet sequence on %llu; independent tracer: %llu "
                "lost, %llu back-face hits\n\n",
                static_cast<unsigned long long>(same_order), static_cast<unsigned long long>(diff_order),
                static_cast<unsigned long long>(diff_from_ge4), static_cast<unsigned long long>(diff_to_ge4),
                static_cast<unsigned long long>(same_facets), static_cast<unsigned long long>(ref_lost),
                static_cast<unsigned long long>(ref_back));
    if (diff_order) {
      std::printf("Different orders: library higher on %llu, lower on %llu; distance of the library's "
                  "or the independent tracer's first different hit (the nearer) to an edge of its facet (cells):\n\n|%s\n|---|---|---|---|---|---|\n|%s\n\n",
                  static_cast<unsigned long long>(lib_higher), static_cast<unsigned long long>(lib_lower),
                  diff_edge.header("").c_str(), diff_edge.row().c_str());
    }
    for (auto& e : diff_examples) std::printf("- %s\n", e.c_str());
    if (!diff_examples.empty()) std::printf("\n");
    const double M = static_cast<double>(a.smith_walks);
    std::printf("| order | library tracer | independent tracer | Smith walk (%llu) |\n|---|---|---|---|\n",
                static_cast<unsigned long long>(a.smith_walks));
    const int bands[][2] = {{1, 1}, {2, 2}, {3, 3}, {4, 1 << 30}, {4, 4}, {5, 5}, {6, 7}, {8, 15}, {16, 1 << 30}};
    for (auto& b : bands) {
      char lab[32];
      if (b[0] == b[1]) std::snprintf(lab, sizeof lab, "%d", b[0]);
      else if (b[1] == (1 << 30)) std::snprintf(lab, sizeof lab, "%d+", b[0]);
      else std::snprintf(lab, sizeof lab, "%d-%d", b[0], b[1]);
      const double pm = albedo(hist_ms, b[0], b[1], N), pr = albedo(hist_ref, b[0], b[1], N),
                   ps = albedo(hist_smith, b[0], b[1], M);
      std::printf("| %s | %.6f ± %.6f | %.6f | %.6f ± %.6f |\n", lab, pm, std::sqrt(pm * (1 - pm) / N), pr,
                  ps, std::sqrt(ps * (1 - ps) / M));
    }
    int max_order = hist_ms.empty() ? 0 : hist_ms.rbegin()->first;
    std::printf("\nlongest path: %d events\n\n", max_order);

    std::printf("Hits of the library tracer's paths, by the path's order (fractions of the hits):\n\n");
    auto table = [&](const char* title, Hist ClassStats::*h) {
      std::printf("| %s |%s\n|---|", title, (cs[0].*h).header("").c_str());
      for (std::size_t k = 0; k <= (cs[0].*h).edges.size(); ++k) std::printf("---|");
      std::printf("\n");
      for (int c = 0; c < 4; ++c) std::printf("| order %s |%s\n", names[c], (cs[c].*h).row().c_str());
      std::printf("\n");
    };
    table("segment length before a hit (cells)", &ClassStats::seg);
    table("distance of a hit to its facet's nearest edge (cells)", &ClassStats::edge);
    table("cos(n, -d) at a hit", &ClassStats::cosv);
    table("hit height / rms height", &ClassStats::height);
    table("path extent: max horizontal distance from the first hit (l)", &ClassStats::extent);
    std::printf("| order | paths | hits | mean height / sigma | consecutive facets: edge-adjacent | "
                "vertex-adjacent | farther | same facet | segments across a seam | revisited facets "
                "per path | mean net travel along / across the incidence plane (l) | hits on walls "
                "along the plane (abs n_y > abs n_x) | consecutive hits on opposite such walls | mean "
                "Laplacian at hits / rms | hits in concave places |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int c = 0; c < 4; ++c) {
      const ClassStats& st = cs[c];
      const double segs = std::max<double>(1, st.hits - st.paths), P = std::max<double>(1, st.paths);
      std::printf("| %s | %llu | %llu | %+.3f | %.4f | %.4f | %.4f | %.4f | %.4f | %.3f | %.2f / %.2f | %.3f | %.3f | %+.3f | %.3f |\n",
                  names[c], static_cast<unsigned long long>(st.paths),
                  static_cast<unsigned long long>(st.hits), st.sum_h / std::max<double>(1, st.hits),
                  st.rel[1] / segs, st.rel[2] / segs, st.rel[3] / segs, st.rel[0] / segs,
                  st.seam_segments / segs, st.revisits / P, st.sum_along / P, st.sum_across / P,
                  st.side_walls / std::max<double>(1, st.hits), st.alternations / segs,
                  st.sum_lap / std::max<double>(1, st.hits), st.concave / std::max<double>(1, st.hits));
    }
    std::printf("\n| after reflection | rays | leaving downward | leaving upward | of those, hit again | "
                "Smith's prediction for the same heights and directions | ratio |\n"
                "|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 4; ++k) {
      const Continuation& q = cont[k];
      const double up = std::max<double>(1, q.up);
      std::printf("| %s | %llu | %.4f | %llu | %.4f ± %.4f | %.4f | %.2f |\n", names[k],
                  static_cast<unsigned long long>(q.up + q.down),
                  q.down / std::max<double>(1, q.up + q.down), static_cast<unsigned long long>(q.up),
                  q.up_hit / up, std::sqrt(q.up_hit / up * (1 - q.up_hit / up) / up), q.smith_up_hit / up,
                  q.up_hit / std::max(1e-300, q.smith_up_hit));
    }
    std::printf("\n");
    for (auto& e : shown) std::printf("```\n%s```\n", e.c_str());
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
