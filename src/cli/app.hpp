// The command tree of microsim, built the same way for the command-line program (main.cpp) and
// for embedders (the Python module), so that both parse the same options and write the same
// records.
#pragma once
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <memory>
#include <string>
#include <vector>

#include "cli_common.hpp"

namespace microsim::cli {

// An App with every command registered on g. --threads, once parsed, limits TBB through a
// global_control the returned App owns (released with it).
std::unique_ptr<CLI::App> build_app(GlobalOptions& g);

// "unknown surface kind 'x' (known: ...)" or "unknown command ..." when the leading words of
// args (without the program name) do not name a command of the tree (CLI11 would only say that a
// subcommand is missing); empty when they do.
std::string unknown_command(const CLI::App& app, const std::vector<std::string>& args);

// Parses args (without the program name) and runs the command inside an output transaction:
// every file it writes is renamed into place once it has succeeded. Throws what the command
// throws: CLI::ParseError (and CLI11's help/version requests), UsageError, other exceptions.
void run_app(CLI::App& app, const std::vector<std::string>& args);

}  // namespace microsim::cli
