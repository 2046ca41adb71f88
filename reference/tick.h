// One servo tick of the reference pipeline (docs/design.md "One servo tick"; thesis Fig. 4.1,
// §4.1.1), written as the Model/Data stages of reference/core/pipeline.h:
//
//   device_terms  device sample (q, qd, t) -> x1, R1, J_t, M, C^T qd, g, tau_f in one pass of
//                 the device model; J1 = J_t^-1 (one LU), V1 = J_t qd                   (2.2)
//   observe       momentum observer (3.7)-(3.8) -> f1_hat (joint), F1_hat = J1^T f1_hat
//                 (or the grip detector's two observers, reference/grip_detector.h)
//   collide       ContactProvider -> contact set {x_o, n, r, depth, material}
//   assemble      force elements on the proxy, affine in V_hat: coupling (4.5), contact
//                 (2.16)/(2.19), decomposition feed-forward T2_pd (4.7); device coupling T1_vc
//                 (4.3)-(4.4); the PMI system (4.9)
//   solve         PMI (4.9) with friction (2.21)-(2.22) -> V2_hat, x2, R2 at k+1       (2.7)
//                 (or explicit Euler with the same force elements at V_k, the baseline)
//   command       T1 = T1_vc (4.3)-(4.4) + T1_pd (4.7) -> tau1 = J_t^T T1 (+ g(q)), saturated
//   drill         the environment's cut over the tick (ContactProvider::drill)
//
// Methods: kExplicitVc = explicit-Euler proxy + standard coupling; kPmiVc = PMI proxy + PMI
// coupling; kPmiPd = kPmiVc + passive decomposition + momentum observer.
//
// Frames: T1 is a wrench on the device in maximal coordinates (f in {O}, tau in the device body
// frame); with V1 = J_t qd the joint torque of T1 is tau1 = J_t^T T1 (= J1^-T T1), since
// qd^T tau1 = V1^T T1. The observer's joint estimate maps the same way: F1_hat = J1^T f1_hat.
//
// The stages never throw and never allocate: constant inputs are validated once, when the
// model is built (make_pipeline_model, with the messages users get), and the tick returns a
// TickStatus (reference/core/pipeline.h).
#pragma once

#include <memory>

#include "reference/core/contact_provider.h"
#include "reference/core/pipeline.h"
#include "reference/friction.h"
#include "reference/grasp_mass_model.h"

