#include "microsim/io/oiio_module.hpp"

#include <dlfcn.h>
#include <link.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <memory>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/io/output.hpp"

// Where the build and the install put the module (CMakeLists.txt, cmake/MicrosimPackage.cmake):
// its file name, the paths from the installed program's and the installed Python module's
// folders to the installed module's folder, the configured install folder, the build tree's file.
#ifndef MICROSIM_OIIO_READER_NAME
#define MICROSIM_OIIO_READER_NAME "libmicrosim_oiio_reader.so"
#endif
#ifndef MICROSIM_PLUGIN_FROM_BIN
#define MICROSIM_PLUGIN_FROM_BIN ""
#endif
#ifndef MICROSIM_PLUGIN_FROM_PYTHON
#define MICROSIM_PLUGIN_FROM_PYTHON ""
#endif
#ifndef MICROSIM_PLUGIN_INSTALL_DIR
#define MICROSIM_PLUGIN_INSTALL_DIR ""
#endif
#ifndef MICROSIM_OIIO_READER
#define MICROSIM_OIIO_READER ""
#endif

namespace microsim {
namespace {

std::string folder_of(const std::string& file) {
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : file.substr(0, slash);
}

// The file this code runs from: a shared object that contains the library (the Python module),
// else the program (a static library is part of it). dladdr names the program by argv[0], which
// need not be a path, so the program is read from /proc/self/exe; both with symbolic links
// resolved, so that a link to the program elsewhere still finds the install tree.
std::string file_holding_this_code() {
  Dl_info info;
  link_map* map = nullptr;
  if (dladdr1(reinterpret_cast<void*>(&oiio_module_symbol), &info, reinterpret_cast<void**>(&map),
              RTLD_DL_LINKMAP) &&
      map && map->l_name && map->l_name[0] != '\0') {
    if (char* real = realpath(map->l_name, nullptr)) {
      std::string file(real);
      std::free(real);
      return file;
    }
  }
  char exe[PATH_MAX];
  const ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
  return len > 0 ? std::string(exe, static_cast<std::size_t>(len)) : std::string();
}

// Candidates in order: relative to the file holding this code (next to it, as in the build tree;
// the installed program's and Python module's way to the install tree), then the bare name
// (the holder's RUNPATH, which the CMake package gives projects linking the installed library,
// and LD_LIBRARY_PATH), the build tree, the configured install folder.
std::vector<std::string> module_candidates() {
  const std::string name = MICROSIM_OIIO_READER_NAME;
  std::vector<std::string> c;
  const std::string holder = file_holding_this_code();
  if (!holder.empty()) {
    const std::string dir = folder_of(holder);
    c.push_back(dir + "/" + name);
    for (const std::string rel : {MICROSIM_PLUGIN_FROM_BIN, MICROSIM_PLUGIN_FROM_PYTHON})
      if (!rel.empty()) c.push_back(dir + "/" + rel + "/" + name);
  }
  c.push_back(name);
  if (*MICROSIM_OIIO_READER) c.push_back(MICROSIM_OIIO_READER);
  if (*MICROSIM_PLUGIN_INSTALL_DIR) c.push_back(std::string(MICROSIM_PLUGIN_INSTALL_DIR) + "/" + name);
  return c;
}

}  // namespace

void* oiio_module_symbol(const char* name) {
  static void* handle = [] {
    std::string errors;
    for (const auto& c : module_candidates()) {
      if (void* h = dlopen(c.c_str(), RTLD_NOW | RTLD_LOCAL)) return h;
      const char* e = dlerror();
      errors += std::string(" ") + (e ? e : c);
    }
    throw RuntimeFailure("cannot load the OpenImageIO module:" + errors);
  }();
  void* f = dlsym(handle, name);
  if (!f) throw RuntimeFailure(std::string("the OpenImageIO module has no entry point ") + name);
  return f;
}

void write_png_rgb8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
  using Encode = int (*)(const char*, int, int, const unsigned char*, unsigned char**, std::size_t*, char*, int);
  const auto encode = reinterpret_cast<Encode>(oiio_module_symbol("microsim_oiio_encode_rgb8"));
  if (rgb.size() != static_cast<std::size_t>(width) * height * 3) throw std::logic_error("write_png_rgb8: size");
  unsigned char* bytes = nullptr;
  std::size_t size = 0;
  char err[1024] = {0};
  if (encode("png", width, height, rgb.data(), &bytes, &size, err, sizeof err))
    throw RuntimeFailure("cannot write " + path + ": " + err);
  const std::unique_ptr<unsigned char, decltype(&std::free)> owned(bytes, &std::free);
  write_stream_atomically(path, [&](std::ofstream& out) {
    out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size));
  });
}

}  // namespace microsim
