#include "microsim/io/rgl_bsdf.hpp"
#include "microsim/models/spectral_rgb.hpp"

#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "microsim/io/output.hpp"

namespace microsim {

// ---------------------------------------------------------------------------------------------
// Tensor file
// ---------------------------------------------------------------------------------------------

namespace {
// A field of dtype holding v's values as raw little-endian bytes (the host's order: x86-64, aarch64).
template <class T>
TensorField raw_field(const std::string& name, std::uint8_t dtype, std::vector<std::uint64_t> shape,
                      const std::vector<T>& v) {
  TensorField f;
  f.name = name;
  f.dtype = dtype;
  f.shape = std::move(shape);
  f.data.resize(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(f.data.data(), v.data(), f.data.size());
  return f;
}
}  // namespace

TensorField TensorField::f32(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<float>& v) {
  return raw_field(name, 10, std::move(shape), v);
}

TensorField TensorField::u8(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<std::uint8_t>& v) {
  return raw_field(name, 1, std::move(shape), v);
}

TensorField TensorField::u16(const std::string& name, std::vector<std::uint64_t> shape, const std::vector<std::uint16_t>& v) {
  return raw_field(name, 3, std::move(shape), v);
}

namespace {
template <class T>
void put(std::vector<std::uint8_t>& out, T x) {  // little-endian host (x86-64, aarch64)
  const auto* p = reinterpret_cast<const std::uint8_t*>(&x);
  out.insert(out.end(), p, p + sizeof(T));
}
}  // namespace

void write_tensor_file(const std::string& path, const std::vector<TensorField>& fields) {
  const char magic[12] = {'t', 'e', 'n', 's', 'o', 'r', '_', 'f', 'i', 'l', 'e', '\0'};
  std::vector<std::uint8_t> head(magic, magic + 12);
  put<std::uint8_t>(head, 1);
  put<std::uint8_t>(head, 0);
  put<std::uint32_t>(head, static_cast<std::uint32_t>(fields.size()));
  std::size_t header_size = head.size();
  for (const auto& f : fields) header_size += 2 + f.name.size() + 2 + 1 + 8 + 8 * f.shape.size();
  auto align = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
  std::uint64_t offset = align(header_size);
  std::vector<std::uint64_t> offsets;
  for (const auto& f : fields) {
    std::uint64_t count = 1;
    for (auto d : f.shape) count *= d;
    if (tensor_element_size(f.dtype) == 0 || count * tensor_element_size(f.dtype) != f.data.size())
      throw std::logic_error("tensor field " + f.name + ": shape does not match its data");
    put<std::uint16_t>(head, static_cast<std::uint16_t>(f.name.size()));
    head.insert(head.end(), f.name.begin(), f.name.end());
    put<std::uint16_t>(head, static_cast<std::uint16_t>(f.shape.size()));
    put<std::uint8_t>(head, f.dtype);
    put<std::uint64_t>(head, offset);
    for (auto d : f.shape) put<std::uint64_t>(head, d);
    offsets.push_back(offset);
    offset = align(offset + f.data.size());
  }
  write_stream_atomically(path, [&](std::ofstream& out) {
    std::vector<std::uint8_t> bytes = head;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      bytes.resize(offsets[k], 0);
      bytes.insert(bytes.end(), fields[k].data.begin(), fields[k].data.end());
    }
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

// ---------------------------------------------------------------------------------------------
// Bilinear warp
// ---------------------------------------------------------------------------------------------

BilinearWarp::BilinearWarp(std::vector<double> values, int nx, int ny) : v_(std::move(values)), nx_(nx), ny_(ny) {
  if (nx < 2 || ny < 2 || v_.size() != static_cast<std::size_t>(nx) * ny)
    throw std::invalid_argument("BilinearWarp needs at least 2 x 2 values");
  cond_.assign(v_.size(), 0.0);
  marg_.assign(static_cast<std::size_t>(ny), 0.0);
  for (int y = 0; y < ny; ++y)
    for (int x = 1; x < nx; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * nx + x;
      cond_[i] = cond_[i - 1] + 0.5 * (v_[i - 1] + v_[i]);  // exact: linear along x
    }
  for (int y = 1; y < ny; ++y)
    marg_[y] = marg_[y - 1] + 0.5 * (cond_[static_cast<std::size_t>(y) * nx - 1] +
                                     cond_[static_cast<std::size_t>(y + 1) * nx - 1]);
}

namespace {
// t in [0, 1] with c0 t + (c1 - c0) t^2 / 2 = r: the inverse CDF of a linear density, written
// without cancellation.
double solve_linear_cdf(double c0, double c1, double r) {
  const double disc = std::max(0.0, c0 * c0 + 2.0 * (c1 - c0) * r);
  const double den = c0 + std::sqrt(disc);
  if (!(den > 0)) return 0.0;
  return std::clamp(2.0 * r / den, 0.0, 1.0);
}
}  // namespace

Vec2 BilinearWarp::sample(const Vec2& s) const {
  const double total = marg_[ny_ - 1];
  const double ty = std::clamp(s.y(), 0.0, 1.0) * total;
  int j = static_cast<int>(std::upper_bound(marg_.begin(), marg_.end(), ty) - marg_.begin()) - 1;
  j = std::clamp(j, 0, ny_ - 2);
  const double T0 = cond_[static_cast<std::size_t>(j + 1) * nx_ - 1];
  const double T1 = cond_[static_cast<std::size_t>(j + 2) * nx_ - 1];
  const double t = solve_linear_cdf(T0, T1, ty - marg_[j]);
  const double tx = std::clamp(s.x(), 0.0, 1.0) * ((1 - t) * T0 + t * T1);
  auto G = [&](int i) {
    return (1 - t) * cond_[static_cast<std::size_t>(j) * nx_ + i] + t * cond_[static_cast<std::size_t>(j + 1) * nx_ + i];
  };
  int lo = 0, hi = nx_ - 2;  // last i with G(i) <= tx
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (G(mid) <= tx) lo = mid;
    else hi = mid - 1;
  }
  const int i = lo;
  auto v = [&](int x, int y) { return v_[static_cast<std::size_t>(y) * nx_ + x]; };
  const double c0 = (1 - t) * v(i, j) + t * v(i, j + 1), c1 = (1 - t) * v(i + 1, j) + t * v(i + 1, j + 1);
  const double tau = solve_linear_cdf(c0, c1, tx - G(i));
  return Vec2((i + tau) / (nx_ - 1), (j + t) / (ny_ - 1));
}

double BilinearWarp::pdf(const Vec2& p) const {
  const double x = std::clamp(p.x(), 0.0, 1.0) * (nx_ - 1), y = std::clamp(p.y(), 0.0, 1.0) * (ny_ - 1);
  const int i = std::min(static_cast<int>(x), nx_ - 2), j = std::min(static_cast<int>(y), ny_ - 2);
  const double fx = x - i, fy = y - j;
  auto v = [&](int a, int b) { return v_[static_cast<std::size_t>(b) * nx_ + a]; };
  const double val = (1 - fy) * ((1 - fx) * v(i, j) + fx * v(i + 1, j)) + fy * ((1 - fx) * v(i, j + 1) + fx * v(i + 1, j + 1));
  return val * (nx_ - 1) * (ny_ - 1) / marg_[ny_ - 1];
}

// Integrals in vertex-index units, as cond_ and marg_ are kept: within a cell the density is
// linear along each axis, so each partial integral is a quadratic in the cell fraction.
namespace {
void locate(double u, int n, int* k, double* f) {
  const double x = std::clamp(u, 0.0, 1.0) * (n - 1);
  *k = std::min(static_cast<int>(x), n - 2);
  *f = x - *k;
}
}  // namespace

double BilinearWarp::row(double y) const {
  int j;
  double t;
  locate(y, ny_, &j, &t);
  const double T0 = cond_[static_cast<std::size_t>(j + 1) * nx_ - 1], T1 = cond_[static_cast<std::size_t>(j + 2) * nx_ - 1];
  return (1 - t) * T0 + t * T1;
}

double BilinearWarp::marginal(double y) const {
  int j;
  double t;
  locate(y, ny_, &j, &t);
  const double T0 = cond_[static_cast<std::size_t>(j + 1) * nx_ - 1], T1 = cond_[static_cast<std::size_t>(j + 2) * nx_ - 1];
  return marg_[j] + T0 * t + 0.5 * (T1 - T0) * t * t;
}

double BilinearWarp::conditional(double x, double y) const {
  int i, j;
  double tau, t;
  locate(x, nx_, &i, &tau);
  locate(y, ny_, &j, &t);
  auto part = [&](int r) {
    const std::size_t b = static_cast<std::size_t>(r) * nx_;
    const double a = v_[b + i], c = v_[b + i + 1];
    return cond_[b + i] + a * tau + 0.5 * (c - a) * tau * tau;
  };
  return (1 - t) * part(j) + t * part(j + 1);
}

// ---------------------------------------------------------------------------------------------
// The table
// ---------------------------------------------------------------------------------------------

namespace {

double u_to_theta(double u) { return u * u * 0.5 * kPi; }
double u_to_phi(double u) { return (2.0 * u - 1.0) * kPi; }
double theta_to_u(double t) { return std::sqrt(std::max(0.0, t) * 2.0 / kPi); }
double phi_to_u(double p) { return (p + kPi) / (2.0 * kPi); }
// Polar angle without the cancellation of acos near the pole (the readers use the same form).
double elevation(const Vec3& d) { return 2.0 * std::asin(std::min(1.0, 0.5 * (d - Vec3::UnitZ()).norm())); }

// Bilinear lookup of a [rows = phi][cols = theta] table at (u_theta, u_phi), as the readers do.
double bilinear(const std::vector<float>& t, int nphi, int ntheta, double ut, double up) {
  const double x = std::clamp(ut, 0.0, 1.0) * (ntheta - 1), y = std::clamp(up, 0.0, 1.0) * (nphi - 1);
  const int i = std::min(static_cast<int>(x), ntheta - 2), j = std::min(static_cast<int>(y), nphi - 2);
  const double fx = x - i, fy = y - j;
  auto v = [&](int a, int b) { return static_cast<double>(t[static_cast<std::size_t>(b) * ntheta + a]); };
  return (1 - fy) * ((1 - fx) * v(i, j) + fx * v(i + 1, j)) + fy * ((1 - fx) * v(i, j + 1) + fx * v(i + 1, j + 1));
}

// The ndf's kernel in theta around vertex i: a tent of half-width w_i, the larger of the
// vertex spacing and kMinKernel. The u-grid crowds its vertices near the pole (theta = u^2
// pi/2: the first steps are hundredths of a degree), where a tent of one spacing would hold
// almost no facets; the angular floor keeps every vertex's estimate on many facets.
constexpr double kMinKernel = 1.5 * kPi / 180.0;
double kernel_width(int i, int n) {
  const double h = 1.0 / (n - 1);
  const double t = u_to_theta(i * h);
  const double lo = i > 0 ? t - u_to_theta((i - 1) * h) : 0.0, hi = i < n - 1 ? u_to_theta((i + 1) * h) - t : 0.0;
  return std::max({lo, hi, kMinKernel});
}
double kernel(double theta, double center, double w) { return std::max(0.0, 1.0 - std::abs(theta - center) / w); }
// int kernel(theta) sin(theta) d theta over [0, pi/2] (8-point Gauss-Legendre per side).
double kernel_weight(double center, double w) {
  static const double x8[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                               0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
  static const double w8[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                               0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  double sum = 0.0;
  for (int side : {-1, 1}) {
    const double a = side < 0 ? std::max(0.0, center - w) : center, b = side < 0 ? center : std::min(0.5 * kPi, center + w);
    if (!(b > a)) continue;
    for (int k = 0; k < 8; ++k) {
      const double t = 0.5 * (a + b) + 0.5 * (b - a) * x8[k];
      sum += 0.5 * (b - a) * w8[k] * kernel(t, center, w) * std::sin(t);
    }
  }
  return sum;
}

struct FacetNormals {
  std::vector<float> ax, ay, az;  // A_f m_f / A
};

FacetNormals facet_normals(const Microsurface& s) {
  FacetNormals f;
  const std::size_t n = s.num_facets();
  f.ax.resize(n);
  f.ay.resize(n);
  f.az.resize(n);
  const double inv_area = 1.0 / s.macro().area;
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) {
    const Vec3 c = 0.5 * s.facet(k).cross() * inv_area;  // area * normal / A
    f.ax[k] = static_cast<float>(c.x());
    f.ay[k] = static_cast<float>(c.y());
    f.az[k] = static_cast<float>(c.z());
  });
  return f;
}

double projected_area(const FacetNormals& f, const Vec3& w) {
  const float wx = static_cast<float>(w.x()), wy = static_cast<float>(w.y()), wz = static_cast<float>(w.z());
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, f.ax.size(), 1 << 14), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double acc) {
        float part = 0.0f;
        double sum = 0.0;
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
          part += std::max(0.0f, wx * f.ax[k] + wy * f.ay[k] + wz * f.az[k]);
          if ((k & 1023) == 1023) {
            sum += part;
            part = 0.0f;
          }
        }
        return acc + sum + part;
      },
      std::plus<double>());
}

