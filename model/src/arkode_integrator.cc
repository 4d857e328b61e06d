// ARKODE behind the Integrator interface: ERKStep for the explicit Runge-Kutta pairs
// (Dormand-Prince 5(4), Verner 6(5), Fehlberg 7(8)) and ARKStep for the implicit DIRK
// (ARK5(4)8L[2]SA, Newton with a dense Jacobian). Dormand-Prince is stepped by dormand_prince.cc,
// ERKStep's algorithm compiled with the project, the library's ERKStep checking its settings.
// Every call's flag is checked; flag names come from ERKStepGetReturnFlagName /
// ARKStepGetReturnFlagName.
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "dormand_prince.h"
#include "sundials_common.h"

namespace fivebar::sim::detail {
namespace {

constexpr int kMaxErrTestFails = 20;  ///< per step (ARKODE's default is 7)

/// One end of the last step: time, state and (lazily) its slope f(t, y).
struct StepEnd {
  double t = 0;
  std::vector<double> y, f;
  bool has_f = false;
};

class Arkode final : public Integrator {
 public:
  Arkode(const OdeProblem& prob, const Options& opt, double t_end)
      : prob_(prob), explicit_(opt.method != Method::kArkodeDirk), t_end_(t_end), sc_(prob, opt) {
    for (StepEnd* e : {&prev_, &cur_, &cache_}) {
      e->y.assign(prob.n, 0.0);
      e->f.assign(prob.n, 0.0);
    }
    ok_ = sc_.ready && (explicit_ ? setup_erk(opt) : setup_dirk(opt));
    if (ok_ && opt.method == Method::kArkodeErk45) {
      // the library's ERKStep keeps checking the settings (tolerances, step limit) as it
      // receives them; the steps are taken by the compiled copy of its algorithm
      own_ = std::make_unique<DormandPrince>(prob.n, &Arkode::evaluate_for, this, opt.rtol, atol(),
                                             kMaxErrTestFails);
    }
  }
  ~Arkode() override {
    if (mem_) {
      if (explicit_) {
        ERKStepFree(&mem_);
      } else {
        ARKStepFree(&mem_);
      }
    }
  }

  bool start(double t0, const double* y0) override {
    long n = 0;
    if (!ok_ || !current_steps(&n)) return false;
    sc_.steps_before += n;
    sc_.load(y0, prob_.n);
    cur_.t = t0;
    std::copy(y0, y0 + prob_.n, cur_.y.begin());
    cur_.has_f = false;
    cache_.has_f = false;  // the modes may have changed at a restart: no earlier evaluation holds
    if (own_) own_->start(t0, y0, t_end_);
    if (explicit_) {
      return check(ERKStepReInit(mem_, &Arkode::rhs, t0, sc_.y), "ERKStepReInit") &&
             check(ERKStepSetStopTime(mem_, t_end_), "ERKStepSetStopTime");
    }
    return check(ARKStepReInit(mem_, nullptr, &Arkode::rhs, t0, sc_.y), "ARKStepReInit") &&
           check(ARKStepSetStopTime(mem_, t_end_), "ARKStepSetStopTime");
  }
  bool set_max_step(double h) override {
    if (own_) own_->set_max_step(h);
    return explicit_ ? check(ERKStepSetMaxStep(mem_, h), "ERKStepSetMaxStep")
                     : check(ARKStepSetMaxStep(mem_, h), "ARKStepSetMaxStep");
  }
  bool step(double* y, double* t) override {
    std::swap(prev_, cur_);
    int flag = 0;
    if (own_) {
      flag = own_->step(y, t);
      if (flag < 0) sc_.solver_message = own_->message();
    } else {
      flag = explicit_ ? ERKStepEvolve(mem_, t_end_, sc_.y, t, ARK_ONE_STEP)
                       : ARKStepEvolve(mem_, t_end_, sc_.y, t, ARK_ONE_STEP);
      sc_.store(y, prob_.n);
    }
    cur_.t = *t;
    std::copy(y, y + prob_.n, cur_.y.begin());
    cur_.has_f = false;
    // the step's end slope while the last evaluation is there (the first-same-as-last stage),
    // before later evaluations replace it, whether or not the switch scan samples this step
    slope_from_cache(&cur_);
    return check(flag, explicit_ ? "ERKStepEvolve" : "ARKStepEvolve");
  }
  bool dense(double t, double* y) override {
    if (own_) {
      const int flag = own_->dense(t, y);
      if (flag < 0) sc_.solver_message = own_->message();
      return check(flag, "ERKStepGetDky");
    }
    NV_DATA_S(sc_.out) = y;  // a view of the caller's array: no allocation per call
    const int flag = explicit_ ? ERKStepGetDky(mem_, t, 0, sc_.out)
                               : ARKStepGetDky(mem_, t, 0, sc_.out);
    return check(flag, explicit_ ? "ERKStepGetDky" : "ARKStepGetDky");
  }
  bool sample(double t, double* y) override {
    if (!slope(&prev_) || !slope(&cur_)) return false;
    // cubic Hermite on [prev, cur]
    const double h = cur_.t - prev_.t;
    const double s = h != 0.0 ? (t - prev_.t) / h : 1.0;
    const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
    const double h01 = s * s * (3 - 2 * s), h11 = -s * s * (1 - s);
    for (int i = 0; i < prob_.n; ++i) {
      y[i] = h00 * prev_.y[i] + h * h10 * prev_.f[i] + h01 * cur_.y[i] + h * h11 * cur_.f[i];
    }
    return true;
  }
  bool steps(long* n) override {
    if (!current_steps(n)) return false;
    *n += sc_.steps_before;
    return true;
  }
  std::string error() const override { return sc_.error; }

