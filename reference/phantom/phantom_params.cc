// Phantom model file: defaults, JSON load/save, physical validation. Format: docs/phantom.md.
#include "reference/phantom/phantom_params.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <vector>

#include "reference/core/io.h"
#include "reference/core/json_reader.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kFormat = "dentsim-phantom-model";
constexpr int kVersion = 1;

// ---- writing -----------------------------------------------------------------------------------

std::string num(double v) { return Json(v).dump(); }  // shortest round-trip representation

}  // namespace

const char* coulomb_sign_name(CoulombSign s) { return s == CoulombSign::kErf ? "erf" : "tanh"; }

namespace {

template <typename V>
std::string vec(const V& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + num(v(i));
  return s + "]";
}

std::string quoted(const std::string& s) { return Json(s).dump(); }

std::string body_text(const PhantomBody& b) {
  return "{\"mass_kg\": " + num(b.mass_kg) + ", \"com_m\": " + vec(b.com_m) +
         ", \"inertia_kg_m2\": " + vec(b.inertia_kg_m2) + "}";
}

// ---- reading ----------------------------------------------------------------------------------

PhantomBody read_body(const JsonReader& r, const JsonReader::Json& bodies,
                      const std::string& name) {
  const std::string path = "bodies." + name;
  const auto& b = r.object(bodies, "bodies", name);
  r.only_keys(b, path, {"mass_kg", "com_m", "inertia_kg_m2"});
  PhantomBody out;
  out.mass_kg = r.number(b, path, "mass_kg");
  out.com_m = r.vec3(b, path, "com_m");
  out.inertia_kg_m2 = r.vec3(b, path, "inertia_kg_m2");
  return out;
}

// Bodies in file order with a pointer-to-member each.
struct BodyField {
  const char* name;
  PhantomBody PhantomParams::*member;
};
const BodyField kBodies[] = {
    {"base", &PhantomParams::base},
    {"upper_arm", &PhantomParams::upper_arm},
    {"forearm", &PhantomParams::forearm},
    {"crank", &PhantomParams::crank},
    {"parallel_link", &PhantomParams::parallel_link},
    {"gimbal_yaw", &PhantomParams::gimbal_yaw},
    {"gimbal_pitch", &PhantomParams::gimbal_pitch},
    {"gimbal_roll", &PhantomParams::gimbal_roll},
};

std::string vec_str(const Eigen::VectorXd& v) { return vec(v); }

// The optional "torque_limit" block: {"model": "clamp"} or the thermal model's keys.
MotorThermalParams read_torque_limit(const JsonReader& r, const JsonReader::Json& root) {
  const auto& b = r.object(root, "", "torque_limit");
  const std::string path = "torque_limit";
  MotorThermalParams t;
  const std::string model = r.string(b, path, "model");
  if (model == "clamp") {
    r.only_keys(b, path, {"model"});
    return t;
  }
  if (model != "thermal") {
    r.fail("torque_limit.model", "expected \"clamp\" or \"thermal\", got \"" + model + "\"");
  }
  r.only_keys(b, path,
              {"model", "peak_n_m", "continuous_n_m", "thermal_resistance_winding_housing_k_per_w",
               "thermal_resistance_housing_ambient_k_per_w", "thermal_time_constant_winding_s",
               "thermal_time_constant_motor_s", "max_winding_temperature_c",
               "ambient_temperature_c", "on_overheat"});
  t.model = TorqueLimitModel::kThermal;
  t.peak_n_m = r.vector<6>(b, path, "peak_n_m");
  t.continuous_n_m = r.vector<6>(b, path, "continuous_n_m");
  t.r_winding_housing_k_per_w = r.vector<6>(b, path, "thermal_resistance_winding_housing_k_per_w");
  t.r_housing_ambient_k_per_w = r.vector<6>(b, path, "thermal_resistance_housing_ambient_k_per_w");
  t.tau_winding_s = r.vector<6>(b, path, "thermal_time_constant_winding_s");
  t.tau_motor_s = r.vector<6>(b, path, "thermal_time_constant_motor_s");
  t.max_winding_c = r.vector<6>(b, path, "max_winding_temperature_c");
  t.ambient_c = r.number(b, path, "ambient_temperature_c");
  const std::string on = r.string(b, path, "on_overheat");
  if (on == "derate") {
    t.on_overheat = OnOverheat::kDerate;
  } else if (on == "fault") {
    t.on_overheat = OnOverheat::kFault;
  } else {
    r.fail("torque_limit.on_overheat", "expected \"derate\" or \"fault\", got \"" + on + "\"");
  }
  return t;
}

}  // namespace

