// Scan volume readers (volume.h): DICOM series through GDCM, NIfTI-1/2 through nifticlib, NRRD
// through teem. Each turns the file's index-to-scanner map into origin, spacing [m] and a rotation
// D (volume.h) and the stored values into rescaled float intensities.
#include <gdcmDataElement.h>
#include <gdcmDirectory.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmTrace.h>
#include <nifti2_io.h>
#include <Eigen/Geometry>
#include <teem/biff.h>
#include <teem/nrrd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "reference/core/io.h"
#include "tooth_io/volume.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void require_readable_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": cannot open the file for reading");
}

// Splits the columns of an index-to-position matrix A = D diag(spacing) (lengths already in
// metres) into spacing and a rotation; `what` names the field in errors.
void set_geometry(ScanVolume& v, const Mat3& a, const Vec3& origin, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    const double s = a.col(c).norm();
    if (!std::isfinite(s) || !(s > 0)) {
      throw InputError(v.source + ": " + what + ": axis " + std::to_string(c) +
                       " has spacing " + std::to_string(s) + "; expected a finite length > 0");
    }
    v.spacing[c] = s;
    v.direction.col(c) = a.col(c) / s;
  }
  const double off = (v.direction.transpose() * v.direction - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!(off < 1e-3)) {
    throw InputError(v.source + ": " + what +
                     ": the axes are not orthogonal (max |D^T D - I| = " + std::to_string(off) +
                     "); expected a rotation (sheared volumes are not supported)");
  }
  if (!origin.allFinite()) throw InputError(v.source + ": " + what + ": non-finite origin");
  v.origin = origin;
}

void check_dims(const ScanVolume& v, const std::string& what) {
  for (int d = 0; d < 3; ++d) {
    if (v.dims[d] < 2 || v.dims[d] > 8192) {
      throw InputError(v.source + ": " + what + ": size " + std::to_string(v.dims[d]) +
                       " along axis " + std::to_string(d) + "; expected 2..8192 samples");
    }
  }
}

// Metres per unit of a unit name; 1e-3 (mm) with a note when empty or unknown.
double unit_scale(const std::string& unit, const std::string& source, std::string* note) {
  const std::string u = lower(unit);
  if (u == "m" || u == "meter" || u == "metre") return 1.0;
  if (u == "mm" || u == "millimeter" || u == "millimetre") return 1e-3;
  if (u == "um" || u == "micron" || u == "micrometer" || u == "micrometre") return 1e-6;
  if (note != nullptr) {
    *note = source + ": no length unit" + (u.empty() ? "" : " I know ('" + unit + "')") +
            "; taking millimetres";
  }
  return 1e-3;
}

// ---- NIfTI ---------------------------------------------------------------------------------------

template <typename T>
void copy_as_float(const void* data, std::size_t n, double slope, double inter,
                   std::vector<float>& out) {
  const T* p = static_cast<const T*>(data);
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(slope * double(p[i]) + inter);
}

struct NiftiFree {
  void operator()(nifti_image* p) const { nifti_image_free(p); }
};

}  // namespace

bool is_volume_path(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return true;
  const std::string p = lower(path);
  return ends_with(p, ".nii") || ends_with(p, ".nii.gz") || ends_with(p, ".nrrd") ||
         ends_with(p, ".nhdr");
}