// The incidences a reader interpolates between: one azimuth (isotropic) or azimuths over the
// full circle, both angle lists increasing.
void check_rgl_incidences(const BsdfTable& t) {
  if (t.phi_i.size() != 1) {
    const double lo = *std::min_element(t.phi_i.begin(), t.phi_i.end());
    const double hi = *std::max_element(t.phi_i.begin(), t.phi_i.end());
    if (std::abs(lo + kPi) > 1e-6 || std::abs(hi - kPi) > 1e-6)
      throw ParameterError("{phi_i}: an anisotropic .bsdf needs incidence azimuths over the full circle "
                           "from -180 to 180 degrees (e.g. {phi_i} -180:180:30), or one azimuth for an isotropic table");
  }
  for (std::size_t k = 1; k < t.theta_i.size(); ++k)
    if (!(t.theta_i[k] > t.theta_i[k - 1])) throw ParameterError("{theta_i} must be increasing for a .bsdf");
  for (std::size_t k = 1; k < t.phi_i.size(); ++k)
    if (!(t.phi_i[k] > t.phi_i[k - 1])) throw ParameterError("{phi_i} must be increasing for a .bsdf");
}

// A spectral conductor's wavelengths (the same for every incidence), else two equal ones.
std::vector<float> rgl_wavelengths(const BsdfTable& t) {
  if (t.results.front().wavelengths() == 0) return {360.0f, 830.0f};
  std::vector<float> nm;
  for (double x : t.results.front().options.wavelengths_nm) nm.push_back(static_cast<float>(x));
  return nm;
}

