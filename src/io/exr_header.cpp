#include "microsim/io/exr_header.hpp"

#include <cstdint>
#include <fstream>

#include "microsim/common.hpp"

namespace microsim {

namespace {
// OpenEXR file layout: magic 20000630 and a version word (flag 0x1000 = multi-part, whose
// headers end with an empty header), then per header the attributes "name\0type\0", a
// little-endian int32 size and that many bytes, closed by an empty name.
constexpr std::uint32_t kMagic = 20000630u;
constexpr std::uint32_t kMultiPart = 0x1000u;

bool read_u32(std::istream& in, std::uint32_t& v) {
  unsigned char b[4];
  if (!in.read(reinterpret_cast<char*>(b), 4)) return false;
  v = b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
  return true;
}

// Reads a NUL-terminated name of at most 255 characters; false if the file ends first.
bool read_name(std::istream& in, std::string& s) {
  s.clear();
  for (char c; in.get(c);) {
    if (c == 0) return true;
    if (s.size() == 255) return false;
    s += c;
  }
  return false;
}
}  // namespace

void check_exr_header_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return;  // OpenEXR reports an unreadable file
  const std::streamoff file_size = in.tellg();
  in.seekg(0);
  std::uint32_t magic = 0, version = 0;
  if (!read_u32(in, magic) || magic != kMagic || !read_u32(in, version)) return;
  const auto corrupt = [&](const std::string& why) {
    throw UsageError(path + " is not a readable EXR file (" + why + ")");
  };
  const bool multi = version & kMultiPart;
  for (;;) {  // one header per part
    std::string name, type;
    int attributes = 0;
    for (;;) {
      if (!read_name(in, name)) corrupt("truncated header");
      if (name.empty()) break;
      std::uint32_t size = 0;
      if (!read_name(in, type) || !read_u32(in, size)) corrupt("truncated header");
      const std::streamoff here = in.tellg();
      if (size > 0x7fffffffu || static_cast<std::streamoff>(size) > file_size - here)
        corrupt("attribute '" + name + "' declares " + std::to_string(size) +
                " bytes, more than the file holds");
      in.seekg(static_cast<std::streamoff>(size), std::ios::cur);
      ++attributes;
    }
    if (!multi || attributes == 0) return;  // single part, or the empty header ending the list
  }
}

}  // namespace microsim
