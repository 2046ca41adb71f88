// Tooth materials (thesis §2.5; docs/design.md "Voxel tooth"). Ids are stored per voxel
// (VoxelGrid). The property table (stiffness scale, drilling threshold, colour) lives in
// materials.cc with its sources.
#pragma once

#include <cstdint>
#include <string>

namespace dentsim {

enum Material : std::uint8_t {
  kEmpty = 0,
  kEnamel = 1,
  kDentin = 2,
  kPulp = 3,
  kCaries = 4,  // a carious lesion (demineralised enamel and dentin): softer, cut faster
  kMaterialCount = 5,
};

struct MaterialProperties {
  const char* name;                 // "enamel", "dentin", "pulp", "caries"
  double stiffness_scale;           // contact stiffness relative to the scene's K_tooth
  double damping_scale;             // contact damping relative to the scene's B_tooth
  double removal_energy_j_per_mm3;  // work per unit volume to remove it by drilling [J/mm^3]
  std::uint8_t rgb[3];              // display colour for pictures
};

const MaterialProperties& material_properties(std::uint8_t material);
// Parses a material name ("enamel", "dentin", "pulp", "caries"); throws dentsim::InputError otherwise.
Material parse_material(const std::string& name);

}  // namespace dentsim
