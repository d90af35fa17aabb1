// Checks of a mesh file's declared sizes before any of it is read: PLY "element vertex N" /
// "element face N" and the OFF counts line must be non-negative integers that the file's length
// can hold and that fit in memory (io/checks.hpp). OBJ has no header (read incrementally).
#pragma once
#include <string>

namespace microsim {

// UsageError naming the file and the field for a count that is negative, not an integer, larger
// than the file can hold (at least 6 bytes per ASCII vertex, 12 per binary one; 8 and 13 per
// triangle) or beyond 80% of the available memory.
void check_mesh_header(const std::string& path);

}  // namespace microsim
