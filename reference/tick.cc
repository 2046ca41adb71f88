#include "reference/tick.h"

#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "reference/contact.h"
#include "reference/coupling.h"
#include "reference/decomposition.h"
#include "reference/explicit_euler.h"
#include "reference/friction.h"
#include "reference/observer.h"
#include "reference/pmi.h"

namespace dentsim {

const char* tick_stage_name(int stage) {
  static const char* const kNames[kStageCount] = {"kinematics", "observer", "collision", "solve",
                                                  "command"};
  return stage >= 0 && stage < kStageCount ? kNames[stage] : "?";
}

namespace {

// Records the wall-clock time of consecutive stages.
class StageClock {
 public:
  explicit StageClock(long* out) : out_(out), last_(std::chrono::steady_clock::now()) {}
  void lap(int stage) {
    const auto now = std::chrono::steady_clock::now();
    out_[stage] = std::chrono::duration_cast<std::chrono::nanoseconds>(now - last_).count();
    last_ = now;
  }

 private:
  long* out_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace

ReferencePipeline::ReferencePipeline(const SixDofDeviceModel& device, PipelineConfig config)
    : device_(device), config_(std::move(config)) {
  const int n = device_.dof();
  if (config_.observer_gain.size() != 0) {
    if (config_.observer_gain.size() != n) {
      throw std::invalid_argument("observer gain has " +
                                  std::to_string(config_.observer_gain.size()) +
                                  " entries; the device has " + std::to_string(n) + " joints");
    }
    if (config_.grasp_model) {
      if (&config_.grasp_model->base() != &device_) {
        throw std::invalid_argument(
            "grasp_model: its base model must be the pipeline's device model");
      }
      grip_ = std::make_unique<GripDetector>(*config_.grasp_model, config_.observer_gain,
                                             config_.observer_input, config_.grip_detector);
    } else {
      observer_ = std::make_unique<MomentumObserver>(device_, config_.observer_gain,
                                                     config_.observer_input);
    }
  } else if (config_.method == Method::kPmiPd) {
    throw std::invalid_argument("method pmi-pd needs the observer gain L (one per joint)");
  }
  if (config_.torque_limit.size() != 0 && config_.torque_limit.size() != n) {
    throw std::invalid_argument("torque limit has " +
                                std::to_string(config_.torque_limit.size()) +
                                " entries; the device has " + std::to_string(n) + " joints");
  }
  tau_prev_ = VecX::Zero(n);
  result_.tau = VecX::Zero(n);
  result_.contacts.reserve(kContactCapacity);
}

ReferencePipeline::~ReferencePipeline() = default;

void ReferencePipeline::reset(const DeviceSample& s) {
  proxy_ = ProxyState{};
  proxy_.pose = device_.forward_kinematics(s.q);
  tau_prev_.setZero();
  if (observer_) observer_->reset(s.q, s.qd);
  if (grip_) grip_->reset(s.q, s.qd);
  t_prev_ = s.t;
  have_prev_ = false;
  result_ = TickResult{};
  result_.tau = VecX::Zero(device_.dof());
  result_.contacts.reserve(kContactCapacity);
}

const TickResult& ReferencePipeline::tick(const DeviceSample& s, double T,
                                          ContactProvider& contacts) {
  if (!(T > 0.0) || !std::isfinite(T)) {
    throw std::invalid_argument("tick length must be positive and finite");
  }
  TickResult& r = result_;
  StageClock clock(r.stage_ns);
  const Method method = config_.method;
  const Scheme scheme = method == Method::kExplicitVc ? Scheme::kExplicit : Scheme::kMidpoint;

  // Device kinematics (2.2): x1, R1, V1 = J1^-1 qd.
  r.device = device_.forward_kinematics(s.q);
  const Mat6 J1 = device_.twist_to_joint(s.q);
  const Eigen::PartialPivLU<Mat6> J1_lu(J1);
  r.V1 = J1_lu.solve(Vec6(s.qd));
  clock.lap(kStageKinematics);

  // Observer (3.7)-(3.8): joint estimate from the torque applied over the last tick, which
  // lasted from the previous sample to this one (tick lengths may vary).
  r.F1_hat.setZero();
  const double T_last = have_prev_ && s.t > t_prev_ ? s.t - t_prev_ : T;
  t_prev_ = s.t;
  have_prev_ = true;
  if (observer_) {
    const VecX& f1_hat = observer_->update(s.q, s.qd, tau_prev_, T_last);
    r.F1_hat = J1.transpose() * f1_hat;  // F1 = J1^T f1
  }
  r.grip_state = -1;
  if (grip_) {
    r.grip_state = grip_->update(s.q, s.qd, tau_prev_, T_last, J1) ? 1 : 0;
    r.grip_statistic = grip_->statistic();
    r.F1_hat = grip_->estimate();
  }
  clock.lap(kStageObserver);

  // Collision.
  contacts.contacts(proxy_.pose, r.contacts);  // (capacity: see the constructor)
  r.max_depth = 0.0;
  for (const Contact& c : r.contacts) {
    r.max_depth = std::max(r.max_depth, penetration_depth(c, proxy_.pose));
  }
  clock.lap(kStageCollision);

  // Force elements on the proxy, affine in the velocity they are evaluated at.
  const AffineWrench coupling =
      coupling_proxy_wrench(config_.coupling, r.device, r.V1, proxy_, T, scheme);
  const AffineWrench contact = contact_wrench(r.contacts, proxy_.pose, T, scheme);
  AffineWrench pd_T1, pd_T2;
  if (method == Method::kPmiPd) {
    const SixDofDeviceModel& model = grip_ ? grip_->model() : device_;
    const Mat6 M1 = J1.transpose() * model.mass_matrix(s.q) * J1;  // (2.2)
    const Decomposition d = decompose(M1, config_.proxy.M(), r.device.R, proxy_.pose.R);
    const PdFeedforward pd = pd_feedforward(d, config_.tool, r.V1, r.F1_hat, contact);
    pd_T1 = pd.T1;
    pd_T2 = pd.T2;
  }

  // Device-side coupling (4.3)-(4.4): uses the proxy at k and V_hat_2,k-1.
  r.T1_vc = coupling_device_wrench(config_.coupling, r.device, r.V1, proxy_, T, scheme);

  Vec6 friction_wrench = Vec6::Zero();
  r.friction_sliding = false;
  if (method == Method::kExplicitVc) {
    // Explicit Euler: every force at V_k.
    r.V_hat = proxy_.V;
    const Vec6 F = coupling.at(proxy_.V) + contact.at(proxy_.V);
    r.F_coupling = coupling.at(proxy_.V);
    r.F_contact = contact.at(proxy_.V);
    r.T1_pd.setZero();
    proxy_ = explicit_euler_advance(config_.proxy, proxy_, F, T);
  } else {
    // PMI (4.9): one linear solve for V_hat, friction as tangential multipliers (2.21)-(2.22).
    PmiSystem sys = pmi_inertia_system(config_.proxy, proxy_, T);
    sys.add(coupling);
    sys.add(contact);
    if (method == Method::kPmiPd) sys.add(pd_T2);
    if (config_.friction.enabled && !r.contacts.empty()) {
      const FrictionSolution fs =
          solve_with_friction(sys, r.contacts, proxy_.pose, contact, config_.friction);
      r.V_hat = fs.V;
      r.friction_sliding = fs.sliding;
      friction_wrench = fs.F;  // (4.10)
    } else {
      r.V_hat = pmi_solve(sys);
    }
    r.F_coupling = coupling.at(r.V_hat);
    r.F_contact = contact.at(r.V_hat) + friction_wrench;
    r.T1_pd = method == Method::kPmiPd ? pd_T1.at(r.V_hat) : Vec6::Zero();
    proxy_ = pmi_advance(proxy_, r.V_hat, T);
  }
  clock.lap(kStageSolve);

  // Device command: tau1 = J1^-T T1 + g(q), scaled down uniformly (direction kept) to the limits.
  r.T1 = r.T1_vc + r.T1_pd;
  r.tau = J1_lu.transpose().solve(r.T1);
  if (config_.compensate_gravity) {
    r.tau_gravity = device_.gravity(s.q);  // (2.1): gravity compensated
    r.tau += r.tau_gravity;
  } else {
    r.tau_gravity = VecX::Zero(r.tau.size());
  }
  r.saturated = false;
  if (config_.torque_limit.size() != 0) {
    double scale = 1.0;
    for (int i = 0; i < r.tau.size(); ++i) {
      const double a = std::abs(r.tau(i));
      if (a > config_.torque_limit(i)) scale = std::min(scale, config_.torque_limit(i) / a);
    }
    if (scale < 1.0) {
      r.tau *= scale;
      r.tau_gravity *= scale;
      r.saturated = true;
    }
  }
  tau_prev_ = r.tau;
  clock.lap(kStageCommand);
  return r;
}

}  // namespace dentsim
