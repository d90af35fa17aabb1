// Shared pieces of the libFuzzer targets: the loaders read paths, so each input is written to a
// file in a private temporary folder (removed at exit) and loaded from there.
//
// Contract checked by every target: a loader either returns or throws its usage error (exit 2
// with a one-line message naming the file). Any other exception aborts the run with its message,
// as do sanitizer reports, timeouts and allocations beyond -rss_limit_mb / -malloc_limit_mb.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>

namespace microsim::fuzz {

// Runs load(); Expected is the documented refusal.
template <class Expected, class F>
void expect_only(F&& load) {
  try {
    load();
  } catch (const Expected&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "refused with an exception other than the usage error: %s\n", e.what());
    std::abort();
  }
}

inline const std::filesystem::path& work_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      std::string tmpl = (std::filesystem::temp_directory_path() / "microsim-fuzz-XXXXXX").string();
      if (!mkdtemp(tmpl.data())) std::abort();
      path = tmpl;
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static Dir dir;
  return dir.path;
}

inline std::string write_file(const std::string& name, std::string_view bytes) {
  const std::string path = (work_dir() / name).string();
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!f) std::abort();
  return path;
}

inline void remove_file(const std::string& name) {
  std::error_code ec;
  std::filesystem::remove(work_dir() / name, ec);
}

// Splits an input at the first occurrence of `sep`: (before, after); no separator: (all, "").
inline std::pair<std::string_view, std::string_view> split(std::string_view in, std::string_view sep) {
  const std::size_t k = in.find(sep);
  if (k == std::string_view::npos) return {in, {}};
  return {in.substr(0, k), in.substr(k + sep.size())};
}

}  // namespace microsim::fuzz
