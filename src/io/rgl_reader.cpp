#include "microsim/io/rgl_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace microsim {

std::map<std::string, TensorField> read_tensor_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the table");
  const std::vector<char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto bad = [&](const std::string& why) { return UsageError(path + ": not an RGL tensor file (" + why + ")"); };
  if (b.size() < 18 || std::memcmp(b.data(), "tensor_file", 12) != 0) throw bad("no tensor_file header");
  if (b[12] != 1 || b[13] != 0) throw bad("version is not 1.0");
  std::size_t pos = 14;
  auto take = [&](std::size_t n) {
    if (n > b.size() - pos) throw bad("truncated header");
    const char* p = b.data() + pos;
    pos += n;
    return p;
  };
  auto get = [&](auto x) {
    std::memcpy(&x, take(sizeof x), sizeof x);
    return x;
  };
  std::map<std::string, TensorField> out;
  const std::uint32_t n = get(std::uint32_t(0));
  if (n > 4096) throw bad("implausible field count");
  for (std::uint32_t k = 0; k < n; ++k) {
    TensorField f;
    const std::uint16_t len = get(std::uint16_t(0));
    f.name.assign(take(len), len);
    const std::uint16_t ndim = get(std::uint16_t(0));
    f.dtype = get(std::uint8_t(0));
    const std::uint64_t offset = get(std::uint64_t(0));
    std::uint64_t count = 1;
    for (int d = 0; d < ndim; ++d) {
      f.shape.push_back(get(std::uint64_t(0)));
      if (f.shape.back() != 0 && count > b.size() / f.shape.back()) throw bad("field " + f.name + " larger than the file");
      count *= f.shape.back();
    }
    if (tensor_element_size(f.dtype) == 0) continue;  // other types: not used here
    const std::uint64_t bytes = count * tensor_element_size(f.dtype);
    if (offset > b.size() || bytes > b.size() - offset) throw bad("field " + f.name + " runs past the end");
    f.data.assign(b.begin() + static_cast<std::ptrdiff_t>(offset), b.begin() + static_cast<std::ptrdiff_t>(offset + bytes));
    out[f.name] = std::move(f);
  }
  return out;
}

namespace {

std::vector<float> floats(const TensorField& f) {
  std::vector<float> v(f.data.size() / 4);
  std::memcpy(v.data(), f.data.data(), v.size() * 4);
  return v;
}
double u_of_theta(double t) { return std::sqrt(std::max(0.0, t) * 2.0 / kPi); }
double u_of_phi(double p) { return (p + kPi) / (2.0 * kPi); }
// Polar angle without acos' cancellation near the pole (as the renderers compute it).
double elevation(const Vec3& d) { return 2.0 * std::asin(std::min(1.0, 0.5 * (d - Vec3::UnitZ()).norm())); }

// Index k in [0, n-2] and clamped weight of x between values[k] and values[k+1].
void interval(const std::vector<float>& values, double x, std::size_t* k, double* w) {
  const std::size_t n = values.size();
  if (n == 1) {
    *k = 0;
    *w = 0.0;
    return;
  }
  std::size_t i = 0;
  while (i + 2 < n && values[i + 1] < x) ++i;
  *k = i;
  *w = std::clamp((x - values[i]) / (values[i + 1] - values[i]), 0.0, 1.0);
}

}  // namespace

double RglMaterial::Grid::operator()(double x, double y, std::size_t offset) const {
  x = std::clamp(x, 0.0, 1.0) * (nx - 1);
  y = std::clamp(y, 0.0, 1.0) * (ny - 1);
  const int i = std::min(static_cast<int>(x), nx - 2), j = std::min(static_cast<int>(y), ny - 2);
  const double a = x - i, c = y - j;
  auto at = [&](int p, int q) { return static_cast<double>(v[offset + static_cast<std::size_t>(q) * nx + p]); };
  return (1 - c) * ((1 - a) * at(i, j) + a * at(i + 1, j)) + c * ((1 - a) * at(i, j + 1) + a * at(i + 1, j + 1));
}

