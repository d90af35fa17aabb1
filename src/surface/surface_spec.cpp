// The table of surface kinds and their options (surface_spec.hpp), option values checked as the
// command line checks them, and presets (read by io/preset_file.hpp). The kinds' builders:
// surface_kinds.cpp.
#include "microsim/surface/surface_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "microsim/common.hpp"
#include "microsim/io/preset_file.hpp"
#include "microsim/surface/gaussian.hpp"
#include "microsim/surface/generators.hpp"
#include "microsim/surface/guard_band.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/mesh_check.hpp"

namespace microsim {

namespace {

using Type = SurfaceOption::Type;
using Check = SurfaceOption::Check;

// A default as the command line has always shown it (a stream's default format: 0.5, 1, 0.001).
template <class T>
std::string shown(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

SurfaceOption number(std::string name, Range r, std::string def, std::string help, std::string sets) {
  return {std::move(name), Type::Number, Check::Range, r, 0, 0, std::move(def), false, std::move(help), std::move(sets)};
}
SurfaceOption finite(std::string name, std::string def, std::string help, std::string sets) {
  return {std::move(name), Type::Number, Check::Finite, {0, 0}, 0, 0, std::move(def), false, std::move(help), std::move(sets)};
}
SurfaceOption any_number(std::string name, std::string def, std::string help, std::string sets) {
  return {std::move(name), Type::Number, Check::None, {0, 0}, 0, 0, std::move(def), false, std::move(help), std::move(sets)};
}
SurfaceOption integer(std::string name, long long lo, long long hi, std::string def, std::string help, std::string sets) {
  return {std::move(name), Type::Integer, Check::Integer, {0, 0}, lo, hi, std::move(def), false, std::move(help), std::move(sets)};
}
SurfaceOption seed(std::string sets) {
  return {"seed", Type::Seed, Check::Seed, {0, 0}, 0, 0, "1", false, "Random seed", std::move(sets)};
}
SurfaceOption text(std::string name, std::string def, std::string help, std::string sets, bool required = false) {
  return {std::move(name), Type::Text, Check::None, {0, 0}, 0, 0, std::move(def), required, std::move(help), std::move(sets)};
}
SurfaceOption flag(std::string name, std::string help, std::string sets) {
  return {std::move(name), Type::Flag, Check::None, {0, 0}, 0, 0, "", false, std::move(help), std::move(sets)};
}

const char* kStructuredOutput = "Output surface file (.ply, .obj, .off; .exr for heightfields)";
const char* kStructuredConfig = "Read options from a TOML preset (see surfaces/); command-line options win";

SurfaceKind gaussian_kind() {
  const GaussianParams ga;
  return {"gaussian", "Periodic Gaussian random heightfield with Beckmann slope statistics",
          "Output surface file (.exr, .ply, .obj, .off)",
          "Read options from a TOML preset (e.g. surfaces/beckmann-0.5.toml); command-line options win",
          {integer("resolution", 4, 32760, shown(ga.resolution), "Grid cells per side", "GaussianParams::resolution"),
           number("size", closed(1e-6, 1e6), shown(ga.size), "Tile side length", "GaussianParams::size"),
           number("correlation-length", positive(), "",
                  "Correlation length of the heights exp(-r^2/l^2), tile units (default: 16 cells, "
                  "at least 16 per tile and 4 cells; converged grid)",
                  "GaussianParams::correlation_length (default: default_correlation_length)"),
           number("alpha", open_closed(0, 10), "", "Isotropic Beckmann roughness alpha (> 0)",
                  "GaussianParams::alpha_x and alpha_y (not with alpha-x/alpha-y)"),
           number("alpha-x", open_closed(0, 10), "", "Roughness along x",
                  "GaussianParams::alpha_x (alone: alpha_y too)"),
           number("alpha-y", open_closed(0, 10), "", "Roughness along y",
                  "GaussianParams::alpha_y (alone: alpha_x too)"),
           seed("GaussianParams::seed")}};
}

SurfaceKind flat_kind() {
  const FlatParams fl;
  return {"flat", "Periodic plane z = 0: the exact reference of every estimator",
          "Output surface file (.exr, .ply, .obj, .off)", "Read options from a TOML preset; command-line options win",
          {integer("resolution", 1, 4096, shown(fl.resolution), "Grid cells per side", "FlatParams::resolution"),
           number("size", closed(1e-6, 1e6), shown(fl.size), "Tile side length", "FlatParams::size")}};
}

SurfaceKind box_kind() {
  const BoxParams bx;
  return {"box", "A box whose flipped bottom face is the macrosurface [GeomBSDF24, Fig. 2]; finite", kStructuredOutput,
          kStructuredConfig,
          {number("width", positive(), shown(bx.width), "W, along x", "BoxParams::width"),
           number("depth", positive(), shown(bx.depth), "D, along y", "BoxParams::depth"),
           number("height", positive(), shown(bx.height), "H, along z", "BoxParams::height")}};
}

SurfaceKind tiled_boxes_kind() {
  const BoxParams bx;
  return {"tiled-boxes", "The box's macrosurface covered by N x N copies of the box scaled by 1/N [GeomBSDF24, Fig. 6]",
          kStructuredOutput, kStructuredConfig,
          {integer("tiles", 1, 256, "4", "N", "BoxParams::tiles (default 4 here)"),
           number("width", positive(), shown(bx.width), "W of the whole (macrosurface), along x", "BoxParams::width"),
           number("depth", positive(), shown(bx.depth), "D of the whole, along y", "BoxParams::depth"),
           number("height", positive(), shown(bx.height), "H of the unscaled box (each copy is H/N high)",
                  "BoxParams::height")}};
}

SurfaceKind square_wave_kind() {
  const SquareWaveParams sq;
  return {"square-wave",
          "Periodic ridges along y (duty F of period P raised by H, vertical walls); --2d: blocks",
          kStructuredOutput, kStructuredConfig,
          {number("period", positive(), shown(sq.period), "P (the tile is P x P)", "SquareWaveParams::period"),
           number("duty", {0, 1, true, true}, shown(sq.duty), "F, raised fraction of the period, in (0, 1)",
                  "SquareWaveParams::duty"),
           number("height", positive(), shown(sq.height), "H", "SquareWaveParams::height"),
           flag("2d", "Raised F P x F P square blocks instead of ridges", "SquareWaveParams::two_d")}};
}

SurfaceKind vgroove_kind() {
  const VGrooveParams vg;
  return {"vgroove", "Periodic V-grooves along y, facet normals (+-sin tm, 0, cos tm); --2d: pyramids",
          kStructuredOutput, kStructuredConfig,
          {number("facet-angle", {0, 90, true, true}, shown(vg.facet_angle_deg), "theta_m in degrees, in (0, 90)",
                  "VGrooveParams::facet_angle_deg"),
           number("period", positive(), shown(vg.period), "P (the tile is one period, P x P)", "VGrooveParams::period"),
           flag("2d", "Square pyramids (a mesh) instead of grooves (a heightfield)", "VGrooveParams::two_d")}};
}

SurfaceKind vcavity_kind() {
  const VCavityParams vc;
  return {"vcavity",
          "The V-cavity model made explicit [Heitz14, Sec. 6.1]: separate V-grooves with normals drawn from D, "
          "each traced on its own by measure g1",
          kStructuredOutput, kStructuredConfig,
          {text("ndf", vc.ndf, "beckmann or ggx", "VCavityParams::ndf"),
           number("alpha", positive(), "", "Isotropic roughness alpha",
                  "VCavityParams::alpha_x and alpha_y (not with alpha-x/alpha-y)"),
           number("alpha-x", positive(), shown(vc.alpha_x), "Roughness along x", "VCavityParams::alpha_x (alone: alpha_y too)"),
           number("alpha-y", positive(), shown(vc.alpha_y), "Roughness along y", "VCavityParams::alpha_y (alone: alpha_x too)"),
           integer("grooves", 1, 1000000, shown(vc.grooves), "Number of grooves K", "VCavityParams::grooves"),
           seed("VCavityParams::seed")}};
}

SurfaceKind parallelepiped_kind() {
  const ParallelepipedParams pp;
  return {"parallelepiped",
          "A box under a linear map [GeomBSDF24, Fig. 3]; shears make walls face downward (n.m < 0)", kStructuredOutput,
          kStructuredConfig,
          {number("width", positive(), shown(pp.width), "W of the box before the map", "ParallelepipedParams::width"),
           number("depth", positive(), shown(pp.depth), "D", "ParallelepipedParams::depth"),
           number("height", positive(), shown(pp.height), "H", "ParallelepipedParams::height"),
           integer("tiles", 1, 256, shown(pp.tiles), "N x N mapped boxes of size 1/N (neighbours share walls)",
                   "ParallelepipedParams::tiles"),
           finite("shear-x", shown(pp.matrix[2]), "x += shear_x z", "ParallelepipedParams::matrix[2] (l13)"),
           finite("shear-y", shown(pp.matrix[5]), "y += shear_y z", "ParallelepipedParams::matrix[5] (l23)"),
           text("matrix", "", "Row-major 3x3 map l11,...,l33 (third row 0,0,k with k > 0); replaces the shears",
                "ParallelepipedParams::matrix (not with shear-x/shear-y)")}};
}

SurfaceKind ellipsoid_kind() {
  const EllipsoidParams el;
  return {"ellipsoid",
          "Upper half of (ax x)^2 + (ay y)^2 + z^2 = 1: its NDF is GGX(ax, ay) [TSBlog24]; finite", kStructuredOutput,
          kStructuredConfig,
          {number("alpha", positive(), "", "Isotropic alpha",
                  "EllipsoidParams::alpha_x and alpha_y (not with alpha-x/alpha-y)"),
           number("alpha-x", positive(), shown(el.alpha_x), "alpha_x (semi-axis 1/alpha_x)",
                  "EllipsoidParams::alpha_x (alone: alpha_y too)"),
           number("alpha-y", positive(), shown(el.alpha_y), "alpha_y (semi-axis 1/alpha_y)",
                  "EllipsoidParams::alpha_y (alone: alpha_x too)"),
           integer("rings", 2, 4096, shown(el.rings), "Latitude steps of the tessellation", "EllipsoidParams::rings"),
           integer("segments", 8, 16384, shown(el.segments), "Longitude steps", "EllipsoidParams::segments")}};
}

SurfaceKind gaussian_ggx_kind() {
  const GaussianGgxParams gg;
  return {"gaussian-ggx",
          "Periodic heightfield whose pooled NDF is GGX(alpha): Gaussian process with slowly varying local "
          "roughness alpha/sqrt(E), E ~ Exp(1)",
          kStructuredOutput, kStructuredConfig,
          {integer("resolution", 4, 32760, shown(gg.resolution), "Grid cells per side", "GaussianGgxParams::resolution"),
           number("size", closed(1e-6, 1e6), shown(gg.size), "Tile side length", "GaussianGgxParams::size"),
           number("correlation-length", positive(), "",
                  "Of the heights (default: 16 cells, at least 16 per tile and 4 cells)",
                  "GaussianGgxParams::correlation_length"),
           number("roughness-correlation-length", positive(), "",
                  "Of the local roughness field (default: 16 correlation lengths)",
                  "GaussianGgxParams::roughness_correlation_length"),
           number("alpha", positive(), "", "Isotropic GGX alpha",
                  "GaussianGgxParams::alpha_x and alpha_y (not with alpha-x/alpha-y)"),
           number("alpha-x", positive(), shown(gg.alpha_x), "GGX alpha along x",
                  "GaussianGgxParams::alpha_x (alone: alpha_y too)"),
           number("alpha-y", positive(), shown(gg.alpha_y), "GGX alpha along y",
                  "GaussianGgxParams::alpha_y (alone: alpha_x too)"),
           number("tail-fraction", {0, 0.5, true, true}, shown(gg.tail_fraction),
                  "Area fraction whose local roughness is capped at alpha/sqrt(-ln(1-q))",
                  "GaussianGgxParams::tail_fraction"),
           seed("GaussianGgxParams::seed")}};
}

SurfaceKind mesh_kind() {
  return {"mesh",
          "Any PLY/OBJ/OFF mesh with a declared macrosurface (validated: manifold, not degenerate, closed but "
          "for its rim, [GeomBSDF24, eq. 1b])",
          kStructuredOutput, kStructuredConfig,
          {text("input", "", "Input mesh (.ply, .obj, .off)", "MeshImportParams::input", true),
           text("normal", "0,0,1", "Macrosurface normal x,y,z in the file's frame (rotated to +z)",
                "MeshImportParams::normal"),
           number("area", positive(), "", "Macrosurface area A (default: from [GeomBSDF24, eq. 1c], or the tile's)",
                  "MeshImportParams::area"),
           flag("periodic", "A periodic tile centered on the origin (else a finite object)",
                "MeshImportParams::periodic"),
           number("tile-x", positive(), "", "Periodic tile size along x", "MeshImportParams::tile_x (with periodic)"),
           number("tile-y", positive(), "", "Periodic tile size along y", "MeshImportParams::tile_y (with periodic)")}};
}

SurfaceKind heightmap_kind() {
  const HeightmapImportParams hm;
  return {"heightmap",
          "A measured heightmap (EXR/TIFF/PNG image or text/CSV grid) as a heightfield; --periodic for a tile "
          "the estimators measure, else a window for info",
          "Output heightfield (.exr)", "Read options from a TOML preset",
          {text("input", "",
                "Heightmap: an image (one channel, or --channel) or a text grid (.txt/.csv/.asc/.xyz/.dat: a "
                "matrix, one row per line, or x,y,z columns)",
                "HeightmapImportParams::input", true),
           text("channel", "", "Image channel holding the heights (default: the only one, else Z, else Y)",
                "HeightmapImportParams::channel"),
           any_number("pixel-size", "",
                      "Grid spacing along x, in --length-unit (required unless the file has x,y columns)",
                      "HeightmapImportParams::pixel_size_x (> 0)"),
           any_number("pixel-size-y", "", "Grid spacing along y (default: --pixel-size)",
                      "HeightmapImportParams::pixel_size_y (> 0)"),
           any_number("height-scale", shown(hm.height_scale),
                      "Height = file value * S (integer images give raw counts)", "HeightmapImportParams::height_scale"),
           text("length-unit", "", "Unit of the pixel sizes and of the surface: m, mm, um, nm, pm",
                "HeightmapImportParams::length_unit"),
           text("height-unit", "", "Unit of the scaled file values (converted to --length-unit; default: the same)",
                "HeightmapImportParams::height_unit"),
           flag("periodic", "The map is one period of a periodic surface: a tile every estimator measures",
                "HeightmapImportParams::periodic"),
           flag("window", "A non-periodic patch (the default): the estimators measure its interior, inside a guard band",
                "HeightmapImportParams::periodic = false"),
           any_number("guard", "",
                      "Window guard band in correlation lengths l (Sal / sqrt(ln 5)) of the patch (default " +
                          [] {
                            std::ostringstream os;
                            os << std::fixed;
                            os.precision(3);
                            os << kDefaultGuardCorrelationLengths;
                            return os.str();
                          }() + ", from the guard-band bias table)",
                      "HeightmapImportParams::guard_correlation_lengths (>= 0)"),
           any_number("guard-width", "", "Window guard band in --length-unit (instead of --guard)",
                      "HeightmapImportParams::guard_width (>= 0)"),
           text("detrend", "mean", "Least-squares form removed: none, mean, plane (tilt) or poly2 (quadratic form)",
                "HeightmapImportParams::detrend"),
           text("crop", "", "x0,y0,w,h: keep this pixel rectangle (before everything else)",
                "HeightmapImportParams::crop, crop_x0, crop_y0, crop_w, crop_h"),
           any_number("nodata", "", "File value that marks a missing pixel (NaN always does)",
                      "HeightmapImportParams::nodata, has_nodata"),
           any_number("max-missing", shown(hm.max_missing_fraction),
                      "Largest fraction of missing pixels filled (harmonic inpainting); more is refused",
                      "HeightmapImportParams::max_missing_fraction (in [0, 1))")}};
}

// Every kind, in the order of `microsim generate --help`.
std::vector<SurfaceKind> make_kinds() {
  return {gaussian_kind(),  flat_kind(),    box_kind(),       tiled_boxes_kind(),    square_wave_kind(),
          vgroove_kind(),   vcavity_kind(), parallelepiped_kind(), ellipsoid_kind(), gaussian_ggx_kind(),
          mesh_kind(),      heightmap_kind()};
}

// Throws a ParameterError naming the option's parameter for a value the option refuses.
void check_value(const SurfaceOption& o, const std::string& value) {
  const std::string name = surface_option_placeholder(o.name);
  try {
    switch (o.check) {
      case Check::Range: parse_number_in(value, o.range, ""); break;
      case Check::Finite: parse_number_in(value, {-1e300, 1e300}, ""); break;
      case Check::Integer: parse_integer_in(value, o.lo, o.hi, ""); break;
      case Check::Seed: parse_seed(value, ""); break;
      case Check::None: break;
    }
  } catch (const UsageError& e) {
    throw ParameterError(name + ": " + message_template(e));
  }
  if (o.type == Type::Flag && value != "true" && value != "false")
    throw ParameterError(name + ": expected true or false (got '" + literal_text(value) + "')");
  if (o.type == Type::Number && o.check == Check::None) {
    char* end = nullptr;
    std::strtold(value.c_str(), &end);
    if (value.empty() || end != value.c_str() + value.size())
      throw ParameterError("Could not convert: " + name + " = " + literal_text(value));
  }
}

}  // namespace

std::string surface_option_placeholder(const std::string& option) {
  std::string name = option;
  std::replace(name.begin(), name.end(), '-', '_');
  return placeholder(name);
}

const SurfaceOption* SurfaceKind::option(const std::string& name) const {
  for (const auto& o : options)
    if (o.name == name) return &o;
  return nullptr;
}

std::string SurfaceKind::option_names() const {
  std::string s;
  for (const auto& o : options) s += (s.empty() ? "" : ", ") + o.name;
  return s;
}

const std::vector<SurfaceKind>& surface_kinds() {
  static const std::vector<SurfaceKind> kinds = make_kinds();
  return kinds;
}

std::string surface_kind_names() {
  std::string s;
  for (const auto& k : surface_kinds()) s += (s.empty() ? "" : ", ") + k.name;
  return s;
}

const SurfaceKind& surface_kind(const std::string& name) {
  for (const auto& k : surface_kinds())
    if (k.name == name) return k;
  throw UsageError("unknown surface kind '" + name + "' (known: " + surface_kind_names() + ")");
}

void set_surface_option(SurfaceRequest& r, const std::string& name, const std::string& value) {
  const SurfaceKind& kind = surface_kind(r.kind);
  const SurfaceOption* o = kind.option(name);
  if (!o)
    throw UsageError("unknown option '" + name + "' for '" + kind.name + "' (known: " + kind.option_names() + ")");
  check_value(*o, value);
  r.options[name] = value;
}

void read_surface_preset(SurfaceRequest& r, const std::string& path) {
  for (const PresetItem& item : read_preset_file(path)) {
    try {
      set_surface_option(r, item.key, item.value);
    } catch (const UsageError& e) {
      throw ParameterError(literal_text(preset_line_where(path, item)) + message_template(e));
    }
  }
}

}  // namespace microsim