Vec6 phantom_torque_clamp(const PhantomParams& p) {
  return p.torque_limit.model == TorqueLimitModel::kThermal ? p.torque_limit.peak_n_m
                                                            : p.torque_limit_n_m;
}

MotorThermalParams phantom_thermal_torque_limit() {
  // docs/device_facts.md §3 "Motor thermal limit": Maxon RE 25 (continuous 28.6 mN m, stall
  // 129 mN m) through the capstans (13.3, 11.2, 11.2); thermal data of the RE 25 catalogue page
  // (assumed where docs/device_facts.md says so). Gimbal: no published motor data; its
  // torque_limit_n_m as both peak and continuous (assumed), so the gimbal keeps its clamp.
  MotorThermalParams t;
  t.model = TorqueLimitModel::kThermal;
  const Vec3 ratio(13.3, 11.2, 11.2);
  for (int j = 0; j < 3; ++j) {
    t.peak_n_m(j) = 0.129 * ratio(j);
    t.continuous_n_m(j) = 0.0286 * ratio(j);
  }
  t.peak_n_m.tail<3>() << 0.188, 0.188, 0.048;
  t.continuous_n_m.tail<3>() = t.peak_n_m.tail<3>();
  t.r_winding_housing_k_per_w.setConstant(3.1);
  t.r_housing_ambient_k_per_w.setConstant(14.0);
  t.tau_winding_s.setConstant(12.5);
  t.tau_motor_s.setConstant(612.0);
  t.max_winding_c.setConstant(125.0);
  t.ambient_c = 25.0;
  t.on_overheat = OnOverheat::kDerate;
  return t;
}

