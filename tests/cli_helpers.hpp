// Running the microsim binary from tests: exit code and captured output, per-process temporary
// names (CTest runs test cases as separate processes in parallel).
#pragma once
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
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
// Runs `microsim ARGS`, capturing stdout and stderr in files named after the current test.
inline Result run_microsim(const std::string& args) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()
                               ? ::testing::UnitTest::GetInstance()->current_test_info()->name()
                               : "setup";
  std::string out = temp_path("run", test + "_stdout.txt"),
              err = temp_path("run", test + "_stderr.txt");
  std::string cmd = std::string(MICROSIM_BINARY) + " " + args + " >" + out + " 2>" + err;
  int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace microsim::testing
