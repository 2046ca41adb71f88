#include "reference/grip_detector.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "reference/core/lowpass.h"

namespace dentsim {
namespace {

void require_positive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("GripDetector: ") + what +
                                " must be finite and > 0, got " + std::to_string(v));
  }
}

void require_non_negative(double v, const char* what) {
  if (!(v >= 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("GripDetector: ") + what +
                                " must be finite and >= 0, got " + std::to_string(v));
  }
}

}  // namespace

void validate_grip_detector(double hand_mass, double hand_inertia, const GripDetectorParams& p) {
  require_positive(hand_mass, "the hand's mass in the grasp model");
  require_positive(hand_inertia, "the hand's inertia in the grasp model");
  require_positive(p.highpass_hz, "highpass_hz");
  require_positive(p.lowpass_hz, "lowpass_hz");
  if (!(p.lowpass_hz > p.highpass_hz)) {
    throw std::invalid_argument("GripDetector: lowpass_hz must exceed highpass_hz (a band)");
  }
  require_positive(p.power_time_constant_s, "power_time_constant_s");
  require_non_negative(p.release_threshold, "release_threshold");
  require_non_negative(p.grip_threshold, "grip_threshold");
  require_positive(p.evidence, "evidence");
}

void grip_filter_reset(const GripDetectorParams& p, GripFilterState& s) {
  s = GripFilterState{};
  s.gripped = p.start_gripped;
}

GripFilterGains grip_filter_gains(const GripDetectorParams& p, double T) {
  GripFilterGains g;
  // Band-pass: b = lowpass_fhi(h), then the high-pass e = b - lowpass_flo(b).
  g.a_lp = lowpass_gain(p.lowpass_hz, T);
  g.a_hp = lowpass_gain(p.highpass_hz, T);
  // The band power's low-pass, time constant tau_p.
  const double f_p = 1.0 / (2.0 * std::numbers::pi * p.power_time_constant_s);
  g.a_p = lowpass_gain(f_p, T);
  return g;
}

bool grip_filter_update(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                        const Vec6& h0, const Vec6& h1, double T) {
  return grip_filter_update(p, norm, s, h0, h1, grip_filter_gains(p, T), T);
}

bool grip_filter_update(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                        const Vec6& h0, const Vec6& h1, const GripFilterGains& g, double T) {
  s.h0 = h0;
  s.h1 = h1;
  // Band-pass: b = lowpass_fhi(h), then the high-pass e = b - lowpass_flo(b).
  const double a_lp = g.a_lp, a_hp = g.a_hp, a_p = g.a_p;
  s.b0 += a_lp * (s.h0 - s.b0);
  s.b1 += a_lp * (s.h1 - s.b1);
  s.lp0 += a_hp * (s.b0 - s.lp0);
  s.lp1 += a_hp * (s.b1 - s.lp1);
  const Vec6 e0 = s.b0 - s.lp0, e1 = s.b1 - s.lp1;
  // Band power of the linear force in the norm 1/m, low-passed with time constant tau_p.
  s.p0 += a_p * (e0.cwiseProduct(norm).dot(e0) - s.p0);
  s.p1 += a_p * (e1.cwiseProduct(norm).dot(e1) - s.p1);
  const double stat = s.p1 - s.p0;
  if (s.gripped) {
    s.g_release = std::max(0.0, s.g_release + T * (stat - p.release_threshold));
    if (s.g_release > p.evidence) {
      s.gripped = false;
      s.g_release = s.g_grip = 0.0;
    }
  } else {
    s.g_grip = std::max(0.0, s.g_grip + T * (-stat - p.grip_threshold));
    if (s.g_grip > p.evidence) {
      s.gripped = true;
      s.g_release = s.g_grip = 0.0;
    }
  }
  return s.gripped;
}

GripDetector::GripDetector(const GraspMassModel& grasp, const VecX& gain_L, ObserverInput input,
                           GripDetectorParams params)
    : grasp_(grasp),
      params_(params),
      obs0_(grasp.base(), gain_L, input),
      obs1_(grasp, gain_L, input) {
  validate_grip_detector(grasp.mass(), grasp.inertia(), params_);
  w_ << Vec3::Constant(1.0 / grasp.mass()), Vec3::Zero();
  grip_filter_reset(params_, f_);
}

const SixDofDeviceModel& GripDetector::model() const {
  return f_.gripped ? static_cast<const SixDofDeviceModel&>(grasp_) : grasp_.base();
}

void GripDetector::reset(const VecX& q, const VecX& qd) {
  obs0_.reset(q, qd);
  obs1_.reset(q, qd);
  grip_filter_reset(params_, f_);
}

bool GripDetector::update(const VecX& q, const VecX& qd, const VecX& tau, double T,
                          const Mat6& J1) {
  const Vec6 h0 = J1.transpose() * obs0_.update(q, qd, tau, T);  // F = J1^T f_hat
  const Vec6 h1 = J1.transpose() * obs1_.update(q, qd, tau, T);
  return grip_filter_update(params_, w_, f_, h0, h1, T);
}

}  // namespace dentsim
