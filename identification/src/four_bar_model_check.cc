// The four-bar's model checks (identify_four_bar.cc): its residual against the noise floor, and
// the five-bar's candidate causes that exist for one crank, freed on the four-bar's Jacobian,
// judged by the five-bar's comparison (model_check_causes.h). Columns, rows whitened by the noise
// floor: the fitted parameters (the residual's Jets), the links' masses, inertias and centres of
// mass (relative, with the prior --inertia-prior; with the inertias fitted, --estimate inertia,
// they are fitted columns and the fit's prior rows follow the samples' instead), the crank
// encoder's zero, tau1's offset (unless the fit has it, --estimate actuator) and gain, and the
// delay (the logged torque's rate), each by central differences where not linear.
#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "fivebar/model/format.h"
#include "four_bar_fit.h"
#include "mechanism_residual.h"
#include "model_check_causes.h"
#include "setup_shared.h"

namespace fivebar::identification::four_bar {

namespace {

using stages::CauseSteps;

/// The inertial parameters freed per link: mass, inertia, centre-of-mass offset (relative to the
/// scene's value; the offset relative to the link's length)
constexpr int kPerLink = 3;

/// The model's drive torque at every sample for the scene `p` (the samples' angles moved by
/// -offset), and with `dx` the rows of d r / d x; false where the model fails.
bool model_torques(const FourBarFit& f, const FourBarParams& p, double offset, Eigen::VectorXd* M,
                   Eigen::MatrixXd* dx = nullptr) {
  const int n = static_cast<int>(f.samples.size());
  M->resize(n);
  if (dx) dx->resize(n, f.layout.size());
  for (int u = 0; u < n; ++u) {
    Sample s = f.samples[u];
    s.q[0] -= offset;
    mech::Vec<1, double> tq;
    Eigen::MatrixXd d;
    if (!stages::mechanism_drive_torques<FourBar>(p, f.layout, f.x.data(), s, f.eval, &tq,
                                                  dx ? &d : nullptr)) {
      return false;
    }
    (*M)(u) = tq(0);
    if (dx) dx->row(u) = d.row(0);
  }
  return M->allFinite();
}

/// The scene with link k's inertial parameter j moved by h (relative units)
FourBarParams moved(const FourBarParams& p, int k, int j, double h) {
  FourBarParams q = p;
  Link<double>& l = q.links[k];
  if (j == 0) l.mass *= 1 + h;
  if (j == 1) l.inertia *= 1 + h;
  if (j == 2) l.com_offset += h * l.length;
  return q;
}

/// The motor's Coulomb and viscous friction columns (stages::motor_friction_columns) when the
/// fit leaves them out (--estimate actuator fits them), those unlike an offset
/// (stages::motor_terms: not a crank that turns one way only); `terms`: their actuator terms.
Eigen::MatrixXd motor_columns(const FourBarFit& f, std::vector<int>* terms) {
  const Eigen::Index n = static_cast<Eigen::Index>(f.samples.size());
  terms->clear();
  if (f.layout.actuator) return Eigen::MatrixXd(n, 0);
  Eigen::MatrixXd D(n, 2);
  for (Eigen::Index u = 0; u < n; ++u) {
    const Sample& s = f.samples[u];
    D.row(u) = stages::motor_friction_columns(f.scene.friction, f.eval, s.v[0], s.a[0]).transpose();
  }
  *terms = stages::motor_terms(D, 1);
  Eigen::MatrixXd Jm(n, static_cast<Eigen::Index>(terms->size()));
  for (size_t k = 0; k < terms->size(); ++k) Jm.col(k) = D.col((*terms)[k] - 1);
  return Jm;
}

/// The fit's prior rows on the fitted inertial parameters (the inertial group: the residual
/// blocks of detail::inertial_prior_cost at f.x, weighed as in the fit by f.prior_scale), rp and
/// their Jacobian Jp on the P fitted parameters; empty without the group; false where the
/// evaluation fails.
bool prior_rows(const FourBarFit& f, Eigen::MatrixXd* Jp, Eigen::VectorXd* rp) {
  const int P = f.layout.size();
  if (!f.layout.inertia) {
    Jp->resize(0, P);
    rp->resize(0);
    return true;
  }
  const std::unique_ptr<ceres::CostFunction> cost(
      detail::inertial_prior_cost(f.prior, P, f.layout.inertia_offset(), &f.prior_scale));
  const int m = cost->num_residuals();
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jac(m, P);
  rp->resize(m);
  const double* x = f.x.data();
  double* jacobians[] = {jac.data()};
  if (!cost->Evaluate(&x, rp->data(), jacobians)) return false;
  *Jp = jac;
  return Jp->allFinite() && rp->allFinite();
}

/// The check's whitened Jacobian J and residual r, and its index sets (fitted, inertial, angle
/// offset, torque readings, the motor's friction where the fit leaves it out, delay:
/// model_check_causes.h); false where an evaluation fails. With the inertial group fitted its
/// parameters are among the fitted columns, and the fit's prior rows (prior_rows) follow the
/// samples' (zero in the causes' columns): without them the directions the log leaves to the
/// prior make every refit singular. The inertial cause then has no columns (it would free the
/// fitted parameters twice).
bool check_jacobian(const FourBarFit& f, const IdentifyResult& out, Eigen::MatrixXd* J,
                    Eigen::VectorXd* r, stages::CauseColumns& idx) {
  constexpr double h = 1e-6;
  const double fl = out.residual_noise_floor[0];
  const int n = static_cast<int>(f.samples.size()), P = f.layout.size();
  Eigen::VectorXd M, Mp, Mm, tau(n), rp;
  Eigen::MatrixXd dx, Jp;
  if (!model_torques(f, f.scene, 0, &M, &dx) || !prior_rows(f, &Jp, &rp)) return false;
  for (int u = 0; u < n; ++u) tau(u) = f.samples[u].tau[0];
  const int ni = f.layout.inertia ? 0 : kFourBarLinks * kPerLink;
  const bool delay = f.opt->estimate_delay;
  // the fit's own offset and motor friction (--estimate actuator) are not freed again by the
  // torque readings' and the motors' causes
  const bool fitted_offset = f.layout.actuator;
  std::vector<int> terms;
  const Eigen::MatrixXd Jm = motor_columns(f, &terms);
  const Eigen::Index rows = n + rp.size();
  J->setZero(rows, P + ni + (fitted_offset ? 2 : 3) + Jm.cols() + (delay ? 1 : 0));
  J->topLeftCorner(n, P) = -dx;  // dx: the torques' derivatives
  J->bottomLeftCorner(rp.size(), P) = Jp;
  for (int i = 0; i < P; ++i) idx[0].push_back(i);
  int c = P;
  for (int k = 0; k < ni / kPerLink; ++k) {
    for (int j = 0; j < kPerLink; ++j, ++c) {
      if (!model_torques(f, moved(f.scene, k, j, h), 0, &Mp) ||
          !model_torques(f, moved(f.scene, k, j, -h), 0, &Mm)) {
        return false;
      }
      J->col(c).head(n) = -(Mp - Mm) / (2 * h);
      idx[stages::kCauseInertia + 1].push_back(c);
    }
  }
  // theta1 reads d more than the scene's angle: the model at theta1 - d
  if (!model_torques(f, f.scene, h, &Mp) || !model_torques(f, f.scene, -h, &Mm)) return false;
  J->col(c).head(n) = -(Mp - Mm) / (2 * h);
  idx[stages::kCauseAngles + 1].push_back(c++);
  for (Eigen::Index k = 0; k < Jm.cols(); ++k) {
    J->col(c).head(n) = Jm.col(k);
    idx[stages::kCauseMotors + 1].push_back(c++);
  }
  // tau1 = (1 + g) M + o, M the model's torque (less the fitted offset)
  if (!fitted_offset) {
    J->col(c).head(n).setConstant(-1.0);
    idx[stages::kCauseTorque + 1].push_back(c++);
  }
  const double o = fitted_offset ? f.x[f.layout.actuator_offset()] : 0.0;
  J->col(c).head(n) = -(M.array() - o).matrix();
  idx[stages::kCauseTorque + 1].push_back(c++);
  if (delay) {  // tau1 lagging by d reads the torque of t + d: its rate (the delay's regressor)
    const TorqueLog& log = f.cond.log;
    std::vector<std::vector<double>> rate;
    stages::delay_regressor(log.t, {&log.tau1}, f.noise.torque, f.index, f.sg.half_window_s, &rate);
    for (int u = 0; u < n; ++u) (*J)(u, c) = rate[0][f.index[u]];
    idx[stages::kCauseDelay + 1].push_back(c++);
  }
  *J /= fl;
  r->resize(rows);
  *r << (tau - M) / fl, rp / fl;
  return J->allFinite() && r->allFinite();
}

/// The score's expectation under the acceleration noise alone (the five-bar's score_bias): an
/// estimated acceleration's noise (std accel_noise) enters a row of J and its residual alike, so
/// J^T r has the mean sum_u accel_noise^2 (dJ_u / da) (dr_u / da) on a clean log (without it a
/// clean double rocker's inertias read a fall of 1.6e3 against 6 for the noise alone). The
/// derivatives by central differences over the noise's own scale; empty where the
/// accelerations are logged.
bool score_bias(const FourBarFit& f, const IdentifyResult& out, Eigen::VectorXd* b) {
  b->resize(0);
  if (!out.accels_estimated || !(f.accel_noise > 0)) return true;
  const double h = f.accel_noise;
  Eigen::MatrixXd Jp, Jm;
  Eigen::VectorXd rp, rm;
  stages::CauseColumns unused[2];
  FourBarFit g = f;
  for (Sample& s : g.samples) s.a[0] += h;
  if (!check_jacobian(g, out, &Jp, &rp, unused[0])) return false;
  for (Sample& s : g.samples) s.a[0] -= 2 * h;
  if (!check_jacobian(g, out, &Jm, &rm, unused[1])) return false;
  const Eigen::VectorXd dr = (rp - rm) / (2 * h);
  *b = h * h * ((Jp - Jm) / (2 * h)).transpose() * dr;
  return b->allFinite();
}

/// The std of the public friction coefficients from the sensors' noise alone (the fit's
/// noise_covariance; the reported std where there is none)
Eigen::VectorXd noise_std(const FourBarFit& f, const IdentifyResult& out) {
  const int nf = f.layout.friction_size();
  Eigen::VectorXd sd(nf);
  for (int i = 0; i < nf; ++i) sd(i) = out.parameters[i].std;
  if (f.noise_covariance.rows() != f.layout.size() || !f.noise_covariance.allFinite()) return sd;
  const Eigen::MatrixXd T = stages::to_public(f.layout).topLeftCorner(nf, f.layout.size());
  const Eigen::MatrixXd Cp = T * f.noise_covariance * T.transpose();
  for (int i = 0; i < nf; ++i) {
    if (Cp(i, i) > 0) sd(i) = std::min(sd(i), std::sqrt(Cp(i, i)));
  }
  return sd;
}

/// The std of the public friction coefficients that the fit's covariance (identify_four_bar.cc)
/// gives with the residual the freed step `fs` of cause `id` leaves (its parameters at the
/// step's values), each at most the estimate's own std: the errors-in-variables sandwich counts
/// the residual beyond its noise floor as white noise, (ratio^2 - 1) (J^T J)^-1 in the floor's
/// units, and s^2 (J^T J)^-1 (--classical-std) is the residual's variance. A model error that
/// the friction absorbs is counted as noise there: the double rocker's tau1 x 1.03 (3 s, seed 1)
/// read coulomb 0.126 +- 0.0049 (the clean log's std 0.0022), the gain's move 0.0054 read as
/// within kFreedMove std. J, r: the check's (whitened by the floor).
Eigen::VectorXd corrected_std(const FourBarFit& f, const Eigen::MatrixXd& J,
                              const Eigen::VectorXd& r, const stages::CauseColumns& idx, int id,
                              const detail::FreedStep& fs, const IdentifyResult& out) {
  const int nf = f.layout.friction_size(), P = f.layout.size();
  const int n = static_cast<int>(r.size());
  const Eigen::MatrixXd& cov = f.noise_covariance.size() > 0 ? f.noise_covariance : out.covariance;
  Eigen::VectorXd sd = noise_std(f, out);
  if (!fs.ok || cov.rows() != P || !cov.allFinite()) return sd;
  Eigen::VectorXd rc = r + J.leftCols(P) * fs.fitted_step;
  const std::vector<int>& extra = idx[id + 1];
  for (size_t k = 0; k < extra.size(); ++k) rc += J.col(extra[k]) * fs.extra_step(k);
  const Eigen::MatrixXd H = J.leftCols(P).transpose() * J.leftCols(P);
  const Eigen::MatrixXd Hinv = H.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
  Eigen::MatrixXd C;
  if (out.std_method == "errors-in-variables") {
    const auto excess = [&](const Eigen::VectorXd& v) {
      return std::max(0.0, v.squaredNorm() / n - 1.0);
    };
    C = cov - (excess(r) - excess(rc)) * Hinv;
  } else {
    C = rc.squaredNorm() / std::max(1, n - P) * Hinv;
  }
  const Eigen::MatrixXd T = stages::to_public(f.layout).topLeftCorner(nf, P);
  const Eigen::MatrixXd Cp = T * C * T.transpose();
  for (int i = 0; i < nf; ++i) {
    if (Cp(i, i) > 0 && std::sqrt(Cp(i, i)) < sd(i)) sd(i) = std::sqrt(Cp(i, i));
  }
  return sd;
}

/// What a named cause reads, in the log's terms: "theta1 reads 0.01 +- 0.001 rad more than the
/// scene's angle", the gain and offset of tau1, the delay in ms.
std::string reading(const FourBarFit& f, int id, const detail::FreedStep& fs) {
  const auto pm = [&](int k, double scale, const char* unit) {
    return format_significant(scale * fs.extra_step(k), 3) + " +- " +
           format_significant(scale * fs.extra_std(k), 2) + unit;
  };
  switch (id) {
    case stages::kCauseAngles:
      return "theta1 reads " + pm(0, 1.0, " rad") +
             " more than the scene's angle: the encoder's zero may be off; subtract the offset "
             "from the logged angles";
    case stages::kCauseTorque:
      if (fs.extra_step.size() == 1) {  // the offset fitted (--estimate actuator): the gain alone
        return "tau1 reads " + pm(0, 100.0, " %") +
               " more than the model: the torque sensor's gain may be off (check its torque "
               "constant)";
      }
      return "tau1 reads " + pm(1, 100.0, " %") + " more than the model and " + pm(0, 1.0, " N m") +
             " above it: the torque sensor's gain or zero may be off (check its torque constant)";
    case stages::kCauseMotors: {
      std::vector<int> terms;  // (the check's columns: motor_columns)
      motor_columns(f, &terms);
      return "the motor's friction reads " + stages::motor_reading(fs, terms, 1) +
             " more than the scene's: the motor (gearbox) has friction the fit leaves out; fit "
             "it with --estimate friction,actuator";
    }
    case stages::kCauseDelay:
      return "the torques seem to lag the angles by " + pm(0, 1e3, " ms") +
             " (negative: lead): a delay of the torque readings";
    default:
      return "the scene's masses or inertias may not match the mechanism";
  }
}

/// Whether a friction coefficient is at its bound
bool friction_at_bound(const FourBarFit& f, const IdentifyResult& out) {
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    if (out.parameters[i].at_bound) return true;
  }
  return false;
}

/// A cause whose move (beyond kFreedMove std: judge) takes a friction coefficient out of its
/// reported interval makes the fit unusable: the interval does not hold what the log reads with
/// the cause corrected. Where the misfit widened the std the move can stay within kUnusableMove
/// of the corrected std and still leave the interval (a drag link's masses 3 % off: viscous
/// 0.0123 +- 0.00084, the truth 0.015 3.2 std off, the inertias' move to 0.0147 7 std of the fit
/// with them corrected).
void leaves_interval(const FourBarFit& f, const detail::FreedStep& fs, const Eigen::VectorXd& sd,
                     const std::string& cause, IdentifyResult* out) {
  if (!out->unusable.empty()) return;
  const int nf = f.layout.friction_size();
  const Eigen::VectorXd move =
      stages::to_public(f.layout).topLeftCorner(nf, nf) * fs.fitted_step.head(nf);
  const Eigen::VectorXd noise = noise_std(f, *out);
  for (int i = 0; i < nf; ++i) {
    const ParameterEstimate& e = out->parameters[i];
    // the interval of the sensors' noise alone (a model error widens the reported one)
    const double bar = std::max(out->ci_quantile * noise(i), stages::kFreedMove * sd(i));
    if (e.at_bound || !(std::abs(move(i)) > bar)) continue;
    // digits enough to show the moved value beyond the bound it passes (0.0199 out of [0.0199, ...
    // at three)
    const double to = e.value + move(i), passed = e.value + (move(i) > 0 ? bar : -bar);
    int d = 3;
    while (d < 8 && format_significant(to, d) == format_significant(passed, d)) ++d;
    out->unusable = cause + ": it would move " + e.name + " to " + format_significant(to, d) +
                    ", out of its interval of the sensors' noise [" +
                    format_significant(e.value - bar, d) + ", " +
                    format_significant(e.value + bar, d) + "] (see the warnings)";
    return;
  }
}

/// The warning and the fit's status for the cause `id` (top: none is named, the one that
/// explains most): the friction's move beyond kFreedMove std is a warning (a named delay is one
/// at any move: identify redoes the fit with the torques shifted by it, and this fit's warnings
/// are then replaced by the refit's); beyond kUnusableMove, or a coefficient at its bound (the
/// move cannot be given), the fit is unusable.
void judge(const FourBarFit& f, const CauseSteps& cs, int id, bool named, const Eigen::VectorXd& sd,
           IdentifyResult* out) {
  const detail::FreedStep& fs = cs.alone[id];
  double largest = 0;
  const std::string moves = stages::friction_moves(f.layout, *out, fs, false, &largest, &sd);
  const bool bound = friction_at_bound(f, *out);
  // a cause it names is always said, as the five-bar's check does (a delay's warning is
  // replaced by the refit's when the refit is used)
  const bool delay = named && id == stages::kCauseDelay;
  if (moves.empty() && !bound && !named) return;
  const std::string what = stages::kCauseText[id].what;
  const std::string moved =
      !moves.empty() ? "the friction would move: " + moves + " (std of the fit with them corrected)"
      : bound        ? "a friction coefficient is at its bound, so the fit cannot say how far "
                       "the friction would move"
              : "the friction would move less than " + format_significant(stages::kFreedMove) +
                    " std (a linearized move" +
                    (delay ? ": refit a log whose torques are shifted by it)" : ")");
  const std::string head = named ? "with " + what + " free (one linearized refit) "
                                 : "the friction estimates absorbed a model error the log cannot "
                                   "attribute: with " +
                                       what + " free, the most of the causes, ";
  out->warnings.push_back(head + stages::drop_clause(fs) + " and " + moved + "; " +
                          (named ? reading(f, id, fs) : "no cause stands out from the others"));
  // the first reason stays; a delay's move within kFreedMove makes nothing unusable
  if (!out->unusable.empty() || (moves.empty() && !bound)) return;
  const std::string cause =
      named ? stages::cause_explaining_most(cs, id, stages::kAllCauses & ~(1u << id),
                                            what + " do not match the log")
            : "a model error the log cannot attribute (" + what +
                  " explain most of it: " + stages::falls_clause(cs, id) + ")";
  // a coefficient at its bound gives no move (friction_moves), so largest is 0 there
  stages::unusable_move(largest, cause, out);
  if (!delay) leaves_interval(f, fs, sd, cause, out);
}

/// A cause's column that the fitted inertias take up all but this fraction of (its std with them
/// fitted over its std with the other fitted parameters alone) is one the log cannot tell from
/// them
constexpr double kHiddenStdRatio = 10.0;

/// The information that the whitened column o keeps beyond the columns `cols` of J (its
/// squared norm off their span), and in *absorb the refit of those columns that takes it up
double information_beyond(const Eigen::MatrixXd& J, const std::vector<int>& cols,
                          const Eigen::VectorXd& o, Eigen::VectorXd* absorb = nullptr) {
  Eigen::MatrixXd X(J.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t k = 0; k < cols.size(); ++k) X.col(k) = J.col(cols[k]);
  const Eigen::VectorXd b = (X.transpose() * X).ldlt().solve(X.transpose() * o);
  if (absorb) *absorb = b;
  return (o - X * b).squaredNorm();
}

/// With the inertias fitted: a warning for each column of tau1's offset and gain and the crank
/// encoder's zero that the log cannot tell from them (kHiddenStdRatio) while its 95 % bound
/// with them fitted would move a friction coefficient beyond kFreedMove std (sd): the check
/// cannot see such an error, which the inertias absorb. (The double rocker's 10 s logs: the
/// offset read to +- 0.14 N m with the inertias, 0.00025 without, its bound moving the friction
/// by 0.26 std at most; the crank-rocker's gain +- 2 % against 0.058 %, 2.1 std at most.)
void hidden_by_inertias(const FourBarFit& f, const Eigen::MatrixXd& J,
                        const stages::CauseColumns& idx, const Eigen::VectorXd& sd,
                        IdentifyResult* out) {
  if (!f.layout.inertia) return;
  std::vector<int> others;  // the fitted parameters but the inertias
  for (int i : idx[0]) {
    if (!f.layout.is_inertial(i)) others.push_back(i);
  }
  struct Column {
    int c;
    const char* what;
    double scale;
    const char* unit;
  };
  std::vector<Column> cols;
  const std::vector<int>& t = idx[stages::kCauseTorque + 1];
  if (t.size() == 2) cols.push_back({t[0], "tau1's offset", 1.0, " N m"});
  if (!t.empty()) cols.push_back({t.back(), "tau1's gain", 100.0, " %"});
  for (int c : idx[stages::kCauseAngles + 1]) cols.push_back({c, "theta1's zero", 1.0, " rad"});
  const int nf = f.layout.friction_size();
  const Eigen::MatrixXd T = stages::to_public(f.layout).topLeftCorner(nf, nf);
  for (const Column& col : cols) {
    Eigen::VectorXd absorb;
    const double with = information_beyond(J, idx[0], J.col(col.c), &absorb);
    const double without = information_beyond(J, others, J.col(col.c));
    if (!(with > 0) || !(with * kHiddenStdRatio * kHiddenStdRatio < without)) continue;
    const double bound = out->ci_quantile / std::sqrt(with);
    const Eigen::VectorXd move = T * absorb.head(nf) * bound;
    std::string moves;
    for (int i = 0; i < nf; ++i) {
      if (!(std::abs(move(i)) > stages::kFreedMove * sd(i))) continue;
      moves += (moves.empty() ? "" : ", ") + out->parameters[i].name + " by " +
               format_significant(std::abs(move(i)) / sd(i), 2) + " std";
    }
    if (moves.empty()) continue;
    out->warnings.push_back(
        std::string("the log cannot tell ") + col.what +
        " from the links' inertial parameters, which absorb it (read to +- " +
        format_significant(col.scale / std::sqrt(with), 2) + col.unit + " with them fitted, +- " +
        format_significant(col.scale / std::sqrt(without), 2) + col.unit +
        " without): the model check cannot see its error, and one of " +
        format_significant(col.scale * bound, 2) + col.unit + " (its 95 % bound) would move " +
        moves + "; check the sensor, or fit without the inertias");
  }
}

}  // namespace

