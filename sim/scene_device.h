// The simulated device and the scripted hand a scene (sim/scene.h) asks for, in one place so the
// simulator (sim/simulator.cc) and the HDAPI emulator (device/hdapi/emulator/) build the same
// plant: the emulator-backed run of a scene must match the direct simulated run (issue #15).
//
// - Device: the scene's device model file (default Phantom when empty), encoder quantisation and
//   saturation as the scene says, tick period T = 1 / tick_hz with uniform jitter of half-width
//   jitter_us when > 0; started at rest at phantom_home_q (the middle of the joint ranges).
// - Hand: keyframes x_ref = x_home + tooth.anchor_offset + offset, feed-forward [force; 0], the
//   tool's orientation held at the home pose's R; impedance from the scene.
#pragma once

#include <memory>

#include "sim/scene.h"
#include "device/scripted_hand.h"
#include "device/simulated_phantom.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

// The device model the scene names (throws InputError for an unreadable model file).
PhantomParams scene_phantom_params(const Scene& scene);
// The simulated device's configuration for the scene.
SimulatedDeviceConfig scene_device_config(const Scene& scene, const PhantomParams& params);
// The scene's scripted hand; `home` is the tool-tip pose at phantom_home_q.
ScriptedHand scene_hand(const Scene& scene, const Pose& home);

}  // namespace dentsim
