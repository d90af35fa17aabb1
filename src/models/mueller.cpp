#include "microsim/models/mueller.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace microsim::models {

namespace {
using C = std::complex<double>;

// Stokes = kA * (E_x E_x*, E_x E_y*, E_y E_x*, E_y E_y*) for the definition in mueller.hpp, and
// its inverse.
Eigen::Matrix4cd stokes_of_coherency() {
  Eigen::Matrix4cd A;
  A << 1, 0, 0, 1,
       1, 0, 0, -1,
       0, 1, 1, 0,
       0, C(0, 1), C(0, -1), 0;
  return A;
}
Eigen::Matrix4cd coherency_of_stokes() {
  Eigen::Matrix4cd B;
  B << 0.5, 0.5, 0, 0,
       0, 0, 0.5, C(0, -0.5),
       0, 0, 0.5, C(0, 0.5),
       0.5, -0.5, 0, 0;
  return B;
}
}  // namespace

Stokes stokes_of_field(C ex, C ey) {
  const C cross = ex * std::conj(ey);
  return Stokes(std::norm(ex) + std::norm(ey), std::norm(ex) - std::norm(ey), 2.0 * cross.real(), -2.0 * cross.imag());
}

Mueller mueller_of_jones(const Jones& J) {
  // (J E) (J E)^* componentwise is (J kron conj J) applied to E kron conj E.
  Eigen::Matrix4cd K;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) K(2 * a + b, 2 * c + d) = J(a, c) * std::conj(J(b, d));
  return (stokes_of_coherency() * K * coherency_of_stokes()).real();
}

double degree_of_polarization(const Stokes& s) {
  if (!(s[0] > 0.0)) return 0.0;
  return std::sqrt(s[1] * s[1] + s[2] * s[2] + s[3] * s[3]) / s[0];
}

Mueller rotation_mueller(double alpha) {
  const double c = std::cos(2.0 * alpha), s = std::sin(2.0 * alpha);
  Mueller R = Mueller::Identity();
  R(1, 1) = c;
  R(1, 2) = s;
  R(2, 1) = -s;
  R(2, 2) = c;
  return R;
}

double frame_angle(const Vec3& f, const Vec3& a, const Vec3& b) {
  return std::atan2(f.dot(a.cross(b)), a.dot(b));
}

Mueller frame_change(const Vec3& f, const Vec3& a, const Vec3& b) { return rotation_mueller(frame_angle(f, a, b)); }

Mueller change_frames(const Mueller& M, const Vec3& f_in, const Vec3& in_from, const Vec3& in_to, const Vec3& f_out,
                      const Vec3& out_from, const Vec3& out_to) {
  // Stokes in the old input frame = frame_change(f_in, in_to, in_from) * Stokes in the new one.
  return frame_change(f_out, out_from, out_to) * M * frame_change(f_in, in_to, in_from);
}

Vec3 stokes_frame(const Vec3& direction) {
  const Vec3 a = Vec3::UnitZ().cross(direction);
  const double n = a.norm();
  if (!(n > 1e-15 * direction.norm())) return Vec3::UnitY();
  return a / n;
}

Mueller fresnel_mueller(double Ps, double Pp, C c) {
  Mueller M = Mueller::Zero();
  M(0, 0) = M(1, 1) = 0.5 * (Ps + Pp);
  M(0, 1) = M(1, 0) = 0.5 * (Ps - Pp);
  M(2, 2) = M(3, 3) = c.real();
  M(2, 3) = c.imag();
  M(3, 2) = -c.imag();
  return M;
}

Mueller facet_reflection_mueller(const Material& mat, double cos_i, bool from_outside) {
  switch (mat.kind) {
    case MaterialKind::Mirror: return fresnel_mueller(1.0, 1.0, C(-1.0, 0.0));
    case MaterialKind::Conductor: {
      const FresnelAmplitudes a = fresnel_conductor_amplitudes(cos_i, mat.eta, mat.k);
      const FresnelReflectance R = fresnel_conductor(cos_i, mat.eta, mat.k);
      return fresnel_mueller(R.Rs, R.Rp, a.rs * std::conj(a.rp));
    }
    case MaterialKind::Dielectric: {
      const double n = from_outside ? mat.eta : 1.0 / mat.eta;
      const FresnelAmplitudes a = fresnel_dielectric_amplitudes(cos_i, n);
      const FresnelReflectance R = fresnel_dielectric(cos_i, n);
      return fresnel_mueller(R.Rs, R.Rp, a.rs * std::conj(a.rp));
    }
  }
  return Mueller::Zero();
}