ScanVolume load_nifti(const std::string& path, std::string* unit_note) {
  require_readable_file(path);
  nifti_set_debug_level(0);
  std::unique_ptr<nifti_image, NiftiFree> nim(nifti_image_read(path.c_str(), 1));
  if (!nim || nim->data == nullptr) {
    throw InputError(path + ": not a readable NIfTI-1/2 image (header or data unreadable or cut "
                     "short); expected a .nii or .nii.gz file");
  }
  ScanVolume v;
  v.source = path;
  v.format = nim->nifti_type == NIFTI_FTYPE_NIFTI2_1 || nim->nifti_type == NIFTI_FTYPE_NIFTI2_2
                 ? "NIfTI-2"
                 : "NIfTI-1";
  if (nim->dim[0] < 3) {
    throw InputError(path + ": header dim[0] = " + std::to_string(nim->dim[0]) +
                     "; expected a 3D volume");
  }
  for (int d = 4; d <= nim->dim[0] && d < 8; ++d) {
    if (nim->dim[d] != 1) {
      throw InputError(path + ": header dim[" + std::to_string(d) + "] = " +
                       std::to_string(nim->dim[d]) + "; expected one 3D volume (no time series)");
    }
  }
  for (int d = 0; d < 3; ++d) v.dims[d] = static_cast<int>(std::min<int64_t>(nim->dim[d + 1], 1 << 30));
  check_dims(v, "header dim");
  const std::size_t n = static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2];
  double slope = nim->scl_slope, inter = nim->scl_inter;
  if (slope == 0.0 || !std::isfinite(slope)) {
    slope = 1.0;
    inter = 0.0;
  }
  switch (nim->datatype) {
    case DT_UINT8: copy_as_float<std::uint8_t>(nim->data, n, slope, inter, v.values); break;
    case DT_INT8: copy_as_float<std::int8_t>(nim->data, n, slope, inter, v.values); break;
    case DT_INT16: copy_as_float<std::int16_t>(nim->data, n, slope, inter, v.values); break;
    case DT_UINT16: copy_as_float<std::uint16_t>(nim->data, n, slope, inter, v.values); break;
    case DT_INT32: copy_as_float<std::int32_t>(nim->data, n, slope, inter, v.values); break;
    case DT_UINT32: copy_as_float<std::uint32_t>(nim->data, n, slope, inter, v.values); break;
    case DT_FLOAT32: copy_as_float<float>(nim->data, n, slope, inter, v.values); break;
    case DT_FLOAT64: copy_as_float<double>(nim->data, n, slope, inter, v.values); break;
    default:
      throw InputError(path + ": header datatype " + std::string(nifti_datatype_string(nim->datatype)) +
                       "; expected a scalar integer or float type");
  }
  // Index -> position: the sform if set, else the qform, else the pixdims alone (NIfTI "method 1").
  Mat3 a = Mat3::Zero();
  Vec3 o = Vec3::Zero();
  std::string what;
  if (nim->sform_code > 0 || nim->qform_code > 0) {
    const nifti_dmat44& m = nim->sform_code > 0 ? nim->sto_xyz : nim->qto_xyz;
    what = nim->sform_code > 0 ? "sform" : "qform";
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a(r, c) = m.m[r][c];
      o[r] = m.m[r][3];
    }
  } else {
    what = "pixdim";
    a.diagonal() << nim->dx, nim->dy, nim->dz;
  }
  std::string unit;
  switch (nim->xyz_units) {
    case NIFTI_UNITS_METER: unit = "m"; break;
    case NIFTI_UNITS_MM: unit = "mm"; break;
    case NIFTI_UNITS_MICRON: unit = "um"; break;
    default: unit = ""; break;
  }
  const double k = unit_scale(unit, path + " (xyz_units)", unit_note);
  set_geometry(v, k * a, k * o, what);
  for (float x : v.values) {
    if (!std::isfinite(x)) throw InputError(path + ": a sample is not finite (NaN or inf)");
  }
  return v;
}

// ---- NRRD ----------------------------------------------------------------------------------------

namespace {
struct NrrdFree {
  void operator()(Nrrd* p) const { nrrdNuke(p); }
};
std::string biff_message(const char* key) {
  char* err = biffGetDone(key);
  std::string s = err != nullptr ? err : "";
  free(err);  // NOLINT: teem allocates with malloc
  // One line: teem's message is a stack of lines, the innermost last.
  for (char& c : s) {
    if (c == '\n') c = ' ';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}
}  // namespace

ScanVolume load_nrrd(const std::string& path, std::string* unit_note) {
  require_readable_file(path);
  std::unique_ptr<Nrrd, NrrdFree> nrrd(nrrdNew());
  if (nrrdLoad(nrrd.get(), path.c_str(), nullptr) != 0) {
    throw InputError(path + ": not a readable NRRD volume: " + biff_message(NRRD));
  }
  ScanVolume v;
  v.source = path;
  v.format = "NRRD";
  if (nrrd->dim != 3) {
    throw InputError(path + ": header dimension " + std::to_string(nrrd->dim) +
                     "; expected 3 (one scalar volume)");
  }
  if (nrrd->type == nrrdTypeBlock || nrrd->type <= nrrdTypeUnknown || nrrd->type > nrrdTypeDouble) {
    throw InputError(path + ": header type is not a scalar number type");
  }
  for (int d = 0; d < 3; ++d) {
    v.dims[d] = static_cast<int>(std::min<std::size_t>(nrrd->axis[d].size, 1u << 30));
  }
  check_dims(v, "header sizes");
  Mat3 a = Mat3::Zero();
  Vec3 o = Vec3::Zero();
  std::string what;
  std::string unit;
  if (nrrd->spaceDim == 3) {
    what = "space directions";
    for (int d = 0; d < 3; ++d) {
      for (int r = 0; r < 3; ++r) a(r, d) = nrrd->axis[d].spaceDirection[r];
    }
    for (int r = 0; r < 3; ++r) o[r] = std::isfinite(nrrd->spaceOrigin[r]) ? nrrd->spaceOrigin[r] : 0.0;
    unit = nrrd->spaceUnits[0] != nullptr ? nrrd->spaceUnits[0] : "";
    for (int r = 1; r < 3; ++r) {
      const std::string ur = nrrd->spaceUnits[r] != nullptr ? nrrd->spaceUnits[r] : "";
      if (ur != unit) throw InputError(path + ": space units differ between axes");
    }
  } else if (nrrd->spaceDim == 0) {
    what = "spacings";
    for (int d = 0; d < 3; ++d) {
      const double s = nrrd->axis[d].spacing;
      if (!std::isfinite(s)) {
        throw InputError(path + ": header has neither \"space directions\" nor \"spacings\" for "
                         "axis " + std::to_string(d) + "; expected the sample spacing");
      }
      a(d, d) = s;
    }
    unit = nrrd->axis[0].units != nullptr ? nrrd->axis[0].units : "";
  } else {
    throw InputError(path + ": header space dimension " + std::to_string(nrrd->spaceDim) +
                     "; expected 3");
  }
  const double k = unit_scale(unit, path + " (space units)", unit_note);
  set_geometry(v, k * a, k * o, what);
  const std::size_t n = static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2];
  v.values.resize(n);
  auto lookup = nrrdDLookup[nrrd->type];
  for (std::size_t i = 0; i < n; ++i) {
    const double x = lookup(nrrd->data, i);
    if (!std::isfinite(x)) {
      throw InputError(path + ": sample " + std::to_string(i) + " is not finite (NaN or inf)");
    }
    v.values[i] = static_cast<float>(x);
  }
  return v;
}

