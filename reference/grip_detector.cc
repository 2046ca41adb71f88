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

GripDetector::GripDetector(const GraspMassModel& grasp, const VecX& gain_L, ObserverInput input,
                           GripDetectorParams params)
    : grasp_(grasp),
      params_(params),
      obs0_(grasp.base(), gain_L, input),
      obs1_(grasp, gain_L, input),
      gripped_(params.start_gripped) {
  require_positive(grasp.mass(), "the hand's mass in the grasp model");
  require_positive(grasp.inertia(), "the hand's inertia in the grasp model");
  require_positive(params_.highpass_hz, "highpass_hz");
  require_positive(params_.lowpass_hz, "lowpass_hz");
  if (!(params_.lowpass_hz > params_.highpass_hz)) {
    throw std::invalid_argument("GripDetector: lowpass_hz must exceed highpass_hz (a band)");
  }
  require_positive(params_.power_time_constant_s, "power_time_constant_s");
  require_non_negative(params_.release_threshold, "release_threshold");
  require_non_negative(params_.grip_threshold, "grip_threshold");
  require_positive(params_.evidence, "evidence");
  w_ << Vec3::Constant(1.0 / grasp.mass()), Vec3::Zero();
}

const SixDofDeviceModel& GripDetector::model() const {
  return gripped_ ? static_cast<const SixDofDeviceModel&>(grasp_) : grasp_.base();
}

void GripDetector::reset(const VecX& q, const VecX& qd) {
  obs0_.reset(q, qd);
  obs1_.reset(q, qd);
  h0_.setZero();
  h1_.setZero();
  b0_.setZero();
  b1_.setZero();
  lp0_.setZero();
  lp1_.setZero();
  p0_ = p1_ = 0.0;
  g_release_ = g_grip_ = 0.0;
  gripped_ = params_.start_gripped;
}

bool GripDetector::update(const VecX& q, const VecX& qd, const VecX& tau, double T,
                          const Mat6& J1) {
  h0_ = J1.transpose() * obs0_.update(q, qd, tau, T);  // F = J1^T f_hat
  h1_ = J1.transpose() * obs1_.update(q, qd, tau, T);
  // Band-pass: b = lowpass_fhi(h), then the high-pass e = b - lowpass_flo(b).
  const double a_lp = lowpass_gain(params_.lowpass_hz, T);
  const double a_hp = lowpass_gain(params_.highpass_hz, T);
  b0_ += a_lp * (h0_ - b0_);
  b1_ += a_lp * (h1_ - b1_);
  lp0_ += a_hp * (b0_ - lp0_);
  lp1_ += a_hp * (b1_ - lp1_);
  const Vec6 e0 = b0_ - lp0_, e1 = b1_ - lp1_;
  // Band power of the linear force in the norm 1/m, low-passed with time constant tau_p.
  const double f_p = 1.0 / (2.0 * std::numbers::pi * params_.power_time_constant_s);
  const double a_p = lowpass_gain(f_p, T);
  p0_ += a_p * (e0.cwiseProduct(w_).dot(e0) - p0_);
  p1_ += a_p * (e1.cwiseProduct(w_).dot(e1) - p1_);
  const double s = p1_ - p0_;
  if (gripped_) {
    g_release_ = std::max(0.0, g_release_ + T * (s - params_.release_threshold));
    if (g_release_ > params_.evidence) {
      gripped_ = false;
      g_release_ = g_grip_ = 0.0;
    }
  } else {
    g_grip_ = std::max(0.0, g_grip_ + T * (-s - params_.grip_threshold));
    if (g_grip_ > params_.evidence) {
      gripped_ = true;
      g_release_ = g_grip_ = 0.0;
    }
  }
  return gripped_;
}

}  // namespace dentsim
