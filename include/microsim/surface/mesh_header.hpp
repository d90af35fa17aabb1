// Checks of a mesh file's declared sizes before any of it is read: PLY "element vertex N" /
// "element face N" and the OFF counts line must be non-negative integers that the file's length
// can hold and that fit in memory (io/checks.hpp). OBJ has no header (read incrementally; each
// face's indices are on its own line).
#pragma once
#include <string>

namespace microsim {

// UsageError naming the file and the field for a count that is negative, not an integer, larger
// than the file can hold (at least 6 bytes per ASCII vertex, 12 per binary one; 8 and 13 per
// triangle) or beyond 80% of the available memory.
// For PLY and OFF the whole file is then checked in the order OpenMesh's reader consumes it
// (check_ply_structure, and the OFF check inside): that reader trusts every count it reads.
void check_mesh_header(const std::string& path);

// UsageError naming the file unless every value OpenMesh 9.0's PLY reader will extract is there
// and well formed: ASCII numbers it reads whole, binary values inside the file, face lists of 3
// to "element vertex" existing vertices, only the layouts it parses correctly.
void check_ply_structure(const std::string& path);

}  // namespace microsim
