#include "microsim/io/oiio_module.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <vector>

#include "microsim/common.hpp"
#include "microsim/io/output.hpp"

namespace microsim {

void* oiio_module_symbol(const char* name) {
  static void* handle = [] {
    std::vector<std::string> candidates;
    char exe[4096];
    const ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (len > 0) {
      std::string dir(exe, static_cast<std::size_t>(len));
      candidates.push_back(dir.substr(0, dir.find_last_of('/')) + "/libmicrosim_oiio_reader.so");
    }
    candidates.push_back(MICROSIM_OIIO_READER);
    std::string errors;
    for (const auto& c : candidates) {
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
  using Write = int (*)(const char*, const char*, int, int, const unsigned char*, char*, int);
  const auto write = reinterpret_cast<Write>(oiio_module_symbol("microsim_oiio_write_rgb8"));
  if (rgb.size() != static_cast<std::size_t>(width) * height * 3) throw std::logic_error("write_png_rgb8: size");
  write_atomically(path, [&](const std::string& tmp) {
    char err[1024] = {0};
    if (write(tmp.c_str(), "png", width, height, rgb.data(), err, sizeof err)) throw RuntimeFailure(err);
  });
}

}  // namespace microsim
