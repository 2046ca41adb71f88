// Tooth material table (reference/tooth/materials.h). Values and where they come from:
//
// stiffness_scale / damping_scale: contact stiffness relative to the scene's K_tooth (and B_tooth).
//   A haptic device cannot render the real moduli (enamel E ~ 80-90 GPa, dentin E ~ 18-25 GPa:
//   Kinney, Marshall & Marshall, "The mechanical properties of human dentin: a critical review and
//   re-evaluation of the dental literature", Crit Rev Oral Biol Med 14(1):13-29, 2003; Habelitz et
//   al., "Mechanical properties of human dental enamel on the nanometre scale", Arch Oral Biol
//   46:173-183, 2001), so the scene's K_tooth is the stiffest the loop renders and is given to
//   enamel; dentin keeps a reduced but still "hard" feel (0.7), and the pulp, a soft connective
//   tissue, 0.05. These are rendering choices ordered as the moduli are, not measured ratios.
//
// removal_energy_j_per_mm3: the work the rotating bur must do on a unit volume to remove it
//   (docs/tooth_octree.md, "Drilling"). Model: the specific removal energy is taken equal to the
//   indentation hardness H (1 GPa = 1 J/mm^3): the plastic work to displace a volume V against a
//   flow pressure H is H V, a lower bound on the specific cutting energy that keeps the ratio
//   between the tissues. Hardness: enamel ~3-4 GPa, dentin ~0.5-0.7 GPa (Meredith, Sherriff,
//   Setchell & Swanson, "Measurement of the microhardness and Young's modulus of human enamel and
//   dentine using an indentation technique", Arch Oral Biol 41(6):539-545, 1996; Kinney et al.
//   2003 above). So enamel 3.0 J/mm^3, dentin 0.6 J/mm^3 (enamel 5x harder to drill). The pulp is
//   soft tissue that a bur tears rather than cuts: 0.01 J/mm^3, a small nonzero value so removal
//   still takes a tick's contact.
//
// caries (a carious lesion through enamel into dentin; the procedural molar carries one under its
//   central fossa, procedural_molar.h): the lesion's infected and affected dentin is
//   demineralised. Knoop hardness falls from ~65-70 KHN (sound dentin) to below ~20 KHN in the
//   infected layer (Fusayama, Okuse & Hosoda, "Relationship between hardness, discoloration, and
//   microbial invasion in carious dentin", J Dent Res 45(4):1033-1046, 1966), i.e. about 0.1-0.2
//   GPa against 0.6 GPa; the elastic modulus of the caries zones drops by an order of magnitude
//   (Pugach et al., "Dentin caries zones: mineral, structure, and properties", J Dent Res
//   88(1):71-76, 2009). So removal energy 0.1 J/mm^3 (6x faster to cut than dentin, 30x than
//   enamel) and stiffness/damping scale 0.3 (clearly softer under the explorer than dentin's 0.7,
//   the "sticky, soft" feel clinicians test for; a rendering choice ordered as the moduli are).
//
// rgb: display colours (ivory enamel, yellowish dentin, red pulp, brown caries).
#include "reference/tooth/materials.h"

#include "reference/core/io.h"

namespace dentsim {
namespace {

// clang-format off
constexpr MaterialProperties kTable[kMaterialCount] = {
    // name      stiffness damping  J/mm^3   rgb
    {"empty",    0.0,      0.0,     0.0,     {0, 0, 0}},
    {"enamel",   1.0,      1.0,     3.0,     {240, 236, 220}},
    {"dentin",   0.7,      0.7,     0.6,     {222, 196, 140}},
    {"pulp",     0.05,     0.05,    0.01,    {200, 60, 60}},
    {"caries",   0.3,      0.3,     0.1,     {120, 80, 40}},
};
// clang-format on

}  // namespace

const MaterialProperties& material_properties(std::uint8_t material) {
  if (material >= kMaterialCount) {
    throw InputError("material id " + std::to_string(material) +
                     ": expected 0 (empty), 1 (enamel), 2 (dentin), 3 (pulp) or 4 (caries)");
  }
  return kTable[material];
}

Material parse_material(const std::string& name) {
  if (name == "enamel") return kEnamel;
  if (name == "dentin") return kDentin;
  if (name == "pulp") return kPulp;
  if (name == "caries") return kCaries;
  throw InputError("material '" + name +
                   "': expected \"enamel\", \"dentin\", \"pulp\" or \"caries\"");
}

}  // namespace dentsim
