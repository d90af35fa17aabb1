#include "output_paths.hpp"

#include <filesystem>
#include <system_error>

#include "scaleout.hpp"
#include "microsim/common.hpp"
#include "microsim/io/output.hpp"

namespace microsim::cli {

namespace {

namespace fs = std::filesystem;

bool is_mesh_file(const std::string& path) {
  const std::string e = extension_of(path);
  return e == "ply" || e == "obj" || e == "off";
}

// measure bsdf and measure albedo write their record beside a table: the same name, .json
// (measure albedo's lookup table also its rows, .csv).
std::string file_beside(const std::string& path, const std::string& ext) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "." + ext;
  return path.substr(0, dot + 1) + ext;
}
std::string record_beside(const std::string& path) { return file_beside(path, "json"); }

// The option's value(s): what was given, else its default (demo's --out-dir).
std::vector<std::string> values_of(const CLI::Option& op) {
  if (op.count() > 0) return op.results();
  const std::string d = op.get_default_str();
  return d.empty() ? std::vector<std::string>{} : std::vector<std::string>{d};
}

bool is_output_option(const CLI::Option& op) {
  for (const char* name : {"--output", "--json", "--out-dir", "--surfaces-dir"})
    if (op.check_name(name)) return true;
  return false;
}

// "-o" for -o/--output, else the option's long name, or a positional argument's name.
std::string option_label(const CLI::Option& op) {
  if (op.check_name("-o")) return "-o";
  return op.get_name();
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  const bool same = fs::equivalent(a, b, ec);  // both exist (symbolic links followed)
  return !ec && same;
}

}  // namespace

std::vector<NamedPath> command_outputs(const CLI::App& cmd, const std::string& shard_text) {
  const bool measure = cmd.get_parent() && cmd.get_parent()->get_name() == "measure";
  const bool bsdf = measure && cmd.get_name() == "bsdf";
  const bool albedo = measure && cmd.get_name() == "albedo";
  std::vector<NamedPath> out;
  for (const CLI::Option* op : cmd.get_options()) {
    if (!is_output_option(*op)) continue;
    const std::string label = option_label(*op);
    for (const std::string& v : values_of(*op)) {
      if (op->check_name("--surfaces-dir")) continue;  // file names come from the suite
      if (op->check_name("--out-dir")) {
        for (const char* name : {"surface.exr", "ndf.json", "g1.json"})
          out.push_back({label + " " + v + ": its " + name, (fs::path(v) / name).string()});
        continue;
      }
      out.push_back({label, v});
      if (is_mesh_file(v)) out.push_back({label + " " + v + ": its sidecar", v + ".json"});
      if ((bsdf || albedo) && extension_of(v) != "json") out.push_back({label + " " + v + ": its record", record_beside(v)});
      if (albedo && extension_of(v) == "exr") out.push_back({label + " " + v + ": its rows", file_beside(v, "csv")});
      if (!shard_text.empty()) {
        try {
          const auto [k, n] = parse_shard(shard_text);
          out.push_back({label + " " + v + ": its shard record", shard_path(v, k, n)});
        } catch (const UsageError&) {
          // the malformed --shard is reported where it is parsed
        }
      }
    }
  }
  return out;
}

std::vector<NamedPath> command_inputs(const CLI::App& cmd) {
  std::vector<NamedPath> in;
  for (const CLI::App* level = &cmd; level; level = level->get_parent())
    for (const CLI::Option* op : level->get_options()) {
      if (is_output_option(*op) || op->get_type_size() == 0 || op->count() == 0) continue;  // flags
      for (const std::string& v : op->results()) {
        std::error_code ec;
        if (v.empty() || !fs::is_regular_file(v, ec)) continue;
        in.push_back({option_label(*op), v});
        if (is_mesh_file(v) && fs::is_regular_file(v + ".json", ec))
          in.push_back({option_label(*op) + " " + v + ": its sidecar", v + ".json"});
      }
    }
  return in;
}

void refuse_outputs_naming_inputs(const CLI::App& app, const std::string& shard_text) {
  const CLI::App* leaf = &app;
  while (!leaf->get_subcommands().empty()) leaf = leaf->get_subcommands().front();
  const CLI::App& cmd = *leaf;
  const std::vector<NamedPath> inputs = command_inputs(cmd);
  if (inputs.empty()) return;
  for (const NamedPath& o : command_outputs(cmd, shard_text))
    for (const NamedPath& i : inputs)
      if (same_file(o.path, i.path))
        throw UsageError(o.option + " " + o.path + " is the input " + i.option + " " + i.path +
                         " (the same file): writing it would replace what the command reads; "
                         "choose another output");
}

}  // namespace microsim::cli
