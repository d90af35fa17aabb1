#include "microsim/surface/surface_io.hpp"
#include "microsim/surface/guard_band.hpp"

#include "openmesh_headers.hpp"

#include <fstream>
#include <sys/stat.h>

#include "microsim/io/checks.hpp"
#include "microsim/io/exr_table.hpp"
#include "microsim/io/json_input.hpp"
#include "microsim/io/output.hpp"
#include "microsim/surface/heightmap_import.hpp"
#include "microsim/surface/mesh_check.hpp"
#include "microsim/surface/metrology.hpp"

namespace microsim {

namespace {
using OMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// OpenMesh logs to stdout/stderr on its own; microsim reports errors itself, in one line.
void silence_openmesh() {
  omlog().disable();
  omout().disable();
  omerr().disable();
}

bool file_exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

Json macro_to_json(const Macrosurface& m) {
  return {{"normal", {m.normal.x(), m.normal.y(), m.normal.z()}},
          {"area", m.area},
          {"periodic", m.periodic},
          {"size_x", m.size_x},
          {"size_y", m.size_y}};
}

// Every field checked (io/checks.hpp): a file naming `file` and the field on a bad value.
Macrosurface macro_from_json(const Json& j, const std::string& file) {
  const auto number = [&](const Json& x, const std::string& key, const Range& r) {
    if (!x.is_number()) throw UsageError(file + ": macrosurface field '" + key + "' must be a number");
    const double v = x.get<double>();
    require_in_range(v, r, literal_text(file) + ": macrosurface field '" + key + "'");
    return v;
  };
  if (!j.is_object()) throw UsageError(file + ": the macrosurface must be a JSON object");
  for (const char* key : {"normal", "area", "periodic", "size_x", "size_y"})
    if (!j.contains(key)) throw UsageError(file + ": macrosurface field '" + key + "' is missing");
  Macrosurface m;
  const Json& n = j.at("normal");
  if (!n.is_array() || n.size() != 3) throw UsageError(file + ": macrosurface field 'normal' must be [x, y, z]");
  m.normal = Vec3(number(n[0], "normal", closed(-1e6, 1e6)), number(n[1], "normal", closed(-1e6, 1e6)),
                  number(n[2], "normal", closed(-1e6, 1e6)));
  if (!(m.normal.norm() > 0)) throw UsageError(file + ": macrosurface field 'normal' must be nonzero");
  m.area = number(j.at("area"), "area", open_closed(0, 1e12));
  if (!j.at("periodic").is_boolean()) throw UsageError(file + ": macrosurface field 'periodic' must be true or false");
  m.periodic = j.at("periodic").get<bool>();
  m.size_x = number(j.at("size_x"), "size_x", closed(0, 1e6));
  m.size_y = number(j.at("size_y"), "size_y", closed(0, 1e6));
  return m;
}

// The nominal NDF travels in the description ("nominal_ndf", "alpha_x", "alpha_y"); each field is
// checked, naming the file and the key.
void restore_nominal(Microsurface& s, const std::string& file) {
  const auto& d = s.description;
  if (!d.is_object()) return;
  for (const char* key : {"alpha_x", "alpha_y"}) {
    if (!d.contains(key)) continue;
    if (!d[key].is_number())
      throw UsageError(file + ": description field '" + key + "' must be a number in (0, 1000]");
    require_in_range(d[key].get<double>(), open_closed(0, 1000), literal_text(file) + ": description field '" + key + "'");
  }
  if (!d.contains("nominal_ndf") || !d.contains("alpha_x") || !d.contains("alpha_y")) return;
  if (!d["nominal_ndf"].is_string() ||
      (d["nominal_ndf"].get<std::string>() != "beckmann" && d["nominal_ndf"].get<std::string>() != "ggx"))
    throw UsageError(file + ": description field 'nominal_ndf' must be \"beckmann\" or \"ggx\"");
  std::string kind = d["nominal_ndf"].get<std::string>();
  double ax = d["alpha_x"].get<double>(), ay = d["alpha_y"].get<double>();
  if (kind == "beckmann") s.nominal = models::Ndf::beckmann(ax, ay);
  if (kind == "ggx") s.nominal = models::Ndf::ggx(ax, ay);
}

void save_heightfield_exr(const Microsurface& s, const std::string& path) {
  ExrTable t;
  t.width = s.nx();
  t.height = s.ny();
  t.channel_names = {"Z"};  // written from the heights themselves (no copy of the tile)
  t.attributes = s.description;
  t.attributes["microsim_surface"] = "heightfield";
  t.attributes["microsim_description"] = s.description.dump();
  // A measured patch imported as a non-periodic window keeps that in its header: the
  // estimators refuse it on loading (load_surface), metrology reads it.
  const bool window = s.description.is_object() && s.description.value("boundary", std::string()) == "window";
  Json macro = macro_to_json(s.macro());
  if (window) macro["periodic"] = false;
  t.attributes["microsim_macrosurface"] = macro.dump();
  t.attributes["parameterization"] =
      "Z(i,j) = height of grid vertex x = -size_x/2 + i size_x/width, y = -size_y/2 + j "
      "size_y/height (row j = y index); " +
      std::string(window ? "non-periodic measured window" : "periodic tile") +
      "; cell split along its (i+1,j)-(i,j+1) diagonal";
  write_exr_pixels(path, t, {s.heights().data()});
}

// Largest heightfield side: Embree's grid limit, as for generate.
constexpr int kMaxGrid = 32760;
// Bytes per grid cell once loaded and traced, at the peak of a measurement: float height (4),
// Embree grid vertex (12) and its compact BVH (10-14 measured), the facet table's two bin
// indices (4) and the facet sampler (1); 40 bytes, i.e. 20 per facet.
double heightfield_bytes(double w, double h) { return (w + 3) * (h + 3) * 40.0; }

Microsurface load_heightfield_exr(const std::string& path, bool allow_window) {
  Macrosurface m;
  // The header is checked before any pixel is allocated: size, macrosurface, description.
  ExrTable t = read_exr(path, [&](const ExrTable& h) {
    if (!h.attributes.contains("microsim_surface") || !h.attributes.contains("microsim_macrosurface") ||
        !h.attributes["microsim_macrosurface"].is_string())
      throw UsageError(path + " is an EXR file but not a microsim heightfield (no microsim header)");
    if (std::find(h.channel_names.begin(), h.channel_names.end(), "Z") == h.channel_names.end())
      throw UsageError(path + " has no Z channel");
    if (h.width < 1 || h.width > kMaxGrid || h.height < 1 || h.height > kMaxGrid)
      throw UsageError(path + ": heightfield size " + std::to_string(h.width) + " x " +
                       std::to_string(h.height) + " is outside [1, " + std::to_string(kMaxGrid) + "] per side");
    Json mj;
    try {
      mj = parse_json_input(h.attributes["microsim_macrosurface"].get<std::string>(), path + " header");
    } catch (const Json::exception& e) {
      throw UsageError(path + " has a corrupt microsim header (" + std::string(e.what()) + ")");
    }
    m = macro_from_json(mj, path);
    // A window read for its metrology (info) peaks at its zero-padded ACF, more than tracing.
    const bool window_metrology = allow_window && !m.periodic;
    require_memory(window_metrology ? std::max(heightfield_bytes(h.width, h.height),
                                               metrology_bytes(h.width, h.height, /*periodic=*/false))
                                    : heightfield_bytes(h.width, h.height),
                   literal_text(path) + " (" + std::to_string(h.width) + " x " + std::to_string(h.height) +
                       (window_metrology ? " heightfield, a non-periodic window" : " heightfield") + ")");
    require_in_range(m.size_x, closed(1e-6, 1e6), literal_text(path) + ": macrosurface field 'size_x'");
    require_in_range(m.size_y, closed(1e-6, 1e6), literal_text(path) + ": macrosurface field 'size_y'");
    // A window is loaded as a grid like a tile; for the estimators it is then made a window
    // measured inside its guard band (surface/guard_band.hpp); metrology reads the grid.
  });
  auto it = std::find(t.channel_names.begin(), t.channel_names.end(), "Z");
  for (float h : t.channels[it - t.channel_names.begin()])
    if (!std::isfinite(h) || std::abs(h) > 1e12) throw UsageError(path + " contains non-finite or absurd heights");
  try {
    Microsurface s = Microsurface::heightfield(t.width, t.height, m.size_x, m.size_y,
                                               std::move(t.channels[it - t.channel_names.begin()]));
    if (t.attributes.contains("microsim_description") && t.attributes["microsim_description"].is_string())
      s.description = parse_json_input(t.attributes["microsim_description"].get<std::string>(), path + " header");
    restore_nominal(s, path);
    if (!m.periodic && !allow_window) apply_recorded_guard_band(s);
    return s;
  } catch (const Json::exception& e) {
    throw UsageError(path + " has a corrupt microsim header (" + std::string(e.what()) + ")");
  }
}

void save_mesh(const Microsurface& s, const std::string& path) {
  silence_openmesh();
  Microsurface m = s.kind() == Microsurface::Kind::Mesh ? s : heightfield_to_mesh(s);
  OMesh om;
  std::vector<OMesh::VertexHandle> vh;
  vh.reserve(m.vertices().size());
  for (const auto& v : m.vertices()) vh.push_back(om.add_vertex(OMesh::Point(v.x(), v.y(), v.z())));
  for (const auto& t : m.triangles()) {
    auto f = om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
    if (!f.is_valid()) throw RuntimeFailure("cannot export: the mesh is not manifold");
  }
  write_stream_atomically(path, [&](std::ofstream& out) {
    OpenMesh::IO::Options opt;
    if (extension_of(path) == "ply") opt += OpenMesh::IO::Options::Binary;
    // Through the checked stream (OpenMesh's own file writer does not report a failed close);
    // the format is chosen by the extension. 9 significant digits: text formats (OBJ, OFF) keep
    // every float vertex exactly.
    if (!OpenMesh::IO::write_mesh(om, out, "." + extension_of(path), opt, 9))
      throw RuntimeFailure("cannot write " + path);
  });
  Json side = {{"microsim_surface", "mesh"},
                         {"macrosurface", macro_to_json(m.macro())},
                         {"description", s.description}};
  write_json(path + ".json", side);
}

Microsurface load_mesh(const std::string& path) {
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  read_mesh_file(path, verts, tris);  // refuses unreadable, non-manifold, repeated-vertex faces
  Macrosurface macro;
  Json description = {{"kind", "mesh"}, {"file", path}};
  std::string side = path + ".json";
  const bool has_sidecar = file_exists(side);
  if (has_sidecar) {
    try {
      std::ifstream f(side);
      auto j = parse_json_input(f, side);
      if (!j.is_object() || !j.contains("macrosurface"))
        throw UsageError(side + ": not a microsim sidecar (no 'macrosurface' field)");
      macro = macro_from_json(j.at("macrosurface"), side);
      if (j.contains("description")) description = j["description"];
    } catch (const Json::exception& e) {
      throw UsageError(side + " is not a valid microsim sidecar (" + std::string(e.what()) + ")");
    }
  } else {
    // No sidecar: a finite object standing on z = 0, window its xy bounds, A from [GeomBSDF24, eq. 1c]
    // (sum_f A_f (n.m_f)); check_mesh then verifies the rim and eq. 1b.
    Eigen::AlignedBox3f box;
    for (const auto& v : verts) box.extend(v);
    macro.periodic = false;
    macro.size_x = 2 * std::max(std::abs(box.min().x()), std::abs(box.max().x()));
    macro.size_y = 2 * std::max(std::abs(box.min().y()), std::abs(box.max().y()));
    macro.area = 1.0;
  }
  Microsurface s = Microsurface::mesh(std::move(verts), std::move(tris), macro);
  s.description = description;
  if (!has_sidecar) {
    macro.area = facet_sums(s).sum_area_cos;
    if (!(macro.area > 0))
      throw ParameterError(literal_text(path) + ": no macrosurface sidecar (" + literal_text(side) + ") and no positive signed "
                           "projected area along +z; declare one with microsim generate mesh {input}");
    s = Microsurface::mesh(s.vertices(), s.triangles(), macro);
    s.description = description;
  }
  try {
    check_mesh(s, path);
  } catch (const UsageError& e) {
    if (has_sidecar) throw;
    throw ParameterError(message_template(e) + " (no sidecar " + literal_text(side) +
                         ": declare the macrosurface with microsim generate mesh {input})");
  }
  restore_nominal(s, side);
  return s;
}
}  // namespace

Microsurface heightfield_to_mesh(const Microsurface& s) {
  if (s.kind() == Microsurface::Kind::Mesh) return s;
  const int nx = s.nx(), ny = s.ny();
  // (nx+1) x (ny+1) vertices: the last row/column duplicates the first one shifted by the
  // tile size, so the mesh's border lies exactly on the tile's border.
  std::vector<Eigen::Vector3f> verts;
  verts.reserve(static_cast<std::size_t>(nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) verts.push_back(s.grid_point(i, j).cast<float>());
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  std::vector<std::array<std::uint32_t, 3>> tris;
  tris.reserve(2 * static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      tris.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
      tris.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  Microsurface m = Microsurface::mesh(std::move(verts), std::move(tris), s.macro());
  m.description = s.description;
  m.nominal = s.nominal;
  return m;
}

void save_surface(const Microsurface& s, const std::string& path) {
  std::string ext = extension_of(path);
  if (ext == "exr") {
    if (s.kind() != Microsurface::Kind::Heightfield)
      throw ParameterError("{output} " + literal_text(path) + ": only heightfields can be saved as EXR; use .ply/.obj");
    save_heightfield_exr(s, path);
  } else if (ext == "ply" || ext == "obj" || ext == "off") {
    save_mesh(s, path);
  } else {
    throw ParameterError("{output} " + literal_text(path) + ": unknown surface format (use .exr, .ply, .obj or .off)");
  }
}

Microsurface load_surface(const std::string& path) { return load_surface_or_window(path); }

void require_readable_surface(const Microsurface& s, const std::string& name) {
  macro_from_json(macro_to_json(s.macro()), name);  // the reader's own rules
  if (s.kind() == Microsurface::Kind::Mesh) check_mesh(s, name);
}

Microsurface load_surface_or_window(const std::string& path, bool allow_window) {
  // A surface written earlier by this command (demo) and not committed yet is read from its
  // temporary.
  const std::string pending = OutputTransaction::pending(path);
  const std::string file = pending.empty() ? path : pending;
  require_regular_input(file, "surface file");
  if (!file_exists(file)) throw UsageError("surface file " + path + " does not exist");
  std::string ext = extension_of(path);
  if (ext == "exr") return load_heightfield_exr(file, allow_window);
  if (ext == "ply" || ext == "obj" || ext == "off") return load_mesh(file);
  throw UsageError("surface file " + path + ": unknown format (expected .exr, .ply, .obj or .off)");
}

}  // namespace microsim
