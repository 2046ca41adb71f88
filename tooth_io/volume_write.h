// Writing scan volumes (NIfTI-1, NRRD, DICOM CT series) and rendering a voxel tooth as a synthetic
// scan, so that the volume path (volume.h) can be exercised and demonstrated without patient data
// (issue #21: "test data made by the tests"; `dentsim voxelize ... --write-volume FILE`).
//
// Units: ScanVolume lengths in metres; the files store millimetres (DICOM's unit; the NIfTI
// header says NIFTI_UNITS_MM, the NRRD header "space units" mm).
#pragma once

#include <string>

#include "tooth_io/volume.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

// Intensities of the synthetic scan (HU-like: air, pulp soft tissue, dentin, enamel), by Material.
struct ScanIntensities {
  double empty = 0, enamel = 2200, dentin = 1200, pulp = 100;
  double of(std::uint8_t m) const {
    return m == kEnamel ? enamel : m == kDentin ? dentin : m == kPulp ? pulp : empty;
  }
};

// A CT-like scan of `grid`: an axis-aligned lattice of spacing `spacing` [m] over the grid's solid
// plus `margin_m` on every side; each sample is the mean intensity of the grid over the sample's
// own box (partial volume; 4^3 sub-samples, each the material of the grid voxel it falls in),
// rounded to an integer after adding Gaussian noise of standard deviation `noise` (std::mt19937
// seeded with `seed`, so the scan is reproducible).
ScanVolume render_scan(const VoxelGrid& grid, const Vec3& spacing, double noise, unsigned seed,
                       double margin_m = 1e-3, const ScanIntensities& intensities = {});

// Writes `v`: .nii / .nii.gz (NIfTI-1, float32, sform), .nrrd / .nhdr (int16, space directions),
// anything else a folder of DICOM CT slices (int16 = value + 1024, RescaleIntercept -1024).
// Integer-valued samples in [-1024, 31743] round-trip exactly through every format. Throws
// std::runtime_error naming the path if a library refuses.
void write_volume(const ScanVolume& v, const std::string& path);
void write_nifti(const ScanVolume& v, const std::string& path);
void write_nrrd(const ScanVolume& v, const std::string& path);
void write_dicom_series(const ScanVolume& v, const std::string& folder);

}  // namespace dentsim
