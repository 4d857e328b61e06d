// Torque-log reading: every kind of bad log gets a message naming file, line/column and reason.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/torque_log.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/torque_log_file.h"

namespace fivebar::identification {
namespace {

using io::CsvTable;
using io::parse_csv;
using io::parse_torque_log;
using io::read_torque_log;
using io::write_torque_log;

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const char* const kHeader = "t,theta1,theta2,tau1,tau2\n";

/// A well-formed log of n samples at 1 kHz with slowly turning cranks (radians).
std::string good_log(int n, bool rates = false) {
  std::ostringstream s;
  s << "# comment line\n" << (rates ? "t,theta1,theta2,tau1,tau2,omega1,omega2\n" : kHeader);
  for (int i = 0; i < n; ++i) {
    const double t = i * 1e-3;
    s << t << "," << 1.5 + 0.5 * t << "," << 1.6 - 0.3 * t << ",1.0,2.0";
    if (rates) s << ",0.5,-0.3";
    s << "\n";
  }
  return s.str();
}

TEST(TorqueLog, ReadsAGoodLogWithCommentsAndRates) {
  const TorqueLog log = parse_torque_log(good_log(10, true), "good.csv");
  EXPECT_EQ(log.size(), 10);
  EXPECT_TRUE(log.has_rates);
  EXPECT_FALSE(log.has_accels);
  EXPECT_EQ(log.lines.front(), 3);  // comment and header come first
  EXPECT_EQ(log.comments.size(), 1u);
}

TEST(TorqueLog, AByteOrderMarkIsNotPartOfTheFirstLine) {
  // spreadsheet programs start UTF-8 files with EF BB BF: before a comment or before the header
  const TorqueLog with_comment = parse_torque_log("\xEF\xBB\xBF" + good_log(10), "bom.csv");
  EXPECT_EQ(with_comment.size(), 10);
  EXPECT_EQ(with_comment.comments.size(), 1u);
  const std::string no_comment = good_log(10).substr(good_log(10).find('\n') + 1);
  EXPECT_EQ(parse_torque_log("\xEF\xBB\xBF" + no_comment, "bom.csv").size(), 10);
}

TEST(TorqueLog, RatesThatDoNotMatchTheAnglesNameTheColumn) {
  // rates of the opposite sign, or in rpm: the log is refused with the column and the ratio
  std::string flipped = good_log(50, true), rpm = good_log(50, true);
  for (size_t at = 0; (at = flipped.find(",0.5,-0.3", at)) != std::string::npos; ++at) {
    flipped.replace(at, 9, ",-0.5,0.3");
  }
  for (size_t at = 0; (at = rpm.find(",0.5,-0.3", at)) != std::string::npos; ++at) {
    rpm.replace(at, 9, ",4.775,-0.3");
  }
  EXPECT_THAT([&] { parse_torque_log(flipped, "flipped.csv"); },
              ThrowsMessage<std::runtime_error>(AllOf(HasSubstr("flipped.csv"),
                                                      HasSubstr("column omega1"),
                                                      HasSubstr("a median -1 times"))));
  EXPECT_THAT([&] { parse_torque_log(rpm, "rpm.csv"); },
              ThrowsMessage<std::runtime_error>(HasSubstr("column omega1")));
  EXPECT_NO_THROW(parse_torque_log(good_log(50, true), "good.csv"));
}

/// A log of n samples at 1 kHz with uniformly accelerating cranks (alpha 2 rad/s^2 and -1.2),
/// its logged accelerations scaled by `scale` and offset by `offset` from sample `from` on.
std::string accelerating_log(int n, double scale, double offset = 0, int from = 0) {
  std::ostringstream s;
  s.precision(17);
  s << "t,theta1,theta2,tau1,tau2,omega1,omega2,alpha1,alpha2\n";
  for (int i = 0; i < n; ++i) {
    const double t = i * 1e-3;
    s << t << "," << 1.5 + 0.5 * t + t * t << "," << 1.6 - 0.3 * t - 0.6 * t * t << ",1.0,2.0,"
      << 0.5 + 2 * t << "," << -0.3 - 1.2 * t << "," << 2 * scale + (i >= from ? offset : 0)
      << "," << -1.2 * scale << "\n";
  }
  return s.str();
}

// accelerations in deg/s^2, or offset from mid-log, if fitted, put both coefficients at their
// bounds ("lag by nan ms"); they are refused naming the column and what was seen
TEST(TorqueLog, AccelerationsThatDoNotMatchTheAnglesNameTheColumn) {
  EXPECT_NO_THROW(parse_torque_log(accelerating_log(1000, 1.0), "good.csv"));
  EXPECT_THAT([&] { parse_torque_log(accelerating_log(1000, 180 / M_PI), "deg.csv"); },
              ThrowsMessage<std::runtime_error>(
                  AllOf(HasSubstr("deg.csv"), HasSubstr("column alpha1"),
                        HasSubstr("a median 0.0175 times the logged acceleration"))));
  EXPECT_THAT([&] { parse_torque_log(accelerating_log(1000, 1.0, 0.4, 500), "offset.csv"); },
              ThrowsMessage<std::runtime_error>(
                  AllOf(HasSubstr("column alpha1"), HasSubstr("a median 0.4 rad/s^2 off"))));
}

TEST(TorqueLog, WriteThenReadRoundTrips) {
  TorqueLog log = parse_torque_log(good_log(5, true), "good.csv");
  log.comments = {" made by a test"};
  const std::string path = ::testing::TempDir() + "/roundtrip.csv";
  write_torque_log(path, log);
  const TorqueLog back = read_torque_log(path);
  EXPECT_EQ(back.theta1, log.theta1);
  EXPECT_EQ(back.omega2, log.omega2);
  EXPECT_EQ(back.comments, log.comments);
  std::remove(path.c_str());
}

/// A malformed log and the parts its one-line message must have (file, line/column, reason).
struct BadLog {
  const char* what;
  std::string text;
  std::vector<std::string> parts;
};

const BadLog kBadLogs[] = {
    {"NaN", std::string(kHeader) + "0,1,1,1,1\n0.001,1,1,nan,1\n",
     {"bad.csv: line 3, column tau1", "not a finite number"}},
    {"text in a number field", std::string(kHeader) + "0,1,1,1,abc\n",
     {"bad.csv: line 2, column tau2: 'abc'"}},
    {"time not increasing",
     std::string(kHeader) + "0,1,1,1,1\n0.001,1,1,1,1\n0.001,1,1,1,1\n",
     {"bad.csv: line 4, column t", "not strictly increasing"}},
    {"time in milliseconds", std::string(kHeader) + "0,1,1,1,1\n1,1,1,1,1\n2,1,1,1,1\n",
     {"bad.csv: column t", "median time step 1:", "look like milliseconds"}},
    {"time in milliseconds at 5 kHz",
     std::string(kHeader) + "0,1,1,1,1\n0.2,1.0001,1,1,1\n0.4,1.0002,1,1,1\n",
     {"bad.csv: column t", "median time step 0.2 under which no crank turns faster than 0.05"}},
    {"missing column", "t,theta1,theta2,tau1\n0,1,1,1\n",
     {"bad.csv: header: missing column 'tau2'"}},
    {"unknown column", "t,theta1,theta2,tau1,tau2,current\n0,1,1,1,1,1\n",
     {"bad.csv: line 1, column 6", "unknown column 'current'"}},
    {"unpaired rate column", "t,theta1,theta2,tau1,tau2,omega1\n0,1,1,1,1,1\n",
     {"'omega1' without 'omega2'"}},
    {"wrong field count", std::string(kHeader) + "0,1,1,1\n",
     {"bad.csv: line 2: expected 5 fields, got 4"}},
    {"empty file", "# only a comment\n", {"bad.csv: header: empty file"}},
    {"no rows", kHeader, {"bad.csv: samples: no data rows"}},
};

TEST(TorqueLog, AFourBarLogHasOneCrank) {
  // dof 1: t, theta1, tau1 and optional omega1, alpha1; written back with the same columns
  const std::string text = "t,theta1,tau1,omega1\n0,1,0.5,0\n0.001,1.0001,0.5,0.1\n";
  TorqueLog log = parse_torque_log(text, "four.csv", 1);
  EXPECT_EQ(log.dof, 1);
  EXPECT_EQ(log.size(), 2);
  EXPECT_TRUE(log.has_rates);
  EXPECT_TRUE(log.theta2.empty());
  const std::string path = ::testing::TempDir() + "/four_bar_log.csv";
  write_torque_log(path, log);
  const CsvTable table = io::read_csv(path);
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "theta1", "tau1", "omega1"}));
  EXPECT_EQ(read_torque_log(path, 1).omega1, log.omega1);
  std::remove(path.c_str());
}

