#include "microsim/surface/heightmap_import.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/surface/guard_band.hpp"

#include <Eigen/Dense>

#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "microsim/io/oiio_module.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/discretization.hpp"
#include "microsim/surface/metrology.hpp"

namespace microsim {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool is_text_extension(const std::string& ext) {
  return ext == "txt" || ext == "csv" || ext == "asc" || ext == "xyz" || ext == "dat" || ext == "tsv";
}

// Images are read by the OpenImageIO module (plugins/oiio_reader.cpp, io/oiio_module.hpp).
using ReadChannel = int (*)(const char*, const char*, int*, int*, double**, char*, int, char*, int);

ReadChannel image_reader() {
  static ReadChannel fn = reinterpret_cast<ReadChannel>(oiio_module_symbol("microsim_oiio_read_channel"));
  return fn;
}

RawHeightGrid read_image(const std::string& path, const std::string& channel) {
  RawHeightGrid g;
  double* data = nullptr;
  char chosen[256] = {0}, err[1024] = {0};
  if (image_reader()(path.c_str(), channel.c_str(), &g.nx, &g.ny, &data, chosen, sizeof chosen, err, sizeof err))
    throw UsageError(err);
  const std::size_t n = static_cast<std::size_t>(g.nx) * g.ny;
  g.z.assign(data, data + n);
  std::free(data);
  g.format = "image";
  g.channel = chosen;
  return g;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// Fields of one line: split on ',' or ';' when present (an empty field is missing), else on
// white space. Returns false if a field is not a number.
bool parse_fields(const std::string& line, std::vector<double>& out, std::string& bad) {
  out.clear();
  std::vector<std::string> fields;
  const char sep = line.find(',') != std::string::npos ? ',' : line.find(';') != std::string::npos ? ';' : 0;
  if (sep) {
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, sep)) fields.push_back(trim(f));
    if (!line.empty() && line.back() == sep) fields.push_back("");
  } else {
    std::stringstream ss(line);
    std::string f;
    while (ss >> f) fields.push_back(f);
  }
  for (const auto& f : fields) {
    if (f.empty()) {
      out.push_back(kNaN);
      continue;
    }
    char* end = nullptr;
    const double v = std::strtod(f.c_str(), &end);
    if (end != f.c_str() + f.size()) {
      bad = f;
      return false;
    }
    out.push_back(v);
  }
  return true;
}

// A regular grid of the distinct values of one column: index of each value, and the spacing.
bool regular_axis(std::vector<double> values, std::map<double, int>& index, double& spacing) {
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  if (values.size() < 2) return false;
  spacing = (values.back() - values.front()) / (values.size() - 1);
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (std::abs(values[k] - (values.front() + k * spacing)) > 1e-6 * spacing) return false;
    index[values[k]] = static_cast<int>(k);
  }
  return spacing > 0;
}

