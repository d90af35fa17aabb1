// The OpenImageIO module (plugins/oiio_reader.cpp): loaded on first use, found from the file
// that holds the library (next to it in the build tree; the install tree's lib/microsim from the
// installed program or Python module), else through the RUNPATH, else where the build put it;
// OpenImageIO's few hundred shared libraries are thereby paid only by the commands that read or
// write images.
#pragma once
#include <string>
#include <vector>

namespace microsim {

// The module's entry point `name`; RuntimeFailure when the module cannot be loaded.
void* oiio_module_symbol(const char* name);

// Writes an 8-bit RGB image (row 0 at the top) as PNG, atomically.
void write_png_rgb8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

}  // namespace microsim
