#include "microsim/io/atomic_write.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <thread>

#include "microsim/common.hpp"

namespace microsim {

namespace {
// Registered temporaries in fixed storage the signal handler can read without allocating: a slot
// is filled, then published by its flag.
constexpr int kSlots = 256;
constexpr std::size_t kPathMax = 4096;
char g_paths[kSlots][kPathMax];
std::atomic<bool> g_used[kSlots];
// A slot taken by one registering thread before it fills the path (compare-and-swap), so that
// two threads never fill the same slot.
std::atomic<bool> g_claimed[kSlots];

// Removes a file, or a folder with its contents. Runs on the signal thread (below), not in a
// signal handler, so opendir/readdir may allocate even while another thread holds a malloc lock.
void remove_path_raw(const char* path, int depth) {
  if (unlink(path) == 0 || depth > 8) return;
  if (DIR* d = opendir(path)) {
    while (dirent* e = readdir(d)) {
      if (!std::strcmp(e->d_name, ".") || !std::strcmp(e->d_name, "..")) continue;
      char child[kPathMax];
      std::size_t n = std::strlen(path), m = std::strlen(e->d_name);
      if (n + m + 2 > kPathMax) continue;
      std::memcpy(child, path, n);
      child[n] = '/';
      std::memcpy(child + n + 1, e->d_name, m + 1);
      remove_path_raw(child, depth + 1);
    }
    closedir(d);
  }
  rmdir(path);
}

std::atomic<bool> g_interrupting{false};

sigset_t interrupt_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, sig);
  return set;
}

// Removes every registered temporary. The other threads run on meanwhile: one may rename a file
// into a temporary folder after its contents were listed (its rmdir then fails) or register a
// folder the sweep has passed, so the sweep repeats until a pass finds nothing registered left on
// disk (at most about 100 ms).
void remove_temporaries() {
  for (int pass = 0; pass < 100; ++pass) {
    bool left = false;
    for (int k = 0; k < kSlots; ++k)
      if (g_used[k].load()) {
        remove_path_raw(g_paths[k], 0);
        left = left || access(g_paths[k], F_OK) == 0;
      }
    if (!left && pass > 0) return;
    usleep(1000);
  }
}

// The signal thread: the interrupt signals are blocked in every other thread, so they arrive
// here (sigwait) as ordinary events. A cleanup inside an asynchronous handler could deadlock:
// opendir allocates, and the interrupted thread may hold the allocator's lock.
void wait_for_interrupt() {
  const sigset_t set = interrupt_signals();
  int sig = 0;
  while (sigwait(&set, &sig) != 0) {
  }
  g_interrupting.store(true);
  remove_temporaries();
  // End the process by the same signal, with its default action (the exit status says so).
  signal(sig, SIG_DFL);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  raise(sig);
  for (;;) pause();
}

// The live transactions of every thread, in the order opened, each with the thread that opened
// it; this list and every transaction's files_ are read and changed under registry_mutex().
struct LiveTransaction {
  OutputTransaction* transaction;
  std::thread::id owner;
};

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}

std::vector<LiveTransaction>& transactions() {
  static std::vector<LiveTransaction> live;
  return live;
}

// The calling thread's innermost live transaction before `below` (nullptr: from the top), or
// nullptr. The caller holds registry_mutex().
OutputTransaction* innermost_of_this_thread(const OutputTransaction* below = nullptr) {
  const auto& live = transactions();
  auto it = live.rbegin();
  if (below)
    while (it != live.rend() && (it++)->transaction != below) {
    }
  for (; it != live.rend(); ++it)
    if (it->owner == std::this_thread::get_id()) return it->transaction;
  return nullptr;
}
}  // namespace

void register_temporary(const std::string& path) {
  if (path.size() + 1 > kPathMax) throw RuntimeFailure("path too long: " + path);
  for (int k = 0; k < kSlots; ++k) {
    bool free = false;
    if (!g_claimed[k].compare_exchange_strong(free, true)) continue;
    std::memcpy(g_paths[k], path.c_str(), path.size() + 1);
    g_used[k].store(true);
    return;
  }
  throw RuntimeFailure("too many temporary files at once");
}

void unregister_temporary(const std::string& path) {
  for (int k = 0; k < kSlots; ++k)
    if (g_used[k].load() && path == g_paths[k]) {
      g_used[k].store(false);
      g_paths[k][0] = 0;
      g_claimed[k].store(false);
      return;
    }
}

void wait_if_interrupted() {
  if (!g_interrupting.load()) return;
  for (;;) pause();  // the handler re-raises the signal with its default action
}

