#include "validation/skip_variants.h"

namespace dentsim {

namespace {

void faces(Scene& s) { s.tooth.contact_model = "faces"; }
void no_hand_mass(Scene& s) {
  s.method.grasp_mass_scale = 0.0;
  s.method.grip_detector = false;
}
void no_observer(PipelineConfig& pc) {
  pc.observer_gain = VecX();
  pc.grasp_model = nullptr;
}

}  // namespace

const std::vector<SkipVariant>& skip_variants() {
  static const std::vector<SkipVariant> kVariants = {
      {"pmi-no-observer", "observer, grip, decomposition, early out, drill (probe, face model)",
       "probe",
       [](Scene& s) {
         faces(s);
         s.method.method = Method::kPmiVc;
       },
       no_observer},
      {"explicit-no-observer", "observer, grip, decomposition, drill (probe, face model)", "probe",
       [](Scene& s) {
         faces(s);
         s.method.method = Method::kExplicitVc;
         s.method.friction.enabled = false;  // explicit Euler has no friction solve
         s.method.friction.mu = 0.0;
       },
       no_observer},
      {"pmi-pd-no-hand", "grip, early out (drill, face model)", "drill",
       [](Scene& s) {
         faces(s);
         no_hand_mass(s);
       },
       nullptr},
      {"pmi-observer-sdf", "decomposition, grip (drill, sdf model)", "drill",
       [](Scene& s) {
         s.method.method = Method::kPmiVc;
         no_hand_mass(s);
       },
       nullptr},
      {"pmi-pd-no-friction", "friction, grip, early out (drill, face model)", "drill",
       [](Scene& s) {
         faces(s);
         no_hand_mass(s);
         s.method.friction.enabled = false;
         s.method.friction.mu = 0.0;
       },
       nullptr},
      {"pmi-pd-drill",
       "the empty set only (the drill scene as built in: sdf model, hand mass, friction)", "drill",
       nullptr, nullptr},
  };
  return kVariants;
}

std::unique_ptr<SceneRig> build_skip_variant_rig(const SkipVariant& v, bool skip_unneeded) {
  Scene scene = load_scene(v.scene);
  if (v.edit_scene) v.edit_scene(scene);
  SceneRigOptions o;
  o.pipeline = "fast";
  o.configure_pipeline = v.edit_config;
  o.skip_unneeded = skip_unneeded;
  return build_scene_rig(scene, o);
}

}  // namespace dentsim