// sum_f (A_f / A) K_v(m_f) at every ndf vertex v (theta vertices at `center`, tents of `width`):
// one row when isotropic, else Np azimuth rows, each facet shared linearly between its two
// neighbouring rows. Empty when no facet faces up.
std::vector<double> ndf_kernel_sums(const FacetNormals& fn, const std::vector<double>& center,
                                    const std::vector<double>& width, bool isotropic, int Np) {
  const int Nt = static_cast<int>(center.size());
  const int rows = isotropic ? 1 : Np;
  using Acc = std::vector<double>;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, fn.ax.size(), 1 << 12), Acc(),
      [&](const tbb::blocked_range<std::size_t>& r, Acc a) {
        if (a.empty()) a.assign(static_cast<std::size_t>(rows) * Nt, 0.0);
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
          const Vec3 v(fn.ax[k], fn.ay[k], fn.az[k]);
          const double w = v.norm();  // A_f / A
          if (!(w > 0) || v.z() <= 0) continue;  // the format holds the upper hemisphere only
          const Vec3 m = v / w;
          const double th = elevation(m);
          int j = 0;
          double fy = 0.0;
          if (!isotropic) {
            const double y = phi_to_u(std::atan2(m.y(), m.x())) * (Np - 1);
            j = std::clamp(static_cast<int>(y), 0, Np - 2);
            fy = std::clamp(y - j, 0.0, 1.0);
          }
          for (int i = 0; i < Nt; ++i) {
            const double kw = w * kernel(th, center[i], width[i]);
            if (kw == 0.0) continue;
            if (isotropic) {
              a[i] += kw;
            } else {
              a[static_cast<std::size_t>(j) * Nt + i] += kw * (1 - fy);
              a[static_cast<std::size_t>(j + 1) * Nt + i] += kw * fy;
            }
          }
        }
        return a;
      },
      [](Acc a, const Acc& b) {
        if (a.empty()) return b;
        for (std::size_t k = 0; k < b.size(); ++k) a[k] += b[k];
        return a;
      });
}

