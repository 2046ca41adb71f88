#include "tooth_io/volume_write.h"

#include <gdcmAttribute.h>
#include <gdcmImageWriter.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>
#include <nifti2_io.h>
#include <teem/nrrd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <vector>

namespace dentsim {

ScanVolume render_scan(const VoxelGrid& grid, const Vec3& spacing, double noise, unsigned seed,
                       double margin_m, const ScanIntensities& intensities) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        lo = lo.cwiseMin(grid.origin + grid.voxel_size * Vec3(i, j, k));
        hi = hi.cwiseMax(grid.origin + grid.voxel_size * Vec3(i + 1, j + 1, k + 1));
      }
    }
  }
  if (!(hi.x() >= lo.x())) throw std::runtime_error("render_scan: the grid has no solid voxel");
  lo -= Vec3::Constant(margin_m);
  hi += Vec3::Constant(margin_m);
  ScanVolume v;
  v.spacing = spacing;
  v.format = "synthetic";
  for (int d = 0; d < 3; ++d) v.dims[d] = static_cast<int>(std::ceil((hi[d] - lo[d]) / spacing[d])) + 1;
  v.origin = lo;
  v.values.resize(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2]);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise > 0 ? noise : 1.0);
  constexpr int m = 4;
  for (int k = 0; k < v.dims[2]; ++k) {
    for (int j = 0; j < v.dims[1]; ++j) {
      for (int i = 0; i < v.dims[0]; ++i) {
        double sum = 0;
        for (int c = 0; c < m * m * m; ++c) {
          const Vec3 f((c % m + 0.5) / m - 0.5, ((c / m) % m + 0.5) / m - 0.5, (c / (m * m) + 0.5) / m - 0.5);
          const Vec3 g = (v.position(Vec3(i, j, k) + f) - grid.origin) / grid.voxel_size;
          sum += intensities.of(grid.at(static_cast<int>(std::floor(g.x())),
                                        static_cast<int>(std::floor(g.y())),
                                        static_cast<int>(std::floor(g.z()))));
        }
        const double value = sum / (m * m * m) + (noise > 0 ? gauss(rng) : 0.0);
        v.values[v.index(i, j, k)] = static_cast<float>(std::round(value));
      }
    }
  }
  return v;
}

// NIfTI-1 (float32, sform in mm); .nii.gz is gzip-compressed by nifticlib.
void write_nifti(const ScanVolume& v, const std::string& path) {
  const int64_t dims[8] = {3, v.dims[0], v.dims[1], v.dims[2], 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, DT_FLOAT32, 1);
  std::memcpy(nim->data, v.values.data(), v.values.size() * sizeof(float));
  nim->dx = nim->pixdim[1] = v.spacing[0] * 1e3;
  nim->dy = nim->pixdim[2] = v.spacing[1] * 1e3;
  nim->dz = nim->pixdim[3] = v.spacing[2] * 1e3;
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->qform_code = 0;
  nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) nim->sto_xyz.m[r][c] = r == 3 ? (c == 3 ? 1.0 : 0.0) : 0.0;
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) nim->sto_xyz.m[r][c] = v.direction(r, c) * v.spacing[c] * 1e3;
    nim->sto_xyz.m[r][3] = v.origin[r] * 1e3;
  }
  nim->sto_ijk = nifti_dmat44_inverse(nim->sto_xyz);
  if (nifti_set_filenames(nim, path.c_str(), 0, 1) != 0) throw std::runtime_error("nifti names");
  nifti_image_write(nim);
  nifti_image_free(nim);
}

// NRRD (int16 samples), space directions and origin in mm;
// `.nhdr` writes a detached header beside a raw data file.
void write_nrrd(const ScanVolume& v, const std::string& path) {
  std::vector<std::int16_t> data(v.values.size());
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::int16_t>(v.values[i]);
  Nrrd* n = nrrdNew();
  if (nrrdWrap_va(n, data.data(), nrrdTypeShort, 3, static_cast<size_t>(v.dims[0]),
                  static_cast<size_t>(v.dims[1]), static_cast<size_t>(v.dims[2])) != 0) {
    throw std::runtime_error("nrrdWrap");
  }
  nrrdSpaceDimensionSet(n, 3);
  double o[3], d[3][3];
  for (int r = 0; r < 3; ++r) {
    o[r] = v.origin[r] * 1e3;
    for (int c = 0; c < 3; ++c) d[c][r] = v.direction(r, c) * v.spacing[c] * 1e3;
    n->spaceUnits[r] = airStrdup("mm");
  }
  nrrdSpaceOriginSet(n, o);
  nrrdAxisInfoSet_va(n, nrrdAxisInfoSpaceDirection, d[0], d[1], d[2]);
  if (nrrdSave(path.c_str(), n, nullptr) != 0) throw std::runtime_error("nrrdSave " + path);
  nrrdNix(n);  // the data belongs to `data`
}

