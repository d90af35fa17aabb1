#include "microsim/models/energy_compensation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace microsim::models {

double directional_albedo_ss(const Ndf& ndf, double mu, int n) {
  mu = std::clamp(mu, kEssMuMin, 1.0);
  const Vec3 i(std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, mu);
  return single_scattering_albedos(ndf, Material::mirror(), i, n).smith.reflected;
}

double fresnel_average(const Material& material) {
  if (material.transmits()) throw std::invalid_argument("fresnel_average: opaque materials only");
  // F(mu) has a steep drop near grazing for conductors: 32 pieces of 8 Gauss nodes.
  return cosine_weighted_average([&](double mu) { return material.reflectance(mu, true); }, 32);
}

namespace {
// Cubic Hermite on [0, 1] between y0 and y1 with end slopes d0, d1 (per unit of t).
double hermite(double y0, double y1, double d0, double d1, double t) {
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * d1;
}
}  // namespace

EssTable::EssTable(const Ndf& ndf, int nodes, int quadrature_n) : ndf_(ndf), n_(quadrature_n) {
  if (nodes < 3) throw std::invalid_argument("EssTable: at least 3 nodes");
  e_.resize(nodes);
  for (int k = 0; k < nodes; ++k) {
    const double s = static_cast<double>(k) / (nodes - 1);
    e_[k] = directional_albedo_ss(ndf, s * s, n_);
  }
  // The interpolant times s^3 is of degree 6 on every interval: 8 Gauss nodes per interval integrate it exactly.
  e_avg_ = average([this](double mu) { return E(mu); });
}

double EssTable::E(double mu) const {
  const int N = static_cast<int>(e_.size());
  const double x = std::sqrt(std::clamp(mu, 0.0, 1.0)) * (N - 1);
  const int k = std::min(N - 2, static_cast<int>(x));
  const double t = x - k;
  // Catmull-Rom slopes (per node spacing), one-sided differences at the two ends.
  const auto slope = [&](int j) {
    if (j == 0) return e_[1] - e_[0];
    if (j == N - 1) return e_[N - 1] - e_[N - 2];
    return 0.5 * (e_[j + 1] - e_[j - 1]);
  };
  return hermite(e_[k], e_[k + 1], slope(k), slope(k + 1), t);
}

double EssTable::interpolation_error(int first) const {
  const int N = static_cast<int>(e_.size());
  double worst = 0.0;
  for (int k = std::max(0, first); k + 1 < N; ++k) {
    const double s = (k + 0.5) / (N - 1), mu = s * s;
    worst = std::max(worst, std::abs(E(mu) - directional_albedo_ss(ndf_, mu, n_)));
  }
  return worst;
}

KullaContyLobe::KullaContyLobe(const EssTable& t, const Material& material) : table(&t) {
  fresnel_factor = fresnel_factor_of(fresnel_average(material), t.E_avg());
}

double KullaContyLobe::fresnel_factor_of(double f_avg, double e_avg) {
  return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
}

double KullaContyLobe::eval(const Vec3& o, const Vec3& i) const {
  if (!(o.z() > 0.0) || !(i.z() > 0.0)) return 0.0;
  const double e_avg = table->E_avg();
  return fresnel_factor * (1.0 - table->E(o.z())) * (1.0 - table->E(i.z())) / (detail::kPi * (1.0 - e_avg));
}

double KullaContyLobe::albedo(double mu_i) const { return fresnel_factor * (1.0 - table->E(mu_i)); }

TurquinLobe::TurquinLobe(const EssTable& t, const Material& material)
    : table(&t), single{t.ndf(), material, Masking::SmithHeightCorrelated}, F0(material.reflectance(1.0, true)) {
  if (material.transmits()) throw std::invalid_argument("TurquinLobe: opaque materials only");
}

double TurquinLobe::scale(double mu_i) const {
  const double e = table->E(mu_i);
  return F0 * (1.0 - e) / e;
}

double TurquinLobe::eval(const Vec3& o, const Vec3& i) const {
  if (!(o.z() > 0.0) || !(i.z() > 0.0)) return 0.0;
  return scale(i.z()) * single.eval(o, i);
}

}  // namespace microsim::models