// D at the Np x Nt vertices from the kernel sums: each divided by its kernel's integral over the
// azimuths it stands for (2 pi isotropic, one phi cell otherwise), then floored at ndf_floor
// times the maximum so that every half vector has a finite spectra value.
std::vector<float> ndf_from_kernel_sums(std::vector<double> a, const std::vector<double>& center,
                                        const std::vector<double>& width, bool isotropic, int Np,
                                        double ndf_floor) {
  const int Nt = static_cast<int>(center.size());
  std::vector<float> ndf(static_cast<std::size_t>(Np) * Nt, 0.0f);
  if (isotropic) {
    for (int i = 0; i < Nt; ++i) {
      const float d = static_cast<float>(a[i] / (2.0 * kPi * kernel_weight(center[i], width[i])));
      ndf[i] = ndf[Nt + i] = d;
    }
  } else {
    // phi = -pi and +pi are one azimuth: merge the two edge rows; the tent in phi then spans
    // a full cell, 2 pi / (Np - 1).
    for (int i = 0; i < Nt; ++i) {
      const double e = a[i] + a[static_cast<std::size_t>(Np - 1) * Nt + i];
      a[i] = a[static_cast<std::size_t>(Np - 1) * Nt + i] = e;
    }
    for (int j = 0; j < Np; ++j)
      for (int i = 0; i < Nt; ++i)
        ndf[static_cast<std::size_t>(j) * Nt + i] = static_cast<float>(
            a[static_cast<std::size_t>(j) * Nt + i] / (2.0 * kPi / (Np - 1) * kernel_weight(center[i], width[i])));
    // theta = 0 is one direction for every phi: its azimuthal mean.
    double pole = 0.0;
    for (int j = 0; j < Np - 1; ++j) pole += ndf[static_cast<std::size_t>(j) * Nt];
    for (int j = 0; j < Np; ++j) ndf[static_cast<std::size_t>(j) * Nt] = static_cast<float>(pole / (Np - 1));
  }
  const float floor = static_cast<float>(ndf_floor * *std::max_element(ndf.begin(), ndf.end()));
  for (float& d : ndf) d = std::max(d, floor);
  return ndf;
}