TEST(TorqueLog, ALogOfTheOtherMechanismNamesTheColumnAndTheMechanism) {
  EXPECT_THAT([] { parse_torque_log(good_log(5), "five.csv", 1); },
              ThrowsMessage<LogError>(AllOf(
                  HasSubstr("five.csv: line 2, column 3"),
                  HasSubstr("column 'theta2' does not belong to this mechanism"),
                  HasSubstr("a four-bar's torque log (one crank) has t,theta1,tau1"))));
  EXPECT_THAT([] { parse_torque_log("t,theta1,tau1\n0,1,1\n", "four.csv"); },
              ThrowsMessage<LogError>(AllOf(
                  HasSubstr("four.csv: header: missing column 'theta2'"),
                  HasSubstr("a five-bar's torque log has t,theta1,theta2,tau1,tau2"))));
}

TEST(TorqueLog, EveryMalformedLogNamesFileLineColumnAndReason) {
  for (const BadLog& bad : kBadLogs) {
    SCOPED_TRACE(bad.what);
    try {
      parse_torque_log(bad.text, "bad.csv");
      ADD_FAILURE() << "accepted";
    } catch (const LogError& e) {
      for (const std::string& part : bad.parts) EXPECT_THAT(e.what(), HasSubstr(part));
    }
  }
}

