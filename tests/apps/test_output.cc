// Output: trajectory.csv columns and numbers, JSON, the atomic output directory, CSV reading,
// finite differences.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fivebar/io/csv.h"
#include "fivebar/io/differences.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"

namespace fivebar::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// a fresh empty directory for one test
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("fivebar_test_apps_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_file(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

TEST(TrajectoryCsv, HeaderIsExactlyTheInterface) {
  const fs::path dir = scratch("header");
  write_trajectory_csv((dir / "t.csv").string(), {});
  EXPECT_EQ(read_file(dir / "t.csv"),
            "t,theta1,theta2,theta3,theta4,omega1,omega2,omega3,omega4,alpha1,alpha2,alpha3,alpha4,"
            "M1,M2,N1,N2,N3,N4,N5,Mf1,Mf2,Mf3,Mf4,Mf5,P_diss,E_diss,W_in,W_ext\n");
}

TEST(TrajectoryCsv, NumbersRoundTripExactly) {
  const fs::path dir = scratch("numbers");
  std::vector<sim::Row> rows(2);
  for (size_t i = 0; i < rows.size(); ++i) {
    sim::Row& r = rows[i];
    r.t = 0.001 * static_cast<double>(i);
    for (int k = 0; k < 4; ++k) {
      r.theta[k] = M_PI / (k + 3) + static_cast<double>(i);
      r.omega[k] = -1.0 / 3 * k;
      r.alpha[k] = 1e-300 * k;
    }
    r.M1 = 0.1;
    r.M2 = -2e20;
    for (int k = 0; k < 5; ++k) {
      r.N[k] = std::sqrt(2.0) * k;
      r.Mf[k] = -std::exp(-k);
    }
    r.P_diss = 1.0 / 7;
    r.E_diss = 2.0 / 7;
    r.W_in = 3.0 / 7;
    r.W_ext = 4.0 / 7;
  }
  write_trajectory_csv((dir / "t.csv").string(), rows, {{"M1_inverse", {1.5, 2.5}}});
  const CsvTable table = read_csv((dir / "t.csv").string());
  ASSERT_EQ(table.columns.size(), trajectory_columns().size() + 1);
  EXPECT_EQ(table.columns.back(), "M1_inverse");
  ASSERT_EQ(table.rows.size(), 2u);
  for (size_t i = 0; i < rows.size(); ++i) {
    const std::vector<double>& v = table.rows[i];
    const sim::Row& r = rows[i];
    EXPECT_EQ(v[table.find("t")], r.t);
    EXPECT_EQ(v[table.find("theta3")], r.theta[2]);
    EXPECT_EQ(v[table.find("omega2")], r.omega[1]);
    EXPECT_EQ(v[table.find("alpha4")], r.alpha[3]);
    EXPECT_EQ(v[table.find("M2")], r.M2);
    EXPECT_EQ(v[table.find("N2")], r.N[1]);
    EXPECT_EQ(v[table.find("Mf5")], r.Mf[4]);
    EXPECT_EQ(v[table.find("P_diss")], r.P_diss);
    EXPECT_EQ(v[table.find("E_diss")], r.E_diss);
    EXPECT_EQ(v[table.find("W_in")], r.W_in);
    EXPECT_EQ(v[table.find("W_ext")], r.W_ext);
  }
  EXPECT_EQ(table.rows[1].back(), 2.5);
  EXPECT_THAT(
      [&] {
        write_trajectory_csv((dir / "u.csv").string(), rows, {{"x", {1.0}}});
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("x: internal")));
}

TEST(Format, ShortestRoundTripAndGridValues) {
  const double t = 476 * 0.001;  // 0.47600000000000003: one ulp above the double nearest 0.476
  EXPECT_EQ(format_double(t), "0.47600000000000003");  // exact: reads back as t
  EXPECT_EQ(std::strtod(format_double(t).c_str(), nullptr), t);
  EXPECT_EQ(format_grid_value(t), "0.476");
  EXPECT_EQ(format_grid_value(0.1 + 0.2), "0.3");
  EXPECT_EQ(format_grid_value(2.0), "2");
  EXPECT_EQ(format_grid_value(0.0), "0");
  EXPECT_EQ(format_grid_value(-1e-10), "-1e-10");
  // a value with no short decimal within one ulp is left exact
  EXPECT_EQ(format_grid_value(M_PI), format_double(M_PI));
  EXPECT_EQ(format_grid_value(NAN), "nan");
  // the t column of trajectory.csv is written that way, the other columns exactly
  const fs::path dir = scratch("grid");
  sim::Row row;
  row.t = t;
  row.theta[0] = t;
  write_trajectory_csv((dir / "t.csv").string(), {row});
  const std::string text = read_file(dir / "t.csv");
  EXPECT_NE(text.find("\n0.476,0.47600000000000003,"), std::string::npos) << text;
}

// the line of `script` that draws `needle` (a series), or ""
std::string line_with(const std::string& script, const std::string& needle) {
  std::stringstream lines(script);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.find(needle) != std::string::npos) return line;
  }
  return "";
}

