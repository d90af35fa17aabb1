#include "microsim/surface/mesh_header.hpp"

#include <sys/stat.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
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
  return parse_integer_in(token, 0, 4000000000LL, literal_text(path) + ": header field '" + field + "'");
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
  require_memory(nv * kBytesPerVertex + nf * kBytesPerFace, literal_text(path) + " (" + std::to_string(nv) +
                                                                " vertices, " + std::to_string(nf) + " faces)");
}

// OpenMesh 9.0's ASCII OFF reader takes the first line as the header and reads the rest with
// operator>>: it skips no comments, ignores counts written on the header line, and runs its
// face loop nF times with no end-of-file test, growing each face's vertex list to the count it
// reads (after a failed read that count keeps a stale value, so a malformed file can loop for
// hours or ask for gigabytes). The whole file is therefore checked first, token by token in the
// reader's own order: counts and indices integers in range, coordinates finite floats, every
// face present. A file that passes is read by OpenMesh without a failed extraction.
class OffTokens {
 public:
  OffTokens(std::istream& in, const std::string& path) : in_(in), path_(path) {}
  [[noreturn]] void fail(const std::string& why) const {
    throw UsageError(path_ + ": malformed OFF file (" + why + ")");
  }
  std::string next(const std::string& what) {
    std::string t;
    if (!(in_ >> t)) fail("the file ends before " + what);
    return t;
  }
  long long integer(const std::string& what, long long hi) {
    const std::string t = next(what);
    if (t.empty() || t.size() > 10 || t.find_first_not_of("0123456789") != std::string::npos ||
        std::stoll(t) > hi)
      fail(what + " must be an integer in [0, " + std::to_string(hi) + "], not '" + t.substr(0, 20) + "'");
    return std::stoll(t);
  }
  // A decimal number that operator>> reads as a whole into a float: no hex, inf or nan, no
  // overflow, no subnormal.
  void coordinate(const std::string& what) {
    const std::string t = next(what);
    std::size_t k = 0;
    auto digits = [&] {
      const std::size_t k0 = k;
      while (k < t.size() && t[k] >= '0' && t[k] <= '9') ++k;
      return k - k0;
    };
    if (k < t.size() && (t[k] == '+' || t[k] == '-')) ++k;
    std::size_t mantissa = digits();
    if (k < t.size() && t[k] == '.') {
      ++k;
      mantissa += digits();
    }
    bool ok = mantissa > 0;
    if (ok && k < t.size() && (t[k] == 'e' || t[k] == 'E')) {
      ++k;
      if (k < t.size() && (t[k] == '+' || t[k] == '-')) ++k;
      ok = digits() > 0;
    }
    const double v = ok && k == t.size() ? std::strtod(t.c_str(), nullptr) : 1e300;
    if (!(std::abs(v) <= std::numeric_limits<float>::max()) ||
        (v != 0 && std::abs(v) < std::numeric_limits<float>::min()))
      fail(what + " must be a finite decimal number, not '" + t.substr(0, 20) + "'");
  }
  void rest_of_line() {
    std::string rest;
    std::getline(in_, rest);
  }

 private:
  std::istream& in_;
  const std::string& path_;
};

void check_off_file(const std::string& path, std::istream& in, double bytes) {
  OffTokens tok(in, path);
  // Header line: [ST][C][N]OFF, as OpenMesh's OFF reader recognizes it. Other first lines (4OFF,
  // nOFF, no OFF at all) are refused by the reader itself.
  std::string header;
  std::getline(in, header);
  std::size_t p = 0;
  const bool texcoord = header.compare(0, 2, "ST") == 0;
  if (texcoord) p = 2;
  const bool color = p < header.size() && header[p] == 'C';
  if (color) ++p;
  const bool normal = p < header.size() && header[p] == 'N';
  if (normal) ++p;
  if (header.compare(p, 3, "OFF") != 0) return;
  const std::string rest = header.substr(p + 3);
  if (rest.find("BINARY") != std::string::npos)
    tok.fail("binary OFF is not supported; write ASCII OFF or PLY");
  if (rest.find_first_not_of(" \t\r") != std::string::npos)
    tok.fail("'" + header.substr(0, p + 3) + "' must stand alone on the first line, the counts on the next");
  (void)texcoord;  // texture coordinates sit in the rest of a vertex line, which the reader skips

  const long long nv = tok.integer("the vertex count", 4000000000LL);
  const long long nf = tok.integer("the face count", 4000000000LL);
  tok.integer("the edge count", 4000000000LL);
  check_counts(nv, nf, 6, 8, bytes, path);
  for (long long i = 0; i < nv; ++i) {
    const std::string what = "vertex " + std::to_string(i);
    for (int c = 0; c < (normal ? 6 : 3); ++c) tok.coordinate(what);
    tok.rest_of_line();  // colour, texture coordinates
  }
  for (long long i = 0; i < nf; ++i) {
    const std::string what = "face " + std::to_string(i);
    const long long n = tok.integer(what + "'s vertex count", 4000000000LL);
    if (n < 3 || n > nv)
      tok.fail(what + " has " + std::to_string(n) + " vertices; a face needs 3 to " + std::to_string(nv) +
               " (the vertex count)");
    for (long long k = 0; k < n; ++k)
      if (nv > 0) tok.integer(what + "'s vertex index", nv - 1);
    if (color) tok.rest_of_line();
  }
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
        break;
      }
    }
    check_ply_structure(path);
    return;
  }
  if (ext == "off") check_off_file(path, f, bytes);
}

}  // namespace microsim
