#include "commands.hpp"

#include <sys/stat.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "microsim/io/output.hpp"
#include "microsim/measure/g1_measure.hpp"
#include "microsim/measure/ndf_measure.hpp"
#include "microsim/surface/surface_io.hpp"
#include "microsim/trace/tracer.hpp"

namespace microsim::cli {

namespace {

// A progress bar with ETA on a terminal; silent in pipes, CI and with --quiet.
class Progress {
 public:
  Progress(const std::string& label, bool quiet)
      : label_(label), enabled_(!quiet && isatty(STDERR_FILENO)),
        start_(std::chrono::steady_clock::now()) {}
  ~Progress() { finish(); }
  void update(double fraction) {
    if (!enabled_) return;
    double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0;
    int width = 30, filled = static_cast<int>(fraction * width);
    std::fprintf(stderr, "\r%s [%s%s] %3.0f%%  elapsed %.0fs  ETA %.0fs   ", label_.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 100 * fraction, elapsed, eta);
    std::fflush(stderr);
    shown_ = true;
  }
  void finish() {
    if (shown_) std::fprintf(stderr, "\n");
    shown_ = false;
  }

 private:
  std::string label_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_;
};

void require_extension(const std::string& path, std::initializer_list<const char*> allowed) {
  std::string ext = extension_of(path);
  std::string list;
  for (const char* a : allowed) {
    if (ext == a) return;
    list += std::string(list.empty() ? "" : ", ") + "." + a;
  }
  throw UsageError("-o " + path + ": unsupported output format (use " + list + ")");
}

void write_record(const std::string& path, const Json& j) {
  if (extension_of(path) == "csv") write_csv_rows(path, j);
  else write_json(path, j);
}

std::string fmt(double x, int precision = 4) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

Json run_header(const std::string& command, const GlobalOptions& g) {
  return {{"command", command},
          {"microsim_version", "0.1.0"},
          {"threads", g.threads > 0 ? g.threads : tbb::this_task_arena::max_concurrency()}};
}

}  // namespace

std::vector<double> parse_angle_list(const std::string& text, const std::string& option) {
  auto number = [&](const std::string& s) {
    try {
      std::size_t used = 0;
      double x = std::stod(s, &used);
      if (used != s.size()) throw std::invalid_argument(s);
      return x;
    } catch (const std::exception&) {
      throw UsageError(option + " '" + text + "': expected a number, a,b,c or start:stop:step");
    }
  };
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::stringstream ss(text);
    std::string p;
    while (std::getline(ss, p, ':')) parts.push_back(p);
    if (parts.size() != 3)
      throw UsageError(option + " '" + text + "': expected start:stop:step");
    double a = number(parts[0]), b = number(parts[1]), step = number(parts[2]);
    if (!(step > 0) || b < a) throw UsageError(option + " '" + text + "': need step > 0 and stop >= start");
    for (int k = 0; a + k * step <= b + 1e-9; ++k) out.push_back(a + k * step);
  } else {
    std::stringstream ss(text);
    std::string p;
    while (std::getline(ss, p, ',')) out.push_back(number(p));
  }
  if (out.empty()) throw UsageError(option + " is empty");
  return out;
}

int run_generate_gaussian(GenerateOptions o, const GlobalOptions& g) {
  if (o.alpha != -1) {
    if (o.alpha_x_given || o.alpha_y_given)
      throw UsageError("--alpha cannot be combined with --alpha-x/--alpha-y");
    o.gaussian.alpha_x = o.gaussian.alpha_y = o.alpha;
  } else if (o.alpha_x_given != o.alpha_y_given) {
    // One axis given: the other keeps the same value (isotropic unless both are given).
    if (o.alpha_x_given) o.gaussian.alpha_y = o.gaussian.alpha_x;
    else o.gaussian.alpha_x = o.gaussian.alpha_y;
  }
  validate(o.gaussian);
  std::string ext = extension_of(o.output);
  if (ext != "exr" && ext != "ply" && ext != "obj" && ext != "off")
    throw UsageError("-o " + o.output + ": unknown surface format (use .exr, .ply, .obj or .off)");
  Microsurface s = generate_gaussian(o.gaussian);
  save_surface(s, o.output);
  if (!g.quiet) {
    FacetSums f = facet_sums(s);
    std::cout << "wrote " << o.output << ": gaussian " << o.gaussian.resolution << "^2, alpha ("
              << o.gaussian.alpha_x << ", " << o.gaussian.alpha_y << "), fitted alpha ("
              << fmt(std::sqrt(2 * f.slope_var_x)) << ", " << fmt(std::sqrt(2 * f.slope_var_y))
              << ")\n";
  }
  return 0;
}