// ndf: kernel estimate from the facet normals (tent in theta, see kernel_width; tent of one
// vertex spacing in phi when anisotropic): D(v) = sum_f (A_f / A) K_v(m_f) / int K_v d omega.
void fill_rgl_ndf(RglTable& out, const FacetNormals& fn, const RglOptions& o) {
  // Anisotropic: at most 17 azimuth vertices (22.5 degrees apart): finer phi tents hold too few
  // facets of one tile, and the reader's f cos / D interpolation turns the noise of D into
  // bias (the mean of 1/D over noisy neighbours exceeds 1/D).
  const int Nt = o.ndf_resolution, Np = out.isotropic ? 2 : std::min(o.ndf_resolution, 17);
  out.ndf_theta = Nt;
  out.ndf_phi = Np;
  std::vector<double> width(Nt), center(Nt);
  for (int i = 0; i < Nt; ++i) {
    center[i] = u_to_theta(static_cast<double>(i) / (Nt - 1));
    width[i] = kernel_width(i, Nt);
  }
  std::vector<double> sums = ndf_kernel_sums(fn, center, width, out.isotropic, Np);
  if (sums.empty()) throw UsageError("the surface has no upward-facing facets");
  out.ndf = ndf_from_kernel_sums(std::move(sums), center, width, out.isotropic, Np, o.ndf_floor);
}