PhantomParams default_phantom_params() {
  PhantomParams p;
  p.name = "Phantom Premium 1.5A/6DoF: Cavusoglu 2002 arm, device_facts.md drive train, nominal gimbal";
  // Cavusoglu, Feygin & Tendick 2002 (docs/device_facts.md §2).
  p.l1_m = 0.215;
  p.l2_m = 0.170;
  p.l3_m = 0.0325;
  // Base: yaw inertia 11.87e-4 (Cavusoglu); mass from the CAD set; x, y moments do not enter the
  // dynamics (the base only yaws) and are set to satisfy the triangle inequality.
  p.base = {0.36159, Vec3::Zero(), Vec3(6.0e-4, 6.0e-4, 11.87e-4)};
  // be: published moments are about the shoulder: (11.09, 10.06, 0.591)e-4. Parallel-axis shift
  // by m l5^2 = 0.2359 * 0.0368^2 gives CoM moments (7.895, 6.865, 0.591)e-4, which break
  // Ixx <= Iyy + Izz; Ixx is set to 7.45e-4 and the excess 0.44534784e-4 moves into the q2
  // armature (it only ever turns with q2). docs/device_facts.md §2, docs/phantom.md §2.
  p.upper_arm = {0.2359, Vec3(0, 0, -0.0368), Vec3(0.000745, 0.000686534784, 0.0000591)};
  p.forearm = {0.0202, Vec3(0, 0.085, 0), Vec3(0.00004864, 0.0000001843, 0.00004864)};
  // df: about the shoulder (7.11, 0.629, 6.246)e-4, shifted by m l6^2 = 0.1906 * 0.0527^2 on x, z:
  // CoM (1.81648526, 0.629, 0.95248526)e-4; Ixx set to 1.58e-4, excess 0.23648526e-4 -> q3.
  p.crank = {0.1906, Vec3(0, -0.0527, 0), Vec3(0.000158, 0.0000629, 0.000095248526)};
  p.parallel_link = {0.0249, Vec3(0, 0, 0.1075), Vec3(0.0000959, 0.0000959, 0.00000051)};
  // Gimbal: not published (docs/device_facts.md §1); nominal values of a light yoke, ring and
  // stylus, to be identified by calibration/.
  p.gimbal_yaw = {0.015, Vec3(0, 0.005, -0.01), Vec3(3.0e-6, 2.0e-6, 2.0e-6)};
  p.gimbal_pitch = {0.012, Vec3::Zero(), Vec3(1.5e-6, 1.5e-6, 1.0e-6)};
  p.gimbal_roll = {0.035, Vec3(0, 0, -0.02), Vec3(5.0e-6, 5.0e-6, 1.0e-6)};
  p.pitch_pos_m = Vec3::Zero();
  p.roll_pos_m = Vec3::Zero();
  p.yaw_axis = Vec3::UnitY();
  p.pitch_axis = Vec3::UnitX();
  p.roll_axis = Vec3::UnitZ();
  p.tip_offset_m = Vec3(0, 0, -0.04);
  // Reflected rotor inertia (docs/device_facts.md §3: 1.8e-4, 1.3e-4, 1.3e-4) + the link excess
  // above; the gimbal motors' values are nominal.
  p.armature_kg_m2 << 0.00018, 0.000174534784, 0.000153648526, 2.0e-6, 2.0e-6, 5.0e-7;
  // Not published: nominal, fitted by calibration/. Coulomb from the vendor's 0.04 N backdrive
  // friction (unverified) times ~0.2 m.
  p.damping_n_m_s_per_rad << 5.0e-4, 5.0e-4, 5.0e-4, 1.0e-5, 1.0e-5, 5.0e-6;
  p.coulomb_n_m << 0.008, 0.006, 0.006, 2.0e-4, 2.0e-4, 1.0e-4;
  p.coulomb_smoothing_rad_s.setConstant(0.01);
  // Box inside which J1 is regular (no stretched elbow, tip off the yaw axis, no gimbal lock).
  p.q_min_rad << -0.9, -0.2, -0.4, -2.4, -1.0, -2.6;
  p.q_max_rad << 0.9, 0.9, 1.0, 2.4, 1.0, 2.6;
  // OpenHaptics' joint-torque example clamps (docs/device_facts.md §3).
  p.torque_limit_n_m << 0.4, 0.35, 0.2, 0.188, 0.188, 0.048;
  // 1024 CPR x4 times the capstan ratios (13.3, 11.2, 11.2) (docs/device_facts.md §3,
  // drive train and sensing); gimbal 4096: assumed, no published resolution of the Premium 1.5/6DoF
  // gimbal encoders was found (docs/simulated_device.md, issue #29).
  p.encoder_counts_per_rev << 54476.8, 45875.2, 45875.2, 4096, 4096, 4096;
  p.gravity_on = true;
  p.gravity_m_s2 = 9.81;
  return p;
}

