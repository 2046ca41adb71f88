#include "device/scripted_hand.h"

#include <cmath>
#include <string>

#include "reference/core/io.h"
#include "reference/core/so3.h"

namespace dentsim {
namespace {

void check_nonneg(double v, const char* field) {
  if (!(std::isfinite(v) && v >= 0.0)) {
    throw InputError(std::string("scripted hand: impedance.") + field + " = " + std::to_string(v) +
                     ", expected a finite value >= 0");
  }
}

}  // namespace

ScriptedHand::ScriptedHand(HandImpedance impedance, std::vector<HandKeyframe> profile, Mat3 R_ref)
    : z_(impedance), profile_(std::move(profile)), R_ref_(R_ref) {
  check_nonneg(z_.mass, "mass");
  check_nonneg(z_.inertia, "inertia");
  check_nonneg(z_.k_lin, "k_lin");
  check_nonneg(z_.b_lin, "b_lin");
  check_nonneg(z_.k_ang, "k_ang");
  check_nonneg(z_.b_ang, "b_ang");
  if (profile_.empty()) throw InputError("scripted hand: profile is empty, expected >= 1 keyframe");
  for (std::size_t i = 0; i < profile_.size(); ++i) {
    const HandKeyframe& k = profile_[i];
    if (!std::isfinite(k.t) || !k.x_ref.allFinite() || !k.wrench_ff.allFinite()) {
      throw InputError("scripted hand: keyframe " + std::to_string(i) +
                       " has a non-finite value, expected finite t, x_ref, wrench_ff");
    }
    if (i > 0 && !(k.t > profile_[i - 1].t)) {
      throw InputError("scripted hand: keyframe " + std::to_string(i) +
                       " has t = " + std::to_string(k.t) + ", expected > " +
                       std::to_string(profile_[i - 1].t) + " (strictly increasing times)");
    }
  }
  if (!R_ref_.allFinite()) throw InputError("scripted hand: R_ref is not finite");
}

ScriptedHand ScriptedHand::holding(HandImpedance impedance, const Pose& pose) {
  HandKeyframe k;
  k.x_ref = pose.x;
  return ScriptedHand(impedance, {k}, pose.R);
}

int ScriptedHand::segment(double t) const {
  if (t < profile_.front().t) return -1;
  for (std::size_t i = 0; i + 1 < profile_.size(); ++i) {
    if (t < profile_[i + 1].t) return static_cast<int>(i);
  }
  return static_cast<int>(profile_.size()) - 1;
}

Vec3 ScriptedHand::x_ref(double t) const {
  const int i = segment(t);
  if (i < 0) return profile_.front().x_ref;
  if (i + 1 >= static_cast<int>(profile_.size())) return profile_.back().x_ref;
  const HandKeyframe& a = profile_[i];
  const HandKeyframe& b = profile_[i + 1];
  const double s = (t - a.t) / (b.t - a.t);
  return a.x_ref + s * (b.x_ref - a.x_ref);
}

Vec3 ScriptedHand::v_ref(double t) const {
  const int i = segment(t);
  if (i < 0 || i + 1 >= static_cast<int>(profile_.size())) return Vec3::Zero();
  const HandKeyframe& a = profile_[i];
  const HandKeyframe& b = profile_[i + 1];
  return (b.x_ref - a.x_ref) / (b.t - a.t);
}

Vec6 ScriptedHand::wrench_ff(double t) const {
  const int i = segment(t);
  if (i < 0) return profile_.front().wrench_ff;
  if (i + 1 >= static_cast<int>(profile_.size())) return profile_.back().wrench_ff;
  const HandKeyframe& a = profile_[i];
  const HandKeyframe& b = profile_[i + 1];
  const double s = (t - a.t) / (b.t - a.t);
  return a.wrench_ff + s * (b.wrench_ff - a.wrench_ff);
}

Vec6 ScriptedHand::wrench(const Pose& tip, const Vec6& V, double t) const {
  Vec6 F = wrench_ff(t);
  // f = f_ff + K_h (x_ref - x) + B_h (v_ref - v)   (world)
  F.head<3>() += z_.k_lin * (x_ref(t) - tip.x) + z_.b_lin * (v_ref(t) - V.head<3>());
  // tau = tau_ff + k_hw log(R^T R_ref) - b_hw w     (body)
  F.tail<3>() += z_.k_ang * so3_spring_vector(tip.R.transpose() * R_ref_) - z_.b_ang * V.tail<3>();
  return F;
}

}  // namespace dentsim
