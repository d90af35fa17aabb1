#include "microsim/render/sphere_preview.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "microsim/models/smith_walk_eval.hpp"

namespace microsim::render {

namespace {
// Cosine-weighted direction about +z (density cos(theta) / pi).
Vec3 cosine_direction(CounterRng& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform();
  const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
  return Vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u1)));
}
}  // namespace

double LambertPreview::eval_cos(const Vec3&, const Vec3& l, CounterRng&) const {
  return l.z() > 0 ? rho_ / kPi * l.z() : 0.0;
}
double LambertPreview::environment(const Vec3& v, CounterRng& rng) const {
  const Vec3 l = cosine_direction(rng);
  return eval_cos(v, l, rng) * kPi / l.z();
}

double TablePreview::eval_cos(const Vec3& v, const Vec3& l, CounterRng&) const { return table_.eval(v, l); }
double TablePreview::environment(const Vec3& v, CounterRng& rng) const {
  constexpr double share = 0.8;  // of the NDF proposal
  Vec3 l;
  if (has_proposal_ && rng.uniform() < share) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    l = models::reflect(v, proposal_.sample_visible_normal(v, u1, u2));
  } else {
    l = cosine_direction(rng);
  }
  if (!(l.z() > 0)) return 0.0;
  double pdf = l.z() / kPi;
  if (has_proposal_) {
    const Vec3 m = (v + l).normalized();
    pdf = (1 - share) * pdf + share * proposal_.D_visible(v, m) / (4.0 * std::abs(l.dot(m)));
  }
  return pdf > 0 ? table_.eval(v, l) / pdf : 0.0;
}

double SingleScatteringPreview::eval_cos(const Vec3& v, const Vec3& l, CounterRng&) const {
  if (!(v.z() > 0) || !(l.z() > 0)) return 0.0;
  return bsdf_.eval(v, l) * l.z();
}
double SingleScatteringPreview::environment(const Vec3& v, CounterRng& rng) const {
  // int f cos d l = E_{m ~ D_v}[F G2 / G1(v)] (the Jacobian [GeomBSDF24, eq. 19b] cancels D; [Heitz14, eq. 13]).
  const models::Ndf& ndf = bsdf_.ndf;
  const double u1 = rng.uniform(), u2 = rng.uniform();
  if (!(v.z() > 0)) return 0.0;
  const Vec3 m = ndf.sample_visible_normal(v, u1, u2);
  const double vm = v.dot(m);
  if (!(vm > 0)) return 0.0;
  const Vec3 l = models::reflect(v, m);
  if (!(l.z() > 0)) return 0.0;
  const double g1 = ndf.G1(v);
  if (!(g1 > 0)) return 0.0;
  return bsdf_.material.reflectance(vm, true) * models::G2_height_correlated(ndf, l, v, m) / g1;
}

double SmithWalkPreview::eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const {
  return models::smith_walk_eval_cos(walk_, v, l, rng);
}
double SmithWalkPreview::environment(const Vec3& v, CounterRng& rng) const {
  if (!(v.z() > 0)) return 0.0;
  const models::WalkExit e = walk_.walk(v, rng);
  return (!e.lost && e.reflected) ? e.weight : 0.0;
}

bool sphere_frame(int i, int j, int size, Vec3* n, Vec3* t, Vec3* b) {
  const double x = -1.0 + (i + 0.5) * 2.0 / size, y = 1.0 - (j + 0.5) * 2.0 / size;
  const double r2 = x * x + y * y;
  if (!(r2 < 1.0)) return false;
  *n = Vec3(x, y, std::sqrt(1.0 - r2));
  *t = Vec3(n->z(), 0.0, -n->x()).normalized();  // y_axis x n
  *b = n->cross(*t);
  return true;
}

