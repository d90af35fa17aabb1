#include "microsim/surface/mesh_header.hpp"

#include <sys/stat.h>

#include <fstream>
#include <sstream>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/io/output.hpp"

namespace microsim {

namespace {
// Bytes a loaded vertex and triangle cost: OpenMesh's kernel (point, normal-free connectivity,
// half-edges) plus microsim's float copies, measured generously.
constexpr double kBytesPerVertex = 120, kBytesPerFace = 160;

long long count_field(const std::string& token, const std::string& path, const std::string& field) {
  return parse_integer_in(token, 0, 4000000000LL, path + ": header field '" + field + "'");
}

void check_counts(long long nv, long long nf, double min_vertex_bytes, double min_face_bytes,
                  double file_bytes, const std::string& path) {
  const double need = nv * min_vertex_bytes + nf * min_face_bytes;
  if (need > file_bytes) {
    std::ostringstream os;
    os << path << ": the header declares " << nv << " vertices and " << nf
       << " faces, more than its " << static_cast<long long>(file_bytes) << " bytes can hold";
    throw UsageError(os.str());
  }
  require_memory(nv * kBytesPerVertex + nf * kBytesPerFace, path + " (" + std::to_string(nv) +
                                                                " vertices, " + std::to_string(nf) + " faces)");
}
}  // namespace

void check_mesh_header(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return;  // the reader reports a missing file
  const double bytes = static_cast<double>(st.st_size);
  const std::string ext = extension_of(path);
  std::ifstream f(path, std::ios::binary);
  if (ext == "ply") {
    std::string line;
    long long nv = 0, nf = 0;
    bool binary = false;
    for (int n = 0; n < 1000 && std::getline(f, line); ++n) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream ls(line);
      std::string word, kind, count;
      ls >> word;
      if (word == "format") {
        ls >> kind;
        binary = kind.rfind("binary", 0) == 0;
      } else if (word == "element") {
        ls >> kind >> count;
        if (kind == "vertex") nv = count_field(count, path, "element vertex");
        else if (kind == "face") nf = count_field(count, path, "element face");
        else count_field(count, path, "element " + kind);
      } else if (word == "end_header") {
        check_counts(nv, nf, binary ? 12 : 6, binary ? 13 : 8, bytes, path);
        return;
      }
    }
    return;  // no header end: the reader refuses the file
  }
  if (ext == "off") {
    std::string line;
    std::vector<std::string> tokens;
    // "OFF" (possibly followed by the counts), comments (#) and blank lines, then nv nf ne.
    for (int n = 0; n < 1000 && tokens.size() < 4 && std::getline(f, line); ++n) {
      auto hash = line.find('#');
      if (hash != std::string::npos) line.erase(hash);
      std::istringstream ls(line);
      for (std::string t; ls >> t;) tokens.push_back(t);
    }
    if (tokens.empty() || tokens[0].find("OFF") == std::string::npos) return;
    if (tokens[0] != "OFF" || tokens.size() < 3) return;  // variants (COFF, binary): the reader decides
    const long long nv = count_field(tokens[1], path, "vertex count");
    const long long nf = count_field(tokens[2], path, "face count");
    if (tokens.size() > 3) count_field(tokens[3], path, "edge count");
    check_counts(nv, nf, 6, 8, bytes, path);
  }
}

}  // namespace microsim
