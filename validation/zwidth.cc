#include "validation/zwidth.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <numbers>
#include <thread>

#include "device/closed_loop.h"
#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "fast/registry.h"
#include "plant/mujoco_plant.h"
#include "plant/phantom_mjcf.h"
#include "reference/core/io.h"
#include "reference/grasp_mass_model.h"
#include "reference/phantom/phantom_model.h"
#include "reference/rigid_body_device.h"
#include "reference/tick.h"
#include "reference/tools.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/tooth_contacts.h"
#include "validation/thread_pool.h"

namespace dentsim {

const char* operator_name(ZwidthOperator op) {
  switch (op) {
    case ZwidthOperator::kGrip:
      return "grip";
    case ZwidthOperator::kForce:
      return "force";
    case ZwidthOperator::kTap:
      return "tap";
    case ZwidthOperator::kRelease:
      return "release";
  }
  return "unknown";
}

ZwidthOperator parse_operator(const std::string& s) {
  if (s == "grip") return ZwidthOperator::kGrip;
  if (s == "force") return ZwidthOperator::kForce;
  if (s == "tap") return ZwidthOperator::kTap;
  if (s == "release") return ZwidthOperator::kRelease;
  throw InputError("operator: expected one of grip, force, tap, release, got '" + s + "'");
}

const char* testbed_name(ZwidthTestbed t) { return t == ZwidthTestbed::kAxis ? "axis" : "phantom"; }

ZwidthTestbed parse_testbed(const std::string& s) {
  if (s == "axis") return ZwidthTestbed::kAxis;
  if (s == "phantom") return ZwidthTestbed::kPhantom;
  throw InputError("testbed: expected axis or phantom, got '" + s + "'");
}

ZwidthGains ZwidthGrid::at(std::size_t i) const {
  const std::size_t nt = k_tooth.size(), nk = k_vc.size();
  ZwidthGains g;
  g.k_tooth = k_tooth[i % nt];
  g.k_vc = k_vc[(i / nt) % nk];
  g.b_vc = b_vc[i / (nt * nk)];
  return g;
}

double colgate_schenkel_max_stiffness(double b_device, double b_virtual, double T) {
  return std::max(0.0, 2.0 * (b_device - b_virtual) / T);  // b > K T / 2 + B
}

double pmi_coupling_max_stiffness(double b_device, double b_vc, double T_k, double T_km1) {
  return std::max(0.0, (b_device - b_vc * (1.0 + T_k / T_km1)) / T_k);  // thesis §3.1
}

namespace {

// The Z-width testbed of one job: a device, the pipeline's (possibly wrong) model of it and
// access to the ground truth the metrics need.
class Rig {
 public:
  virtual ~Rig() = default;
  virtual Device& device() = 0;
  virtual const SixDofDeviceModel& model() const = 0;
  virtual void set_hand(const ScriptedHand* hand) = 0;
  virtual Pose true_tip() const = 0;
};

class AxisRig : public Rig {
 public:
  explicit AxisRig(const ZwidthScenario& sc)
      : dev_(axis_params(sc), Vec3::Zero()),
        model_(axis_device_model_params(sc.axis.mass * sc.model_mass_scale,
                                        sc.axis.damping * sc.model_damping_scale)) {}
  Device& device() override { return dev_; }
  const SixDofDeviceModel& model() const override { return model_; }
  void set_hand(const ScriptedHand* hand) override { dev_.set_hand(hand); }
  Pose true_tip() const override { return dev_.tip_pose(); }

  static AxisDeviceParams axis_params(const ZwidthScenario& sc) {
    AxisDeviceParams p = sc.axis;
    p.period = sc.tick;
    p.jitter_half_width = sc.jitter_half_width;
    p.seed = sc.seed;
    return p;
  }

