// Reads one channel of an image (and writes 8-bit previews) through OpenImageIO, behind C entry
// points. microsim loads this module only when it imports an image (heightmap_import.cpp) or
// writes a PNG preview (render/sphere_preview.cpp): OpenImageIO pulls in a few
// hundred shared libraries, which would otherwise cost every microsim command seconds of start-up.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {
// Largest value of an integer pixel type: OpenImageIO converts integers to [0, 1] (or [-1, 1]);
// multiplying back gives the instrument's raw counts.
double integer_range(const OIIO::TypeDesc& t) {
  switch (t.basetype) {
    case OIIO::TypeDesc::UINT8: return 255.0;
    case OIIO::TypeDesc::INT8: return 127.0;
    case OIIO::TypeDesc::UINT16: return 65535.0;
    case OIIO::TypeDesc::INT16: return 32767.0;
    case OIIO::TypeDesc::UINT32: return 4294967295.0;
    case OIIO::TypeDesc::INT32: return 2147483647.0;
    default: return 0.0;
  }
}

int fail(char* err, int cap, std::string msg) {
  std::replace(msg.begin(), msg.end(), '\n', ' ');
  std::snprintf(err, static_cast<std::size_t>(cap), "%s", msg.c_str());
  return 1;
}
}  // namespace

// Returns 0 and a malloc'ed width*height array of doubles (row 0 first) in *data, the channel
// used in chosen[cap]; or nonzero and a one-line message in err[cap].
extern "C" int microsim_oiio_read_channel(const char* path, const char* channel, int* width, int* height,
                                          double** data, char* chosen, int chosen_cap, char* err, int err_cap) {
  *data = nullptr;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return fail(err, err_cap, std::string(path) + ": not a readable image (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec spec = in->spec();
  int ch = -1;
  std::string names;
  for (int c = 0; c < spec.nchannels; ++c) names += (c ? "," : "") + spec.channelnames[c];
  if (channel && *channel) {
    for (int c = 0; c < spec.nchannels; ++c)
      if (spec.channelnames[c] == channel) ch = c;
    if (ch < 0) return fail(err, err_cap, std::string("--channel ") + channel + ": " + path + " has channels " + names);
  } else if (spec.nchannels == 1) {
    ch = 0;
  } else {
    for (const char* pref : {"Z", "Y", "height"})
      for (int c = 0; c < spec.nchannels && ch < 0; ++c)
        if (spec.channelnames[c] == pref) ch = c;
    if (ch < 0)
      return fail(err, err_cap, std::string(path) + " has channels " + names + ": choose the height channel with --channel");
  }
  if (spec.width <= 0 || spec.height <= 0 || spec.depth > 1) return fail(err, err_cap, std::string(path) + ": not a 2D image");
  const std::size_t n = static_cast<std::size_t>(spec.width) * spec.height;
  double* z = static_cast<double*>(std::malloc(n * sizeof(double)));
  if (!z) return fail(err, err_cap, std::string(path) + ": out of memory");
  if (!in->read_image(0, 0, ch, ch + 1, OIIO::TypeDesc::DOUBLE, z)) {
    std::free(z);
    return fail(err, err_cap, std::string(path) + ": cannot read its pixels (" + in->geterror() + ")");
  }
  const double range = integer_range(spec.channelformat(ch));
  if (range > 0)
    for (std::size_t k = 0; k < n; ++k) z[k] = std::round(z[k] * range);
  *width = spec.width;
  *height = spec.height;
  *data = z;
  std::snprintf(chosen, static_cast<std::size_t>(chosen_cap), "%s", spec.channelnames[ch].c_str());
  return 0;
}

// Encodes an 8-bit RGB image (width*height*3 bytes, row 0 at the top) in the format named by
// `format` ("png") in memory: the caller writes the bytes through its checked output (an image
// writer's close does not report a full disk). Returns 0 and a malloc'ed buffer of *size bytes
// in *bytes (freed by the caller), or nonzero and a one-line message in err[cap].
extern "C" int microsim_oiio_encode_rgb8(const char* format, int width, int height, const unsigned char* rgb,
                                         unsigned char** bytes, std::size_t* size, char* err, int err_cap) {
  *bytes = nullptr;
  *size = 0;
  auto out = OIIO::ImageOutput::create(format);
  if (!out) return fail(err, err_cap, std::string("no ") + format + " writer in OpenImageIO (" + OIIO::geterror() + ")");
  if (!out->supports("ioproxy"))
    return fail(err, err_cap, std::string("the ") + format + " writer of OpenImageIO cannot write to memory");
  OIIO::Filesystem::IOVecOutput memory;
  out->set_ioproxy(&memory);
  const std::string name = std::string("image.") + format;
  const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  if (!out->open(name, spec)) return fail(err, err_cap, out->geterror());
  if (!out->write_image(OIIO::TypeDesc::UINT8, rgb)) return fail(err, err_cap, out->geterror());
  if (!out->close()) return fail(err, err_cap, out->geterror());
  const std::vector<unsigned char>& encoded = memory.buffer();
  *bytes = static_cast<unsigned char*>(std::malloc(std::max<std::size_t>(1, encoded.size())));
  if (!*bytes) return fail(err, err_cap, "out of memory");
  std::memcpy(*bytes, encoded.data(), encoded.size());
  *size = encoded.size();
  return 0;
}
