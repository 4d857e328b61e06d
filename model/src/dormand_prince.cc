// Dormand-Prince 5(4) as SUNDIALS 6.4's ERKStep steps it (dormand_prince.h). The names follow
// the library's (arkode.c, arkode_adapt.c, arkode_erkstep.c); the comments say which of its
// routines each part reproduces. Compiled without contracting a*b + c into a fused multiply-add
// (model/CMakeLists.txt), as the library is.
#include "dormand_prince.h"

#include <arkode/arkode.h>
#include <arkode/arkode_butcher_erk.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace fivebar::sim::detail {
namespace {

constexpr double kUround = std::numeric_limits<double>::epsilon();
constexpr double kFuzz = 100.0;       // FUZZ_FACTOR
constexpr double kTiny = 1.0e-10;     // TINY
constexpr double kOnePsm = 1.000001;  // ONEPSM
constexpr double kOneMsm = 0.999999;  // ONEMSM
// ERKStep's defaults (ERKStepSetDefaults over arkSetDefaults)
constexpr double kSafety = 0.99, kBias = 1.2, kGrowth = 25.0, kK1 = 0.8, kK2 = 0.31;
constexpr double kEtaMx1 = 10000.0, kEtaMxf = 0.3, kEtaMin = 0.1, kCfl = 0.5;
constexpr double kLBound = 1.0, kUBound = 1.5;
constexpr int kSmallNef = 2;
constexpr int kEmbeddingOrder = 4;  // the controller's k (pq off: the embedding's order)

/// SUNMAX and SUNMIN (which differ from std::max and std::min where an argument is NaN)
double sun_max(double a, double b) { return a > b ? a : b; }
double sun_min(double a, double b) { return a < b ? a : b; }

/// z = sum_k c_k x_k of K vectors, accumulated in k order for each element
template <int K>
void combine_fixed(const double* c, const double* const* x, int n, double* z) {
  for (int i = 0; i < n; ++i) {
    double s = c[0] * x[0][i];
    for (int k = 1; k < K; ++k) s += c[k] * x[k][i];
    z[i] = s;
  }
}

/// z = sum_k c_k x_k (nvec from 2 to 8), accumulated in k order for each element: the
/// arithmetic of N_VLinearCombination of three or more vectors, and with two, where the second
/// coefficient is 1, of N_VLinearSum. z may be one of the x.
void combine(int nvec, const double* c, const double* const* x, int n, double* z) {
  switch (nvec) {
    case 2:
      return combine_fixed<2>(c, x, n, z);
    case 3:
      return combine_fixed<3>(c, x, n, z);
    case 4:
      return combine_fixed<4>(c, x, n, z);
    case 5:
      return combine_fixed<5>(c, x, n, z);
    case 6:
      return combine_fixed<6>(c, x, n, z);
    case 7:
      return combine_fixed<7>(c, x, n, z);
    default:
      return combine_fixed<8>(c, x, n, z);
  }
}

/// z = a x + b y as N_VLinearSum rounds it: a (x - y) where a = -b and neither is +-1
void linear_sum(double a, const double* x, double b, const double* y, int n, double* z) {
  const bool unit = a == 1.0 || a == -1.0 || b == 1.0 || b == -1.0;
  for (int i = 0; i < n; ++i) {
    if (!unit && a == b) {
      z[i] = a * (x[i] + y[i]);
    } else if (!unit && a == -b) {
      z[i] = a * (x[i] - y[i]);
    } else {
      z[i] = a * x[i] + b * y[i];
    }
  }
}

DormandPrince::Table load_table() {
  DormandPrince::Table t;
  ARKodeButcherTable B = ARKodeButcherTable_LoadERK(ARKODE_DORMAND_PRINCE_7_4_5);
  for (int i = 0; i < DormandPrince::kStages; ++i) {
    for (int j = 0; j < DormandPrince::kStages; ++j) t.A[i][j] = B->A[i][j];
    t.b[i] = B->b[i];
    t.c[i] = B->c[i];
    t.d[i] = B->d[i];
  }
  ARKodeButcherTable_Free(B);
  return t;
}

std::string printed(const char* format, double a, double b = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

}  // namespace

void DopriDense::set(double t_end, double step, const std::vector<double>& y0,
                     const std::vector<double>& y1, const std::vector<double> (&k)[7]) {
  // DOPRI5's coefficients of its continuous extension
  constexpr double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0;
  constexpr double d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0;
  constexpr double d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
  t_new = t_end;
  h = step;
  const size_t n = y0.size();
  for (size_t i = 0; i < n; ++i) {
    ydiff[i] = y1[i] - y0[i];
    bspl[i] = h * k[0][i] - ydiff[i];
    r4[i] = ydiff[i] - h * k[6][i] - bspl[i];
    r5[i] = h * (d1 * k[0][i] + d3 * k[2][i] + d4 * k[3][i] + d5 * k[4][i] + d6 * k[5][i] +
                 d7 * k[6][i]);
  }
}

void DopriDense::at(double t, double* y) const {
  const double theta = (t - (t_new - h)) / h, theta1 = 1.0 - theta;
  for (size_t i = 0; i < y_old.size(); ++i) {
    y[i] = y_old[i] + theta * (ydiff[i] + theta1 * (bspl[i] + theta * (r4[i] + theta1 * r5[i])));
  }
}

bool DopriDense::covers(double t) const {
  const double fuzz = kFuzz * kUround * (std::abs(t_new) + std::abs(h));
  return (t - (t_new - h - fuzz)) * (t - (t_new + fuzz)) <= 0.0;
}

DormandPrince::DormandPrince(int n, RhsFn rhs, void* user, double rtol,
                             const std::vector<double>& atol, int max_nef)
    : n_(n),
      rhs_(rhs),
      user_(user),
      rtol_(rtol),
      atol_(atol),
      max_nef_(max_nef),
      tab_(load_table()) {
  atol_has_zero_ = *std::min_element(atol_.begin(), atol_.end()) == 0.0;
  for (auto* v : {&yn_, &ycur_, &ewt_, &tmp_, &dense_.y_old, &dense_.ydiff, &dense_.bspl,
                  &dense_.r4, &dense_.r5}) {
    v->assign(n, 0.0);
  }
  for (auto& f : F_) f.assign(n, 0.0);
}

void DormandPrince::start(double t0, const double* y0, double t_stop) {
  // arkInit (FIRST_INIT), then arkSetStopTime
  tn_ = tcur_ = t0;
  std::copy(y0, y0 + n_, yn_.begin());
  nst_ = 0;
  ehist_[0] = ehist_[1] = 1.0;
  initsetup_ = true;
  has_step_ = false;
  tstop_ = t_stop;
  tstopset_ = true;
  message_.clear();
}

/// arkEwtSetSV: ewt = 1 / (rtol |y| + atol); false where a weight would not be positive
bool DormandPrince::set_weights(const double* y) {
  for (int i = 0; i < n_; ++i) tmp_[i] = rtol_ * std::abs(y[i]) + 1.0 * atol_[i];
  if (atol_has_zero_ && *std::min_element(tmp_.begin(), tmp_.end()) <= 0.0) return false;
  for (int i = 0; i < n_; ++i) ewt_[i] = 1.0 / tmp_[i];
  return true;
}

double DormandPrince::weighted_rms(const double* x) const {
  double sum = 0.0;
  for (int i = 0; i < n_; ++i) {
    const double p = x[i] * ewt_[i];
    sum += p * p;
  }
  return std::sqrt(sum / static_cast<double>(n_));
}

int DormandPrince::fail(int flag, const std::string& words) {
  message_ = "ARKODE/" + words;
  return flag;
}

/// arkInitialSetup: the weights, f(t0, y0), the interpolant's start, the first step's size
int DormandPrince::initial_setup() {
  if (!set_weights(yn_.data())) {
    return fail(ARK_ILL_INPUT, "arkInitialSetup: Some initial ewt component = 0.0 illegal.");
  }
  if (rhs_(tcur_, yn_.data(), F_[0].data(), user_) != 0) {
    return fail(ARK_RHSFUNC_FAIL, "ARKODE: " + printed("At t = %g, the right-hand side routine "
                                                       "failed in an unrecoverable manner.",
                                                       tcur_));
  }
  const double tout = tstop_;  // the simulator evolves to its stop time
  h_ = std::abs(tout - tcur_);
  if (h_ == 0.0) h_ = 1.0;
  const int flag = initial_step(tout);
  if (flag != ARK_SUCCESS) return flag;
  etamax_ = kEtaMx1;
  const double rh = std::abs(h_) * hmax_inv_;
  if (rh > 1.0) h_ /= rh;
  if (tstopset_ && (tcur_ + h_ - tstop_) * h_ > 0.0) h_ = (tstop_ - tcur_) * (1.0 - 4.0 * kUround);
  eta_ = 1.0;
  hprime_ = h_;
  return ARK_SUCCESS;
}

/// arkYddNorm: the weighted norm of (f(t + hg, y + hg f) - f) / hg
bool DormandPrince::ydd_norm(double hg, double* norm) {
  linear_sum(hg, F_[0].data(), 1.0, yn_.data(), n_, ycur_.data());
  if (rhs_(tcur_ + hg, ycur_.data(), tmp_.data(), user_) != 0) return false;
  linear_sum(1.0 / hg, tmp_.data(), -1.0 / hg, F_[0].data(), n_, tmp_.data());
  ycur_ = yn_;
  *norm = weighted_rms(tmp_.data());
  return true;
}

/// arkHin with arkUpperBoundH0 (the simulator integrates forward: sign +1)
int DormandPrince::initial_step(double tout) {
  const double tdiff = tout - tcur_, tdist = std::abs(tdiff);
  const double tround = kUround * sun_max(std::abs(tcur_), std::abs(tout));
  if (tdiff == 0.0 || tdist < 2.0 * tround) {
    return fail(ARK_TOO_CLOSE, "ARKODE: tout too close to t0 to start integration.");
  }
  const double hlb = 100.0 * tround;
  double hub_inv = 0.0;
  for (int i = 0; i < n_; ++i) {
    const double bound = 0.1 * std::abs(yn_[i]) + 1.0 * (1.0 / ewt_[i]);
    const double ratio = std::abs(F_[0][i]) / bound;
    if (ratio > hub_inv) hub_inv = ratio;  // N_VMaxNorm
  }
  double hub = 0.1 * tdist;
  if (hub * hub_inv > 1.0) hub = 1.0 / hub_inv;
  double hg = std::sqrt(hlb * hub);
  if (hub < hlb) {
    h_ = hg;
    return ARK_SUCCESS;
  }
  double hs = hg, hnew = hg, yddnrm = 0.0;
  constexpr int kIters = 4;  // H0_ITERS
  for (int count1 = 1; count1 <= kIters; ++count1) {
    if (!ydd_norm(hg, &yddnrm)) {
      return fail(ARK_RHSFUNC_FAIL, "ARKODE: " + printed("At t = %g, the right-hand side routine "
                                                         "failed in an unrecoverable manner.",
                                                         tcur_));
    }
    hs = hg;
    hnew = (yddnrm * hub * hub > 2.0) ? std::sqrt(2.0 / yddnrm) : std::sqrt(hg * hub);
    if (count1 == kIters) break;
    const double hrat = hnew / hg;
    if (hrat > 0.5 && hrat < 2.0) break;
    if (count1 > 1 && hrat > 2.0) {
      hnew = hg;
      break;
    }
    hg = hnew;
  }
  static_cast<void>(hs);
  double h0 = 0.5 * hnew;  // H0_BIAS
  if (h0 < hlb) h0 = hlb;
  if (h0 > hub) h0 = hub;
  h_ = h0;
  return ARK_SUCCESS;
}

/// erkStep_TakeStep with erkStep_ComputeSolutions: the stages, the solution into ycur and the
/// weighted error estimate
int DormandPrince::attempt(double* dsm) {
  double c[kStages + 1];
  const double* x[kStages + 1];
  for (int is = 1; is < kStages; ++is) {
    tcur_ = tn_ + tab_.c[is] * h_;
    int nvec = 0;
    for (int js = 0; js < is; ++js, ++nvec) {
      c[nvec] = h_ * tab_.A[is][js];
      x[nvec] = F_[js].data();
    }
    c[nvec] = 1.0;
    x[nvec++] = yn_.data();
    combine(nvec, c, x, n_, ycur_.data());
    const int flag = rhs_(tcur_, ycur_.data(), F_[is].data(), user_);
    if (flag < 0) return ARK_RHSFUNC_FAIL;
    if (flag > 0) return ARK_UNREC_RHSFUNC_ERR;
  }
  for (int j = 0; j < kStages; ++j) {
    c[j] = h_ * tab_.b[j];
    x[j] = F_[j].data();
  }
  c[kStages] = 1.0;
  x[kStages] = yn_.data();
  combine(kStages + 1, c, x, n_, ycur_.data());
  for (int j = 0; j < kStages; ++j) c[j] = h_ * (tab_.b[j] - tab_.d[j]);
  combine(kStages, c, x, n_, tmp_.data());
  *dsm = weighted_rms(tmp_.data());
  return ARK_SUCCESS;
}

/// arkAdapt with ERKStep's PI controller: eta for the next attempt or step
void DormandPrince::adapt(double dsm) {
  const double hcur = h_, ecur = kBias * dsm;
  const double k1 = -kK1 / kEmbeddingOrder, k2 = kK2 / kEmbeddingOrder;
  const double e1 = sun_max(ecur, kTiny), e2 = sun_max(ehist_[0], kTiny);
  double h_acc = hcur * std::pow(e1, k1) * std::pow(e2, k2);
  const double int_dir = hcur / std::abs(hcur);
  double h_cfl = 1.0e30 * std::abs(hcur);  // arkExpStab: no stability limit
  h_acc *= kSafety;
  h_cfl *= kCfl * int_dir;
  h_acc = int_dir * sun_min(std::abs(h_acc), std::abs(etamax_ * hcur));
  h_acc = int_dir * sun_max(std::abs(h_acc), std::abs(kEtaMin * hcur));
  h_acc = int_dir * sun_min(std::abs(h_acc), std::abs(h_cfl));
  if (dsm <= 1.0 && std::abs(h_acc) > std::abs(hcur * kLBound * kOneMsm) &&
      std::abs(h_acc) < std::abs(hcur * kUBound * kOnePsm)) {
    h_acc = hcur;
  }
  eta_ = h_acc / hcur;
  eta_ = sun_max(eta_, 0.0 / std::abs(hcur));  // hmin = 0
  eta_ /= sun_max(1.0, std::abs(hcur) * hmax_inv_ * eta_);
}

/// arkCheckTemporalError: ARK_SUCCESS, TRY_AGAIN (1) with eta set, or ARK_ERR_FAILURE
int DormandPrince::check_error(double dsm, int* nef) {
  adapt(dsm);
  if (dsm <= 1.0) return ARK_SUCCESS;
  ++*nef;
  if (*nef == max_nef_) return ARK_ERR_FAILURE;
  etamax_ = 1.0;
  if (*nef >= kSmallNef) eta_ = sun_min(eta_, kEtaMxf);
  return 1;
}

/// arkCompleteStep: the new time (snapped to the stop time within rounding), the interpolant's
/// ends, the first-same-as-last slope, the error history
void DormandPrince::complete_step(double dsm) {
  tcur_ = tn_ + h_;
  if (tstopset_ && std::abs(tcur_ - tstop_) <= kFuzz * kUround * (std::abs(tcur_) + std::abs(h_))) {
    tcur_ = tstop_;
  }
  dense_.set(tcur_, h_, yn_, ycur_, F_);
  // the step's start moves into the interpolant, its end into yn and its last slope into F[0]
  // (c = 1 at the last stage: f(t_new, y_new)); ycur and F[6], left with the old contents, are
  // written before they are read
  std::swap(dense_.y_old, yn_);
  std::swap(yn_, ycur_);
  std::swap(F_[0], F_[kStages - 1]);
  ehist_[1] = ehist_[0];
  ehist_[0] = dsm * kBias;
  ++nst_;
  tn_ = tcur_;
  hprime_ = h_ * eta_;
  etamax_ = kGrowth;
  initsetup_ = false;
  has_step_ = true;
}

/// arkEvolve's and arkStopTests' limit: the next step ends before the stop time
void DormandPrince::limit_to_stop() {
  if (tstopset_ && (tcur_ + hprime_ - tstop_) * h_ > 0.0) {
    hprime_ = (tstop_ - tcur_) * (1.0 - 4.0 * kUround);
    eta_ = hprime_ / h_;
  }
}

int DormandPrince::step(double* y, double* t) {
  message_.clear();
  if (initsetup_) {
    tretlast_ = tcur_;
    const int flag = initial_setup();
    if (flag != ARK_SUCCESS) return flag;
  } else {
    limit_to_stop();  // arkStopTests (one-step mode: tcur was returned last time)
  }
  if (!initsetup_ && !set_weights(yn_.data())) {
    return fail(ARK_ILL_INPUT,
                "arkEvolve: " + printed("At t = %g, a component of ewt has become <= 0.", tcur_));
  }
  if (kUround * weighted_rms(yn_.data()) > 1.0) {
    return fail(ARK_TOO_MUCH_ACC,
                "arkEvolve: " + printed("At t = %g, too much accuracy requested.", tcur_));
  }
  if (hprime_ != h_) h_ = h_ * eta_;
  double dsm = 0.0;
  int nef = 0;
  for (;;) {
    int flag = attempt(&dsm);
    if (flag == ARK_RHSFUNC_FAIL || flag == ARK_UNREC_RHSFUNC_ERR) {
      const char* what = flag == ARK_RHSFUNC_FAIL
                             ? "the right-hand side routine failed in an unrecoverable manner."
                             : "the right-hand side failed in a recoverable manner, but no "
                               "recovery is possible.";
      return fail(flag, "ARKODE: " + printed("At t = %g, ", tcur_) + what);
    }
    flag = check_error(dsm, &nef);
    if (flag == ARK_ERR_FAILURE) {
      return fail(flag, "ARKODE: " + printed("At t = %g and h = %g, the error test failed "
                                             "repeatedly or with |h| = hmin.",
                                             tcur_, h_));
    }
    eta_ = sun_min(eta_, etamax_);
    eta_ = sun_max(eta_, 0.0 / std::abs(h_));
    eta_ /= sun_max(1.0, std::abs(h_) * hmax_inv_ * eta_);
    if (flag == ARK_SUCCESS) break;
    h_ *= eta_;
    hprime_ = h_;
  }
  complete_step(dsm);
  if (tstopset_) {
    if (tcur_ == tstop_) {  // (complete_step puts the step's end on the stop time within rounding)
      std::copy(yn_.begin(), yn_.end(), y);
      tretlast_ = *t = tstop_;
      tstopset_ = false;
      return ARK_TSTOP_RETURN;
    }
    limit_to_stop();
  }
  tretlast_ = *t = tcur_;
  std::copy(yn_.begin(), yn_.end(), y);
  return ARK_SUCCESS;
}

int DormandPrince::dense(double t, double* y) {
  if (!has_step_ || !dense_.covers(t)) {
    return fail(ARK_BAD_T, "arkGetDky: " + printed("Illegal value for t. t = %g is not within the "
                                                   "last step, which ends at %g.",
                                                   t, dense_.t_new));
  }
  dense_.at(t, y);
  return ARK_SUCCESS;
}

}  // namespace fivebar::sim::detail