 private:
  bool setup_erk(const Options& opt) {
    mem_ = ERKStepCreate(&Arkode::rhs, 0.0, sc_.y, sc_.ctx);
    if (!check_created(mem_, "ERKStepCreate", &sc_.error) ||
        !check(ERKStepSetErrHandlerFn(mem_, &SundialsCommon::on_error, &sc_),
               "ERKStepSetErrHandlerFn")) {
      return false;
    }
    // ARKODE names tables NAME_stages_embedding_order. Dense output: ARKODE's default Hermite
    // interpolant, of degree order - 1 up to 5 (cubic Hermite or Lagrange lose one to two digits
    // at the 1 ms grid, measured with `fivebar accuracy`); Dormand-Prince steps in
    // dormand_prince.cc with its own continuous extension, no extra right-hand side
    const auto table = opt.method == Method::kArkodeErk45   ? ARKODE_DORMAND_PRINCE_7_4_5
                       : opt.method == Method::kArkodeErk65 ? ARKODE_VERNER_8_5_6
                                                            : ARKODE_FEHLBERG_13_7_8;
    return check(ERKStepSetTableNum(mem_, table), "ERKStepSetTableNum") &&
           check(ERKStepSVtolerances(mem_, opt.rtol, sc_.atol), "ERKStepSVtolerances") &&
           check(ERKStepSetUserData(mem_, this), "ERKStepSetUserData") &&
           check(ERKStepSetMaxNumSteps(mem_, opt.max_steps), "ERKStepSetMaxNumSteps") &&
           // a kink that is not located (switches not located) costs a high-order pair more
           // than ARKODE's default 7 error-test failures to step over at tight tolerances
           check(ERKStepSetMaxErrTestFails(mem_, kMaxErrTestFails), "ERKStepSetMaxErrTestFails");
  }
  bool setup_dirk(const Options& opt) {
    mem_ = ARKStepCreate(nullptr, &Arkode::rhs, 0.0, sc_.y, sc_.ctx);
    if (!check_created(mem_, "ARKStepCreate", &sc_.error)) return false;
    bool ok = check(ARKStepSetErrHandlerFn(mem_, &SundialsCommon::on_error, &sc_),
                    "ARKStepSetErrHandlerFn") &&
              check(ARKStepSetTableNum(mem_, ARKODE_ARK548L2SA_DIRK_8_4_5, ARKODE_ERK_NONE),
                    "ARKStepSetTableNum");
    // Lagrange dense output for stiff states, as ARKODE recommends: the Hermite one overshoots
    // LuGre bristles at output times; elsewhere Hermite is two digits more accurate
    // (both measured with `fivebar stress` and `fivebar accuracy`)
    if (prob_.stiff_states) {
      ok = ok && check(ARKStepSetInterpolantType(mem_, ARK_INTERP_LAGRANGE),
                       "ARKStepSetInterpolantType");
    }
    return ok && sc_.make_dense_solver(prob_.n) &&
           check(ARKStepSVtolerances(mem_, opt.rtol, sc_.atol), "ARKStepSVtolerances") &&
           check(ARKStepSetUserData(mem_, this), "ARKStepSetUserData") &&
           check(ARKStepSetMaxNumSteps(mem_, opt.max_steps), "ARKStepSetMaxNumSteps") &&
           check(ARKStepSetMaxErrTestFails(mem_, kMaxErrTestFails), "ARKStepSetMaxErrTestFails") &&
           check(ARKStepSetLinearSolver(mem_, sc_.ls, sc_.A), "ARKStepSetLinearSolver") &&
           (!prob_.freeze || check(ARKStepSetJacFn(mem_, &Arkode::jacobian), "ARKStepSetJacFn"));
  }
  /// the absolute tolerances the library was given
  std::vector<double> atol() const {
    const double* a = NV_DATA_S(sc_.atol);
    return std::vector<double>(a, a + prob_.n);
  }
  bool check(int flag, const char* call) {
    return check_flag(flag, call, explicit_ ? &ERKStepGetReturnFlagName : &ARKStepGetReturnFlagName,
                      &sc_.solver_message, &sc_.error);
  }
  /// f(t, y) at one end of the step: from the last right-hand side ARKODE evaluated there (the
  /// first-same-as-last stage of Dormand-Prince), else evaluated here.
  bool slope(StepEnd* e) {
    if (e->has_f || slope_from_cache(e)) return true;
    if (prob_.rhs(e->t, e->y.data(), e->f.data(), prob_.user) != 0) {
      sc_.error = "right-hand side failed at a sampled point";
      return false;
    }
    e->has_f = true;
    return true;
  }
  /// f(t, y) at one end of the step from the last evaluation, when that was there.
  bool slope_from_cache(StepEnd* e) {
    const size_t bytes = sizeof(double) * prob_.n;
    if (!cache_.has_f || cache_.t != e->t ||
        std::memcmp(cache_.y.data(), e->y.data(), bytes) != 0) {
      return false;
    }
    e->f = cache_.f;
    e->has_f = true;
    return true;
  }
  /// Steps since the last (re)start; 0 before the solver exists.
  bool current_steps(long* n) {
    *n = 0;
    if (own_) {
      *n = own_->steps();
      return true;
    }
    if (!mem_) return true;
    return explicit_ ? check(ERKStepGetNumSteps(mem_, n), "ERKStepGetNumSteps")
                     : check(ARKStepGetNumSteps(mem_, n), "ARKStepGetNumSteps");
  }
  /// The right-hand side for ARKODE. An evaluation at exactly the point of the last one is
  /// served from it: Dormand-Prince's last stage is the step's end (y_{n+1}, computed with the
  /// same coefficients), where ARKODE evaluates f again for the next step and the interpolant
  /// (first-same-as-last, which ERKStep does not exploit itself).
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* self) {
    // the serial vector's data (the library's accessors: two unoptimized calls each)
    return static_cast<Arkode*>(self)->evaluate(t, NV_DATA_S(y), NV_DATA_S(ydot));
  }
  int evaluate(double t, const double* yp, double* fp) {
    StepEnd& c = cache_;  // the last evaluation, for slope() and the repeat
    int flag = 0;
    if (c.has_f && c.t == t && std::memcmp(yp, c.y.data(), sizeof(double) * prob_.n) == 0) {
      std::copy(c.f.begin(), c.f.end(), fp);
    } else {
      flag = prob_.rhs(t, yp, fp, prob_.user);
      c.has_f = flag == 0;
      if (c.has_f) {
        c.t = t;
        std::copy(yp, yp + prob_.n, c.y.begin());
        std::copy(fp, fp + prob_.n, c.f.begin());
      }
    }
    return flag;
  }
  /// The right-hand side for the compiled Dormand-Prince (DormandPrince): as for ARKODE's.
  static int evaluate_for(double t, const double* y, double* f, void* self) {
    return static_cast<Arkode*>(self)->evaluate(t, y, f);
  }
  /// Newton Jacobian by forward differences with the switched parts of the right-hand side
  /// frozen at y (OdeProblem::freeze). ARKODE's own difference quotients would divide a Coulomb
  /// sign flip by an increment of ~1e-20 where a rate is near zero: the huge Jacobian then makes
  /// every Newton update tiny, and stage values that do not solve their equations pass the
  /// convergence test (a run then ends with angles inconsistent with its rates).
  static int jacobian(realtype t, N_Vector y, N_Vector, SUNMatrix J, void* self, N_Vector tmp1,
                      N_Vector tmp2, N_Vector) {
    auto* me = static_cast<Arkode*>(self);
    const int n = me->prob_.n;
    double* yp = N_VGetArrayPointer(y);
    double* f0 = N_VGetArrayPointer(tmp1);
    double* f1 = N_VGetArrayPointer(tmp2);
    me->prob_.freeze(yp, true, me->prob_.user);
    int flag = me->prob_.rhs(t, yp, f0, me->prob_.user);
    const double root_eps = std::sqrt(std::numeric_limits<double>::epsilon());
    for (int j = 0; j < n && flag == 0; ++j) {
      const double yj = yp[j];
      const double h = root_eps * std::max(std::abs(yj), 1.0);
      yp[j] = yj + h;
      flag = me->prob_.rhs(t, yp, f1, me->prob_.user);
      yp[j] = yj;
      double* col = SUNDenseMatrix_Column(J, j);
      for (int i = 0; i < n; ++i) col[i] = (f1[i] - f0[i]) / h;
    }
    me->prob_.freeze(yp, false, me->prob_.user);
    return flag == 0 ? 0 : 1;  // > 0: recoverable, ARKODE retries with a smaller step
  }
  OdeProblem prob_;
  bool explicit_;
  double t_end_;
  SundialsCommon sc_;
  bool ok_ = false;
  void* mem_ = nullptr;
  StepEnd prev_, cur_, cache_;
  /// Dormand-Prince stepped by the compiled copy of ERKStep's algorithm (null: the library steps)
  std::unique_ptr<DormandPrince> own_;
};

}  // namespace

std::unique_ptr<Integrator> make_arkode(const OdeProblem& prob, const Options& opt,
                                        double t_end) {
  return std::make_unique<Arkode>(prob, opt, t_end);
}

}  // namespace fivebar::sim::detail
