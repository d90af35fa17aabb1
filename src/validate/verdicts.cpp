// Verdict rules of `microsim validate`: z, thresholds (Sidak, Student t), verdict per row.
#include "checks_common.hpp"

namespace microsim::validation {

const char* to_string(Kind k) {
  switch (k) {
    case Kind::Identity: return "identity";
    case Kind::Deterministic: return "deterministic";
    case Kind::Model: return "model";
    case Kind::Info: return "info";
  }
  return "info";
}

double sidak_z(double alpha, std::size_t k) {
  return microsim::sidak_z(alpha, static_cast<int>(std::min<std::size_t>(k, 1u << 30)));
}

Estimate proportion(std::uint64_t k, std::uint64_t n) {
  Estimate e = binomial_estimate(k, n);
  e.stderr_ = std::max(e.stderr_, proportion_floor(n));
  return e;
}

void set_chi2(Row& r, double chi2, int dof) {
  const double d = std::max(1, dof);
  r.measured = chi2 / d;
  r.stderr_ = std::sqrt(2.0 / d);
  r.model = 1.0;
}

Row albedo_total_row(std::uint64_t paths, std::uint64_t lost, std::uint64_t unterminated,
                     double albedo_up, double albedo_down) {
  Row e;
  e.quantity = "albedo_total";
  e.model_name = "one";
  e.kind = Kind::Deterministic;
  e.reference = "energy conservation of a mirror ([GeomBSDF24, eq. 21d] with F = 1): every path leaves";
  e.measured = albedo_up + albedo_down;
  e.model = 1.0;
  // Every path of `paths` that does not leave moves the total by 1/paths. Accepted: the loss
  // budget of the tracer, kMaxLostFraction of the paths (at least one path), plus half a path
  // for the rounding of the sums.
  const double n = static_cast<double>(paths);
  const double allowed = std::max(1.0, std::ceil(kMaxLostFraction * n));
  e.tolerance = paths > 0 ? (allowed + 0.5) / n : 0.0;
  std::ostringstream budget;
  budget << kMaxLostFraction;
  e.error = "exact (lost and unterminated paths counted; budget " + budget.str() +
            " of the paths, at least one)";
  e.extra = {{"paths", paths}, {"lost", lost}, {"unterminated", unterminated}};
  return e;
}

double assign_verdicts(std::vector<Row>& rows, double significance) {
  std::size_t tested = 0;
  for (const Row& r : rows)
    if ((r.kind == Kind::Identity || r.kind == Kind::Model) && r.model && r.stderr_) ++tested;
  const double zt = sidak_z(significance, tested);
  const int k = static_cast<int>(std::min<std::size_t>(std::max<std::size_t>(tested, 1), 1u << 30));
  std::map<int, double> t_threshold;  // by degrees of freedom
  for (Row& r : rows) {
    r.z.reset();
    r.rel_dev.reset();
    r.threshold.reset();
    if (r.model && *r.model != 0) r.rel_dev = (r.measured - *r.model) / std::abs(*r.model);
    const bool tests = (r.kind == Kind::Identity || r.kind == Kind::Model) && r.model && r.stderr_;
    if (tests) {
      const double diff = r.measured - *r.model;
      if (*r.stderr_ > 0) r.z = diff / *r.stderr_;
      else r.z = std::abs(diff) <= 1e-12 * std::max(1.0, std::abs(*r.model))
                     ? 0.0
                     : std::copysign(std::numeric_limits<double>::infinity(), diff);
      if (r.dof && *r.dof >= 1) {
        auto it = t_threshold.find(*r.dof);
        if (it == t_threshold.end())
          it = t_threshold.emplace(*r.dof, microsim::sidak_t(significance, k, *r.dof)).first;
        r.threshold = it->second;
      } else {
        r.threshold = zt;
      }
    }
    switch (r.kind) {
      case Kind::Deterministic:
        r.verdict = r.model && std::abs(r.measured - *r.model) <= r.tolerance ? "pass" : "FAIL";
        break;
      case Kind::Identity:
        r.verdict = tests && std::abs(*r.z) <= *r.threshold ? "pass" : "FAIL";
        break;
      case Kind::Model:
        r.verdict = !tests ? "measured" : std::abs(*r.z) <= *r.threshold ? "agrees" : "deviates (finding)";
        break;
      case Kind::Info: r.verdict = "measured"; break;
    }
  }
  return zt;
}

std::size_t Result::count(const std::string& verdict) const {
  return static_cast<std::size_t>(
      std::count_if(rows.begin(), rows.end(), [&](const Row& r) { return r.verdict == verdict; }));
}

}  // namespace microsim::validation
