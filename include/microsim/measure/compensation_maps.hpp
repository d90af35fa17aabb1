// Hemisphere maps of analytic lobes in the equal-area convention of measure bsdf (HemisphereMap), so that
// they compare pixel by pixel with the measured maps, and a distance between two lobes' shapes.
// (docs/theory/energy-compensation.md)
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "microsim/measure/bsdf_measure.hpp"
#include "microsim/models/energy_compensation.hpp"

namespace microsim {

// A lobe as a function of the outgoing direction o (upper hemisphere, unit), in 1/sr.
using LobeFunction = std::function<double(const Vec3& o)>;

// The map of a lobe: pixel px (HemisphereMap's index j R + i) holds the cosine-weighted pixel average
// int_pixel f |cos| d omega / int_pixel |cos| d omega, the quantity of the measured maps
// (f = p / int_pixel |cos| d omega). The pixel integral: sub x sub midpoints of the pixel's square
// (equal area: uniform in solid angle).
std::vector<double> lobe_map(const HemisphereMap& map, const LobeFunction& f, int sub = 8);

// sum_px f[px] int_px |cos| d omega: the albedo (power) of a map.
double map_albedo(const HemisphereMap& map, const std::vector<double>& f);

// The Smith random walk's [Heitz16] map of the orders >= min_order for light from i: `walks` walks
// (CounterRng(seed, 0, k)), each exit's weight binned by its direction. Also the albedo of those orders.
struct WalkMap {
  std::vector<double> f;
  double albedo = 0.0;
};
WalkMap smith_walk_map(const models::Ndf& ndf, const models::Material& material, const Vec3& i,
                       const HemisphereMap& map, int min_order, std::uint64_t walks, std::uint64_t seed = 1);

// Hellinger distance between two lobes' shapes: each map is turned into the distribution of its power over the
// pixels, p_px = max(f_px, 0) c_px / sum (c_px = int_px |cos| d omega), which removes the albedo;
// H = sqrt(1 - sum_px sqrt(p_px q_px)) in [0, 1]: 0 for the same shape, 1 for disjoint supports.
// Throws when a map has no positive power or the sizes differ.
double hellinger_distance(const std::vector<double>& cos_integrals, const std::vector<double>& f,
                          const std::vector<double>& g);
double hellinger_distance(const HemisphereMap& map, const std::vector<double>& f, const std::vector<double>& g);

}  // namespace microsim
