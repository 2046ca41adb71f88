// Scan volume -> voxel tooth (volume.h: thresholds, resampling, partial-volume correction,
// islands, pulp by seed fill).
#include "tooth_io/volume.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "reference/core/io.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

using Mask = std::vector<std::uint8_t>;

// 6-connected components of equal values of `cls` on an nx x ny x nz lattice (i fastest). Returns
// each voxel's component id in `label` and the components' sizes.
std::vector<long> label_components(const Mask& cls, const std::array<int, 3>& dims,
                                   std::vector<int>& label) {
  const std::size_t nx = dims[0], ny = dims[1], nz = dims[2];
  label.assign(cls.size(), -1);
  std::vector<long> sizes;
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < cls.size(); ++seed) {
    if (label[seed] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    const std::uint8_t c = cls[seed];
    long size = 0;
    label[seed] = id;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::size_t x = stack.back();
      stack.pop_back();
      ++size;
      const std::size_t i = x % nx, j = (x / nx) % ny, k = x / (nx * ny);
      auto visit = [&](std::size_t y) {
        if (label[y] < 0 && cls[y] == c) {
          label[y] = id;
          stack.push_back(y);
        }
      };
      if (i > 0) visit(x - 1);
      if (i + 1 < nx) visit(x + 1);
      if (j > 0) visit(x - nx);
      if (j + 1 < ny) visit(x + nx);
      if (k > 0) visit(x - nx * ny);
      if (k + 1 < nz) visit(x + nx * ny);
    }
    sizes.push_back(size);
  }
  return sizes;
}

// Dilation of a 0/1 mask on an N^3 grid by a cube of half-width r (Chebyshev distance <= r),
// separably: along each axis a voxel is set if any voxel within r along that axis is set.
Mask dilate_cube(const Mask& in, int n, int r) {
  Mask cur = in, next(in.size());
  std::vector<int> prefix(static_cast<std::size_t>(n) + 1);
  const std::size_t stride[3] = {1, static_cast<std::size_t>(n),
                                 static_cast<std::size_t>(n) * static_cast<std::size_t>(n)};
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t s = stride[axis];
    const std::size_t o1 = stride[(axis + 1) % 3], o2 = stride[(axis + 2) % 3];
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) {
        const std::size_t base = a * o1 + b * o2;
        prefix[0] = 0;
        for (int t = 0; t < n; ++t) prefix[t + 1] = prefix[t] + cur[base + t * s];
        for (int t = 0; t < n; ++t) {
          const int lo = std::max(0, t - r), hi = std::min(n, t + r + 1);
          next[base + t * s] = prefix[hi] - prefix[lo] > 0 ? 1 : 0;
        }
      }
    }
    std::swap(cur, next);
  }
  return cur;
}

double parse_number(const std::string& s, const std::string& flag, const std::string& item) {
  std::size_t used = 0;
  double x = 0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size() || !std::isfinite(x)) {
    throw InputError(flag + ": '" + item + "': '" + s + "' is not a number; expected NAME=LO:HI");
  }
  return x;
}

}  // namespace

MaterialThresholds parse_material_thresholds(const std::string& text, const std::string& flag) {
  MaterialThresholds t;
  t.automatic = false;
  bool have_enamel = false, have_dentin = false;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    const auto colon = item.find(':', eq == std::string::npos ? 0 : eq);
    if (eq == std::string::npos || colon == std::string::npos) {
      throw InputError(flag + ": '" + item + "': expected NAME=LO:HI (NAME enamel or dentin)");
    }
    const std::string name = item.substr(0, eq);
    const double lo = parse_number(item.substr(eq + 1, colon - eq - 1), flag, item);
    const double hi = parse_number(item.substr(colon + 1), flag, item);
    if (!(lo <= hi)) throw InputError(flag + ": '" + item + "': expected LO <= HI");
    if (name == "enamel" && !have_enamel) {
      t.enamel_lo = lo;
      t.enamel_hi = hi;
      have_enamel = true;
    } else if (name == "dentin" && !have_dentin) {
      t.dentin_lo = lo;
      t.dentin_hi = hi;
      have_dentin = true;
    } else {
      throw InputError(flag + ": '" + item + "': expected enamel or dentin, each once");
    }
  }
  if (!have_enamel || !have_dentin) {
    throw InputError(flag + ": '" + text + "': expected both enamel=LO:HI and dentin=LO:HI");
  }
  if (t.enamel_lo <= t.dentin_hi && t.dentin_lo <= t.enamel_hi) {
    throw InputError(flag + ": '" + text + "': the enamel and dentin ranges overlap");
  }
  return t;
}

