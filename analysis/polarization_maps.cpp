// The degree of polarization of a spectral conductor's reflected light direction by direction,
// per scattering order (analysis, not a test; used by analysis/spectral_polarized.py).
//
// `measure bsdf --polarized` records, per order, the flux-weighted mean of the pixel degrees of
// polarization of a coarse hemisphere map (resolved_degree_of_polarization); the map itself stays
// in the library's PolarizationTally. This program runs the same measurement through the library
// (same seed and streams as the command line, so the same paths) and writes the map: per
// incidence, order slot, wavelength and pixel, the reflected flux of the unpolarized input (flux)
// and of the s input (flux_s) per incident path and the degree of polarization of the outgoing
// light for each of the two inputs, each pixel's matrices summed in the frames of their own exit
// directions.
//
//   polarization_maps SURFACE METAL NM[,NM...] THETA_DEG[,THETA...] RAYS SEED OUT.json
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "arg_lists.hpp"
#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/models/metals.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"

using namespace microsim;

namespace {

// The conductor of each wavelength, from a shipped table.
std::vector<models::Material> conductors(const std::string& metal, const std::vector<double>& nm) {
  const models::IndexTable& table = models::metal_table(metal);
  std::vector<models::Material> out;
  for (double x : nm) {
    const models::OpticalConstant c = table.at(x);
    out.push_back(models::Material::conductor(c.n, c.k));
  }
  return out;
}

// Degree of polarization of a Stokes vector (0 for no flux).
double degree_of_polarization(const models::Stokes& s) {
  return s[0] > 0.0 ? s.tail<3>().norm() / s[0] : 0.0;
}

// One pixel's mean Mueller matrix per path (row-major block of 16 sums).
models::Mueller pixel_mean(const double* sums, std::uint64_t paths) {
  models::Mueller m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m(i, j) = sums[4 * i + j] / static_cast<double>(paths);
  return m;
}

// The map of one incidence: [slot][wavelength] -> {flux, dop_unpolarized, dop_s} per pixel.
Json incidence_maps(const BsdfResult& r, const std::vector<double>& nm) {
  const PolarizationTally& t = *r.polarization;
  const HemisphereMap map(kPolarizationMapResolution);
  const models::Stokes unpolarized(1.0, 0.0, 0.0, 0.0), s_input(1.0, 1.0, 0.0, 0.0);
  Json pixels = Json::array();
  for (int px = 0; px < t.pixels; ++px) {
    const int i = px % map.resolution(), j = px / map.resolution();
    const double a = -1.0 + (2.0 * i + 1.0) / map.resolution(), b = -1.0 + (2.0 * j + 1.0) / map.resolution();
    const Vec3 d = map.from_square(a, b);
    pixels.push_back({{"i", i}, {"j", j}, {"center", {d.x(), d.y(), d.z()}}});
  }
  Json slots = Json::object();
  for (int k = 0; k < t.slots(); ++k) {
    Json per_nm = Json::array();
    for (int l = 0; l < t.wavelengths; ++l) {
      Json flux = Json::array(), flux_s = Json::array(), dop_u = Json::array(), dop_s = Json::array();
      const std::size_t at = (static_cast<std::size_t>(k) * t.wavelengths + l) * t.pixels * 16;
      for (int px = 0; px < t.pixels; ++px) {
        const models::Mueller m = pixel_mean(t.map_total.data() + at + 16 * static_cast<std::size_t>(px), t.paths);
        const models::Stokes out_s = m * s_input;
        flux.push_back(m(0, 0));
        flux_s.push_back(out_s[0]);
        dop_u.push_back(degree_of_polarization(m * unpolarized));
        dop_s.push_back(degree_of_polarization(out_s));
      }
      per_nm.push_back({{"wavelength_nm", nm[l]}, {"flux", flux}, {"flux_s", flux_s},
                        {"dop_unpolarized", dop_u}, {"dop_s", dop_s}});
    }
    slots[order_key(k, t.orders)] = per_nm;
  }
  return {{"theta_i_deg", r.options.theta_i * 180.0 / kPi}, {"paths", t.paths},
          {"map_resolution", map.resolution()}, {"pixels", pixels}, {"reflected", slots}};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 8) {
    std::fprintf(stderr, "usage: polarization_maps SURFACE METAL NM[,NM...] THETA_DEG[,...] RAYS SEED OUT.json\n");
    return 2;
  }
  try {
    const Microsurface s = load_surface(argv[1]);
    const Tracer tracer(s);
    const std::vector<double> nm = analysis::parse_list(argv[3]);
    BsdfOptions o;
    o.wavelengths_nm = nm;
    o.spectral = conductors(argv[2], nm);
    o.material = o.spectral.front();
    o.rays = std::strtoull(argv[5], nullptr, 10);
    o.seed = std::strtoull(argv[6], nullptr, 10);
    o.models = false;
    o.polarized = true;
    Json out = {{"surface", argv[1]}, {"metal", argv[2]}, {"wavelengths_nm", nm}, {"incidences", Json::array()}};
    for (double theta : analysis::parse_list(argv[4])) {
      o.theta_i = theta * kPi / 180.0;
      out["incidences"].push_back(incidence_maps(measure_bsdf(tracer, o), nm));
    }
    write_json(argv[7], out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polarization_maps: %s\n", e.what());
    return 1;
  }
  return 0;
}
