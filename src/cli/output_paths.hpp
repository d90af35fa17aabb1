// The files a parsed command will write and the files it reads, compared before it runs: an
// output that is the same file as an input of the same run would replace what the run reads.
#pragma once
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace microsim::cli {

// A file the command names, with the option that names it (for the message).
struct NamedPath {
  std::string option;  // "-o", "--json", "--out-dir", "surface", "--config"...
  std::string path;
};

// What the parsed command `cmd` (a leaf of the tree) will write: its -o/--output values,
// --json, the files demo writes into --out-dir, and the files written beside an output (a mesh's
// .json sidecar, measure bsdf's .json record beside its table, a shard's partial record).
// `shard_text` is the global --shard K/N (empty if none).
std::vector<NamedPath> command_outputs(const CLI::App& cmd, const std::string& shard_text);

// What it reads: every other option or argument of the command that names an existing file, and
// the .json sidecar beside an input mesh.
std::vector<NamedPath> command_inputs(const CLI::App& cmd);

// UsageError naming both options when an output of the command parsed by `app` (the command
// itself, or the root of the tree: its parsed leaf) is the same file as one of its inputs
// (resolved: symbolic links, other spellings and hard links name the same file).
void refuse_outputs_naming_inputs(const CLI::App& app, const std::string& shard_text);

}  // namespace microsim::cli