MaterialThresholds otsu_three_class(const std::vector<float>& values, int bins) {
  if (values.empty()) throw InputError("volume has no samples");
  const auto [mn_it, mx_it] = std::minmax_element(values.begin(), values.end());
  const double mn = *mn_it, mx = *mx_it;
  if (!(mx > mn)) throw InputError("volume is uniform (every sample " + std::to_string(mn) + ")");
  const double width = (mx - mn) / bins;
  std::vector<double> count(bins, 0.0);
  for (float v : values) {
    const int b = std::min(bins - 1, static_cast<int>((v - mn) / width));
    count[b] += 1.0;
  }
  // Prefix sums of weight and first moment (bin centres), P[k] / S[k] over bins < k.
  std::vector<double> p(bins + 1, 0.0), s(bins + 1, 0.0);
  for (int b = 0; b < bins; ++b) {
    p[b + 1] = p[b] + count[b];
    s[b + 1] = s[b] + count[b] * (mn + (b + 0.5) * width);
  }
  auto term = [&](int a, int b) {  // w mu^2 of bins [a, b), up to the constant 1/N
    const double w = p[b] - p[a];
    return w > 0 ? (s[b] - s[a]) * (s[b] - s[a]) / w : -1.0;
  };
  double best = -1;
  int best1 = 1, best2 = 2;
  for (int t1 = 1; t1 < bins - 1; ++t1) {
    const double c0 = term(0, t1);
    if (c0 < 0) continue;
    for (int t2 = t1 + 1; t2 < bins; ++t2) {
      const double c1 = term(t1, t2), c2 = term(t2, bins);
      if (c1 < 0 || c2 < 0) continue;
      const double v = c0 + c1 + c2;
      if (v > best) {
        best = v;
        best1 = t1;
        best2 = t2;
      }
    }
  }
  if (best < 0) throw InputError("volume has fewer than three distinct intensity levels");
  MaterialThresholds t;
  t.automatic = true;
  t.dentin_lo = mn + best1 * width;
  t.enamel_lo = mn + best2 * width;
  // Half-open ranges [lo, next lo) as closed ones: the largest float below the next edge.
  t.dentin_hi = std::nextafter(t.enamel_lo, -std::numeric_limits<double>::infinity());
  t.enamel_hi = mx;
  return t;
}

std::uint8_t classify_intensity(const MaterialThresholds& t, double value) {
  if (value >= t.enamel_lo && value <= t.enamel_hi) return kEnamel;
  if (value >= t.dentin_lo && value <= t.dentin_hi) return kDentin;
  return kEmpty;
}

double sample_trilinear(const ScanVolume& v, const Vec3& p, double outside) {
  const Vec3 ijk = (v.direction.transpose() * (p - v.origin)).cwiseQuotient(v.spacing);
  int i0[3];
  double f[3];
  for (int d = 0; d < 3; ++d) {
    if (!(ijk[d] >= 0.0 && ijk[d] <= v.dims[d] - 1)) return outside;
    i0[d] = std::min(static_cast<int>(ijk[d]), v.dims[d] - 2);
    f[d] = ijk[d] - i0[d];
  }
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int a = c & 1, b = (c >> 1) & 1, e = (c >> 2) & 1;
    const double w = (a ? f[0] : 1 - f[0]) * (b ? f[1] : 1 - f[1]) * (e ? f[2] : 1 - f[2]);
    if (w != 0.0) acc += w * v.values[v.index(i0[0] + a, i0[1] + b, i0[2] + e)];
  }
  return acc;
}

Vec3 solid_centroid(const VoxelGrid& grid) {
  Vec3 sum = Vec3::Zero();
  long n = 0;
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        sum += grid.center(i, j, k);
        ++n;
      }
    }
  }
  return n > 0 ? Vec3(sum / double(n)) : Vec3::Zero();
}