TEST(Csv, OneParserKeepsCommentsLinesAndHeader) {
  // the parser under read_torque_log and the apps' io::read_csv (tests/apps/test_output.cc)
  const CsvTable t =
      parse_csv("# made by hand\n\n t , theta1 \n0,1\n# mid\n0.5, 2 \n", "m.csv");
  EXPECT_EQ(t.header_line, 3);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"t", "theta1"}));
  EXPECT_EQ(t.lines, (std::vector<int>{4, 6}));
  EXPECT_EQ(t.rows.back(), (std::vector<double>{0.5, 2.0}));
  EXPECT_EQ(t.comments, (std::vector<std::string>{" made by hand", " mid"}));
  EXPECT_EQ(parse_csv("# only a comment\n", "m.csv").header_line, 0);
  EXPECT_THAT([&] { parse_csv("t,theta1\n0,\n", "m.csv"); },
              ThrowsMessage<LogError>(HasSubstr("m.csv: line 2, column theta1: '' is not a")));
  EXPECT_THAT([&] { parse_csv("t,theta1\n0,1,\n", "m.csv"); },
              ThrowsMessage<LogError>(HasSubstr("m.csv: line 2: expected 2 fields, got 3")));
}

TEST(Csv, FieldsReadAsStrtodReadsThem) {
  // every syntax strtod takes, with its value to the last bit; nan and inf only when asked
  const char* fields[] = {"0.1",
                          "-2.5e-3",
                          "+1",
                          "0x1p-3",
                          "1e-320",
                          "1.",
                          ".5",
                          "7",
                          "-0",
                          "0.47600000000000003",
                          "1.5707963267948966"};
  std::string text = "x\n";
  for (const char* f : fields) text += std::string(f) + "\n";
  const CsvTable t = parse_csv(text, "m.csv");
  ASSERT_EQ(t.rows.size(), std::size(fields));
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const double expected = std::strtod(fields[i], nullptr);
    EXPECT_EQ(std::memcmp(&t.rows[i][0], &expected, sizeof expected), 0) << fields[i];
  }
  EXPECT_THAT([&] { parse_csv("x\n1e999\n", "m.csv"); },
              ThrowsMessage<LogError>(HasSubstr("'1e999' is not a finite number")));
  EXPECT_THAT([&] { parse_csv("x\n1e\n", "m.csv"); },
              ThrowsMessage<LogError>(HasSubstr("'1e' is not a finite number")));
  io::CsvRules rules;
  rules.non_finite = true;
  const CsvTable n = parse_csv("x\nnan\n-inf\n", "m.csv", rules);
  EXPECT_TRUE(std::isnan(n.rows[0][0]));
  EXPECT_EQ(n.rows[1][0], -HUGE_VAL);
}

