// The contact sweep of validation/crosscheck_contact.h (issue #16).
#include "validation/crosscheck_contact.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <utility>

#include "reference/core/contact_provider.h"
#include "reference/core/io.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/sdf.h"
#include "reference/tooth/tooth_contacts.h"
#include "tooth_io/voxelize.h"
#include "reference/tools.h"
#include "reference/core/so3.h"
#include "validation/wall_loop.h"

namespace dentsim {
namespace {

constexpr double kAlpha = 0.5;        // relaxation gain of the quasi-static probe
constexpr double kMaxStepM = 0.1e-3;  // a hand at 0.1 m/s, 1 ms ticks
constexpr double kSlideStepM = 0.02e-3;
constexpr double kStartGapM = 0.3e-3;  // start this far outside the tip's touching distance
constexpr double kSphereRadiusM = 5e-3;
constexpr int kRippleTicks = 800;
// The closed-loop slide (see sliding_ripple_closed_loop): settle at the pole, then the same
// meridian in kRippleTicks ticks of 1 ms.
constexpr double kLoopSettleS = 0.4;
constexpr double kLoopStartGapM = 0.2e-3;
constexpr double kHandTangentialStiffness = 200.0;  // [N/m]
constexpr double kHandDamping = 2.0;                // [N s/m]

struct Probe {
  Vec3 start, d, t;
};

// A swept tooth: the voxels, and (when the "field" model is swept) the field of its source.
struct SweptTooth {
  VoxelTooth tooth;
  std::unique_ptr<SampledField> field;
};

SweptTooth build_swept_tooth(const std::string& mesh_path, double size_mm, int resolution,
                             bool with_field, double rho) {
  SweptTooth out;
  if (mesh_path.empty()) {
    const MolarParams params;
    out.tooth = VoxelTooth(voxelize_procedural_molar(params, resolution));
    if (with_field) {
      const VoxelGrid& grid = out.tooth.grid();
      out.field = std::make_unique<SampledField>(build_sampled_field(
          grid, triangulate_implicit(grid, [&](const Vec3& p) { return molar_solid(params, p); }),
          field_band_for_tip(rho, grid.voxel_size, field_stride_for(rho, grid.voxel_size))));
    }
    return out;
  }
  LoadedMesh loaded = load_mesh(mesh_path);
  scale_mesh(loaded.mesh, scale_for_size(loaded.mesh, 1e-3 * size_mm));
  VoxelizeOptions opt;
  opt.resolution = resolution;
  out.tooth = VoxelTooth(voxelize_mesh(loaded.mesh, opt));
  if (with_field) {
    const double h = out.tooth.grid().voxel_size;
    out.field = std::make_unique<SampledField>(build_sampled_field(
        out.tooth.grid(), loaded.mesh, field_band_for_tip(rho, h, field_stride_for(rho, h))));
  }
  return out;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vec3 v;
  do {
    v = Vec3(g(rng), g(rng), g(rng));
  } while (v.norm() < 1e-6);
  return v.normalized();
}

// `count` probes on exposed faces of `tooth`, starting in free space.
std::vector<Probe> draw_probes(const VoxelTooth& tooth, int count, double rho,
                               std::mt19937_64& rng) {
  const VoxelGrid& g = tooth.grid();
  std::vector<std::uint64_t> faces;
  for (std::size_t v = 0; v < g.voxels.size(); ++v) {
    const std::uint8_t code = tooth.codes.code(v);
    for (int f = 0; f < 6; ++f) {
      if (code & (1u << f)) faces.push_back(8 * v + static_cast<std::uint64_t>(f));
    }
  }
  if (faces.empty()) throw InputError("crosscheck contact: a tooth has no exposed face");
  std::uniform_int_distribution<std::size_t> pick(0, faces.size() - 1);
  const std::size_t n = static_cast<std::size_t>(g.n);
  std::vector<Probe> out;
  for (int attempt = 0; static_cast<int>(out.size()) < count && attempt < 100 * count; ++attempt) {
    const std::uint64_t e = faces[pick(rng)];
    const std::size_t v = e / 8;
    const int f = static_cast<int>(e % 8);
    const Vec3 nf = face_normal(f);
    const Vec3 p = g.center(static_cast<int>(v % n), static_cast<int>((v / n) % n),
                            static_cast<int>(v / (n * n))) +
                   0.5 * g.voxel_size * nf;
    const Vec3 d = -(nf + 0.8 * random_unit(rng)).normalized();
    if (d.dot(nf) > -0.2) continue;
    Probe probe;
    probe.d = d;
    probe.start = p - (rho + kStartGapM) * d;
    if (signed_distance(tooth, probe.start, 2.0 * rho).phi < rho + 0.5 * kStartGapM) continue;
    const Vec3 w = random_unit(rng);
    probe.t = (w - w.dot(d) * d);
    if (probe.t.norm() < 1e-6) continue;
    probe.t.normalize();
    out.push_back(probe);
  }
  return out;
}

struct ProbeOutcome {
  bool popped = false;
  double max_penetration = 0.0;  // [m]
};

ProbeOutcome run_probe(VoxelTooth& tooth, SampledField* field, ContactModel model,
                       const Probe& probe, double force, const ContactCrosscheckOptions& o) {
  const double rho = o.tip_radius_m;
  ToothContactProvider provider(tooth, ToolTip{rho, Vec3::Zero()}, o.k_tooth, 0.0, nullptr, model,
                                &signed_distance, field);
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  Pose pose;
  pose.x = probe.start;
  ProbeOutcome out;
  for (int tick = 0; tick < o.settle_ticks + o.slide_ticks; ++tick) {
    provider.contacts(pose, contacts);
    const Vec3 f = blended_contact_force(contacts);
    const Vec3 y = model != ContactModel::kFaces && provider.surface_proxy().valid()
                       ? provider.surface_proxy().g()
                       : pose.x;
    const SignedDistance sd = signed_distance(tooth, y, 2.0 * rho);
    // The field model's own solid is {phi_field <= 0}; the rendered centre must be outside both.
    const double phi_field = model == ContactModel::kField ? field->value(y) : sd.phi;
    out.max_penetration = std::max(out.max_penetration, rho - phi_field);
    if ((sd.phi < 0.0 || phi_field < 0.0) && -f.dot(probe.d) < 0.5 * force) out.popped = true;
    Vec3 step = kAlpha * (force * probe.d + f) / o.k_tooth;
    if (step.norm() > kMaxStepM) step *= kMaxStepM / step.norm();
    if (tick >= o.settle_ticks) step += kSlideStepM * probe.t;
    pose.x += step;
  }
  out.max_penetration = std::max(0.0, out.max_penetration);
  return out;
}

// The voxelised sphere of radius 5 mm with voxel size h (centre test), on the smallest
// power-of-two grid holding it with a 1 mm margin.
VoxelTooth make_sphere(double h, Vec3* centre) {
  int n = 16;
  while (n * h < 2.0 * (kSphereRadiusM + 1e-3)) n *= 2;
  VoxelGrid g(n, Vec3::Zero(), h);
  *centre = Vec3::Constant(0.5 * n * h);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if ((g.center(i, j, k) - *centre).norm() < kSphereRadiusM) g.set(i, j, k, kEnamel);
      }
    }
  }
  return VoxelTooth(std::move(g));
}