std::string phantom_params_to_text(const PhantomParams& p) {
  std::ostringstream s;
  s << "{\n";
  s << "  \"format\": " << quoted(kFormat) << ",\n";
  s << "  \"version\": " << kVersion << ",\n";
  s << "  \"name\": " << quoted(p.name) << ",\n";
  s << "  \"gravity_on\": " << (p.gravity_on ? "true" : "false") << ",\n";
  s << "  \"gravity_m_s2\": " << num(p.gravity_m_s2) << ",\n";
  s << "  \"arm\": {\"l1_m\": " << num(p.l1_m) << ", \"l2_m\": " << num(p.l2_m)
    << ", \"l3_m\": " << num(p.l3_m) << "},\n";
  s << "  \"bodies\": {\n";
  for (size_t i = 0; i < std::size(kBodies); ++i) {
    s << "    " << quoted(kBodies[i].name) << ": " << body_text(p.*(kBodies[i].member))
      << (i + 1 < std::size(kBodies) ? ",\n" : "\n");
  }
  s << "  },\n";
  s << "  \"gimbal\": {\n";
  s << "    \"pitch_pos_m\": " << vec(p.pitch_pos_m) << ",\n";
  s << "    \"roll_pos_m\": " << vec(p.roll_pos_m) << ",\n";
  s << "    \"yaw_axis\": " << vec(p.yaw_axis) << ",\n";
  s << "    \"pitch_axis\": " << vec(p.pitch_axis) << ",\n";
  s << "    \"roll_axis\": " << vec(p.roll_axis) << ",\n";
  s << "    \"tip_offset_m\": " << vec(p.tip_offset_m) << "\n";
  s << "  },\n";
  s << "  \"joints\": {\n";
  s << "    \"armature_kg_m2\": " << vec(p.armature_kg_m2) << ",\n";
  s << "    \"damping_n_m_s_per_rad\": " << vec(p.damping_n_m_s_per_rad) << ",\n";
  s << "    \"coulomb_n_m\": " << vec(p.coulomb_n_m) << ",\n";
  const Vec6& vs = p.coulomb_smoothing_rad_s;
  s << "    \"coulomb_smoothing_rad_s\": "
    << ((vs.array() == vs(0)).all() ? num(vs(0)) : vec(vs)) << ",\n";
  const auto& sign = p.coulomb_sign;
  if (std::any_of(sign.begin(), sign.end(), [](CoulombSign c) { return c != CoulombSign::kTanh; })) {
    s << "    \"coulomb_sign\": ";
    if (std::all_of(sign.begin(), sign.end(), [&](CoulombSign c) { return c == sign[0]; })) {
      s << '"' << coulomb_sign_name(sign[0]) << '"';
    } else {
      s << "[";
      for (int j = 0; j < 6; ++j) s << (j ? ", " : "") << '"' << coulomb_sign_name(sign[j]) << '"';
      s << "]";
    }
    s << ",\n";
  }
  s << "    \"q_min_rad\": " << vec(p.q_min_rad) << ",\n";
  s << "    \"q_max_rad\": " << vec(p.q_max_rad) << ",\n";
  s << "    \"torque_limit_n_m\": " << vec(p.torque_limit_n_m) << ",\n";
  s << "    \"encoder_counts_per_rev\": " << vec(p.encoder_counts_per_rev) << "\n";
  s << "  }";
  // Written only when not the clamp: the files written before read (and write) the same.
  const MotorThermalParams& t = p.torque_limit;
  if (t.model == TorqueLimitModel::kThermal) {
    s << ",\n  \"torque_limit\": {\n";
    s << "    \"model\": \"thermal\",\n";
    s << "    \"peak_n_m\": " << vec(t.peak_n_m) << ",\n";
    s << "    \"continuous_n_m\": " << vec(t.continuous_n_m) << ",\n";
    s << "    \"thermal_resistance_winding_housing_k_per_w\": " << vec(t.r_winding_housing_k_per_w)
      << ",\n";
    s << "    \"thermal_resistance_housing_ambient_k_per_w\": " << vec(t.r_housing_ambient_k_per_w)
      << ",\n";
    s << "    \"thermal_time_constant_winding_s\": " << vec(t.tau_winding_s) << ",\n";
    s << "    \"thermal_time_constant_motor_s\": " << vec(t.tau_motor_s) << ",\n";
    s << "    \"max_winding_temperature_c\": " << vec(t.max_winding_c) << ",\n";
    s << "    \"ambient_temperature_c\": " << num(t.ambient_c) << ",\n";
    s << "    \"on_overheat\": \""
      << (t.on_overheat == OnOverheat::kFault ? "fault" : "derate") << "\"\n";
    s << "  }";
  }
  s << "\n}\n";
  return s.str();
}

std::string default_phantom_model_file() {
  return phantom_params_to_text(default_phantom_params());
}