RglMaterial::RglMaterial(const std::string& path) {
  const auto f = read_tensor_file(path);
  auto field = [&](const char* name, int ndim, int dtype) -> const TensorField& {
    auto it = f.find(name);
    if (it == f.end() || static_cast<int>(it->second.shape.size()) != ndim || it->second.dtype != dtype)
      throw UsageError(path + ": RGL field '" + name + "' missing or of the wrong shape");
    return it->second;
  };
  const TensorField& th = field("theta_i", 1, 10);
  const TensorField& ph = field("phi_i", 1, 10);
  const TensorField& wl = field("wavelengths", 1, 10);
  const TensorField& ndf = field("ndf", 2, 10);
  const TensorField& sigma = field("sigma", 2, 10);
  const TensorField& vndf = field("vndf", 4, 10);
  const TensorField& spectra = field("spectra", 5, 10);
  const TensorField& jac = field("jacobian", 1, 1);
  const TensorField& desc = field("description", 1, 1);
  theta_i_ = floats(th);
  phi_i_ = floats(ph);
  const std::size_t np = phi_i_.size(), nt = theta_i_.size();
  n_wavelengths_ = static_cast<int>(wl.shape[0]);
  res_ = static_cast<int>(vndf.shape[3]);
  if (np == 0 || nt == 0 || n_wavelengths_ == 0 || res_ < 2 || vndf.shape[0] != np || vndf.shape[1] != nt ||
      vndf.shape[2] != vndf.shape[3] || spectra.shape[0] != np || spectra.shape[1] != nt ||
      spectra.shape[2] != wl.shape[0] || spectra.shape[3] != vndf.shape[2] || spectra.shape[4] != vndf.shape[3] ||
      ndf.shape[0] < 2 || ndf.shape[1] < 2 || sigma.shape[0] < 2 || sigma.shape[1] < 2 || jac.shape[0] != 1)
    throw UsageError(path + ": RGL fields of inconsistent shapes");
  isotropic_ = np <= 2;
  if (!isotropic_ && std::abs(phi_i_.back() - phi_i_.front() - 2 * kPi) > 1e-3)
    throw UsageError(path + ": anisotropic table whose phi_i do not span the full circle (symmetry-reduced "
                     "tables are not supported)");
  jacobian_ = jac.data[0] != 0;
  description_.assign(desc.data.begin(), desc.data.end());
  ndf_ = Grid{floats(ndf), static_cast<int>(ndf.shape[1]), static_cast<int>(ndf.shape[0])};
  sigma_ = Grid{floats(sigma), static_cast<int>(sigma.shape[1]), static_cast<int>(sigma.shape[0])};
  const std::vector<float> vn = floats(vndf);
  const std::size_t slice = static_cast<std::size_t>(res_) * res_;
  for (std::size_t s = 0; s < np * nt; ++s)
    vndf_.emplace_back(std::vector<double>(vn.begin() + static_cast<std::ptrdiff_t>(s * slice),
                                           vn.begin() + static_cast<std::ptrdiff_t>((s + 1) * slice)),
                       res_, res_);
  spectra_ = Grid{floats(spectra), res_, res_};
}

RglMaterial::Blend RglMaterial::blend(double phi_i, double theta_i) const {
  std::size_t kp, kt;
  double wp, wt;
  interval(phi_i_, phi_i, &kp, &wp);
  interval(theta_i_, theta_i, &kt, &wt);
  const std::size_t nt = theta_i_.size();
  const std::size_t dp = phi_i_.size() > 1 ? 1 : 0, dt = nt > 1 ? 1 : 0;
  Blend b;
  for (int a = 0; a < 2; ++a)
    for (int c = 0; c < 2; ++c) {
      const double w = (a ? wp : 1 - wp) * (c ? wt : 1 - wt);
      if (w == 0.0) continue;
      b.slice[b.n] = (kp + a * dp) * nt + kt + c * dt;
      b.weight[b.n++] = w;
    }
  return b;
}

// The inverse of the interpolated warp: each table's CDFs normalized, then blended (the
// interpolated density's own CDFs, since all are linear in the table values).
Vec2 RglMaterial::invert_vndf(const Vec2& um, const Blend& b) const {
  const double x = std::clamp(um.x(), 0.0, 1.0), y = std::clamp(um.y(), 0.0, 1.0);
  double sy = 0, row = 0, sx = 0;
  for (int k = 0; k < b.n; ++k) {
    const BilinearWarp& w = vndf_[b.slice[k]];
    const double c = b.weight[k] / w.total();
    sy += c * w.marginal(y);
    row += c * w.row(y);
    sx += c * w.conditional(x, y);
  }
  return Vec2(row > 0 ? sx / row : x, sy);
}

double RglMaterial::eval(const Vec3& wi, const Vec3& wo) const {
  if (!(wi.z() > 0.0) || !(wo.z() > 0.0)) return 0.0;
  const Vec3 m = (wi + wo).normalized();
  const double theta_i = elevation(wi), phi_i = std::atan2(wi.y(), wi.x());
  const double theta_m = elevation(m), phi_m = std::atan2(m.y(), m.x());
  Vec2 um(u_of_theta(theta_m), u_of_phi(isotropic_ ? phi_m - phi_i : phi_m));
  um.y() -= std::floor(um.y());
  const Blend b = blend(phi_i, theta_i);
  const Vec2 s = invert_vndf(um, b);
  const std::size_t slice = static_cast<std::size_t>(res_) * res_;
  double value = 0.0;
  for (int k = 0; k < b.n; ++k)
    for (int l = 0; l < n_wavelengths_; ++l)
      value += b.weight[k] * spectra_(s.x(), s.y(), (b.slice[k] * n_wavelengths_ + l) * slice);
  value /= n_wavelengths_;
  if (jacobian_) value *= ndf_(um.x(), um.y()) / (4.0 * sigma_(u_of_theta(theta_i), u_of_phi(phi_i)));
  return std::max(0.0, value * scale_);
}

}  // namespace microsim
