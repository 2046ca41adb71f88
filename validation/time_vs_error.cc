#include "validation/time_vs_error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "sim/scene.h"
#include "sim/simulator.h"
#include "fast/registry.h"
#include "reference/core/io.h"

namespace dentsim {
namespace {

std::string rate_name(double hz) {
  char b[32];
  if (std::fmod(hz, 1000.0) == 0.0) {
    std::snprintf(b, sizeof(b), "%gkHz", hz / 1000.0);
  } else {
    std::snprintf(b, sizeof(b), "%gHz", hz);
  }
  return b;
}

// "fast@1kHz/r128", "fast-float@1kHz/r128", "reference@8kHz/r512".
std::string name_of(const BenchSettings& s) {
  return s.pipeline + (s.float_device_terms ? "-float" : "") + "@" + rate_name(s.tick_hz) + "/r" +
         std::to_string(s.resolution);
}

bool same(const BenchSettings& a, const BenchSettings& b) { return name_of(a) == name_of(b); }

// The base and every one-setting change of it, without repeats and without the finest run.
std::vector<BenchSettings> variant_settings(const TimeVsErrorConfig& c) {
  std::vector<BenchSettings> v;
  auto add = [&](const BenchSettings& s) {
    if (same(s, c.finest)) return;
    for (const BenchSettings& o : v) {
      if (same(o, s)) return;
    }
    v.push_back(s);
  };
  add(c.base);
  BenchSettings ref = c.base;
  ref.pipeline = "reference";
  ref.float_device_terms = false;
  add(ref);
  for (double hz : {1000.0, 2000.0, 4000.0, 8000.0}) {
    BenchSettings s = c.base;
    s.tick_hz = hz;
    add(s);
  }
  for (int res : {64, 128, 256, 512}) {
    BenchSettings s = c.base;
    s.resolution = res;
    add(s);
  }
  const Implementation* impl = find_implementation(c.base.pipeline);
  if (impl != nullptr && impl->phantom_model_float != nullptr && !c.base.float_device_terms) {
    BenchSettings s = c.base;
    s.float_device_terms = true;
    add(s);
  }
  return v;
}

void check_settings(const BenchSettings& s, const std::string& what) {
  if (find_stage_table(s.pipeline) == nullptr) {
    throw InputError(what + ": unknown pipeline '" + s.pipeline + "' (expected one of " +
                     stage_table_names() + ")");
  }
  if (!(s.tick_hz >= 100.0 && s.tick_hz <= 20000.0)) {
    throw InputError(what + ": tick rate must be within [100, 20000] Hz");
  }
  if (s.resolution < 32 || s.resolution > 512 || (s.resolution & (s.resolution - 1)) != 0) {
    throw InputError(what + ": resolution must be a power of two from 32 to 512");
  }
  if (s.float_device_terms && find_implementation(s.pipeline)->phantom_model_float == nullptr) {
    throw InputError(what + ": float device terms exist in the fast pipeline only");
  }
}

struct Run {
  BenchVariant v;
  std::vector<double> t;  // tick start times [s]
  std::vector<Vec3> f;    // force fed back to the device over the tick (T1, world) [N]
};

Run simulate(const TimeVsErrorConfig& c, const BenchSettings& s) {
  nlohmann::json patch = {{"tick_hz", s.tick_hz}, {"tooth", {{"resolution", s.resolution}}}};
  if (!c.contact_model.empty()) patch["tooth"]["contact_model"] = c.contact_model;
  const Scene scene = load_scene_patched(c.scene, patch, "(" + name_of(s) + ")");
  RunOptions ro;
  ro.pipeline = s.pipeline;
  ro.float_device_terms = s.float_device_terms;
  ro.duration_override = c.duration_s;
  const RunResult r = run_scene(scene, ro);
  if (!r.faults.empty()) {
    throw std::runtime_error("time vs error: the run " + name_of(s) +
                             " faulted: " + r.faults.front());
  }
  Run run;
  run.v.name = name_of(s);
  run.v.settings = s;
  run.v.ticks = r.ticks;
  run.v.simulated_s = r.simulated_s;
  for (const auto& [stage, st] : r.timing) {
    if (stage == "tick") {
      run.v.tick_us_median = st.median_us;
      run.v.tick_us_p99 = st.p99_us;
      run.v.tick_us_mean = st.mean_us;
    } else if (stage == "servo_tick") {
      run.v.servo_tick_us_median = st.median_us;
      run.v.servo_tick_us_p99 = st.p99_us;
    }
  }
  run.v.field_edit_servo_takeovers = r.field_edit_servo_takeovers;
  run.v.field_edit_worker_waits = r.field_edit_worker_waits;
  run.v.cpu_s_per_simulated_s =
      r.simulated_s > 0.0 ? 1e-6 * run.v.tick_us_mean * static_cast<double>(r.ticks) / r.simulated_s
                          : 0.0;
  run.v.removed_volume_mm3 = r.removed_volume_total_mm3;
  run.t.reserve(r.series.size());
  run.f.reserve(r.series.size());
  for (const RunSample& smp : r.series) {
    run.t.push_back(smp.t);
    run.f.push_back(smp.device_force);
    run.v.max_force_n = std::max(run.v.max_force_n, smp.device_force.norm());
  }
  return run;
}

// A run as a job's JSON and back, exactly: finite doubles round-trip through JSON numbers bit for
// bit; NaN and the infinities, which JSON lacks, go as strings. The force errors are not sent:
// they are computed after the gather (compare).
nlohmann::json wire(double x) {
  if (std::isfinite(x)) return x;
  return std::isnan(x) ? (std::signbit(x) ? "-nan" : "nan") : (x > 0 ? "inf" : "-inf");
}

double from_wire(const nlohmann::json& j) {
  if (!j.is_string()) return j.get<double>();
  const std::string s = j.get<std::string>();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  if (s == "nan" || s == "-nan") return s == "nan" ? nan : -nan;
  if (s == "inf" || s == "-inf") return s == "inf" ? inf : -inf;
  throw std::runtime_error("bench job result: expected a number, got '" + s + "'");
}

nlohmann::json run_to_wire(const Run& run) {
  const BenchVariant& v = run.v;
  nlohmann::json t = nlohmann::json::array(), f = nlohmann::json::array();
  for (double x : run.t) t.push_back(wire(x));
  for (const Vec3& x : run.f) {
    for (int i = 0; i < 3; ++i) f.push_back(wire(x[i]));
  }
  return {{"name", v.name},
          {"pipeline", v.settings.pipeline},
          {"tick_hz", wire(v.settings.tick_hz)},
          {"resolution", v.settings.resolution},
          {"float_device_terms", v.settings.float_device_terms},
          {"ticks", v.ticks},
          {"simulated_s", wire(v.simulated_s)},
          {"tick_us", {wire(v.tick_us_median), wire(v.tick_us_p99), wire(v.tick_us_mean)}},
          {"servo_tick_us", {wire(v.servo_tick_us_median), wire(v.servo_tick_us_p99)}},
          {"stand_ins", {v.field_edit_servo_takeovers, v.field_edit_worker_waits}},
          {"cpu_s_per_simulated_s", wire(v.cpu_s_per_simulated_s)},
          {"removed_volume_mm3", wire(v.removed_volume_mm3)},
          {"max_force_n", wire(v.max_force_n)},
          {"t", t},
          {"f", f}};
}

Run run_from_wire(const nlohmann::json& j) {
  Run run;
  BenchVariant& v = run.v;
  v.name = j.at("name").get<std::string>();
  v.settings.pipeline = j.at("pipeline").get<std::string>();
  v.settings.tick_hz = from_wire(j.at("tick_hz"));
  v.settings.resolution = j.at("resolution").get<int>();
  v.settings.float_device_terms = j.at("float_device_terms").get<bool>();
  v.ticks = j.at("ticks").get<long>();
  v.simulated_s = from_wire(j.at("simulated_s"));
  const nlohmann::json& tick = j.at("tick_us");
  v.tick_us_median = from_wire(tick.at(0));
  v.tick_us_p99 = from_wire(tick.at(1));
  v.tick_us_mean = from_wire(tick.at(2));
  const nlohmann::json& servo = j.at("servo_tick_us");
  v.servo_tick_us_median = from_wire(servo.at(0));
  v.servo_tick_us_p99 = from_wire(servo.at(1));
  const nlohmann::json& stand_ins = j.at("stand_ins");
  v.field_edit_servo_takeovers = stand_ins.at(0).get<long>();
  v.field_edit_worker_waits = stand_ins.at(1).get<long>();
  v.cpu_s_per_simulated_s = from_wire(j.at("cpu_s_per_simulated_s"));
  v.removed_volume_mm3 = from_wire(j.at("removed_volume_mm3"));
  v.max_force_n = from_wire(j.at("max_force_n"));
  const nlohmann::json& t = j.at("t");
  const nlohmann::json& f = j.at("f");
  if (f.size() != 3 * t.size())
    throw std::runtime_error("bench job result: t and f differ in size");
  run.t.reserve(t.size());
  run.f.reserve(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    run.t.push_back(from_wire(t[i]));
    run.f.push_back(Vec3(from_wire(f[3 * i]), from_wire(f[3 * i + 1]), from_wire(f[3 * i + 2])));
  }
  return run;
}

// The zero-order hold of (t, f) (f_i held over [t_i, t_i+1)) and its integral from t_0.
struct Held {
  const Run& r;
  std::vector<Vec3> prefix;  // prefix[i] = integral of f from t_0 to t_i
  explicit Held(const Run& run) : r(run), prefix(run.t.size(), Vec3::Zero()) {
    for (std::size_t i = 1; i < r.t.size(); ++i) {
      prefix[i] = prefix[i - 1] + r.f[i - 1] * (r.t[i] - r.t[i - 1]);
    }
  }
  std::size_t index(double at) const {  // the last sample at or before `at` (0 before t_0)
    const auto it = std::upper_bound(r.t.begin(), r.t.end(), at + 1e-12);
    return it == r.t.begin() ? 0 : static_cast<std::size_t>(it - r.t.begin()) - 1;
  }
  const Vec3& value(double at) const { return r.f[index(at)]; }
  Vec3 integral(double at) const {
    const std::size_t i = index(at);
    return prefix[i] + r.f[i] * std::max(0.0, at - r.t[i]);
  }
  // The mean over [at - w, at] (w = 0: the held value).
  Vec3 mean(double at, double w) const {
    if (w <= 0.0) return value(at);
    const double from = std::max(r.t.front(), at - w);
    if (at <= from) return value(at);
    return (integral(at) - integral(from)) / (at - from);
  }
};

void compare(const Run& finest, Run& run, double dt, double smooth) {
  if (run.t.empty() || finest.t.empty()) return;
  const double end = std::min(run.t.back(), finest.t.back());
  const long n = static_cast<long>(std::floor(end / dt + 1e-9)) + 1;
  const Held a(run), b(finest);
  double sum2 = 0.0, worst = 0.0, raw2 = 0.0, raw_worst = 0.0;
  for (long k = 0; k < n; ++k) {
    const double at = static_cast<double>(k) * dt;
    const double e = (a.mean(at, smooth) - b.mean(at, smooth)).norm();
    sum2 += e * e;
    worst = std::max(worst, e);
    const double e_raw = (a.value(at) - b.value(at)).norm();
    raw2 += e_raw * e_raw;
    raw_worst = std::max(raw_worst, e_raw);
  }
  run.v.force_rms_error_n = std::sqrt(sum2 / static_cast<double>(n));
  run.v.force_max_error_n = worst;
  run.v.force_rms_error_raw_n = std::sqrt(raw2 / static_cast<double>(n));
  run.v.force_max_error_raw_n = raw_worst;
  run.v.removed_volume_error_mm3 = std::abs(run.v.removed_volume_mm3 - finest.v.removed_volume_mm3);
}

nlohmann::json settings_json(const BenchSettings& s) {
  return {{"pipeline", s.pipeline},
          {"tick_hz", s.tick_hz},
          {"resolution", s.resolution},
          {"precision", s.float_device_terms ? "float device terms" : "double"}};
}

}  // namespace

std::vector<std::string> time_vs_error_variant_names(const TimeVsErrorConfig& config) {
  std::vector<std::string> names{name_of(config.finest)};
  for (const BenchSettings& s : variant_settings(config)) names.push_back(name_of(s));
  return names;
}

TimeVsErrorResult run_time_vs_error(
    const TimeVsErrorConfig& config,
    const std::function<void(int, int, const std::string&)>& progress,
    const BenchJobRunner& runner) {
  check_settings(config.base, "time vs error base");
  check_settings(config.finest, "time vs error finest run");
  if (!(config.compare_dt_s > 0.0) || !std::isfinite(config.compare_dt_s)) {
    throw InputError("time vs error: the comparison grid must be a positive time");
  }
  if (!(config.smooth_s >= 0.0) || !std::isfinite(config.smooth_s)) {
    throw InputError("time vs error: the smoothing window must be a time >= 0");
  }
  if (config.duration_s < 0.0 || !std::isfinite(config.duration_s)) {
    throw InputError("time vs error: the duration must be finite and >= 0");
  }
  std::vector<BenchSettings> runs;
  const std::vector<BenchSettings> all = variant_settings(config);
  if (config.only.empty()) {
    runs = all;
  } else {
    for (const std::string& want : config.only) {
      bool found = want == name_of(config.finest);
      for (const BenchSettings& s : all) {
        if (name_of(s) == want) {
          found = true;
          runs.push_back(s);
        }
      }
      if (!found) {
        std::string known;
        for (const std::string& n : time_vs_error_variant_names(config)) {
          known += (known.empty() ? "" : ", ") + n;
        }
        throw InputError("time vs error: unknown variant '" + want + "' (variants: " + known + ")");
      }
    }
  }
  TimeVsErrorResult res;
  res.config = config;
  res.reference_variant = name_of(config.finest);
  // Job 0 the finest run, job k the k-th variant: independent simulations, compared once all are
  // back (in the order they were run one after the other before).
  std::vector<BenchSettings> jobs{config.finest};
  jobs.insert(jobs.end(), runs.begin(), runs.end());
  const int total = static_cast<int>(jobs.size());
  const auto job = [&](int k) -> nlohmann::json {
    if (progress) progress(k, total, name_of(jobs[k]));
    return run_to_wire(simulate(config, jobs[k]));
  };
  std::vector<nlohmann::json> results;
  if (runner) {
    results = runner(total, job);
  } else {
    for (int k = 0; k < total; ++k) results.push_back(job(k));
  }
  Run finest = run_from_wire(results.at(0));
  compare(finest, finest, config.compare_dt_s,
          config.smooth_s);  // zero by construction; computed all the same
  res.variants.push_back(finest.v);
  for (int k = 1; k < total; ++k) {
    Run run = run_from_wire(results.at(k));
    compare(finest, run, config.compare_dt_s, config.smooth_s);
    res.variants.push_back(run.v);
  }
  if (progress) progress(total, total, "");
  return res;
}

nlohmann::json time_vs_error_json(const TimeVsErrorResult& r) {
  nlohmann::json j;
  j["scene"] = r.config.scene;
  j["contact_model"] = r.config.contact_model;  // "" = the scene's own
  j["duration_s"] = r.config.duration_s;
  j["compare_dt_s"] = r.config.compare_dt_s;
  j["smooth_s"] = r.config.smooth_s;
  j["reference_variant"] = r.reference_variant;
  j["variants"] = nlohmann::json::array();
  for (const BenchVariant& v : r.variants) {
    j["variants"].push_back({{"name", v.name},
                             {"settings", settings_json(v.settings)},
                             {"ticks", v.ticks},
                             {"simulated_s", v.simulated_s},
                             {"tick_us_median", v.tick_us_median},
                             {"tick_us_p99", v.tick_us_p99},
                             {"tick_us_mean", v.tick_us_mean},
                             {"servo_tick_us_median", v.servo_tick_us_median},
                             {"servo_tick_us_p99", v.servo_tick_us_p99},
                             {"field_edit_servo_takeovers", v.field_edit_servo_takeovers},
                             {"field_edit_worker_waits", v.field_edit_worker_waits},
                             {"cpu_s_per_simulated_s", v.cpu_s_per_simulated_s},
                             {"force_rms_error_n", v.force_rms_error_n},
                             {"force_max_error_n", v.force_max_error_n},
                             {"force_rms_error_raw_n", v.force_rms_error_raw_n},
                             {"force_max_error_raw_n", v.force_max_error_raw_n},
                             {"removed_volume_mm3", v.removed_volume_mm3},
                             {"removed_volume_error_mm3", v.removed_volume_error_mm3},
                             {"max_force_n", v.max_force_n}});
  }
  return j;
}

std::string time_vs_error_table(const TimeVsErrorResult& r) {
  // The servo tick's columns: its own time (the field edit's takeovers and waits left out, the
  // tick a real-time servo runs) and how many batches a simulated run's servo stood in for.
  char b[1024];
  std::snprintf(b, sizeof(b),
                "| variant | tick median [us] | tick p99 [us] | servo tick median [us] | servo "
                "tick p99 [us] | field edits stood in for (taken over + waited) | CPU s per "
                "simulated s | force RMS error [N] (%g ms mean) | force max error [N] | "
                "tick-by-tick RMS error [N] | removed volume [mm^3] | its error [mm^3] |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n",
                1e3 * r.config.smooth_s);
  std::string s = b;
  for (const BenchVariant& v : r.variants) {
    std::snprintf(b, sizeof(b),
                  "| %s%s | %.2f | %.2f | %.2f | %.2f | %ld + %ld | %.4f | %.3g | %.3g | %.3g | "
                  "%.3f | %.3g |\n",
                  v.name.c_str(), v.name == r.reference_variant ? " (finest: the yardstick)" : "",
                  v.tick_us_median, v.tick_us_p99, v.servo_tick_us_median, v.servo_tick_us_p99,
                  v.field_edit_servo_takeovers, v.field_edit_worker_waits,
                  v.cpu_s_per_simulated_s, v.force_rms_error_n, v.force_max_error_n,
                  v.force_rms_error_raw_n, v.removed_volume_mm3, v.removed_volume_error_mm3);
    s += b;
  }
  return s;
}

}  // namespace dentsim
