// The serial N_Vector's per-step operations, compiled with the project's optimization: the
// distribution's SUNDIALS library is built without it (-O0), and on a 7-element state its vector
// calls cost ERKStep and CVODE more than their own bookkeeping. Each operation does the
// arithmetic of SUNDIALS 6.4's serial vector element by element in the same order (same
// products, same sums, same special cases where those round differently), so every result is
// bit-identical to the library's; this file is compiled without contracting a*b + c into a
// fused multiply-add (model/CMakeLists.txt), as the library is.
#include "serial_vector_ops.h"

#include <cmath>

namespace fivebar::sim::detail {
namespace {

double* data(N_Vector v) { return NV_DATA_S(v); }
sunindextype length(N_Vector v) { return NV_LENGTH_S(v); }

/// z = a x + b y. Where a and b are neither 1 nor -1, equal or opposite coefficients are
/// factored out, a (x + y) and a (x - y), which round differently from a x + b y; every other
/// case (an axpy, a copy, a difference) gives the bits of a x + b y.
void linear_sum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  const sunindextype n = length(x);
  const bool unit = a == 1.0 || a == -1.0 || b == 1.0 || b == -1.0;
  if (!unit && a == b) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * (xd[i] + yd[i]);
  } else if (!unit && a == -b) {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * (xd[i] - yd[i]);
  } else {
    for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
  }
}

void constant(realtype c, N_Vector z) {
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = c;
}

void prod(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = xd[i] * yd[i];
}

void div(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = xd[i] / yd[i];
}

void scale(realtype c, N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = c * xd[i];
}

void abs(N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = std::abs(xd[i]);
}

void inv(N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = 1.0 / xd[i];
}

void add_const(N_Vector x, realtype b, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(x); i < n; ++i) zd[i] = xd[i] + b;
}

realtype max_norm(N_Vector x) {
  const double* xd = data(x);
  double m = 0.0;
  for (sunindextype i = 0, n = length(x); i < n; ++i) {
    if (std::abs(xd[i]) > m) m = std::abs(xd[i]);
  }
  return m;
}

/// sum of (x_i w_i)^2, in index order
realtype weighted_square_sum(N_Vector x, N_Vector w) {
  const double *xd = data(x), *wd = data(w);
  double sum = 0.0;
  for (sunindextype i = 0, n = length(x); i < n; ++i) {
    const double p = xd[i] * wd[i];
    sum += p * p;
  }
  return sum;
}

realtype wrms_norm(N_Vector x, N_Vector w) {
  return std::sqrt(weighted_square_sum(x, w) / static_cast<double>(length(x)));
}

realtype min(N_Vector x) {
  const double* xd = data(x);
  double m = xd[0];
  for (sunindextype i = 1, n = length(x); i < n; ++i) {
    if (xd[i] < m) m = xd[i];
  }
  return m;
}

/// z = sum_k c_k X_k, accumulated in k order for each element (two terms: a linear sum, with
/// its factored cases). z may be X_0.
int linear_combination(int nvec, realtype* c, N_Vector* X, N_Vector z) {
  if (nvec < 1) return -1;
  if (nvec == 1) {
    scale(c[0], X[0], z);
    return 0;
  }
  if (nvec == 2) {
    linear_sum(c[0], X[0], c[1], X[1], z);
    return 0;
  }
  double* zd = data(z);
  const sunindextype n = length(z);
  constexpr sunindextype kShort = 16;  // longer than any fivebar state
  if (n > kShort) {                    // vector by vector (z is not one of X_1 ..)
    scale(c[0], X[0], z);
    for (int k = 1; k < nvec; ++k) {
      const double* xd = data(X[k]);
      for (sunindextype i = 0; i < n; ++i) zd[i] += c[k] * xd[i];
    }
    return 0;
  }
  double s[kShort];  // the sums, apart from z (which may be X_0)
  const double* x0 = data(X[0]);
  for (sunindextype i = 0; i < n; ++i) s[i] = c[0] * x0[i];
  for (int k = 1; k < nvec; ++k) {
    const double* xd = data(X[k]);
    for (sunindextype i = 0; i < n; ++i) s[i] += c[k] * xd[i];
  }
  for (sunindextype i = 0; i < n; ++i) zd[i] = s[i];
  return 0;
}

/// Z_k = a_k x + Y_k (Z may be Y)
int scale_add_multi(int nvec, realtype* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  if (nvec < 1) return -1;
  const double* xd = data(x);
  const sunindextype n = length(x);
  for (int k = 0; k < nvec; ++k) {
    const double* yd = data(Y[k]);
    double* zd = data(Z[k]);
    for (sunindextype i = 0; i < n; ++i) zd[i] = a[k] * xd[i] + yd[i];
  }
  return 0;
}

/// Z_k = c_k X_k (Z may be X)
int scale_vector_array(int nvec, realtype* c, N_Vector* X, N_Vector* Z) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) scale(c[k], X[k], Z[k]);
  return 0;
}

}  // namespace

void use_compiled_serial_ops(N_Vector v) {
  N_Vector_Ops ops = v->ops;
  ops->nvlinearsum = &linear_sum;
  ops->nvconst = &constant;
  ops->nvprod = &prod;
  ops->nvdiv = &div;
  ops->nvscale = &scale;
  ops->nvabs = &abs;
  ops->nvinv = &inv;
  ops->nvaddconst = &add_const;
  ops->nvmaxnorm = &max_norm;
  ops->nvwrmsnorm = &wrms_norm;
  ops->nvwsqrsumlocal = &weighted_square_sum;
  ops->nvmin = &min;
  ops->nvlinearcombination = &linear_combination;
  ops->nvscaleaddmulti = &scale_add_multi;
  ops->nvscalevectorarray = &scale_vector_array;
}

}  // namespace fivebar::sim::detail