Mueller facet_transmission_mueller(const Material& mat, double cos_i, bool from_outside) {
  if (mat.kind != MaterialKind::Dielectric) return Mueller::Zero();
  const double n = from_outside ? mat.eta : 1.0 / mat.eta;
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const FresnelAmplitudes a = fresnel_dielectric_amplitudes(cos_i, n);
  if (a.cos_t < 0.0 || cos_i == 0.0) return Mueller::Zero();
  const FresnelReflectance T = fresnel_dielectric_transmittance(cos_i, n);
  const double k = n * a.cos_t / cos_i;  // power per unit area across the interface
  return fresnel_mueller(T.Rs, T.Rp, k * a.ts * std::conj(a.tp));
}

Mueller reversed_path_mueller(const Mueller& M) {
  const Eigen::Vector4d q(1.0, 1.0, -1.0, 1.0);
  return q.asDiagonal() * M.transpose() * q.asDiagonal();
}

PathMuellerBuilder::PathMuellerBuilder(const Vec3& wi, std::optional<Vec3> x_in)
    : d_(-wi.normalized()), x_(x_in ? *x_in : stokes_frame(wi)) {}

bool PathMuellerBuilder::add(const Vec3& normal, bool refract_through, const Material& mat) {
  const Vec3 m = normal.normalized();
  const double dm = d_.dot(m);
  const bool from_outside = dm < 0.0;
  if (!from_outside && mat.kind != MaterialKind::Dielectric) return false;  // opaque: hit from inside
  // The facet's s axis; at normal incidence every axis is one (r_p = -r_s): keep the current one.
  Vec3 s = m.cross(d_);
  const double sn = s.norm();
  s = sn > 1e-12 ? Vec3(s / sn) : x_;
  const double cos_i = std::abs(dm);
  Vec3 d_next;
  Mueller F;
  if (refract_through) {
    if (mat.kind != MaterialKind::Dielectric) return false;
    const double eta_ratio = from_outside ? 1.0 / mat.eta : mat.eta;  // incident side over far side
    if (!refract(-d_, m, eta_ratio, &d_next)) return false;
    d_next.normalize();
    F = facet_transmission_mueller(mat, cos_i, from_outside);
  } else {
    d_next = d_ - 2.0 * dm * m;
    F = facet_reflection_mueller(mat, cos_i, from_outside);
  }
  M_ = F * (frame_change(d_, x_, s) * M_);
  d_ = d_next;
  x_ = s;  // perpendicular to the new direction too: it is normal to the plane of d and m
  return true;
}

Mueller PathMuellerBuilder::matrix(std::optional<Vec3> x_out) const {
  return frame_change(d_, x_, x_out ? *x_out : stokes_frame(d_)) * M_;
}

PathMueller path_mueller(const Vec3& wi, const std::vector<PathEvent>& events, const Material& mat,
                         std::optional<Vec3> x_in, std::optional<Vec3> x_out) {
  PathMueller out;
  PathMuellerBuilder b(wi, x_in);
  for (const PathEvent& e : events)
    if (!b.add(e.m, e.refract, mat)) return out;
  out.direction_out = b.direction();
  out.M = b.matrix(x_out);
  out.valid = true;
  return out;
}

Eigen::Matrix4cd coherency_matrix(const Mueller& M) {
  // N = sum_k J_k kron conj J_k; regrouping its indices gives sum_k vec(J_k) vec(J_k)^H.
  const Eigen::Matrix4cd N = coherency_of_stokes() * M.cast<C>() * stokes_of_coherency();
  Eigen::Matrix4cd H;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) H(2 * a + c, 2 * b + d) = 0.5 * N(2 * a + b, 2 * c + d);
  return 0.5 * (H + H.adjoint());  // exactly Hermitian
}

double min_coherency_eigenvalue(const Mueller& M) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4cd> es(coherency_matrix(M), Eigen::EigenvaluesOnly);
  return es.eigenvalues().minCoeff();
}

bool is_realizable(const Mueller& M, double tol) {
  if (!M.allFinite() || M(0, 0) < 0.0) return false;
  return min_coherency_eigenvalue(M) >= -tol * std::max(M(0, 0), 0.0);
}

}  // namespace microsim::models
