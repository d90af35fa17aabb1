// Sphere previews of a BSDF: a unit sphere seen by an orthographic camera, lit by a directional
// light or by a uniform white environment, for a measured table beside the analytic models.
//
// Geometry (camera frame: x right, y up, z toward the camera): pixel (i, j) of an S x S image
// (row j = 0 at the top) has its centre at x = -1 + (i + 1/2) 2/S, y = 1 - (j + 1/2) 2/S and sees
// the sphere where x^2 + y^2 < 1, with normal n = (x, y, sqrt(1 - x^2 - y^2)). The surface frame
// is that of a globe whose axis is the image's vertical: tangent t = normalize(y_axis x n) (along
// the parallels, pointing right on the front of the sphere), bitangent b = n x t. A direction d
// has local coordinates (d.t, d.b, d.n): for an anisotropic table its x axis (phi = 0) runs
// along the parallels. The direction toward the camera is v = (0, 0, 1).
//
// Radiance: a directional light of irradiance E on a plane facing it gives
//   L = f(v, l) cos(theta_l) E,
// E = pi by default, so that a white Lambertian surface facing the light has L = 1; the uniform
// white environment has radiance 1, so L = int f(v, l) cos(theta_l) d l = the directional albedo
// at v (by reciprocity), 1 for a lossless surface (white furnace).
//
// Estimators (per pixel, from a counter-based generator keyed by (seed, stream, pixel): the
// image does not depend on the thread count):
//   measured table: eval exact; environment by one-sample multiple importance sampling: l from
//     a mixture, 80 % reflected about the visible normals of v of the models' NDF ([Heitz14, eq. 13];
//     density D_v(m) / (4 v.m), [GeomBSDF24, eq. 19b]), 20 % cosine-weighted (density cos(theta_l) / pi,
//     which covers every direction the table can send light to), weight eval / mixture density
//     (unbiased for any table; the table's own sampling is not used);
//   single scattering ([GeomBSDF24, eq. 21d] with the height-correlated Smith G2, [Heitz14, eq. 21]): eval exact;
//     environment by sampling the visible normals of v [Heitz14, eq. 13], weight F G2 / G1(v);
//   Smith random walk (models/smith_random_walk.hpp): the directional light by the walk's point
//     estimator (models/smith_walk_eval.hpp, started from v), the environment by walks from v
//     (the weight of the walks that leave upward).
// Each pixel reports its mean and the standard error of the mean of its samples.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/io/rgl_reader.hpp"
#include "microsim/models/microfacet_bsdf.hpp"
#include "microsim/models/smith_random_walk.hpp"

namespace microsim::render {

// A reflectance model as the preview sees it (local frame, z the normal; v toward the camera,
// l toward the light).
class PreviewBsdf {
 public:
  virtual ~PreviewBsdf() = default;
  // One sample of an unbiased (or exact) estimate of f(v, l) cos(theta_l).
  virtual double eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const = 0;
  // One sample of an unbiased estimate of int f(v, l) cos(theta_l) d l.
  virtual double environment(const Vec3& v, CounterRng& rng) const = 0;
  // True when eval_cos is exact (one evaluation per pixel suffices).
  virtual bool exact_eval() const { return true; }
};

class LambertPreview : public PreviewBsdf {
 public:
  explicit LambertPreview(double albedo) : rho_(albedo) {}
  double eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const override;
  double environment(const Vec3& v, CounterRng& rng) const override;

 private:
  double rho_;
};

class TablePreview : public PreviewBsdf {
 public:
  // `proposal`: an NDF whose visible normals, reflected about them, give the environment
  // directions (mixed with cosine-weighted ones); without it, cosine-weighted only.
  explicit TablePreview(const RglMaterial& table, const models::Ndf* proposal = nullptr)
      : table_(table), proposal_(proposal ? *proposal : models::Ndf()), has_proposal_(proposal != nullptr) {}
  double eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const override;
  double environment(const Vec3& v, CounterRng& rng) const override;

 private:
  const RglMaterial& table_;
  models::Ndf proposal_;
  bool has_proposal_;
};

class SingleScatteringPreview : public PreviewBsdf {
 public:
  explicit SingleScatteringPreview(const models::MicrofacetBsdf& bsdf) : bsdf_(bsdf) {}
  double eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const override;
  double environment(const Vec3& v, CounterRng& rng) const override;

 private:
  models::MicrofacetBsdf bsdf_;
};

class SmithWalkPreview : public PreviewBsdf {
 public:
  explicit SmithWalkPreview(const models::SmithRandomWalk& walk) : walk_(walk) {}
  double eval_cos(const Vec3& v, const Vec3& l, CounterRng& rng) const override;
  double environment(const Vec3& v, CounterRng& rng) const override;
  bool exact_eval() const override { return false; }

 private:
  models::SmithRandomWalk walk_;
};

struct Lighting {
  bool environment = false;
  Vec3 light = Vec3(-1, 1, 1).normalized();  // camera frame, toward the light
  double irradiance = kPi;
};

struct PreviewOptions {
  int size = 256;
  int samples = 64;  // per pixel: environment samples, or point estimates of a stochastic eval
  std::uint64_t seed = 1;
};

struct PreviewImage {
  int size = 0;
  std::vector<float> radiance, stderr_;  // row-major, row 0 at the top; 0 off the sphere
  std::vector<std::uint8_t> on_sphere;
};

// The local frame at the centre of pixel (i, j): false off the sphere.
bool sphere_frame(int i, int j, int size, Vec3* n, Vec3* t, Vec3* b);

PreviewImage render_sphere(const PreviewBsdf& bsdf, const Lighting& light, const PreviewOptions& o,
                           std::uint64_t stream);

// Display encodings of the panel (8-bit sRGB):
//   radiance: grey, L / white clamped to [0, 1], then the sRGB transfer curve;
//   difference d: diverging, t = clamp(d / range, -1, 1): white at 0, toward pure red (1, 0, 0)
//     for t = +1 and pure blue (0, 0, 1) for t = -1, linear in t in the encoded values;
//   off the sphere and in the gaps: dark grey (sRGB 48).
// A panel is a grid of tiles (rows x cols, each size x size, 4-pixel gaps).
struct PanelTile {
  const PreviewImage* image = nullptr;
  bool difference = false;  // image holds a signed difference
};
std::vector<unsigned char> panel_rgb8(const std::vector<std::vector<PanelTile>>& rows, double white, double range,
                                      int* width, int* height);

// Signed difference a - b on the sphere (stderr combined in quadrature).
PreviewImage difference(const PreviewImage& a, const PreviewImage& b);

}  // namespace microsim::render
