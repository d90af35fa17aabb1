#include "microsim/io/output.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>

#include "microsim/common.hpp"
#include "microsim/io/exr_header.hpp"

namespace microsim {

std::string extension_of(const std::string& path) {
  auto slash = path.find_last_of('/');
  auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), ::tolower);
  return e;
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  // Same folder, so the rename is atomic; the temporary keeps the extension (EXR/PLY writers
  // choose formats by it).
  auto slash = path.find_last_of('/');
  std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  std::string tmp = dir + ".tmp-" + std::to_string(getpid()) + "-" + base;
  try {
    write(tmp);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw RuntimeFailure("cannot write " + path);
  }
}

void write_json(const std::string& path, const Json& j) {
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream f(tmp);
    if (!f) throw RuntimeFailure("cannot open " + path + " for writing");
    f << std::setw(2) << j << "\n";
    if (!f) throw RuntimeFailure("error writing " + path);
  });
}

void write_csv_rows(const std::string& path, const Json& j) {
  const auto& rows = j.at("rows");
  std::vector<std::string> cols;
  for (const auto& row : rows)
    for (auto it = row.begin(); it != row.end(); ++it)
      if (!it->is_structured() && std::find(cols.begin(), cols.end(), it.key()) == cols.end())
        cols.push_back(it.key());
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream f(tmp);
    if (!f) throw RuntimeFailure("cannot open " + path + " for writing");
    f << std::setprecision(10);
    for (std::size_t c = 0; c < cols.size(); ++c) f << (c ? "," : "") << cols[c];
    f << "\n";
    for (const auto& row : rows) {
      for (std::size_t c = 0; c < cols.size(); ++c) {
        if (c) f << ",";
        auto it = row.find(cols[c]);
        if (it == row.end() || it->is_null()) continue;
        if (it->is_string()) f << it->get<std::string>(); else f << *it;
      }
      f << "\n";
    }
    if (!f) throw RuntimeFailure("error writing " + path);
  });
}

void write_exr(const std::string& path, const ExrTable& t) {
  write_atomically(path, [&](const std::string& tmp) {
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
    for (std::size_t c = 0; c < t.channels.size(); ++c) {
      header.channels().insert(t.channel_names[c], Imf::Channel(Imf::FLOAT));
      fb.insert(t.channel_names[c],
                Imf::Slice(Imf::FLOAT, (char*)t.channels[c].data(), sizeof(float),
                           sizeof(float) * t.width));
    }
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(t.height);
  });
}

ExrTable read_exr(const std::string& path) {
  ExrTable t;
  check_exr_header_sizes(path);  // before OpenEXR allocates what a corrupt header declares
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& h = file.header();
    auto dw = h.dataWindow();
    t.width = dw.max.x - dw.min.x + 1;
    t.height = dw.max.y - dw.min.y + 1;
    for (auto it = h.begin(); it != h.end(); ++it) {
      if (auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&it.attribute()))
        t.attributes[it.name()] = d->value();
      else if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
        t.attributes[it.name()] = s->value();
      else if (auto* i = dynamic_cast<const Imf::IntAttribute*>(&it.attribute()))
        t.attributes[it.name()] = i->value();
    }
    Imf::FrameBuffer fb;
    for (auto c = h.channels().begin(); c != h.channels().end(); ++c) {
      t.channel_names.push_back(c.name());
      t.channels.emplace_back(static_cast<std::size_t>(t.width) * t.height);
    }
    for (std::size_t c = 0; c < t.channels.size(); ++c) {
      char* base = (char*)t.channels[c].data() -
                   (static_cast<long>(dw.min.x) + static_cast<long>(dw.min.y) * t.width) *
                       static_cast<long>(sizeof(float));
      fb.insert(t.channel_names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                               sizeof(float) * t.width));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
  } catch (const std::exception& e) {
    throw UsageError(path + " is not a readable EXR file (" + std::string(e.what()) + ")");
  }
  return t;
}

}  // namespace microsim
