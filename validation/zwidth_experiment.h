// The Z-width experiment as `dentsim zwidth` runs it (issue #7; thesis §4.2, Fig. 4.9-4.11;
// protocol in docs/zwidth_protocol.md). validation/zwidth.h defines one run, one grid point and
// one sweep; this file defines the experiment built from them:
// - what is run: every method under every operator; the strictest operator (force) on the full
//   grid, the others (grip, tap, release) on a smaller grid around the thesis's gains;
// - the headline: per method, the Z-width of the force sweep (of the first operator's sweep when
//   force is not run), its gains, the thesis's value beside it (Fig. 4.11: 315, 570, 3000 N/m) and
//   two bounds at its b_vc, per unit of translational device damping b_d at the tip [N s/m]:
//       Colgate-Schenkel   K < 2 (b_d - b_vc) / T,
//       PMI coupling       k_vc <= (b_d - b_vc (1 + T_k / T_k-1)) / T_k   (thesis §3.1);
// - what is compared: the ratios Z(pmi) / Z(explicit) and Z(pmi-pd) / Z(explicit) (thesis 1.8
//   and 9.5), null when explicit VC has no stable, passive point;
// - the sensitivity (optional): each method's headline point re-run with the hand's impedance
//   halved and doubled (grip operator), tick jitter +-0.2 T, observer gain L = 100, 500, 900 1/s,
//   the thesis's unmatched observer input, the device model's mass and damping -20 % / +20 %,
//   and a 4 kHz tick;
// - the traces the figures draw (optional): each method's headline point re-run with a trace, and
//   with the grip detector the best `release` point of PMI + PD with the hand's mass fixed in the
//   model and with the detector.
// The JSON (zwidth_experiment_json) is the contract of `dentsim zwidth --json` (issue #7).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "validation/zwidth.h"

namespace dentsim {

// The grids [N/m, N s/m, N/m]: the force operator's full grid (10 K_vc x 5 b_vc x 4 K_tooth), the
// other operators' grid (the thesis's neighbourhood and the corners of the force grid's stable
// region, at the coupling damping that is stable for all) and the short grid of --quick (every
// operator).
ZwidthGrid zwidth_full_grid();
ZwidthGrid zwidth_other_grid();
ZwidthGrid zwidth_quick_grid();

// The thesis's Z-width of a method (Fig. 4.11) [N/m].
double zwidth_thesis_value(Method m);

// One sensitivity variant: the operator it runs under and how it changes the scenario.
struct ZwidthSensitivityVariant {
  std::string name;
  ZwidthOperator op = ZwidthOperator::kForce;
  std::function<void(ZwidthScenario&)> apply;
};
// The variants in the order they are run and reported ("nominal" first: the headline point
// under the force operator, unchanged).
const std::vector<ZwidthSensitivityVariant>& zwidth_sensitivity_variants();

struct ZwidthExperiment {
  ZwidthScenario scenario;
  std::vector<Method> methods = {Method::kExplicitVc, Method::kPmiVc, Method::kPmiPd};
  std::vector<ZwidthOperator> operators = {ZwidthOperator::kForce, ZwidthOperator::kGrip,
                                           ZwidthOperator::kTap, ZwidthOperator::kRelease};
  ZwidthGrid grid = zwidth_full_grid();         // the force operator's grid
  ZwidthGrid other_grid = zwidth_other_grid();  // grip, tap, release
  bool sensitivity = false;
  bool traces = false;  // record the figures' traces (ZwidthMethodResult::trace, grip_traces)
  int threads = 1;      // std::threads of the sweeps (>= 1)
};

struct ZwidthSensitivityResult {
  std::string variant;  // ZwidthSensitivityVariant::name
  ZwidthOperator op = ZwidthOperator::kForce;
  ZwidthPoint point;
};

struct ZwidthMethodResult {
  Method method = Method::kExplicitVc;
  std::vector<ZwidthSweep> sweeps;  // one per experiment operator, in that order
  int headline = 0;                 // index into sweeps: force if run, else 0
  double thesis_z_width_n_per_m = 0.0;
  double colgate_schenkel_max_stiffness_n_per_m = 0.0;  // at the headline point's b_vc (0 if none)
  double pmi_coupling_bound_n_per_m = 0.0;              // same
  std::vector<ZwidthSensitivityResult> sensitivity;     // empty: not asked, or no headline point
  ZwidthTrace trace;  // the headline point re-run (traces asked and a headline point exists)

