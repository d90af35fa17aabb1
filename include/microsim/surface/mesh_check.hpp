// Meshes as microsurfaces: validation and import with a declared macrosurface.
//
// A triangle mesh is a valid microsurface when (each refusal is one UsageError line):
//  - every triangle has three distinct vertices and a nonzero area (not degenerate);
//  - it is an oriented 2-manifold: an edge belongs to at most two triangles, which use it in
//    opposite directions, and the triangles around a vertex form a single fan;
//  - it is closed wherever it must be: a boundary edge may only lie on the macrosurface's rim,
//    i.e. on the base plane z = 0 for a finite object, on a tile border for a periodic tile;
//  - [GeomBSDF24, eq. 1b] holds: sum_f A_f m_f = A n (the declared area and normal agree with the
//    signed projected area; this also catches an inside-out mesh).
// The vcavity ensemble (separate strips standing for periods of infinite grooves) is exempt
// from the rim rule only.
#pragma once
#include <string>

#include "microsim/surface/microsurface.hpp"

namespace microsim {

struct MeshCheckReport {
  std::size_t triangles = 0, vertices = 0;
  std::size_t boundary_edges = 0;
  double eq_1b_relative_error = 0;  // |sum A_f m_f / A - n|
};

// Throws UsageError("<name>: ...") on the first violation. check_eq_1b = false checks the
// topology only (used before the macro area is known).
MeshCheckReport check_mesh(const Microsurface& s, const std::string& name, bool check_eq_1b = true);

// Reads the triangles of a PLY/OBJ/OFF file with OpenMesh (polygons are triangulated).
// UsageError for an unreadable file, a face with repeated or invalid vertices, and for
// non-manifold or inconsistently oriented input (OpenMesh refuses such faces; they are not
// silently repaired).
void read_mesh_file(const std::string& path, std::vector<Eigen::Vector3f>& vertices,
                    std::vector<std::array<std::uint32_t, 3>>& triangles);

// generate mesh: any PLY/OBJ/OFF file with a declared macrosurface.
struct MeshImportParams {
  std::string input;
  Vec3 normal{0, 0, 1};  // macrosurface normal n in the file's frame; the mesh is rotated n -> +z
  double area = 0;       // A; 0 = from [GeomBSDF24, eq. 1c], A = sum_f A_f (n.m_f)
  bool periodic = false;
  double tile_x = 0, tile_y = 0;  // periodic tile size (centered on the origin after rotation)
};
// Finite objects are shifted so that their rim (boundary) lies on z = 0, centered in x, y on
// the rim's bounding box; periodic tiles are used as they are (after rotation).
Microsurface import_mesh(const MeshImportParams& p);

}  // namespace microsim
