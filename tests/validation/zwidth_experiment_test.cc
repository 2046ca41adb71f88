// The Z-width experiment as `dentsim zwidth` runs it (validation/zwidth_experiment.h), on the
// 1-DoF axis testbed (deterministic: no jitter, seed 1): the headline is the force operator's
// sweep whatever the operator order, its point re-run alone gives the same verdict bit for bit,
// the ratios are the quotients of the headline values, the tip damping and quantum of the axis
// device are its own, the JSON carries the struct's numbers, and the nominal sensitivity
// variant reproduces the headline point exactly.
#include "validation/zwidth_experiment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "reference/core/io.h"

namespace dentsim {
namespace {

ZwidthExperiment axis_experiment() {
  ZwidthExperiment e;
  e.scenario.testbed = ZwidthTestbed::kAxis;
  e.threads = 2;
  return e;
}

TEST(ZwidthExperiment, HeadlineIsTheForceSweepAndRatiosAreItsQuotients) {
  ZwidthExperiment e = axis_experiment();
  e.methods = {Method::kExplicitVc, Method::kPmiVc};
  e.operators = {ZwidthOperator::kGrip, ZwidthOperator::kForce};  // force second on purpose
  e.grid.k_vc = {400.0};
  e.grid.b_vc = {2.0};
  e.grid.k_tooth = {1500.0, 3000.0};
  e.other_grid.k_vc = {400.0};
  e.other_grid.b_vc = {2.0};
  e.other_grid.k_tooth = {1500.0};
  const ZwidthExperimentResult r = run_zwidth_experiment(e);
  // The axis device is a point mass on one axis: its tip damping and quantum are its own.
  EXPECT_EQ(r.device_tip_damping_n_s_per_m, e.scenario.axis.damping);
  EXPECT_EQ(r.device_tip_quantum_m, e.scenario.axis.quantum);
  EXPECT_EQ(&r.headline_grid(), &r.experiment.grid);
  ASSERT_EQ(r.methods.size(), 2u);
  const nlohmann::json j = zwidth_experiment_json(r);
  for (const ZwidthMethodResult& mr : r.methods) {
    const char* name = method_name(mr.method);
    ASSERT_EQ(mr.sweeps.size(), 2u);
    EXPECT_EQ(mr.headline, 1) << name;
    EXPECT_EQ(mr.sweeps[0].op, ZwidthOperator::kGrip);
    EXPECT_EQ(mr.sweeps[0].points.size(), e.other_grid.size());
    EXPECT_EQ(mr.sweeps[1].points.size(), e.grid.size());
    // Both methods have a stable, passive point here (tests/validation/zwidth_test.cc
    // ZwidthVerdicts: (400, 2, 1500)).
    const ZwidthSweep& s = mr.headline_sweep();
    ASSERT_GE(s.best, 0) << name;
    const ZwidthGains g = s.points[s.best].gains;
    // The best point re-run alone (its own device, pipeline and tooth) gives the same numbers.
    const ZwidthPoint alone = run_zwidth_point(mr.method, ZwidthOperator::kForce, g, e.scenario);
    EXPECT_TRUE(alone.stable && alone.passive) << name;
    EXPECT_EQ(alone.z_width_n_per_m, mr.z_width_n_per_m()) << name;
    // No stable, passive point of the grid renders a stiffer wall than the best.
    for (const ZwidthPoint& p : s.points) {
      if (p.stable && p.passive) {
        EXPECT_LE(p.z_width_n_per_m, mr.z_width_n_per_m()) << name;
      }
    }
    EXPECT_EQ(mr.thesis_z_width_n_per_m, zwidth_thesis_value(mr.method));
    EXPECT_EQ(mr.colgate_schenkel_max_stiffness_n_per_m,
              colgate_schenkel_max_stiffness(e.scenario.axis.damping, g.b_vc, e.scenario.tick));
    EXPECT_EQ(mr.pmi_coupling_bound_n_per_m,
              pmi_coupling_max_stiffness(e.scenario.axis.damping, g.b_vc, e.scenario.tick,
                                         e.scenario.tick));
    EXPECT_TRUE(mr.sensitivity.empty());
    EXPECT_TRUE(mr.trace.t.empty());
    const auto& mj = j["methods"][name];
    EXPECT_EQ(mj["z_width_n_per_m"].get<double>(), mr.z_width_n_per_m()) << name;
    EXPECT_EQ(mj["strictest_operator"].get<std::string>(), "force") << name;
    EXPECT_EQ(mj["gains"]["k_vc_n_per_m"].get<double>(), g.k_vc) << name;
    EXPECT_EQ(mj["operators"]["grip"]["z_width_n_per_m"].get<double>(),
              mr.sweeps[0].z_width_n_per_m())
        << name;
  }
  const double z_explicit = r.methods[0].z_width_n_per_m();
  ASSERT_GT(z_explicit, 0.0);
  EXPECT_EQ(r.ratio_pmi_over_explicit, r.methods[1].z_width_n_per_m() / z_explicit);
  EXPECT_EQ(j["ratio_pmi_over_explicit"].get<double>(), r.ratio_pmi_over_explicit);
  EXPECT_TRUE(std::isnan(r.ratio_pmipd_over_explicit));  // pmi-pd not run
  EXPECT_TRUE(j["ratio_pmipd_over_explicit"].is_null());
  EXPECT_EQ(j["grid"]["k_tooth_n_per_m"].get<std::vector<double>>(), e.grid.k_tooth);
  EXPECT_EQ(j["grid_other_operators"]["k_vc_n_per_m"].get<std::vector<double>>(),
            e.other_grid.k_vc);
}

// Without the force operator the first operator's sweep is the headline, on the other grid; with
// explicit VC not run the ratios are undefined (null in the JSON).
TEST(ZwidthExperiment, WithoutForceTheFirstOperatorLeadsAndRatiosAreNull) {
  ZwidthExperiment e = axis_experiment();
  e.methods = {Method::kPmiVc};
  e.operators = {ZwidthOperator::kGrip};
  e.other_grid.k_vc = {400.0};
  e.other_grid.b_vc = {2.0};
  e.other_grid.k_tooth = {1500.0};
  const ZwidthExperimentResult r = run_zwidth_experiment(e);
  ASSERT_EQ(r.methods.size(), 1u);
  EXPECT_EQ(r.methods[0].headline, 0);
  EXPECT_EQ(&r.headline_grid(), &r.experiment.other_grid);
  EXPECT_TRUE(std::isnan(r.ratio_pmi_over_explicit));
  const nlohmann::json j = zwidth_experiment_json(r);
  EXPECT_TRUE(j["ratio_pmi_over_explicit"].is_null());
  EXPECT_TRUE(j["ratio_pmipd_over_explicit"].is_null());
  EXPECT_EQ(j["methods"]["pmi"]["strictest_operator"].get<std::string>(), "grip");
  e.operators.clear();
  EXPECT_THROW(run_zwidth_experiment(e), InputError);
}

// The sensitivity re-runs the headline point once per variant; "nominal" is that point unchanged
// and must reproduce it exactly (a 1.5 s hold keeps the 11 variants short: the point is the
// bookkeeping, not the verdict). The traces re-run it once more: the Z-width is max f / max p
// over the run after first contact, and before contact the tool is in free space (p < 0, f = 0),
// so the trace's own max f / max p is the same number.
TEST(ZwidthExperiment, NominalVariantAndTraceReproduceTheHeadlinePoint) {
  ZwidthExperiment e = axis_experiment();
  e.scenario.hold_s = 1.5;
  e.methods = {Method::kPmiVc};
  e.operators = {ZwidthOperator::kForce};
  e.grid.k_vc = {400.0};
  e.grid.b_vc = {2.0};
  e.grid.k_tooth = {1500.0};
  e.sensitivity = true;
  e.traces = true;
  const ZwidthExperimentResult r = run_zwidth_experiment(e);
  const ZwidthMethodResult& mr = r.methods[0];
  ASSERT_GE(mr.headline_sweep().best, 0);
  const auto& variants = zwidth_sensitivity_variants();
  ASSERT_EQ(mr.sensitivity.size(), variants.size());
  for (std::size_t i = 0; i < variants.size(); ++i) {
    EXPECT_EQ(mr.sensitivity[i].variant, variants[i].name);
    EXPECT_EQ(mr.sensitivity[i].op, variants[i].op);
  }
  const ZwidthPoint& best = mr.headline_sweep().points[mr.headline_sweep().best];
  const ZwidthPoint& nominal = mr.sensitivity[0].point;
  EXPECT_EQ(mr.sensitivity[0].variant, "nominal");
  EXPECT_EQ(nominal.stable, best.stable);
  EXPECT_EQ(nominal.passive, best.passive);
  EXPECT_EQ(nominal.z_width_n_per_m, best.z_width_n_per_m);
  const nlohmann::json j = zwidth_experiment_json(r);
  EXPECT_EQ(j["methods"]["pmi"]["sensitivity"].size(), variants.size());
  EXPECT_EQ(j["methods"]["pmi"]["sensitivity"]["4 kHz"]["z_width_n_per_m"].get<double>(),
            mr.sensitivity.back().point.z_width_n_per_m);
  const ZwidthTrace& tr = mr.trace;
  ASSERT_FALSE(tr.t.empty());
  const double f_max = *std::max_element(tr.force_n.begin(), tr.force_n.end());
  const double p_max = *std::max_element(tr.penetration_m.begin(), tr.penetration_m.end());
  EXPECT_NEAR(f_max / p_max, best.z_width_n_per_m, 1e-12 * best.z_width_n_per_m);
  EXPECT_FALSE(r.has_grip_traces);  // no grip detector in this scenario
}

}  // namespace
}  // namespace dentsim
