#include "microsim/surface/mesh_check.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/surface/mesh_header.hpp"

#include "openmesh_headers.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <mutex>
#include <numeric>
#include <sstream>

#include "microsim/io/output.hpp"
#include "microsim/surface/generators.hpp"

namespace microsim {

namespace {

// While alive, OpenMesh's omerr writes into a string and omlog/omout are silenced; the streams'
// buffers are restored on destruction (also when read_mesh throws). The buffers are swapped
// rather than multiplex targets connected: OpenMesh's disconnect() never deletes the target it
// allocated in connect(), so one connect per load leaked. The mutex makes concurrent loads safe.
class OpenMeshStreamCapture {
 public:
  OpenMeshStreamCapture()
      : lock_(mutex()),
        err_(omerr().rdbuf(captured_.rdbuf())),
        log_(omlog().rdbuf(discarded_.rdbuf())),
        out_(omout().rdbuf(discarded_.rdbuf())) {}
  ~OpenMeshStreamCapture() {
    omerr().flush();
    omerr().rdbuf(err_);
    omlog().rdbuf(log_);
    omout().rdbuf(out_);
  }
  OpenMeshStreamCapture(const OpenMeshStreamCapture&) = delete;
  OpenMeshStreamCapture& operator=(const OpenMeshStreamCapture&) = delete;
  std::string text() {
    omerr().flush();
    return captured_.str();
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::ostringstream captured_, discarded_;
  std::streambuf *err_, *log_, *out_;
};

// OpenMesh 9.0's PLY header parser files each "property" under the last declared element and
// crashes (SEGV) when none was declared yet, and loops forever when the file ends before
// end_header or an element count is not a number. The header is checked first, token by token
// as OpenMesh reads it (comments skipped).
void check_ply_header(const std::string& path) {
  const auto malformed = [&](const std::string& why) {
    throw UsageError(path + ": malformed PLY header (" + why + ")");
  };
  std::ifstream in(path, std::ios::binary);
  bool element = false;
  std::string word, name, count;
  for (int tokens = 0; tokens < 100000 && in >> word; ++tokens) {
    if (word == "end_header") return;
    if (word == "comment" || word == "obj_info") {
      std::getline(in, word);
    } else if (word == "element") {
      if (!(in >> name >> count) || count.empty() || count.size() > 10 ||
          count.find_first_not_of("0123456789") != std::string::npos)
        malformed("element " + name + " needs a count");
      element = true;
    } else if (word == "property" && !element) {
      malformed("a property before any element");
    }
  }
  malformed("no end_header");
}

std::string point_str(const Eigen::Vector3f& p) {
  std::ostringstream os;
  os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return os.str();
}

struct DirectedEdge {
  std::uint32_t lo, hi, tri;
  bool forward;  // the triangle runs lo -> hi
};

// Edges grouped by their two vertices (sorted). Returns the sorted list.
std::vector<DirectedEdge> sorted_edges(const std::vector<std::array<std::uint32_t, 3>>& tris) {
  std::vector<DirectedEdge> e;
  e.reserve(3 * tris.size());
  for (std::uint32_t k = 0; k < tris.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      std::uint32_t a = tris[k][c], b = tris[k][(c + 1) % 3];
      e.push_back({std::min(a, b), std::max(a, b), k, a < b});
    }
  std::sort(e.begin(), e.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.tri < y.tri;
  });
  return e;
}

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

int corner_of(const std::array<std::uint32_t, 3>& t, std::uint32_t v) {
  return t[0] == v ? 0 : t[1] == v ? 1 : 2;
}

// Every triangle has three distinct vertices and an area above rounding (relative to `scale`).
void check_triangles_not_degenerate(const Microsurface& s, const std::string& name, double scale) {
  const auto& V = s.vertices();
  const auto& T = s.triangles();
  for (std::size_t k = 0; k < T.size(); ++k) {
    const auto& t = T[k];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw UsageError(name + ": degenerate triangle " + std::to_string(k) + " (repeated vertex)");
    if (!(s.facet(k).area() > 1e-13 * scale * scale))
      throw UsageError(name + ": degenerate triangle " + std::to_string(k) + " (zero area) at " +
                       point_str(V[t[0]]));
  }
}

// An edge where an open mesh may end: on a periodic tile's border (continued by the next
// tile), else on the base plane z = 0.
bool edge_on_rim(const Macrosurface& macro, const Eigen::Vector3f& p, const Eigen::Vector3f& q, double tol) {
  const double hx = 0.5 * macro.size_x, hy = 0.5 * macro.size_y;
  if (!macro.periodic) return std::abs(p.z()) <= tol && std::abs(q.z()) <= tol;
  for (double side : {hx, -hx})
    if (std::abs(p.x() - side) <= tol && std::abs(q.x() - side) <= tol) return true;
  for (double side : {hy, -hy})
    if (std::abs(p.y() - side) <= tol && std::abs(q.y() - side) <= tol) return true;
  return false;
}

// Edges: at most two triangles, in opposite directions; boundary edges (counted in rep) on the
// rim. Returns the triangle corners joined across shared edges: the fans around each vertex.
UnionFind check_edges(const Microsurface& s, const std::string& name, double tol, MeshCheckReport& rep) {
  const auto& V = s.vertices();
  const auto& T = s.triangles();
  const Macrosurface& macro = s.macro();
  const bool rim_rule = !is_vcavity(s);
  const double hx = 0.5 * macro.size_x, hy = 0.5 * macro.size_y;
  std::vector<DirectedEdge> E = sorted_edges(T);
  UnionFind fans(3 * T.size());
  for (std::size_t i = 0; i < E.size();) {
    std::size_t j = i;
    while (j < E.size() && E[j].lo == E[i].lo && E[j].hi == E[i].hi) ++j;
    const std::size_t count = j - i;
    if (count > 2)
      throw UsageError(name + ": non-manifold mesh: the edge " + point_str(V[E[i].lo]) + "-" +
                       point_str(V[E[i].hi]) + " is shared by " + std::to_string(count) + " triangles");
    if (count == 2) {
      if (E[i].forward == E[i + 1].forward)
        throw UsageError(name + ": inconsistently oriented mesh: triangles " +
                         std::to_string(E[i].tri) + " and " + std::to_string(E[i + 1].tri) +
                         " run their shared edge in the same direction");
      const auto &t1 = T[E[i].tri], &t2 = T[E[i + 1].tri];
      for (std::uint32_t v : {E[i].lo, E[i].hi})
        fans.unite(3 * E[i].tri + corner_of(t1, v), 3 * E[i + 1].tri + corner_of(t2, v));
    } else {
      ++rep.boundary_edges;
      if (rim_rule && !edge_on_rim(macro, V[E[i].lo], V[E[i].hi], tol))
        throw UsageError(
            name + ": open mesh: the boundary edge " + point_str(V[E[i].lo]) + "-" +
            point_str(V[E[i].hi]) + " is not on the macrosurface's rim (" +
            (macro.periodic ? std::string("a tile border x = +-") + std::to_string(hx) +
                                  " or y = +-" + std::to_string(hy)
                            : std::string("the base plane z = 0")) +
            "); the surface must be closed elsewhere");
    }
    i = j;
  }
  return fans;
}

// One fan per vertex (no two cones or sheets meeting at a single vertex).
void check_one_fan_per_vertex(const Microsurface& s, const std::string& name, UnionFind& fans) {
  const auto& V = s.vertices();
  const auto& T = s.triangles();
  std::vector<std::uint32_t> root_of(V.size(), UINT32_MAX);
  for (std::uint32_t k = 0; k < T.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      std::uint32_t v = T[k][c], r = fans.find(3 * k + c);
      if (root_of[v] == UINT32_MAX) root_of[v] = r;
      else if (root_of[v] != r)
        throw UsageError(name + ": non-manifold mesh: separate sheets meet at the single vertex " +
                         point_str(V[v]));
    }
}

// A periodic tile's vertices lie inside the tile (within tol).
void check_inside_tile(const Microsurface& s, const std::string& name, double tol) {
  const Macrosurface& macro = s.macro();
  if (!macro.periodic) return;
  const double hx = 0.5 * macro.size_x, hy = 0.5 * macro.size_y;
  for (const auto& v : s.vertices())
    if (std::abs(v.x()) > hx + tol || std::abs(v.y()) > hy + tol)
      throw UsageError(name + ": vertex " + point_str(v) + " lies outside the periodic tile " +
                       std::to_string(macro.size_x) + " x " + std::to_string(macro.size_y));
}

// [GeomBSDF24, eq. 1b]: sum_f A_f m_f = A n; the relative error goes into rep.
void check_area_normal_sum(const Microsurface& s, const std::string& name, MeshCheckReport& rep) {
  const Macrosurface& macro = s.macro();
  if (!(macro.area > 0)) throw UsageError(name + ": the macrosurface area must be > 0");
  FacetSums f = facet_sums(s);
  const Vec3 ratio = f.sum_area_normal / macro.area;
  rep.eq_1b_relative_error = (ratio - macro.normal).norm();
  if (!(rep.eq_1b_relative_error <= 1e-5)) {
    std::ostringstream os;
    os << name << ": [GeomBSDF24, eq. 1b] fails: sum_f A_f m_f / A = (" << ratio.x() << ", " << ratio.y()
       << ", " << ratio.z() << "), not the macrosurface normal; the declared area/normal is wrong "
       << "or the mesh is inside-out";
    throw UsageError(os.str());
  }
}

}  // namespace

MeshCheckReport check_mesh(const Microsurface& s, const std::string& name, bool check_eq_1b) {
  MeshCheckReport rep;
  if (s.kind() != Microsurface::Kind::Mesh) return rep;
  const auto& V = s.vertices();
  const auto& T = s.triangles();
  const Macrosurface& macro = s.macro();
  rep.triangles = T.size();
  rep.vertices = V.size();
  if (T.empty()) throw UsageError(name + ": the mesh has no triangles");
  for (const auto& v : V)
    if (!v.allFinite()) throw UsageError(name + ": non-finite vertex coordinate");
  const Eigen::AlignedBox3d box = s.bounds();
  const double scale = std::max({box.sizes().norm(), macro.size_x, macro.size_y, 1e-30});
  const double tol = 1e-6 * scale;
  check_triangles_not_degenerate(s, name, scale);
  UnionFind fans = check_edges(s, name, tol, rep);
  check_one_fan_per_vertex(s, name, fans);
  check_inside_tile(s, name, tol);
  if (check_eq_1b) check_area_normal_sum(s, name, rep);
  return rep;
}

void read_mesh_file(const std::string& path, std::vector<Eigen::Vector3f>& verts,
                    std::vector<std::array<std::uint32_t, 3>>& tris) {
  using OMesh = OpenMesh::TriMesh_ArrayKernelT<>;
  if (!std::ifstream(path).good()) throw UsageError("mesh file " + path + " does not exist or cannot be read");
  check_mesh_header(path);  // declared counts against the file's length and memory, before reading

  // OpenMesh reports problems on omerr and repairs non-manifold faces by duplicating their
  // vertices; capture its messages and read the repair flags instead.
  if (extension_of(path) == "ply") check_ply_header(path);
  OMesh om;
  om.request_face_status();
  std::string msg;
  bool ok = false;
  {
    OpenMeshStreamCapture capture;
    OpenMesh::IO::Options opt;
    ok = OpenMesh::IO::read_mesh(om, path, opt);
    msg = capture.text();
  }
  if (!ok || om.n_faces() == 0)
    throw UsageError(path + " is not a readable mesh (PLY/OBJ/OFF with at least one face)");
  if (msg.find("equal vertices") != std::string::npos)
    throw UsageError(path + ": degenerate face (a face repeats a vertex)");
  if (msg.find("invalid vertex index") != std::string::npos)
    throw UsageError(path + ": a face refers to a vertex that does not exist");
  for (auto f : om.faces())
    if (om.status(f).fixed_nonmanifold())
      throw UsageError(path + ": non-manifold mesh (an edge shared by more than two faces, "
                       "faces with opposite orientations, or sheets meeting at one vertex)");
  verts.clear();
  tris.clear();
  verts.reserve(om.n_vertices());
  for (auto v : om.vertices()) {
    auto p = om.point(v);
    verts.emplace_back(p[0], p[1], p[2]);
  }
  for (auto f : om.faces()) {
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (auto v : om.fv_range(f)) {
      if (k == 3) throw UsageError(path + ": face with more than 3 vertices after triangulation");
      t[k++] = static_cast<std::uint32_t>(v.idx());
    }
    tris.push_back(t);
  }
}

Microsurface import_mesh(const MeshImportParams& p) {
  require_regular_input(p.input, "{input}");
  if (!p.normal.allFinite() || !(p.normal.norm() > 0))
    throw ParameterError("{normal} must be a nonzero vector x,y,z");
  if (p.area < 0 || !std::isfinite(p.area)) throw ParameterError("{area} must be > 0");
  if (p.periodic && !(p.tile_x > 0 && p.tile_y > 0 && std::isfinite(p.tile_x) && std::isfinite(p.tile_y)))
    throw ParameterError("{periodic} needs {tile_x} and {tile_y} > 0");
  std::vector<Eigen::Vector3f> verts;
  std::vector<std::array<std::uint32_t, 3>> tris;
  read_mesh_file(p.input, verts, tris);
  // Rotate the declared normal onto +z.
  const Eigen::Matrix3d R =
      Eigen::Quaterniond::FromTwoVectors(p.normal.normalized(), Vec3::UnitZ()).toRotationMatrix();
  for (auto& v : verts) v = (R * v.cast<double>()).cast<float>();
  Macrosurface m;
  m.periodic = p.periodic;
  if (p.periodic) {
    m.size_x = p.tile_x;
    m.size_y = p.tile_y;
    m.area = p.area > 0 ? p.area : p.tile_x * p.tile_y;
  } else {
    // The rim: vertices of boundary edges. Shift it onto z = 0, centered in x and y.
    std::vector<DirectedEdge> E = sorted_edges(tris);
    Eigen::AlignedBox3d rim;
    double zmin = 1e300;
    for (std::size_t i = 0; i < E.size();) {
      std::size_t j = i;
      while (j < E.size() && E[j].lo == E[i].lo && E[j].hi == E[i].hi) ++j;
      if (j - i == 1)
        for (auto v : {E[i].lo, E[i].hi}) {
          rim.extend(verts[v].cast<double>());
          zmin = std::min(zmin, static_cast<double>(verts[v].z()));
        }
      i = j;
    }
    if (rim.isEmpty())
      throw UsageError(p.input + ": closed mesh: with no rim its signed projected area is zero "
                       "[GeomBSDF24, eq. 1a], so it cannot stand on a macrosurface; remove its base");
    const Vec3 shift(-rim.center().x(), -rim.center().y(), -zmin);
    for (auto& v : verts) v = (v.cast<double>() + shift).cast<float>();
    m.size_x = rim.sizes().x();
    m.size_y = rim.sizes().y();
    m.area = p.area;
  }
  if (m.area == 0) m.area = 1;  // placeholder until eq. 1c below
  Microsurface s = Microsurface::mesh(std::move(verts), std::move(tris), m);
  check_mesh(s, p.input, false);  // topology first: its errors are the more specific ones
  if (!p.periodic && p.area == 0) {
    // [GeomBSDF24, eq. 1c]: A = sum_f A_f (n.m_f); eq. 1b then checks the tangential part.
    const double a = facet_sums(s).sum_area_cos;
    if (!(a > 0))
      throw ParameterError(literal_text(p.input) + ": the signed projected area along {normal} is not positive "
                           "(inside-out mesh or wrong {normal})");
    m.area = a;
    s = Microsurface::mesh(s.vertices(), s.triangles(), m);
  }
  s.description = {{"kind", "mesh"},
                   {"input", p.input},
                   {"declared_normal", {p.normal.x(), p.normal.y(), p.normal.z()}},
                   {"periodic", p.periodic},
                   {"area", m.area}};
  if (p.periodic) {
    s.description["tile_x"] = p.tile_x;
    s.description["tile_y"] = p.tile_y;
  }
  check_mesh(s, p.input);
  return s;
}

}  // namespace microsim
