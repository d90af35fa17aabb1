// microsim command line: CLI11 parsing; each command lives in src/cli/cmd_*.cpp and runs from
// its callback (the tree is built in app.cpp). Usage errors exit 2 with one line, runtime
// failures exit 1.
#include <iostream>

#include "app.hpp"
#include "microsim/io/output.hpp"

using namespace microsim;
using namespace microsim::cli;

namespace {
int run_main(int argc, char** argv) {
  GlobalOptions g;
  std::unique_ptr<CLI::App> app = build_app(g);
  const std::vector<std::string> args(argv + 1, argv + argc);
  const std::string unknown = unknown_command(*app, args);
  if (!unknown.empty()) {
    std::cerr << "microsim: error: " << unknown << "\n";
    return 2;
  }
  // Every output of the command (main file, sidecar, tables) is renamed into place together once
  // the command has succeeded; an error or an interrupt leaves no file and no temporary behind.
  install_interrupt_cleanup();
  try {
    run_app(*app, args);
  } catch (const CLI::CallForHelp& e) {
    return app->exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app->exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app->exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "microsim: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    wait_if_interrupted();  // a failure caused by the interrupt's own cleanup is not reported
    std::cerr << "microsim: failed: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  const int status = run_main(argc, argv);
  wait_if_interrupted();
  return status;
}