double sliding_ripple(VoxelTooth& sphere, SampledField* field, const Vec3& centre,
                      ContactModel model, double force, const ContactCrosscheckOptions& o) {
  const double rho = o.tip_radius_m;
  ToothContactProvider provider(sphere, ToolTip{rho, Vec3::Zero()}, o.k_tooth, 0.0, nullptr, model,
                                &signed_distance, field);
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  const double azimuth = 20.0 * std::numbers::pi / 180.0;
  const double radius = kSphereRadiusM + rho - force / o.k_tooth;
  double sum2 = 0.0;
  for (int i = 0; i < kRippleTicks; ++i) {
    const double polar = (80.0 * std::numbers::pi / 180.0) * i / (kRippleTicks - 1);
    const Vec3 u(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                 std::cos(polar));
    Pose pose;
    pose.x = centre + radius * u;
    provider.contacts(pose, contacts);
    const Vec3 f = blended_contact_force(contacts);
    sum2 += (f - force * u).squaredNorm() / (force * force);
  }
  return std::sqrt(sum2 / kRippleTicks);
}

// Records the pose the tick's contact stage was asked at (the tool pose the contact force belongs
// to), and forwards to the wrapped provider.
class PoseRecorder : public ContactProvider {
 public:
  explicit PoseRecorder(ContactProvider& inner) : inner_(inner) {}
  bool contacts(const Pose& proxy, std::vector<Contact>& out) override {
    last_ = proxy.x;
    return inner_.contacts(proxy, out);
  }
  const Vec3& last() const { return last_; }

 private:
  ContactProvider& inner_;
  Vec3 last_ = Vec3::Zero();
};

