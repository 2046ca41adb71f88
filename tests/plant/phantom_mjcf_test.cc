// The MJCF of the Phantom generated from the device model file (plant/phantom_mjcf.h), loaded
// through MujocoPhantom (plant/mujoco_phantom.h): the model file's numbers arrive in MuJoCo
// unchanged (exact equality: they are copied, not computed), and the generated closed chain holds
// under gravity compensation.
#include "plant/phantom_mjcf.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cstdio>

#include "plant/mujoco_phantom.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

TEST(PhantomMjcf, GeneratedFromTheModelFile) {
  PhantomParams p = default_phantom_params();
  p.name = "unit <7> -- & --> test";  // must not break the XML comment it is written into
  p.forearm.mass_kg = 0.031;
  p.damping_n_m_s_per_rad(2) = 0.0042;
  p.armature_kg_m2(0) = 0.00021;
  MujocoPhantom mj(p);
  const mjModel* m = mj.model();
  EXPECT_EQ(m->nv, 8);
  EXPECT_EQ(m->neq, 2);
  EXPECT_EQ(m->nu, 6);
  const int forearm = mj_name2id(m, mjOBJ_BODY, "forearm");
  ASSERT_GE(forearm, 0);
  EXPECT_EQ(m->body_mass[forearm], 0.031);
  const int q3 = mj_name2id(m, mjOBJ_JOINT, "q3");
  EXPECT_EQ(m->dof_damping[m->jnt_dofadr[q3]], 0.0042);
  const int q1 = mj_name2id(m, mjOBJ_JOINT, "q1");
  EXPECT_EQ(m->dof_armature[m->jnt_dofadr[q1]], 0.00021);
  EXPECT_EQ(m->jnt_limited[q1], 1);
  EXPECT_EQ(m->jnt_range[2 * q1 + 1], p.q_max_rad(0));
  const int tau6 = mj_name2id(m, mjOBJ_ACTUATOR, "tau6");
  EXPECT_EQ(m->actuator_ctrlrange[2 * tau6 + 1], p.torque_limit_n_m(5));
  // set_state closes the chain exactly and reads back q.
  const Vec6 q = (Vec6() << 0.1, 0.3, 0.2, 0.4, -0.2, 0.5).finished();
  mj.set_state(q, Vec6::Zero());
  EXPECT_EQ(mj.q(), q);
  EXPECT_LT(mj.closure_error(), 1e-15);
}

// Holding gravity-compensating torques, MuJoCo's closed chain stays put and closed. MuJoCo's
// equalities are soft: under the static gravity load the closure sags by a small steady-state
// deflection (measured 4.5e-8 rad with impedance 0.9999 and time constant 2 ms); bounded at 2e-7.
TEST(PhantomMjcf, GravityCompensatedDeviceStaysClosedAndAtRest) {
  PhantomParams p = default_phantom_params();
  PhantomMjcfOptions o;
  o.joint_limits = false;
  MujocoPhantom mj(p, o);
  const PhantomModelD model(p);
  const Vec6 q = (Vec6() << 0.2, 0.35, 0.3, 0.0, 0.0, 0.0).finished();
  mj.set_state(q, Vec6::Zero());
  for (int k = 0; k < 1000; ++k) {  // 0.1 s
    mj.set_torque(model.g(mj.q()));
    mj.step();
  }
  std::printf("drift %.3e rad, closure %.3e rad\n", (mj.q() - q).cwiseAbs().maxCoeff(),
              mj.closure_error());
  EXPECT_LT((mj.q() - q).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT(mj.closure_error(), 2e-7);
}

}  // namespace
}  // namespace dentsim
