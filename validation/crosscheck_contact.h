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
// force). `sliding_ripple_rms` is the largest over the forces. This is the quasi-static ripple:
// the tool is placed, nothing moves by dynamics.
// Closed-loop ripple (issue #30: the dynamic part apart from the geometric part): the same
// sphere and meridian felt through a closed loop (validation/wall_loop.h run_provider_loop: the
// ideal rigid-body device with a Phantom's apparent tip, the reference pmi-pd pipeline with the
// handpiece, default coupling and proxy, 1 kHz): a hand pushes with F towards the centre and
// steers the device along the meridian (a spring in the tangent plane only), 0.4 s settling at the
// pole, then the meridian in 800 ticks. Per tick of the slide, with x the tool pose the contact
// stage was asked at, u = (x - c) / |x - c|, f_c the model's blended contact force there,
// f_exact = K (R + rho - |x - c|)_+ u the analytic sphere's force at the same pose and f_d the
// force the motors apply to the device:
//   e_total = f_d - F u            (what the hand feels against the ideal),
//   e_geo   = f_c - f_exact        (the model's shape error along the path actually taken),
//   e_dyn   = e_total - e_geo      (the loop: coupling, integration, the device, the hand),
// so e_total = e_geo + e_dyn tick by tick; each reported as RMS over the slide of |e| / F (the
// RMS do not add: the loop's mass and coupling filter part of e_geo, so e_dyn holds -e_geo's
// filtered share). The loop's own ripple apart from any model: the same loop and hand on the
// exact sphere (a contact provider with the penalty law on |x - c|), `exact_sphere`.
// Ripple here is the fluctuation: each e minus its mean over a centred window of +-25 ticks
// (what is slower than ~20 Hz is the feel given to the tool, e.g. the rendered handpiece's drag,
// not a ripple; the voxels' ripple at this speed is at 55 Hz (128^3) and above); `error` keeps
// the whole RMS |e_total| / F. Measured only where F / K <= R / 3 (else null): deeper, the hand's
// script decides where the tool goes (at 8.5 N and 3000 N/m it slips through the centre of the
// exact sphere too).
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

struct ClosedLoopRipple {
  double total = 0.0;      // RMS |f_d - F u| / F
  double geometric = 0.0;  // RMS |f_c - f_exact| / F
  double dynamic = 0.0;    // RMS |e_total - e_geo| / F
  double exact_sphere = 0.0;  // `total` of the same loop on the exact sphere (no shape error)
  double error = 0.0;      // RMS |f_d - F u| / F, not detrended (the drag and the lag included)
};

struct ContactSweepRow {
  std::string model;
  int resolution = 0;
  double voxel_size_m = 0.0;  // the procedural molar's h at this resolution
  // The "field" model's sample spacing H on the molar and the sphere at this resolution (the
  // automatic rule, reference/tooth/sampled_field.h field_stride_for: k h, k the largest with
  // k h <= H_max(tip)); 0 for the other models. JSON "field_spacing_mm".
  double field_spacing_m = 0.0;
  long probes = 0;            // (point, direction) pairs
  long runs = 0;              // probes x forces
  long pop_throughs = 0;
  double max_penetration_over_radius = 0.0;
  double max_penetration_over_voxel = 0.0;  // the same depth over h
  std::vector<double> ripple_per_force;     // parallel to forces_n
  double sliding_ripple_rms = 0.0;          // max of ripple_per_force
  std::vector<long> pop_throughs_per_force;
  std::vector<ClosedLoopRipple> closed_loop_per_force;  // parallel to forces_n
  double closed_loop_ripple_rms = 0.0;  // the largest total over the forces
  double geometric_ripple_rms = 0.0;    // the largest geometric part
  double dynamic_ripple_rms = 0.0;      // the largest dynamic part
  double exact_sphere_ripple_rms = 0.0;  // the largest ripple of the loop on the exact sphere
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