TEST(TorqueLog, MissingFile) {
  EXPECT_THAT([&] { read_torque_log("/nonexistent/log.csv"); },
              ThrowsMessage<LogError>(HasSubstr("/nonexistent/log.csv: (file): cannot open")));
}

TEST(TorqueLog, MultiTurnAnglesAreNotDegrees) {
  // a log cut from the middle of a run starts many turns out: radians all the same (degrees
  // are told from the motion by identify, see test_condition.cc)
  std::ostringstream s;
  s << kHeader;
  for (int i = 0; i < 20; ++i) s << i * 1e-3 << "," << 90 + 0.01 * i << ",90,1,1\n";
  const TorqueLog log = parse_torque_log(s.str(), "turns.csv");
  EXPECT_EQ(log.theta1.front(), 90.0);
}

TEST(TorqueLog, DegreesWithRates) {
  // angles in degrees, rates in rad/s: d theta/dt is 57.3 omega
  std::ostringstream s;
  s << "t,theta1,theta2,tau1,tau2,omega1,omega2\n";
  for (int i = 0; i < 50; ++i) {
    const double t = i * 1e-3, th = 0.5 + 2.0 * t;  // radians, 2 rad/s
    s << t << "," << th * 180 / M_PI << "," << 0.5 << ",1,1,2.0,0.0\n";
  }
  EXPECT_THAT(
      [&] { parse_torque_log(s.str(), "deg.csv"); },
      ThrowsMessage<LogError>(AllOf(HasSubstr("deg.csv: column theta1"), HasSubstr("180/pi"))));
}

TEST(TorqueLog, FewerSamplesThanParameters) {
  const TorqueLog log = parse_torque_log(good_log(2, true) + "", "short.csv");
  IdentifyOptions opt;
  opt.layout.per_joint = true;  // 10 parameters
  const auto loads = [](double) { return Loads<double>{}; };
  EXPECT_THAT([&] { identify(paper_params(), loads, log, opt); },
              ThrowsMessage<LogError>(
                  AllOf(HasSubstr("short.csv: samples: 2 samples"), HasSubstr("10 parameters"))));
}

TEST(TorqueLog, PoseThatCannotAssemble) {
  // short couplers (l3 + l4 = 0.2 m) cannot reach from B = (-0.08, 0) to D = (0.34, 0)
  Params<double> p = paper_params();
  p.links[2].length = p.links[3].length = 0.1;
  p.links[2].com_offset = p.links[3].com_offset = 0.05;
  p.point_p = 0.05;
  // B = (0.08, 0), D = (0.24, 0) assembles; the fifth sample does not
  const std::string text = std::string(kHeader) + "0,0,3.14159,1,1\n0.001,0,3.14159,1,1\n" +
                           "0.002,0,3.14159,1,1\n0.003,0,3.14159,1,1\n0.004,3.14159,0,1,1\n";
  const TorqueLog log = parse_torque_log(text, "pose.csv");
  EXPECT_THAT(
      [&] { check_poses(log, p); },
      ThrowsMessage<LogError>(AllOf(HasSubstr("pose.csv: line 6"), HasSubstr("cannot assemble"))));
}

}  // namespace
}  // namespace fivebar::identification