// sigma: exact projected area at each vertex direction (isotropic: averaged over 16 azimuths).
void fill_rgl_sigma(RglTable& out, const FacetNormals& fn, const RglOptions& o) {
  const int St = o.sigma_resolution, Sp = out.isotropic ? 2 : o.sigma_resolution;
  out.sigma_theta = St;
  out.sigma_phi = Sp;
  out.sigma.assign(static_cast<std::size_t>(Sp) * St, 0.0f);
  for (int i = 0; i < St; ++i) {
    const double theta = u_to_theta(static_cast<double>(i) / (St - 1));
    if (out.isotropic) {
      double sum = 0.0;
      const int naz = i == 0 ? 1 : 16;
      for (int a = 0; a < naz; ++a) sum += projected_area(fn, direction_from_angles(theta, 2 * kPi * (a + 0.5) / naz));
      out.sigma[i] = out.sigma[St + i] = static_cast<float>(sum / naz);
    } else {
      for (int j = 0; j < Sp; ++j)
        out.sigma[static_cast<std::size_t>(j) * St + i] = static_cast<float>(
            projected_area(fn, direction_from_angles(theta, u_to_phi(static_cast<double>(j) / (Sp - 1)))));
    }
  }
}

// The measured light of one incidence (p, q) as the table stores it: f at wo, all orders, of
// every wavelength into f_l and the luminance returned (wavelength independent: f itself).
struct IncidenceLight {
  const BsdfTable& t;
  int p, q, L;
  const std::optional<models::SpectrumToRgb>& colour;
  std::vector<double> f_l;
  Vec3 wi;
  double phi_ref;  // azimuth of u_phi = 1/2: the incidence's when isotropic (phi_m - phi_i stored)

  IncidenceLight(const BsdfTable& table, int p_, int q_, int L_, bool isotropic,
                 const std::optional<models::SpectrumToRgb>& c)
      : t(table), p(p_), q(q_), L(L_), colour(c), f_l(std::max(L_, 1)),
        wi(direction_from_angles(table.theta_i[q_], table.phi_i[p_])),
        phi_ref(isotropic ? table.phi_i[p_] : 0.0) {}
  double f(const Vec3& wo) {
    const int K = t.at(p, q).options.orders;
    if (L == 0) return table_f(t, p, q, 0, K, wo);
    for (int l = 0; l < L; ++l) f_l[l] = table_f(t, p, q, 0, K, wo, l);
    return colour->luminance(f_l.data());
  }
  Vec3 half_vector(double ut, double up) const {
    return direction_from_angles(u_to_theta(ut), u_to_phi(up) + phi_ref);
  }
};

// The vndf warp's density over the R x R u-grid: the facets' visible normals, D <wi.m> d omega /
// du, the half vectors of the measured reflected light, f cos(theta_o) d omega_o / du, and of
// outgoing directions uniform over the hemisphere, d omega_o / du; mixed by RglOptions' shares.
std::vector<double> vndf_mixture(const RglTable& out, IncidenceLight& light, const RglOptions& o) {
  const int R = out.resolution;
  const std::size_t slice = static_cast<std::size_t>(R) * R;
  const Vec3& wi = light.wi;
  std::vector<double> vis(slice, 0.0), lit(slice, 0.0), all(slice, 0.0);
  double sum_vis = 0.0, sum_lit = 0.0, sum_all = 0.0;
  for (int j = 0; j < R; ++j)
    for (int i = 0; i < R; ++i) {
      const double ut = static_cast<double>(i) / (R - 1), up = static_cast<double>(j) / (R - 1);
      const Vec3 m = light.half_vector(ut, up);
      const double jac = 2.0 * kPi * kPi * ut * std::sin(u_to_theta(ut));  // d omega_m / du
      const double wm = std::max(0.0, wi.dot(m));
      const std::size_t k = static_cast<std::size_t>(j) * R + i;
      vis[k] = bilinear(out.ndf, out.ndf_phi, out.ndf_theta, ut, up) * wm * jac;
      const Vec3 wo = 2.0 * wi.dot(m) * m - wi;
      if (wo.z() > 0) {
        lit[k] = light.f(wo) * wo.z() * 4.0 * wm * jac;
        all[k] = 4.0 * wm * jac;
      }
      sum_vis += vis[k];
      sum_lit += lit[k];
      sum_all += all[k];
    }
  std::vector<double> vn(slice);
  for (std::size_t k = 0; k < slice; ++k)
    vn[k] = (1.0 - o.measured_share - o.uniform_share) * vis[k] / sum_vis +
            (sum_lit > 0 ? o.measured_share * lit[k] / sum_lit : 0.0) + o.uniform_share * all[k] / sum_all;
  return vn;
}