stages::ModelVerdict cause_check(const FourBarFit& f, IdentifyResult* out) {
  if (!out->converged) return {};
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  stages::CauseColumns idx;
  if (!check_jacobian(f, *out, &J, &r, idx) || J.rows() < stages::kCheckRowsPerColumn * J.cols()) {
    return {};
  }
  const Eigen::VectorXd info =
      Eigen::VectorXd::Constant(static_cast<Eigen::Index>(idx[stages::kCauseInertia + 1].size()),
                                1.0 / std::pow(f.opt->inertia_prior, 2));
  Eigen::VectorXd bias;
  if (!score_bias(f, *out, &bias)) return {};
  CauseSteps cs = stages::cause_steps(J, r, idx, info, bias, true);
  // the delay's estimate: its step freed alone with the friction (the five-bar's estimate_delay)
  const detail::FreedStep& ds = cs.alone[stages::kCauseDelay];
  if (!idx[stages::kCauseDelay + 1].empty() && ds.ok && ds.extra_step.size() == 1) {
    out->delay_s = ds.extra_step(0);
    out->delay_std_s = ds.extra_std(0);
  }
  const int top = stages::most_explaining_cause(cs);
  // the delay: named when it is evidenced beyond the model causes and explains the most
  const int d = cs.slot[stages::kCauseDelay];
  if (d >= 0) {
    const IdentifyResult::MisfitCause& m = cs.report[d];
    cs.report[d].evidenced =
        top == stages::kCauseDelay && m.z > detail::kCauseZ && m.z_given > detail::kCauseZ;
  }
  out->model_check = cs.report;
  const bool open = out->unusable.empty();  // a reason given before (the misfit) stays first
  bool any = false;
  const auto sd = [&](int id) { return corrected_std(f, J, r, idx, id, cs.alone[id], *out); };
  for (int id : {stages::kCauseTorque, stages::kCauseMotors, stages::kCauseAngles,
                 stages::kCauseInertia, stages::kCauseDelay}) {
    if (!cs.named(id)) continue;
    any = true;
    judge(f, cs, id, true, sd(id), out);
  }
  if (!any && top < stages::kCauseCount) judge(f, cs, top, false, sd(top), out);
  hidden_by_inertias(f, J, idx, noise_std(f, *out), out);
  // the five-bar's decisive evidence, its named cause's move judged as judge's
  const int nc = stages::named_cause(cs);
  double largest = 0;
  const bool bound = friction_at_bound(f, *out);
  const Eigen::VectorXd nsd = nc < stages::kCauseCount ? sd(nc) : Eigen::VectorXd();
  const bool moves =
      nc < stages::kCauseCount &&
      (bound ||
       !stages::friction_moves(f.layout, *out, cs.alone[nc], false, &largest, &nsd).empty());
  stages::decisive_model_error(cs, moves, bound ? 0.0 : largest, out);
  stages::ModelVerdict verdict;
  using D = stages::ModelVerdict::Delay;
  verdict.delay = cs.named(stages::kCauseDelay)           ? D::kExplainsMost
                  : d >= 0 && cs.report[d].z > detail::kCauseZ ? D::kNotMost
                                                          : D::kNotEvidenced;
  verdict.cause_decided = any && open && !out->unusable.empty();
  return verdict;
}

