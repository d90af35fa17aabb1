// Polarization: Stokes vectors, Mueller matrices, Stokes frames, the Fresnel Mueller matrix of a
// facet and the Mueller matrix of a specular path (docs/theory/polarization.md states every
// convention and derives the signs; Mitsuba 3 [Mitsuba22] uses the same Stokes frames and rotation
// sign, so its `measured_polarized` tables of [Baek20] are written from these, io/pbsdf.hpp).
//
// Conventions (in short):
//   Stokes frame  a beam travelling along the unit vector f carries a reference axis x (unit,
//                 x . f = 0) and y = f x x, so (x, y, f) is right-handed. With the field's complex
//                 components (E_x, E_y) and time dependence exp(-i omega t):
//                 s0 = |E_x|^2 + |E_y|^2, s1 = |E_x|^2 - |E_y|^2, s2 = 2 Re(E_x E_y*),
//                 s3 = -2 Im(E_x E_y*). s3 > 0: the field turns from x toward y, counterclockwise
//                 for a receiver looking back at the source.
//   Directions    microsim's directions point away from the surface: the light's direction i
//                 is travelled along f = -i, the outgoing direction o along f = o. Both use the
//                 reference axis stokes_frame(direction) = normalize(z x direction) (the azimuthal
//                 unit vector), so a path and its reverse are in matched frames.
//   Facet         s = normalize(m x d) for the propagation direction d hitting the facet of normal
//                 m; p = d x s before and d' x s after (d' the new propagation direction).
//   Rotation      frame_change(f, a, b) re-expresses a Stokes vector in the frame whose x is b,
//                 from the frame whose x is a: the rotation by the angle from a to b, positive
//                 counterclockwise about f.
#pragma once

#include <Eigen/Core>

#include <complex>
#include <optional>
#include <vector>

#include "microsim/models/fresnel.hpp"
#include "microsim/models/microfacet_bsdf.hpp"

