// microsim generate KIND: build a microsurface and save it. The kinds and their options are the
// library's surface spec (surface/surface_spec.hpp); this file only registers them and prints.
#include <iostream>

#include "cli_common.hpp"
#include "commands.hpp"
#include "option_checks.hpp"

namespace microsim::cli {

void add_surface_options(CLI::App& cmd, const SurfaceKind& kind, SurfaceOptionValues& v) {
  using Type = SurfaceOption::Type;
  using Check = SurfaceOption::Check;
  for (const SurfaceOption& o : kind.options) {
    const std::string name = "--" + o.name;
    if (o.type == Type::Flag) {
      v.options[o.name] = cmd.add_flag(name, v.flags[o.name], o.help);
      continue;
    }
    std::string& text = v.text[o.name];
    text = o.default_text;
    CLI::Option* op = cmd.add_option(name, text, o.help);
    op->type_name(o.type == Type::Integer ? "INT" : o.type == Type::Number ? "FLOAT" : o.type == Type::Seed ? "UINT" : "TEXT");
    if (!o.default_text.empty()) op->capture_default_str();
    if (o.required) op->required();
    if (o.check == Check::Range) op->check(number_in(o.range));
    if (o.check == Check::Finite) op->check(finite_number());
    if (o.check == Check::Integer) op->check(integer_in(o.lo, o.hi));
    if (o.check == Check::Seed) op->check(seed_value());
    v.options[o.name] = op;
  }
}

SurfaceRequest given_surface_options(const SurfaceKind& kind, const SurfaceOptionValues& v) {
  SurfaceRequest r{kind.name, {}};
  for (const auto& [name, op] : v.options) {
    if (op->count() == 0) continue;  // given on the command line or in the preset
    auto flag = v.flags.find(name);
    r.options[name] = flag != v.flags.end() ? (flag->second ? "true" : "false") : v.text.at(name);
  }
  return r;
}

void write_generated(const SurfaceRequest& r, const std::string& path, const GlobalOptions& g) {
  Microsurface s = generate_surface(r, path);
  output_surface(g, s, path);
  const SurfaceReport report = surface_report(r, s, path, !g.quiet);
  for (const auto& w : report.warnings) std::cerr << "microsim: warning: " << w << "\n";
  if (g.quiet) return;
  std::cout << report.summary;
  for (const auto& n : report.notes) std::cerr << "microsim: warning: " << n << "\n";
}

void register_generate(CLI::App& app, const GlobalOptions& g) {
  auto* gen = app.add_subcommand("generate", "Generate a microsurface and save it (.exr, .ply, .obj, .off)");
  gen->require_subcommand(1);
  for (const SurfaceKind& kind : surface_kinds()) {
    auto* k = gen->add_subcommand(kind.name, kind.help);
    auto values = std::make_shared<SurfaceOptionValues>();
    auto out = std::make_shared<std::string>();
    // Every kind reads its preset the same way (option_checks.hpp); CLI11's own reader, which
    // heightmap used, left the keys of a subcommand's preset unapplied.
    add_preset_option(*k, kind.config_help);
    k->add_option("-o,--output", *out, kind.output_help)->required();
    add_surface_options(*k, kind, *values);
    const SurfaceKind* spec = &kind;
    auto run = [spec, values, out, &g] { write_generated(given_surface_options(*spec, *values), *out, g); };
    on_run(k, run);
  }
}

}  // namespace microsim::cli