// The exact sphere of radius R about c as a contact provider (the penalty law of the models:
// depth R + rho - |x - c|, normal (x - c) / |x - c|, stiffness K, weight 1), for the loop's own
// ripple with no shape error at all.
class ExactBall : public ContactProvider {
 public:
  ExactBall(const Vec3& centre, double radius, double rho, double k)
      : c_(centre), r_(radius), rho_(rho), k_(k) {}
  bool contacts(const Pose& proxy, std::vector<Contact>& out) override {
    out.clear();
    const Vec3 d = proxy.x - c_;
    const double dist = d.norm();
    const double depth = r_ + rho_ - dist;
    if (depth <= 0.0 || dist == 0.0) return true;
    if (out.capacity() == 0) return false;
    const Vec3 n = d / dist;
    Contact c;
    const Vec3 x_c = proxy.x - rho_ * n;
    c.x_o = x_c + depth * n;
    c.n = n;
    c.r = proxy.R.transpose() * (x_c - proxy.x);
    c.depth = depth;
    c.stiffness = k_;
    c.damping = 0.0;
    c.weight = 1.0;
    out.push_back(c);
    return true;
  }

 private:
  Vec3 c_;
  double r_, rho_, k_;
};

// The meridian of sliding_ripple (polar angle 0..80 deg at azimuth 20 deg), at the polar angle
// 80 deg x s(fraction), s the smoothstep 3 f^2 - 2 f^3: the hand starts and stops without a jerk
// (a reference whose speed steps would ring the loop by the hand's own doing).
Vec3 meridian(double fraction) {
  const double azimuth = 20.0 * std::numbers::pi / 180.0;
  const double f = std::clamp(fraction, 0.0, 1.0);
  const double polar = (80.0 * std::numbers::pi / 180.0) * f * f * (3.0 - 2.0 * f);
  return Vec3(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
              std::cos(polar));
}

// The RMS over the series of |e_i - mean of e over the centred window of +-kRippleWindow ticks|,
// over `scale`: the fluctuation, without the slow part (the rendered tool's drag while it slides,
// the hand's steering lag), which is a feel the tool is given, not a ripple.
constexpr int kRippleWindow = 25;  // +-25 ms: passes what is faster than ~20 Hz

double detrended_rms(const std::vector<Vec3>& e, double scale) {
  const int n = static_cast<int>(e.size());
  double sum2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const int lo = std::max(0, i - kRippleWindow), hi = std::min(n - 1, i + kRippleWindow);
    Vec3 mean = Vec3::Zero();
    for (int j = lo; j <= hi; ++j) mean += e[static_cast<std::size_t>(j)];
    mean /= static_cast<double>(hi - lo + 1);
    sum2 += (e[static_cast<std::size_t>(i)] - mean).squaredNorm();
  }
  return std::sqrt(sum2 / static_cast<double>(n)) / scale;
}

double rms(const std::vector<Vec3>& e, double scale) {
  double sum2 = 0.0;
  for (const Vec3& v : e) sum2 += v.squaredNorm();
  return std::sqrt(sum2 / static_cast<double>(e.size())) / scale;
}

// Whether the closed-loop slide is measured at this push: the tool sits F / K inside the sphere,
// and past a third of its radius the hand's script (steering towards the centre) rather than the
// model decides where the tool goes (at 8.5 N and 3000 N/m the tool sits 2.6 mm from the centre of
// the 5 mm sphere; it slips through the centre there on the exact sphere too).
bool closed_loop_measured(double force, const ContactCrosscheckOptions& o) {
  return force / o.k_tooth <= kSphereRadiusM / 3.0;
}

