// Teeth from scan volumes: micro-CT / CBCT intensities -> voxel tooth with enamel, dentin and pulp
// (issue #21; thesis §2.5.2 builds the voxel tooth with a 3D seed fill, reused here for the pulp).
//
// Frames and units: a ScanVolume is an image of intensities on a lattice of sample points
// p(i, j, k) = origin + D diag(spacing) (i, j, k)^T [m] in the scanner frame, D a rotation (the
// columns are the directions of the i, j, k axes; DICOM ImageOrientationPatient, the NIfTI
// qform/sform, NRRD "space directions"). The voxel tooth's frame {O} is the scanner frame.
//
// Pipeline (build_volume_tooth; each stage a function the tests check alone):
//  1. Thresholds: three-class Otsu (Otsu, IEEE SMC 9(1), 1979; the multi-level form of Liao, Chen
//     & Chung, J. Inf. Sci. Eng. 17, 2001): over a 256-bin histogram of all samples, the pair
//     t1 < t2 maximising the between-class variance sum_c w_c mu_c^2 of background (< t1),
//     dentin [t1, t2) and enamel (>= t2); or the user's ranges (`enamel=LO:HI,dentin=LO:HI`).
//  2. Grid: N^3 cubic voxels, axis-aligned in the scanner frame, around the bounding box of the
//     largest 6-connected component of samples classed solid (so speckle does not widen it; two
//     empty voxels per side, make_grid of voxelize.h).
//  3. Resampling: each cubic voxel centre takes the trilinearly interpolated intensity of the 8
//     surrounding samples (outside the sampled lattice: the background class mean), then its class.
//     Trilinear interpolation is exact on linear ramps, so a partial-volume edge (a ramp between
//     two class means) is cut where the ramp crosses the threshold.
//  4. Partial-volume correction: on an enamel/background edge the ramp passes through the dentin
//     range, which would leave a thin false dentin skin on the enamel. A dentin voxel that has both
//     an enamel and a background voxel within r voxels (r = the largest scan spacing over h, at
//     least 1; the width of one sample's footprint) is an edge voxel between enamel and background:
//     it becomes enamel if its intensity is >= (mu_enamel + mu_background) / 2, else background.
//  5. Islands: every 6-connected component of one class (background, dentin, enamel) with fewer
//     than `min_island_voxels` voxels takes the class most frequent among its 6-neighbours
//     outside it (speckle from noise, air bubbles); one pass, components found on the step-4
//     labels.
//  6. Pulp: background voxels that the seed fill of the outside (seed_fill_outside of voxelize.h,
//     6-connected from the grid boundary, solid = barrier) does not reach: low intensity enclosed
//     by dentin. A canal open to the outside at the apex (wider than a voxel) is reached by the
//     fill and stays empty; the report says how many pulp voxels were found.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

struct ScanVolume {
  std::array<int, 3> dims = {0, 0, 0};  // samples along i, j, k
  Vec3 spacing = Vec3::Zero();          // sample distance along i, j, k [m]
  Mat3 direction = Mat3::Identity();    // columns: unit i, j, k axes in the scanner frame
  Vec3 origin = Vec3::Zero();           // position of sample (0, 0, 0) [m]
  std::vector<float> values;            // intensity (rescaled: DICOM HU, NIfTI scl_*), i fastest
  std::string format;                   // "DICOM", "NIfTI-1", "NIfTI-2", "NRRD"
  std::string source;                   // the path it came from (messages)

  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * k);
  }
  // Position of sample (i, j, k) [m] (fractional indices allowed).
  Vec3 position(const Vec3& ijk) const {
    return origin + direction * spacing.cwiseProduct(ijk);
  }
};

// True for a path that names a volume: a directory (DICOM series) or .nii, .nii.gz, .nrrd, .nhdr
// (case-insensitive).
bool is_volume_path(const std::string& path);

