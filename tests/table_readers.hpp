// Readers of the RGL tensor (.bsdf) and MERL (.binary) formats written from the format
// descriptions (docs/theory/exports.md; [Dupuy18]), not from microsim's writers: they
// parse the bytes, rebuild the bilinear interpolants and warps, and evaluate, sample and give
// the density the way a renderer does.
#pragma once
#include <cmath>
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "microsim/common.hpp"

namespace microsim::testing {

struct Tensor {
  int dtype = 0;
  std::vector<std::uint64_t> shape;
  std::vector<float> f;          // dtype 10
  std::vector<std::uint8_t> u8;  // dtype 1
};

inline std::map<std::string, Tensor> read_tensor_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (b.size() < 18 || std::memcmp(b.data(), "tensor_file\0", 12) != 0) throw std::runtime_error("not a tensor file");
  if (b[12] != 1 || b[13] != 0) throw std::runtime_error("unknown tensor file version");
  std::size_t pos = 14;
  auto take = [&](std::size_t n) {
    if (pos + n > b.size()) throw std::runtime_error("truncated tensor file");
    const char* p = b.data() + pos;
    pos += n;
    return p;
  };
  auto u16 = [&] { std::uint16_t x; std::memcpy(&x, take(2), 2); return x; };
  auto u32 = [&] { std::uint32_t x; std::memcpy(&x, take(4), 4); return x; };
  auto u64 = [&] { std::uint64_t x; std::memcpy(&x, take(8), 8); return x; };
  std::map<std::string, Tensor> out;
  const std::uint32_t n = u32();
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint16_t len = u16();
    std::string name(take(len), len);
    const std::uint16_t ndim = u16();
    Tensor t;
    t.dtype = static_cast<std::uint8_t>(*take(1));
    const std::uint64_t offset = u64();
    std::uint64_t count = 1;
    for (int d = 0; d < ndim; ++d) {
      t.shape.push_back(u64());
      count *= t.shape.back();
    }
    const std::size_t bytes = count * (t.dtype == 10 ? 4 : 1);
    if (offset + bytes > b.size()) throw std::runtime_error("field " + name + " runs past the end");
    if (t.dtype == 10) {
      t.f.resize(count);
      std::memcpy(t.f.data(), b.data() + offset, bytes);
    } else {
      t.u8.assign(b.begin() + static_cast<std::ptrdiff_t>(offset), b.begin() + static_cast<std::ptrdiff_t>(offset + bytes));
    }
    out[name] = std::move(t);
  }
  return out;
}

// A 2D table of vertex values on [0, 1]^2 (rows along y, columns along x), bilinear between them.
struct Bilinear2 {
  const float* v = nullptr;
  int nx = 0, ny = 0;
  double at(int i, int j) const { return v[static_cast<std::size_t>(j) * nx + i]; }
  double operator()(double x, double y) const {
    x = std::clamp(x, 0.0, 1.0) * (nx - 1);
    y = std::clamp(y, 0.0, 1.0) * (ny - 1);
    const int i = std::min(static_cast<int>(x), nx - 2), j = std::min(static_cast<int>(y), ny - 2);
    const double a = x - i, c = y - j;
    return (1 - c) * ((1 - a) * at(i, j) + a * at(i + 1, j)) + c * ((1 - a) * at(i, j + 1) + a * at(i + 1, j + 1));
  }
};