  const ZwidthSweep& headline_sweep() const { return sweeps[headline]; }
  double z_width_n_per_m() const { return headline_sweep().z_width_n_per_m(); }
  // Over stable, passive and quiet points of the headline sweep (issue #29).
  double quiet_z_width_n_per_m() const { return headline_sweep().quiet_z_width_n_per_m(); }
};

struct ZwidthExperimentResult {
  ZwidthExperiment experiment;
  double device_tip_damping_n_s_per_m = 0.0;  // b_d (testbed_tip_damping)
  double device_tip_quantum_m = 0.0;          // Delta_n (testbed_tip_quantum)
  std::vector<ZwidthMethodResult> methods;    // in experiment order
  // Z(pmi) / Z(explicit), Z(pmi-pd) / Z(explicit); NaN when explicit VC was not run or has no
  // stable, passive point, or the other method was not run.
  double ratio_pmi_over_explicit = 0.0;
  double ratio_pmipd_over_explicit = 0.0;
  // The same over the quiet Z-widths (ZwidthMethodResult::quiet_z_width_n_per_m; issue #29).
  double quiet_ratio_pmi_over_explicit = 0.0;
  double quiet_ratio_pmipd_over_explicit = 0.0;
  // Grip detector at work (traces asked, scenario.grip_detector, release run, PMI + PD has a best
  // release point): that point re-run with the hand's mass fixed in the model and with the
  // detector. has_grip_traces says whether they were run.
  bool has_grip_traces = false;
  ZwidthGains grip_trace_gains;
  ZwidthTrace grip_trace_fixed, grip_trace_detector;

  // The grid the headline sweeps ran on (the force grid if force was run, else the other grid).
  const ZwidthGrid& headline_grid() const;
};

// Runs the jobs job(0), ..., job(n - 1) of one stage of the experiment — independent of each
// other, each returning its result as JSON — and returns the n results in index order, on every
// process that calls it. The experiment has two stages: "grid" (every operator's grid points for
// every method) and "re-runs" (the sensitivity variants and traces at each method's best point,
// which depend on the grid). The default runs them in this process on e.threads std::threads;
// `dentsim zwidth` passes one that spreads them over MPI ranks (cli/mpi_sweep.h). A job's JSON
// carries every number bit for bit (non-finite values included), so the result does not depend
// on where the jobs ran.
using ZwidthJobRunner = std::function<std::vector<nlohmann::json>(
    const std::string& stage, int n, const std::function<nlohmann::json(int)>& job)>;

// Runs the experiment. `progress(op, done, total)` is called (serialised) after every grid point
// of each operator's sweep that this process runs. Throws InputError on an empty method or
// operator list; a job's exception reaches the caller (through the runner).
ZwidthExperimentResult run_zwidth_experiment(
    const ZwidthExperiment& e, const std::function<void(ZwidthOperator, int, int)>& progress = {},
    const ZwidthJobRunner& runner = {});

// A grid point and a trace as a job's JSON and back, exactly (doubles bit for bit, NaN and
// infinities as strings): the wire format of ZwidthJobRunner.
nlohmann::json zwidth_point_to_wire(const ZwidthPoint& p);
ZwidthPoint zwidth_point_from_wire(const nlohmann::json& j);
nlohmann::json zwidth_trace_to_wire(const ZwidthTrace& t);
ZwidthTrace zwidth_trace_from_wire(const nlohmann::json& j);

// Why the ratio of `m`'s headline Z-width over explicit's is not a number ("" when it is): a
// method not run (--methods), or explicit without a stable and passive grid point (Z-width 0).
// `dentsim zwidth` prints "n/a (REASON)"; the JSON has null and "<key>_reason".
std::string zwidth_ratio_reason(const ZwidthExperimentResult& r, Method m);

// The result as `dentsim zwidth --json` writes it (keys: docs/zwidth_protocol.md).
nlohmann::json zwidth_experiment_json(const ZwidthExperimentResult& r);

}  // namespace dentsim