 private:
  AxisDevice dev_;
  RigidBodyDevice model_;
};

PhantomParams phantom_truth(const ZwidthScenario& sc) {
  PhantomParams p = sc.phantom_device_params ? *sc.phantom_device_params : default_phantom_params();
  p.gravity_on = false;  // a gravity-compensated device, as the thesis assumes (2.1)
  if (sc.phantom_damping.minCoeff() >= 0.0) p.damping_n_m_s_per_rad = sc.phantom_damping;
  return p;
}

// What the pipeline believes: its model file (gravity-compensated like the device) or the
// device's, with every inertia (masses, body inertias, armature) and the damping scaled; the
// geometry (kinematics) exact.
PhantomParams phantom_belief(const ZwidthScenario& sc) {
  PhantomParams p = phantom_truth(sc);
  if (sc.phantom_pipeline_params) {
    p = *sc.phantom_pipeline_params;
    p.gravity_on = false;
  }
  const double s = sc.model_mass_scale;
  for (PhantomBody* b : {&p.base, &p.upper_arm, &p.forearm, &p.crank, &p.parallel_link,
                         &p.gimbal_yaw, &p.gimbal_pitch, &p.gimbal_roll}) {
    b->mass_kg *= s;
    b->inertia_kg_m2 *= s;
  }
  p.armature_kg_m2 *= s;
  p.damping_n_m_s_per_rad *= sc.model_damping_scale;
  return p;
}

// The simulated Phantom's joint encoder quanta [rad]: the device model file's
// encoder_counts_per_rev when `--device` gave one (issue #29: a finer gimbal encoder), else the
// built-in 1024 CPR x4 x drive ratio (the default file's counts, kept bit for bit).
VecX phantom_testbed_quantum(const ZwidthScenario& sc) {
  if (sc.phantom_device_params) {
    return phantom_device_config(*sc.phantom_device_params).encoder_quantum;
  }
  return encoder_quantum(1024, 4, phantom_drive_ratios());
}

class PhantomRig : public Rig {
 public:
  explicit PhantomRig(const ZwidthScenario& sc)
      : truth_(phantom_truth(sc)), model_(make_phantom_model(sc.pipeline, phantom_belief(sc))) {
    SimulatedDeviceConfig cfg;
    cfg.gravity = false;
    cfg.encoder_quantum = phantom_testbed_quantum(sc);
    if (sc.phantom_device_params) {
      // The model file's motor limit (issue #29): its torque_limit_n_m clamp, or with
      // "torque_limit": {"model": "thermal"} the motors' peak and thermal model. Without a file
      // the built-in clamp (the default file's, bit for bit).
      const SimulatedDeviceConfig file = phantom_device_config(*sc.phantom_device_params);
      cfg.tau_max = file.tau_max;
      cfg.tau_fault = file.tau_fault;
      cfg.torque_limit = file.torque_limit;
    }
    if (sc.jitter_half_width > 0.0) {
      cfg.jitter.kind = TickJitterKind::kUniform;
      cfg.jitter.half_width = sc.jitter_half_width;
    }
    cfg.jitter.period = sc.tick;
    cfg.jitter.seed = sc.seed;
    dev_ = std::make_unique<SimulatedPhantom>(phantom_plant(truth_), cfg, VecX(sc.phantom_q0));
  }
  Device& device() override { return *dev_; }
  const SixDofDeviceModel& model() const override { return *model_; }
  void set_hand(const ScriptedHand* hand) override { dev_->set_hand(hand); }
  Pose true_tip() const override { return dev_->tip_pose(); }

 private:
  PhantomParams truth_;
  // The pipeline implementation's evaluation of the believed model (fast/registry.h).
  std::unique_ptr<SixDofDeviceModel> model_;
  std::unique_ptr<SimulatedPhantom> dev_;
};

std::unique_ptr<Rig> make_rig(const ZwidthScenario& sc) {
  if (sc.testbed == ZwidthTestbed::kAxis) return std::make_unique<AxisRig>(sc);
  return std::make_unique<PhantomRig>(sc);
}

// A slab of enamel voxels, 64^3 grid of voxel size h centred laterally on `centre`, top face
// (normal +z) at height z_surface, solid below it for half the grid.
VoxelTooth enamel_slab(const Vec3& centre, double z_surface, double h) {
  const int n = 64;
  VoxelGrid g(n, Vec3(centre.x() - 0.5 * n * h, centre.y() - 0.5 * n * h, z_surface - 0.5 * n * h),
              h);
  for (int k = 0; k < n / 2; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) g.set(i, j, k, kEnamel);
    }
  }
  return VoxelTooth(std::move(g));
}

