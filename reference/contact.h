// Penalty contact of the proxy with the tooth: depth, contact-point Jacobian, aggregation of a
// contact set, and the contact wrench with its PMI terms and damping (thesis §2.3, (2.15)-(2.19),
// the PMI system (4.9)). Derivations: docs/derivations/contact_and_friction.md.
//
// Units: m, s, N, N m; K [N/m], B [N s/m].
// Frames: twist V = [v (world {O}); w (body {B})], wrench F = [f (world); tau (body)], V^T F is
// power. A contact point on the proxy is r in the proxy body frame: x_c = x2 + R2 r. n is the unit
// outward tooth normal in the world frame; x_o is on the tooth surface (world).
//
//   depth          delta = n^T (x_o - x_c)                 > 0 penetrating               (§2.3)
//   point velocity xdot_c = v + R S(w) r = [I, -R S(r)] V = J_c V
//   depth rate     d(delta)/dt = -n^T J_c V = n^T [-I, R S(r)] V                          (2.16)
//   wrench of f    F = J_c^T f = [I; S(r) R^T] f  (body torque of f at x_c, about x2)    (2.15)
//
// Torque frame: the body-frame torque of f applied at x_c is R^T ((R r) x f) = S(r) R^T f. The
// thesis prints R^T S(r) f in (2.15), (2.19), (4.9), (4.10); that equals the correct value only
// when R = I. We use S(r) R^T (the transpose of J_c's angular block, so that V^T F = f^T xdot_c);
// tests/reference/contact_test.cc pins it with a power test and shows the printed form fails it.
//
// Aggregation (one contact set = what collision reports for ONE tool-tip sphere): each member i
// gets a normalised weight w_i (contact_weights, sum w_i = 1), and the set acts as the weighted
// blend  f = sum_i w_i K_i delta_i n_i. The same geometric contact reported N times (or by N finer
// faces at the same depth) gives w_i = 1/N and exactly the force of one report, and the set's
// stiffness d f/d delta = sum w_i K_i n_i n_i^T never exceeds max K_i (a finer tooth does not feel
// stiffer). Weights are normalised over the whole reported set; a member whose depth, recomputed
// from the pose, is <= 0 contributes nothing (unilateral), so the force is continuous in the pose.
#pragma once

#include <span>
#include <vector>

#include "reference/core/affine_wrench.h"
#include "reference/core/contact_provider.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// x_c = x2 + R2 r: the contact point on the proxy in the world frame.
Vec3 contact_point(const Contact& c, const Pose& proxy);

// delta = n^T (x_o - x_c), recomputed from the pose (> 0 = penetrating) (§2.3).
double penetration_depth(const Contact& c, const Pose& proxy);

// J_c = [I, -R S(r)]: xdot_c = J_c V for V = [v (world); w (body)].
Mat36 contact_point_jacobian(const Vec3& r, const Mat3& R);

// J_c^T = [I; S(r) R^T]: the wrench [f (world); tau (body)] of a world force f applied at x_c
// (2.15), with the torque frame as derived above (not the printed R^T S(r)).
Mat63 contact_wrench_map(const Vec3& r, const Mat3& R);

// Normalised blend weights of a contact set: w_i = weight_i / sum_j weight_j (sum 1); if all
// weights are zero, equal weights 1/N. Empty set -> empty vector. Throws InputError naming the
// member if a weight is negative or not finite.
std::vector<double> contact_weights(std::span<const Contact> contacts);

// The same weights without a vector (the servo tick's form; no validation): w(c) =
// c.weight / sum over the set, or 1/N when all weights are zero. Bitwise equal to
// contact_weights.
class ContactWeights {
 public:
  explicit ContactWeights(std::span<const Contact> contacts);
  double operator()(const Contact& c) const {
    return sum_ > 0.0 ? c.weight / sum_ : 1.0 / static_cast<double>(n_);
  }

 private:
  double sum_ = 0.0;
  std::size_t n_ = 0;
};

// Whether every member satisfies validate_contacts's rules (never throws).
bool contacts_well_formed(std::span<const Contact> contacts);

// Penalty contact (2.15)-(2.16) + damping (2.19) of a contact set as a wrench affine in the proxy
// twist, F(V) = f0 + G V. With w_i from contact_weights, J_i = J_c(r_i, R2), d_i = -n_i^T J_i
// (so d(delta_i)/dt = d_i V), and only members with delta_i,k > 0 (depth recomputed from `proxy`):
//   kMidpoint (PMI, evaluate at V_hat_k; (2.16)-(2.18), (4.9)):
//     f_i = w_i K_i (delta_i,k + T/2 d_i V) n_i + w_i B_i (d_i V) n_i
//     f0 = sum J_i^T w_i K_i delta_i,k n_i,  G = -sum (w_i K_i T/2 + w_i B_i) J_i^T n_i n_i^T J_i
//   kExplicit (explicit Euler, evaluate at V_k): the spring at its value at t_k, damping at V_k:
//     f0 as above, G = -sum w_i B_i J_i^T n_i n_i^T J_i.
//     An explicit caller evaluates F.at(V_k); it must not put G into an implicit system.
// G is symmetric negative semidefinite, so the PMI contact never generates energy for fixed n, r
// (exactly so for translation). The spring part never pulls at t_k (delta_i,k > 0); the midpoint
// value K (delta_k + delta_k+1)/2 becomes negative only on a tick that leaves the surface faster
// than delta_k+1 < -delta_k, and damping (Kelvin-Voigt) pulls while separating.
// Throws InputError if T is not positive and finite or a member is malformed (non-unit normal,
// negative or non-finite stiffness/damping/weight, non-finite x_o or r).
AffineWrench contact_wrench(std::span<const Contact> contacts, const Pose& proxy, double T,
                            Scheme scheme);