RawHeightGrid read_text(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw UsageError(path + ": cannot open");
  std::vector<std::vector<double>> rows;
  std::vector<int> line_of_row;
  std::string line, bad;
  std::vector<double> fields;
  bool header_seen = false;
  for (int lineno = 1; std::getline(f, line); ++lineno) {
    // A UTF-8 byte order mark (spreadsheet exports) is not part of the first row.
    if (lineno == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    const std::string t = trim(line);  // also the '\r' of CRLF line ends
    if (t.empty() || t[0] == '#' || t[0] == '%' || t.rfind("//", 0) == 0) continue;
    if (!parse_fields(t, fields, bad)) {
      if (rows.empty() && !header_seen) {  // a header line naming the columns
        header_seen = true;
        continue;
      }
      throw UsageError(path + ":" + std::to_string(lineno) + ": '" + bad + "' is not a number");
    }
    if (fields.empty()) continue;
    if (!rows.empty() && fields.size() != rows.front().size())
      throw UsageError(path + ":" + std::to_string(lineno) + ": " + std::to_string(fields.size()) +
                       " values where the first row has " + std::to_string(rows.front().size()));
    rows.push_back(fields);
    line_of_row.push_back(lineno);
  }
  if (rows.empty()) throw UsageError(path + ": no numbers (an empty or non-numeric file)");
  RawHeightGrid g;
  // x,y,z columns when the first two columns are regular grid coordinates covering the rows.
  if (rows.front().size() == 3 && rows.size() >= 4) {
    std::vector<double> xs, ys;
    bool finite = true;
    for (const auto& r : rows) {
      xs.push_back(r[0]);
      ys.push_back(r[1]);
      finite = finite && std::isfinite(r[0]) && std::isfinite(r[1]);
    }
    std::map<double, int> ix, iy;
    double sx = 0, sy = 0;
    if (finite && regular_axis(xs, ix, sx) && regular_axis(ys, iy, sy) &&
        ix.size() * iy.size() <= 2 * rows.size()) {
      g.format = "xyz";
      g.nx = static_cast<int>(ix.size());
      g.ny = static_cast<int>(iy.size());
      g.dx = sx;
      g.dy = sy;
      g.z.assign(static_cast<std::size_t>(g.nx) * g.ny, kNaN);
      std::vector<char> seen(g.z.size(), 0);
      for (std::size_t k = 0; k < rows.size(); ++k) {
        const std::size_t at = static_cast<std::size_t>(iy[rows[k][1]]) * g.nx + ix[rows[k][0]];
        if (seen[at])
          throw UsageError(path + ":" + std::to_string(line_of_row[k]) + ": a second height at x " +
                           std::to_string(rows[k][0]) + ", y " + std::to_string(rows[k][1]));
        seen[at] = 1;
        g.z[at] = rows[k][2];
      }
      return g;
    }
  }
  g.format = "matrix";
  g.nx = static_cast<int>(rows.front().size());
  g.ny = static_cast<int>(rows.size());
  for (const auto& r : rows) g.z.insert(g.z.end(), r.begin(), r.end());
  return g;
}

bool finite_positive(double x) { return std::isfinite(x) && x > 0; }

std::string num(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}
}  // namespace

RawHeightGrid read_height_grid(const std::string& path, const std::string& channel) {
  require_regular_input(path, "{input}");
  std::ifstream probe(path);
  if (!probe) throw ParameterError("{input} " + literal_text(path) + ": cannot open");
  if (is_text_extension(extension_of(path))) {
    if (!channel.empty()) throw ParameterError("{channel}: " + literal_text(path) + " is a text grid, not an image");
    return read_text(path);
  }
  return read_image(path, channel);
}

Detrend parse_detrend(const std::string& name) {
  if (name == "none") return Detrend::None;
  if (name == "mean") return Detrend::Mean;
  if (name == "plane") return Detrend::Plane;
  if (name == "poly2") return Detrend::Poly2;
  throw ParameterError("{detrend} " + literal_text(name) + ": expected none, mean, plane or poly2");
}

std::string to_string(Detrend d) {
  switch (d) {
    case Detrend::None: return "none";
    case Detrend::Mean: return "mean";
    case Detrend::Plane: return "plane";
    case Detrend::Poly2: return "poly2";
  }
  return "";
}