namespace microsim::models {

using Stokes = Eigen::Vector4d;
using Mueller = Eigen::Matrix4d;
using Jones = Eigen::Matrix2cd;  // field components out = J * field components in

// Stokes vector of a field with complex components (ex, ey) in a Stokes frame.
Stokes stokes_of_field(std::complex<double> ex, std::complex<double> ey);
// Mueller matrix of a deterministic (Jones) element: s_out = M s_in for every field.
Mueller mueller_of_jones(const Jones& J);
// sqrt(s1^2 + s2^2 + s3^2) / s0; 0 when s0 <= 0.
double degree_of_polarization(const Stokes& s);

// Rotation of the reference axis by alpha (counterclockwise about the propagation direction):
// s1' = cos 2a s1 + sin 2a s2, s2' = -sin 2a s1 + cos 2a s2, s0 and s3 unchanged.
Mueller rotation_mueller(double alpha);
// The angle from the axis a to the axis b (both perpendicular to f), counterclockwise about f.
double frame_angle(const Vec3& f, const Vec3& a, const Vec3& b);
// Stokes vector in the frame of axis b = frame_change(f, a, b) * Stokes vector in the frame of a.
Mueller frame_change(const Vec3& f, const Vec3& a, const Vec3& b);
// M re-expressed between new frames: input axis in_from -> in_to (beam along f_in), output axis
// out_from -> out_to (beam along f_out).
Mueller change_frames(const Mueller& M, const Vec3& f_in, const Vec3& in_from, const Vec3& in_to, const Vec3& f_out,
                      const Vec3& out_from, const Vec3& out_to);

// Reference axis of a direction (pointing away from the surface, either hemisphere):
// normalize(z x direction), the azimuthal unit vector (-sin phi, cos phi, 0); (0, 1, 0) on the
// z axis (phi = 0).
Vec3 stokes_frame(const Vec3& direction);

// Fresnel Mueller matrix in the s/p frames from the s and p power factors (R_s, R_p, or T_s, T_p)
// and the cross term c = a_s conj(a_p) (r_s conj(r_p), or (n cos_t / cos_i) t_s conj(t_p)):
//   1/2 [[Ps + Pp, Ps - Pp, 0, 0], [Ps - Pp, Ps + Pp, 0, 0],
//        [0, 0, 2 Re c, 2 Im c], [0, 0, -2 Im c, 2 Re c]].
Mueller fresnel_mueller(double Ps, double Pp, std::complex<double> c);
// A facet's reflection / transmission Mueller matrix in its s/p frames, for light arriving from
// outside the material (from_outside) or from inside (dielectrics), at |cos| = cos_i to the facet
// normal. Mirror: r_s = -1, r_p = 1. Transmission: dielectrics only (zero matrix under total
// internal reflection). M(0, 0) is the library's unpolarized reflectance (transmittance) exactly.
Mueller facet_reflection_mueller(const Material& mat, double cos_i, bool from_outside = true);
Mueller facet_transmission_mueller(const Material& mat, double cos_i, bool from_outside = true);

// Reciprocity: the Mueller matrix of the reversed path in matched frames (the reverse path keeps
// each beam's reference axis; y flips with the propagation direction): Q M^T Q, Q = diag(1, 1, -1, 1).
Mueller reversed_path_mueller(const Mueller& M);

// One specular event of a path: the facet normal m (pointing out of the material) and whether
// the ray is refracted through it (dielectrics) instead of reflected.
struct PathEvent {
  Vec3 m;
  bool refract = false;
};

struct PathMueller {
  Mueller M = Mueller::Zero();  // input Stokes frame -> output Stokes frame
  Vec3 direction_out = Vec3::Zero();  // the outgoing direction (away from the surface)
  bool valid = false;  // false: a conductor hit from inside, a refraction under total reflection
};

// The Mueller matrix of a specular path: light from the direction wi (travelling along -wi, Stokes
// axis x_in, perpendicular to wi) meets the facets in order; the result maps the incoming Stokes
// vector to the outgoing one in the frame of axis x_out (default stokes_frame(direction_out)).
// x_in default stokes_frame(wi).
PathMueller path_mueller(const Vec3& wi, const std::vector<PathEvent>& events, const Material& mat,
                         std::optional<Vec3> x_in = std::nullopt, std::optional<Vec3> x_out = std::nullopt);

// The same product built one event at a time, for a walk that follows a ray: start at the light's
// direction, add each facet as the ray meets it, read the matrix in the frame of the outgoing
// direction at the end. path_mueller is this loop.
class PathMuellerBuilder {
 public:
  explicit PathMuellerBuilder(const Vec3& wi, std::optional<Vec3> x_in = std::nullopt);
  // Applies the facet of normal m (reflection, or refraction when `refract`); false (and the
  // builder unchanged) for a conductor or mirror hit from inside or a refraction under total
  // internal reflection.
  bool add(const Vec3& m, bool refract, const Material& mat);
  const Vec3& direction() const { return d_; }  // current direction of travel
  // The matrix so far, from the input frame to the frame of axis x_out (default
  // stokes_frame(direction())) of the current direction.
  Mueller matrix(std::optional<Vec3> x_out = std::nullopt) const;

 private:
  Vec3 d_, x_;  // direction of travel, current reference axis
  Mueller M_ = Mueller::Identity();
};

// Coherency (Cloude) matrix of M: Hermitian 4 x 4, trace M(0, 0), positive semidefinite exactly
// when M is a convex sum of Jones Mueller matrices (physically realizable). For M of one Jones
// matrix J it is vec(J) vec(J)^H / 2.
Eigen::Matrix4cd coherency_matrix(const Mueller& M);
double min_coherency_eigenvalue(const Mueller& M);
// Realizable: the coherency matrix's eigenvalues are >= -tol * max(M(0,0), 0) (and M(0,0) >= 0).
bool is_realizable(const Mueller& M, double tol = 1e-12);

}  // namespace microsim::models