// Tip-space damping along z and encoder quantum along z of a testbed at its start pose.
struct TipProperties {
  double damping = 0.0;  // (J1^T B J1)_zz [N s/m]
  double mass = 0.0;     // (J1^T M J1)_zz [kg]
  double quantum = 0.0;  // sum_i |dz/dq_i| Delta_i [m]
};

TipProperties tip_properties(const ZwidthScenario& sc) {
  TipProperties tp;
  if (sc.testbed == ZwidthTestbed::kAxis) {
    tp.damping = sc.axis.damping;
    tp.mass = sc.axis.mass;
    tp.quantum = sc.axis.quantum;
    return tp;
  }
  const PhantomParams p = phantom_truth(sc);
  const PhantomModel m(p);
  const VecX q0 = sc.phantom_q0;
  const Mat6 J1 = m.twist_to_joint(q0);
  const Mat6 B = p.damping_n_m_s_per_rad.asDiagonal();
  tp.damping = (J1.transpose() * B * J1)(2, 2);
  tp.mass = (J1.transpose() * m.mass_matrix(q0) * J1)(2, 2);
  const Mat6 Jt = m.model().tool_jacobian(q0);
  const VecX quantum = phantom_testbed_quantum(sc);
  for (int i = 0; i < 6; ++i) tp.quantum += std::abs(Jt(2, i)) * quantum(i);
  return tp;
}

// The quiet measures of a run's contact (every sample of qs is after first contact + settle).
QuietPhase zwidth_quiet_measures(const QuietSeries& qs, const QuietBounds& b, double quantum) {
  QuietPhase q;
  q.phase = "hold";
  q.kind = "press";
  q.touched = !qs.t.empty();
  q.ticks = static_cast<long>(qs.t.size());
  if (q.touched) {
    q.t_begin_s = qs.t.front();
    q.steady_from_s = qs.t.front();
    q.t_end_s = qs.t.back() + qs.tick_s;
    const int h = quiet_half_window(b, qs.tick_s);
    q.ripple_contact_force = force_ripple(qs.contact_force_n, h);
    q.ripple_device_force = force_ripple(qs.device_force_n, h);
    q.contact_fraction = contact_fraction(qs.contacts);
    q.contact_losses = contact_losses(qs.contacts);
    q.oscillation_amplitude_m = std::numbers::sqrt2 * residual_rms(qs.tip_z_m, h);
    q.oscillation_amplitude_quanta = quantum > 0.0 ? q.oscillation_amplitude_m / quantum : 0.0;
    q.mean_contact_force_n = mean(qs.contact_force_n);
    q.mean_device_force_n = mean(qs.device_force_n);
    q.mean_penetration_m = mean(qs.device_penetration_m);
    q.static_stiffness_n_per_m = static_stiffness(qs.device_force_n, qs.device_penetration_m);
    q.motor_energy_j = rise(qs.energy_j);
  }
  q.quiet = phase_is_quiet(q, b);
  return q;
}

// Least-squares slope of y against x (0 for fewer than two points).
double ls_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 2) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

}  // namespace

double testbed_tip_damping(const ZwidthScenario& sc) { return tip_properties(sc).damping; }
double testbed_tip_quantum(const ZwidthScenario& sc) { return tip_properties(sc).quantum; }