// Reads a volume; the format from the path as above. Throws InputError naming the file (and the
// slice or header field) and what was expected: an unreadable or malformed file, not three
// dimensions, a non-positive or non-finite spacing, a non-orthogonal direction matrix, a DICOM
// folder with no images, mixed series, unequal slice sizes or uneven slice spacing.
// Lengths without a unit in the file (NRRD without "space units", NIfTI with xyz_units unknown)
// are taken as millimetres (DICOM's unit); `unit_note` (if given) says so.
ScanVolume load_volume(const std::string& path, std::string* unit_note = nullptr);
ScanVolume load_nifti(const std::string& path, std::string* unit_note = nullptr);
ScanVolume load_nrrd(const std::string& path, std::string* unit_note = nullptr);
ScanVolume load_dicom_series(const std::string& folder);

// Intensity ranges [lo, hi] (inclusive) of enamel and dentin; everything else is background.
struct MaterialThresholds {
  double enamel_lo = 0, enamel_hi = 0;
  double dentin_lo = 0, dentin_hi = 0;
  bool automatic = true;  // from otsu_three_class (else given by the user)
};

// Parses "enamel=LO:HI,dentin=LO:HI" (both, any order); throws InputError naming `flag`.
// The ranges must be non-empty (LO <= HI) and must not overlap.
MaterialThresholds parse_material_thresholds(const std::string& text, const std::string& flag);

// Three-class Otsu on `values` over `bins` equal bins from min to max: thresholds t1 < t2 at bin
// edges, background < t1 <= dentin < t2 <= enamel. Throws InputError if all values are equal.
MaterialThresholds otsu_three_class(const std::vector<float>& values, int bins = 256);

// Class of one intensity: kEmpty, kDentin or kEnamel.
std::uint8_t classify_intensity(const MaterialThresholds& t, double value);

// Trilinear interpolation of the volume at world point p; `outside` beyond the sampled lattice.
double sample_trilinear(const ScanVolume& v, const Vec3& p, double outside);

struct VolumeToothOptions {
  int resolution = 256;
  int margin_voxels = 2;
  bool automatic_thresholds = true;
  MaterialThresholds thresholds;  // used when !automatic_thresholds
  int min_island_voxels = 64;     // step 5
  bool partial_volume_rule = true;  // step 4 (off only to measure what it does)
};

struct VolumeToothReport {
  MaterialThresholds thresholds;
  std::array<double, 3> class_means = {0, 0, 0};  // background, dentin, enamel (raw samples)
  long partial_volume_voxels = 0;                 // step 4: dentin edge voxels reassigned
  long island_components = 0;                     // step 5: components relabelled
  long island_voxels = 0;
  long pulp_voxels = 0;
  double interpolation_radius_voxels = 0;  // step 4's r
};

// Steps 3-4 as a rule on an intensity, so that the solid can be asked between the voxel centres
// too (the scan's field: tooth_io/tooth_field.h). At a voxel centre, with that voxel's `edge`
// flag and the float intensity step 3 stores, classify() is the class steps 3-4 give the voxel.
struct VolumeSolidRule {
  MaterialThresholds thresholds;
  double background = 0.0;  // sample_trilinear's value outside the sampled lattice (step 3)
  double cut = 0.0;         // step 4's level, (mean enamel + mean background) / 2
  std::vector<std::uint8_t> edge;  // per grid voxel (N^3): 1 where step 4 applies
  // The class of intensity `value` where step 4 applies (`at_edge`: dentin is cut at `cut` into
  // enamel or background) or not (classify_intensity).
  std::uint8_t classify(double value, bool at_edge) const;
};

// Steps 1-6; `rule` (if given) receives steps 3-4's rule. Throws InputError naming the volume's
// source when it is degenerate (a size below 2 samples, samples missing, a spacing that is not
// positive and finite) or when nothing is classed solid.
VoxelGrid build_volume_tooth(const ScanVolume& volume, const VolumeToothOptions& options,
                             VolumeToothReport* report = nullptr, VolumeSolidRule* rule = nullptr);

// Mean centre of the solid voxels [m] (zero for an empty grid).
Vec3 solid_centroid(const VoxelGrid& grid);

// The crown's direction for pictures: from the solid's centroid towards the enamel's, snapped to
// the nearest grid axis (+z when the enamel is centred, e.g. a layered sphere).
Vec3 enamel_axis(const VoxelGrid& grid);

// Step 5 alone on a grid of classes (kEmpty, kDentin, kEnamel); returns components relabelled and
// adds their voxels to *voxels.
long remove_islands(VoxelGrid& grid, int min_voxels, long* voxels);

}  // namespace dentsim
