#include "sim/scene_device.h"

#include "device/phantom_device.h"

namespace dentsim {

PhantomParams scene_phantom_params(const Scene& scene) {
  return scene.device.model_file.empty() ? default_phantom_params()
                                         : load_phantom_params(scene.device.model_file);
}

SimulatedDeviceConfig scene_device_config(const Scene& scene, const PhantomParams& params) {
  SimulatedDeviceConfig c = phantom_device_config(params);
  c.quantize = scene.device.quantize;
  c.saturate = scene.device.saturate;
  c.jitter.period = 1.0 / scene.tick_hz;
  if (scene.device.jitter_us > 0.0) {
    c.jitter.kind = TickJitterKind::kUniform;
    c.jitter.half_width = 1e-6 * scene.device.jitter_us;
  }
  return c;
}

ScriptedHand scene_hand(const Scene& scene, const Pose& home) {
  const Vec3 anchor_target = home.x + scene.tooth.anchor_offset;
  std::vector<HandKeyframe> keys;
  keys.reserve(scene.script.size());
  for (const SceneHandKey& k : scene.script) {
    HandKeyframe hk;
    hk.t = k.t;
    hk.x_ref = anchor_target + k.offset;
    hk.wrench_ff << k.force, Vec3::Zero();
    keys.push_back(hk);
  }
  return ScriptedHand(scene.hand, keys, home.R);
}

}  // namespace dentsim