// ---- DICOM ---------------------------------------------------------------------------------------

namespace {

struct Slice {
  std::string file;
  unsigned cols = 0, rows = 0;
  Vec3 position = Vec3::Zero();  // ImagePositionPatient [mm]
  Vec3 row_dir = Vec3::UnitX(), col_dir = Vec3::UnitY();
  double spacing_x = 0, spacing_y = 0;
  std::string series;
  std::vector<float> values;
  double s = 0;  // position along the slice normal
};

std::string element_string(const gdcm::DataSet& ds, const gdcm::Tag& tag) {
  if (!ds.FindDataElement(tag)) return "";
  const gdcm::ByteValue* bv = ds.GetDataElement(tag).GetByteValue();
  if (bv == nullptr) return "";
  std::string s(bv->GetPointer(), bv->GetLength());
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  return s;
}

template <typename T>
void slice_values(const std::vector<char>& buf, double slope, double inter, std::vector<float>& out) {
  const std::size_t n = buf.size() / sizeof(T);
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    T x;
    std::memcpy(&x, buf.data() + i * sizeof(T), sizeof(T));
    out[i] = static_cast<float>(slope * double(x) + inter);
  }
}

Slice read_slice(const std::string& file) {
  gdcm::ImageReader reader;
  reader.SetFileName(file.c_str());
  if (!reader.Read()) {
    throw InputError(file + ": not a readable DICOM image (every file of a DICOM series folder "
                     "must be one, apart from DICOMDIR)");
  }
  const gdcm::Image& img = reader.GetImage();
  Slice s;
  s.file = file;
  if (img.GetNumberOfDimensions() != 2) {
    throw InputError(file + ": a " + std::to_string(img.GetNumberOfDimensions()) +
                     "D image; expected one 2D slice per file");
  }
  const gdcm::PixelFormat pf = img.GetPixelFormat();
  if (pf.GetSamplesPerPixel() != 1) {
    throw InputError(file + ": SamplesPerPixel " + std::to_string(pf.GetSamplesPerPixel()) +
                     "; expected 1 (a grey-scale CT slice)");
  }
  s.cols = img.GetDimension(0);
  s.rows = img.GetDimension(1);
  s.spacing_x = img.GetSpacing(0);
  s.spacing_y = img.GetSpacing(1);
  s.position = Vec3(img.GetOrigin(0), img.GetOrigin(1), img.GetOrigin(2));
  const double* dc = img.GetDirectionCosines();
  s.row_dir = Vec3(dc[0], dc[1], dc[2]);
  s.col_dir = Vec3(dc[3], dc[4], dc[5]);
  s.series = element_string(reader.GetFile().GetDataSet(), gdcm::Tag(0x0020, 0x000e));
  std::vector<char> buf(img.GetBufferLength());
  if (!img.GetBuffer(buf.data())) {
    throw InputError(file + ": the pixel data cannot be decoded (compressed with a codec GDCM "
                     "lacks, or cut short)");
  }
  const double slope = img.GetSlope(), inter = img.GetIntercept();
  switch (pf.GetScalarType()) {
    case gdcm::PixelFormat::UINT8: slice_values<std::uint8_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::INT8: slice_values<std::int8_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::UINT16: slice_values<std::uint16_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::INT16: slice_values<std::int16_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::UINT32: slice_values<std::uint32_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::INT32: slice_values<std::int32_t>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::FLOAT32: slice_values<float>(buf, slope, inter, s.values); break;
    case gdcm::PixelFormat::FLOAT64: slice_values<double>(buf, slope, inter, s.values); break;
    default:
      throw InputError(file + ": pixel format " + std::string(pf.GetScalarTypeAsString()) +
                       "; expected 8/16/32-bit integers or floats");
  }
  if (s.values.size() != static_cast<std::size_t>(s.cols) * s.rows) {
    throw InputError(file + ": pixel data holds " + std::to_string(s.values.size()) +
                     " values; expected Columns x Rows = " + std::to_string(s.cols * s.rows));
  }
  return s;
}

}  // namespace

