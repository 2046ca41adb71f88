// Calibration log (issue #5): what `dentsim excite` records and `dentsim calibrate` reads.
//
// Format: CSV text, one sample per line, '#' lines are comments (the writer puts the device
// model name and the excitation there). The first non-comment line is the header; columns are
// found by name (any order, extra columns ignored):
//     t_s                     sample time [s] (strictly increasing)
//     q1_rad .. q6_rad        joint angles as the encoders report them [rad]
//     qd1_rad_s .. qd6_rad_s  joint velocities as the driver estimates them [rad/s]
//     tau1_n_m .. tau6_n_m    joint torque applied over the tick that starts at t (after
//                             saturation) [N m]
// Device joint order and units as in device/device.h (index 1 = device).
//
// The reader rejects, with an InputError naming the file, the line and the problem: a missing
// or repeated column, a non-numeric or non-finite value, a value beyond the limits below (no
// Phantom reaches them; 1e300 in one cell would otherwise turn the fit's residual infinite), a
// short row, non-monotonic time, a log with fewer than kMinLogSamples samples, and a joint that
// never moves (range of q below kMinJointRange).
#pragma once

#include <string>
#include <vector>

#include "reference/core/types.h"

namespace dentsim {

inline constexpr int kLogJoints = 6;
inline constexpr int kMinLogSamples = 200;
inline constexpr double kMinJointRange = 1e-3;  // [rad]
inline constexpr double kMaxLogTime = 1e6;      // |t| [s]
inline constexpr double kMaxLogAngle = 100.0;   // |q| [rad]
inline constexpr double kMaxLogVelocity = 1e4;  // |qd| [rad/s]
inline constexpr double kMaxLogTorque = 100.0;  // |tau| [N m]

struct CalibrationLog {
  std::vector<double> t;              // [s]
  std::vector<Vec6> q;                // [rad]
  std::vector<Vec6> qd;               // [rad/s]
  std::vector<Vec6> tau;              // [N m]
  std::vector<std::string> comments;  // without the leading '#'
  // Why the log ends early (an excitation stopped by a device fault, a guard or an interruption:
  // "device fault hd_comm_error at t = 2.300 s"); empty for a complete log. Written as the
  // comment line "# incomplete: REASON" right after the format line; `dentsim calibrate` refuses
  // such a log unless --allow-incomplete (calibration/calibrate.h).
  std::string incomplete;

  int size() const { return static_cast<int>(t.size()); }
};

// The column names in the order the writer uses.
std::vector<std::string> calibration_log_columns();

// CSV text of `log` (17 significant digits: re-reads exactly).
std::string calibration_log_to_text(const CalibrationLog& log);
// Writes atomically (nothing is overwritten on failure).
void write_calibration_log(const std::string& path, const CalibrationLog& log);

// Parses and validates; `origin` names the source in error messages.
CalibrationLog parse_calibration_log(const std::string& text, const std::string& origin);
CalibrationLog read_calibration_log(const std::string& path);

}  // namespace dentsim