std::vector<double> detrend(std::vector<double>& z, int nx, int ny, double dx, double dy, Detrend d) {
  if (d == Detrend::None) return {};
  const int terms = d == Detrend::Mean ? 1 : d == Detrend::Plane ? 3 : 6;
  // Coordinates centred on the grid, so that the normal equations are well conditioned.
  const double cx = 0.5 * (nx - 1) * dx, cy = 0.5 * (ny - 1) * dy;
  auto basis = [&](int i, int j, double* b) {
    const double x = i * dx - cx, y = j * dy - cy;
    const double all[6] = {1, x, y, x * x, x * y, y * y};
    std::copy(all, all + terms, b);
  };
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(terms, terms);
  Eigen::VectorXd atz = Eigen::VectorXd::Zero(terms);
  std::size_t n = 0;
  double b[6];
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double v = z[static_cast<std::size_t>(j) * nx + i];
      if (!std::isfinite(v)) continue;
      basis(i, j, b);
      Eigen::Map<Eigen::VectorXd> bv(b, terms);
      ata += bv * bv.transpose();
      atz += bv * v;
      ++n;
    }
  if (n < static_cast<std::size_t>(terms) * 2)
    throw ParameterError("{detrend} " + to_string(d) + ": too few heights (" + std::to_string(n) + ") to fit");
  // The normal equations of centred coordinates, solved by LDLT: exact to rounding for these few,
  // well-scaled terms (tested to 1e-12); a rank-deficient fit (a single row or column) is refused.
  Eigen::LDLT<Eigen::MatrixXd> ldlt(ata);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-13)
    throw ParameterError("{detrend} " + to_string(d) + ": the grid is too narrow to fit it");
  Eigen::VectorXd c = ldlt.solve(atz);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      basis(i, j, b);
      double fit = 0;
      for (int t = 0; t < terms; ++t) fit += c[t] * b[t];
      z[static_cast<std::size_t>(j) * nx + i] -= fit;
    }
  // Report the coefficients about the grid origin (x = i dx, y = j dy), not the centre.
  std::vector<double> out(c.data(), c.data() + terms);
  if (terms >= 3) {
    double c0 = out[0] - out[1] * cx - out[2] * cy, c1 = out[1], c2 = out[2];
    if (terms == 6) {
      c0 += out[3] * cx * cx + out[4] * cx * cy + out[5] * cy * cy;
      c1 += -2 * out[3] * cx - out[4] * cy;
      c2 += -2 * out[5] * cy - out[4] * cx;
    }
    out[0] = c0;
    out[1] = c1;
    out[2] = c2;
  }
  return out;
}

std::size_t fill_missing(std::vector<double>& z, int nx, int ny, bool periodic) {
  std::vector<std::size_t> holes;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
  std::size_t known = 0;
  for (std::size_t k = 0; k < z.size(); ++k) {
    if (!std::isfinite(z[k])) {
      holes.push_back(k);
      continue;
    }
    lo = std::min(lo, z[k]);
    hi = std::max(hi, z[k]);
    sum += z[k];
    ++known;
  }
  if (holes.empty()) return 0;
  if (known == 0) throw UsageError("no finite heights to fill from");
  for (auto k : holes) z[k] = sum / known;
  const double tol = 1e-9 * std::max(hi - lo, std::abs(hi));
  // Gauss-Seidel with over-relaxation; omega near 2 converges in O(hole width) sweeps.
  const double omega = 1.9;
  for (int sweep = 0; sweep < 100000; ++sweep) {
    double largest = 0;
    for (auto k : holes) {
      const int i = static_cast<int>(k % nx), j = static_cast<int>(k / nx);
      double s = 0;
      int m = 0;
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int e = 0; e < 4; ++e) {
        int a = i + di[e], b = j + dj[e];
        if (periodic) {
          a = (a + nx) % nx;
          b = (b + ny) % ny;
        } else if (a < 0 || a >= nx || b < 0 || b >= ny) {
          continue;
        }
        s += z[static_cast<std::size_t>(b) * nx + a];
        ++m;
      }
      if (m == 0) continue;
      const double update = omega * (s / m - z[k]);
      z[k] += update;
      largest = std::max(largest, std::abs(update));
    }
    if (largest <= tol) break;
  }
  return holes.size();
}

double length_unit_in_metres(const std::string& u) {
  if (u.empty()) return 0;
  if (u == "m") return 1;
  if (u == "mm") return 1e-3;
  if (u == "um") return 1e-6;
  if (u == "nm") return 1e-9;
  if (u == "pm") return 1e-12;
  return -1;
}