// The closed-loop slide over `provider` (a model's sphere or the exact one).
ClosedLoopRipple sliding_ripple_closed_loop(ContactProvider& provider, const Vec3& centre,
                                            double force, const ContactCrosscheckOptions& o) {
  const double rho = o.tip_radius_m;
  PoseRecorder recorder(provider);
  WallLoopConfig c;
  c.device.mass = 0.075;  // the apparent tip of a Phantom Premium (validation/wall_demo.h)
  c.device.inertia = Mat3::Identity() * 2e-4;
  c.device.damping_lin = 0.5;
  c.device.damping_ang = 0.002;
  c.pipeline.method = Method::kPmiPd;
  c.pipeline.tool = tool_preset("handpiece");
  c.pipeline.observer_gain = VecX::Constant(6, 100.0);  // coupling, proxy: the defaults
  c.tick = 1e-3;
  const double r_eq = kSphereRadiusM + rho - force / o.k_tooth;
  c.start = centre + (kSphereRadiusM + rho + kLoopStartGapM) * meridian(0.0);
  const double slide_s = kRippleTicks * c.tick;
  c.duration = kLoopSettleS + slide_s;
  // The hand pushes with `force` towards the centre (ramped over 0.2 s), steers along the
  // meridian with a spring in the tangent plane only (so the normal force is the push), and
  // damps all motion a little; the wrist holds the orientation (WallHand's defaults).
  const WallHand wrist;
  const HandWrenchFn hand = [&](double t, const Vec3& x, const Mat3& R, const Vec3& v,
                                const Vec3& w) {
    const Vec3 u = (x - centre).normalized();
    const Vec3 x_ref = centre + r_eq * meridian((t - kLoopSettleS) / slide_s);
    const Vec3 to_ref = x_ref - x;
    const double ramp = std::min(1.0, t / 0.2);
    const Vec3 f = -ramp * force * u + kHandTangentialStiffness * (to_ref - to_ref.dot(u) * u) -
                   kHandDamping * v;
    const Vec3 tau = -wrist.stiffness_ang * log_so3(R) - wrist.damping_ang * w;
    return stack(f, tau);
  };
  std::vector<Vec3> e_total, e_geo, e_dyn;
  e_total.reserve(kRippleTicks);
  e_geo.reserve(kRippleTicks);
  e_dyn.reserve(kRippleTicks);
  const bool finite = run_provider_loop(c, recorder, hand, [&](const ProviderLoopRecord& rec) {
    if (rec.t <= kLoopSettleS + 0.5 * c.tick) return;  // the slide's ticks only
    const Vec3 x = recorder.last();  // the pose the contact force was computed at
    const Vec3 u = (x - centre).normalized();
    const Vec3 f_contact = blended_contact_force(rec.tick->contacts);
    const Vec3 f_exact = o.k_tooth * std::max(0.0, kSphereRadiusM + rho - (x - centre).norm()) * u;
    e_total.push_back(rec.device_force - force * u);
    e_geo.push_back(f_contact - f_exact);
    e_dyn.push_back(e_total.back() - e_geo.back());
  });
  ClosedLoopRipple out;
  if (!finite || e_total.empty()) {
    out.total = out.geometric = out.dynamic = out.error = std::numeric_limits<double>::infinity();
    return out;
  }
  out.total = detrended_rms(e_total, force);
  out.geometric = detrended_rms(e_geo, force);
  out.dynamic = detrended_rms(e_dyn, force);
  out.error = rms(e_total, force);
  return out;
}

}  // namespace

