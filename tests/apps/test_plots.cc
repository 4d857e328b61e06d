// Tests of the figure helpers of fivebar::io (plots.h): axis labels, heatmap, excitation figures.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fivebar/io/plots.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

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

}  // namespace
}  // namespace fivebar::io