namespace {

void check_zwidth_inputs(const ZwidthGains& gains, const ZwidthScenario& sc) {
  if (!(sc.hold_s > sc.settle_s + 2.0 * sc.window_s) || !(sc.window_s > 0.0)) {
    throw InputError("zwidth scenario: hold_s must exceed settle_s + 2 window_s");
  }
  if (!(gains.k_vc > 0.0) || !(gains.k_tooth > 0.0) || gains.b_vc < 0.0) {
    throw InputError("zwidth gains: expected k_vc > 0, k_tooth > 0, b_vc >= 0");
  }
}

// The operator's hand: its impedance, its keyframes from the start tip tip0 toward the wall's
// surface z_s, and the approach speed (tap: approach_speed, grip and release: the scenario's).
struct ZwidthOperatorScript {
  HandImpedance z;
  std::vector<HandKeyframe> frames;
  double speed = 0.0;
};

ZwidthOperatorScript operator_script(ZwidthOperator op, const ZwidthScenario& sc, const Pose& tip0,
                                     double z_s, double approach_speed) {
  const double rho = sc.tip_radius_m;
  ZwidthOperatorScript script;
  HandImpedance& z = script.z;
  z = sc.hand;
  script.speed = op == ZwidthOperator::kTap ? approach_speed : sc.grip_speed_m_s;
  const double speed = script.speed;
  if (op == ZwidthOperator::kForce) {
    z = HandImpedance{0, 0, 0, 0, 0, 0};
    HandKeyframe a, b;
    a.t = 0.0;
    a.x_ref = tip0.x;
    b.t = sc.force_ramp_s;
    b.x_ref = tip0.x;
    b.wrench_ff(2) = -sc.push_force_n;
    script.frames = {a, b};
  } else {
    if (!(speed > 0.0) || !(z.k_lin > 0.0)) {
      throw InputError("zwidth operator " + std::string(operator_name(op)) +
                       ": expected approach speed > 0 and hand stiffness > 0");
    }
    const double z_target = z_s + rho - sc.push_force_n / z.k_lin;
    HandKeyframe a, b;
    a.t = 0.0;
    a.x_ref = tip0.x;
    b.t = (tip0.x.z() - z_target) / speed;
    b.x_ref = Vec3(tip0.x.x(), tip0.x.y(), z_target);
    script.frames = {a, b};
  }
  return script;
}

// What the pipeline believes about the device: the rig's model, plus (grasp_mass_scale > 0)
// the nominal mass of the hand gripping the tool (reference/grasp_mass_model.h). The `force`
// operator has no hand mass, so a fixed mass is not added there.
// With the grip detector the model's hand is there under `force` too (starting "gripped"):
// the detector has to find that no hand is on the tool. Null: no hand mass.
std::unique_ptr<GraspMassModel> zwidth_grasp_model(const ZwidthScenario& sc, const Rig& rig,
                                                   const HandImpedance& z) {
  std::unique_ptr<GraspMassModel> grasp;
  if (sc.grasp_mass_scale > 0.0 && (z.mass > 0.0 || sc.grip_detector)) {
    grasp = std::make_unique<GraspMassModel>(rig.model(), sc.grasp_mass_scale * sc.hand.mass,
                                             sc.grasp_mass_scale * sc.hand.inertia);
  }
  return grasp;
}

// The pipeline on `model` (what it believes), with the method's and the scenario's settings.
std::unique_ptr<Pipeline> zwidth_pipeline(Method method, const ZwidthGains& gains,
                                          const ZwidthScenario& sc, Rig& rig,
                                          const GraspMassModel* grasp,
                                          const SixDofDeviceModel& model) {
  Device& dev = rig.device();
  const bool detect = grasp && sc.grip_detector;
  PipelineConfig pc;
  pc.method = method;
  pc.proxy = sc.proxy;
  if (sc.proxy_damping_rule) {
    pc.proxy.damping_lin = std::max(pc.proxy.damping_lin, 0.5 * gains.k_vc * sc.tick);
  }
  pc.coupling = CouplingGains{gains.k_vc, sc.k_vc_ang, gains.b_vc, sc.b_vc_ang};
  if (sc.pipeline_saturation) pc.torque_limit = dev.limits().tau_max;
  if (detect) {
    pc.grasp_model = grasp;
    pc.grip_detector = sc.grip_detector_params;
  }
  // As sim/simulator.cc sets them from a scene's method block.
  pc.encoder_kalman = sc.encoder_kalman;
  pc.encoder_kalman_params.model_friction = sc.encoder_kalman_friction;
  pc.encoder_kalman_params.stick_slip = sc.encoder_kalman_stick_slip;
  pc.encoder_quantum = dev.capabilities().encoder_quantum;
  pc.lag_compensation = sc.lag_compensation;
  pc.velocity_estimate = matched_observer_input(dev.capabilities());
  pc.time_stages = false;  // a sweep reads no stage time: no clock read in its ticks
  DeviceSample s0 = dev.make_sample();
  dev.read(s0);
  if (method == Method::kPmiPd) {
    pc.observer_gain = VecX::Constant(6, sc.observer_gain);
    if (sc.observer_input_matched) pc.observer_input = matched_observer_input(dev.capabilities());
    // The locked inertia is floored on the heaviest model the pipeline may use (with the
    // detector: the gripped one), so the desired dynamics do not change when it switches.
    const SixDofDeviceModel& heaviest =
        grasp ? static_cast<const SixDofDeviceModel&>(*grasp) : rig.model();
    const Mat6 J1 = heaviest.twist_to_joint(s0.q);
    const Mat6 M1 = J1.transpose() * heaviest.mass_matrix(s0.q) * J1;  // (2.2)
    pc.tool = tool_preset(sc.tool, M1 + sc.proxy.M());                 // floor M_L at the start
  }
  return make_pipeline(sc.pipeline, model, pc);
}

// One run's measurements tick by tick: torque bookkeeping for the energy tolerance, the contact
// phase (penetration, forces, the quiet signals, the tail means), the grip detector, the trace.
struct ZwidthMeter {
  ZwidthMeter(ZwidthOperator op_in, const ZwidthScenario& sc_in, Rig& rig_in, ZwidthRun& run_in,
              ZwidthTrace* trace_in)
      : op(op_in), sc(sc_in), rig(rig_in), run(run_in), trace(trace_in) {
    n = rig.device().dof();
    tau_max = VecX::Zero(n);
    tau_var = VecX::Zero(n);
    tau_prev = VecX::Zero(n);
    qs.tick_s = sc.tick;
  }

