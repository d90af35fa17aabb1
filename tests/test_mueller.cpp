// Polarization (models/mueller.hpp): the Stokes convention, the Fresnel Mueller matrix of a facet,
// the Mueller matrix of specular paths checked against closed forms and against an explicit
// propagation of the complex electric field in 3D (the independent check of every sign), the
// reciprocity of paths, realizability and depolarization by random facets.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "microsim/common.hpp"
#include "microsim/models/mueller.hpp"

using namespace microsim;
using namespace microsim::models;
using Cx = std::complex<double>;
using CVec3 = Eigen::Vector3cd;

namespace {

const Material kGold = Material::conductor(0.47, 2.4);
const Material kGlass = Material::dielectric(1.5);

double max_abs_diff(const Mueller& a, const Mueller& b) { return (a - b).cwiseAbs().maxCoeff(); }

// The closed form of the Fresnel Mueller matrix in the s/p frames, written from the amplitudes.
Mueller closed_form(Cx as, Cx ap, double power_factor = 1.0) {
  const double S = std::norm(as), P = std::norm(ap);
  const Cx c = as * std::conj(ap);
  Mueller M;
  M << S + P, S - P, 0, 0,
       S - P, S + P, 0, 0,
       0, 0, 2 * c.real(), 2 * c.imag(),
       0, 0, -2 * c.imag(), 2 * c.real();
  return 0.5 * power_factor * M;
}

// Amplitudes written here from the textbook forms (w = n cos_t = sqrt(n^2 - sin^2)), not from
// the library's functions.
void conductor_amplitudes(double cos_i, Cx n, Cx* rs, Cx* rp) {
  const Cx w = std::sqrt(n * n - Cx(1 - cos_i * cos_i));
  *rs = (cos_i - w) / (cos_i + w);
  *rp = (n * n * cos_i - w) / (n * n * cos_i + w);
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

// ---- The independent route: the complex field vector carried through each reflection in 3D.
struct FieldPath {
  Vec3 d;         // propagation direction
  CVec3 E;        // complex field, perpendicular to d
};

// One reflection: E = rs (E.s) s + rp (E.p) p', with s = d x m (the opposite sign of the
// library's m x d: the Mueller matrix must not depend on it), p = d x s, p' = d' x s.
void reflect_field(FieldPath* f, const Vec3& m, const Material& mat) {
  Vec3 s = f->d.cross(m);
  if (s.norm() < 1e-12) s = f->d.unitOrthogonal();
  s.normalize();
  const double cos_i = std::abs(f->d.dot(m));
  Cx rs(-1), rp(1);
  if (mat.kind == MaterialKind::Conductor) conductor_amplitudes(cos_i, Cx(mat.eta, mat.k), &rs, &rp);
  const Vec3 p_in = f->d.cross(s);
  const Vec3 d_out = f->d - 2 * f->d.dot(m) * m;
  const Vec3 p_out = d_out.cross(s);
  Cx es(0), ep(0);  // components without conjugation (Eigen's dot() conjugates)
  for (int k = 0; k < 3; ++k) {
    es += f->E[k] * s[k];
    ep += f->E[k] * p_in[k];
  }
  f->E = rs * es * s.cast<Cx>() + rp * ep * p_out.cast<Cx>();
  f->d = d_out;
}

// The Jones matrix of a reflection path between the frames (x_in, f_in x x_in) and (x_out, d x x_out).
Jones jones_by_fields(const Vec3& wi, const std::vector<Vec3>& normals, const Material& mat, const Vec3& x_in,
                      const Vec3& x_out, Vec3* d_out) {
  const Vec3 f_in = -wi;
  const Vec3 y_in = f_in.cross(x_in);
  Jones J;
  for (int col = 0; col < 2; ++col) {
    FieldPath f{f_in, (col == 0 ? x_in : y_in).cast<Cx>()};
    for (const Vec3& m : normals) reflect_field(&f, m, mat);
    const Vec3 y_out = f.d.cross(x_out);
    Cx ex(0), ey(0);
    for (int k = 0; k < 3; ++k) {
      ex += f.E[k] * x_out[k];
      ey += f.E[k] * y_out[k];
    }
    J(0, col) = ex;
    J(1, col) = ey;
    *d_out = f.d;
  }
  return J;
}

// Mueller matrix from a Jones matrix by fitting: four input fields, their Stokes vectors in and
// out (the definition of the Stokes vector only), M = S_out S_in^-1.
Mueller mueller_by_stokes_fit(const Jones& J) {
  const Cx in[4][2] = {{1, 0}, {0, 1}, {1 / std::sqrt(2.0), 1 / std::sqrt(2.0)}, {1 / std::sqrt(2.0), Cx(0, 1 / std::sqrt(2.0))}};
  Eigen::Matrix4d Sin, Sout;
  for (int k = 0; k < 4; ++k) {
    Sin.col(k) = stokes_of_field(in[k][0], in[k][1]);
    const Eigen::Vector2cd e = J * Eigen::Vector2cd(in[k][0], in[k][1]);
    Sout.col(k) = stokes_of_field(e[0], e[1]);
  }
  return Sout * Sin.inverse();
}

Mueller mueller_by_fields(const Vec3& wi, const std::vector<Vec3>& normals, const Material& mat, Vec3* d_out) {
  Vec3 d;
  const Jones J0 = jones_by_fields(wi, normals, mat, stokes_frame(wi), Vec3::UnitX(), &d);  // find d first
  (void)J0;
  const Jones J = jones_by_fields(wi, normals, mat, stokes_frame(wi), stokes_frame(d), &d);
  *d_out = d;
  return mueller_by_stokes_fit(J);
}

std::vector<PathEvent> reflections(const std::vector<Vec3>& normals) {
  std::vector<PathEvent> e;
  for (const Vec3& m : normals) e.push_back({m, false});
  return e;
}

// A random reflection path: each normal faces the current propagation direction.
std::vector<Vec3> random_path(std::mt19937_64& rng, const Vec3& wi, int n) {
  std::vector<Vec3> normals;
  Vec3 d = -wi;
  for (int k = 0; k < n; ++k) {
    Vec3 m = random_unit(rng);
    if (m.dot(d) > 0) m = -m;
    normals.push_back(m);
    d = d - 2 * d.dot(m) * m;
  }
  return normals;
}

}  // namespace

// s3 > 0 is a field turning from x toward y (counterclockwise for the receiver): the physical
// field Re((ex x + ey y) exp(-i w t)) at two instants.
TEST(StokesConvention, PositiveS3TurnsFromXTowardY) {
  const Cx ex(1.0, 0.0), ey(0.0, 1.0);
  const Stokes s = stokes_of_field(ex, ey);
  EXPECT_NEAR(s[3], 2.0, 1e-15);
  auto field = [&](double wt) {
    const Cx ph = std::exp(Cx(0, -wt));
    return Eigen::Vector2d((ex * ph).real(), (ey * ph).real());
  };
  const Eigen::Vector2d a = field(0.0), b = field(0.1);
  EXPECT_GT(a.x() * b.y() - a.y() * b.x(), 0.0);  // z-component of a x b: turning from x to y
  // The opposite field turns the other way and has s3 < 0.
  EXPECT_LT(stokes_of_field(ex, std::conj(ey))[3], 0.0);
  // Linear fields: s2 = +s0 at +45 degrees between x and y.
  EXPECT_NEAR(stokes_of_field(1.0, 1.0)[2], 2.0, 1e-15);
  EXPECT_NEAR(degree_of_polarization(Stokes(1, 0.3, 0.4, 0)), 0.5, 1e-15);
}

// The rotation matrix equals the Stokes vector recomputed from the same 3D field in the rotated
// frame.
TEST(StokesConvention, FrameChangeMatchesTheFieldInTheNewFrame) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 f = random_unit(rng);
    const Vec3 a = f.unitOrthogonal();
    const Vec3 b = random_unit(rng).cross(f).normalized();
    const CVec3 E = Cx(0.3, -0.7) * a.cast<Cx>() + Cx(-0.2, 0.9) * f.cross(a).cast<Cx>();
    auto stokes_in = [&](const Vec3& x) {
      const Vec3 y = f.cross(x);
      Cx ex(0), ey(0);
      for (int k = 0; k < 3; ++k) {
        ex += E[k] * x[k];
        ey += E[k] * y[k];
      }
      return stokes_of_field(ex, ey);
    };
    const Stokes expected = stokes_in(b), got = frame_change(f, a, b) * stokes_in(a);
    EXPECT_LT((expected - got).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(FresnelAmplitudes, SquaredModuliAreThePowerReflectances) {
  for (double c : {0.0, 0.05, 0.3, 0.5, 0.7071, 0.9, 1.0}) {
    const FresnelAmplitudes a = fresnel_conductor_amplitudes(c, 0.47, 2.4);
    const FresnelReflectance R = fresnel_conductor(c, 0.47, 2.4);
    EXPECT_EQ(std::norm(a.rs), R.Rs);
    EXPECT_EQ(std::norm(a.rp), R.Rp);
    for (double n : {1.5, 1.0 / 1.5}) {
      const FresnelAmplitudes d = fresnel_dielectric_amplitudes(c, n);
      const FresnelReflectance Rd = fresnel_dielectric(c, n), Td = fresnel_dielectric_transmittance(c, n);
      if (d.cos_t >= 0) {
        EXPECT_EQ(std::norm(d.rs), Rd.Rs);
        EXPECT_EQ(std::norm(d.rp), Rd.Rp);
        if (c > 0) {
          EXPECT_NEAR(n * d.cos_t / c * std::norm(d.ts), Td.Rs, 1e-15);
        }
      } else {  // total internal reflection: unit moduli, a phase difference
        EXPECT_NEAR(std::norm(d.rs), 1.0, 1e-15);
        EXPECT_NEAR(std::norm(d.rp), 1.0, 1e-15);
      }
    }
  }
  // Normal incidence: r_p = -r_s (the sign convention of the p axes).
  const FresnelAmplitudes g = fresnel_dielectric_amplitudes(1.0, 1.5);
  EXPECT_NEAR(g.rs.real(), -0.2, 1e-15);
  EXPECT_NEAR(g.rp.real(), 0.2, 1e-15);
}

// One flat facet (m = z): the path matrix in the s/p frames and in the directions' Stokes frames
// is the closed form; M00 is the library's unpolarized reflectance (transmittance) exactly.
TEST(PathMueller, FlatFacetIsTheClosedFormFresnelMatrix) {
  double worst = 0.0;
  for (double deg_i : {0.0, 10.0, 30.0, 45.0, 56.3, 70.0, 85.0, 89.5})
    for (double phi : {0.0, 1.0, 4.0}) {
      const double ti = deg_i * kPi / 180;
      const Vec3 wi = direction_from_angles(ti, phi);
      const double c = std::abs(wi.normalized().z());  // the facet cosine as the path sees it
      const Vec3 s = Vec3::UnitZ().cross(-wi).norm() > 1e-12 ? Vec3(Vec3::UnitZ().cross(-wi).normalized()) : Vec3::UnitY();
      const std::vector<PathEvent> flat = {{Vec3::UnitZ(), false}};
      // Mirror: r_s = -1, r_p = 1.
      {
        const PathMueller p = path_mueller(wi, flat, Material::mirror(), s, s);
        ASSERT_TRUE(p.valid);
        worst = std::max(worst, max_abs_diff(p.M, closed_form(-1.0, 1.0)));
      }
      // Gold-like conductor, in the s/p frames and in the Stokes frames of the directions.
      {
        Cx rs, rp;
        conductor_amplitudes(c, Cx(0.47, 2.4), &rs, &rp);
        const PathMueller p = path_mueller(wi, flat, kGold, s, s);
        const PathMueller q = path_mueller(wi, flat, kGold);
        worst = std::max({worst, max_abs_diff(p.M, closed_form(rs, rp)), max_abs_diff(q.M, closed_form(rs, rp))});
        EXPECT_EQ(p.M(0, 0), fresnel_conductor(c, 0.47, 2.4).unpolarized());
        EXPECT_EQ(q.M(0, 0), fresnel_conductor(c, 0.47, 2.4).unpolarized());
        EXPECT_LT((q.direction_out - Vec3(-wi.x(), -wi.y(), wi.z())).norm(), 1e-15);
      }
      // Dielectric 1.5: reflection and transmission.
      {
        const double ct = std::sqrt(1 - (1 - c * c) / 2.25);
        const double rs = (c - 1.5 * ct) / (c + 1.5 * ct), rp = (1.5 * c - ct) / (1.5 * c + ct);
        const double ts = 2 * c / (c + 1.5 * ct), tp = 2 * c / (1.5 * c + ct);
        const PathMueller r = path_mueller(wi, flat, kGlass);
        worst = std::max(worst, max_abs_diff(r.M, closed_form(rs, rp)));
        EXPECT_EQ(r.M(0, 0), fresnel_dielectric(c, 1.5).unpolarized());
        const PathMueller t = path_mueller(wi, {{Vec3::UnitZ(), true}}, kGlass);
        ASSERT_TRUE(t.valid);
        worst = std::max(worst, max_abs_diff(t.M, closed_form(ts, tp, 1.5 * ct / c)));
        EXPECT_EQ(t.M(0, 0), fresnel_dielectric_transmittance(c, 1.5).unpolarized());
        EXPECT_NEAR(r.M(0, 0) + t.M(0, 0), 1.0, 1e-15);
        EXPECT_LT(std::abs(t.direction_out.z() + ct), 1e-15);
      }
    }
  EXPECT_LT(worst, 1e-14);
  // Mirror at normal incidence: diag(1, 1, -1, -1) (s2 and s3 change sign on reflection).
  const PathMueller n = path_mueller(Vec3::UnitZ(), {{Vec3::UnitZ(), false}}, Material::mirror());
  EXPECT_LT(max_abs_diff(n.M, Eigen::Vector4d(1, 1, -1, -1).asDiagonal().toDenseMatrix()), 1e-15);
  // Brewster's angle of glass: no p reflectance, the reflected light is s-polarized.
  const double tb = std::atan(1.5);
  const PathMueller b = path_mueller(direction_from_angles(tb, 0.3), {{Vec3::UnitZ(), false}}, kGlass);
  EXPECT_LT(fresnel_dielectric(std::cos(tb), 1.5).Rp, 1e-30);
  EXPECT_NEAR(b.M(0, 0), b.M(0, 1), 1e-16);
  EXPECT_NEAR(b.M(2, 2), 0.0, 1e-16);
  EXPECT_NEAR(degree_of_polarization(b.M * Stokes(1, 0, 0, 0)), 1.0, 1e-12);
  // Total internal reflection inside glass at 60 degrees: lossless, a pure retarder.
  const PathMueller tir = path_mueller(direction_from_angles(kPi - rad(60.0), 0.0), {{Vec3::UnitZ(), false}}, kGlass);
  ASSERT_TRUE(tir.valid);
  EXPECT_NEAR(tir.M(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(tir.M(0, 1), 0.0, 1e-15);
  EXPECT_GT(std::abs(tir.M(2, 3)), 0.1);
  EXPECT_FALSE(path_mueller(direction_from_angles(kPi - rad(60.0), 0.0), {{Vec3::UnitZ(), true}}, kGlass).valid);
}

// A tilted facet: the path matrix in the directions' Stokes frames equals the field propagation.
TEST(PathMueller, TiltedFacetMatchesTheFieldPropagation) {
  std::mt19937_64 rng(11);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 wi = random_unit(rng);
    if (wi.z() < 0) wi.z() = -wi.z();
    const std::vector<Vec3> normals = random_path(rng, wi, 1);
    Vec3 d;
    const Mueller ref = mueller_by_fields(wi, normals, kGold, &d);
    const PathMueller p = path_mueller(wi, reflections(normals), kGold);
    ASSERT_TRUE(p.valid);
    EXPECT_LT((p.direction_out - d).norm(), 1e-14);
    worst = std::max(worst, max_abs_diff(p.M, ref));
  }
  EXPECT_LT(worst, 1e-12);
}

// V-groove along y, facets (+-sin a, 0, cos a), light in the xz plane: both planes of incidence are
// the xz plane, so M = M_F(theta2) M_F(theta1). In that plane a direction at angle psi from +z
// (toward +x) reflects on a facet whose normal is at angle mu to 2 mu + pi - psi: the ray
// d0 = -wi (angle theta_i + pi) meets facet 1 (mu = a) at theta1 = |theta_i - a|, leaves at
// 2a - theta_i and meets facet 2 (mu = -a) at cos theta2 = -cos(3a - theta_i), theta2 = pi - |3a - theta_i|
// (a hit needs cos(3a - theta_i) < 0).
TEST(PathMueller, VGrooveInPlaneIsTheProductOfTwoFresnelMatrices) {
  double worst = 0.0;
  int cases = 0;
  for (double a_deg : {30.0, 45.0, 55.0, 65.0})
    for (double ti_deg : {0.0, 10.0, 25.0, 40.0, 60.0}) {
      const double a = rad(a_deg), ti = rad(ti_deg);
      const Vec3 m1(std::sin(a), 0, std::cos(a)), m2(-std::sin(a), 0, std::cos(a));
      const Vec3 wi = direction_from_angles(ti, 0.0);
      if (!(std::cos(3 * a - ti) < 0.0)) continue;  // the reflected ray misses facet 2
      const double t1 = std::abs(ti - a), t2 = kPi - std::abs(3 * a - ti);
      ASSERT_NEAR(std::cos(t1), wi.dot(m1), 1e-14);
      for (const Material& mat : {kGold, Material::mirror(), kGlass}) {
        const PathMueller p = path_mueller(wi, {{m1, false}, {m2, false}}, mat);
        ASSERT_TRUE(p.valid);
        const Mueller expected = facet_reflection_mueller(mat, std::cos(t2)) * facet_reflection_mueller(mat, std::cos(t1));
        worst = std::max(worst, max_abs_diff(p.M, expected));
      }
      // Gold from the closed forms of the amplitudes too.
      Cx rs1, rp1, rs2, rp2;
      conductor_amplitudes(std::cos(t1), Cx(0.47, 2.4), &rs1, &rp1);
      conductor_amplitudes(std::cos(t2), Cx(0.47, 2.4), &rs2, &rp2);
      worst = std::max(worst, max_abs_diff(path_mueller(wi, {{m1, false}, {m2, false}}, kGold).M,
                                           closed_form(rs2, rp2) * closed_form(rs1, rp1)));
      ++cases;
    }
  EXPECT_GT(cases, 10);
  EXPECT_LT(worst, 1e-14);
  // The 90-degree groove retroreflects in its plane.
  const PathMueller r = path_mueller(direction_from_angles(rad(20.0), 0.0),
                                     {{Vec3(std::sqrt(0.5), 0, std::sqrt(0.5)), false}, {Vec3(-std::sqrt(0.5), 0, std::sqrt(0.5)), false}}, kGold);
  EXPECT_LT((r.direction_out - direction_from_angles(rad(20.0), 0.0)).norm(), 1e-14);
}

// Out of the groove's cross-section the two planes of incidence differ and the frames rotate
// between the facets: the product with rotations equals the field propagation, and differs from
// the plain product (the rotation matters).
TEST(PathMueller, VGrooveOutOfPlaneMatchesTheFieldPropagation) {
  double worst = 0.0, rotation_effect = 0.0;
  for (double a_deg : {40.0, 45.0, 55.0})
    for (double phi_deg : {10.0, 30.0, 60.0})
      for (double ti_deg : {15.0, 35.0}) {
        const double a = rad(a_deg);
        const Vec3 m1(std::sin(a), 0, std::cos(a)), m2(-std::sin(a), 0, std::cos(a));
        const Vec3 wi = direction_from_angles(rad(ti_deg), rad(phi_deg));
        const Vec3 d1 = -wi - 2 * (-wi).dot(m1) * m1;
        if (!(-wi.dot(m1) < 0) || !(d1.dot(m2) < 0)) continue;
        for (const Material& mat : {kGold, Material::mirror()}) {
          Vec3 d;
          const Mueller ref = mueller_by_fields(wi, {m1, m2}, mat, &d);
          const PathMueller p = path_mueller(wi, {{m1, false}, {m2, false}}, mat);
          ASSERT_TRUE(p.valid);
          EXPECT_LT((p.direction_out - d).norm(), 1e-14);
          worst = std::max(worst, max_abs_diff(p.M, ref));
          const double t1 = std::acos(wi.dot(m1)), t2 = std::acos(-d1.dot(m2));
          rotation_effect = std::max(rotation_effect, max_abs_diff(ref, facet_reflection_mueller(mat, std::cos(t2)) *
                                                                            facet_reflection_mueller(mat, std::cos(t1))));
        }
      }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(rotation_effect, 0.1);
}

// Random paths of 1-4 reflections on gold: the reversed path's matrix in matched frames (each
// direction keeps its stokes_frame axis) is Q M^T Q, Q = diag(1, 1, -1, 1); the plain transpose
// is not.
TEST(PathMueller, ReversedPathIsQTransposeQ) {
  std::mt19937_64 rng(3);
  double worst = 0.0, plain = 0.0;
  for (int trial = 0; trial < 400; ++trial) {
    Vec3 wi = random_unit(rng);
    if (wi.z() < 0) wi.z() = -wi.z();
    std::vector<Vec3> normals = random_path(rng, wi, 1 + trial % 4);
    const PathMueller fwd = path_mueller(wi, reflections(normals), kGold);
    std::vector<Vec3> back(normals.rbegin(), normals.rend());
    const PathMueller rev = path_mueller(fwd.direction_out, reflections(back), kGold);
    ASSERT_TRUE(fwd.valid && rev.valid);
    EXPECT_LT((rev.direction_out - wi).norm(), 1e-12);
    worst = std::max(worst, max_abs_diff(fwd.M, reversed_path_mueller(rev.M)));
    plain = std::max(plain, max_abs_diff(fwd.M, Mueller(rev.M.transpose())));
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(plain, 0.01);
}

// Every path matrix is realizable; matrices that are not (a mirror image of circular light
// alone, s3 -> -s3; Q itself) are refused.
TEST(Realizability, PathMatricesAreRealizableAndNonPhysicalOnesAreRefused) {
  std::mt19937_64 rng(5);
  double lowest = 1.0;
  for (int trial = 0; trial < 300; ++trial) {
    Vec3 wi = random_unit(rng);
    if (wi.z() < 0) wi.z() = -wi.z();
    const PathMueller p = path_mueller(wi, reflections(random_path(rng, wi, 1 + trial % 4)), trial % 2 ? kGold : kGlass);
    ASSERT_TRUE(p.valid);
    lowest = std::min(lowest, min_coherency_eigenvalue(p.M));
    EXPECT_TRUE(is_realizable(p.M));
  }
  // Refractions into and out of glass.
  const PathMueller t = path_mueller(direction_from_angles(0.6, 0.2),
                                     {{Vec3(0.2, 0.1, 1).normalized(), true}, {Vec3(-0.1, 0.3, 1).normalized(), true}}, kGlass);
  ASSERT_TRUE(t.valid);
  EXPECT_TRUE(is_realizable(t.M));
  EXPECT_GT(lowest, -1e-12);
  EXPECT_NEAR(coherency_matrix(t.M).trace().real(), t.M(0, 0), 1e-14);
  EXPECT_FALSE(is_realizable(Eigen::Vector4d(1, 1, 1, -1).asDiagonal().toDenseMatrix()));
  EXPECT_NEAR(min_coherency_eigenvalue(Eigen::Vector4d(1, 1, 1, -1).asDiagonal().toDenseMatrix()), -0.5, 1e-15);
  EXPECT_FALSE(is_realizable(Eigen::Vector4d(1, 1, -1, 1).asDiagonal().toDenseMatrix()));
  EXPECT_FALSE(is_realizable(-Mueller::Identity()));
  EXPECT_TRUE(is_realizable(Eigen::Vector4d(1, 0, 0, 0).asDiagonal().toDenseMatrix()));  // ideal depolarizer
  EXPECT_TRUE(is_realizable(Eigen::Vector4d(1, 1, -1, -1).asDiagonal().toDenseMatrix()));  // mirror
  // Mueller of a random Jones matrix: realizable, and the library's Kronecker form agrees with
  // the fit to Stokes vectors.
  Jones J;
  J << Cx(0.3, -0.2), Cx(0.1, 0.5), Cx(-0.7, 0.1), Cx(0.2, 0.2);
  EXPECT_TRUE(is_realizable(mueller_of_jones(J)));
  EXPECT_LT(max_abs_diff(mueller_of_jones(J), mueller_by_stokes_fit(J)), 1e-14);
}

// The mean of the path matrices over random facet normals (one normal per bounce, tilted at
// most 40 degrees from the mirror normal of the previous direction) depolarizes a fully
// polarized beam more with every bounce.
TEST(Depolarization, DegreeOfPolarizationFallsWithRandomBounces) {
  std::mt19937_64 rng(12345);
  const Vec3 wi = direction_from_angles(rad(30.0), 0.0);
  const Stokes s_in(1, 0, 0.6, 0.8);  // fully polarized, elliptical
  std::vector<double> dop;
  for (int bounces = 1; bounces <= 4; ++bounces) {
    Mueller sum = Mueller::Zero();
    const int n = 20000;
    for (int k = 0; k < n; ++k) {
      std::vector<Vec3> normals;
      Vec3 d = -wi;
      for (int b = 0; b < bounces; ++b) {
        Vec3 m = (-d + 0.7 * random_unit(rng)).normalized();
        if (m.dot(d) > 0) m = -m;
        normals.push_back(m);
        d = d - 2 * d.dot(m) * m;
      }
      // Each path in the frame of its own outgoing direction, then averaged (as a bin would).
      const PathMueller p = path_mueller(wi, reflections(normals), kGold);
      sum += p.M;
    }
    dop.push_back(degree_of_polarization(sum / n * s_in));
  }
  EXPECT_GT(dop[0], 0.5);
  for (int k = 1; k < 4; ++k) EXPECT_LT(dop[k], dop[k - 1] - 0.03) << "bounces " << k + 1;
}

// The incremental builder (what a walk calls facet by facet) gives path_mueller's matrix, and a
// refused event leaves it as it was.
TEST(PathMueller, BuilderFollowsTheRayAndRefusesImpossibleEvents) {
  const Vec3 wi = direction_from_angles(rad(40.0), 0.5);
  const std::vector<PathEvent> events = {{Vec3(0.3, 0.1, 1).normalized(), true}, {Vec3(-0.2, 0.2, 1).normalized(), false},
                                         {Vec3(0.1, -0.3, 1).normalized(), false}};
  PathMuellerBuilder b(wi);
  for (const PathEvent& e : events) ASSERT_TRUE(b.add(e.m, e.refract, kGlass));
  const PathMueller p = path_mueller(wi, events, kGlass);
  ASSERT_TRUE(p.valid);
  EXPECT_EQ(b.direction(), p.direction_out);
  EXPECT_EQ(b.matrix(), p.M);
  // A conductor cannot be hit from inside; glass refracts nothing beyond its critical angle.
  PathMuellerBuilder g(wi);
  const Mueller before = g.matrix();
  EXPECT_FALSE(g.add(Vec3(0, 0, -1), false, kGold));
  EXPECT_EQ(g.matrix(), before);
  PathMuellerBuilder inside(direction_from_angles(kPi - rad(60.0), 0.0));
  EXPECT_FALSE(inside.add(Vec3::UnitZ(), true, kGlass));
  EXPECT_TRUE(inside.add(Vec3::UnitZ(), false, kGlass));
}
