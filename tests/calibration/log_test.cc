// Calibration log (calibration/log.h): exact round trip and one clear error per bad-log case.
#include "calibration/log.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

using ::testing::HasSubstr;

CalibrationLog sine_log(int n) {
  CalibrationLog log;
  for (int k = 0; k < n; ++k) {
    const double t = 1e-3 * k;
    Vec6 q, qd, tau;
    for (int j = 0; j < 6; ++j) {
      q(j) = 0.1 * std::sin(2.0 * t + j) + 1.0 / 3.0;
      qd(j) = 0.2 * std::cos(2.0 * t + j);
      tau(j) = 0.01 * j - 0.1 * t;
    }
    log.t.push_back(t);
    log.q.push_back(q);
    log.qd.push_back(qd);
    log.tau.push_back(tau);
  }
  return log;
}

void add_cell(std::string& s, const std::string& x) {
  s += ',';
  s += x;
}

std::string error_of(const std::string& text) {
  try {
    parse_calibration_log(text, "bad.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CalibLog, RoundTripIsExact) {
  CalibrationLog log = sine_log(2000);
  log.comments.push_back(" device: test");
  const CalibrationLog back = parse_calibration_log(calibration_log_to_text(log), "mem");
  ASSERT_EQ(back.size(), log.size());
  for (int k = 0; k < log.size(); ++k) {
    ASSERT_EQ(back.t[k], log.t[k]);
    ASSERT_EQ(back.q[k], log.q[k]);
    ASSERT_EQ(back.qd[k], log.qd[k]);
    ASSERT_EQ(back.tau[k], log.tau[k]);
  }
}

TEST(CalibLog, ColumnsAreFoundByName) {
  // Reversed column order plus an extra column.
  const auto cols = calibration_log_columns();
  std::string text = "extra";
  for (auto it = cols.rbegin(); it != cols.rend(); ++it) add_cell(text, *it);
  text += "\n";
  const CalibrationLog ref = sine_log(300);
  for (int k = 0; k < ref.size(); ++k) {
    text += "7";
    for (int j = 5; j >= 0; --j) add_cell(text, std::to_string(ref.tau[k](j)));
    for (int j = 5; j >= 0; --j) add_cell(text, std::to_string(ref.qd[k](j)));
    for (int j = 5; j >= 0; --j) add_cell(text, std::to_string(ref.q[k](j)));
    add_cell(text, std::to_string(ref.t[k]));
    text += '\n';
  }
  const CalibrationLog log = parse_calibration_log(text, "mem");
  EXPECT_NEAR(log.q[100](2), ref.q[100](2), 1e-6);
  EXPECT_NEAR(log.tau[100](5), ref.tau[100](5), 1e-6);
  EXPECT_NEAR(log.t[100], ref.t[100], 1e-6);
}

TEST(CalibLog, MissingColumnIsNamed) {
  std::string text = calibration_log_to_text(sine_log(300));
  const auto pos = text.find("qd3_rad_s,");
  text.replace(pos, 10, "qdX_rad_s,");
  EXPECT_THAT(error_of(text), HasSubstr("missing column(s) qd3_rad_s"));
  EXPECT_THAT(error_of(text), HasSubstr("bad.csv: line 2: header"));
}

TEST(CalibLog, NanIsNamedWithLineAndColumn) {
  CalibrationLog log = sine_log(300);
  log.qd[10](1) = std::nan("");
  // The header is line 2 (one comment line): sample 10 is on line 13.
  EXPECT_THAT(error_of(calibration_log_to_text(log)),
              HasSubstr("bad.csv: line 13: column qd2_rad_s: expected a finite number, got 'nan'"));
}

TEST(CalibLog, DuplicateColumnIsAnError) {
  // A second q2_rad column used to be taken silently (the last one won).
  std::string text = calibration_log_to_text(sine_log(300));
  const auto h = text.find("t_s,");
  text.insert(h + 4, "q2_rad,");
  EXPECT_THAT(error_of(text),
              HasSubstr("bad.csv: line 2: header: column 'q2_rad' given twice (columns 2 and 4)"));
}

TEST(CalibLog, HugeValuesAreNamed) {
  // One velocity or torque cell of 1e300 used to crash the fit or make it "converge" with an
  // infinite residual (issue #18).
  CalibrationLog log = sine_log(300);
  log.qd[10](2) = 1e300;
  EXPECT_THAT(error_of(calibration_log_to_text(log)),
              HasSubstr("bad.csv: line 13: column qd3_rad_s: |value| must be at most 10000, "
                        "got 1.0000000000000001e+300"));
  log = sine_log(300);
  log.tau[20](5) = -1e300;
  EXPECT_THAT(error_of(calibration_log_to_text(log)),
              HasSubstr("line 23: column tau6_n_m: |value| must be at most 100, got"));
  log = sine_log(300);
  log.q[30](0) = 101.0;
  EXPECT_THAT(error_of(calibration_log_to_text(log)),
              HasSubstr("line 33: column q1_rad: |value| must be at most 100, got 101"));
}

TEST(CalibLog, GarbageIsEscapedInTheMessage) {
  CalibrationLog log = sine_log(300);
  std::string text = calibration_log_to_text(log);
  const auto l3 = text.find('\n', text.find('\n') + 1) + 1;
  text.replace(l3, text.find(',', l3) - l3, "\x1b[2J");
  EXPECT_THAT(error_of(text), HasSubstr("line 3: column t_s: expected a finite number, got "
                                        "'\\x1b[2J'"));
}

TEST(CalibLog, NonMonotonicTimeIsNamed) {
  CalibrationLog log = sine_log(300);
  log.t[50] = log.t[49];
  EXPECT_THAT(error_of(calibration_log_to_text(log)),
              HasSubstr("line 53: column t_s: time must increase strictly"));
}

TEST(CalibLog, TooShortIsNamed) {
  EXPECT_THAT(error_of(calibration_log_to_text(sine_log(150))),
              HasSubstr("too short: 150 samples, expected at least 200"));
}

TEST(CalibLog, JointThatNeverMovesIsNamed) {
  CalibrationLog log = sine_log(300);
  for (auto& q : log.q) q(3) = 0.25;
  EXPECT_THAT(error_of(calibration_log_to_text(log)), HasSubstr("joint 4 never moves"));
}

TEST(CalibLog, ShortRowAndGarbageAreNamed) {
  std::string text = calibration_log_to_text(sine_log(300));
  std::string cut = text;
  const auto l5 = cut.find('\n', cut.find('\n', cut.find('\n', cut.find('\n') + 1) + 1) + 1);
  // Truncate line 5 after its first value.
  const auto comma = cut.find(',', l5 + 1);
  const auto eol = cut.find('\n', l5 + 1);
  cut.erase(comma, eol - comma);
  EXPECT_THAT(error_of(cut), HasSubstr("line 5: expected 19 values, got 1"));
  EXPECT_THAT(error_of("t_s\n1\n"), HasSubstr("missing column(s) q1_rad"));
  EXPECT_THAT(error_of(""), HasSubstr("no header line"));
}


// A log cut short (issue #33) says so in its header, and reads back with the reason; a complete
// log has no such line.
TEST(CalibLog, IncompleteMarkRoundTrips) {
  CalibrationLog log = sine_log(300);
  log.comments = {" device: x"};
  EXPECT_EQ(calibration_log_to_text(log).find("incomplete"), std::string::npos);
  EXPECT_TRUE(parse_calibration_log(calibration_log_to_text(log), "mem").incomplete.empty());
  log.incomplete = "device fault hd_comm_error at t = 0.300 s";
  const std::string text = calibration_log_to_text(log);
  EXPECT_EQ(text.rfind("# dentsim calibration log v1 (columns: docs/calibration.md)\n"
                       "# incomplete: device fault hd_comm_error at t = 0.300 s\n",
                       0),
            0u)
      << text;
  const CalibrationLog back = parse_calibration_log(text, "mem");
  EXPECT_EQ(back.incomplete, log.incomplete);
  EXPECT_EQ(back.comments.back(), log.comments.back());
  const std::string again = calibration_log_to_text(back);
  EXPECT_EQ(again.find("# incomplete: "), again.rfind("# incomplete: "));  // written once
  // Too short to fit: the error says it was cut short.
  log = sine_log(50);
  log.incomplete = "interrupted at t = 0.050 s";
  try {
    parse_calibration_log(calibration_log_to_text(log), "cut.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("too short: 50 samples"));
    EXPECT_THAT(e.what(), HasSubstr("(marked incomplete: interrupted at t = 0.050 s)"));
  }
}

}  // namespace
}  // namespace dentsim