int run_convert(const std::string& input, const std::string& output, const GlobalOptions& g) {
  std::string ext = extension_of(output);
  if (ext != "exr" && ext != "ply" && ext != "obj" && ext != "off")
    throw UsageError("-o " + output + ": unknown surface format (use .exr, .ply, .obj or .off)");
  Microsurface s = load_surface(input);
  save_surface(s, output);
  if (!g.quiet) std::cout << "wrote " << output << " (" << s.num_facets() << " facets)\n";
  return 0;
}

int run_info(const std::string& path, const std::string& json_out, const GlobalOptions& g) {
  if (!json_out.empty()) require_extension(json_out, {"json"});
  Microsurface s = load_surface(path);
  FacetSums f = facet_sums(s);
  Json j = run_header("info", g);
  j["file"] = path;
  j["surface"] = s.description;
  j["kind"] = s.kind() == Microsurface::Kind::Heightfield ? "heightfield" : "mesh";
  j["facets"] = s.num_facets();
  j["macrosurface"] = {{"area", s.macro().area}, {"periodic", s.macro().periodic},
                       {"size_x", s.macro().size_x}, {"size_y", s.macro().size_y}};
  j["checks"] = surface_checks_json(f, s);
  if (!g.quiet) {
    const auto& c = j["checks"];
    std::cout << "surface      " << path << " (" << j["kind"].get<std::string>() << ", "
              << s.num_facets() << " facets)\n"
              << "description  " << s.description.dump() << "\n"
              << "macrosurface area " << s.macro().area << ", "
              << (s.macro().periodic ? "periodic tile " : "finite window ") << s.macro().size_x
              << " x " << s.macro().size_y << "\n"
              << "slope var    x " << c["slope_var_x"].get<double>() << ", y "
              << c["slope_var_y"].get<double>() << ", cov " << c["slope_cov_xy"].get<double>()
              << "\n"
              << "fitted alpha x " << fmt(c["fitted_alpha_x"].get<double>()) << ", y "
              << fmt(c["fitted_alpha_y"].get<double>());
    if (s.nominal)
      std::cout << "   (nominal " << models::to_string(s.nominal->kind) << " " << s.nominal->alpha_x
                << ", " << s.nominal->alpha_y << ")";
    std::cout << "\n000 eq. 1b   sum A_f m_f / A = " << c["eq_1b_sum_area_normal_over_A"].dump()
              << "  |error| " << c["eq_1b_error"].get<double>() << "\n"
              << "000 eq. 1c   sum A_f (n.m_f) / A = " << c["eq_1c_sum_area_cos_over_A"].get<double>()
              << "  |error| " << c["eq_1c_error"].get<double>() << "\n"
              << "area ratio   sum A_f / A = " << c["total_area_over_A"].get<double>() << "\n";
  }
  if (!json_out.empty()) write_json(json_out, j);
  return 0;
}

