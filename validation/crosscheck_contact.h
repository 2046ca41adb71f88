// Contact sweep (issue #16): does a non-drilling tool pressed into the tooth stay outside it, how
// deep does the rendered tip sink, and how much does the force ripple when sliding? Run for each
// contact model (sdf = reference/tooth/sdf.h, faces = reference/tooth/collision.h), resolution
// and push force, over the procedural molar and the real meshes (../shared/data), held out from
// any tuning. Results and command: docs/results/contact_sweep.md.
//
// Probe (quasi-static, one tick = 1 ms): a surface point p is drawn uniformly among the exposed
// voxel faces (outward normal n_f); the push direction d (into the tooth) is -n_f tilted by a
// random vector (d^T n_f <= -0.2); the tool's tip centre starts at p - (rho + 0.3 mm) d, in free
// space (else the point is redrawn). Each tick the tool moves by
//   dc = clamp(alpha (F d + f(c)) / K, 0.1 mm) (+ v t during the slide)
// (alpha = 0.5, K = k_tooth, f = the blended contact force of the model at c; 0.1 mm per tick is
// a hand at 0.1 m/s), first `settle_ticks` pressing, then `slide_ticks` sliding along t (unit,
// t^T d = 0) at v = 0.02 mm per tick while pressing.
// Measures, per tick:
//   rendered tip centre y: the surface proxy g (sdf) or the tool itself c (faces);
//   penetration = max(0, rho - phi(y)) (the depth of the rendered sphere in the solid, phi the
//     exact signed distance of reference/tooth/sdf.h); reported as max over all ticks / rho;
//   a pop-through (counted once per probe and force): phi(y) < 0 (the rendered centre inside
//     the solid) while the push is resisted by less than half of it (-f^T d < F / 2) — the tool
//     has gone into the tooth and the tooth no longer holds it.
// Sliding ripple: a voxelised sphere of radius 5 mm on a grid with the procedural molar's voxel
// size at that resolution; the tool's centre is led along a meridian (azimuth 20 deg, polar
// angle 0..80 deg, 800 ticks) at the analytic equilibrium radius R + rho - F/K for each push F;
// ripple = RMS over ticks of |f - F u| / F, u the radial unit vector (the analytic sphere's
// force). `sliding_ripple_rms` is the largest over the forces.
#pragma once

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace dentsim {

struct ContactCrosscheckOptions {
  std::vector<int> resolutions = {128, 256, 512};
  std::vector<double> forces_n = {1.0, 4.0, 8.5};
  std::vector<std::string> models = {"sdf", "faces"};
  int probes = 2000;             // (point, direction) pairs per resolution, over all teeth
  std::string data_dir;          // holds molar-cc0.stl, chai3d-tooth.obj; empty: molar only
  double mesh_size_mm = 21.5;    // largest extent the meshes are scaled to
  double tip_radius_m = 0.4e-3;  // explorer tip radius rho
  double k_tooth = 3000.0;       // [N/m]
  int settle_ticks = 150;
  int slide_ticks = 150;
  std::uint64_t seed = 1;
  // Optional stop request (the CLI's SIGINT / SIGTERM flag, cli/interrupt.h), checked before each
  // probe: once set, the sweep returns what it has (ContactCrosscheckResult::stopped).
  const std::atomic<bool>* stop_request = nullptr;
};

struct ContactSweepRow {
  std::string model;
  int resolution = 0;
  double voxel_size_m = 0.0;  // the procedural molar's h at this resolution
  long probes = 0;            // (point, direction) pairs
  long runs = 0;              // probes x forces
  long pop_throughs = 0;
  double max_penetration_over_radius = 0.0;
  double max_penetration_over_voxel = 0.0;  // the same depth over h
  std::vector<double> ripple_per_force;     // parallel to forces_n
  double sliding_ripple_rms = 0.0;          // max of ripple_per_force
  std::vector<long> pop_throughs_per_force;
  // The resolution the stop request interrupted: the probes run so far, no sliding ripple
  // (ripple_per_force empty, sliding_ripple_rms NaN; null in the JSON).
  bool partial = false;
};

struct ContactCrosscheckResult {
  ContactCrosscheckOptions options;
  std::vector<std::string> teeth;  // names of the teeth swept
  std::vector<ContactSweepRow> rows;
  // The stop request ended the sweep early: the rows of the resolutions done, then those of the
  // one in progress marked partial; `stopped_at` says where ("n=256, tooth 2 of 3").
  bool stopped = false;
  std::string stopped_at;
};

// Throws InputError naming the option (resolution not a power of two in 16..512, unknown model,
// probes < 1, forces <= 0) or the missing mesh file.
ContactCrosscheckResult crosscheck_contact(const ContactCrosscheckOptions& options);

nlohmann::json crosscheck_contact_json(const ContactCrosscheckResult& result);

}  // namespace dentsim