Vec3 enamel_axis(const VoxelGrid& grid) {
  VoxelGrid enamel = grid;
  for (std::uint8_t& m : enamel.voxels) m = m == kEnamel ? 1 : 0;
  if (std::find(enamel.voxels.begin(), enamel.voxels.end(), 1) == enamel.voxels.end()) {
    return Vec3::UnitZ();
  }
  const Vec3 d = solid_centroid(enamel) - solid_centroid(grid);
  if (d.norm() < grid.voxel_size) return Vec3::UnitZ();
  Eigen::Index a = 0;
  d.cwiseAbs().maxCoeff(&a);
  Vec3 axis = Vec3::Zero();
  axis[a] = d[a] > 0 ? 1.0 : -1.0;
  return axis;
}

long remove_islands(VoxelGrid& grid, int min_voxels, long* voxels) {
  const int n = grid.n;
  std::vector<int> label;
  const std::vector<long> sizes = label_components(grid.voxels, {n, n, n}, label);
  std::vector<int> small_id(sizes.size(), -1);
  int n_small = 0;
  for (std::size_t c = 0; c < sizes.size(); ++c) {
    if (sizes[c] < min_voxels) small_id[c] = n_small++;
  }
  if (n_small == 0) return 0;
  std::vector<std::array<long, kMaterialCount>> votes(n_small);
  for (auto& v : votes) v.fill(0);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::size_t x = grid.index(i, j, k);
        const int s = small_id[label[x]];
        if (s < 0) continue;
        const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                              {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& q : nb) {
          if (!grid.inside(q[0], q[1], q[2])) continue;
          const std::size_t y = grid.index(q[0], q[1], q[2]);
          if (label[y] != label[x]) ++votes[s][grid.voxels[y]];
        }
      }
    }
  }
  long changed = 0;
  for (std::size_t x = 0; x < grid.voxels.size(); ++x) {
    const int s = small_id[label[x]];
    if (s < 0) continue;
    const auto& v = votes[s];
    const auto best = std::max_element(v.begin(), v.end()) - v.begin();
    if (v[best] == 0) continue;  // the whole grid is one small component
    grid.voxels[x] = static_cast<std::uint8_t>(best);
    ++changed;
  }
  if (voxels != nullptr) *voxels += changed;
  return n_small;
}

std::uint8_t VolumeSolidRule::classify(double value, bool at_edge) const {
  const std::uint8_t c = classify_intensity(thresholds, value);
  if (at_edge && c == kDentin) return value >= cut ? kEnamel : kEmpty;
  return c;
}

