// Running the microsim binary from tests: exit code and captured output, per-process temporary
// names (CTest runs test cases as separate processes in parallel).
#pragma once
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace microsim::testing {

struct Result {
  int code;
  std::string out, err;
};

// A temporary path unique to this process: TempDir/microsim_<prefix>_<pid>_<name>.
inline std::string temp_path(const std::string& prefix, const std::string& name) {
  return ::testing::TempDir() + "microsim_" + prefix + "_" + std::to_string(getpid()) + "_" + name;
}
inline std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
inline bool exists(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0;
}
inline int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}
// The binary under test: MICROSIM_BINARY at build time, or the environment variable
// MICROSIM_TEST_BINARY (to run the same tests against another build).
inline std::string binary() {
  const char* env = std::getenv("MICROSIM_TEST_BINARY");
  return env && *env ? env : MICROSIM_BINARY;
}

// Removes this process's temporary files (TempDir/microsim_*_<pid>_*, see temp_path) when the
// test program ends, so that tests leave nothing in /tmp.
class RemoveTemporaries : public ::testing::Environment {
 public:
  void TearDown() override {
    const std::string mark = "_" + std::to_string(getpid()) + "_";
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(::testing::TempDir(), ec)) {
      const std::string name = e.path().filename().string();
      if (name.rfind("microsim_", 0) == 0 && name.find(mark) != std::string::npos)
        std::filesystem::remove_all(e.path(), ec);
    }
  }
};
inline ::testing::Environment* const kRemoveTemporaries =
    ::testing::AddGlobalTestEnvironment(new RemoveTemporaries);

// Runs `microsim ARGS`, capturing stdout and stderr in files named after the current test.
// `prefix` goes before the binary in the shell command (e.g. "ulimit -v N; timeout 60").
inline Result run_microsim(const std::string& args, const std::string& prefix = "") {
  std::string test = ::testing::UnitTest::GetInstance()->current_test_info()
                         ? ::testing::UnitTest::GetInstance()->current_test_info()->name()
                         : "setup";
  std::replace(test.begin(), test.end(), '/', '_');  // parameterized tests: "Name/param"
  std::string out = temp_path("run", test + "_stdout.txt"),
              err = temp_path("run", test + "_stderr.txt");
  std::string cmd = prefix + " " + binary() + " " + args + " >" + out + " 2>" + err;
  int status = std::system(cmd.c_str());
  Result r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

}  // namespace microsim::testing
