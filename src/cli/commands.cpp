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

int run_measure_g1(const MeasureOptions& o, const GlobalOptions& g) {
  require_extension(o.output, {"json", "csv"});
  std::vector<double> thetas = parse_angle_list(o.theta, "--theta");
  std::vector<double> phis = parse_angle_list(o.phi, "--phi");
  for (double t : thetas)
    if (!(t >= 0 && t < 90))
      throw UsageError("--theta must be in [0, 90) degrees (got " + fmt(t, 2) + ")");
  if (o.rays <= 0) throw UsageError("--rays must be a positive integer (got " + std::to_string(o.rays) + ")");
  Microsurface s = load_surface(o.surface);
  auto t0 = std::chrono::steady_clock::now();
  Tracer tracer(s);

  G1Options go;
  go.rays = static_cast<std::uint64_t>(o.rays);
  go.seed = o.seed;
  Json j = run_header("measure g1", g);
  j["file"] = o.surface;
  j["surface"] = s.description;
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
      {"stderr", "ray-count standard error of this one surface (binomial bound; stratified "
                 "sampling only lowers it)"}};
  j["build_seconds"] = tracer.build_seconds();
  Progress progress("measure g1", g.quiet);
  std::size_t total = thetas.size() * phis.size(), done = 0;
  go.progress = [&](double f) { progress.update((done + f) / total); };
  const FacetTable table = build_facet_table(s, g1_normal_binning(go));
  Json rows = Json::array();
  TraceCounters counters;
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
  progress.finish();
  j["rows"] = rows;
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["wall_seconds"] = wall;
  j["total_rays"] = counters.rays;
  j["rays_per_second"] = counters.rays / wall;
  write_record(o.output, j);
  if (!g.quiet) {
    std::cout << "G1 of " << o.surface << "  (" << go.rays << " rays per estimator and direction)\n";
    std::cout << std::setw(7) << "theta" << std::setw(6) << "phi" << std::setw(10) << "g1"
              << std::setw(10) << "stderr" << std::setw(10) << "raycast" << std::setw(10)
              << "smith_num" << std::setw(8) << "z_num" << std::setw(10) << "smith_nom"
              << std::setw(10) << "rel_dev" << std::setw(9) << "vis_ar" << std::setw(8)
              << "max|z|" << "\n";
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
      std::cout << std::setw(9) << fmt(row["visible_area_ratio"].get<double>())
                << std::setw(8) << fmt(row["max_abs_z_estimators"].get<double>(), 2) << "\n";
    }
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
