// The scripted hand (device/scripted_hand.h): its wrench is exactly the impedance law, the
// profile interpolates, and bad input is rejected with the field named.
#include "device/scripted_hand.h"

#include <gtest/gtest.h>

#include <string>

#include "reference/core/io.h"
#include "reference/core/so3.h"

namespace dentsim {
namespace {

TEST(ScriptedHand, WrenchIsTheImpedanceLaw) {
  HandImpedance z;
  HandKeyframe a, b;
  a.t = 0.0;
  a.x_ref = Vec3(0.1, 0.0, 0.05);
  b.t = 2.0;
  b.x_ref = Vec3(0.1, 0.04, 0.05);
  b.wrench_ff << 0.0, 0.0, -2.0, 0.0, 0.01, 0.0;
  const Mat3 R_ref = exp_so3(Vec3(0.1, -0.2, 0.3));
  const ScriptedHand hand(z, {a, b}, R_ref);
  Pose tip;
  tip.x = Vec3(0.11, 0.01, 0.04);
  tip.R = exp_so3(Vec3(0.0, 0.1, 0.25));
  Vec6 V;
  V << 0.01, -0.02, 0.03, 0.5, -0.4, 0.2;
  const double t = 0.5;
  const Vec6 F = hand.wrench(tip, V, t);
  const Vec3 x_ref(0.1, 0.01, 0.05), v_ref(0.0, 0.02, 0.0);
  const Vec3 f = Vec3(0, 0, -0.5) + z.k_lin * (x_ref - tip.x) + z.b_lin * (v_ref - V.head<3>());
  const Vec3 tau =
      Vec3(0, 0.0025, 0) + z.k_ang * log_so3(tip.R.transpose() * R_ref) - z.b_ang * V.tail<3>();
  EXPECT_LT((F.head<3>() - f).norm(), 1e-14);
  EXPECT_LT((F.tail<3>() - tau).norm(), 1e-15);
  // At rest on the reference the hand exerts only the feed-forward wrench.
  Pose at_ref;
  at_ref.x = hand.x_ref(3.0);
  at_ref.R = R_ref;
  EXPECT_LT((hand.wrench(at_ref, Vec6::Zero(), 3.0) - b.wrench_ff).norm(), 1e-15);
}

TEST(ScriptedHand, SpringForceIsKTimesOffsetAtRest) {
  HandImpedance z;
  const Pose p{Vec3(0.2, -0.1, 0.3), Mat3::Identity()};
  const ScriptedHand hand = ScriptedHand::holding(z, p);
  Pose tip = p;
  tip.x += Vec3(0.002, -0.001, 0.003);
  const Vec6 F = hand.wrench(tip, Vec6::Zero(), 1.0);
  EXPECT_LT((F.head<3>() - z.k_lin * (p.x - tip.x)).norm(), 1e-15);
  EXPECT_EQ(F.tail<3>(), Vec3::Zero());
  // Literature defaults (Sci. Rep. 5:18004, 2015, Fig. 3): 135 N/m, 6.45 N s/m, 0.554 kg.
  EXPECT_EQ(z.k_lin, 135.0);
  EXPECT_EQ(z.b_lin, 6.45);
  EXPECT_EQ(z.mass, 0.554);
}

TEST(ScriptedHand, ProfileInterpolatesAndHoldsOutside) {
  HandKeyframe a, b, c;
  a.t = 1.0;
  b.t = 2.0;
  b.x_ref = Vec3(0.01, 0, 0);
  b.wrench_ff[2] = -1.0;
  c.t = 4.0;
  c.x_ref = Vec3(0.01, 0.02, 0);
  const ScriptedHand hand(HandImpedance{}, {a, b, c});
  EXPECT_EQ(hand.x_ref(0.0), Vec3::Zero());
  EXPECT_EQ(hand.v_ref(0.5), Vec3::Zero());
  EXPECT_LT((hand.x_ref(1.5) - Vec3(0.005, 0, 0)).norm(), 1e-17);
  EXPECT_LT((hand.v_ref(1.5) - Vec3(0.01, 0, 0)).norm(), 1e-15);
  EXPECT_DOUBLE_EQ(hand.wrench_ff(1.5)[2], -0.5);
  EXPECT_LT((hand.v_ref(3.0) - Vec3(0, 0.01, 0)).norm(), 1e-15);
  EXPECT_EQ(hand.x_ref(9.0), c.x_ref);
  EXPECT_EQ(hand.v_ref(9.0), Vec3::Zero());
}

TEST(ScriptedHand, BadInputNamesTheField) {
  auto expect_msg = [](auto make, const std::string& what) {
    try {
      make();
      ADD_FAILURE() << "no throw, expected " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  HandImpedance z;
  z.k_lin = -1.0;
  expect_msg([&] { ScriptedHand(z, {HandKeyframe{}}); }, "impedance.k_lin");
  expect_msg([] { ScriptedHand(HandImpedance{}, {}); }, "profile is empty");
  HandKeyframe a, b;
  a.t = 1.0;
  b.t = 1.0;
  expect_msg([&] { ScriptedHand(HandImpedance{}, {a, b}); }, "keyframe 1");
}

}  // namespace
}  // namespace dentsim
