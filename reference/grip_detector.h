// Is the hand on the tool? A sensorless grip detector for the passive decomposition's model
// (docs/derivations/decomposition_and_observer.md §9).
//
// Why: the momentum observer attributes whatever its model lacks to the human force. With a hand
// of mass m_h gripping the tool and a model without it, the estimate carries -m_h a and the
// feed-forward (4.7) turns it into a negative damping; with the hand's mass in the model
// (reference/grasp_mass_model.h) and the hand gone, the model carries a mass that is no longer
// there and the term flips sign. Neither fixed model survives both grip and release.
//
// How: two momentum observers run side by side on the same input, one on the device model
// alone (hypothesis H0: no hand) and one on the device plus the hand's nominal mass (H1: gripped).
// Their estimates h0, h1 (maximal coordinates, F = J1^T f_hat) differ by the hand's inertial
// reaction, h1 - h0 = Mt a seen through the observer's lag (Mt = diag(m I, J I)). Which
// hypothesis is right cannot be told from one sample (an external force -Mt a and a mass Mt are
// the same to the device); it can be told from the prior that a human's own force is slow: the
// right hypothesis leaves the smaller high-frequency force. The statistic is
//     s = P1 - P0,   P_i = lowpass_tau( |highpass(h_i)|^2 in the norm Mt^-1 )   [N^2/kg]
// with the high-pass replaced by a band-pass (4-20 Hz by default, two first-order stages). The
// state changes on accumulated evidence (Page's CUSUM), so that a brief human force transient
// does not flip it:
//     g_r = max(0, g_r + T (s - release_threshold))    while gripped:  released when g_r > G
//     g_g = max(0, g_g + T (-s - grip_threshold))      while released: gripped  when g_g > G
// with G = evidence [N^2 s/kg]; both sums restart at a switch. Only the linear force enters (the norm's rotational part is
// dropped: the gimbal's encoder noise swamps the hand's small rotational inertia).
// For a hand of stiffness K_h oscillating at w on the tool, P0 - P1 = m_h w^2 |x|^2 (m_h w^2 -
// 2 K_h): a cycle faster than sqrt(2 K_h / m_h) (3.5 Hz for the literature hand) is explained
// better by H1. After a release, H1 reports m_h a and s rises at once. Encoder noise n in the
// velocity biases s upward (it reaches h_i as L M_i n, larger in the heavier model); the band's
// upper edge keeps most of it out. Thresholds: docs/derivations/decomposition_and_observer.md §9.
#pragma once

#include <memory>

#include "reference/grasp_mass_model.h"
#include "reference/observer.h"

namespace dentsim {

// GripDetectorParams: reference/core/params.h.

// The detector's filters and decision for one tick, given the two hypotheses' estimates
// h0 (no hand), h1 (gripped) in maximal coordinates; `norm` is the diagonal of the statistic's
// norm (1/m on the force, 0 on the torque). Shared by GripDetector and the tick's observe stage.
// Returns whether the hand is judged on the tool after this tick.
void grip_filter_reset(const GripDetectorParams& p, GripFilterState& s);
bool grip_filter_update(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                        const Vec6& h0, const Vec6& h1, double T);
// The filters' three gains for a tick of length T (GripFilterGains, reference/core/pipeline.h),
// and the update with them given: grip_filter_update(p, norm, s, h0, h1, T) is this with
// grip_filter_gains(p, T), so gains kept from an earlier tick of the same T give the same doubles.
GripFilterGains grip_filter_gains(const GripDetectorParams& p, double T);
bool grip_filter_update(const GripDetectorParams& p, const Vec6& norm, GripFilterState& s,
                        const Vec6& h0, const Vec6& h1, const GripFilterGains& g, double T);
// Throws std::invalid_argument naming the parameter unless the hand has mass and inertia and the
// filter constants and thresholds are valid (used when a pipeline model is built, too).
void validate_grip_detector(double hand_mass, double hand_inertia, const GripDetectorParams& p);

class GripDetector {
 public:
  // `grasp` (its base is the device model alone) must outlive the detector. Throws
  // std::invalid_argument for a grasp model without mass or inertia, non-positive filter
  // constants or negative thresholds.
  GripDetector(const GraspMassModel& grasp, const VecX& gain_L, ObserverInput input,
               GripDetectorParams params = {});

  void reset(const VecX& q, const VecX& qd);
  // One tick (as MomentumObserver::update) with the Jacobian J1 = twist_to_joint(q). Returns
  // whether the hand is judged on the tool after this tick.
  bool update(const VecX& q, const VecX& qd, const VecX& tau, double T, const Mat6& J1);

  bool gripped() const { return f_.gripped; }
  // The human wrench estimate (maximal coordinates) under the current hypothesis, and the model
  // that hypothesis uses.
  const Vec6& estimate() const { return f_.gripped ? f_.h1 : f_.h0; }
  const SixDofDeviceModel& model() const;
  double statistic() const { return f_.p1 - f_.p0; }  // s [N^2/kg]
  const Vec6& estimate_released() const { return f_.h0; }
  const Vec6& estimate_gripped() const { return f_.h1; }
  const GripDetectorParams& params() const { return params_; }

 private:
  const GraspMassModel& grasp_;
  GripDetectorParams params_;
  MomentumObserver obs0_, obs1_;
  Vec6 w_ = Vec6::Zero();  // diagonal of the norm: 1/m on the force, 0 on the torque
  GripFilterState f_;
};

}  // namespace dentsim