  // The largest torque and the total variation per joint (ZwidthRun::energy_tol_j).
  void record_torque(const VecX& tau) {
    for (int i = 0; i < n; ++i) {
      tau_max(i) = std::max(tau_max(i), std::abs(tau(i)));
      tau_var(i) += std::abs(tau(i) - tau_prev(i));
    }
    tau_prev = tau;
  }

  // A tick from first contact on: force, penetration p, energy E at time t.
  void in_contact(const TickResult& r, double t, double force, double p, double E) {
    run.contact = true;
    run.max_force_n = std::max(run.max_force_n, force);
    run.max_penetration_m = std::max(run.max_penetration_m, p);
    if (t >= t_first + sc.settle_s) {
      ts.push_back(t);
      ps.push_back(p);
    }
    if (t >= t_first + sc.quiet.settle_s) {
      qs.t.push_back(t);
      qs.contacts.push_back(static_cast<int>(r.contacts.size()));
      qs.contact_force_n.push_back(r.F_contact.head<3>().norm());
      qs.device_force_n.push_back(force);
      qs.device_penetration_m.push_back(std::max(0.0, p));
      qs.tip_z_m.push_back(p);
      qs.energy_j.push_back(E);
    }
    if (t >= t_first + sc.hold_s - 1.0) {
      sum_f += force;
      sum_p += p;
      ++n_tail;
    }
    if (r.grip_state >= 0) {
      ++n_grip_ticks;
      const bool hand_on = op != ZwidthOperator::kForce && !released;
      if ((r.grip_state == 1) == hand_on) ++n_grip_agree;
      if (released && r.grip_state == 0 && run.release_detected_after_s < 0.0) {
        run.release_detected_after_s = t - t_released;
      }
    }
    if (op == ZwidthOperator::kRelease && !released && t >= t_first + sc.release_after_s) {
      rig.set_hand(nullptr);
      released = true;
      t_released = t;
    }
  }

  // The grip detector's switches and the range of its statistic with the hand on and off.
  void grip_statistics(const TickResult& r) {
    if (r.grip_state >= 0 && last_grip >= 0 && r.grip_state != last_grip) ++run.grip_switches;
    if (r.grip_state >= 0 && !released) {
      const bool first = n_on++ == 0;
      run.grip_statistic_max_on =
          first ? r.grip_statistic : std::max(run.grip_statistic_max_on, r.grip_statistic);
      run.grip_statistic_min_on =
          first ? r.grip_statistic : std::min(run.grip_statistic_min_on, r.grip_statistic);
    } else if (r.grip_state >= 0) {
      run.grip_statistic_max_off =
          n_off++ == 0 ? r.grip_statistic : std::max(run.grip_statistic_max_off, r.grip_statistic);
    }
    last_grip = r.grip_state;
  }

