// One servo tick of dentsim's pipelines on the default Phantom Premium 1.5/6DoF, built against the
// installed package (examples/cpp/CMakeLists.txt; docs/install.md).
//
//   one_tick [MODEL.json]     the device model file (default: the built-in Premium 1.5A, which
//                             <prefix>/share/dentsim/devices/ holds as a file)
//
// Each pipeline places its proxy on the device at rest at the home pose (middle of the joint
// ranges), in free space (no tooth), and runs one tick; twice, with the device at two poses.
// Three checks, each against physics rather than a stored number:
//   1. The device still at home: the coupling is zero, so the command is the gravity
//      compensation alone, tau = g(q) (reference/tick.h "command").
//   2. The device turned by 0.01 rad about the base yaw q1 away from the proxy: the coupling
//      spring pulls it back, force f1 = -k_vc,x (x1 - x2) (4.3), and the joint torques are the
//      wrench through the Jacobian, tau - g(q) = J_t^T T1.
//   3. The fast pipeline and the reference pipeline command the same torques (both ticks).
// Prints the numbers; exit status 0 when all hold, 1 when one fails, 2 for a bad model file.
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <memory>

#include "device/phantom_device.h"
#include "fast/phantom/phantom_model.h"
#include "fast/registry.h"
#include "reference/core/contact_provider.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"

namespace {

using dentsim::Vec3;
using dentsim::VecX;

// What one pipeline commands in its first tick, with the device at home and moved.
struct TwoTicks {
  VecX tau1, tau2;     // joint torques, device at home / moved
  dentsim::Vec6 T1_2;  // device wrench, device moved
  Vec3 proxy_x;        // proxy position as the tick starts (the device's at home)
};

TwoTicks run(const char* implementation, const dentsim::SixDofDeviceModel& model,
             const dentsim::PipelineConfig& config, const VecX& q_home, const VecX& q_moved) {
  const std::unique_ptr<dentsim::Pipeline> p =
      dentsim::make_pipeline(implementation, model, config);
  dentsim::NoContacts free_space;
  dentsim::DeviceSample home;
  home.q = q_home;
  home.qd = VecX::Zero(6);
  dentsim::DeviceSample moved = home;
  moved.q = q_moved;
  TwoTicks out;
  p->reset(home);  // proxy on the device, at rest
  out.proxy_x = p->proxy().pose.x;
  out.tau1 = p->tick(home, 1e-3, free_space).tau;
  p->reset(home);
  const dentsim::TickResult& r = p->tick(moved, 1e-3, free_space);
  out.tau2 = r.tau;
  out.T1_2 = r.T1;
  return out;
}

void print(const char* what, const VecX& v) {
  std::printf("  %-34s", what);
  for (int i = 0; i < v.size(); ++i) std::printf(" %+.6e", v[i]);
  std::printf("\n");
}

// |a - b| relative to the larger of |b| and `floor` (a zero reference with a zero difference is 0).
double rel(const VecX& a, const VecX& b, double floor) {
  return (a - b).norm() / std::max(b.norm(), floor);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2) {
    std::fprintf(stderr, "usage: one_tick [MODEL.json]\n");
    return 2;
  }
  try {
    const dentsim::PhantomParams params =
        argc == 2 ? dentsim::load_phantom_params(argv[1]) : dentsim::default_phantom_params();
    const dentsim::fast::PhantomModel fast_model(params);
    const dentsim::PhantomModel reference_model(params);

    // The default tick (PMI proxy and coupling, gravity compensated, no saturation), with the
    // coupling dampers off so that the moved device's force is the spring alone.
    dentsim::PipelineConfig config;
    config.coupling.b_lin = 0.0;
    config.coupling.b_ang = 0.0;

    const VecX q_home = dentsim::phantom_home_q(params);
    VecX q_moved = q_home;
    q_moved[0] += 0.01;

    const TwoTicks fast = run("fast", fast_model, config, q_home, q_moved);
    const TwoTicks ref = run("reference", reference_model, config, q_home, q_moved);

    std::printf("one_tick: device model \"%s\", q_home = (%.4f %.4f %.4f %.4f %.4f %.4f) rad\n",
                params.name.c_str(), q_home[0], q_home[1], q_home[2], q_home[3], q_home[4],
                q_home[5]);
    bool ok = true;

    // 1. At rest on the proxy: tau = g(q). g is some 0.1 N m on the arm joints, so a relative
    // error of 1e-12 is round-off; a model with gravity on must have g(q) well above that (else
    // the check would compare zeros), one with gravity off must command exactly nothing.
    const VecX g_home = fast_model.gravity(q_home);
    const double e1 = rel(fast.tau1, g_home, 1e-300);
    std::printf("one tick, device at rest on the proxy:\n");
    print("tau [N m]", fast.tau1);
    print("g(q) [N m]", g_home);
    std::printf("  |tau - g| / |g| = %.3e (limit 1e-12), |g| = %.4f N m\n", e1, g_home.norm());
    if (!(e1 <= 1e-12 && (params.gravity_on ? g_home.norm() > 1e-3 : fast.tau1.norm() == 0.0))) {
      ok = false;
    }

    // 2. Moved 0.01 rad about q1: the spring force on the device, and the torques through J_t.
    const Vec3 x1 = fast_model.forward_kinematics(q_moved).x;
    const Vec3 f_spring = -config.coupling.k_lin * (x1 - fast.proxy_x);
    const Vec3 f1 = fast.T1_2.head<3>();
    const dentsim::Mat6 J_t = fast_model.twist_to_joint(q_moved).inverse();
    const VecX tau_from_wrench = J_t.transpose() * fast.T1_2 + fast_model.gravity(q_moved);
    const double e2 = (f1 - f_spring).norm() / f_spring.norm();
    const double e3 = rel(fast.tau2, tau_from_wrench, 0.0);
    std::printf("one tick, device turned 0.01 rad about q1 from the proxy (tool moved %.3f mm):\n",
                1e3 * (x1 - fast.proxy_x).norm());
    print("coupling force f1 [N]", VecX(f1));
    print("-k_vc,x (x1 - x2) [N]", VecX(f_spring));
    print("tau [N m]", fast.tau2);
    std::printf("  |f1 - spring| / |spring| = %.3e (limit 1e-9), |f1| = %.4f N\n", e2, f1.norm());
    std::printf("  |tau - (J_t^T T1 + g)| / |tau| = %.3e (limit 1e-9)\n", e3);
    if (!(f_spring.norm() > 0.1 && e2 <= 1e-9 && e3 <= 1e-9)) ok = false;

    // 3. fast vs reference: 1e-9 relative, with differences below 1e-15 N m counted as agreement
    // (docs/tolerance_policy.md "fast vs reference").
    const double e4 = std::max(rel(fast.tau1, ref.tau1, 1e-6), rel(fast.tau2, ref.tau2, 1e-6));
    std::printf("fast vs reference: max |tau_fast - tau_ref| / |tau_ref| = %.3e (limit 1e-9)\n",
                e4);
    if (!(e4 <= 1e-9)) ok = false;

    std::printf("%s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
  } catch (const dentsim::InputError& e) {
    std::fprintf(stderr, "one_tick: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "one_tick: %s\n", e.what());
    return 1;
  }
}