// the text between the first `key` and the next blank in `line`
std::string value_after(const std::string& line, const std::string& key) {
  const size_t at = line.find(key);
  if (at == std::string::npos) return "";
  const size_t start = at + key.size();
  return line.substr(start, line.find(' ', start) - start);
}

TEST(Plots, WorkPrecisionColourPerIntegratorDashPerTreatment) {
  studies::WorkPrecision wp;
  auto point = [](sim::Method m, studies::Treatment t, double tol, double time, double err) {
    // method, treatment, tolerance, ok, message, error, error_vs_exact, wall time
    return studies::PrecisionPoint{m, t, tol, true, "", err, 0, time};
  };
  using sim::Method;
  using studies::Treatment;
  wp.points = {point(Method::kCvodeAdams, Treatment::kExactLocated, 1e-8, 0.004, 1e-6),
               point(Method::kCvodeAdams, Treatment::kRegularized, 1e-8, 0.003, 2e-6),
               point(Method::kArkodeErk45, Treatment::kExactLocated, 1e-8, 0.009, 1e-9),
               point(Method::kArkodeErk45, Treatment::kRegularized, 1e-8, 0.008, 3e-9)};
  wp.points[2].pareto = wp.points[0].pareto = true;  // listed out of time order on purpose
  wp.recommendations = {{1e-6, true, wp.points[0]}, {1e-8, true, wp.points[2]},
                        {1e-9, true, wp.points[2]}};
  const std::string s = work_precision_plot_script(wp, "paper_scene.yaml", "pngcairo");
  EXPECT_NE(s.find("noenhanced"), std::string::npos);
  // the same colour for an integrator under every treatment, different between integrators
  const std::string adams_exact = line_with(s, "'cvode_adams' && strcol(2) eq 'exact_located'");
  const std::string adams_reg = line_with(s, "'cvode_adams' && strcol(2) eq 'regularized'");
  const std::string erk_exact = line_with(s, "'arkode_erk45' && strcol(2) eq 'exact_located'");
  ASSERT_FALSE(adams_exact.empty() || adams_reg.empty() || erk_exact.empty()) << s;
  EXPECT_EQ(value_after(adams_exact, "lc rgb "), value_after(adams_reg, "lc rgb "));
  EXPECT_NE(value_after(adams_exact, "lc rgb "), value_after(erk_exact, "lc rgb "));
  // the same dash for a treatment under every integrator, different between treatments
  EXPECT_EQ(value_after(adams_exact, " dt "), value_after(erk_exact, " dt "));
  EXPECT_NE(value_after(adams_exact, " dt "), value_after(adams_reg, " dt "));
  // the Pareto front in order of time, and one label per recommended point
  EXPECT_NE(s.find("$pareto << EOD\n0.004,1e-06\n0.009,1e-09\nEOD\n"), std::string::npos) << s;
  EXPECT_NE(s.find("'1: for 1e-06 rad: cvode_adams at 1e-08 (exact_located)'"), std::string::npos)
      << s;
  EXPECT_NE(s.find("'2: for 1e-08, 1e-09 rad: arkode_erk45 at 1e-08 (exact_located)'"),
            std::string::npos)
      << s;
  // one panel per treatment and one for the key
  EXPECT_NE(s.find("set multiplot layout 2,2"), std::string::npos) << s;
}

TEST(Plots, SimulationFiguresUsePlainText) {
  const std::string s = simulation_plot_script(SimulationFigures{}, "pngcairo");
  EXPECT_NE(s.find("noenhanced"), std::string::npos);
  EXPECT_EQ(s.find(" enhanced"), std::string::npos);
  EXPECT_EQ(s.find("{/Symbol"), std::string::npos);
  EXPECT_NE(s.find("\"theta1 [rad]\""), std::string::npos);
}

TEST(Json, ObjectsArraysEscapesAndNonFinite) {
  Json j = Json::object();
  j.set("a", 1.5).set("n", 3).set("big", 12345678901L).set("flag", true).set("s", "q\"\\\n");
  j.set("nan", std::nan("")).set("empty", Json::object());
  Json inner = Json::object();
  inner.set("x", 0.1);
  j.set("inner", inner);
  Json list = Json::array();
  list.push(1.0).push("two").push(Json());
  j.set("list", list);
  j.set("a", 2.5);  // replaced in place
  EXPECT_EQ(j.dump(0),
            "{\"a\": 2.5, \"n\": 3, \"big\": 12345678901, \"flag\": true, \"s\": \"q\\\"\\\\\\n\", "
            "\"nan\": null, \"empty\": {}, \"inner\": {\"x\": 0.1}, \"list\": [1, \"two\", null]}");
  EXPECT_EQ(inner.dump(2), "{\n  \"x\": 0.1\n}");
}