  void trace_tick(const TickResult& r, double t, double force, double p, double E) {
    if (!trace) return;
    trace->t.push_back(t);
    trace->penetration_m.push_back(p);
    trace->force_n.push_back(force);
    trace->energy_j.push_back(E);
    trace->grip_state.push_back(r.grip_state);
    trace->grip_statistic.push_back(r.grip_statistic);
  }

  const ZwidthOperator op;
  const ZwidthScenario& sc;
  Rig& rig;
  ZwidthRun& run;
  ZwidthTrace* trace;
  int n = 0;  // the device's degrees of freedom
  VecX tau_max, tau_var, tau_prev;
  double t_first = -1.0;
  bool released = false;
  double t_released = -1.0;
  int last_grip = -1;
  long n_grip_ticks = 0, n_grip_agree = 0, n_on = 0, n_off = 0;
  std::vector<double> ts, ps;  // penetration after first contact + settle
  // The quiet measures' signals, from first contact + quiet.settle_s (sim/quiet_measures.h).
  QuietSeries qs;
  double sum_f = 0, sum_p = 0;
  long n_tail = 0;
};

// The closed loop against the wall (surface z_s) until the hold after first contact is over, a
// fault, a non-finite state, or the time cap.
void run_zwidth_ticks(ClosedLoop& loop, const Pipeline& pipeline, const SixDofDeviceModel& model,
                      double z_s, double cap, ZwidthMeter& meter) {
  const ZwidthScenario& sc = meter.sc;
  ZwidthRun& run = meter.run;
  Device& dev = meter.rig.device();
  const double rho = sc.tip_radius_m;
  DeviceSample prev = loop.sample();
  for (;;) {
    const TickResult& r = loop.step();
    const DeviceSample& s = loop.sample();
    const double t = s.t;
    const Pose tip = meter.rig.true_tip();
    if (!tip.x.allFinite() || !pipeline.proxy().pose.x.allFinite() || !r.tau.allFinite()) {
      run.finite = false;
      break;
    }
    run.faults |= dev.faults();
    if (run.faults != kFaultNone) break;
    run.saturated = run.saturated || r.saturated;
    const VecX& tau = dev.applied_torque();
    meter.record_torque(tau);
    const Mat6 J1 = model.twist_to_joint(prev.q);
    // The force fed back: the motors' wrench T1 = J1^T tau along the wall normal n = +z.
    const double force = std::max(0.0, Vec6(J1.transpose() * tau)(2));
    const double p = rho - (tip.x.z() - z_s);
    const double E = loop.energy_virtual_j();
    if (rho - (pipeline.proxy().pose.x.z() - z_s) >= 2.0 * rho) run.proxy_tunnelled = true;
    run.energy_max_j = std::max(run.energy_max_j, E);
    if (meter.t_first < 0.0 && !r.contacts.empty()) meter.t_first = t;
    if (meter.t_first >= 0.0) meter.in_contact(r, t, force, p, E);
    meter.grip_statistics(r);
    meter.trace_tick(r, t, force, p, E);
    prev = s;
    if (meter.t_first >= 0.0 && t >= meter.t_first + sc.hold_s) break;
    if (t >= cap) break;
  }
}

// Envelope: peak-to-peak per full window of the penetration after first contact + settle, and the
// growth rate of ln(A + Delta_n) (a least-squares slope over the windows). Returns the number of
// full windows.
std::size_t penetration_envelope(const ZwidthMeter& meter, double quantum, ZwidthRun& run) {
  const ZwidthScenario& sc = meter.sc;
  const std::vector<double>& ts = meter.ts;
  const std::vector<double>& ps = meter.ps;
  std::vector<double> wc, wl;
  if (!ts.empty()) {
    std::size_t i = 0;
    while (i < ts.size()) {
      const double w0 = ts[i];
      double lo = ps[i], hi = ps[i];
      std::size_t j = i;
      while (j < ts.size() && ts[j] < w0 + sc.window_s) {
        lo = std::min(lo, ps[j]);
        hi = std::max(hi, ps[j]);
        ++j;
      }
      if (ts[j - 1] - w0 >= 0.9 * sc.window_s - 1e-12) {  // full windows only
        wc.push_back(w0 + 0.5 * sc.window_s);
        wl.push_back(std::log(hi - lo + quantum + 1e-12));
        run.last_amplitude_m = hi - lo;
      }
      i = j;
    }
  }
  run.growth_rate_per_s = ls_slope(wc, wl);
  run.growth_limit_per_s = std::log(2.0) / (sc.hold_s - sc.settle_s);
  return wc.size();
}

// After the loop: energy tolerance, contact time, grip agreement, Z-width, static stiffness.
void zwidth_totals(const ClosedLoop& loop, const ZwidthMeter& meter, const VecX& quantum,
                   ZwidthRun& run) {
  run.energy_final_j = loop.energy_virtual_j();
  run.energy_tol_j = 1e-9;
  for (int i = 0; i < meter.n; ++i) {
    run.energy_tol_j += quantum(i) * (2.0 * meter.tau_max(i) + meter.tau_var(i));
  }
  run.contact_time_s = meter.t_first >= 0.0 ? loop.sample().t - meter.t_first : 0.0;
  if (meter.n_grip_ticks > 0) {
    run.grip_agreement = double(meter.n_grip_agree) / double(meter.n_grip_ticks);
  }
  if (run.max_penetration_m > 0.0) {
    run.z_width_n_per_m = run.max_force_n / run.max_penetration_m;
  }
  if (meter.n_tail > 0 && meter.sum_p > 0.0) {
    run.static_stiffness_n_per_m = meter.sum_f / meter.sum_p;
  }
}

// The verdicts: stable, passive, quiet.
void zwidth_verdicts(const ZwidthScenario& sc, const ZwidthMeter& meter, std::size_t windows,
                     double quantum, ZwidthRun& run) {
  // Held by the wall: >= hold of contact and the proxy never fell through the slab. The device's
  // own depth is not a criterion: a soft coupling (small K_vc) lets the device sink F / K_vc below
  // a proxy the wall holds, which is a low rendered stiffness, not an instability.
  const bool held = run.contact && run.contact_time_s >= sc.hold_s - 2.0 * sc.tick &&
                    windows >= 2 && !run.proxy_tunnelled;
  run.stable = run.finite && run.faults == kFaultNone && held &&
               run.growth_rate_per_s <= run.growth_limit_per_s &&
               run.last_amplitude_m <= run.amplitude_bound_m;
  run.passive = run.finite && run.faults == kFaultNone && run.energy_max_j <= run.energy_tol_j;
  run.quiet_measures = zwidth_quiet_measures(meter.qs, sc.quiet, quantum);
  run.quiet = run.finite && run.faults == kFaultNone && run.contact && run.quiet_measures.quiet;
}

}  // namespace