VoxelGrid build_volume_tooth(const ScanVolume& volume, const VolumeToothOptions& options,
                             VolumeToothReport* report, VolumeSolidRule* rule) {
  // A degenerate volume (trilinear interpolation needs two samples per axis).
  std::size_t samples = 1;
  for (int d = 0; d < 3; ++d) {
    if (volume.dims[d] < 2) {
      throw InputError(volume.source + ": size " + std::to_string(volume.dims[d]) + " along axis " +
                       std::to_string(d) + "; expected at least 2 samples per axis");
    }
    if (!(volume.spacing[d] > 0.0) || !std::isfinite(volume.spacing[d])) {
      throw InputError(volume.source + ": spacing " + std::to_string(volume.spacing[d]) +
                       " along axis " + std::to_string(d) + "; expected a positive finite length");
    }
    samples *= static_cast<std::size_t>(volume.dims[d]);
  }
  if (volume.values.size() != samples) {
    throw InputError(volume.source + ": " + std::to_string(volume.values.size()) +
                     " samples for a " + std::to_string(volume.dims[0]) + " x " +
                     std::to_string(volume.dims[1]) + " x " + std::to_string(volume.dims[2]) +
                     " lattice");
  }
  VolumeToothReport rep;
  // 1. Thresholds and the class means of the raw samples.
  try {
    rep.thresholds = options.automatic_thresholds ? otsu_three_class(volume.values)
                                                  : options.thresholds;
  } catch (const InputError& e) {
    throw InputError(volume.source + ": " + e.what());
  }
  const MaterialThresholds& th = rep.thresholds;
  Mask sample_class(volume.values.size());
  std::array<double, 3> sum = {0, 0, 0};
  std::array<long, 3> cnt = {0, 0, 0};
  auto slot = [](std::uint8_t c) { return c == kEmpty ? 0 : (c == kDentin ? 1 : 2); };
  for (std::size_t x = 0; x < volume.values.size(); ++x) {
    sample_class[x] = classify_intensity(th, volume.values[x]);
    sum[slot(sample_class[x])] += volume.values[x];
    ++cnt[slot(sample_class[x])];
  }
  for (int c = 0; c < 3; ++c) rep.class_means[c] = cnt[c] > 0 ? sum[c] / cnt[c] : 0.0;
  if (cnt[1] + cnt[2] == 0) {
    throw InputError(volume.source + ": no sample lies in the enamel or dentin range; expected a "
                     "tooth (check --material-thresholds)");
  }
  const double background = rep.class_means[0];

  // 2. The grid around the largest solid component of the samples (speckle does not widen it).
  Mask solid_samples(sample_class.size());
  for (std::size_t x = 0; x < sample_class.size(); ++x) solid_samples[x] = sample_class[x] != kEmpty;
  std::vector<int> label;
  const std::vector<long> sizes = label_components(solid_samples, volume.dims, label);
  int biggest = -1;
  for (std::size_t x = 0; x < label.size(); ++x) {
    if (solid_samples[x] != 0 && (biggest < 0 || sizes[label[x]] > sizes[biggest])) biggest = label[x];
  }
  Aabb bounds;
  bounds.min = Vec3::Constant(std::numeric_limits<double>::infinity());
  bounds.max = -bounds.min;
  const Vec3 half = 0.5 * (volume.direction.cwiseAbs() * volume.spacing);  // half a sample's box
  for (int k = 0; k < volume.dims[2]; ++k) {
    for (int j = 0; j < volume.dims[1]; ++j) {
      for (int i = 0; i < volume.dims[0]; ++i) {
        if (label[volume.index(i, j, k)] != biggest) continue;
        const Vec3 p = volume.position(Vec3(i, j, k));
        bounds.min = bounds.min.cwiseMin(p - half);
        bounds.max = bounds.max.cwiseMax(p + half);
      }
    }
  }
  label.clear();
  label.shrink_to_fit();
  VoxelGrid grid = make_grid(bounds, options.resolution, options.margin_voxels);
  const int n = grid.n;

  // 3. Resample (trilinear) and classify.
  std::vector<float> value(grid.voxels.size());
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::size_t x = grid.index(i, j, k);
        value[x] = static_cast<float>(sample_trilinear(volume, grid.center(i, j, k), background));
        grid.voxels[x] = classify_intensity(th, value[x]);
      }
    }
  }

  // 4. Partial-volume correction at enamel/background edges.
  const int r = std::max(1, static_cast<int>(std::ceil(volume.spacing.maxCoeff() / grid.voxel_size)));
  rep.interpolation_radius_voxels = r;
  Mask is_enamel(grid.voxels.size()), is_empty(grid.voxels.size());
  for (std::size_t x = 0; x < grid.voxels.size(); ++x) {
    is_enamel[x] = grid.voxels[x] == kEnamel;
    is_empty[x] = grid.voxels[x] == kEmpty;
  }
  VolumeSolidRule solid_rule;
  solid_rule.thresholds = th;
  solid_rule.background = background;
  solid_rule.cut = 0.5 * (rep.class_means[2] + rep.class_means[0]);
  solid_rule.edge = dilate_cube(is_enamel, n, r);  // near enamel, then also near background:
  const Mask near_empty = dilate_cube(is_empty, n, r);
  for (std::size_t x = 0; x < grid.voxels.size(); ++x) {
    solid_rule.edge[x] =
        options.partial_volume_rule && solid_rule.edge[x] != 0 && near_empty[x] != 0 ? 1 : 0;
    if (solid_rule.edge[x] && grid.voxels[x] == kDentin) {
      grid.voxels[x] = solid_rule.classify(value[x], true);
      ++rep.partial_volume_voxels;
    }
  }

  // 5. Islands.
  rep.island_components = remove_islands(grid, options.min_island_voxels, &rep.island_voxels);

  // 6. Pulp: background not reached from the grid boundary.
  Mask barrier(grid.voxels.size());
  for (std::size_t x = 0; x < barrier.size(); ++x) barrier[x] = grid.voxels[x] != kEmpty;
  const Mask outside = seed_fill_outside(barrier, n);
  for (std::size_t x = 0; x < barrier.size(); ++x) {
    if (barrier[x] == 0 && outside[x] == 0) {
      grid.voxels[x] = kPulp;
      ++rep.pulp_voxels;
    }
  }
  if (report != nullptr) *report = rep;
  if (rule != nullptr) *rule = std::move(solid_rule);
  return grid;
}

}  // namespace dentsim
