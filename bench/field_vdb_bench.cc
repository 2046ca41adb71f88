// The field contact model's sampled field (reference/tooth/sampled_field.h, fast/tooth/field.h)
// against OpenVDB 10's narrow-band level set of the same triangles (issue #30; benchmark-only
// dependency, Debian libopenvdb-dev; built by `DENTSIM_OPENVDB`, see CMakeLists.txt).
//
// The tooth: the procedural molar as the drill scene voxelises it (default MolarParams, N^3 for
// N = 128 and 256; in the molar's own frame, not moved to the scene's anchor), its surface the
// triangles build_tooth_field makes of it (triangulate_implicit of molar_solid), the band of the
// drill scene's 0.5 mm bur (field_band_for_tip: c_out = 1.25 rho + 2 h outside, c_in = 2 h
// inside). OpenVDB's grid has the same voxel size and its voxel centres on our samples (index
// (i, j, k) at the centre of voxel (i, j, k): the transform is the scale h then the grid's origin
// + h/2), and the same band (exterior c_out / h, interior c_in / h voxels).
//
// Query (BM_FieldVdbQuery): value and gradient at a point, at the same 4096 points as
// BM_FieldQuery (bench/tooth_bench.cc) taken about the top of the centre column
// (bench::occlusal_pose): `scatter`, seeded within 0.6 mm (each query in another cell), and
// `path`, 0.55 um apart from 1 mm above down through the surface (consecutive queries in one
// cell). The gradient is the trilinear interpolant's, on both sides:
// - ours: SampledField::sample (reference: the brick index read per corner) and
//   fast::FieldBricks::sample (9^3 bricks, the last brick kept), value and analytic gradient
//   from one gather; and the surface proxy's query as the tick calls it (FieldSolid::distance(x,
//   rho), then normal(x) where found; the fast one with its kept query and free-space
//   certificate), as BM_FieldQuery times it;
// - OpenVDB: math::BoxStencil<FloatGrid> (moveTo the cell, then interpolation() and gradient():
//   the trilinear interpolant and its analytic gradient, the 8 corners read through the stencil's
//   ValueAccessor, which caches the last leaf and internal nodes; moveTo skips the gather when the
//   cell is the stencil's current one); and tools::GridSampler<FloatGrid::ConstAccessor,
//   BoxSampler>::wsSample for the value (its accessor caches the last leaf; 8 probes a query)
//   with BoxStencil's gradient; and the sampler's value alone. World to index by the grid's
//   transform in every OpenVDB row. Accessors and stencils are made once and reused.
// Before timing the values and gradients at every point are checked to agree (both are
// distances to the same triangles, interpolated the same way: kValueBound and the others below).
//
// Build (BM_FieldVdbBuild): build_sampled_field (ours, one thread; the signs read from the
// voxelised tooth) against tools::meshToSignedDistanceField (the same asymmetric band; OpenVDB
// finds the signs itself) at one TBB thread and at all threads, and tools::meshToLevelSet (a
// symmetric band of c_out / h voxels, the wider interior costing it more) at one thread.
// Inputs made before timing: our TriangleMesh, OpenVDB's float points and triangles.
//
// Results and command: docs/benchmarks.md "The field against OpenVDB".
#include <benchmark/benchmark.h>
#include <openvdb/math/Stencils.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bench/tooth_bench.h"
#include "fast/tooth/field.h"
#include "reference/tooth/field_contact.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

constexpr double kRho = 0.5e-3;  // the drill scene's bur radius [m]
// Agreement bounds: at every query point |phi_ours - phi_vdb| <= kValueBound h and
// |grad_ours - grad_vdb|_inf <= kGradientBound, and at least kCloseFraction of the points within
// kCloseBound h. Both fields are distances to the same triangles on the same lattice, interpolated
// by the same formula, but OpenVDB's values are not exact near the surface: where the samples
// differ, ours matched the brute-force nearest-triangle distance (checked by hand at 128^3), while meshToVolume
// renormalises the voxels next to the surface (interior values move by up to ~0.5 h), classifies
// the sign of voxel centres within ~0.06 h of the surface differently from the voxelised solid,
// and grows the band to values up to ~0.05 h above the nearest distance near 2 h. Measured: max
// 0.53 h (128^3) / 0.24 h (256^3), median 0.003 h / 0, 59 % / 81 % within 0.01 h (docs/
// benchmarks.md). A lattice misplaced by a fraction of a voxel fails the share; a gradient is a
// difference of samples over h, so a sample difference of e h moves it by up to ~2 e.
constexpr double kValueBound = 0.75;
constexpr double kGradientBound = 1.0;
constexpr double kCloseBound = 1e-2, kCloseFraction = 0.5;

