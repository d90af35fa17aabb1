// microsim merge PARTS... -o OUT: the record of a run from the partial records of its shards
// (measure/shards.hpp). The parts are checked to belong to one run and to cover it exactly once;
// then the run's own command is replayed on the merged tallies (it traces nothing), so the
// record is written by the same code as a single run's, from the same numbers.
#include <fstream>
#include <iostream>

#include "scaleout.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/io/json_input.hpp"
#include "microsim/io/output.hpp"

namespace microsim::cli {

bool command_can_split(const std::vector<std::string>& words) {
  if (words.size() == 1) return words[0] == "validate";
  if (words.size() == 2 && words[0] == "measure")
    return words[1] == "g1" || words[1] == "g2" || words[1] == "vndf" || words[1] == "bsdf";
  return false;
}

namespace {

struct MergeOptions {
  std::vector<std::string> parts;
  std::string output;
};

Json read_part(const std::string& path) {
  require_regular_input(path, "part");
  std::ifstream in(path);
  if (!in) throw UsageError("part " + path + " cannot be read");
  try {
    // A part holds the tallies of every unit of its share: large, but bounded.
    return parse_json_input(in, "part " + literal_text(path), JsonLimits{64, std::size_t(1) << 30, false});
  } catch (const Json::exception&) {
    throw UsageError("part " + path + " is not JSON (expected a partial record written by --shard)");
  }
}

int run_merge(const MergeOptions& o, const GlobalOptions& g) {
  std::vector<std::pair<std::string, Json>> parts;
  for (const auto& p : o.parts) parts.emplace_back(p, read_part(p));
  MergedRun merged = merge_partials(parts);
  // The replay reads the inputs again: they must be the files the shards measured.
  for (const auto& in : merged.run.inputs) {
    std::uint64_t bytes = 0;
    std::string hash;
    try {
      hash = file_hash(in.path, &bytes);
    } catch (const RuntimeFailure&) {
      throw UsageError("input " + in.path + " of the shards' run cannot be read (merge in the folder "
                       "the shards ran in, with the same files)");
    }
    if (hash != in.hash || bytes != in.bytes)
      throw UsageError("input " + in.path + " changed since the shards ran (hash " + hash + ", the parts have " +
                       in.hash + ")");
  }
  std::vector<std::string> args;
  for (const auto& w : merged.run.command) args.push_back(w == kOutputPlaceholder ? o.output : w);
  if (g.threads > 0) {
    args.push_back("--threads");
    args.push_back(std::to_string(g.threads));
  }
  if (g.quiet) args.push_back("--quiet");
  TallyReplay replay(std::move(merged.entries));
  const int code = run_cli(args, &replay);
  if (code != 0) throw CommandExit{code};
  return 0;
}

}  // namespace

void register_merge(CLI::App& app, const GlobalOptions& g) {
  auto o = std::make_shared<MergeOptions>();
  auto* cmd = app.add_subcommand(
      "merge", "Merge the partial records of --shard K/N runs into the run's record (checks that "
               "they belong to one run and cover it exactly once)");
  cmd->add_option("parts", o->parts, "Partial records (OUTPUT.shard-K-of-N.json), all N of them")->required();
  cmd->add_option("-o,--output", o->output,
                  "Output of the merged run (any output the original command accepts)")
      ->required();
  cmd->callback([o, &g] { run_merge(*o, g); });
}

}  // namespace microsim::cli