namespace {
// The window's guard band, recorded in the description (the loader applies it). An explicit
// width that leaves no interior is refused; the default one is only noted (the estimators
// then refuse the file, metrology still reads it).
void record_guard_band(Microsurface& s, const HeightmapImportParams& p) {
  const bool given = p.guard_width >= 0 || p.guard_correlation_lengths >= 0;
  const double l = patch_correlation_length(s);
  const double k = p.guard_correlation_lengths >= 0 ? p.guard_correlation_lengths : kDefaultGuardCorrelationLengths;
  const double w = p.guard_width >= 0 ? p.guard_width : k * l;
  const std::string option = p.guard_width >= 0 ? "{guard_width} " + num(p.guard_width)
                                                : "{guard} " + num(k) + " (correlation lengths, l = " + num(l) + ")";
  Microsurface region = s;
  try {
    apply_guard_band(region, guard_cells(w, s.dx()), guard_cells(w, s.dy()), false, l, option);
  } catch (const UsageError&) {
    if (given) throw;
    s.description["guard_band_note"] = "the default guard (" + num(k) + " l) leaves no interior: "
                                       "import with a narrower --guard to measure this patch";
    return;
  }
  s.description["guard_band"] = region.description["guard_band"];
}

// How finely the map resolves the surface, in the terms of the discretization study
// (docs/theory/discretization.md): the Gaussian correlation length l = (ACF decay length to 0.2) /
// sqrt(ln 5), as metrology reports it; cells per the shortest l (of the coarser pixel side) and
// the measured extent (the tile, or a window's interior) per the longest. A map whose ACF does
// not decay states nothing.
void record_discretization(Microsurface& s, bool periodic) {
  HeightGridView v = grid_view(s);
  v.periodic = periodic;
  const AcfStats a = acf_stats(v);
  if (!a.decayed || !(a.sal > 0) || !(a.longest > 0)) return;
  const double k = std::sqrt(std::log(1.0 / a.threshold));
  double extent = std::min(s.macro().size_x, s.macro().size_y);
  const Json& d = s.description;
  if (d.contains("guard_band") && d["guard_band"].contains("interior")) {
    const Json& in = d["guard_band"]["interior"];
    extent = std::min(in["x1"].get<double>() - in["x0"].get<double>(), in["y1"].get<double>() - in["y0"].get<double>());
  }
  add_discretization(s.description, std::max(s.dx(), s.dy()), extent, a.sal / k, a.longest / k);
}

// The parameters checked, in the order the import has always checked them; returns the factor
// from file values times height_scale (in height_unit) to the surface's length unit.
double checked_unit_factor(const HeightmapImportParams& p) {
  if (p.pixel_size_x != 0 && !finite_positive(p.pixel_size_x))
    throw ParameterError("{pixel_size} " + num(p.pixel_size_x) + ": must be a finite number > 0");
  if (p.pixel_size_y != 0 && !finite_positive(p.pixel_size_y))
    throw ParameterError("{pixel_size_y} " + num(p.pixel_size_y) + ": must be a finite number > 0");
  if (!std::isfinite(p.height_scale) || p.height_scale == 0)
    throw ParameterError("{height_scale} " + num(p.height_scale) + ": must be a finite nonzero number");
  if (!(p.max_missing_fraction >= 0 && p.max_missing_fraction < 1))
    throw ParameterError("{max_missing} " + num(p.max_missing_fraction) + ": must be in [0, 1)");
  if (p.has_nodata && !std::isfinite(p.nodata))
    throw ParameterError("{nodata} " + num(p.nodata) + ": must be a finite number (NaN is always missing)");
  const double lu = length_unit_in_metres(p.length_unit), hu = length_unit_in_metres(p.height_unit);
  if (lu < 0) throw ParameterError("{length_unit} " + literal_text(p.length_unit) + ": expected m, mm, um, nm or pm");
  if (hu < 0) throw ParameterError("{height_unit} " + literal_text(p.height_unit) + ": expected m, mm, um, nm or pm");
  if ((lu == 0) != (hu == 0) && !p.height_unit.empty() && p.length_unit.empty())
    throw ParameterError("{height_unit} " + literal_text(p.height_unit) + " needs {length_unit} (the unit of {pixel_size})");
  // File value * scale is in height_unit; the surface keeps one length unit for x, y and z.
  return (lu > 0 && hu > 0) ? hu / lu : 1.0;
}

// Grid spacings: the options, else the file's x,y columns; dy defaults to dx.
std::pair<double, double> pixel_sizes(const HeightmapImportParams& p, const RawHeightGrid& g) {
  double dx = p.pixel_size_x, dy = p.pixel_size_y;
  if (dx == 0) {
    if (g.dx <= 0) throw ParameterError("{pixel_size} is required for " + literal_text(p.input) + " (a " + g.format + " has no x,y columns)");
    dx = g.dx;
    if (dy == 0) dy = g.dy;
  }
  if (dy == 0) dy = dx;
  return {dx, dy};
}

// The crop's window of the grid (when asked), then at least 2 x 2 heights.
void crop_grid(RawHeightGrid& g, const HeightmapImportParams& p) {
  const std::string& path = p.input;
  if (p.crop) {
    if (p.crop_w < 2 || p.crop_h < 2 || p.crop_x0 < 0 || p.crop_y0 < 0 || p.crop_x0 + p.crop_w > g.nx ||
        p.crop_y0 + p.crop_h > g.ny)
      throw ParameterError("{crop} " + std::to_string(p.crop_x0) + "," + std::to_string(p.crop_y0) + "," +
                           std::to_string(p.crop_w) + "," + std::to_string(p.crop_h) + ": outside the " +
                           std::to_string(g.nx) + " x " + std::to_string(g.ny) + " grid of " + literal_text(path) +
                           " (or smaller than 2 x 2)");
    std::vector<double> c;
    c.reserve(static_cast<std::size_t>(p.crop_w) * p.crop_h);
    for (int j = p.crop_y0; j < p.crop_y0 + p.crop_h; ++j)
      for (int i = p.crop_x0; i < p.crop_x0 + p.crop_w; ++i) c.push_back(g.z[static_cast<std::size_t>(j) * g.nx + i]);
    g.z = std::move(c);
    g.nx = p.crop_w;
    g.ny = p.crop_h;
  }
  if (g.nx < 2 || g.ny < 2)
    throw UsageError(path + ": a " + std::to_string(g.nx) + " x " + std::to_string(g.ny) +
                     " grid; a heightmap needs at least 2 x 2 heights");
}

// Missing heights (NaN, nodata) as NaN, the others scaled to the surface's unit; refused when
// too many are missing or the rest is constant. Returns the fraction missing and the range.
struct ScaledHeights {
  double missing_fraction, lo, hi;
};
ScaledHeights scale_heights(RawHeightGrid& g, const HeightmapImportParams& p, double unit_factor) {
  const std::string& path = p.input;
  std::size_t missing = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 0; k < g.z.size(); ++k) {
    double& v = g.z[k];
    if (std::isnan(v) || (p.has_nodata && v == p.nodata)) {
      v = kNaN;
      ++missing;
      continue;
    }
    // Only NaN and --nodata mark a missing height: an infinite one (or one beyond the range of
    // a double, such as 1e999, or one the scale carries there) is a defect of the file, not a
    // hole to fill.
    const double raw = v;
    v *= p.height_scale * unit_factor;
    if (!std::isfinite(v))
      throw ParameterError(literal_text(path) + ": height " + num(raw) + " at column " + std::to_string(k % g.nx) + ", row " +
                           std::to_string(k / g.nx) + (std::isfinite(raw) ? " times {height_scale}" : "") +
                           " is not a finite number (missing heights are NaN or {nodata})");
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  const double fraction = static_cast<double>(missing) / g.z.size();
  if (missing == g.z.size()) throw ParameterError(literal_text(path) + ": every height is missing (NaN or {nodata})");
  if (fraction > p.max_missing_fraction)
    throw ParameterError(literal_text(path) + ": " + std::to_string(missing) + " of " + std::to_string(g.z.size()) +
                         " heights missing (" + num(100 * fraction) + "%), above {max_missing} " +
                         num(p.max_missing_fraction) + "; crop to the measured region or raise {max_missing}");
  if (!(hi > lo)) throw UsageError(path + ": constant heights (" + num(lo) + "): a plane, nothing to measure");
  return {fraction, lo, hi};
}

// The detrend's coefficients; refused when it leaves nothing (the map is that form exactly).
std::vector<double> detrended(RawHeightGrid& g, const HeightmapImportParams& p, double dx, double dy,
                              const ScaledHeights& before) {
  const std::vector<double> coef = detrend(g.z, g.nx, g.ny, dx, dy, p.detrend);
  double lo2 = std::numeric_limits<double>::infinity(), hi2 = -lo2;
  for (double v : g.z)
    if (std::isfinite(v)) {
      lo2 = std::min(lo2, v);
      hi2 = std::max(hi2, v);
    }
  if (!(hi2 - lo2 > 1e-6 * (before.hi - before.lo)))
    throw ParameterError(literal_text(p.input) + ": nothing left after {detrend} " + to_string(p.detrend) +
                         " (the map is that form exactly)");
  return coef;
}

// Data that is not periodic gets a cliff where the tile wraps: the RMS slopes with and without
// the wrap-around cells (equal for a truly periodic map, up to 1/n noise).
Json seam_check(const Microsurface& s) {
  HeightGridView v = grid_view(s);
  v.periodic = false;
  const SlopeStats inner = slope_stats(v, 2);
  v.periodic = true;
  const SlopeStats all = slope_stats(v, 2);
  return {{"slope_rms_x_tile", all.rms_x}, {"slope_rms_y_tile", all.rms_y},
          {"slope_rms_x_without_wrap", inner.rms_x}, {"slope_rms_y_without_wrap", inner.rms_y}};
}
}  // namespace