PreviewImage render_sphere(const PreviewBsdf& bsdf, const Lighting& light, const PreviewOptions& o,
                           std::uint64_t stream) {
  if (o.size < 1 || o.samples < 1) throw UsageError("preview size and samples must be at least 1");
  PreviewImage img;
  img.size = o.size;
  const std::size_t npx = static_cast<std::size_t>(o.size) * o.size;
  img.radiance.assign(npx, 0.0f);
  img.stderr_.assign(npx, 0.0f);
  img.on_sphere.assign(npx, 0);
  const Vec3 view(0, 0, 1), L = light.light.normalized();
  tbb::parallel_for(0, o.size, [&](int j) {
    for (int i = 0; i < o.size; ++i) {
      Vec3 n, t, b;
      if (!sphere_frame(i, j, o.size, &n, &t, &b)) continue;
      const std::size_t px = static_cast<std::size_t>(j) * o.size + i;
      img.on_sphere[px] = 1;
      CounterRng rng(o.seed, stream, px);
      const Vec3 v(view.dot(t), view.dot(b), view.dot(n));
      int count = 0;
      double sum = 0.0, sum2 = 0.0;
      if (light.environment) {
        count = o.samples;
        for (int k = 0; k < count; ++k) {
          const double x = bsdf.environment(v, rng);
          sum += x;
          sum2 += x * x;
        }
      } else {
        const Vec3 l(L.dot(t), L.dot(b), L.dot(n));
        count = (bsdf.exact_eval() || !(l.z() > 0)) ? 1 : o.samples;
        for (int k = 0; k < count && l.z() > 0; ++k) {
          const double x = bsdf.eval_cos(v, l, rng) * light.irradiance;
          sum += x;
          sum2 += x * x;
        }
      }
      const double mean = sum / count;
      img.radiance[px] = static_cast<float>(mean);
      if (count > 1)
        img.stderr_[px] = static_cast<float>(std::sqrt(std::max(0.0, sum2 / count - mean * mean) / (count - 1)));
    }
  });
  return img;
}

PreviewImage difference(const PreviewImage& a, const PreviewImage& b) {
  if (a.size != b.size) throw std::logic_error("difference of previews of different sizes");
  PreviewImage d = a;
  for (std::size_t k = 0; k < a.radiance.size(); ++k) {
    d.radiance[k] = a.radiance[k] - b.radiance[k];
    d.stderr_[k] = std::hypot(a.stderr_[k], b.stderr_[k]);
  }
  return d;
}

namespace {
unsigned char srgb8(double c) {
  c = std::clamp(c, 0.0, 1.0);
  const double e = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(255.0 * e));
}
unsigned char unit8(double c) { return static_cast<unsigned char>(std::lround(255.0 * std::clamp(c, 0.0, 1.0))); }
}  // namespace

std::vector<unsigned char> panel_rgb8(const std::vector<std::vector<PanelTile>>& rows, double white, double range,
                                      int* width, int* height) {
  constexpr int gap = 4;
  constexpr unsigned char background = 48;
  int size = 0;
  std::size_t cols = 0;
  for (const auto& r : rows) {
    cols = std::max(cols, r.size());
    for (const auto& t : r)
      if (t.image) size = t.image->size;
  }
  *width = static_cast<int>(cols) * (size + gap) + gap;
  *height = static_cast<int>(rows.size()) * (size + gap) + gap;
  std::vector<unsigned char> rgb(static_cast<std::size_t>(*width) * *height * 3, background);
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < rows[r].size(); ++c) {
      const PanelTile& tile = rows[r][c];
      if (!tile.image) continue;
      for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
          const std::size_t px = static_cast<std::size_t>(j) * size + i;
          if (!tile.image->on_sphere[px]) continue;
          const int X = gap + static_cast<int>(c) * (size + gap) + i, Y = gap + static_cast<int>(r) * (size + gap) + j;
          unsigned char* p = &rgb[(static_cast<std::size_t>(Y) * *width + X) * 3];
          const double x = tile.image->radiance[px];
          if (tile.difference) {
            const double t = std::clamp(x / range, -1.0, 1.0);
            p[0] = unit8(t < 0 ? 1 + t : 1.0);
            p[1] = unit8(1 - std::abs(t));
            p[2] = unit8(t > 0 ? 1 - t : 1.0);
          } else {
            p[0] = p[1] = p[2] = srgb8(x / white);
          }
        }
    }
  return rgb;
}

}  // namespace microsim::render