ZwidthRun run_zwidth_once(Method method, ZwidthOperator op, const ZwidthGains& gains,
                          const ZwidthScenario& sc, double approach_speed, ZwidthTrace* trace) {
  check_zwidth_inputs(gains, sc);
  const TipProperties tp = tip_properties(sc);
  std::unique_ptr<Rig> rig = make_rig(sc);
  Device& dev = rig->device();

  // The wall below the start tip: surface approach_gap below the tip sphere.
  const Pose tip0 = rig->true_tip();
  const double rho = sc.tip_radius_m;
  const double z_s = tip0.x.z() - rho - sc.approach_gap_m;
  VoxelTooth slab = enamel_slab(tip0.x, z_s, sc.voxel_size_m);
  ToothContactProvider wall(slab, ToolTip{rho, Vec3::Zero()}, gains.k_tooth, sc.b_tooth);

  const ZwidthOperatorScript script = operator_script(op, sc, tip0, z_s, approach_speed);
  const ScriptedHand hand(script.z, script.frames, tip0.R);
  rig->set_hand(&hand);

  const std::unique_ptr<GraspMassModel> grasp = zwidth_grasp_model(sc, *rig, script.z);
  const bool detect = grasp && sc.grip_detector;
  // With the detector the pipeline's model is the device alone; the detector picks the mass.
  const SixDofDeviceModel& model = grasp && !detect ? *grasp : rig->model();
  const std::unique_ptr<Pipeline> pipeline_ptr =
      zwidth_pipeline(method, gains, sc, *rig, grasp.get(), model);
  Pipeline& pipeline = *pipeline_ptr;
  ClosedLoop loop(dev, pipeline, wall);
  loop.start();

  ZwidthRun run;
  run.approach_speed_m_s = op == ZwidthOperator::kTap ? approach_speed : 0.0;
  run.amplitude_bound_m = sc.amplitude_bound_quanta * tp.quantum;
  const VecX quantum = dev.capabilities().encoder_quantum;
  ZwidthMeter meter(op, sc, *rig, run, trace);
  const double cap = 2.0 + sc.hold_s + (tip0.x.z() - z_s) / std::max(script.speed, 1e-3);
  run_zwidth_ticks(loop, pipeline, model, z_s, cap, meter);
  rig->set_hand(nullptr);
  zwidth_totals(loop, meter, quantum, run);
  const std::size_t windows = penetration_envelope(meter, tp.quantum, run);
  zwidth_verdicts(sc, meter, windows, tp.quantum, run);
  return run;
}