Microsurface import_heightmap(const HeightmapImportParams& p) {
  const std::string& path = p.input;
  const double unit_factor = checked_unit_factor(p);
  RawHeightGrid g = read_height_grid(path, p.channel);
  const auto [dx, dy] = pixel_sizes(p, g);
  crop_grid(g, p);
  const ScaledHeights scaled = scale_heights(g, p, unit_factor);
  const std::vector<double> coef = detrended(g, p, dx, dy, scaled);
  const std::size_t filled = fill_missing(g.z, g.nx, g.ny, p.periodic);

  std::vector<float> heights(g.z.begin(), g.z.end());
  Microsurface s = Microsurface::heightfield(g.nx, g.ny, g.nx * dx, g.ny * dy, std::move(heights));
  Json d;
  d["kind"] = "heightmap";
  d["file"] = path;
  d["format"] = g.format;
  if (!g.channel.empty()) d["channel"] = g.channel;
  d["resolution_x"] = g.nx;
  d["resolution_y"] = g.ny;
  d["pixel_size_x"] = dx;
  d["pixel_size_y"] = dy;
  d["length_unit"] = p.length_unit.empty() ? "unspecified" : p.length_unit;
  d["height_unit_in_file"] = p.height_unit.empty() ? d["length_unit"].get<std::string>() : p.height_unit;
  d["height_scale"] = p.height_scale;
  d["height_factor"] = p.height_scale * unit_factor;
  d["boundary"] = p.periodic ? "periodic" : "window";
  if (p.crop) d["crop"] = {p.crop_x0, p.crop_y0, p.crop_w, p.crop_h};
  if (p.has_nodata) d["nodata"] = p.nodata;
  d["missing_filled"] = filled;
  d["missing_fraction"] = scaled.missing_fraction;
  d["fill_rule"] = "harmonic: each missing height is the mean of its 4 neighbours (discrete Laplace equation)";
  d["detrend"] = to_string(p.detrend);
  d["detrend_coefficients"] = coef;
  d["detrend_basis"] = "1, x, y, x^2, x y, y^2 with x = i pixel_size_x, y = j pixel_size_y (first terms)";
  if (p.periodic) d["seam_check"] = seam_check(s);
  s.description = d;
  if (!p.periodic) record_guard_band(s, p);
  record_discretization(s, p.periodic);
  return s;
}
}  // namespace microsim