ContactCrosscheckResult crosscheck_contact(const ContactCrosscheckOptions& o) {
  for (const int r : o.resolutions) {
    if (r < 16 || r > 512 || (r & (r - 1)) != 0) {
      throw InputError("--resolutions: " + std::to_string(r) +
                       ", expected powers of two from 16 to 512");
    }
  }
  for (const double f : o.forces_n) {
    if (!(f > 0.0) || !std::isfinite(f)) {
      throw InputError("--forces: " + std::to_string(f) + ", expected finite forces > 0 [N]");
    }
  }
  if (o.probes < 1) throw InputError("--probes: expected at least 1");
  if (o.models.empty()) throw InputError("--models: expected at least one of sdf, faces, field");
  std::vector<ContactModel> models;
  for (const std::string& m : o.models) models.push_back(parse_contact_model(m));
  const bool with_field =
      std::find(models.begin(), models.end(), ContactModel::kField) != models.end();
  std::vector<std::string> meshes;
  if (!o.data_dir.empty()) {
    for (const char* file : {"molar-cc0.stl", "chai3d-tooth.obj"}) {
      const std::string path = o.data_dir + "/" + file;
      if (!std::filesystem::exists(path)) {
        throw InputError("--data-dir: " + path +
                         " not found (expected the meshes of "
                         "../shared/data; --data-dir '' sweeps the procedural molar only)");
      }
      meshes.push_back(path);
    }
  }

  ContactCrosscheckResult result;
  result.options = o;
  result.teeth.push_back("procedural molar");
  for (const std::string& m : meshes) {
    result.teeth.push_back(std::filesystem::path(m).filename().string());
  }
  const int teeth = static_cast<int>(result.teeth.size());
  const int per_tooth = (o.probes + teeth - 1) / teeth;
  // The field's spacing on voxels of size h (the automatic rule; 0 for the other models).
  const auto spacing_of = [&](const std::string& model, double h) {
    return model == "field" ? field_stride_for(o.tip_radius_m, h) * h : 0.0;
  };
  for (const int res : o.resolutions) {
    std::vector<ContactSweepRow> rows(models.size());
    for (std::size_t m = 0; m < models.size(); ++m) {
      rows[m].model = o.models[m];
      rows[m].resolution = res;
      rows[m].pop_throughs_per_force.assign(o.forces_n.size(), 0);
    }
    double h_molar = 0.0;
    for (int t = 0; t < teeth; ++t) {
      SweptTooth swept = build_swept_tooth(t == 0 ? std::string() : meshes[t - 1],
                                           o.mesh_size_mm, res, with_field, o.tip_radius_m);
      VoxelTooth& tooth = swept.tooth;
      if (t == 0) h_molar = tooth.grid().voxel_size;
      std::mt19937_64 rng(o.seed + 1000003ULL * static_cast<std::uint64_t>(res) +
                          static_cast<std::uint64_t>(t));
      const std::vector<Probe> probes = draw_probes(tooth, per_tooth, o.tip_radius_m, rng);
      for (std::size_t m = 0; m < models.size(); ++m) {
        ContactSweepRow& row = rows[m];
        for (const Probe& probe : probes) {
          if (o.stop_request != nullptr && o.stop_request->load(std::memory_order_relaxed)) {
            // What it has: the resolutions done are in result.rows; this one's probes so far
            // follow, marked partial (no ripple).
            for (ContactSweepRow& done : rows) {
              done.partial = true;
              done.voxel_size_m = h_molar;
              done.field_spacing_m = spacing_of(done.model, h_molar);
              done.sliding_ripple_rms = std::numeric_limits<double>::quiet_NaN();
              result.rows.push_back(done);
            }
            result.stopped = true;
            result.stopped_at = "n=" + std::to_string(res) + ", tooth " + std::to_string(t + 1) +
                                " of " + std::to_string(teeth);
            return result;
          }
          ++row.probes;
          for (std::size_t fi = 0; fi < o.forces_n.size(); ++fi) {
            const ProbeOutcome out =
                run_probe(tooth, swept.field.get(), models[m], probe, o.forces_n[fi], o);
            ++row.runs;
            if (out.popped) {
              ++row.pop_throughs;
              ++row.pop_throughs_per_force[fi];
            }
            row.max_penetration_over_radius =
                std::max(row.max_penetration_over_radius, out.max_penetration / o.tip_radius_m);
            row.max_penetration_over_voxel = std::max(
                row.max_penetration_over_voxel, out.max_penetration / tooth.grid().voxel_size);
          }
        }
      }
    }
    Vec3 centre;
    VoxelTooth sphere = make_sphere(h_molar, &centre);
    std::unique_ptr<SampledField> sphere_field;
    if (with_field) {  // from the sphere's own implicit function (the voxels' centre test)
      sphere_field = std::make_unique<SampledField>(build_sampled_field(
          sphere.grid(),
          triangulate_implicit(sphere.grid(),
                               [&](const Vec3& p) { return (p - centre).norm() < kSphereRadiusM; }),
          field_band_for_tip(o.tip_radius_m, h_molar,
                             field_stride_for(o.tip_radius_m, h_molar))));
    }
    // The loop on the exact sphere: the same for every model (no voxels, no field).
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> exact_sphere;
    for (const double f : o.forces_n) {
      ExactBall ball(centre, kSphereRadiusM, o.tip_radius_m, o.k_tooth);
      exact_sphere.push_back(closed_loop_measured(f, o)
                                 ? sliding_ripple_closed_loop(ball, centre, f, o).total
                                 : kNaN);
    }
    for (std::size_t m = 0; m < models.size(); ++m) {
      rows[m].voxel_size_m = h_molar;
      rows[m].field_spacing_m = spacing_of(rows[m].model, h_molar);
      for (const double f : o.forces_n) {
        rows[m].ripple_per_force.push_back(
            sliding_ripple(sphere, sphere_field.get(), centre, models[m], f, o));
      }
      rows[m].sliding_ripple_rms =
          *std::max_element(rows[m].ripple_per_force.begin(), rows[m].ripple_per_force.end());
      for (std::size_t fi = 0; fi < o.forces_n.size(); ++fi) {
        const double f = o.forces_n[fi];
        if (!closed_loop_measured(f, o)) {
          rows[m].closed_loop_per_force.push_back({kNaN, kNaN, kNaN, kNaN, kNaN});
          continue;
        }
        ToothContactProvider provider(sphere, ToolTip{o.tip_radius_m, Vec3::Zero()}, o.k_tooth,
                                      0.0, nullptr, models[m], &signed_distance,
                                      sphere_field.get());
        ClosedLoopRipple cl = sliding_ripple_closed_loop(provider, centre, f, o);
        cl.exact_sphere = exact_sphere[fi];
        rows[m].closed_loop_per_force.push_back(cl);
        rows[m].closed_loop_ripple_rms = std::max(rows[m].closed_loop_ripple_rms, cl.total);
        rows[m].geometric_ripple_rms = std::max(rows[m].geometric_ripple_rms, cl.geometric);
        rows[m].dynamic_ripple_rms = std::max(rows[m].dynamic_ripple_rms, cl.dynamic);
        rows[m].exact_sphere_ripple_rms =
            std::max(rows[m].exact_sphere_ripple_rms, cl.exact_sphere);
      }
      result.rows.push_back(rows[m]);
    }
  }
  return result;
}