PhantomParams parse_phantom_params(const std::string& text, const std::string& origin) {
  const JsonReader r(origin);
  const JsonReader::Json root = r.parse(text);
  if (!root.is_object())
    r.fail("(top level)", "expected a JSON object, got " + JsonReader::shown(root));
  r.only_keys(root, "",
              {"format", "version", "name", "gravity_on", "gravity_m_s2", "arm", "bodies", "gimbal",
               "joints", "torque_limit"});
  const auto& format = r.member(root, "", "format");
  if (!format.is_string() || format.get<std::string>() != kFormat) {
    r.fail("format", std::string("expected \"") + kFormat + "\", got " + JsonReader::shown(format));
  }
  if (!r.member(root, "", "version").is_number_integer() ||
      r.integer(root, "", "version", 0, 1000) != kVersion) {
    r.fail("version", "expected " + std::to_string(kVersion) + ", got " +
                          JsonReader::shown(root.at("version")));
  }
  PhantomParams p;
  p.name = r.string(root, "", "name");
  p.gravity_on = r.boolean(root, "", "gravity_on");
  p.gravity_m_s2 = r.number(root, "", "gravity_m_s2");

  const auto& arm = r.object(root, "", "arm");
  r.only_keys(arm, "arm", {"l1_m", "l2_m", "l3_m"});
  p.l1_m = r.number(arm, "arm", "l1_m");
  p.l2_m = r.number(arm, "arm", "l2_m");
  p.l3_m = r.number(arm, "arm", "l3_m");

  const auto& bodies = r.object(root, "", "bodies");
  r.only_keys(bodies, "bodies",
              {"base", "upper_arm", "forearm", "crank", "parallel_link", "gimbal_yaw",
               "gimbal_pitch", "gimbal_roll"});
  for (const auto& b : kBodies) p.*(b.member) = read_body(r, bodies, b.name);

  const auto& gimbal = r.object(root, "", "gimbal");
  r.only_keys(gimbal, "gimbal",
              {"pitch_pos_m", "roll_pos_m", "yaw_axis", "pitch_axis", "roll_axis", "tip_offset_m"});
  p.pitch_pos_m = r.vec3(gimbal, "gimbal", "pitch_pos_m");
  p.roll_pos_m = r.vec3(gimbal, "gimbal", "roll_pos_m");
  p.yaw_axis = r.vec3(gimbal, "gimbal", "yaw_axis");
  p.pitch_axis = r.vec3(gimbal, "gimbal", "pitch_axis");
  p.roll_axis = r.vec3(gimbal, "gimbal", "roll_axis");
  p.tip_offset_m = r.vec3(gimbal, "gimbal", "tip_offset_m");

  const auto& joints = r.object(root, "", "joints");
  r.only_keys(joints, "joints",
              {"armature_kg_m2", "damping_n_m_s_per_rad", "coulomb_n_m", "coulomb_smoothing_rad_s",
               "coulomb_sign", "q_min_rad", "q_max_rad", "torque_limit_n_m",
               "encoder_counts_per_rev"});
  p.armature_kg_m2 = r.vector<6>(joints, "joints", "armature_kg_m2");
  p.damping_n_m_s_per_rad = r.vector<6>(joints, "joints", "damping_n_m_s_per_rad");
  p.coulomb_n_m = r.vector<6>(joints, "joints", "coulomb_n_m");
  // One number (every joint) or one per joint.
  if (r.has(joints, "coulomb_smoothing_rad_s") && joints.at("coulomb_smoothing_rad_s").is_array()) {
    p.coulomb_smoothing_rad_s = r.vector<6>(joints, "joints", "coulomb_smoothing_rad_s");
  } else {
    p.coulomb_smoothing_rad_s.setConstant(r.number(joints, "joints", "coulomb_smoothing_rad_s"));
  }
  // Optional: "tanh" or "erf", one for every joint or one per joint.
  if (r.has(joints, "coulomb_sign")) {
    const auto& cs = joints.at("coulomb_sign");
    const auto one = [&](const JsonReader::Json& e, const std::string& where) {
      if (e.is_string() && e.get<std::string>() == "tanh") return CoulombSign::kTanh;
      if (e.is_string() && e.get<std::string>() == "erf") return CoulombSign::kErf;
      r.fail(where, "expected \"tanh\" or \"erf\", got " + JsonReader::shown(e));
      return CoulombSign::kTanh;
    };
    if (cs.is_array()) {
      if (cs.size() != 6) {
        r.fail("joints.coulomb_sign", "expected one sign or 6, got " + JsonReader::shown(cs));
      }
      for (int j = 0; j < 6; ++j) {
        p.coulomb_sign[j] = one(cs[static_cast<std::size_t>(j)],
                                "joints.coulomb_sign[" + std::to_string(j) + "]");
      }
    } else {
      p.coulomb_sign.fill(one(cs, "joints.coulomb_sign"));
    }
  }
  p.q_min_rad = r.vector<6>(joints, "joints", "q_min_rad");
  p.q_max_rad = r.vector<6>(joints, "joints", "q_max_rad");
  p.torque_limit_n_m = r.vector<6>(joints, "joints", "torque_limit_n_m");
  p.encoder_counts_per_rev = r.vector<6>(joints, "joints", "encoder_counts_per_rev");
  if (r.has(root, "torque_limit")) p.torque_limit = read_torque_limit(r, root);

  validate_phantom_params(p, origin);
  return p;
}

