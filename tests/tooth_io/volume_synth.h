// Synthetic scan volumes for the volume tests (issue #21): a layered sphere (enamel shell, dentin,
// pulp) sampled like a CT: each sample is the mean intensity over its own box (partial volume,
// 4^3 sub-samples where the box meets a layer boundary), plus Gaussian noise; written as NIfTI,
// NRRD and a DICOM series by tooth_io/volume_write.h (the same libraries the readers use).
//
// Units: lengths in metres in the structs; the files store millimetres (DICOM's unit, and the
// unit the NIfTI/NRRD headers name).
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "tooth_io/volume.h"
#include "tooth_io/volume_write.h"

namespace dentsim::testing {

struct LayeredSphere {
  Vec3 center = Vec3(1.0e-3, -2.0e-3, 3.0e-3);
  double r_outer = 5.0e-3;   // enamel outside
  double r_dentin = 3.8e-3;  // enamel-dentin junction
  double r_pulp = 2.0e-3;    // pulp chamber
  // Intensities (HU-like): air, pulp (soft tissue), dentin, enamel; noise standard deviation.
  double background = 0, pulp = 100, dentin = 1200, enamel = 2200, noise = 60;

  double ball(double r) const { return 4.0 / 3.0 * std::numbers::pi * r * r * r; }
  double enamel_volume() const { return ball(r_outer) - ball(r_dentin); }
  double dentin_volume() const { return ball(r_dentin) - ball(r_pulp); }
  double pulp_volume() const { return ball(r_pulp); }
  double intensity(const Vec3& p) const {
    const double r = (p - center).norm();
    return r < r_pulp ? pulp : r < r_dentin ? dentin : r < r_outer ? enamel : background;
  }
};

// A sampled lattice around the sphere (6.5 mm half-width), spacing `spacing` [m], axes `rot`.
inline ScanVolume render_sphere(const LayeredSphere& s, const Vec3& spacing, const Mat3& rot,
                                unsigned seed = 2024) {
  ScanVolume v;
  v.spacing = spacing;
  v.direction = rot;
  for (int d = 0; d < 3; ++d) v.dims[d] = static_cast<int>(std::ceil(13.0e-3 / spacing[d])) + 1;
  const Vec3 half_extent = spacing.cwiseProduct(Vec3(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1)) / 2;
  v.origin = s.center - rot * half_extent;
  v.values.resize(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2]);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, s.noise);
  const double half_diag = 0.5 * spacing.norm();
  for (int k = 0; k < v.dims[2]; ++k) {
    for (int j = 0; j < v.dims[1]; ++j) {
      for (int i = 0; i < v.dims[0]; ++i) {
        const Vec3 c = v.position(Vec3(i, j, k));
        const double r = (c - s.center).norm();
        double value = 0;
        const bool edge = std::abs(r - s.r_outer) < half_diag || std::abs(r - s.r_dentin) < half_diag ||
                          std::abs(r - s.r_pulp) < half_diag;
        if (!edge) {
          value = s.intensity(c);
        } else {
          constexpr int m = 4;
          for (int a = 0; a < m; ++a) {
            for (int b = 0; b < m; ++b) {
              for (int e = 0; e < m; ++e) {
                const Vec3 f((a + 0.5) / m - 0.5, (b + 0.5) / m - 0.5, (e + 0.5) / m - 0.5);
                value += s.intensity(v.position(Vec3(i, j, k) + f));
              }
            }
          }
          value /= m * m * m;
        }
        v.values[v.index(i, j, k)] = static_cast<float>(std::round(value + noise(rng)));
      }
    }
  }
  return v;
}

inline Mat3 rotation(double angle_rad, const Vec3& axis) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

}  // namespace dentsim::testing