nlohmann::json crosscheck_contact_json(const ContactCrosscheckResult& r) {
  const ContactCrosscheckOptions& o = r.options;
  nlohmann::json rows = nlohmann::json::array();
  long default_pops = 0;
  for (const ContactSweepRow& row : r.rows) {
    if (row.model == "sdf") default_pops += row.pop_throughs;
    nlohmann::json per_force = nlohmann::json::array();
    const auto or_null = [](bool have, double v) {
      return have && !std::isnan(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
    };
    for (std::size_t i = 0; i < o.forces_n.size(); ++i) {
      const bool loop = i < row.closed_loop_per_force.size();
      per_force.push_back(
          {{"force_n", o.forces_n[i]},
           {"pop_throughs", row.pop_throughs_per_force[i]},
           {"sliding_ripple_rms",
            or_null(i < row.ripple_per_force.size(),
                    i < row.ripple_per_force.size() ? row.ripple_per_force[i] : 0.0)},
           {"closed_loop_ripple_rms", or_null(loop, loop ? row.closed_loop_per_force[i].total : 0.0)},
           {"geometric_ripple_rms",
            or_null(loop, loop ? row.closed_loop_per_force[i].geometric : 0.0)},
           {"dynamic_ripple_rms", or_null(loop, loop ? row.closed_loop_per_force[i].dynamic : 0.0)},
           {"exact_sphere_ripple_rms",
            or_null(loop, loop ? row.closed_loop_per_force[i].exact_sphere : 0.0)},
           {"closed_loop_error_rms", or_null(loop, loop ? row.closed_loop_per_force[i].error : 0.0)}});
    }
    rows.push_back({{"model", row.model},
                    {"resolution", row.resolution},
                    {"voxel_size_mm", 1e3 * row.voxel_size_m},
                    {"field_spacing_mm", 1e3 * row.field_spacing_m},
                    {"probes", row.probes},
                    {"runs", row.runs},
                    {"pop_throughs", row.pop_throughs},
                    {"max_penetration_over_radius", row.max_penetration_over_radius},
                    {"max_penetration_over_voxel", row.max_penetration_over_voxel},
                    {"sliding_ripple_rms", or_null(!row.partial, row.sliding_ripple_rms)},
                    {"closed_loop_ripple_rms", or_null(!row.partial, row.closed_loop_ripple_rms)},
                    {"geometric_ripple_rms", or_null(!row.partial, row.geometric_ripple_rms)},
                    {"dynamic_ripple_rms", or_null(!row.partial, row.dynamic_ripple_rms)},
                    {"exact_sphere_ripple_rms", or_null(!row.partial, row.exact_sphere_ripple_rms)},
                    {"per_force", per_force}});
    if (row.partial) rows.back()["partial"] = true;
  }
  return {{"teeth", r.teeth},
          {"resolutions", o.resolutions},
          {"forces_n", o.forces_n},
          {"models", o.models},
          {"tip_radius_mm", 1e3 * o.tip_radius_m},
          {"k_tooth_n_per_m", o.k_tooth},
          {"mesh_size_mm", o.mesh_size_mm},
          {"settle_ticks", o.settle_ticks},
          {"slide_ticks", o.slide_ticks},
          {"seed", o.seed},
          {"default_model", "sdf"},
          {"default_model_pop_throughs", default_pops},
          {"rows", rows}};
}

}  // namespace dentsim
