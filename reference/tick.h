// One servo tick of the reference pipeline (DESIGN.md "One servo tick"; thesis Fig. 4.1, §4.1.1).
//
//   device sample (q, qd, t)          -> forward kinematics: x1, R1, V1 = J1^-1 qd      (2.2)
//   observer (3.7)-(3.8)              -> f1_hat (joint), F1_hat = J1^T f1_hat (maximal)
//   collision (ContactProvider)       -> contact set {x_o, n, r, depth, material}
//   proxy solve: PMI (4.9) with coupling (4.5), contact (2.16)/(2.19), friction (2.21),
//     decomposition feed-forward T2_pd (4.7)  -> V2_hat, then x2, R2 at k+1            (2.7)
//     (or explicit Euler with the same force elements evaluated at V_k, the baseline)
//   device command T1 = T1_vc (4.3)-(4.4) + T1_pd (4.7) -> tau1 = J1^-T T1 (+ g(q)), saturated
//
// Methods: kExplicitVc = explicit-Euler proxy + standard coupling; kPmiVc = PMI proxy + PMI
// coupling; kPmiPd = kPmiVc + passive decomposition + momentum observer.
//
// Frames: T1 is a wrench on the device in maximal coordinates (f in {O}, tau in the device body
// frame); tau1 = J1^-T T1 since qd = J1 V1 makes qd^T tau1 = V1^T T1. The observer's joint
// estimate maps the same way: F1_hat = J1^T f1_hat.
//
// Drilling is not part of the tick here: the caller (simulator) applies it after the tick from
// the returned contact set and contact wrench (see reference/tooth/drilling.h).
#pragma once

#include <memory>
#include <vector>

#include "reference/core/affine_wrench.h"
#include "reference/core/contact_provider.h"
#include "reference/core/device_model.h"
#include "reference/core/params.h"
#include "reference/grip_detector.h"
#include "reference/observer.h"

namespace dentsim {

struct PipelineConfig {
  Method method = Method::kPmiVc;
  ProxyParams proxy;
  CouplingGains coupling;
  FrictionParams friction;
  ToolDynamics tool;            // desired locked dynamics (kPmiPd)
  VecX observer_gain;           // L per joint [1/s] (kPmiPd; also run for the estimate when set)
  ObserverInput observer_input;  // input matched to the driver's velocity estimate (observer.h)
  VecX torque_limit;            // |tau_i| <= torque_limit_i [N m]; empty = no saturation
  // Add the model's gravity torque g(q) to the command: the thesis assumes gravity compensated
  // (2.1); the observer accounts for it either way since it sees the total torque.
  bool compensate_gravity = true;
  // kPmiPd with a hand on the tool: the device model plus the hand's nominal mass (must outlive
  // the pipeline; its base() must be the pipeline's device model). Set, the pipeline runs a
  // GripDetector (reference/grip_detector.h) in place of the single observer and uses, tick by
  // tick, the estimate and the mass matrix of the hypothesis it judges true.
  const GraspMassModel* grasp_model = nullptr;
  GripDetectorParams grip_detector;
};

// Stages of the tick, for timing (TickResult::stage_ns).
enum TickStage { kStageKinematics, kStageObserver, kStageCollision, kStageSolve, kStageCommand,
                 kStageCount };
const char* tick_stage_name(int stage);  // "kinematics", "observer", "collision", "solve", "command"

// Everything one tick computed (for logging, tests and the fast path's differential tests).
struct TickResult {
  Pose device;                        // x1, R1
  Vec6 V1 = Vec6::Zero();             // device twist
  Vec6 F1_hat = Vec6::Zero();         // human wrench estimate (maximal), zero without observer
  Vec6 T1_vc = Vec6::Zero();          // coupling wrench on the device
  Vec6 T1_pd = Vec6::Zero();          // decomposition feed-forward on the device
  Vec6 T1 = Vec6::Zero();             // total device wrench before saturation
  VecX tau;                           // joint torques sent to the device (saturated)
  VecX tau_gravity;                   // the gravity-compensation part of tau (zero when off)
  bool saturated = false;
  Vec6 V_hat = Vec6::Zero();          // proxy velocity the forces were evaluated at
  Vec6 F_contact = Vec6::Zero();      // contact + friction wrench on the proxy at V_hat
  Vec6 F_coupling = Vec6::Zero();     // coupling wrench on the proxy at V_hat
  std::vector<Contact> contacts;      // the contact set of this tick
  double max_depth = 0.0;             // deepest penetration in the set [m]
  bool friction_sliding = false;
  int grip_state = -1;                // grip detector: 1 gripped, 0 released, -1 no detector
  double grip_statistic = 0.0;        // its statistic s [N^2/kg] (GripDetector::statistic)
  long stage_ns[kStageCount] = {};    // wall-clock time of each stage [ns] (steady_clock)
};

// The pipeline interface both reference/ and fast/ implement.
class Pipeline {
 public:
  virtual ~Pipeline() = default;
  // Places the proxy on the device pose at rest and resets the observer.
  virtual void reset(const DeviceSample& s) = 0;
  // One tick of length T (the time until the next sample; may vary tick to tick).
  virtual const TickResult& tick(const DeviceSample& s, double T, ContactProvider& contacts) = 0;
  virtual const ProxyState& proxy() const = 0;
};

class ReferencePipeline : public Pipeline {
 public:
  // `device` must outlive the pipeline. Throws std::invalid_argument on inconsistent config
  // (e.g. kPmiPd without an observer gain of the device's size).
  ReferencePipeline(const SixDofDeviceModel& device, PipelineConfig config);
  ~ReferencePipeline() override;

  void reset(const DeviceSample& s) override;
  const TickResult& tick(const DeviceSample& s, double T, ContactProvider& contacts) override;
  const ProxyState& proxy() const override { return proxy_; }
  const PipelineConfig& config() const { return config_; }

 private:
  const SixDofDeviceModel& device_;
  PipelineConfig config_;
  ProxyState proxy_;
  std::unique_ptr<MomentumObserver> observer_;
  std::unique_ptr<GripDetector> grip_;
  VecX tau_prev_;           // torque applied during the previous tick (observer input)
  double t_prev_ = 0.0;     // time of the previous sample
  bool have_prev_ = false;
  TickResult result_;
};

}  // namespace dentsim
