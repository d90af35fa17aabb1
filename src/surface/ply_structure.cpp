// The body of a PLY file checked in the order OpenMesh 9.0's reader consumes it, before that
// reader runs. Its loops trust the file: a face's list count sizes a vector directly (a count of
// 2^31 asks for 8 GB), and after a failed ASCII extraction the count keeps a stale value while
// the face loop goes on for the declared number of faces. So every value the reader will extract
// is checked here: ASCII tokens are numbers that operator>> reads whole, binary values lie inside
// the file, and a face's vertex list has 3 to "element vertex" entries, each an existing vertex.
// Layouts the reader misparses (lists other than the faces' vertex_indices, or vertex_indices
// after other face properties, which it silently drops) are refused rather than guessed.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/surface/mesh_header.hpp"

namespace microsim {

namespace {

enum class Kind { Int, Float, Other };

struct Type {
  int bytes = 0;
  Kind kind = Kind::Other;
  bool is_signed = false;
};

// PLY scalar type names as the reader knows them (the rest it does not support).
Type type_of(const std::string& name) {
  if (name == "char" || name == "int8") return {1, Kind::Int, true};
  if (name == "uchar" || name == "uint8") return {1, Kind::Int, false};
  if (name == "short" || name == "int16") return {2, Kind::Int, true};
  if (name == "ushort" || name == "uint16") return {2, Kind::Int, false};
  if (name == "int" || name == "int32") return {4, Kind::Int, true};
  if (name == "uint" || name == "uint32") return {4, Kind::Int, false};
  if (name == "float" || name == "float32") return {4, Kind::Float, true};
  if (name == "double" || name == "float64") return {8, Kind::Float, true};
  return {};
}

struct Property {
  std::string name;
  Type value;
  bool list = false;
  Type count;  // list only
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> props;
};

// A whole token that operator>> reads completely as a number of this kind: decimal digits for
// integers (sign only if signed), decimal floats within the float range (the reader stores every
// coordinate as float) and not subnormal.
bool ascii_value_ok(const std::string& t, const Type& type, long long* value) {
  std::size_t k = 0;
  if (k < t.size() && (t[k] == '+' || t[k] == '-')) ++k;
  auto digits = [&] {
    const std::size_t k0 = k;
    while (k < t.size() && t[k] >= '0' && t[k] <= '9') ++k;
    return k - k0;
  };
  if (type.kind == Kind::Int) {
    if (t[0] == '-' && !type.is_signed) return false;
    const std::size_t n = digits();
    if (n == 0 || n > 10 || k != t.size()) return false;
    const long long v = std::strtoll(t.c_str(), nullptr, 10);
    const long long lim = type.bytes == 4 ? (type.is_signed ? INT32_MAX : UINT32_MAX)
                                          : (1LL << (8 * type.bytes - (type.is_signed ? 1 : 0))) - 1;
    if (v > lim || v < -lim - 1) return false;
    if (value) *value = v;
    return true;
  }
  std::size_t mantissa = digits();
  if (k < t.size() && t[k] == '.') {
    ++k;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (k < t.size() && (t[k] == 'e' || t[k] == 'E')) {
    ++k;
    if (k < t.size() && (t[k] == '+' || t[k] == '-')) ++k;
    if (digits() == 0) return false;
  }
  if (k != t.size()) return false;
  const double v = std::abs(std::strtod(t.c_str(), nullptr));
  return v <= std::numeric_limits<float>::max() && (v == 0 || v >= std::numeric_limits<float>::min());
}

// The reader stores coordinates, normals and texture coordinates as float through a float-only
// conversion, colours through an int-or-float one and face texture numbers through an integer
// one; any other type is not consumed from a binary file (an integer coordinate), or misread from
// an ASCII one (a double colour), which shifts everything after it. Such properties are refused.
template <class Fail>
void check_reader_type(const std::string& element, const Property& p, bool binary, Fail&& malformed) {
  static const char* const kFloatOnly[] = {"x", "y", "z", "nx", "ny", "nz", "u", "v", "s", "t"};
  static const char* const kColour[] = {"red", "green", "blue", "alpha", "diffuse_red", "diffuse_green", "diffuse_blue"};
  const auto in = [&](const auto& names) {
    for (const char* n : names)
      if (p.name == n) return true;
    return false;
  };
  bool ok = true;
  if (binary && element == "vertex" && in(kFloatOnly)) ok = p.value.kind == Kind::Float;
  if ((element == "vertex" || element == "face") && in(kColour)) ok = !(p.value.kind == Kind::Float && p.value.bytes == 8);
  if (element == "face" && p.name == "texnumber") ok = p.value.kind == Kind::Int;
  if (!ok) malformed("property '" + p.name + "' of element " + element + " has a type the reader does not convert");
}

class Body {
 public:
  Body(std::istream& in, const std::string& path, bool binary, bool big_endian)
      : in_(in), path_(path), binary_(binary), big_(big_endian) {}
  [[noreturn]] void fail(const std::string& why) const {
    throw UsageError(path_ + ": malformed PLY file (" + why + ")");
  }
  // One value of `type`; returns it when it is an integer (list counts and indices).
  long long value(const Type& type, const std::string& what) {
    if (!binary_) {
      std::string t;
      if (!(in_ >> t)) fail("the file ends in " + what);
      long long v = 0;
      if (!ascii_value_ok(t, type, &v))
        fail(what + ": '" + t.substr(0, 20) + "' is not a " + (type.kind == Kind::Int ? "integer" : "finite number") +
             " of its declared type");
      return v;
    }
    unsigned char b[8];
    if (!in_.read(reinterpret_cast<char*>(b), type.bytes)) fail("the file ends in " + what);
    if (type.kind != Kind::Int) return 0;
    std::uint64_t u = 0;
    for (int i = 0; i < type.bytes; ++i) u |= std::uint64_t(b[big_ ? type.bytes - 1 - i : i]) << (8 * i);
    if (type.is_signed && type.bytes < 8 && (u >> (8 * type.bytes - 1)))
      return static_cast<long long>(u) - (1LL << (8 * type.bytes));
    return static_cast<long long>(u);
  }

 private:
  std::istream& in_;
  const std::string& path_;
  bool binary_, big_;
};

// What a malformed file is told: "PATH: malformed PLY file (WHY)".
using Malformed = std::function<void(const std::string& why)>;

struct PlyHeader {
  std::string format;
  std::vector<Element> elements;
  std::streamoff before_end = 0;  // the position before "end_header" was extracted
};

// One "property" line of the header, after the word "property"; false when the reader refuses
// it (a list count type it does not read).
bool read_property(std::istream& in, std::vector<Element>& elements, bool binary, const Malformed& malformed) {
  if (elements.empty()) malformed("a property before any element");
  Property p;
  std::string a, b;
  in >> a;
  if (a == "list") {
    in >> a >> b >> p.name;
    p.list = true;
    p.count = type_of(a);
    p.value = type_of(b);
    if (a != "uchar" && a != "uint8" && a != "uint16" && a != "int") return false;  // the reader refuses it
  } else {
    in >> b;
    p.value = type_of(a).bytes ? type_of(a) : type_of(b);
    p.name = type_of(a).bytes ? b : a;
  }
  Element& e = elements.back();
  if (p.list && !(e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index")))
    malformed("list property '" + p.name + "' of element " + e.name +
              ": the only list read is the faces' vertex_indices");
  if (p.list && !e.props.empty())
    malformed("vertex_indices must be the first property of element face");
  if (p.value.bytes == 0 || type_of(p.name).bytes)
    malformed("property '" + p.name + "' of element " + e.name + ": one known type and a name");
  check_reader_type(e.name, p, binary, malformed);
  if (p.list && p.value.kind != Kind::Int) malformed("vertex_indices must hold integers");
  e.props.push_back(p);
  return true;
}

// The header, read with the reader's own stream operations; nothing where the reader refuses
// the file itself (not "ply", an unknown format, a list it does not read).
std::optional<PlyHeader> read_ply_header(std::istream& in, const Malformed& malformed) {
  PlyHeader h;
  std::string line, word;
  std::getline(in, line);
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) line.erase(0, 1);
  if (line != "ply" && line != "PLY") return std::nullopt;  // the reader refuses it
  std::string version;
  if (!(in >> word >> h.format >> version) || !ascii_value_ok(version, type_of("float"), nullptr))
    malformed("the second line must be 'format ascii|binary_little_endian|binary_big_endian 1.0'");
  const bool binary = h.format != "ascii";
  if (h.format != "ascii" && h.format != "binary_little_endian" && h.format != "binary_big_endian")
    return std::nullopt;  // the reader refuses it
  h.before_end = in.tellg();
  for (int tokens = 0; in >> word && word != "end_header"; ++tokens) {
    if (tokens > 100000) malformed("no end_header");
    if (word == "comment") {
      std::getline(in, line);
    } else if (word == "element") {
      Element e;
      std::string count;
      in >> e.name >> count;
      if (count.empty() || count.size() > 10 || count.find_first_not_of("0123456789") != std::string::npos)
        malformed("element " + e.name + " needs a count");
      e.count = std::stoll(count);
      for (const Element& seen : h.elements)
        if (seen.name == e.name) malformed("element " + e.name + " declared twice");
      h.elements.push_back(e);
    } else if (word == "property") {
      if (!read_property(in, h.elements, binary, malformed)) return std::nullopt;
    }
    h.before_end = in.tellg();
  }
  if (word != "end_header") malformed("no end_header");
  return h;
}

// Each value takes at least one byte: this bounds every loop of the body (and the reader's) by
// the file's length. Leaves `in` at the end of the header.
void check_counts_fit(std::istream& in, const std::vector<Element>& elements, const Malformed& malformed) {
  in.clear();
  const std::streamoff header_end = in.tellg();
  in.seekg(0, std::ios::end);
  const double data_bytes = static_cast<double>(in.tellg() - header_end);
  in.seekg(header_end);
  for (const Element& e : elements)
    if (e.count > 0 && (e.props.empty() || double(e.count) * double(e.props.size()) > data_bytes))
      malformed("element " + e.name + " declares " + std::to_string(e.count) + " items of " +
                std::to_string(e.props.size()) + " properties, more than the file holds");
}

// Every value up to the faces (the reader stops after them): readable, and each face 3 to nv
// existing vertices.
void check_ply_body(Body& body, const std::vector<Element>& elements, const Malformed& malformed) {
  long long nv = 0;
  for (const Element& e : elements)
    if (e.name == "vertex") nv = e.count;
  for (const Element& e : elements) {
    for (long long i = 0; i < e.count; ++i) {
      for (const Property& p : e.props) {
        const std::string what = "element " + e.name + " " + std::to_string(i) + " property " + p.name;
        if (!p.list) {
          body.value(p.value, what);
          continue;
        }
        const long long n = body.value(p.count, what + " count");
        if (n < 3 || n > nv)
          malformed(what + ": " + std::to_string(n) + " vertices; a face needs 3 to " + std::to_string(nv) +
                    " (element vertex)");
        for (long long k = 0; k < n; ++k) {
          const long long v = body.value(p.value, what);
          if (v < 0 || v >= nv)
            malformed(what + ": vertex " + std::to_string(v) + " does not exist (" + std::to_string(nv) +
                      " vertices)");
        }
      }
    }
    if (e.name == "face") break;  // the reader stops after the faces
  }
}

}  // namespace

void check_ply_structure(const std::string& path) {
  const Malformed malformed = [&](const std::string& why) {
    throw UsageError(path + ": malformed PLY file (" + why + ")");
  };
  std::ifstream in(path, std::ios::binary);
  const std::optional<PlyHeader> h = read_ply_header(in, malformed);
  if (!h) return;  // the reader refuses it
  const bool binary = h->format != "ascii";
  check_counts_fit(in, h->elements, malformed);
  if (binary) {
    // The reader's binary data starts 12 or 14 bytes after the position before "end_header"
    // was extracted.
    in.clear();
    in.seekg(h->before_end);
    char c1 = 0, c2 = 0;
    in.get(c1);
    in.get(c2);
    in.seekg(h->before_end + ((c1 == '\r' && c2 == '\n') ? 14 : 12));
  }
  Body body(in, path, binary, h->format == "binary_big_endian");
  check_ply_body(body, h->elements, malformed);
}
}  // namespace microsim