namespace {

/// Samples left between slip reversals too dense for the rate filter: fewer than
/// kMinWindowsLeft of its windows, and fewer than those left out near the reversals (the
/// crank-rocker logged at 100 Hz: 5 of 301 left, its 44 reversals in 3 s one every 68 ms against
/// a window of 110 ms; at 200 Hz 189 of 601, coulomb within 1.8 std over seeds 1-3).
constexpr int kMinWindowsLeft = 10;

/// Whether the fit is not to be used because the slip reversals leave too few samples (above);
/// out->unusable names the log's rate.
bool too_few_between_reversals(const FourBarFit& f, IdentifyResult* out) {
  const int window = 2 * f.hw + 1;
  if (f.hw <= 0 || out->samples_used >= kMinWindowsLeft * window ||
      out->samples_used >= out->samples_near_reversals) {
    return false;
  }
  const double dt = f.cond.log.duration() / std::max(1, f.cond.log.size() - 1);
  out->unusable =
      "only " + std::to_string(out->samples_used) + " samples lie away from the " +
      std::to_string(out->slip_reversals) + " slip reversals (one every " +
      format_significant(1e3 * f.cond.log.duration() / std::max(1, out->slip_reversals), 3) +
      " ms against the rate filter's window of " + format_significant(1e3 * window * dt, 3) +
      " ms): the log is sampled too slowly to estimate the accelerations between "
      "them; log the rates or sample faster";
  out->warnings.push_back(out->unusable);
  return true;
}

}  // namespace

