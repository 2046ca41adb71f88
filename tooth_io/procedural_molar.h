// The default tooth: a procedurally generated, deterministic lower (mandibular) first molar, so the
// project needs no data file to run (issue #4).
//
// Frame and units: metres; z is the tooth's long axis pointing occlusally, z = 0 is the
// cemento-enamel junction (CEJ) plane, x mesiodistal (mesial -x), y buccolingual (buccal -y); the
// CEJ cross-section is centred on the z axis.
//
// Anatomy (default dimensions, mm): Wheeler's Dental Anatomy, Physiology and Occlusion (S. J.
// Nelson, M. M. Ash, 9th ed., Saunders 2010), table of the mandibular first molar: crown length
// (cervico-occlusal) 7.5, root length 14 (the distal root ~1 shorter), crown mesiodistal 11.0,
// cervix mesiodistal 9.0, crown buccolingual 10.5, cervix buccolingual 9.0; five cusps (mesio-
// buccal, distobuccal, distal, mesiolingual, distolingual; the lingual ones the tallest), a
// central mesiodistal groove, two roots (mesial, distal) joined by a root trunk of ~3 mm to the
// furcation. Enamel is ~2.5 mm thick over the cusps and thins to nothing at the CEJ (Nanci, Ten
// Cate's Oral Histology, 8th ed., Mosby 2012, ch. 7); the pulp chamber lies in the cervical part
// of the crown and the trunk, with horns under the cusps and a canal in each root.
//
// Model: an implicit solid. The crown is a superellipse (exponent 2.5) cross-section whose half
// widths follow the height of contour in the cervical third, capped by an occlusal surface that is
// the upper envelope of five paraboloid cusps minus a Gaussian central groove (the envelope's
// creases are the buccal/lingual grooves); the trunk continues the cervix; each root is a tapered,
// buccolingually wide ellipse swept along a curved centreline with a rounded apex. The pulp is a
// chamber (superellipse with paraboloid horns) plus one tapered canal per root. Enamel is not
// modelled here: voxelize.h assigns it by depth from the surface with the CEJ of molar_crown_frame.
#pragma once

#include "tooth_io/mesh.h"
#include "reference/tooth/voxel_grid.h"
#include "tooth_io/voxelize.h"

namespace dentsim {

struct MolarParams {
  double scale = 1.0;                    // multiplies every length below (target size)
  double crown_mesiodistal_m = 11.0e-3;  // at the height of contour
  double crown_buccolingual_m = 10.5e-3;
  double cervix_mesiodistal_m = 9.0e-3;  // at the CEJ
  double cervix_buccolingual_m = 9.0e-3;
  double crown_height_m = 7.5e-3;         // CEJ to the tallest (mesiolingual) cusp tip
  double mesial_root_length_m = 14.0e-3;  // CEJ to apex
  double distal_root_length_m = 13.0e-3;
  double root_trunk_m = 3.0e-3;  // CEJ to the furcation
  // Depth-rule parameter t_cusp of voxelize.h. The cusps sit within ~2 mm of the crown walls, so
  // the depth rule leaves more than t_cusp of enamel under a tip; 2.2 mm gives the anatomical
  // ~2.5 mm there (tested) and 1.6 mm laterally at mid-crown.
  double enamel_cusp_m = 2.2e-3;
  // A carious lesion (material kCaries) in the distal part of the central groove: the solid,
  // non-pulp voxels inside the ellipsoid of these semi-axes whose top touches the groove floor at
  // (caries_x_m, 0): an occlusal lesion that has crossed the enamel into dentin. The drill scene
  // cuts sound enamel and dentin mesial of it. Off with caries_lesion = false.
  bool caries_lesion = true;
  double caries_x_m = 3.0e-3;
  Vec3 caries_radii_m = Vec3(1.0e-3, 0.8e-3, 1.2e-3);
};

// Whether the point p (metres, frame above) is inside the tooth / inside the pulp.
bool molar_solid(const MolarParams& params, const Vec3& p);
bool molar_pulp(const MolarParams& params, const Vec3& p);

// molar_solid(params, p) for many points p (the field's surface: 40 bisections of it per surface
// edge, ~7 x 10^7 calls at 512^3; issue #30): the same answer at every point, cheaper. The
// parameters' derived lengths are computed once, and the two power functions (the cross-section's
// |t|^2.5 and the root taper's u^6) are first taken as products (t t sqrt(t), (u u)^3), whose
// relative error is a few units in the last place: where the test's sum lies farther from its
// threshold than a margin far above that error, the products decide; otherwise std::pow does,
// as molar_solid (procedural_molar.cc states the margins).
class MolarSolidTest {
 public:
  explicit MolarSolidTest(const MolarParams& params);
  bool operator()(const Vec3& p) const;

 private:
  MolarParams params_;
  double unit_;            // metres per model millimetre
  double lengths_[8];      // the model's lengths (procedural_molar.cc Mm)
  double roots_[2][5];     // the roots' shapes (procedural_molar.cc RootShape)
};
// Whether p lies in the caries lesion's ellipsoid (false when caries_lesion is off).
bool molar_caries(const MolarParams& params, const Vec3& p);

// Axis-aligned bounds of the solid (exact extents of the model's parts, before voxelisation).
Aabb molar_bounds(const MolarParams& params);

// The crown frame for enamel assignment: axis +z, CEJ at z = 0, crown height = tallest cusp.
CrownFrame molar_crown_frame(const MolarParams& params);

// The procedural molar on an N^3 grid (N a power of two): solid and pulp sampled at the voxel
// centres, enamel by depth (assign_materials), then the caries lesion. Deterministic: the same params give the same bytes.
VoxelGrid voxelize_procedural_molar(const MolarParams& params, int resolution,
                                    VoxelizeReport* report = nullptr);

}  // namespace dentsim