// The inversion-method warp of a bilinear density: the marginal in y, then x given y.
struct Warp2 {
  Bilinear2 d;
  std::vector<double> rows;  // int_0^{x_i} of vertex row j, at [j * nx + i] (trapezoid: exact)
  std::vector<double> cum;   // int_0^{y_j} of the row integrals at the vertex rows
  explicit Warp2(Bilinear2 b) : d(b) {
    if (d.ny < 2) return;
    const double hx = 1.0 / (d.nx - 1), hy = 1.0 / (d.ny - 1);
    rows.assign(static_cast<std::size_t>(d.nx) * d.ny, 0.0);
    for (int j = 0; j < d.ny; ++j)
      for (int i = 1; i < d.nx; ++i)
        rows[static_cast<std::size_t>(j) * d.nx + i] =
            rows[static_cast<std::size_t>(j) * d.nx + i - 1] + 0.5 * (d.at(i - 1, j) + d.at(i, j)) * hx;
    cum.assign(static_cast<std::size_t>(d.ny), 0.0);
    for (int j = 1; j < d.ny; ++j)  // row integrals are linear in y between vertex rows
      cum[j] = cum[j - 1] + 0.5 * (row_total(j - 1) + row_total(j)) * hy;
  }
  double row_total(int j) const { return rows[static_cast<std::size_t>(j + 1) * d.nx - 1]; }
  double total() const { return cum.back(); }
  // int_0^x of the density's row at height y: the two vertex rows' integrals, blended.
  double integral_x(double x, double y) const {
    const double hx = 1.0 / (d.nx - 1), hy = 1.0 / (d.ny - 1);
    const int j = std::min(static_cast<int>(y / hy), d.ny - 2);
    const double t = y / hy - j;
    const int i = std::min(static_cast<int>(x / hx), d.nx - 2);
    const double x0 = i * hx;
    auto part = [&](int row) {  // trapezoid over [x0, x] of that row (linear there)
      const double f0 = d.at(i, row), f1 = d.at(i, row) + (d.at(i + 1, row) - d.at(i, row)) * (x - x0) / hx;
      return rows[static_cast<std::size_t>(row) * d.nx + i] + 0.5 * (f0 + f1) * (x - x0);
    };
    return (1 - t) * part(j) + t * part(j + 1);
  }
  double row_integral(double y) const { return integral_x(1.0, y); }
  double integral_y(double y) const {
    const double h = 1.0 / (d.ny - 1);
    const int j = std::min(static_cast<int>(y / h), d.ny - 2);
    const double r0 = row_total(j), r1 = row_total(j + 1), t = y / h - j;
    return cum[j] + h * (r0 * t + 0.5 * (r1 - r0) * t * t);
  }
  double pdf(const Vec2& p) const { return d(p.x(), p.y()) / total(); }
  // Point -> uniform square (the CDFs).
  Vec2 invert(const Vec2& p) const {
    const double y = std::clamp(p.y(), 0.0, 1.0), x = std::clamp(p.x(), 0.0, 1.0);
    const double row = row_integral(y);
    return Vec2(row > 0 ? integral_x(x, y) / row : x, integral_y(y) / total());
  }
  // Uniform square -> point, by bisection of the monotone CDFs (an independent route).
  Vec2 sample(const Vec2& s) const {
    double lo = 0, hi = 1;
    for (int k = 0; k < 50; ++k) {
      const double mid = 0.5 * (lo + hi);
      (integral_y(mid) / total() < s.y() ? lo : hi) = mid;
    }
    const double y = 0.5 * (lo + hi), row = row_integral(y);
    lo = 0;
    hi = 1;
    for (int k = 0; k < 50; ++k) {
      const double mid = 0.5 * (lo + hi);
      (integral_x(mid, y) / row < s.x() ? lo : hi) = mid;
    }
    return Vec2(0.5 * (lo + hi), y);
  }
};

// An RGL material at one measured incidence (phi_i index p, theta_i index t): eval, pdf, sample.
class RglReader {
 public:
  RglReader(const std::string& path, int p, int t) : f_(read_tensor_file(path)) {
    const Tensor& th = f_.at("theta_i");
    const Tensor& ph = f_.at("phi_i");
    iso_ = ph.shape[0] <= 2;
    theta_i_ = th.f[t];
    phi_i_ = ph.f[p];
    R_ = static_cast<int>(f_.at("vndf").shape[3]);
    const std::size_t slice = static_cast<std::size_t>(R_) * R_;
    const std::size_t inc = static_cast<std::size_t>(p) * th.shape[0] + t;
    ndf_ = grid("ndf", 0);
    sigma_ = grid("sigma", 0);
    vndf_ = Warp2(Bilinear2{f_.at("vndf").f.data() + inc * slice, R_, R_});
    lum_ = Warp2(Bilinear2{f_.at("luminance").f.data() + inc * slice, R_, R_});
    const std::size_t nw = f_.at("wavelengths").shape[0];
    spectra_ = Bilinear2{f_.at("spectra").f.data() + inc * nw * slice, R_, R_};
    jacobian_ = f_.at("jacobian").u8[0] != 0;
  }
  Vec3 wi() const { return direction_from_angles(theta_i_, phi_i_); }
  std::string description() const {
    const auto& d = f_.at("description").u8;
    return std::string(d.begin(), d.end());
  }
  void scale_spectra(double c) {
    for (float& x : f_.at("spectra").f) x = static_cast<float>(x * c);
  }

  // f cos(theta_o) for light from wi() to wo.
  double eval(const Vec3& wo) const {
    const Vec3 wi = this->wi();
    if (wo.z() <= 0) return 0.0;
    const Vec3 m = (wi + wo).normalized();
    const Vec2 um = u_of(m);
    const Vec2 s = vndf_.invert(um);
    double v = spectra_(s.x(), s.y());
    if (jacobian_) v *= ndf_(um.x(), um.y()) / (4.0 * sigma_(u_theta(theta_i_), u_phi(phi_i_)));
    return v;
  }
  // Solid-angle density of sample().
  double pdf(const Vec3& wo) const {
    if (wo.z() <= 0) return 0.0;
    const Vec3 m = (wi() + wo).normalized();
    const Vec2 um = u_of(m);
    const Vec2 s = vndf_.invert(um);
    return lum_.pdf(s) * vndf_.pdf(um) / jac(um, m);
  }
  // wo from two uniform numbers; returns false below the horizon.
  bool sample(const Vec2& xi, Vec3* wo, double* pdf) const {
    const Vec2 s = lum_.sample(xi);
    const Vec2 um = vndf_.sample(s);
    const Vec3 m = half_vector(um);
    *wo = 2.0 * wi().dot(m) * m - wi();
    *pdf = lum_.pdf(s) * vndf_.pdf(um) / jac(um, m);
    return wo->z() > 0;
  }
  // The sample grid (resolution() x resolution() vertices of `spectra`) and the outgoing
  // direction its vertex (i, j) stands for: the vndf warp's image of the vertex, reflected.
  int resolution() const { return R_; }
  Vec3 vertex_direction(int i, int j) const {
    const Vec2 um = vndf_.sample(Vec2(static_cast<double>(i) / (R_ - 1), static_cast<double>(j) / (R_ - 1)));
    const Vec3 m = half_vector(um);
    return 2.0 * wi().dot(m) * m - wi();
  }

