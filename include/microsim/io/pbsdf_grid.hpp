// The sizes of a measured .pbsdf table (io/pbsdf.hpp): how many wavelengths Mitsuba's
// `measured_polarized` reads and how many nodes a table resolution gives. Apart from the writer
// so that a BSDF request can be checked (and its memory estimated) without the file format's
// code: this header depends on nothing of microsim.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace microsim {

// The plugin copies exactly this many wavelengths from the file.
constexpr std::size_t kPbsdfWavelengths = 5;
// The wavelengths written for a single index (mirror, one conductor index): the same matrix at each.
inline std::vector<std::uint16_t> pbsdf_single_index_wavelengths() { return {450, 500, 550, 600, 650}; }

// The node counts of a measured table of resolution n (the request's table resolution):
// theta_h and theta_d n / 2 + 1 nodes over [0, pi/2], phi_d n + 1 nodes over [-pi, pi], so that
// the spacing is 90 / (n / 2) degrees along each angle.
struct PbsdfGrid {
  int theta_h = 0, theta_d = 0, phi_d = 0;
};
inline PbsdfGrid pbsdf_grid(int table_resolution) {
  return {table_resolution / 2 + 1, table_resolution / 2 + 1, table_resolution + 1};
}

}  // namespace microsim