using openvdb::FloatGrid;

struct Tooth {
  VoxelTooth tooth;
  TriangleMesh surface;
  FieldBand band;
  SampledField field;
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  openvdb::math::Transform::Ptr xform;
  float exterior = 0.0f, interior = 0.0f;  // OpenVDB's band [voxels]
  FloatGrid::Ptr vdb;
  std::vector<Vec3> scatter, path;
  // Max over the points: value difference / h, gradient difference, sampler against stencil / h.
  double value_diff = 0.0, gradient_diff = 0.0, sampler_diff = 0.0;
  double median_diff = 0.0, close_fraction = 0.0;  // median / h; the share within kCloseBound h
  Vec3 worst = Vec3::Zero();  // where the value differs most
  bool agree = false;

  explicit Tooth(int n) : tooth(voxelize_procedural_molar(MolarParams{}, n)) {
    openvdb::initialize();
    const VoxelGrid& g = tooth.grid();
    const double h = g.voxel_size;
    const MolarParams params;
    surface = triangulate_implicit(g, [&](const Vec3& p) { return molar_solid(params, p); });
    band = field_band_for_tip(kRho, h);
    field = build_sampled_field(g, surface, band);
    for (const Vec3& v : surface.vertices) {
      points.emplace_back(static_cast<float>(v.x()), static_cast<float>(v.y()),
                          static_cast<float>(v.z()));
    }
    for (const auto& t : surface.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    xform = openvdb::math::Transform::createLinearTransform(h);
    const Vec3 centre0 = g.origin + 0.5 * h * Vec3::Ones();
    xform->postTranslate(openvdb::Vec3d(centre0.x(), centre0.y(), centre0.z()));
    exterior = static_cast<float>(field.outside_clamp() / h);
    interior = static_cast<float>(field.inside_clamp() / h);
    vdb = openvdb::tools::meshToSignedDistanceField<FloatGrid>(
        *xform, points, triangles, std::vector<openvdb::Vec4I>(), exterior, interior);

    // BM_FieldQuery's points about the top of the centre column.
    const Vec3 a = bench::occlusal_pose(g, 0.0).x;
    std::mt19937_64 rng(30);
    std::uniform_real_distribution<double> u(-0.6e-3, 0.6e-3);
    for (int i = 0; i < 4096; ++i) scatter.push_back(a + Vec3(u(rng), u(rng), u(rng)));
    Vec3 x = a + Vec3(-0.4e-3, 0.1e-3, 1.0e-3);
    for (int i = 0; i < 4096; ++i, x += Vec3(0.2e-6, 0.05e-6, -0.5e-6)) path.push_back(x);

    // Agreement (header comment): value and gradient of ours against OpenVDB's BoxStencil, and
    // the GridSampler's value against the stencil's.
    openvdb::math::BoxStencil<FloatGrid> stencil(*vdb);
    const FloatGrid::ConstAccessor acc = vdb->getConstAccessor();
    const openvdb::tools::GridSampler<FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
        sampler(acc, vdb->transform());
    std::vector<double> diffs;
    for (const auto* set : {&scatter, &path}) {
      for (const Vec3& p : *set) {
        const FieldSample ours = field.sample(p);
        const openvdb::Vec3d w(p.x(), p.y(), p.z());
        const openvdb::Vec3d ijk = vdb->transform().worldToIndex(w);
        stencil.moveTo(ijk);
        const float v = stencil.interpolation(openvdb::Vec3f(ijk));
        const openvdb::Vec3f gv = stencil.gradient(openvdb::Vec3f(ijk));
        diffs.push_back(std::abs(ours.value - v) / h);
        if (std::abs(ours.value - v) / h > value_diff) {
          value_diff = std::abs(ours.value - v) / h;
          worst = p;
        }
        for (int k = 0; k < 3; ++k) {
          gradient_diff = std::max(gradient_diff, std::abs(ours.gradient[k] - gv[k]));
        }
        sampler_diff = std::max(sampler_diff, std::abs(sampler.wsSample(w) - v) / h);
      }
    }
    std::sort(diffs.begin(), diffs.end());
    median_diff = diffs[diffs.size() / 2];
    close_fraction = static_cast<double>(std::upper_bound(diffs.begin(), diffs.end(), kCloseBound) -
                                         diffs.begin()) /
                     static_cast<double>(diffs.size());
    agree = close_fraction >= kCloseFraction && value_diff <= kValueBound && sampler_diff <= kValueBound &&
            gradient_diff <= kGradientBound;
  }
};
Tooth& tooth(int n) { return bench::built_once<Tooth>(n); }

// Args: implementation (below), resolution, points (0 scatter, 1 path).
enum QueryImpl {
  kReferenceSample,
  kFastSample,
  kReferenceSolid,
  kFastSolid,
  kVdbStencil,
  kVdbSamplerStencil,
  kVdbSamplerValue,
  kQueryImpls
};
const char* const kQueryLabel[kQueryImpls] = {
    "ours reference SampledField::sample", "ours fast FieldBricks::sample",
    "ours reference FieldSolid distance+normal", "ours fast FieldSolid distance+normal",
    "openvdb BoxStencil value+gradient", "openvdb GridSampler<BoxSampler> value + BoxStencil gradient",
    "openvdb GridSampler<BoxSampler> value only"};

// Times query(x) over the points in order, cyclically.
template <class Query>
void run_points(benchmark::State& state, const std::vector<Vec3>& points, Query query) {
  std::size_t i = 0;
  for (auto _ : state) {
    query(points[i]);
    i = i + 1 == points.size() ? 0 : i + 1;
  }
}

template <class Solid>
void run_solid(benchmark::State& state, const Solid& solid, const std::vector<Vec3>& points) {
  run_points(state, points, [&](const Vec3& x) {
    const SignedDistance sd = solid.distance(x, kRho);
    benchmark::DoNotOptimize(sd);
    if (sd.found) benchmark::DoNotOptimize(solid.normal(x, sd));
  });
}

void BM_FieldVdbQuery(benchmark::State& state) {
  const int impl = static_cast<int>(state.range(0));
  Tooth& t = tooth(static_cast<int>(state.range(1)));
  const std::vector<Vec3>& points = state.range(2) == 0 ? t.scatter : t.path;
  state.SetLabel(std::string(kQueryLabel[impl]) + (state.range(2) == 0 ? ", scatter" : ", path"));
  if (!t.agree) {
    const std::string what = "ours and OpenVDB's fields disagree at the query points: max |dphi| / h " +
                             std::to_string(t.value_diff) + " at (" + std::to_string(t.worst.x()) +
                             ", " + std::to_string(t.worst.y()) + ", " +
                             std::to_string(t.worst.z()) + "), max |dgrad| " +
                             std::to_string(t.gradient_diff) + ", sampler " +
                             std::to_string(t.sampler_diff) +
                             ", median / h " + std::to_string(t.median_diff) + ", share within " +
                             std::to_string(kCloseBound) + " h " + std::to_string(t.close_fraction);
    state.SkipWithError(what.c_str());
    return;
  }
  state.counters["max_dphi_over_h"] = t.value_diff;
  state.counters["median_dphi_over_h"] = t.median_diff;
  state.counters["close_share"] = t.close_fraction;
  state.counters["max_dgrad"] = t.gradient_diff;
  const openvdb::math::Transform& xf = t.vdb->transform();
  const auto index_of = [&](const Vec3& x) {
    return xf.worldToIndex(openvdb::Vec3d(x.x(), x.y(), x.z()));
  };
  switch (impl) {
    case kReferenceSample:
      run_points(state, points, [&](const Vec3& x) { benchmark::DoNotOptimize(t.field.sample(x)); });
      break;
    case kFastSample: {
      const fast::FieldBricks bricks(t.field, 0);
      run_points(state, points, [&](const Vec3& x) { benchmark::DoNotOptimize(bricks.sample(x)); });
      break;
    }
    case kReferenceSolid:
      run_solid(state, dentsim::FieldSolid(t.tooth, t.field), points);
      break;
    case kFastSolid: {
      const fast::FieldBricks bricks(t.field, 0);
      run_solid(state, fast::FieldSolid(t.tooth, bricks), points);
      break;
    }
    case kVdbStencil: {
      openvdb::math::BoxStencil<FloatGrid> stencil(*t.vdb);
      run_points(state, points, [&](const Vec3& x) {
        const openvdb::Vec3d ijk = index_of(x);
        stencil.moveTo(ijk);
        benchmark::DoNotOptimize(stencil.interpolation(openvdb::Vec3f(ijk)));
        benchmark::DoNotOptimize(stencil.gradient(openvdb::Vec3f(ijk)));
      });
      break;
    }
    case kVdbSamplerStencil:
    case kVdbSamplerValue: {
      const FloatGrid::ConstAccessor acc = t.vdb->getConstAccessor();
      const openvdb::tools::GridSampler<FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
          sampler(acc, xf);
      openvdb::math::BoxStencil<FloatGrid> stencil(*t.vdb);
      const bool gradient = impl == kVdbSamplerStencil;
      run_points(state, points, [&](const Vec3& x) {
        benchmark::DoNotOptimize(sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())));
        if (gradient) {
          const openvdb::Vec3d ijk = index_of(x);
          stencil.moveTo(ijk);
          benchmark::DoNotOptimize(stencil.gradient(openvdb::Vec3f(ijk)));
        }
      });
      break;
    }
    default:
      state.SkipWithError("no such implementation");
  }
}
BENCHMARK(BM_FieldVdbQuery)
    ->ArgsProduct({benchmark::CreateDenseRange(0, kQueryImpls - 1, 1), {128, 256}, {0, 1}});

