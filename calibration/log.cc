#include "calibration/log.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "reference/core/io.h"

namespace dentsim {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

std::string fmt(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

constexpr const char* kIncompletePrefix = "incomplete:";

std::string column(const char* prefix, int j, const char* suffix) {
  std::string s(prefix);
  s += std::to_string(j);
  s += suffix;
  return s;
}

}  // namespace

std::vector<std::string> calibration_log_columns() {
  std::vector<std::string> c{"t_s"};
  for (int j = 1; j <= kLogJoints; ++j) c.push_back(column("q", j, "_rad"));
  for (int j = 1; j <= kLogJoints; ++j) c.push_back(column("qd", j, "_rad_s"));
  for (int j = 1; j <= kLogJoints; ++j) c.push_back(column("tau", j, "_n_m"));
  return c;
}

std::string calibration_log_to_text(const CalibrationLog& log) {
  std::string s = "# dentsim calibration log v1 (columns: docs/calibration.md)\n";
  if (!log.incomplete.empty()) {
    s += "# " + std::string(kIncompletePrefix) + " " + log.incomplete + "\n";
  }
  for (const auto& c : log.comments) {
    s += '#';
    s += c;
    s += '\n';
  }
  const auto cols = calibration_log_columns();
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (i) s += ',';
    s += cols[i];
  }
  s += "\n";
  for (int k = 0; k < log.size(); ++k) {
    s += fmt(log.t[k]);
    for (const Vec6* v : {&log.q[k], &log.qd[k], &log.tau[k]}) {
      for (int j = 0; j < kLogJoints; ++j) {
        s += ',';
        s += fmt((*v)(j));
      }
    }
    s += "\n";
  }
  return s;
}

void write_calibration_log(const std::string& path, const CalibrationLog& log) {
  write_file_atomic(path, calibration_log_to_text(log));
}

CalibrationLog parse_calibration_log(const std::string& text, const std::string& origin) {
  CalibrationLog log;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  std::map<std::string, int> index;  // column name -> position
  std::vector<int> pos;              // position of each expected column
  std::size_t width = 0;
  const auto cols = calibration_log_columns();
  while (std::getline(in, line)) {
    ++line_no;
    const std::string l = trim(line);
    if (l.empty()) continue;
    if (l[0] == '#') {
      if (index.empty()) {
        const std::string c = trim(l.substr(1));
        if (c.rfind(kIncompletePrefix, 0) == 0) {
          log.incomplete = trim(c.substr(std::string(kIncompletePrefix).size()));
          if (log.incomplete.empty()) log.incomplete = "no reason given";
        } else {
          log.comments.push_back(l.substr(1));
        }
      }
      continue;
    }
    const auto cells = split_csv(l);
    if (index.empty()) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (!index.emplace(cells[i], static_cast<int>(i)).second) {
          throw InputError(origin + ": line " + std::to_string(line_no) + ": header: column '" +
                           printable(cells[i]) + "' given twice (columns " +
                           std::to_string(index[cells[i]] + 1) + " and " + std::to_string(i + 1) +
                           "); expected each column once");
        }
      }
      std::string missing;
      for (const auto& c : cols) {
        if (index.count(c)) {
          pos.push_back(index[c]);
        } else {
          if (!missing.empty()) missing += ", ";
          missing += c;
        }
      }
      if (!missing.empty()) {
        throw InputError(origin + ": line " + std::to_string(line_no) +
                         ": header: missing column(s) " + missing +
                         " (expected t_s, q1_rad..q6_rad, qd1_rad_s..qd6_rad_s, "
                         "tau1_n_m..tau6_n_m)");
      }
      width = cells.size();
      continue;
    }
    if (cells.size() < width) {
      throw InputError(origin + ": line " + std::to_string(line_no) + ": expected " +
                       std::to_string(width) + " values, got " + std::to_string(cells.size()));
    }
    double v[1 + 3 * kLogJoints];
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const std::string& cell = cells[pos[c]];
      double x = 0.0;
      const auto res = std::from_chars(cell.data(), cell.data() + cell.size(), x);
      const bool parsed = res.ec == std::errc() && res.ptr == cell.data() + cell.size();
      if (!parsed || !std::isfinite(x)) {
        throw InputError(origin + ": line " + std::to_string(line_no) + ": column " + cols[c] +
                         ": expected a finite number, got '" + printable(cell) + "'");
      }
      const double limit = c == 0                ? kMaxLogTime
                           : c <= kLogJoints     ? kMaxLogAngle
                           : c <= 2 * kLogJoints ? kMaxLogVelocity
                                                 : kMaxLogTorque;
      if (!(std::abs(x) <= limit)) {
        throw InputError(origin + ": line " + std::to_string(line_no) + ": column " + cols[c] +
                         ": |value| must be at most " + fmt(limit) + ", got " + fmt(x));
      }
      v[c] = x;
    }
    if (!log.t.empty() && !(v[0] > log.t.back())) {
      throw InputError(origin + ": line " + std::to_string(line_no) +
                       ": column t_s: time must increase strictly, got " + fmt(v[0]) + " after " +
                       fmt(log.t.back()));
    }
    log.t.push_back(v[0]);
    Vec6 q, qd, tau;
    for (int j = 0; j < kLogJoints; ++j) {
      q(j) = v[1 + j];
      qd(j) = v[1 + kLogJoints + j];
      tau(j) = v[1 + 2 * kLogJoints + j];
    }
    log.q.push_back(q);
    log.qd.push_back(qd);
    log.tau.push_back(tau);
  }
  if (index.empty()) throw InputError(origin + ": no header line (expected " + cols[0] + ",...)");
  if (log.size() < kMinLogSamples) {
    throw InputError(origin + ": too short: " + std::to_string(log.size()) +
                     " samples, expected at least " + std::to_string(kMinLogSamples) +
                     (log.incomplete.empty() ? "" : " (marked incomplete: " + log.incomplete + ")"));
  }
  for (int j = 0; j < kLogJoints; ++j) {
    double lo = log.q[0](j), hi = lo;
    for (const auto& q : log.q) {
      lo = std::min(lo, q(j));
      hi = std::max(hi, q(j));
    }
    if (hi - lo < kMinJointRange) {
      throw InputError(origin + ": column q" + std::to_string(j + 1) + "_rad: joint " +
                       std::to_string(j + 1) + " never moves (range " + fmt(hi - lo) +
                       " rad, expected at least " + fmt(kMinJointRange) +
                       " rad): its parameters cannot be identified");
    }
  }
  return log;
}

CalibrationLog read_calibration_log(const std::string& path) {
  return parse_calibration_log(read_file(path), path);
}

}  // namespace dentsim