void install_interrupt_cleanup() {
  // Blocked here, before any other thread exists, so every thread started later inherits the
  // mask and only the signal thread receives them.
  const sigset_t set = interrupt_signals();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::thread(wait_for_interrupt).detach();
}

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  std::string tmpl = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
  if (!mkdtemp(tmpl.data())) throw RuntimeFailure("cannot create a temporary folder in " + tmpl);
  path_ = tmpl;
  register_temporary(path_);
  // Made while an interrupt's sweep was running: it may have passed this folder's slot already.
  if (g_interrupting.load()) {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
    wait_if_interrupted();
  }
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  unregister_temporary(path_);
}

namespace {
std::string folder_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
}

// The one line every failed output reports: the file, and why (errno when it says).
[[noreturn]] void fail_writing(const std::string& path, int err, const std::string& why = "") {
  std::string reason = why.empty() && err ? std::strerror(err) : why;
  throw RuntimeFailure("cannot write " + path + (reason.empty() ? "" : ": " + reason));
}

// An existing file that is neither a regular file nor a folder (stat follows symbolic links, so
// /dev/stdout is its terminal or pipe): a device or a pipe, written in place.
bool is_device_or_pipe(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

// The data reaches the disk before the rename makes it the output, so that a crash leaves the
// previous file or the new one, never a renamed file with missing blocks. Also refuses a
// writer that returned without creating its file.
void sync_file(const std::string& file, const std::string& path) {
  const int fd = open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail_writing(path, errno);
  const int rc = fsync(fd);
  const int err = errno;
  close(fd);
  // EINVAL: a file that cannot be synchronized (a device written in place).
  if (rc != 0 && err != EINVAL) fail_writing(path, err);
}

// The rename itself reaches the disk (best effort: a folder that cannot be synced loses nothing
// that the file's own sync did not keep).
void sync_folder_of(const std::string& path) {
  const int fd = open(folder_of(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  fsync(fd);
  close(fd);
}

// The message of a writer's exception, naming the output rather than its temporary.
std::string naming_output(std::string what, const std::string& tmp, const std::string& path) {
  const std::string tmp_name = tmp.substr(tmp.find_last_of('/') + 1);
  const std::string name = path.substr(path.find_last_of('/') + 1);
  for (std::size_t at; (at = what.find(tmp_name)) != std::string::npos;) what.replace(at, tmp_name.size(), name);
  return what;
}

// A writer's failure as the output's one line: kept when it already names the output.
[[noreturn]] void fail_with_writer_message(const std::string& what, const std::string& path) {
  if (what.rfind("cannot write " + path, 0) == 0) throw RuntimeFailure(what);
  fail_writing(path, 0, what);
}

void remove_folders_if_empty(const std::vector<std::string>& folders) {
  for (auto it = folders.rbegin(); it != folders.rend(); ++it) {
    rmdir(it->c_str());  // fails, and keeps the folder, when anything else is in it
    unregister_temporary(*it);
  }
}
}  // namespace

OutputTransaction::OutputTransaction() {
  const std::lock_guard<std::mutex> lock(registry_mutex());
  transactions().push_back({this, std::this_thread::get_id()});
}

OutputTransaction::~OutputTransaction() {
  {
    const std::lock_guard<std::mutex> lock(registry_mutex());
    auto& live = transactions();
    live.erase(std::remove_if(live.begin(), live.end(), [this](const LiveTransaction& l) { return l.transaction == this; }),
               live.end());
  }
  for (const auto& [tmp, path] : files_) {
    std::remove(tmp.c_str());
    unregister_temporary(tmp);
  }
  for (const auto& path : placed_) {
    std::remove(path.c_str());
    unregister_temporary(path);
  }
  remove_folders_if_empty(folders_);
}

void OutputTransaction::commit() {
  std::vector<std::pair<std::string, std::string>> files;
  {
    const std::lock_guard<std::mutex> lock(registry_mutex());
    files = std::move(files_);
    files_.clear();
  }
  std::string failed;
  // A destination that cannot take a file (a folder of that name) fails the whole set before
  // anything is renamed.
  for (const auto& [tmp, path] : files) {
    struct stat st;
    if (stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) failed = path;
  }
  // While the set is being renamed an interrupt removes the files already in place too: the
  // outputs appear together or not at all.
  const bool renaming = failed.empty();
  if (renaming)
    for (const auto& [tmp, path] : files) register_temporary(path);
  std::size_t renamed = 0;
  int err = 0;
  for (const auto& [tmp, path] : files) {
    if (failed.empty() && std::rename(tmp.c_str(), path.c_str()) != 0) {
      failed = path;
      err = errno;
    }
    if (failed.empty()) ++renamed; else std::remove(tmp.c_str());
    unregister_temporary(tmp);
  }
  if (!failed.empty())  // the files renamed before the failure go too
    for (std::size_t k = 0; k < renamed; ++k) std::remove(files[k].second.c_str());
  if (renaming)
    for (const auto& [tmp, path] : files) unregister_temporary(path);
  if (!failed.empty()) fail_writing(failed, err);
  for (const auto& [tmp, path] : files) sync_folder_of(path);
  // Files placed earlier and folders created for the outputs are kept from now on.
  for (const auto& path : placed_) unregister_temporary(path);
  placed_.clear();
  for (const auto& folder : folders_) unregister_temporary(folder);
  folders_.clear();
}

void OutputTransaction::place_provisionally() {
  OutputTransaction* parent = nullptr;
  std::vector<std::string> finals;
  {
    const std::lock_guard<std::mutex> lock(registry_mutex());
    parent = innermost_of_this_thread(this);
    for (const auto& [tmp, path] : files_) finals.push_back(path);
  }
  // Registered before the rename: an interrupt in between removes them as well.
  for (const auto& path : finals) register_temporary(path);
  try {
    commit();
  } catch (...) {
    for (const auto& path : finals) unregister_temporary(path);
    throw;
  }
  if (parent)
    parent->placed_.insert(parent->placed_.end(), finals.begin(), finals.end());
  else
    for (const auto& path : finals) unregister_temporary(path);
}

void OutputTransaction::created_folder(const std::string& path) {
  register_temporary(path);
  folders_.push_back(path);
}

bool create_output_folder(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) return true;
  // The missing folders, outermost first, each created and tied to the transaction.
  std::vector<fs::path> missing;
  for (fs::path p = fs::path(path).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.insert(missing.begin(), p);
    if (p == p.parent_path()) break;
  }
  for (const auto& p : missing) {
    if (mkdir(p.c_str(), 0755) != 0) {
      if (errno == EEXIST && fs::is_directory(p, ec)) continue;
      return false;
    }
    OutputTransaction* innermost = nullptr;
    {
      const std::lock_guard<std::mutex> lock(registry_mutex());
      innermost = innermost_of_this_thread();
    }
    if (innermost) innermost->created_folder(p.string());
  }
  return fs::is_directory(path, ec);
}

std::string OutputTransaction::pending(const std::string& path) {
  const std::lock_guard<std::mutex> lock(registry_mutex());
  for (auto it = transactions().rbegin(); it != transactions().rend(); ++it)
    for (const auto& [tmp, final_path] : it->transaction->files_)
      if (final_path == path) return tmp;
  return "";
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  if (is_device_or_pipe(path)) {
    try {
      write(path);
    } catch (const UsageError&) {
      throw;
    } catch (const std::exception& e) {
      fail_with_writer_message(e.what(), path);
    }
    return;
  }
  // Same folder, so the rename is atomic; the temporary keeps the extension (EXR/PLY writers
  // choose formats by it).
  auto slash = path.find_last_of('/');
  std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  static std::atomic<int> counter{0};
  std::string tmp = dir + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" + base;
  register_temporary(tmp);
  auto discard = [&] {
    std::remove(tmp.c_str());
    unregister_temporary(tmp);
  };
  try {
    write(tmp);
    sync_file(tmp, path);
  } catch (const UsageError&) {
    discard();
    throw;
  } catch (const std::exception& e) {
    discard();
    fail_with_writer_message(naming_output(e.what(), tmp, path), path);
  } catch (...) {
    discard();
    throw;
  }
  {
    const std::lock_guard<std::mutex> lock(registry_mutex());
    if (OutputTransaction* t = innermost_of_this_thread()) {
      t->files_.emplace_back(tmp, path);
      return;
    }
  }
  const bool ok = std::rename(tmp.c_str(), path.c_str()) == 0;
  const int err = errno;
  if (!ok) std::remove(tmp.c_str());
  unregister_temporary(tmp);
  if (!ok) fail_writing(path, err);
  sync_folder_of(path);
}

void write_stream_atomically(const std::string& path, const std::function<void(std::ofstream&)>& write) {
  write_atomically(path, [&](const std::string& file) {
    errno = 0;
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    if (!out) fail_writing(path, errno);
    write(out);
    // The stream buffers: the last block reaches the file only at the flush, and the close can
    // fail too. The first errno seen is the reason (a full disk: ENOSPC).
    int err = out ? 0 : errno;
    out.flush();
    if (!out && !err) err = errno;
    out.close();
    if (!out) fail_writing(path, err ? err : errno);
  });
}

}  // namespace microsim