ZwidthPoint run_zwidth_point(Method method, ZwidthOperator op, const ZwidthGains& gains,
                             const ZwidthScenario& sc) {
  ZwidthPoint pt;
  pt.gains = gains;
  if (op == ZwidthOperator::kTap) {
    for (double v : sc.tap_speeds_m_s) pt.runs.push_back(run_zwidth_once(method, op, gains, sc, v));
  } else {
    pt.runs.push_back(run_zwidth_once(method, op, gains, sc));
  }
  pt.stable = !pt.runs.empty();
  pt.passive = !pt.runs.empty();
  pt.quiet = !pt.runs.empty();
  pt.z_width_n_per_m = pt.runs.empty() ? 0.0 : pt.runs.front().z_width_n_per_m;
  for (const ZwidthRun& r : pt.runs) {
    pt.stable = pt.stable && r.stable;
    pt.passive = pt.passive && r.passive;
    pt.quiet = pt.quiet && r.quiet;
    pt.z_width_n_per_m = std::min(pt.z_width_n_per_m, r.z_width_n_per_m);
  }
  return pt;
}

std::vector<ZwidthSweep> run_zwidth_sweep(const std::vector<Method>& methods,
                                          const std::vector<ZwidthOperator>& ops,
                                          const ZwidthGrid& grid, const ZwidthScenario& sc,
                                          int threads,
                                          const std::function<void(int, int)>& progress) {
  std::vector<ZwidthSweep> out;
  for (Method m : methods) {
    for (ZwidthOperator op : ops) {
      ZwidthSweep s;
      s.method = m;
      s.op = op;
      s.points.resize(grid.size());
      out.push_back(std::move(s));
    }
  }
  const int total = static_cast<int>(out.size() * grid.size());
  run_jobs_on_threads(
      total, threads,
      [&](int job) {
        ZwidthSweep& sw = out[job / grid.size()];
        const std::size_t i = job % grid.size();
        sw.points[i] = run_zwidth_point(sw.method, sw.op, grid.at(i), sc);
      },
      progress);
  for (ZwidthSweep& sw : out) {
    for (std::size_t i = 0; i < sw.points.size(); ++i) {
      const ZwidthPoint& p = sw.points[i];
      if (p.stable && p.passive &&
          (sw.best < 0 || p.z_width_n_per_m > sw.points[sw.best].z_width_n_per_m)) {
        sw.best = static_cast<int>(i);
      }
      if (p.stable && p.passive && p.quiet &&
          (sw.best_quiet < 0 || p.z_width_n_per_m > sw.points[sw.best_quiet].z_width_n_per_m)) {
        sw.best_quiet = static_cast<int>(i);
      }
    }
  }
  return out;
}

}  // namespace dentsim
