// Tests of the figure helpers of fivebar::io (plots.h): axis labels, heatmap, excitation figures,
// the binary copies gnuplot reads, and run_gnuplot's two processes and failures.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fivebar/io/plots.h"

namespace fivebar::io {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(SceneKeyLabel, LinksAreOneBasedWithUnits) {
  EXPECT_EQ(scene_key_label("mechanism.links.2.length"), "l3: length of link 3 (coupler B-C) [m]");
  EXPECT_EQ(scene_key_label("mechanism.links.0.length"), "l1: length of link 1 (crank O-B) [m]");
  EXPECT_EQ(scene_key_label("mechanism.links.3.mass"), "mass of link 4 (coupler D-C) [kg]");
  EXPECT_EQ(scene_key_label("mechanism.links.1.com_offset"),
            "centre-of-mass offset of link 2 (crank D0-D) [m]");
  EXPECT_EQ(scene_key_label("mechanism.point_p"), "lp: distance B-P on link 3 [m]");
  // keys it does not know, and malformed link indices, come back unchanged
  EXPECT_EQ(scene_key_label("friction.coulomb"), "friction.coulomb");
  EXPECT_EQ(scene_key_label("mechanism.links.7.length"), "mechanism.links.7.length");
  EXPECT_EQ(scene_key_label("mechanism.links.2.colour"), "mechanism.links.2.colour");
}

TEST(StudyHeatmap, MarksInfeasibleDesignsAndTheBest) {
  StudyHeatmap h;
  h.x_key = "mechanism.links.2.length";
  h.y_key = "mechanism.links.3.length";
  h.x_lo = 0.15;
  h.x_hi = 0.35;
  h.y_lo = 0.15;
  h.y_hi = 0.35;
  h.cell_x = h.cell_y = 0.02;
  h.title = "total";
  const std::string plain = study_heatmap_script(h, "png");
  EXPECT_THAT(plain, HasSubstr("set xlabel \"l3: length of link 3 (coupler B-C) [m]\""));
  EXPECT_THAT(plain, Not(HasSubstr("heatmap_infeasible.dat")));
  EXPECT_THAT(plain, Not(HasSubstr("best design")));
  h.infeasible = "heatmap_infeasible.dat";
  h.has_best = true;
  h.best_x = 0.28;
  h.best_y = 0.26;
  const std::string marked = study_heatmap_script(h, "png");
  EXPECT_THAT(marked, HasSubstr("'heatmap_infeasible.dat' using 1:2:(0.01):(0.01) with boxxyerror "
                                "fs pattern"));
  EXPECT_THAT(marked, HasSubstr("(0.28000000000000003):(0.26000000000000001)"));
  EXPECT_THAT(marked, HasSubstr("title 'best design'"));
}

TEST(ExcitationFigures, WithoutABaselineTheStdFigureDrawsTheDesignOnly) {
  ExcitationFigures f;
  f.torque_limit = 0.2;
  const std::string with = excitation_plot_script(f, "pngcairo");
  EXPECT_THAT(with, HasSubstr("\"multisine_relative_std\""));
  f.baseline = false;  // its columns are all nan: gnuplot fails on a histogram without points
  const std::string without = excitation_plot_script(f, "pngcairo");
  EXPECT_THAT(without, Not(HasSubstr("multisine_relative_std")));
  EXPECT_THAT(without, Not(HasSubstr("vs multi-sine")));
  EXPECT_THAT(without, HasSubstr("using \"relative_std\":xtic(1)"));
}

// A four-bar's excitation has one crank: its figures draw theta1, omega1, alpha1 and M1 only (the
// columns its excitation.csv has).
TEST(ExcitationFigures, OneCrankDrawsItsColumnsOnly) {
  ExcitationFigures f;
  EXPECT_THAT(excitation_plot_script(f, "pngcairo"), HasSubstr("\"M2\""));
  f.cranks = 1;
  const std::string one = excitation_plot_script(f, "pngcairo");
  for (const char* c : {"\"theta1\"", "\"omega1\"", "\"alpha1\"", "\"M1\""})
    EXPECT_THAT(one, HasSubstr(c));
  for (const char* c : {"theta2", "omega2", "alpha2", "M2", "crank 2"})
    EXPECT_THAT(one, Not(HasSubstr(c)));
}

TEST(ExcitationFigures, AFigureGnuplotCannotDrawIsRemovedNotLeftEmpty) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fivebar_plots_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {  // no parameter has a relative std (all scene values 0): no valid point in the histogram
    std::ofstream csv(dir / "predicted_std.csv");
    csv << "name,value,std,relative_std,multisine_std,multisine_relative_std\n"
           "offset_1,0,0.01,nan,nan,nan\noffset_2,0,0.01,nan,nan,nan\n";
    std::ofstream motion(dir / "excitation.csv");
    motion << "t,theta1,theta2,omega1,omega2,alpha1,alpha2,M1,M2\n0,1,1,0,0,0,0,0,0\n"
              "0.1,1.1,1.1,1,1,0,0,0.1,0.1\n";
  }
  ExcitationFigures f;
  f.torque_limit = 0.2;
  f.baseline = false;
  const std::string warning = plot_excitation(dir.string(), f);
  if (warning.find("not found") == std::string::npos) {  // gnuplot present
    EXPECT_THAT(warning, HasSubstr("removed the empty fig_std.png"));
    EXPECT_FALSE(std::filesystem::exists(dir / "fig_std.png"));
    EXPECT_GT(std::filesystem::file_size(dir / "fig_motion.png"), 0u);
  }
  std::filesystem::remove_all(dir);
}