int run_measure_ndf(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv", "exr"});
  Microsurface s = load_surface(o.surface);
  NdfOptions no;
  no.n_theta = o.theta_bins;
  no.n_phi = o.phi_bins;
  auto t0 = std::chrono::steady_clock::now();
  NdfResult r = measure_ndf(s, no);
  if (extension_of(o.output) == "exr") {
    write_exr(o.output, ndf_to_exr(r, s));
  } else {
    Json j = ndf_to_json(r, s);
    j.update(run_header("measure ndf", g));
    j["file"] = o.surface;
    j["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_record(o.output, j);
  }
  if (!g.quiet) {
    Json c = surface_checks_json(r.sums, s);
    std::cout << "D of " << o.surface << " (phi-averaged rings; stderr from "
              << r.blocks * r.blocks << " spatial blocks)\n"
              << "000 eq. 1b |error| " << c["eq_1b_error"].get<double>() << ", eq. 1c |error| "
              << c["eq_1c_error"].get<double>() << "\n"
              << std::setw(12) << "theta_deg" << std::setw(14) << "D" << std::setw(12) << "stderr"
              << std::setw(14) << "nominal" << std::setw(9) << "z" << "\n";
    Json rows = ndf_to_json(r, s)["rows"];
    for (const auto& row : rows) {
      if (row["d"].get<double>() == 0 && (row["d_nominal"].is_null() || row["d_nominal"].get<double>() < 1e-6))
        continue;
      std::cout << std::setw(5) << fmt(row["theta_lo_deg"].get<double>(), 0) << "-" << std::setw(6)
                << std::left << fmt(row["theta_hi_deg"].get<double>(), 0) << std::right
                << std::setw(14) << fmt(row["d"].get<double>(), 5) << std::setw(12)
                << fmt(row["d_stderr"].get<double>(), 5);
      if (!row["d_nominal"].is_null())
        std::cout << std::setw(14) << fmt(row["d_nominal"].get<double>(), 5) << std::setw(9)
                  << fmt(row["z"].get<double>(), 2);
      std::cout << "\n";
    }
    std::cout << "wrote " << o.output << "\n";
  }
  return 0;
}

namespace {

// Mean over surfaces of a numeric field, with the between-surface standard error sd / sqrt(K).
std::pair<double, double> ensemble_stat(const std::vector<const Json*>& rows, const char* key) {
  double sum = 0, sum2 = 0;
  int k = 0;
  for (const Json* r : rows) {
    auto it = r->find(key);
    if (it == r->end() || !it->is_number()) continue;
    double x = it->get<double>();
    sum += x;
    sum2 += x * x;
    ++k;
  }
  if (k == 0) return {0.0, 0.0};
  double mean = sum / k;
  double var = k > 1 ? std::max(0.0, (sum2 - k * mean * mean) / (k - 1)) : 0.0;
  return {mean, std::sqrt(var / k)};
}

// Ensemble rows (DESIGN.md "Two kinds of error bar"): every field is the mean over surfaces;
// g1_stderr etc. are the between-surface standard errors, the ray-count ones are kept as
// *_stderr_rays. Bins are matched by their normal ranges.
Json ensemble_row(const std::vector<const Json*>& rows) {
  Json e;
  e["theta_deg"] = (*rows[0])["theta_deg"];
  e["phi_deg"] = (*rows[0])["phi_deg"];
  e["surfaces"] = rows.size();
  for (const char* key : {"g1", "g1_raycast", "visible_area_ratio", "smith_numeric"}) {
    auto [mean, se] = ensemble_stat(rows, key);
    e[key] = mean;
    e[std::string(key) + "_stderr"] = se;
    double rays2 = 0;
    for (const Json* r : rows) {
      auto it = r->find(std::string(key) + "_stderr");
      if (it != r->end()) rays2 += std::pow(it->get<double>(), 2);
    }
    if (key != std::string("smith_numeric"))
      e[std::string(key) + "_stderr_rays"] = std::sqrt(rays2) / rows.size();
  }
  e["smith_nominal"] = (*rows[0])["smith_nominal"];
  if (e["smith_nominal"].is_number()) {
    double model = e["smith_nominal"].get<double>(), se = e["g1_stderr"].get<double>();
    e["z_nominal"] = se > 0 ? (e["g1"].get<double>() - model) / se : 0.0;
    e["rel_dev_nominal"] = (e["g1"].get<double>() - model) / model;
  } else {
    e["z_nominal"] = nullptr;
    e["rel_dev_nominal"] = nullptr;
  }
  double se_num = e["g1_stderr"].get<double>();
  e["z_numeric"] = se_num > 0 ? (e["g1"].get<double>() - e["smith_numeric"].get<double>()) / se_num : 0.0;
  Json bins = Json::array();
  for (const auto& b0 : (*rows[0])["bins"]) {
    std::vector<const Json*> same;
    for (const Json* r : rows)
      for (const auto& b : (*r)["bins"])
        if (b["theta_m_range_deg"] == b0["theta_m_range_deg"] &&
            b["phi_m_range_deg"] == b0["phi_m_range_deg"])
          same.push_back(&b);
    Json eb;
    eb["theta_m_range_deg"] = b0["theta_m_range_deg"];
    eb["phi_m_range_deg"] = b0["phi_m_range_deg"];
    Vec3 m = Vec3::Zero();
    for (const Json* b : same) m += Vec3((*b)["m"][0], (*b)["m"][1], (*b)["m"][2]);
    m.normalize();
    eb["m"] = {m.x(), m.y(), m.z()};
    for (const char* key : {"area_fraction", "g1", "g1_raycast"}) {
      auto [mean, se] = ensemble_stat(same, key);
      eb[key] = mean;
      if (key != std::string("area_fraction")) eb[std::string(key) + "_stderr"] = se;
    }
    eb["surfaces"] = same.size();
    bins.push_back(eb);
  }
  e["bins"] = bins;
  return e;
}

void print_g1_table(const Json& rows, bool ensemble) {
  std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(10) << "g1"
            << std::setw(10) << "stderr" << std::setw(10) << "raycast" << std::setw(10)
            << "smith_num" << std::setw(8) << "z_num" << std::setw(10) << "smith_nom"
            << std::setw(10) << "rel_dev" << std::setw(9) << (ensemble ? "z_nom" : "vis_ar")
            << std::setw(8) << (ensemble ? "" : "max|z|") << "\n";
  for (const auto& row : rows) {
    std::cout << std::setw(7) << fmt(row["theta_deg"].get<double>(), 1) << std::setw(6)
              << fmt(row["phi_deg"].get<double>(), 0) << std::setw(10)
              << fmt(row["g1"].get<double>()) << std::setw(10)
              << fmt(row["g1_stderr"].get<double>(), 5) << std::setw(10)
              << fmt(row["g1_raycast"].get<double>()) << std::setw(10)
              << fmt(row["smith_numeric"].get<double>()) << std::setw(8)
              << fmt(row["z_numeric"].get<double>(), 2);
    if (!row["smith_nominal"].is_null())
      std::cout << std::setw(10) << fmt(row["smith_nominal"].get<double>()) << std::setw(9)
                << fmt(100 * row["rel_dev_nominal"].get<double>(), 2) << "%";
    else
      std::cout << std::setw(10) << "-" << std::setw(10) << "-";
    if (ensemble)
      std::cout << std::setw(9)
                << (row["z_nominal"].is_null() ? std::string("-") : fmt(row["z_nominal"].get<double>(), 2));
    else
      std::cout << std::setw(9) << fmt(row["visible_area_ratio"].get<double>()) << std::setw(8)
                << fmt(row["max_abs_z_estimators"].get<double>(), 2);
    std::cout << "\n";
  }
}

}  // namespace

int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  std::vector<double> thetas = parse_angle_list(o.theta, "--theta");
  std::vector<double> phis = parse_angle_list(o.phi, "--phi");
  for (double t : thetas)
    if (!(t >= 0 && t < 90))
      throw UsageError("--theta must be in [0, 90) degrees (got " + fmt(t, 2) + ")");
  if (o.rays <= 0) throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  std::vector<std::string> files = {o.surface};
  files.insert(files.end(), o.extra_surfaces.begin(), o.extra_surfaces.end());
  // Check every file before the long run starts.
  std::vector<Microsurface> first;
  first.push_back(load_surface(files[0]));
  for (std::size_t k = 1; k < files.size(); ++k) load_surface(files[k]);
  auto t0 = std::chrono::steady_clock::now();

  G1Options go;
  go.rays = static_cast<std::uint64_t>(o.rays);
  go.seed = o.seed;
  Json j = run_header("measure g1", g);
  j["file"] = files.size() == 1 ? Json(files[0]) : Json(files);
  j["surface"] = first[0].description;
  j["parameters"] = {{"theta", o.theta}, {"phi", o.phi}, {"rays", o.rays}, {"seed", o.seed},
                     {"normal_bins", {{"theta", go.normal_theta_bins}, {"phi", go.normal_phi_bins}}}};
  j["definitions"] = {
      {"g1", "area sampling: fraction of points, drawn by projected area A_f max(0,v.m_f), "
             "unoccluded toward v (DESIGN.md estimator b)"},
      {"g1_raycast", "visible projected area of first hits along -v / sum_f A_f max(0,v.m_f) "
                     "(estimator a)"},
      {"visible_area_ratio", "visible projected area / ((v.n) A)"},
      {"smith_numeric", "1/(1+Lambda), Lambda = sum_f A_f max(0,-v.m_f) / ((v.n) A)"},
      {"smith_nominal", "Smith G1 of the generator's nominal NDF (001 eq. 11 with alpha_o)"},
      {"stderr", files.size() == 1
                     ? "ray-count standard error of this one surface (binomial bound; stratified "
                       "sampling only lowers it)"
                     : "between-surface standard error (sd over surfaces / sqrt(K)); the ray-count "
                       "one is *_stderr_rays; per_surface holds each surface's own rows"}};
  Progress progress("measure g1", g.quiet);
  const std::size_t total = files.size() * thetas.size() * phis.size();
  std::size_t done = 0;
  go.progress = [&](double f) { progress.update((done + f) / total); };
  std::vector<Json> per_surface;
  TraceCounters counters;
  double build_seconds = 0;
  for (std::size_t k = 0; k < files.size(); ++k) {
    Microsurface s = k == 0 ? std::move(first[0]) : load_surface(files[k]);
    Tracer tracer(s);
    build_seconds += tracer.build_seconds();
    const FacetTable table = build_facet_table(s, g1_normal_binning(go));
    Json rows = Json::array();
    for (double p : phis)
      for (double t : thetas) {
        G1Result r = measure_g1(tracer, direction_from_angles(rad(t), rad(p)), go, &table);
        counters += r.counters;
        Json row = g1_row_json(r, s);
        row["theta_deg"] = t;  // exactly as requested (no round trip through radians)
        row["phi_deg"] = p;
        rows.push_back(row);
        ++done;
      }
    per_surface.push_back(rows);
  }
  progress.finish();
  j["build_seconds"] = build_seconds;
  if (files.size() == 1) {
    j["rows"] = per_surface[0];
  } else {
    Json rows = Json::array();
    for (std::size_t d = 0; d < per_surface[0].size(); ++d) {
      std::vector<const Json*> same;
      for (const auto& ps : per_surface) same.push_back(&ps[d]);
      rows.push_back(ensemble_row(same));
    }
    j["rows"] = rows;
    Json ps = Json::array();
    for (std::size_t k = 0; k < files.size(); ++k) ps.push_back({{"file", files[k]}, {"rows", per_surface[k]}});
    j["per_surface"] = ps;
  }
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["rays_per_second"] = counters.rays / wall;
  j["lost_rays"] = counters.lost_below + counters.unresolved;
  j["backface_hits"] = counters.backface_hits;
  write_record(o.output, j);
  if (!g.quiet) {
    std::cout << "G1 of " << (files.size() == 1 ? files[0] : std::to_string(files.size()) + " surfaces")
              << "  (" << go.rays << " rays per estimator and direction"
              << (files.size() > 1 ? "; stderr between surfaces" : "") << ")\n";
    print_g1_table(j["rows"], files.size() > 1);
    std::cout << "rays lost " << counters.lost_below + counters.unresolved << ", back-face hits "
              << counters.backface_hits << ", " << fmt(counters.rays / wall / 1e6, 2)
              << " Mrays/s; wrote " << o.output << "\n";
  }
  return 0;
}

int run_demo(GenerateOptions gen, MeasureOptions meas, const std::string& dir,
             const GlobalOptions& g) {
  if (mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw UsageError("--out-dir " + dir + ": cannot create the folder");
  gen.output = dir + "/surface.exr";
  run_generate_gaussian(gen, g);
  meas.surface = gen.output;
  meas.output = dir + "/ndf.json";
  if (!g.quiet) std::cout << "\n";
  run_measure_ndf(meas, g);
  meas.output = dir + "/g1.json";
  if (!g.quiet) std::cout << "\n";
  run_measure_g1(meas, g);
  return 0;
}

}  // namespace microsim::cli