// spectra, luminance (and rgb of a spectral conductor) of one incidence at every sample-square
// vertex s: wm = warp(s), wo = reflect(wi, wm), the measured f cos(theta_o) times
// 4 sigma(u_wi) / ndf(u_m) as the reader interpolates them; 0 below the horizon.
void fill_rgl_spectra(RglTable& out, IncidenceLight& light, const BilinearWarp& warp, double sig) {
  const int R = out.resolution, nt = static_cast<int>(out.theta_i.size()), L = light.L;
  const std::size_t slice = static_cast<std::size_t>(R) * R, nl = out.wavelengths.size();
  const std::size_t incidence = static_cast<std::size_t>(light.p) * nt + light.q;
  std::vector<double>& f_l = light.f_l;
  for (int j = 0; j < R; ++j)
    for (int i = 0; i < R; ++i) {
      const Vec2 um = warp.sample(Vec2(static_cast<double>(i) / (R - 1), static_cast<double>(j) / (R - 1)));
      const Vec3 m = light.half_vector(um.x(), um.y());
      const Vec3 wo = 2.0 * light.wi.dot(m) * m - light.wi;
      double value = 0.0;
      std::fill(f_l.begin(), f_l.end(), 0.0);
      if (wo.z() > 0) {
        const double D = bilinear(out.ndf, out.ndf_phi, out.ndf_theta, um.x(), um.y());
        value = light.f(wo) * wo.z() * 4.0 * sig / D;
        for (int l = 0; l < L; ++l) f_l[l] = f_l[l] * wo.z() * 4.0 * sig / D;
      }
      const std::size_t k = static_cast<std::size_t>(j) * R + i;
      out.luminance[incidence * slice + k] = static_cast<float>(value);
      const std::size_t sb = incidence * nl * slice;
      if (L == 0) {
        out.spectra[sb + k] = out.spectra[sb + slice + k] = static_cast<float>(value);
        continue;
      }
      for (int l = 0; l < L; ++l) out.spectra[sb + l * slice + k] = static_cast<float>(f_l[l]);
      const auto c = light.colour->rgb(f_l.data());
      const std::size_t cb = incidence * 3 * slice;
      for (int ch = 0; ch < 3; ++ch) out.rgb[cb + ch * slice + k] = static_cast<float>(c[ch]);
    }
}

// vndf, spectra and luminance of incidence (p, q); out's ndf and sigma are filled.
void fill_rgl_incidence(RglTable& out, IncidenceLight& light, const RglOptions& o) {
  const int R = out.resolution, nt = static_cast<int>(out.theta_i.size());
  const std::size_t slice = static_cast<std::size_t>(R) * R;
  const std::vector<double> vn = vndf_mixture(out, light, o);
  const std::size_t base = (static_cast<std::size_t>(light.p) * nt + light.q) * slice;
  for (std::size_t k = 0; k < slice; ++k) out.vndf[base + k] = static_cast<float>(vn[k]);
  // The warp as the reader builds it: from the float values in the file.
  std::vector<double> vf(slice);
  for (std::size_t k = 0; k < slice; ++k) vf[k] = out.vndf[base + k];
  const BilinearWarp warp(std::move(vf), R, R);
  const BsdfTable& t = light.t;
  const double sig = bilinear(out.sigma, out.sigma_phi, out.sigma_theta, theta_to_u(t.theta_i[light.q]),
                              phi_to_u(t.phi_i[light.p]));
  fill_rgl_spectra(out, light, warp, sig);
}

}  // namespace