 private:
  Vec3 half_vector(const Vec2& um) const {
    const double th = um.x() * um.x() * 0.5 * kPi;
    const double ph = (2 * um.y() - 1) * kPi + (iso_ ? phi_i_ : 0.0);
    return direction_from_angles(th, ph);
  }
  static double u_theta(double t) { return std::sqrt(t / (0.5 * kPi)); }
  static double u_phi(double p) { return (p + kPi) / (2 * kPi); }
  Vec2 u_of(const Vec3& m) const {
    const double th = 2.0 * std::asin(std::min(1.0, 0.5 * (m - Vec3::UnitZ()).norm()));
    double ph = std::atan2(m.y(), m.x()) - (iso_ ? phi_i_ : 0.0);
    double up = u_phi(ph);
    up -= std::floor(up);
    return Vec2(u_theta(th), up);
  }
  // d omega_o / du: (2 pi^2 u sin theta_m) (4 wi.m)
  double jac(const Vec2& um, const Vec3& m) const {
    return 2.0 * kPi * kPi * um.x() * std::sqrt(std::max(0.0, 1 - m.z() * m.z())) * 4.0 * wi().dot(m);
  }
  Bilinear2 grid(const char* name, std::size_t) const {
    const Tensor& t = f_.at(name);
    return Bilinear2{t.f.data(), static_cast<int>(t.shape[1]), static_cast<int>(t.shape[0])};
  }

  std::map<std::string, Tensor> f_;
  int R_ = 0;
  bool iso_ = true, jacobian_ = true;
  double theta_i_ = 0, phi_i_ = 0;
  Bilinear2 ndf_, sigma_, spectra_;
  Warp2 vndf_{Bilinear2{}}, lum_{Bilinear2{}};
};

// MERL .binary: f(wi, wo) per channel by the standard half/difference lookup.
class MerlReader {
 public:
  explicit MerlReader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::int32_t dims[3];
    in.read(reinterpret_cast<char*>(dims), sizeof(dims));
    if (!in || dims[0] != 90 || dims[1] != 90 || dims[2] != 180) throw std::runtime_error("not a MERL file");
    data_.resize(3u * 90 * 90 * 180);
    in.read(reinterpret_cast<char*>(data_.data()), static_cast<std::streamsize>(data_.size() * sizeof(double)));
    if (!in) throw std::runtime_error("truncated MERL file");
  }
  double f(const Vec3& wi, const Vec3& wo, int channel) const {
    const Vec3 h = (wi + wo).normalized();
    const double th = std::acos(std::clamp(h.z(), -1.0, 1.0)), ph = std::atan2(h.y(), h.x());
    // Difference vector: wi seen from the half vector's frame (rotate by -phi_h about z, then by
    // -theta_h about y).
    const Vec3 a(std::cos(-ph) * wi.x() - std::sin(-ph) * wi.y(), std::sin(-ph) * wi.x() + std::cos(-ph) * wi.y(), wi.z());
    const Vec3 d(std::cos(-th) * a.x() + std::sin(-th) * a.z(), a.y(), -std::sin(-th) * a.x() + std::cos(-th) * a.z());
    const double td = std::acos(std::clamp(d.z(), -1.0, 1.0));
    double pd = std::atan2(d.y(), d.x());
    if (pd < 0) pd += kPi;
    const int ih = std::clamp(static_cast<int>(std::sqrt(th / (0.5 * kPi)) * 90), 0, 89);
    const int id = std::clamp(static_cast<int>(td / (0.5 * kPi) * 90), 0, 89);
    const int ip = std::clamp(static_cast<int>(pd / kPi * 180), 0, 179);
    const double scale[3] = {1.0 / 1500, 1.15 / 1500, 1.66 / 1500};
    return data_[static_cast<std::size_t>(channel) * 90 * 90 * 180 + ip + 180 * (id + 90 * ih)] * scale[channel];
  }

 private:
  std::vector<double> data_;
};

}  // namespace microsim::testing
