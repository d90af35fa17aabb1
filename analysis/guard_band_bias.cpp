// The bias of a measured patch's guard band. A periodic Gaussian tile (Beckmann alpha) is
// measured twice with the same sample points and seeds: as a non-periodic window (traced
// without wrap-around, sample points and ray footprints inset by the guard) and as the periodic
// tile restricted to the same interior cells (wrap-around kept: the surroundings are real).
// The difference is what the missing surroundings do; z = (window - periodic) / sqrt(se_w^2 +
// se_p^2) with both ray-count errors. Guards in correlation lengths l of the Gaussian ACF.
// Long (minutes at 1024^2): run through analysis/guard_band_bias.sh, nice -n 10.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "microsim/io/output.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/g2_measure.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/guard_band.hpp"
#include "microsim/trace/tracer.hpp"
#include "arg_lists.hpp"

using namespace microsim;
using microsim::analysis::parse_list;

namespace {

struct Value {
  std::string name;
  double mean = 0, se = 0;
};

// Every quantity of the table for one surface (window or reference).
double phi_deg = 0;  // azimuth of the G1 views and of the BSDF incidence

std::vector<Value> measure_all(const Microsurface& s, std::uint64_t rays, std::uint64_t bsdf_rays,
                               std::uint64_t seed, double& side_fraction) {
  Tracer tracer(s);
  std::vector<Value> out;
  std::uint64_t side = 0, traced = 0;
  G1Options go;
  go.rays = rays;
  go.seed = seed;
  for (double t : {60.0, 80.0, 85.0}) {
    const G1Result r = measure_g1(tracer, direction_from_angles(rad(t), rad(phi_deg)), go);
    const Estimate b = r.g1_area_sampling(), a = r.g1_raycast();
    char name[64];
    std::snprintf(name, sizeof name, "G1(%g) area sampling", t);
    out.push_back({name, b.mean, b.stderr_});
    std::snprintf(name, sizeof name, "G1(%g) ray casting", t);
    out.push_back({name, a.mean, a.stderr_});
    side += r.counters.side_exits + r.counters.side_entries;
    traced += r.counters.rays;
  }
  G2Options o2;
  o2.rays = rays;
  o2.seed = seed;
  const G2Result g2 = measure_g2(tracer, direction_from_angles(rad(70.0), 0.0),
                                 direction_from_angles(rad(70.0), kPi), o2);
  const Estimate e2 = g2.g2();
  out.push_back({"G2(70/70, opposite azimuths)", e2.mean, e2.stderr_});
  side += g2.counters.side_exits;
  traced += g2.counters.rays;
  BsdfOptions bo;
  bo.rays = bsdf_rays;
  bo.seed = seed;
  bo.theta_i = rad(60.0);
  bo.phi_i = rad(phi_deg);
  bo.models = false;
  bo.resolution = 8;
  const BsdfResult br = measure_bsdf(tracer, bo);
  const char* names[] = {"albedo order 1 (60)", "albedo order 2 (60)", "albedo order 3 (60)",
                         "albedo order 4+ (60)", "albedo total (60)"};
  for (int k = 0; k <= bo.orders; ++k) {
    const Estimate e = br.albedo(0, k);
    out.push_back({names[k], e.mean, e.stderr_});
  }
  side += br.measured.counters.side_exits + br.measured.counters.side_entries;
  traced += br.measured.counters.rays;
  side_fraction = traced ? static_cast<double>(side) / traced : 0.0;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int resolution = 1024, cells_per_l = 8;
  std::vector<double> alphas = {0.5, 1.0}, guards = {0, 1, 2, 4, 8};
  std::uint64_t rays = 1000000, bsdf_rays = 1000000, seed = 1;
  const char* csv = nullptr;
  for (int k = 1; k < argc; ++k) {
    auto next = [&] {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", argv[k]);
        std::exit(2);
      }
      return argv[++k];
    };
    if (!std::strcmp(argv[k], "--resolution")) resolution = std::atoi(next());
    else if (!std::strcmp(argv[k], "--cells-per-l")) cells_per_l = std::atoi(next());
    else if (!std::strcmp(argv[k], "--alphas")) alphas = parse_list(next());
    else if (!std::strcmp(argv[k], "--guards")) guards = parse_list(next());
    else if (!std::strcmp(argv[k], "--rays")) rays = std::strtoull(next(), nullptr, 10);
    else if (!std::strcmp(argv[k], "--bsdf-rays")) bsdf_rays = std::strtoull(next(), nullptr, 10);
    else if (!std::strcmp(argv[k], "--seed")) seed = std::strtoull(next(), nullptr, 10);
    else if (!std::strcmp(argv[k], "--csv")) csv = next();
    else if (!std::strcmp(argv[k], "--phi")) phi_deg = std::atof(next());
    else {
      std::fprintf(stderr, "unknown option %s\n", argv[k]);
      return 2;
    }
  }
  // The CSV rows, written at the end through the checked atomic output (a full disk fails the
  // run instead of leaving a truncated table).
  std::string rows;
  auto row = [&rows](const char* format, auto... values) {
    char line[512];
    std::snprintf(line, sizeof line, format, values...);
    rows += line;
  };
  if (csv)
    row("%s", "alpha,guard_l,guard_cells,interior_cells,quantity,window,window_stderr,periodic,"
                    "periodic_stderr,difference,z,side_fraction\n");
  std::printf("Tile %d^2 cells, l = %d cells (%g l per side), %llu rays per G1/G2 estimate, %llu BSDF "
              "paths, seed %llu\n",
              resolution, cells_per_l, static_cast<double>(resolution) / cells_per_l,
              static_cast<unsigned long long>(rays), static_cast<unsigned long long>(bsdf_rays),
              static_cast<unsigned long long>(seed));
  for (double alpha : alphas) {
    GaussianParams p;
    p.resolution = resolution;
    p.alpha_x = p.alpha_y = alpha;
    p.correlation_length = static_cast<double>(cells_per_l) / resolution;
    p.seed = seed;
    const Microsurface tile = generate_gaussian(p);
    const int cx = resolution - 1;  // the window's cells (between its vertices)
    for (double g : guards) {
      const int gc = static_cast<int>(std::lround(g * cells_per_l));
      Microsurface window = tile, reference = tile;
      apply_guard_band(window, gc, gc, false, p.correlation_length);
      reference.set_sample_region(gc, cx - gc, gc, cx - gc, true);  // the same cells, wrapped
      double side_w = 0, side_p = 0;
      const std::vector<Value> w = measure_all(window, rays, bsdf_rays, seed, side_w);
      const std::vector<Value> r = measure_all(reference, rays, bsdf_rays, seed, side_p);
      std::printf("\n### Beckmann alpha %g, guard %g l (%d cells), interior %d^2 cells; rays meeting a "
                  "side wall: %.3g%%\n\n",
                  alpha, g, gc, cx - 2 * gc, 100 * side_w);
      std::printf("| quantity | window | periodic | window - periodic | z |\n|---|---|---|---|---|\n");
      for (std::size_t q = 0; q < w.size(); ++q) {
        const double d = w[q].mean - r[q].mean, se = std::hypot(w[q].se, r[q].se);
        const double z = se > 0 ? d / se : 0.0;
        std::printf("| %s | %.5f +- %.5f | %.5f +- %.5f | %+.5f | %+.2f |\n", w[q].name.c_str(), w[q].mean,
                    w[q].se, r[q].mean, r[q].se, d, z);
        if (csv)
          row("%g,%g,%d,%d,\"%s\",%.8g,%.8g,%.8g,%.8g,%.8g,%.4f,%.6g\n", alpha, g, gc, cx - 2 * gc,
                       w[q].name.c_str(), w[q].mean, w[q].se, r[q].mean, r[q].se, d, z, side_w);
      }
      std::fflush(stdout);
    }
  }
  if (csv) {
    try {
      write_stream_atomically(csv, [&](std::ofstream& out) { out << rows; });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "guard_band_bias: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}