PhantomParams load_phantom_params(const std::string& path) {
  return parse_phantom_params(read_file(path), "device model file '" + path + "'");
}

void validate_phantom_params(const PhantomParams& p, const std::string& origin,
                             int workspace_samples) {
  const JsonReader r(origin);
  auto positive = [&](double v, const std::string& field) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      r.fail(field, "expected a positive finite number, got " + num(v));
    }
  };
  auto non_negative6 = [&](const Vec6& v, const std::string& field) {
    for (int j = 0; j < 6; ++j) {
      if (!(v(j) >= 0.0) || !std::isfinite(v(j))) {
        r.fail(field + "[" + std::to_string(j) + "]",
               "expected a non-negative finite number, got " + num(v(j)));
      }
    }
  };
  auto finite3 = [&](const Vec3& v, const std::string& field) {
    if (!v.allFinite()) r.fail(field, "expected finite numbers, got " + vec_str(v));
  };
  auto unit3 = [&](const Vec3& v, const std::string& field) {
    finite3(v, field);
    if (std::abs(v.norm() - 1.0) > 1e-9) {
      r.fail(field, "expected a unit vector (|a| = 1 within 1e-9), got " + vec_str(v) +
                        " with norm " + num(v.norm()));
    }
  };
  positive(p.gravity_m_s2, "gravity_m_s2");
  positive(p.l1_m, "arm.l1_m");
  positive(p.l2_m, "arm.l2_m");
  positive(p.l3_m, "arm.l3_m");
  for (const auto& b : kBodies) {
    const PhantomBody& body = p.*(b.member);
    const std::string path = std::string("bodies.") + b.name;
    positive(body.mass_kg, path + ".mass_kg");
    finite3(body.com_m, path + ".com_m");
    const Vec3& I = body.inertia_kg_m2;
    for (int a = 0; a < 3; ++a) {
      if (!(I(a) > 0.0) || !std::isfinite(I(a))) {
        r.fail(path + ".inertia_kg_m2[" + std::to_string(a) + "]",
               "expected a positive finite moment of inertia, got " + num(I(a)));
      }
    }
    for (int a = 0; a < 3; ++a) {
      const double others = I((a + 1) % 3) + I((a + 2) % 3);
      if (I(a) > others) {
        r.fail(path + ".inertia_kg_m2",
               "moments " + vec_str(I) + " break the triangle inequality I[" + std::to_string(a) +
                   "] <= sum of the other two (" + num(I(a)) + " > " + num(others) +
                   "): no rigid body has them; move the excess into joints.armature_kg_m2");
      }
    }
  }
  finite3(p.pitch_pos_m, "gimbal.pitch_pos_m");
  finite3(p.roll_pos_m, "gimbal.roll_pos_m");
  finite3(p.tip_offset_m, "gimbal.tip_offset_m");
  unit3(p.yaw_axis, "gimbal.yaw_axis");
  unit3(p.pitch_axis, "gimbal.pitch_axis");
  unit3(p.roll_axis, "gimbal.roll_axis");
  non_negative6(p.armature_kg_m2, "joints.armature_kg_m2");
  non_negative6(p.damping_n_m_s_per_rad, "joints.damping_n_m_s_per_rad");
  non_negative6(p.coulomb_n_m, "joints.coulomb_n_m");
  for (int j = 0; j < 6; ++j) {
    const double vs = p.coulomb_smoothing_rad_s(j);
    if (!(vs >= 0.0) || !std::isfinite(vs)) {
      r.fail("joints.coulomb_smoothing_rad_s",
             "expected non-negative numbers (0 = sign), got " + num(vs) + " for joint " +
                 std::to_string(j + 1));
    }
  }
  for (int j = 0; j < 6; ++j) {
    std::string idx("[");  // (built by appending: GCC 12's -Wrestrict misfires on "[" + s)
    idx += std::to_string(j);
    idx += ']';
    if (!std::isfinite(p.q_min_rad(j))) r.fail("joints.q_min_rad" + idx, "expected a finite angle");
    if (!std::isfinite(p.q_max_rad(j))) r.fail("joints.q_max_rad" + idx, "expected a finite angle");
    if (!(p.q_min_rad(j) < p.q_max_rad(j))) {
      r.fail("joints.q_max_rad" + idx,
             "expected q_max > q_min = " + num(p.q_min_rad(j)) + ", got " + num(p.q_max_rad(j)));
    }
    positive(p.torque_limit_n_m(j), "joints.torque_limit_n_m" + idx);
    positive(p.encoder_counts_per_rev(j), "joints.encoder_counts_per_rev" + idx);
  }
  const MotorThermalParams& t = p.torque_limit;
  if (t.model == TorqueLimitModel::kThermal) {
    if (!std::isfinite(t.ambient_c)) {
      r.fail("torque_limit.ambient_temperature_c", "expected a finite temperature, got " +
                                                       num(t.ambient_c));
    }
    for (int j = 0; j < 6; ++j) {
      std::string idx("[");
      idx += std::to_string(j);
      idx += ']';
      positive(t.continuous_n_m(j), "torque_limit.continuous_n_m" + idx);
      positive(t.peak_n_m(j), "torque_limit.peak_n_m" + idx);
      if (t.peak_n_m(j) < t.continuous_n_m(j)) {
        r.fail("torque_limit.peak_n_m" + idx, "expected at least continuous_n_m = " +
                                                  num(t.continuous_n_m(j)) + ", got " +
                                                  num(t.peak_n_m(j)));
      }
      positive(t.r_winding_housing_k_per_w(j),
               "torque_limit.thermal_resistance_winding_housing_k_per_w" + idx);
      positive(t.r_housing_ambient_k_per_w(j),
               "torque_limit.thermal_resistance_housing_ambient_k_per_w" + idx);
      positive(t.tau_winding_s(j), "torque_limit.thermal_time_constant_winding_s" + idx);
      positive(t.tau_motor_s(j), "torque_limit.thermal_time_constant_motor_s" + idx);
      if (!std::isfinite(t.max_winding_c(j)) || !(t.max_winding_c(j) > t.ambient_c)) {
        r.fail("torque_limit.max_winding_temperature_c" + idx,
               "expected a finite temperature above ambient_temperature_c = " + num(t.ambient_c) +
                   ", got " + num(t.max_winding_c(j)));
      }
    }
  }

  // M(q) positive definite over the joint-limit box: at its centre, its 64 corners and a
  // fixed-seed uniform sample of `workspace_samples` points (deterministic, ~1 ms per 100).
  const PhantomModelD model(p);
  std::vector<Vec6> samples;
  const Vec6 centre = 0.5 * (p.q_min_rad + p.q_max_rad);
  samples.push_back(centre);
  for (int mask = 0; mask < 64; ++mask) {
    Vec6 q;
    for (int j = 0; j < 6; ++j) q(j) = (mask >> j) & 1 ? p.q_max_rad(j) : p.q_min_rad(j);
    samples.push_back(q);
  }
  std::mt19937_64 rng(20021);  // fixed seed: validation is deterministic
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int s = 0; s < workspace_samples; ++s) {
    Vec6 q;
    for (int j = 0; j < 6; ++j) q(j) = p.q_min_rad(j) + u(rng) * (p.q_max_rad(j) - p.q_min_rad(j));
    samples.push_back(q);
  }
  for (const Vec6& q : samples) {
    const Mat6 M = model.M(q);
    Eigen::SelfAdjointEigenSolver<Mat6> eig(M);
    const double lmin = eig.eigenvalues()(0);
    const double lmax = eig.eigenvalues()(5);
    if (!M.allFinite() || !(lmin > 1e-12 * lmax)) {
      // Name the joint the null direction moves most, and the fields that give it inertia.
      int j = 0;
      eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&j);
      const int body = phantom_actuated_tree_joint(j);
      r.fail("joints.armature_kg_m2[" + std::to_string(j) + "] / bodies." +
                 phantom_tree_body_name(body) + ".inertia_kg_m2",
             "mass matrix M(q) is not positive definite at q = " + vec_str(q) +
                 " (smallest eigenvalue " + num(lmin) + ", largest " + num(lmax) + ", joint q" +
                 std::to_string(j + 1) + " has no inertia)");
    }
  }
}

}  // namespace dentsim