namespace dentsim {

struct PipelineConfig {
  Method method = Method::kPmiVc;
  ProxyParams proxy;
  CouplingGains coupling;
  FrictionParams friction;
  ToolDynamics tool;             // desired locked dynamics (kPmiPd)
  VecX observer_gain;            // L per joint [1/s] (kPmiPd; also run for the estimate when set)
  ObserverInput observer_input;  // input matched to the driver's velocity estimate (observer.h)
  VecX torque_limit;             // |tau_i| <= torque_limit_i [N m]; empty = no saturation
  // Add the model's gravity torque g(q) to the command: the thesis assumes gravity compensated
  // (2.1); the observer accounts for it either way since it sees the total torque.
  bool compensate_gravity = true;
  // kPmiPd with a hand on the tool: the device model plus the hand's nominal mass (must outlive
  // the pipeline; its base() must be the pipeline's device model). Set, the pipeline runs a
  // grip detector (reference/grip_detector.h) in place of the single observer and uses, tick by
  // tick, the estimate and the mass matrix of the hypothesis it judges true.
  const GraspMassModel* grasp_model = nullptr;
  GripDetectorParams grip_detector;
  bool skip_unneeded = true;  // PipelineModel::skip_unneeded
  bool time_stages = true;    // PipelineModel::time_stages (false: stage_ns stays zero)
  // The encoder Kalman filter (reference/encoder_kalman.h): a sub-count estimate of (q, qd) from
  // the quantised encoders, per joint quantum `encoder_quantum` (the device's; empty or zero:
  // that joint passes through). Off by default.
  bool encoder_kalman = false;
  VecX encoder_quantum;
  EncoderKalmanParams encoder_kalman_params;
  // Loop-lag compensation (reference/lag_compensation.h): the coupling and the decomposition's
  // D_d see the device velocity advanced over the loop's known lags with the device model. Off by
  // default. `velocity_estimate` describes the driver's velocity estimate (a backward difference?
  // its low-pass cut-off): device/device.h matched_observer_input of the device's capabilities.
  bool lag_compensation = false;
  ObserverInput velocity_estimate;
  // Shape control passive under actuator saturation (reference/saturation_passive.h; issue #29):
  // after a tick whose command saturated, the decomposition's feed-forward is scaled by what the
  // device delivered and the coupling's linear spring is capped at the force the device can
  // deliver along it. Needs torque_limit; changes nothing while the command does not saturate.
  // Off by default (as the scene key method.saturation_passive).
  bool saturation_passive = false;
};

// Validates `config` against `device` and builds the constant model of the tick. Throws
// std::invalid_argument (or InputError) naming what is wrong: an observer gain of the wrong size
// or not positive, kPmiPd without an observer gain, a torque limit of the wrong size, a grasp
// model on another device, bad proxy parameters, coupling gains, friction coefficient, tool
// dynamics or grip-detector parameters. `device` must outlive the model.
PipelineModel make_pipeline_model(const SixDofDeviceModel& device, const PipelineConfig& config);

// The reference stages (same names and signatures as fast/tick.h's).
namespace reference {
TickStatus device_terms(const PipelineModel& m, PipelineData& d);
TickStatus observe(const PipelineModel& m, PipelineData& d);
TickStatus collide(const PipelineModel& m, PipelineData& d);
TickStatus assemble(const PipelineModel& m, PipelineData& d);
TickStatus solve(const PipelineModel& m, PipelineData& d);
TickStatus command(const PipelineModel& m, PipelineData& d);
TickStatus drill(const PipelineModel& m, PipelineData& d);
// Proxy on the device pose at rest, observers at rest on the sample in d (device_terms first).
TickStatus reset(const PipelineModel& m, PipelineData& d);

// The parts of assemble and solve that fast/ shares (it brings its own contact wrench and PMI
// solver; everything else in these two stages is one code).
namespace detail {
// assemble with d.contact already computed.
TickStatus assemble_given_contact(const PipelineModel& m, PipelineData& d);
// solve with `pmi_solver` for the frictionless PMI system (4.9), `friction_solver` for the system
// with friction (reference/friction.h's or fast/friction.h's) and `friction` (m.friction, or
// fast/'s mu = 0 stand-in when skips are off). The friction solver runs when friction is enabled
// and the contact set is not empty (or `even_without_contacts`).
TickStatus solve_with(const PipelineModel& m, PipelineData& d,
                      bool (*pmi_solver)(const PmiSystem&, Vec6*), FrictionSolve friction_solver,
                      const FrictionParams& friction, bool even_without_contacts = false);
}  // namespace detail
}  // namespace reference

// The reference implementation's entry of the stage registry.
const StageTable& reference_stage_table();

// The pipeline interface every implementation offers to the loop owner (device/closed_loop.h).
class Pipeline {
 public:
  virtual ~Pipeline() = default;
  // Places the proxy on the device pose at rest and resets the observer.
  virtual TickStatus reset(const DeviceSample& s) = 0;
  // One tick of length T (the time until the next sample; may vary tick to tick). Never throws;
  // the result's status says whether the tick succeeded (if not, its torque is zero).
  virtual const TickResult& tick(const DeviceSample& s, double T, ContactProvider& contacts) = 0;
  virtual const ProxyState& proxy() const = 0;
  virtual const char* name() const = 0;  // "reference", "fast"
};

// A Pipeline running one StageTable over its own model and data.
class StagedPipeline : public Pipeline {
 public:
  // Builds the model (make_pipeline_model: throws on a bad configuration) and the data.
  StagedPipeline(const StageTable& table, const SixDofDeviceModel& device,
                 const PipelineConfig& config);
  TickStatus reset(const DeviceSample& s) override;
  const TickResult& tick(const DeviceSample& s, double T, ContactProvider& contacts) override;
  const ProxyState& proxy() const override { return data_->proxy; }
  const char* name() const override { return table_->implementation; }
  const PipelineModel& model() const { return model_; }
  const PipelineData& data() const { return *data_; }
  PipelineData& mutable_data() { return *data_; }

 private:
  const StageTable* table_;
  PipelineModel model_;
  std::unique_ptr<PipelineData> data_;
};

class ReferencePipeline : public StagedPipeline {
 public:
  ReferencePipeline(const SixDofDeviceModel& device, const PipelineConfig& config)
      : StagedPipeline(reference_stage_table(), device, config) {}
};

}  // namespace dentsim
