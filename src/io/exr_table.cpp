#include "microsim/io/exr_table.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStdIO.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <algorithm>

#include "microsim/io/atomic_write.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/io/exr_header.hpp"

namespace microsim {

void write_exr(const std::string& path, const ExrTable& t) {
  std::vector<const float*> pixels;
  for (const auto& c : t.channels) pixels.push_back(c.data());
  write_exr_pixels(path, t, pixels);
}

void write_exr_pixels(const std::string& path, const ExrTable& t, const std::vector<const float*>& pixels) {
  if (pixels.size() != t.channel_names.size())
    throw RuntimeFailure("write_exr: " + std::to_string(t.channel_names.size()) + " channel names for " +
                         std::to_string(pixels.size()) + " channels");
  write_stream_atomically(path, [&](std::ofstream& out) {
    Imf::Header header(t.width, t.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (auto it = t.attributes.begin(); it != t.attributes.end(); ++it) {
      if (it->is_number())
        header.insert(it.key(), Imf::DoubleAttribute(it->get<double>()));
      else if (it->is_string())
        header.insert(it.key(), Imf::StringAttribute(it->get<std::string>()));
      else
        header.insert(it.key(), Imf::StringAttribute(it->dump()));
    }
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < pixels.size(); ++c) {
      header.channels().insert(t.channel_names[c], Imf::Channel(Imf::FLOAT));
      fb.insert(t.channel_names[c],
                Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(pixels[c])),
                           sizeof(float), sizeof(float) * static_cast<std::size_t>(t.width)));
    }
    // OpenEXR writes through the checked stream: its destructor, which writes the line offsets
    // and swallows any error, runs before the stream is closed and checked.
    Imf::StdOFStream stream(out, path.c_str());
    Imf::OutputFile file(stream, header);
    file.setFrameBuffer(fb);
    file.writePixels(t.height);
  });
}

ExrTable read_exr(const std::string& path, const std::function<void(const ExrTable&)>& check_header) {
  ExrTable t;
  check_exr_header_sizes(path);  // before OpenEXR allocates what a corrupt header declares
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& h = file.header();
    auto dw = h.dataWindow();
    // 64-bit sizes: a corrupt data window must not overflow before it is refused.
    const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1;
    const long long hgt = static_cast<long long>(dw.max.y) - dw.min.y + 1;
    if (w < 1 || hgt < 1 || w > (1 << 30) || hgt > (1 << 30))
      throw UsageError(path + ": EXR data window " + std::to_string(w) + " x " + std::to_string(hgt) +
                       " is empty or absurd");
    t.width = static_cast<int>(w);
    t.height = static_cast<int>(hgt);
    for (auto it = h.begin(); it != h.end(); ++it) {
      if (auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&it.attribute()))
        t.attributes[it.name()] = d->value();
      else if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
        t.attributes[it.name()] = s->value();
      else if (auto* i = dynamic_cast<const Imf::IntAttribute*>(&it.attribute()))
        t.attributes[it.name()] = i->value();
    }
    for (auto c = h.channels().begin(); c != h.channels().end(); ++c) t.channel_names.push_back(c.name());
    if (check_header) check_header(t);
    require_memory(static_cast<double>(w) * hgt * 4.0 * std::max<std::size_t>(1, t.channel_names.size()),
                   literal_text(path) + " (" + std::to_string(w) + " x " + std::to_string(hgt) + " pixels)");
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < t.channel_names.size(); ++c)
      t.channels.emplace_back(static_cast<std::size_t>(t.width) * t.height);
    for (std::size_t c = 0; c < t.channels.size(); ++c) {
      char* base = (char*)t.channels[c].data() -
                   (static_cast<long>(dw.min.x) + static_cast<long>(dw.min.y) * t.width) *
                       static_cast<long>(sizeof(float));
      fb.insert(t.channel_names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                               sizeof(float) * t.width));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception& e) {
    throw UsageError(path + " is not a readable EXR file (" + std::string(e.what()) + ")");
  }
  return t;
}

}  // namespace microsim
