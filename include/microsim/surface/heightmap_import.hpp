// Measured heightmaps (confocal microscope, interferometer, AFM, profilometer exports) as
// microsurfaces: reading, cropping, no-data filling, detrending, units.
//
// Formats: any image OpenImageIO reads (EXR, TIFF, PNG...; one channel, or the one named by
// `channel`; integer images give their raw integer values, not values scaled to [0, 1]); text
// grids (.txt .csv .asc .xyz .dat): either a matrix (one grid row per line, numbers separated by
// commas, semicolons, tabs or spaces) or x,y,z columns on a regular grid. Lines starting with
// '#', '%' or '//' and a first non-numeric line (a header) are skipped.
// Orientation: row r of the file (image row r, matrix line r, r-th distinct y) is grid row j = r,
// column c is grid column i = c, so a microsim EXR tile read back is the same tile.
#pragma once
#include <string>
#include <vector>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

// A raw height grid as read: row-major in j, NaN where a value is missing.
struct RawHeightGrid {
  int nx = 0, ny = 0;
  std::vector<double> z;
  double dx = 0, dy = 0;  // pixel sizes found in the file (x,y columns), 0 if none
  std::string format;     // "image", "matrix", "xyz"
  std::string channel;    // image channel used
};

// Throws UsageError naming the file for unreadable, malformed or empty input.
RawHeightGrid read_height_grid(const std::string& path, const std::string& channel = "");

enum class Detrend { None, Mean, Plane, Poly2 };
Detrend parse_detrend(const std::string& name);  // ParameterError naming {detrend}
std::string to_string(Detrend d);

// Least-squares fit of {1}, {1, x, y} or {1, x, y, x^2, xy, y^2} (x = i dx, y = j dy) over
// the finite values, subtracted from every value; returns the coefficients in that order.
// Throws UsageError when there are fewer finite values than coefficients.
std::vector<double> detrend(std::vector<double>& z, int nx, int ny, double dx, double dy, Detrend d);

// Harmonic inpainting: every missing (NaN) value becomes the mean of its four neighbours (across
// the tile's sides if periodic, else only those inside), i.e. the discrete Laplace equation
// with the known values as boundary condition, solved by successive over-relaxation until the
// largest update is below 1e-9 of the height range. Returns the number filled.
std::size_t fill_missing(std::vector<double>& z, int nx, int ny, bool periodic);

struct HeightmapImportParams {
  std::string input;
  std::string channel;                 // image channel (default: the only one, else Z, else Y)
  double pixel_size_x = 0;             // > 0; for x,y,z files 0 = from the x column
  double pixel_size_y = 0;             // 0 = pixel_size_x (or from the y column)
  double height_scale = 1;             // file value * scale = height in height_unit
  std::string length_unit;             // unit of the pixel sizes and of the saved surface
  std::string height_unit;             // unit of the scaled file values (default: length_unit)
  bool periodic = false;
  Detrend detrend = Detrend::Mean;
  bool crop = false;
  int crop_x0 = 0, crop_y0 = 0, crop_w = 0, crop_h = 0;
  bool has_nodata = false;
  double nodata = 0;                   // file value meaning "no measurement" (NaN always does)
  double max_missing_fraction = 0.05;  // refuse to fill more than this
  // Window guard band (surface/guard_band.hpp): a width in surface units (>= 0), else in
  // correlation lengths (>= 0), else the default; recorded in the description ("guard_band"),
  // applied when the window is loaded for the estimators.
  double guard_width = -1;
  double guard_correlation_lengths = -1;
};

// Factor of a length unit in metres (m, mm, um, nm, pm; "" = 0: no unit).
double length_unit_in_metres(const std::string& unit);

// The imported heightfield (a periodic tile when p.periodic, else a non-periodic window: its
// description has "boundary": "window" and its saved header a non-periodic macrosurface), with the whole import recorded in its description. UsageError (one
// line naming the file or the option) for bad options, malformed files, all-missing maps, more
// missing values than allowed, and constant maps (before or after detrending).
Microsurface import_heightmap(const HeightmapImportParams& p);

}  // namespace microsim
