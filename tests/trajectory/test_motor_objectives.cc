// The motors' losses in the trajectory objectives: winding heat, total dissipation, supply
// energy (softplus-smoothed), free end accelerations, the limit tolerance of `ok`, and the
// TaskResult codec derived from visit_fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/bspline.h"
#include "fivebar/trajectory/optimizer.h"
#include "fivebar/trajectory/problem.h"
#include "paper_fixture.h"

namespace fivebar::trajectory {
namespace {

using testing::paper_initial;
using testing::paper_loads;
using testing::paper_tasks;
const std::array<double, 2> kStart = {M_PI / 2, M_PI / 2};

// the winding heat coefficient of the motors of datasets/scenes/paper_motors.yaml
const double kHeat = 0.3 / ((0.03 * 66) * (0.03 * 66));

TEST(EndAcceleration, FreeEndsRestButAccelerate) {
  const RestToRest m(11, 0.7, {0.3, -1.0}, {1.2, 0.4}, EndAcceleration::kFree);
  EXPECT_EQ(m.fixed(), 2);
  EXPECT_EQ(m.num_variables(), 2 * (11 - 4));
  std::vector<double> x(m.num_variables());
  for (size_t i = 0; i < x.size(); ++i) x[i] = std::sin(3.0 * i + 1.0);
  const auto s0 = m.state(x.data(), 0.0), s1 = m.state(x.data(), 0.7);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(s0[0][j], m.start()[j], 1e-12);
    EXPECT_NEAR(s1[0][j], m.goal()[j], 1e-12);
    EXPECT_NEAR(s0[1][j], 0.0, 1e-9);  // at rest
    EXPECT_NEAR(s1[1][j], 0.0, 1e-9);
    EXPECT_GT(std::abs(s0[2][j]), 1.0);  // but free to accelerate
  }
  // the minimum-jerk quintic is still in the space
  const std::vector<double> mj = m.minimum_jerk();
  const auto mid = m.state(mj.data(), 0.35);
  EXPECT_NEAR(mid[0][0], 0.3 + 0.9 * 0.5, 1e-9);
}

TEST(Objectives, TotalDissipationIsFrictionPlusWindingHeat) {
  ProblemOptions o;
  o.objective = Objective::kTotalDissipation;
  o.winding_heat = {kHeat, kHeat};
  const Params<double> p = paper_params();
  const TrajectoryProblem problem(p, paper_loads(), RestToRest(10, 0.5, kStart, {0.7, 0.6}), o);
  const std::vector<double> x = problem.motion().minimum_jerk();
  Energies e;
  ASSERT_TRUE(problem.energies(x.data(), o.quadrature_points, &e).ok());
  Evaluated ev;
  ASSERT_TRUE(problem.evaluate(x.data(), false, &ev).ok());
  EXPECT_NEAR(ev.objective, e.dissipated + e.winding_heat, 1e-12 * ev.objective);
  // c int M1^2 + M2^2 dt by the trapezoidal rule on the torques
  const double c = kHeat, dt = 1e-4;
  double heat = 0;
  for (int i = 0; i <= 5000; ++i) {
    double M1 = 0, M2 = 0;
    ASSERT_TRUE(problem.smoothed_torques(x.data(), i * dt, &M1, &M2).ok());
    heat += (i == 0 || i == 5000 ? 0.5 : 1.0) * dt * c * (M1 * M1 + M2 * M2);
  }
  EXPECT_NEAR(e.winding_heat, heat, 1e-5 * heat);
  EXPECT_GT(e.winding_heat, e.dissipated);  // catalogue motors: copper loss dominates
}

// input_energy is int |M1 w1| + |M2 w2| dt; the optimizer's smoothed |p| = sqrt(p^2 + eps^2) - eps
// is below it by at most eps per motor
TEST(Objectives, InputEnergyIsTheExactAbsoluteWork) {
  ProblemOptions o;
  o.objective = Objective::kInputEnergy;
  const TrajectoryProblem problem(paper_params(), paper_loads(),
                                  RestToRest(10, 0.5, kStart, {0.7, 0.6}), o);
  const std::vector<double> x = problem.motion().minimum_jerk();
  Energies e;
  ASSERT_TRUE(problem.energies(x.data(), 4 * o.quadrature_points, &e).ok());
  const double dt = 1e-4;
  double work = 0;
  for (int i = 0; i <= 5000; ++i) {
    double M1 = 0, M2 = 0;
    ASSERT_TRUE(problem.smoothed_torques(x.data(), i * dt, &M1, &M2).ok());
    const auto s = problem.motion().state(x.data(), i * dt);
    const double p = std::abs(M1 * s[1][0]) + std::abs(M2 * s[1][1]);
    work += (i == 0 || i == 5000 ? 0.5 : 1.0) * dt * p;
  }
  EXPECT_NEAR(e.input, work, 1e-4 * work);  // Gauss-Legendre across the kinks of |p|
  EXPECT_LE(e.input_smoothed, e.input);
  EXPECT_GE(e.input_smoothed, e.input - 2 * o.power_smoothing * 0.5);
  Evaluated ev;
  ASSERT_TRUE(problem.evaluate(x.data(), false, &ev).ok());
  Energies own;
  ASSERT_TRUE(problem.energies(x.data(), o.quadrature_points, &own).ok());
  EXPECT_NEAR(ev.objective, own.input_smoothed, 1e-12 * ev.objective);
}

TEST(Objectives, SupplyEnergySoftplusIsWithinItsBound) {
  for (Regeneration reg : {Regeneration::kNone, Regeneration::kSharedBus}) {
    ProblemOptions o;
    o.objective = Objective::kSupplyEnergy;
    o.regeneration = reg;
    o.winding_heat = {kHeat, kHeat};
    const TrajectoryProblem problem(paper_params(), paper_loads(),
                                    RestToRest(10, 0.5, kStart, {0.7, 0.6}), o);
    const std::vector<double> x = problem.motion().minimum_jerk();
    Energies e;
    ASSERT_TRUE(problem.energies(x.data(), 4 * o.quadrature_points, &e).ok());
    // softplus - max(0, p) in (0, eps ln 2] per clipped power, over 0.5 s
    const int clipped = reg == Regeneration::kNone ? 2 : 1;
    EXPECT_GE(e.supply_smoothed, e.supply);
    EXPECT_LE(e.supply_smoothed - e.supply, clipped * o.power_smoothing * std::log(2.0) * 0.5);
    // the supply covers the heat and at least the net mechanical work
    EXPECT_GE(e.supply, e.winding_heat);
  }
  Energies none, shared;
  for (Regeneration reg : {Regeneration::kNone, Regeneration::kSharedBus}) {
    ProblemOptions o;
    o.regeneration = reg;
    o.winding_heat = {kHeat, kHeat};
    const TrajectoryProblem problem(paper_params(), paper_loads(),
                                    RestToRest(10, 0.5, kStart, {0.7, 0.6}), o);
    const std::vector<double> x = problem.motion().minimum_jerk();
    ASSERT_TRUE(problem.energies(x.data(), 48, reg == Regeneration::kNone ? &none : &shared).ok());
  }
  EXPECT_LE(shared.supply, none.supply + 1e-12);  // a shared bus can only save
}

// exact gradients of the new objectives against central differences (free ends)
TEST(Objectives, GradientsMatchCentralDifferences) {
  for (Objective objective : {Objective::kTotalDissipation, Objective::kSupplyEnergy}) {
    ProblemOptions o;
    o.objective = objective;
    o.torque_limit = 20.0;
    o.winding_heat = {kHeat, kHeat};
    const TrajectoryProblem p(paper_params(), paper_loads(),
                              RestToRest(10, 0.5, kStart, {2.2, 1.0}, EndAcceleration::kFree), o);
    std::vector<double> x = p.motion().minimum_jerk();
    for (size_t i = 0; i < x.size(); ++i) x[i] += 0.05 * std::sin(7.0 * i);
    Evaluated e;
    ASSERT_TRUE(p.evaluate(x.data(), true, &e).ok());
    double scale = 0;
    for (double g : e.objective_grad) scale = std::max(scale, std::abs(g));
    constexpr double kStep = 1e-5;
    for (int v = 0; v < p.num_variables(); ++v) {
      std::vector<double> xp = x, xm = x;
      xp[v] += kStep;
      xm[v] -= kStep;
      double fp = 0, fm = 0;
      ASSERT_TRUE(p.objective(xp.data(), &fp).ok());
      ASSERT_TRUE(p.objective(xm.data(), &fm).ok());
      EXPECT_NEAR(e.objective_grad[v], (fp - fm) / (2 * kStep), 1e-6 * scale)
          << objective_name(objective) << " variable " << v;
    }
  }
}

// swing_right on 10 control points under total_dissipation with winding coefficient c
TrajectoryProblem heat_problem(double c) {
  ProblemOptions o;
  o.objective = Objective::kTotalDissipation;
  o.winding_heat = {c, c};
  o.torque_limit = 30.0;
  return TrajectoryProblem(paper_params(), paper_loads(), RestToRest(10, 0.5, kStart, {0.7, 0.6}),
                           o);
}

TEST(Objectives, HeatShareIsTheWindingHeatOverTheObjective) {
  const TrajectoryProblem p = heat_problem(kHeat);
  const std::vector<double> x = p.motion().minimum_jerk();
  Energies e;
  ASSERT_TRUE(p.energies(x.data(), p.options().quadrature_points, &e).ok());
  EXPECT_NEAR(p.heat_share(x.data()), e.winding_heat / (e.dissipated + e.winding_heat), 1e-12);
  EXPECT_GT(p.heat_share(x.data()), 0.5);  // the shipped motors: the heat is most of it
  EXPECT_LT(heat_problem(5e-4).heat_share(x.data()), 0.05);
}

TEST(Objectives, GaussNewtonPreconditionerReachesTheOptimumInFewerEvaluations) {
  // where the heat dominates (paper_motors.yaml), a 10-point solve (10 variables, below the
  // size at which the difference Hessian preconditions) in the heat's Gauss-Newton variables
  // ends at the plain solve's optimum in fewer evaluations (counts are deterministic)
  const TrajectoryProblem p = heat_problem(kHeat);
  const std::vector<double> x0 = p.motion().minimum_jerk();
  OptimizerOptions plain, pre;
  plain.precondition = false;
  plain.stall_rtol = pre.stall_rtol = 0;  // full solves
  const OptimizeResult a = optimize(p, x0, plain), b = optimize(p, x0, pre);
  ASSERT_TRUE(a.solver.usable()) << a.solver.message;
  ASSERT_TRUE(b.solver.usable()) << b.solver.message;
  EXPECT_NEAR(b.objective, a.objective, 1e-6 * a.objective);
  EXPECT_LT(3 * b.evaluations, 2 * a.evaluations) << a.evaluations << " " << b.evaluations;
}

TEST(Objectives, NamesParseAndList) {
  Objective o;
  for (const char* name : {"total_dissipation", "supply_energy", "dissipated_energy"}) {
    ASSERT_TRUE(parse_objective(name, &o)) << name;
    EXPECT_EQ(std::string(objective_name(o)), name);
    EXPECT_NE(objective_names().find(name), std::string::npos);
  }
  EXPECT_FALSE(parse_objective("energy", &o));
  EXPECT_TRUE(needs_winding(Objective::kTotalDissipation));
  EXPECT_FALSE(needs_winding(Objective::kDissipatedEnergy));
  Regeneration r;
  EXPECT_TRUE(parse_regeneration("shared_bus", &r));
  EXPECT_FALSE(parse_regeneration("bus", &r));
  EndAcceleration a;
  EXPECT_TRUE(parse_end_acceleration("zero", &a));
  EXPECT_EQ(a, EndAcceleration::kZero);
  EXPECT_FALSE(parse_end_acceleration("none", &a));
}

// an initializer of any member (its conversion is only declared: unevaluated contexts only)
struct AnyMember {
  template <typename T>
  operator T() const;
};

// the members of an aggregate: the largest count of initializers it accepts (each member takes
// one AnyMember, so brace elision never splits an array member)
template <typename T, typename... A>
constexpr auto accepts(int) -> decltype(T{std::declval<A>()...}, bool()) {
  return true;
}
template <typename T, typename... A>
constexpr bool accepts(...) {
  return false;
}
template <typename T, typename... A>
constexpr int member_count() {
  if constexpr (accepts<T, A..., AnyMember>(0)) {
    return member_count<T, A..., AnyMember>();
  } else {
    return static_cast<int>(sizeof...(A));
  }
}

// visit_fields visits every member of TaskResult: a member added to the struct and not to the
// list would be left out of the codec and of summary.csv
TEST(Codec, VisitFieldsListsEveryMember) {
  TaskResult r;
  int visits = 0;
  visit_fields(r, [&](const char*, auto&) { ++visits; });
  // start and goal are visited per element (theta1_start, theta2_start, ...)
  EXPECT_EQ(visits, member_count<TaskResult>() + 2);
}

// every field of a TaskResult survives the codec, each compared with its original (every field
// set to its own non-default value, so that a field the codec leaves out comes back different)
TEST(Codec, EveryFieldRoundTrips) {
  TaskResult r;
  int k = 0;
  visit_fields(r, [&](const char* name, auto& v) {
    using V = std::decay_t<decltype(v)>;
    ++k;
    if constexpr (std::is_same_v<V, std::string>) {
      v = std::string(name) + "," + std::to_string(k) + "\n\"";
    } else if constexpr (std::is_same_v<V, double>) {
      v = 0.1 * k + 1e-17 * k;
    } else if constexpr (std::is_same_v<V, int>) {
      v = 1000 + k;
    } else if constexpr (std::is_same_v<V, bool>) {
      v = true;
    } else {
      v = {1.5 * k, -2.0, NAN};
    }
  });
  const TaskResult back = decode(encode(r));
  std::vector<std::string> names;
  visit_fields(r, [&](const char* name, const auto&) { names.push_back(name); });
  size_t i = 0;
  std::vector<const void*> originals;
  visit_fields(r, [&](const char*, const auto& v) { originals.push_back(&v); });
  visit_fields(back, [&](const char*, const auto& v) {
    using V = std::decay_t<decltype(v)>;
    const V& original = *static_cast<const V*>(originals[i]);
    if constexpr (std::is_same_v<V, std::vector<double>>) {
      ASSERT_EQ(v.size(), original.size());
      EXPECT_EQ(std::memcmp(v.data(), original.data(), v.size() * sizeof(double)), 0);
    } else {
      EXPECT_EQ(v, original) << names[i];
    }
    ++i;
  });
  EXPECT_EQ(i, names.size());
  EXPECT_TRUE(back.refinement_limited);  // once left out of the codec
  EXPECT_EQ(back.winding_heat, r.winding_heat);
  EXPECT_THROW(decode(encode(r).substr(0, 20)), std::exception);
}

// a task over its limit by more than limit_rtol is not ok (the dense check decides)
TEST(Limits, NoOkAboveTheLimit) {
  BatchOptions options;
  options.validate = false;
  options.problem.objective = Objective::kTotalDissipation;
  options.problem.winding_heat = {kHeat, kHeat};
  options.refine.control_points = kSmoothRefineLevels;
  options.refine.tol = 1e-4;
  for (const TaskSpec& task : paper_tasks()) {
    const TaskResult r = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
    if (r.status != "ok") continue;
    EXPECT_LE(r.peak_torque, r.torque_limit * (1.0 + options.limit_rtol)) << task.name;
    EXPECT_GE(r.min_coupler_sine, options.problem.singular_margin * (1.0 - options.limit_rtol))
        << task.name;
    EXPECT_NEAR(r.total_dissipation, r.dissipated_energy + r.winding_heat, 1e-12);
    EXPECT_LT(r.total_dissipation, r.baseline_total_dissipation) << task.name;
  }
}

// a task solved within its limits is ok only when the forward simulation of its torques reaches
// the goal: a miss over miss_tol, or NaN (a simulation that failed), is validation_failed
TEST(Limits, NoOkWithoutValidation) {
  BatchOptions options;
  options.problem.objective = Objective::kTotalDissipation;
  options.problem.winding_heat = {kHeat, kHeat};
  const TaskSpec task = paper_tasks()[1];
  const TaskResult r = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_LE(std::max(r.miss_distance, r.miss_distance_exact), options.miss_tol);
  options.miss_tol = 0.1 * std::min(r.miss_distance, r.miss_distance_exact);
  const TaskResult tight = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
  EXPECT_EQ(tight.status, "validation_failed");
  EXPECT_NE(tight.message.find("miss the goal"), std::string::npos) << tight.message;
  options.miss_tol = NAN;  // a NaN comparison is no pass
  const TaskResult nan = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
  EXPECT_EQ(nan.status, "validation_failed");
}

}  // namespace
}  // namespace fivebar::trajectory