// Args: implementation (below), resolution.
enum BuildImpl { kOursBuild, kVdbSdfOneThread, kVdbSdfAllThreads, kVdbLevelSetOneThread, kBuildImpls };
const char* const kBuildLabel[kBuildImpls] = {
    "ours build_sampled_field (1 thread)", "openvdb meshToSignedDistanceField, same band (1 thread)",
    "openvdb meshToSignedDistanceField, same band (all threads)",
    "openvdb meshToLevelSet, half width c_out (1 thread)"};

void BM_FieldVdbBuild(benchmark::State& state) {
  const int impl = static_cast<int>(state.range(0));
  Tooth& t = tooth(static_cast<int>(state.range(1)));
  state.SetLabel(kBuildLabel[impl]);
  std::optional<tbb::global_control> one_thread;
  if (impl == kVdbSdfOneThread || impl == kVdbLevelSetOneThread) {
    one_thread.emplace(tbb::global_control::max_allowed_parallelism, 1);
  }
  const std::vector<openvdb::Vec4I> no_quads;
  double stored = 0.0, bytes = 0.0;
  for (auto _ : state) {
    if (impl == kOursBuild) {
      const SampledField f = build_sampled_field(t.tooth.grid(), t.surface, t.band);
      stored = static_cast<double>(f.brick_count() * SampledField::kBrickSamples);
      bytes = static_cast<double>(f.memory_bytes());
      benchmark::DoNotOptimize(f.lipschitz());
    } else {
      const FloatGrid::Ptr g =
          impl == kVdbLevelSetOneThread
              ? openvdb::tools::meshToLevelSet<FloatGrid>(*t.xform, t.points, t.triangles,
                                                          t.exterior)
              : openvdb::tools::meshToSignedDistanceField<FloatGrid>(
                    *t.xform, t.points, t.triangles, no_quads, t.exterior, t.interior);
      stored = static_cast<double>(g->activeVoxelCount());
      bytes = static_cast<double>(g->memUsage());
      benchmark::DoNotOptimize(g.get());
    }
  }
  state.counters["triangles"] = static_cast<double>(t.surface.triangles.size());
  state.counters["stored_values"] = stored;  // ours: samples in bricks; OpenVDB: active voxels
  state.counters["bytes"] = bytes;
}
BENCHMARK(BM_FieldVdbBuild)
    ->ArgsProduct({benchmark::CreateDenseRange(0, kBuildImpls - 1, 1), {128, 256}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace dentsim