RglTable build_rgl_table(const BsdfTable& t, const Microsurface& s, const RglOptions& o) {
  if (o.resolution < 2 || o.ndf_resolution < 2 || o.sigma_resolution < 2)
    throw ParameterError("{table_resolution} must be at least 2");
  check_rgl_incidences(t);
  RglTable out;
  out.isotropic = t.phi_i.size() == 1;
  const int R = o.resolution, nt = static_cast<int>(t.theta_i.size()), np = static_cast<int>(t.phi_i.size());
  out.resolution = R;
  out.description = o.description;
  for (double x : t.theta_i) out.theta_i.push_back(static_cast<float>(x));
  for (double x : t.phi_i) out.phi_i.push_back(static_cast<float>(x));
  out.wavelengths = rgl_wavelengths(t);
  const int L = t.results.front().wavelengths();
  std::optional<models::SpectrumToRgb> colour;
  if (L > 0) colour.emplace(t.results.front().options.wavelengths_nm);

  const FacetNormals fn = facet_normals(s);
  fill_rgl_ndf(out, fn, o);
  fill_rgl_sigma(out, fn, o);

  const std::size_t slice = static_cast<std::size_t>(R) * R;
  out.vndf.assign(static_cast<std::size_t>(np) * nt * slice, 0.0f);
  out.luminance.assign(out.vndf.size(), 0.0f);
  out.spectra.assign(static_cast<std::size_t>(np) * nt * out.wavelengths.size() * slice, 0.0f);
  if (L > 0) out.rgb.assign(static_cast<std::size_t>(np) * nt * 3 * slice, 0.0f);
  for (int p = 0; p < np; ++p)
    for (int q = 0; q < nt; ++q) {
      IncidenceLight light(t, p, q, L, out.isotropic, colour);
      fill_rgl_incidence(out, light, o);
    }
  return out;
}

std::vector<TensorField> RglTable::fields() const {
  using U = std::uint64_t;
  const U np = phi_i.size(), nt = theta_i.size(), R = static_cast<U>(resolution);
  std::vector<std::uint8_t> text(description.begin(), description.end());
  std::vector<float> grey;
  const std::size_t slice = R * R, nl = wavelengths.size();
  if (rgb.empty())
    for (std::size_t s = 0; s < np * nt; ++s)
      for (int c = 0; c < 3; ++c)
        grey.insert(grey.end(), spectra.begin() + static_cast<std::ptrdiff_t>(s * nl * slice),
                    spectra.begin() + static_cast<std::ptrdiff_t>(s * nl * slice + slice));
  return {TensorField::u8("description", {text.size()}, text),
          TensorField::u8("jacobian", {1}, {1}),
          TensorField::f32("theta_i", {nt}, theta_i),
          TensorField::f32("phi_i", {np}, phi_i),
          TensorField::f32("wavelengths", {wavelengths.size()}, wavelengths),
          TensorField::f32("ndf", {static_cast<U>(ndf_phi), static_cast<U>(ndf_theta)}, ndf),
          TensorField::f32("sigma", {static_cast<U>(sigma_phi), static_cast<U>(sigma_theta)}, sigma),
          TensorField::f32("vndf", {np, nt, R, R}, vndf),
          TensorField::f32("luminance", {np, nt, R, R}, luminance),
          TensorField::f32("spectra", {np, nt, wavelengths.size(), R, R}, spectra),
          TensorField::f32("rgb", {np, nt, 3, R, R}, rgb.empty() ? grey : rgb)};
}

void write_rgl_bsdf(const std::string& path, const RglTable& table) { write_tensor_file(path, table.fields()); }

}  // namespace microsim