ScanVolume load_dicom_series(const std::string& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw InputError(folder + ": not a folder (DICOM series)");
  gdcm::Trace::WarningOff();
  gdcm::Trace::DebugOff();
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string name = e.path().filename().string();
    if (!e.is_regular_file() || name.empty() || name[0] == '.' || lower(name) == "dicomdir") continue;
    files.push_back(e.path().string());
  }
  if (ec) throw InputError(folder + ": cannot list the folder: " + ec.message());
  std::sort(files.begin(), files.end());
  if (files.size() < 2) {
    throw InputError(folder + ": " + std::to_string(files.size()) +
                     " DICOM file(s); expected a series of at least 2 slices");
  }
  std::vector<Slice> slices;
  slices.reserve(files.size());
  for (const std::string& f : files) slices.push_back(read_slice(f));
  const Slice& first = slices.front();
  const Vec3 normal = first.row_dir.cross(first.col_dir);
  for (Slice& s : slices) {
    if (s.series != first.series) {
      throw InputError(s.file + ": SeriesInstanceUID '" + s.series + "' differs from '" +
                       first.series + "' of " + first.file + "; expected one series per folder");
    }
    if (s.cols != first.cols || s.rows != first.rows) {
      throw InputError(s.file + ": " + std::to_string(s.cols) + " x " + std::to_string(s.rows) +
                       " pixels; expected " + std::to_string(first.cols) + " x " +
                       std::to_string(first.rows) + " as in " + first.file);
    }
    if ((s.row_dir - first.row_dir).norm() > 1e-4 || (s.col_dir - first.col_dir).norm() > 1e-4 ||
        std::abs(s.spacing_x - first.spacing_x) > 1e-6 * first.spacing_x ||
        std::abs(s.spacing_y - first.spacing_y) > 1e-6 * first.spacing_y) {
      throw InputError(s.file + ": ImageOrientationPatient or PixelSpacing differs from " +
                       first.file + "; expected one geometry for the series");
    }
    s.s = s.position.dot(normal);
  }
  std::sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) { return a.s < b.s; });
  // The slice distance: the median gap (a missing or duplicate slice is then the odd one out).
  std::vector<double> gaps;
  for (std::size_t i = 1; i < slices.size(); ++i) gaps.push_back(slices[i].s - slices[i - 1].s);
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  const double dz = gaps[gaps.size() / 2];
  for (std::size_t i = 1; i < slices.size(); ++i) {
    const double gap = slices[i].s - slices[i - 1].s;
    if (!(dz > 0) || std::abs(gap - dz) > 0.01 * dz) {
      throw InputError(slices[i].file + ": " + std::to_string(gap) + " mm from " +
                       slices[i - 1].file + " along the slice normal; expected an even spacing of " +
                       std::to_string(dz) + " mm (a duplicate, missing or tilted slice?)");
    }
  }
  ScanVolume v;
  v.source = folder;
  v.format = "DICOM";
  v.dims = {static_cast<int>(first.cols), static_cast<int>(first.rows),
            static_cast<int>(slices.size())};
  check_dims(v, "series size");
  Mat3 a;
  a.col(0) = first.row_dir * first.spacing_x;
  a.col(1) = first.col_dir * first.spacing_y;
  a.col(2) = normal * dz;
  set_geometry(v, 1e-3 * a, 1e-3 * slices.front().position, "ImageOrientationPatient/PixelSpacing");
  v.values.reserve(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2]);
  for (const Slice& s : slices) v.values.insert(v.values.end(), s.values.begin(), s.values.end());
  return v;
}

ScanVolume load_volume(const std::string& path, std::string* unit_note) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return load_dicom_series(path);
  const std::string p = lower(path);
  if (ends_with(p, ".nii") || ends_with(p, ".nii.gz")) return load_nifti(path, unit_note);
  if (ends_with(p, ".nrrd") || ends_with(p, ".nhdr")) return load_nrrd(path, unit_note);
  throw InputError(path + ": unknown volume format; expected a DICOM series folder, .nii, "
                   ".nii.gz, .nrrd or .nhdr");
}

}  // namespace dentsim
