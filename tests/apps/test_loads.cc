// Load expressions: values, constant detection, errors, independence of copies, threads.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <thread>
#include <vector>

#include "fivebar/io/errors.h"
#include "fivebar/io/loads.h"
#include "paper.h"

namespace fivebar::io {
namespace {

using ::testing::HasSubstr;

// muParser evaluates in double precision: a few roundings of sin/cos arguments
constexpr double kTol = 1e-12;

LoadExpressions paper_expressions() {
  return LoadExpressions({"2 + 5*sin(8*pi*t)", "3 + 5*cos(pi*t)", "6", "50"}, M_PI / 2,
                         "paper.yaml");
}

// the loads of these expressions as the fixture writes them (common/paper.h)
using fivebar::testing::paper_loads;

TEST(Loads, PaperValues) {
  const LoadExpressions loads = paper_expressions();
  const Loads<double> l = loads(0.0625);  // 8 pi t = pi/2
  EXPECT_NEAR(l.M1, 7.0, kTol);
  EXPECT_NEAR(l.M2, paper_loads(0.0625).M2, kTol);
  EXPECT_EQ(l.M3, 6.0);
  EXPECT_EQ(l.F, 50.0);
  EXPECT_EQ(l.F_angle, M_PI / 2);
  EXPECT_NEAR(loads(1.0).M2, -2.0, kTol);
}

TEST(Loads, ConstantExpressionsAreDetected) {
  const LoadExpressions loads = paper_expressions();
  EXPECT_FALSE(loads.constant(LoadExpressions::kM1));
  EXPECT_FALSE(loads.constant(LoadExpressions::kM2));
  EXPECT_TRUE(loads.constant(LoadExpressions::kM3));
  EXPECT_TRUE(loads.constant(LoadExpressions::kF));
  const LoadExpressions folded({"2*pi", "sqrt(4) + 1", "0", "t - t"}, 0, "x.yaml");
  EXPECT_TRUE(folded.constant(0));
  EXPECT_NEAR(folded(3.0).M1, 2 * M_PI, kTol);
  EXPECT_EQ(folded(3.0).M2, 3.0);
  EXPECT_FALSE(folded.constant(3));  // uses t, even if the value does not change
}

TEST(Loads, ErrorsNameFileKeyAndReason) {
  EXPECT_THAT(
      [] {
        LoadExpressions({"0", "sin(", "0", "0"}, 0, "s.yaml");
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("s.yaml: loads.M2: 'sin(': Unexpected")));
  EXPECT_THAT(
      [] {
        LoadExpressions({"0", "0", "y*2", "0"}, 0, "s.yaml");
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("s.yaml: loads.M3: 'y*2': ")));
  EXPECT_THAT(
      [] {
        LoadExpressions({"0", "0", "0", "log(t)"}, 0, "s.yaml");
      },
      ::testing::ThrowsMessage<InputError>(
          HasSubstr("s.yaml: loads.F: 'log(t)' is not finite at t = 0 (-inf)")));
  EXPECT_THAT(
      [] {
        LoadExpressions({"1/(t-1)", "0", "0", "0"}, 0, "s.yaml");
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("not finite at t = 1")));
}

TEST(Loads, FromScene) {
  Scene s;
  s.M1 = "t";
  s.M2 = "2*t";
  s.F_angle = 0.5;
  s.path = "scene.yaml";
  const LoadExpressions loads(s);
  EXPECT_EQ(loads(3).M1, 3.0);
  EXPECT_EQ(loads(3).M2, 6.0);
  EXPECT_EQ(loads(3).M3, 0.0);
  EXPECT_EQ(loads(3).F_angle, 0.5);
}

TEST(Loads, CopiesAreIndependent) {
  auto original = std::make_unique<LoadExpressions>(paper_expressions());
  LoadExpressions copy = *original;
  LoadExpressions assigned({"0", "0", "0", "0"}, 0, "z.yaml");
  assigned = copy;
  // interleaved calls at different t: each copy has its own `t`
  for (double t : {0.01, 0.33, 0.7, 1.9}) {
    const double other = 1.0 - t;
    EXPECT_NEAR((*original)(t).M1, paper_loads(t).M1, kTol);
    EXPECT_NEAR(copy(other).M1, paper_loads(other).M1, kTol);
    EXPECT_NEAR((*original)(t).M2, paper_loads(t).M2, kTol);
    EXPECT_NEAR(assigned(t / 2).M2, paper_loads(t / 2).M2, kTol);
  }
  // a copy outlives its original, and so does a LoadFunction made from it
  const sim::LoadFunction f = original->function();
  original.reset();
  EXPECT_NEAR(copy(0.0625).M1, 7.0, kTol);
  EXPECT_NEAR(f(0.0625).M1, 7.0, kTol);
  const sim::LoadFunction g = f;  // std::function copy: copies the expressions
  EXPECT_NEAR(g(0.2).M2, paper_loads(0.2).M2, kTol);
  LoadExpressions moved = std::move(copy);
  EXPECT_NEAR(moved(0.2).M1, paper_loads(0.2).M1, kTol);
}

// each thread checks many evaluations against the closed form
void hammer(const std::function<Loads<double>(double)>& f, int seed, int* failures) {
  for (int i = 0; i < 20000; ++i) {
    const double t = 1e-4 * ((i * 7919 + seed * 104729) % 20000);
    const Loads<double> l = f(t);
    const Loads<double> want = paper_loads(t);
    if (std::fabs(l.M1 - want.M1) > kTol || std::fabs(l.M2 - want.M2) > kTol) {
      ++*failures;
    }
  }
}

TEST(Loads, ThreadsWithTheirOwnCopies) {
  const sim::LoadFunction f = paper_expressions().function();
  std::vector<int> failures(4, 0);
  std::vector<std::thread> threads;
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([f, k, &failures] { hammer(f, k, &failures[k]); });  // f copied
  }
  for (auto& t : threads) t.join();
  for (int k = 0; k < 4; ++k) EXPECT_EQ(failures[k], 0) << "thread " << k;
}

TEST(Loads, ThreadsSharingOneObject) {
  const LoadExpressions shared = paper_expressions();
  const auto call = [&shared](double t) { return shared(t); };
  std::vector<int> failures(4, 0);
  std::vector<std::thread> threads;
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&call, k, &failures] { hammer(call, k, &failures[k]); });
  }
  for (auto& t : threads) t.join();
  for (int k = 0; k < 4; ++k) EXPECT_EQ(failures[k], 0) << "thread " << k;
}

}  // namespace
}  // namespace fivebar::io