// contact_wrench without validation (the tick checks the set with contacts_well_formed and T
// once): never throws, never allocates.
AffineWrench contact_wrench_unchecked(std::span<const Contact> contacts, const Pose& proxy,
                                      double T, Scheme scheme);

// The surface-proxy contact's spring across its normal (issue #32; reference/tooth/sdf.h): that
// contact renders K (g - c) to an anchor g, c = x2 + R2 o the tool sphere's centre. Across n the
// force turns with the tool only as far as the anchor does not follow it: the across-normal
// stiffness is K_t = h w K, h = 1 - (how far g follows c across n) in [0, 1] (0 where g slides
// freely on a face, 1 where it is held, as in a drilled hole). contact_wrench integrates only the
// part along n; the rest is evaluated at t_k, i.e. explicitly inside the implicit step. Over one
// PMI tick with an explicit spring K_e and the implicit damping C (coupling and proxy dampers),
//     E_k+1 - E_k = -T V_hat^T (C - T/2 K_e J_o^T (I - n n^T) J_o) V_hat
// (the implicit elements are energy-neutral or dissipative), so the explicit part is stable
// iff K_e T/2 <= b_t, b_t the damping C gives the centre across n (a 1-DoF check: the map of
// m x'' = -K_e x_k - K_c x_hat - b v_hat has determinant 1 + 2T(K_e T - 2b)/(4m + K_c T^2 + 2bT):
// < 1 iff K_e T < 2b, whatever m and K_c; docs/derivations/sdf_contact.md §3a).
// 1/b_t <= 1/b_lin + |o|^2/b_ang bounds the centre's mobility across n, so
//     b_t = 1 / (1/b_lin + |o|^2/b_ang)    (0 if b_lin = 0, or b_ang = 0 with o != 0).
// add_anchored_spring_unchecked keeps the spring explicit up to that bound and integrates the
// excess, K_imp = K_t - 2 b_t/T when positive, at its midpoint value (under kMidpoint only):
//     G -= sum_i K_imp,i T/2 J_o^T (I - n_i n_i^T) J_o,   J_o = J_c(o, R2),
// over the penetrating members. Where K_t T/2 <= b_t nothing is added (F unchanged, bit for bit).
struct AnchoredSpring {
  Vec3 center = Vec3::Zero();  // o, the tool sphere's centre in the proxy body frame [m]
  double held = 0.0;           // h in [0, 1]: the fraction of K the anchor holds across n
};
// The damping b_t [N s/m] the implicit step gives the centre o across any direction (above).
double anchored_spring_damping(const Vec3& center, double b_lin, double b_ang);
// kExplicit: no change. b_lin, b_ang: the implicit linear and angular damping on the proxy
// (coupling plus proxy damping). Never throws, never allocates.
void add_anchored_spring_unchecked(AffineWrench* F, std::span<const Contact> contacts,
                                   const Pose& proxy, double T, Scheme scheme,
                                   const AnchoredSpring& spring, double b_lin, double b_ang);
// The anchored spring of `env` when it renders the surface-proxy contact (kSurfaceProxy, kField),
// else nullptr. Defined with the tooth (reference/tooth/tooth_contacts.cc).
const AnchoredSpring* anchored_spring(const ContactProvider* env);

// Contact potential U = sum_i w_i 1/2 K_i delta_i^2 over members with delta_i > 0 [J].
// -dU/dt = V^T F(V) for the spring part (F at kExplicit without damping).
double contact_potential(std::span<const Contact> contacts, const Pose& proxy);

// The contact set blended into one contact point, used by friction (2.20)-(2.22): over the members
// with delta_i > 0 and weight a_i = w_i, r = sum a_i r_i / sum a_i, n = normalised sum a_i n_i,
// depth = sum a_i delta_i / sum a_i. `active` is false when no member penetrates (or the blended
// normal vanishes); then the other fields are meaningless.
struct BlendedContact {
  bool active = false;
  Vec3 n = Vec3::UnitZ();
  Vec3 r = Vec3::Zero();
  double depth = 0.0;
};
BlendedContact blended_contact(std::span<const Contact> contacts, const Pose& proxy);

// Throws InputError naming `where` and the member if a contact is malformed (see contact_wrench).
void validate_contacts(std::span<const Contact> contacts, const char* where);

}  // namespace dentsim