// a fresh directory of its own for one test
std::filesystem::path test_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("fivebar_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(PlotData, TheBinaryCopyHoldsTheRowsOfTheCsvAndTheScriptNamesColumnsByNumber) {
  const std::filesystem::path dir = test_dir("plot_data");
  std::ofstream(dir / "run.csv") << "t,a,b\n0,1.5,nan\n0.5,-2,3e-3\n";
  std::ofstream(dir / "names.csv") << "name,value\noffset_1,2\n";
  PlotData d;
  ASSERT_TRUE(d.convert(dir.string(), "run.csv"));
  EXPECT_FALSE(d.convert(dir.string(), "names.csv"));  // a text field: gnuplot reads the CSV
  EXPECT_FALSE(d.convert(dir.string(), "missing.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "names.bin"));

  const std::string bin = file_text(dir / "run.bin");
  ASSERT_EQ(bin.size(), 6 * sizeof(double));
  std::vector<double> v(6);
  std::memcpy(v.data(), bin.data(), bin.size());
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[1], 1.5);
  EXPECT_TRUE(std::isnan(v[2]));
  EXPECT_EQ(v[3], 0.5);
  EXPECT_EQ(v[4], -2.0);
  EXPECT_EQ(v[5], 3e-3);

  EXPECT_EQ(d.file("run.csv"), "\"run.bin\" binary format=\"%3float64\"");
  EXPECT_EQ(d.column("run.csv", "b"), "3");
  EXPECT_EQ(d.value("run.csv", "a"), "$2");
  EXPECT_EQ(d.column("run.csv", "c"), "\"c\"");  // not in the file: gnuplot names it
  EXPECT_EQ(d.file("names.csv"), "\"names.csv\"");
  EXPECT_EQ(d.column("names.csv", "value"), "\"value\"");
  EXPECT_EQ(d.value("names.csv", "value"), "column(\"value\")");
  // the script's reader is told what the numbers stand for
  EXPECT_EQ(d.key(), "# run.bin: run.csv as float64, columns 1 t, 2 a, 3 b\n");
  std::filesystem::remove_all(dir);
}

TEST(PlotData, SimulationFiguresReadTheCopyOfTheTrajectory) {
  const std::filesystem::path dir = test_dir("plot_simulation_data");
  {
    std::ofstream csv(dir / "trajectory.csv");
    const std::vector<std::string> columns = trajectory_columns({});
    for (size_t j = 0; j < columns.size(); ++j) csv << (j ? "," : "") << columns[j];
    csv << "\n";
    for (int i = 0; i < 3; ++i) {
      for (size_t j = 0; j < columns.size(); ++j) csv << (j ? "," : "") << i + 0.25 * j;
      csv << "\n";
    }
  }
  SimulationFigures f;
  f.inverse = false;
  ASSERT_TRUE(f.data.convert(dir.string(), f.trajectory));
  const std::string s = simulation_plot_script(f, "pngcairo");
  EXPECT_THAT(s, HasSubstr("plot \"trajectory.bin\" binary format=\"%" +
                           std::to_string(trajectory_columns({}).size()) +
                           "float64\" using 1:2 with lines ls 1"));
  EXPECT_THAT(s, HasSubstr("stats \"trajectory.bin\""));
  EXPECT_THAT(s, Not(HasSubstr("\"trajectory.csv\"")));  // (the CSV only in the key)
  std::filesystem::remove_all(dir);
}

// a script of three small figures a.png, b.png, c.png; `broken`: a's second panel reads a file
// that does not exist (gnuplot stops with its first panel drawn)
std::string three_figures(bool broken) {
  return "set terminal " + gnuplot().terminal +
         " size 200,150\nset samples 50\nunset key\n"
         "set output 'a.png'\nset multiplot layout 2,1\nplot sin(x)\nplot " +
         std::string(broken ? "'missing.csv' using 1:2" : "cos(x)") +
         "\nunset multiplot\n"
         "set output 'b.png'\nplot x\nset output 'c.png'\nplot x**2\n";
}

TEST(RunGnuplot, StandAloneFiguresAreDrawnInTwoPartsAndTheScriptRedrawsThemAll) {
  if (!gnuplot().available) GTEST_SKIP() << "gnuplot not found";
  const std::filesystem::path dir = test_dir("plot_parts");
  EXPECT_EQ(run_gnuplot(dir.string(), "plots.gnuplot", three_figures(false), Figures::kStandAlone),
            "");
  const std::string script = file_text(dir / "plots.gnuplot");
  EXPECT_THAT(script, HasSubstr("if (!exists(\"part\") || part == 1) {\nset output 'a.png'"));
  EXPECT_THAT(script, HasSubstr("if (!exists(\"part\") || part == 1) {\nset output 'b.png'"));
  EXPECT_THAT(script, HasSubstr("if (!exists(\"part\") || part == 2) {\nset output 'c.png'"));
  std::vector<std::string> drawn;
  for (const char* name : {"a.png", "b.png", "c.png"}) {
    drawn.push_back(file_text(dir / name));
    EXPECT_GT(drawn.back().size(), 0u) << name;
    std::filesystem::remove(dir / name);
  }
  // the user's redraw: one gnuplot without `part` draws every figure, the same
  const std::string redraw =
      "cd '" + dir.string() + "' && '" + gnuplot().executable + "' plots.gnuplot 2>/dev/null";
  ASSERT_EQ(std::system(redraw.c_str()), 0);
  EXPECT_EQ(file_text(dir / "a.png"), drawn[0]);
  EXPECT_EQ(file_text(dir / "b.png"), drawn[1]);
  EXPECT_EQ(file_text(dir / "c.png"), drawn[2]);
  std::filesystem::remove_all(dir);
}

TEST(RunGnuplot, AFigureLeftUnfinishedByAnErrorIsRemovedAndTheOtherPartStillDraws) {
  if (!gnuplot().available) GTEST_SKIP() << "gnuplot not found";
  for (Figures figures : {Figures::kStandAlone, Figures::kInOrder}) {
    const std::filesystem::path dir = test_dir("plot_failure");
    const std::string warning =
        run_gnuplot(dir.string(), "plots.gnuplot", three_figures(true), figures);
    EXPECT_THAT(warning, HasSubstr("gnuplot failed on plots.gnuplot: "));
    EXPECT_THAT(warning, HasSubstr("missing.csv"));
    EXPECT_THAT(warning, HasSubstr("removed the unfinished a.png"));
    EXPECT_FALSE(std::filesystem::exists(dir / "a.png"));  // half drawn: not left behind
    // drawn by the second process; in order, gnuplot stopped before them
    const bool parts = figures == Figures::kStandAlone && std::thread::hardware_concurrency() >= 2;
    EXPECT_EQ(std::filesystem::exists(dir / "c.png"), parts);
    EXPECT_FALSE(std::filesystem::exists(dir / "b.png"));  // part 1, after the error
    std::filesystem::remove_all(dir);
  }
}

// A gnuplot killed while writing a PNG leaves it cut short (no IEND chunk): after a failure, a
// figure of the script in that state is removed and named (here one left before the run, where
// the failing gnuplot never reaches it); the error is worded with the figure gnuplot was drawing,
// not with its line number (off inside the parts' blocks).
TEST(RunGnuplot, AFigureCutShortIsRemovedAndTheErrorNamesTheFigureBeingDrawn) {
  if (!gnuplot().available) GTEST_SKIP() << "gnuplot not found";
  const std::filesystem::path dir = test_dir("plot_cut");
  std::ofstream(dir / "c.png", std::ios::binary) << "\x89PNG\r\n\x1a\n\0\0\0\rIHDR";
  const std::string warning =
      run_gnuplot(dir.string(), "plots.gnuplot", three_figures(true), Figures::kInOrder);
  EXPECT_THAT(warning, HasSubstr("(drawing a.png)"));
  EXPECT_THAT(warning, Not(HasSubstr("\" line ")));
  EXPECT_THAT(warning, HasSubstr("removed the unfinished a.png, c.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "c.png"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fivebar::io