// A DICOM CT series: one file per k-slice, int16 stored as HU + 1024 with RescaleIntercept -1024.
void write_dicom_series(const ScanVolume& v, const std::string& folder) {
  std::filesystem::create_directories(folder);
  gdcm::Trace::WarningOff();  // the writer warns about attributes it fills in itself
  gdcm::UIDGenerator uid;
  const std::string study = uid.Generate(), series = uid.Generate();
  const Vec3 row = v.direction.col(0), col = v.direction.col(1);
  for (int k = 0; k < v.dims[2]; ++k) {
    gdcm::ImageWriter w;
    gdcm::Image& im = w.GetImage();
    im.SetNumberOfDimensions(2);
    im.SetDimension(0, v.dims[0]);
    im.SetDimension(1, v.dims[1]);
    im.SetSpacing(0, v.spacing[0] * 1e3);
    im.SetSpacing(1, v.spacing[1] * 1e3);
    im.SetSpacing(2, v.spacing[2] * 1e3);
    const Vec3 ipp = 1e3 * v.position(Vec3(0, 0, k));
    for (int r = 0; r < 3; ++r) im.SetOrigin(r, ipp[r]);
    const double dc[6] = {row[0], row[1], row[2], col[0], col[1], col[2]};
    im.SetDirectionCosines(dc);
    im.SetPixelFormat(gdcm::PixelFormat::INT16);
    im.SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    im.SetIntercept(-1024);
    im.SetSlope(1);
    std::vector<std::int16_t> px(static_cast<std::size_t>(v.dims[0]) * v.dims[1]);
    for (int j = 0; j < v.dims[1]; ++j) {
      for (int i = 0; i < v.dims[0]; ++i) {
        px[i + static_cast<std::size_t>(v.dims[0]) * j] =
            static_cast<std::int16_t>(v.values[v.index(i, j, k)] + 1024);
      }
    }
    gdcm::DataElement pixel(gdcm::Tag(0x7fe0, 0x0010));
    pixel.SetByteValue(reinterpret_cast<const char*>(px.data()),
                       static_cast<std::uint32_t>(px.size() * sizeof(std::int16_t)));
    im.SetDataElement(pixel);
    gdcm::DataSet& ds = w.GetFile().GetDataSet();
    gdcm::Attribute<0x0008, 0x0016> sop_class;
    sop_class.SetValue("1.2.840.10008.5.1.4.1.1.2");  // CT Image Storage
    ds.Replace(sop_class.GetAsDataElement());
    gdcm::Attribute<0x0020, 0x000d> study_uid;
    study_uid.SetValue(study);
    ds.Replace(study_uid.GetAsDataElement());
    gdcm::Attribute<0x0020, 0x000e> series_uid;
    series_uid.SetValue(series);
    ds.Replace(series_uid.GetAsDataElement());
    char name[32];
    std::snprintf(name, sizeof name, "slice%04d.dcm", k);
    w.SetFileName((std::filesystem::path(folder) / name).string().c_str());
    if (!w.Write()) throw std::runtime_error("gdcm write " + folder);
  }
}

void write_volume(const ScanVolume& v, const std::string& path) {
  std::string p = path;
  std::transform(p.begin(), p.end(), p.begin(), [](unsigned char c) { return std::tolower(c); });
  auto ends = [&p](const std::string& s) {
    return p.size() >= s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0;
  };
  if (ends(".nii") || ends(".nii.gz")) return write_nifti(v, path);
  if (ends(".nrrd") || ends(".nhdr")) return write_nrrd(v, path);
  write_dicom_series(v, path);
}

}  // namespace dentsim
