// The serial vector operations compiled with the simulator (model/src/serial_vector_ops.cc) give
// the SUNDIALS library's results bit for bit: the integrators' step sequences, and so every
// trajectory, do not change with them. Seeded random vectors, the coefficients whose special
// cases round differently (equal, opposite, +-1, 0) and the aliasing the solvers use (z = x,
// z = y, X_0 = z, Z = Y).
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "serial_vector_ops.h"

namespace fivebar::sim::detail {
namespace {

constexpr int kLength = 7;  // the five-bar's state
constexpr int kVectors = 9;

class SerialVectorOps : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(SUNContext_Create(nullptr, &ctx_), 0);
    std::mt19937 gen(42);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    for (int k = 0; k < kVectors; ++k) {
      lib_.push_back(N_VNew_Serial(kLength, ctx_));
      ours_.push_back(N_VNew_Serial(kLength, ctx_));
      use_compiled_serial_ops(ours_.back());
      for (int i = 0; i < kLength; ++i) {
        // a spread of magnitudes, so that factored and unfactored sums round differently
        const double v = u(gen) * std::pow(10.0, static_cast<int>(u(gen) * 3));
        NV_Ith_S(lib_[k], i) = NV_Ith_S(ours_[k], i) = v;
      }
    }
  }
  void TearDown() override {
    for (N_Vector v : lib_) N_VDestroy(v);
    for (N_Vector v : ours_) N_VDestroy(v);
    SUNContext_Free(&ctx_);
  }
  /// every vector of both sets holds the same bits
  void expect_same(const char* what) {
    for (int k = 0; k < kVectors; ++k) {
      EXPECT_EQ(std::memcmp(NV_DATA_S(lib_[k]), NV_DATA_S(ours_[k]), kLength * sizeof(double)), 0)
          << what << ": vector " << k;
    }
  }
  SUNContext ctx_ = nullptr;
  std::vector<N_Vector> lib_, ours_;
};

const double kCoefficients[] = {1.0, -1.0, 0.0, 0.3, -0.3, 0.7, 2.5e-3};

TEST_F(SerialVectorOps, LinearSumMatchesTheLibraryInEveryCase) {
  for (double a : kCoefficients) {
    for (double b : kCoefficients) {
      // z apart, z = y (axpy), z = x
      for (int z : {2, 1, 0}) {
        N_VLinearSum_Serial(a, lib_[0], b, lib_[1], lib_[z]);
        ours_[z]->ops->nvlinearsum(a, ours_[0], b, ours_[1], ours_[z]);
        expect_same("linear sum");
      }
    }
  }
}

TEST_F(SerialVectorOps, ElementwiseOperationsAndNormsMatchTheLibrary) {
  N_Vector* o = ours_.data();
  for (double c : kCoefficients) {
    N_VScale_Serial(c, lib_[0], lib_[3]);
    o[3]->ops->nvscale(c, o[0], o[3]);
    N_VScale_Serial(c, lib_[4], lib_[4]);
    o[4]->ops->nvscale(c, o[4], o[4]);
    N_VAddConst_Serial(lib_[1], c, lib_[5]);
    o[5]->ops->nvaddconst(o[1], c, o[5]);
    expect_same("scale, add constant");
  }
  N_VAbs_Serial(lib_[0], lib_[6]);
  o[6]->ops->nvabs(o[0], o[6]);
  N_VInv_Serial(lib_[6], lib_[7]);
  o[7]->ops->nvinv(o[6], o[7]);
  N_VProd_Serial(lib_[1], lib_[2], lib_[8]);
  o[8]->ops->nvprod(o[1], o[2], o[8]);
  N_VDiv_Serial(lib_[8], lib_[7], lib_[3]);
  o[3]->ops->nvdiv(o[8], o[7], o[3]);
  expect_same("abs, inv, prod, div");
  EXPECT_EQ(N_VWrmsNorm_Serial(lib_[1], lib_[7]), o[1]->ops->nvwrmsnorm(o[1], o[7]));
  EXPECT_EQ(N_VWSqrSumLocal_Serial(lib_[2], lib_[7]), o[2]->ops->nvwsqrsumlocal(o[2], o[7]));
  EXPECT_EQ(N_VMaxNorm_Serial(lib_[2]), o[2]->ops->nvmaxnorm(o[2]));
  EXPECT_EQ(N_VMin_Serial(lib_[2]), o[2]->ops->nvmin(o[2]));
  N_VConst_Serial(0.25, lib_[0]);
  o[0]->ops->nvconst(0.25, o[0]);
  expect_same("const");
}

TEST_F(SerialVectorOps, FusedOperationsMatchTheLibrary) {
  std::vector<double> c = {1.0, 0.1, -0.2, 0.3, 0.3, -0.3, 1e-3, 2.0};
  for (int nvec = 1; nvec <= 8; ++nvec) {
    // z apart, then z = X_0 (with c_0 = 1 and c_0 != 1, the library's in-place cases)
    for (double c0 : {1.0, 0.7}) {
      c[0] = c0;
      N_VLinearCombination_Serial(nvec, c.data(), lib_.data(), lib_[8]);
      ours_[8]->ops->nvlinearcombination(nvec, c.data(), ours_.data(), ours_[8]);
      N_VLinearCombination_Serial(nvec, c.data(), lib_.data(), lib_[0]);
      ours_[0]->ops->nvlinearcombination(nvec, c.data(), ours_.data(), ours_[0]);
      expect_same("linear combination");
    }
    // two terms with equal and opposite coefficients (the linear sum's factored cases)
    std::vector<double> pair = {0.3, nvec % 2 ? 0.3 : -0.3};
    N_VLinearCombination_Serial(2, pair.data(), lib_.data() + 1, lib_[7]);
    ours_[7]->ops->nvlinearcombination(2, pair.data(), ours_.data() + 1, ours_[7]);
    // Z = Y + a x, apart and in place
    N_VScaleAddMulti_Serial(nvec, c.data(), lib_[0], lib_.data() + 1, lib_.data() + 1);
    ours_[1]->ops->nvscaleaddmulti(nvec, c.data(), ours_[0], ours_.data() + 1, ours_.data() + 1);
    expect_same("scale add multi (in place)");
    if (nvec <= 4) {
      N_VScaleAddMulti_Serial(nvec, c.data(), lib_[0], lib_.data() + 1, lib_.data() + 5);
      ours_[1]->ops->nvscaleaddmulti(nvec, c.data(), ours_[0], ours_.data() + 1, ours_.data() + 5);
      N_VScaleVectorArray_Serial(nvec, c.data(), lib_.data() + 1, lib_.data() + 5);
      ours_[5]->ops->nvscalevectorarray(nvec, c.data(), ours_.data() + 1, ours_.data() + 5);
      expect_same("scale add multi, scale vector array");
    }
  }
}

}  // namespace
}  // namespace fivebar::sim::detail