TEST(OutputDir, FilesAppearOnlyAtCommit) {
  const fs::path dir = scratch("commit") / "out";  // created with its parents
  {
    OutputDir out(dir.string(), {"a.csv", "summary.json"});
    write_text_file(out.file("a.csv"), "x\n");
    write_text_file(out.file("summary.json"), "{}\n");
    EXPECT_FALSE(fs::exists(dir / "a.csv"));
    EXPECT_TRUE(fs::exists(out.file("a.csv")));
    EXPECT_EQ(fs::path(out.staging()).parent_path(), dir);
    EXPECT_EQ(out.commit(), (std::vector<std::string>{"a.csv", "summary.json"}));
  }
  EXPECT_EQ(read_file(dir / "a.csv"), "x\n");
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  // nothing else left: no staging directory
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
}

TEST(OutputDir, AFailedRunLeavesNoResultsBehind) {
  const fs::path dir = scratch("failed");
  write_file(dir / "trajectory.csv", "old\n");  // a previous complete run
  write_file(dir / "summary.json", "{}\n");
  write_file(dir / "notes.txt", "mine\n");  // not an output of the run: kept
  {
    OutputDir out(dir.string(), {"trajectory.csv", "summary.json"});
    write_text_file(out.file("trajectory.csv"), "half");
    // the run fails here: no commit
  }
  EXPECT_FALSE(fs::exists(dir / "trajectory.csv"));
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(OutputDir, UnusableDirectoryIsAnInputError) {
  const fs::path dir = scratch("blocked");
  write_file(dir / "file", "x");
  EXPECT_THAT([&] { OutputDir((dir / "file").string(), {}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("--out: cannot create")));
}

TEST(Csv, ReadsCommentsAndBlanks) {
  const fs::path path = scratch("csv") / "m.csv";
  write_file(path, "# a log\n t , theta1,theta2\n\n0,1,2\n# mid\n0.5, 1e-3 ,-2\n");
  const CsvTable t = read_csv(path.string());
  EXPECT_EQ(t.columns, (std::vector<std::string>{"t", "theta1", "theta2"}));
  EXPECT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.lines, (std::vector<int>{4, 6}));
  EXPECT_EQ(t.column("theta1"), (std::vector<double>{1, 1e-3}));
}

TEST(Csv, ErrorsNameFileLineAndColumn) {
  const fs::path dir = scratch("csv_errors");
  const auto expect = [&](const std::string& text, const std::string& message) {
    write_file(dir / "m.csv", text);
    const std::string path = (dir / "m.csv").string();
    EXPECT_THAT([&] { read_csv(path); },
                ::testing::ThrowsMessage<InputError>(HasSubstr(path + ": " + message)));
  };
  expect("t,theta1\n0,1\n0.1,nan\n", "line 3, column theta1: not finite: nan");
  expect("t,theta1\n0,1\n0.1,abc\n", "line 3, column theta1: not a number: 'abc'");
  expect("t,theta1\n0,1,2\n", "line 2: expected 2 fields, got 3");
  expect("t,t\n", "line 1: duplicate column 't'");
  expect("# only a comment\n", "(file): empty");
  write_file(dir / "m.csv", "t,theta1\n0,1\n");
  EXPECT_THAT([&] { read_csv((dir / "m.csv").string()).column("theta2"); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr("header: missing column 'theta2' (the header has: t,theta1)")));
}

TEST(Differences, ExactOnQuartics) {
  // 5-point formulas are exact for polynomials of degree 4 (up to rounding)
  constexpr double kTol = 1e-8;
  const double h = 0.01;
  std::vector<double> f, df, d2f;
  for (int i = 0; i < 12; ++i) {
    const double t = 0.3 + h * i;
    f.push_back(t * t * t * t - 2 * t * t * t + t);
    df.push_back(4 * t * t * t - 6 * t * t + 1);
    d2f.push_back(12 * t * t - 12 * t);
  }
  const std::vector<double> d1 = first_derivative(f, h), d2 = second_derivative(f, h);
  for (size_t i = 0; i < f.size(); ++i) {
    EXPECT_NEAR(d1[i], df[i], kTol) << i;
    EXPECT_NEAR(d2[i], d2f[i], 1e3 * kTol) << i;  // divided by h^2: rounding x 1/h
  }
}

TEST(Differences, UniformStep) {
  const std::vector<int> lines = {2, 3, 4, 5};
  EXPECT_DOUBLE_EQ(uniform_step({0, 0.001, 0.002, 0.003}, lines, "m.csv"), 0.001);
  EXPECT_THAT(
      [&] {
        uniform_step({0, 0.001, 0.0025, 0.003}, lines, "m.csv");
      },
      ::testing::ThrowsMessage<InputError>(
          HasSubstr("m.csv: line 4, column t: the time grid is not uniform")));
}

}  // namespace
}  // namespace fivebar::io