/// The model check: a residual more than kMisfitRatio times its noise floor is structure the
/// fit misses; the fit is then not to be used (out->unusable). Its cause: outliers where a
/// robust loss discounted them (the residual counts them), else the friction law or the scene.
void model_check(const FourBarFit& f, IdentifyResult* out) {
  if (too_few_between_reversals(f, out)) return;
  const double floor = out->residual_noise_floor[0];
  const double ratio = out->rms_torque_residual[0] / floor;
  if (!(ratio > stages::kMisfitRatio)) return;
  std::string bound;
  for (const ParameterEstimate& p : out->parameters) {
    if (p.at_bound) bound += (bound.empty() ? "" : ", ") + p.name;
  }
  const std::string cause =
      f.opt->loss != Loss::kNone
          ? "outliers that the robust loss discounted (the residual counts them), or the "
            "friction law or the scene misses what the log shows"
          : "the friction law or the scene misses what the log shows";
  out->unusable = "the torque residual (rms " + format_significant(out->rms_torque_residual[0], 3) +
                  " N m) is " + format_significant(ratio, 3) + " times its noise floor: " + cause +
                  (bound.empty() ? "" : " (at its bound: " + bound + ")");
  out->warnings.push_back(out->unusable);
}

}  // namespace fivebar::identification::four_bar
