// Model check of identify(): the freed causes' steps, their warnings, and the verdict for the
// refits.
#include "identify_stages.h"
#include "model_check_causes.h"

namespace fivebar::identification::stages {

/// The clause of a model_check warning on the friction: "the friction would move: ..." when a
/// freed step moves a coefficient beyond kFreedMove std (friction_moves). When a coefficient is
/// at its bound no move is given; for a cause the log evidences (`evidenced`) the warning is
/// still due, and says so (a crank inertia 10 % off puts coulomb at 0 and viscous 23 std off,
/// which the bound's warning alone does not explain). Empty: no warning.
std::string friction_clause(const Fit& f, const IdentifyResult& out, const detail::FreedStep& fs,
                            bool own, bool evidenced, double* largest = nullptr) {
  const std::string moved = friction_moves(f.layout, out, fs, own, largest);
  if (!moved.empty()) return "the friction would move: " + moved;
  const int nf = f.layout.friction_size();
  bool bound = false;
  for (int i = 0; i < nf; ++i) bound = bound || out.parameters[i].at_bound;
  if (!evidenced || !bound) return "";
  return "a friction coefficient is at its bound, so the fit cannot say how far the friction "
         "would move";
}

/// "a, b (+- sa, sb)" of extras k and k + 1 of a freed step, each times `scale`
std::string pair_clause(const detail::FreedStep& fs, int k, double scale) {
  return format_significant(scale * fs.extra_step(k)) + ", " +
         format_significant(scale * fs.extra_step(k + 1)) + " (+- " +
         format_significant(scale * fs.extra_std(k), 2) + ", " +
         format_significant(scale * fs.extra_std(k + 1), 2) + ")";
}

/// A gain is advised only from this size on (gains of 0.1 to 0.2 % are merely significant on
/// logs with rates, and not worth advising)
constexpr double kSmallestGain = 0.005;

/// model_check's warning on the torque readings (so that a torque sensor's offset is not blamed
/// on the masses, and a 3 % gain error, read at +13 to +18 std, is not silent):
/// the offsets o_c and gains g_c of tau_c = (1 + g_c) M_c + o_c that the refit reads beyond
/// kFreedMove of their std (gains also from kSmallestGain on), with what to do about each.
std::string torque_warning(const TorqueColumns& tc, const detail::FreedStep& fs,
                           const std::string& moved) {
  const auto beyond = [&](int k) {
    return k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k);
  };
  std::vector<std::string> advice;
  for (int c = 0; c < kDof; ++c) {
    const std::string tau = "tau" + std::to_string(c + 1);
    if (beyond(tc.offset[c])) {
      const double o = fs.extra_step(tc.offset[c]);
      advice.push_back("a torque sensor's zero may be off: " + tau + " reads " +
                       format_significant(o, 3) + " +- " +
                       format_significant(fs.extra_std(tc.offset[c]), 2) +
                       " N m more than the model (subtract it, or fit the offsets with "
                       "--estimate friction,actuator)");
    }
    if (beyond(tc.gain[c]) && std::abs(fs.extra_step(tc.gain[c])) >= kSmallestGain) {
      const double g = fs.extra_step(tc.gain[c]);
      advice.push_back("a torque sensor's gain may be off: " + tau + " reads " +
                       format_significant(100 * g, 3) + " +- " +
                       format_significant(100 * fs.extra_std(tc.gain[c]), 2) +
                       " % more than the model (divide " + tau + " by " +
                       format_significant(1 + g, 5) + ", or check its torque constant)");
    }
  }
  if (advice.empty()) advice.push_back("the torque readings may be off");
  std::string w = "with offsets and gains of the logged torques free (one linearized refit) " +
                  drop_clause(fs) + " and " + moved;
  for (const std::string& a : advice) w += "; " + a;
  return w;
}

/// The torque readings' gains and offsets of torque_warning in short: "tau1 reads 0.5 times the
/// model"
/// (gains beyond kFreedMove of their std, from kSmallestGain on), offsets "tau1 +0.15 N m".
std::string torque_reading(const TorqueColumns& tc, const detail::FreedStep& fs) {
  std::string out;
  const auto beyond = [&](int k) {
    return k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k);
  };
  for (int c = 0; c < kDof; ++c) {
    const std::string tau = "tau" + std::to_string(c + 1);
    if (beyond(tc.gain[c]) && std::abs(fs.extra_step(tc.gain[c])) >= kSmallestGain) {
      out += (out.empty() ? "" : ", ") + tau + " reads " +
             format_significant(1 + fs.extra_step(tc.gain[c]), 3) + " times the model";
    } else if (beyond(tc.offset[c])) {
      out += (out.empty() ? "" : ", ") + tau + " reads " +
             format_significant(fs.extra_step(tc.offset[c]), 2) + " N m more than the model";
    }
  }
  return out.empty() ? "see the warnings" : out;
}

/// A torque reading's gain off by more than this fraction (read beyond kUnusableMove of its std)
/// makes the fit unusable: the friction estimates are off by about as much (torques logged at
/// half the model's: gains -0.5, coulomb 0.067 for 0.134, a move of 3 std only at the small
/// window's noise)
constexpr double kUnusableGain = 0.1;

/// The largest |gain| of the torque readings that the refit fs reads beyond kUnusableMove std.
double largest_gain(const TorqueColumns& tc, const detail::FreedStep& fs) {
  double g = 0;
  for (int c = 0; c < kDof; ++c) {
    const int k = tc.gain[c];
    if (k >= 0 && std::abs(fs.extra_step(k)) > kUnusableMove * fs.extra_std(k)) {
      g = std::max(g, std::abs(fs.extra_step(k)));
    }
  }
  return g;
}

/// Whether a friction coefficient of the fit is at its bound
bool friction_at_bound(const Fit& f, const IdentifyResult& out) {
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    if (out.parameters[i].at_bound) return true;
  }
  return false;
}

/// A named cause's warning clause when the friction moves within kFreedMove std
std::string moves_little() {
  return "the friction moves less than " + format_significant(kFreedMove) + " std";
}

/// A named cause `id` whose refit would move the friction by `largest` std makes the fit unusable
/// by unusable_move (0 where a coefficient is at its bound), the reason naming it or the cause
/// that explains clearly more (cause_explaining_most)
void unusable_by_named(const Fit& f, const CauseSteps& cs, int id, double largest,
                       IdentifyResult* out) {
  unusable_move(friction_at_bound(f, *out) ? 0 : largest,
                cause_explaining_most(cs, id, kAllCauses & ~(1u << id), kCauseText[id].off), out);
}

/// model_check's warning when a candidate cause alone is evidenced and would move the friction
/// (`top`: the one that explains most, most_explaining_cause), but no cause stands out beyond
/// the others' parameters or explains the misfit (with per-joint friction fitted by the shared
/// law, every cause reduces a misfit none explains; on a 2 s angles-only log of the paper scene,
/// a torque offset of 0.1 N m on tau1 gave coulomb +24 std without a word: the offsets'
/// evidence, 14 std alone, was 4.7 std beyond the inertias' and the encoders' zeros')
std::string unresolved_warning(const CauseSteps& cs, int top, const std::string& moved,
                               bool rates_biased) {
  std::vector<IdentifyResult::MisfitCause> causes(cs.report.begin(), cs.report.end() - 1);
  std::sort(causes.begin(), causes.end(), [](const auto& a, const auto& b) { return a.z > b.z; });
  std::string each;
  for (const IdentifyResult::MisfitCause& c : causes) {
    each += (each.empty() ? "" : ", ") + c.name + " " + format_significant(c.z, 2);
  }
  const std::string others = other_falls(cs, top);
  return "the friction estimates absorbed a model error the log cannot attribute: with " +
         std::string(kCauseText[top].what) + " free (one linearized refit) " +
         drop_clause(cs.alone[top]) +
         (others.empty() ? std::string() : ", the most of the causes (against " + others + ")") +
         " and " + moved +
         ", but no cause stands out from the others or explains the misfit (evidence of each "
         "alone, in std: " +
         each +
         "). Check the friction law (--per-joint, --law), the "
         "scene's masses (--estimate friction,inertia), the encoders' zeros, and the torque "
         "sensors and the motors' friction (--estimate friction,actuator), or log a longer motion" +
         (rates_biased ? std::string("; the estimated accelerations show smoothing bias at "
                                     "every window: log the rates, or sample faster")
                       : std::string());
}

/// Whether the refit fs reads both torque readings' gains (beyond kFreedMove std, from
/// kSmallestGain on) off alike: the same sign, both readings positive (1 + g_c > 0: a negative
/// one is a sign, torque_signs) and within a factor 2 of each other (or within kFreedMove of
/// their difference's std): a common scale of the logged torques (gains read 0.828 and -0.976 are
/// no common scale)
bool common_gain(const TorqueColumns& tc, const detail::FreedStep& fs) {
  std::array<double, kDof> g{}, sd{};
  for (int c = 0; c < kDof; ++c) {
    const int k = tc.gain[c];
    if (k < 0 || !(std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k)) ||
        std::abs(fs.extra_step(k)) < kSmallestGain || !(1 + fs.extra_step(k) > 0)) {
      return false;
    }
    g[c] = fs.extra_step(k);
    sd[c] = fs.extra_std(k);
  }
  const double small = std::min(std::abs(g[0]), std::abs(g[1]));
  const double large = std::max(std::abs(g[0]), std::abs(g[1]));
  return g[0] * g[1] > 0 && (2 * small >= large || std::abs(g[0] - g[1]) <=
                                                       kFreedMove * std::hypot(sd[0], sd[1]));
}

/// The torque channels (bit 0: tau1, bit 1: tau2) whose reading the refit fs reads negative,
/// 1 + g_c < 0 with g_c beyond kFreedMove of its std: logged with the sign opposite the model's
/// (a light mechanism's tau1 negated read -1.02 times the model, its residual 2.6 times its floor,
/// below the sign check's kMisfitRatio)
unsigned torque_signs(const TorqueColumns& tc, const detail::FreedStep& fs) {
  unsigned out = 0;
  for (int c = 0; c < kDof && fs.ok; ++c) {
    const int k = tc.gain[c];
    if (k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k) &&
        1 + fs.extra_step(k) < 0) {
      out |= 1u << c;
    }
  }
  return out;
}

/// model_check on the encoders' zeros: the warning when the log evidences them, unusable when
/// the friction would move beyond kUnusableMove (or one is at its bound)
void angles_check(const Fit& f, const CauseSteps& cs, IdentifyResult* out) {
  const detail::FreedStep& fo = cs.alone[kCauseAngles];
  double largest = 0;
  if (!cs.named(kCauseAngles)) return;
  std::string moved = friction_clause(f, *out, fo, false, true, &largest);
  // named, the zeros are said even where the linearized refit moves the friction little, unless
  // another cause explains clearly more (an encoder 0.005 rad off on a heavy mechanism: read
  // 0.0052 +- 0.00075 rad at 31 std, a move of coulomb by 1 std, while the fit's coulomb was
  // 10 std off, from the smallest window the zeros' error had chosen: unbounded_error; masses
  // 5 % off on another evidenced zeros too, at a fall of 27 against 414)
  if (moved.empty()) {
    for (int k = 0; k < kCauseCount; ++k) {
      if (k != kCauseAngles && clearly_more(cs, k, kCauseAngles)) return;  // not the zeros
    }
    moved = moves_little();
    largest = -1;  // no move to judge
  }
  out->warnings.push_back(
      "with offsets of the logged angles free (one linearized refit) " + drop_clause(fo) +
      " and " + moved + ". theta1, theta2 read " + pair_clause(fo, 0, 1.0) +
      " rad more than the scene's angles: an encoder's zero may be off; subtract the offsets "
      "from the logged angles");
  if (largest < 0) return;
  // evidenced zeros that hold a coefficient at its bound make the fit unusable, whatever the
  // other coefficients' move (theta1 0.02 rad off on the light mechanism: viscous at 0, coulomb
  // 4 std)
  unusable_by_named(f, cs, kCauseAngles, largest, out);
}

/// model_check on the motors' friction, which the fit leaves out (--estimate actuator fits it),
/// when the log evidences it: the warning with what the refit reads, even where the friction
/// moves little; unusable by the rule of the other causes (unusable_move). Without it a motor
/// Coulomb friction of 0.05 N m on a multi-sine log of the paper scene was blamed on the torque
/// sensors' zeros (coulomb_4 5.5 std, viscous_4 11 std off).
void motors_check(const Fit& f, const CauseSteps& cs, const std::vector<int>& terms,
                  IdentifyResult* out) {
  if (!cs.named(kCauseMotors)) return;
  const detail::FreedStep& fm = cs.alone[kCauseMotors];
  double largest = 0;
  std::string moved = friction_clause(f, *out, fm, false, true, &largest);
  if (moved.empty()) {
    moved = moves_little();
    largest = -1;  // no move to judge
  }
  out->warnings.push_back(
      "with the motors' friction free (one linearized refit) " + drop_clause(fm) + " and " + moved +
      ". The motors' friction at O, D0 reads " + motor_reading(fm, terms, kActuators) +
      " more than the scene's: the motors (gearboxes) have friction the fit leaves out; fit it "
      "with --estimate friction,actuator");
  if (largest < 0) return;
  unusable_by_named(f, cs, kCauseMotors, largest, out);
}

/// The torque readings' step of model_check and the indices of its offsets and gains
struct ReadingStep {
  detail::FreedStep fs;
  TorqueColumns tc;  ///< offset and gain indices into fs's extras (-1: left out)
};

/// model_check on the torque readings, when the log evidences them: the warning when the
/// friction would move, a gain is off by kUnusableGain, the residual is far above its floor
/// (kMisfitRatio; evidenced, the readings explain at least half of that excess) or the evidence
/// is decisive (kDecisiveCauseZ). Each of these but a move within kUnusableMove makes the fit
/// unusable, naming the readings (a common scale of both when both gains are off alike).
void torque_check(const Fit& f, const CauseSteps& cs, const ReadingStep& rs,
                  IdentifyResult* out) {
  if (!cs.named(kCauseTorque)) return;
  // the motors' friction named and explaining clearly more: the readings' offsets took a share
  // of it (motors' Coulomb friction of 0.05 N m on cranks that reverse seldom read as tau1 0.026
  // N m above the model), and motors_check said what it is
  if (cs.named(kCauseMotors) && clearly_more(cs, kCauseMotors, kCauseTorque)) return;
  const detail::FreedStep& ft = rs.fs;
  const TorqueColumns& tc = rs.tc;
  double largest = 0;
  const std::string moved = friction_clause(f, *out, ft, false, true, &largest);
  // a gain off by kUnusableGain scales the friction with it, whatever the move's std
  const bool scaled = largest_gain(tc, ft) > kUnusableGain;
  const double ratio = misfit_ratio(*out), z = cs.report[cs.slot[kCauseTorque]].z_given;
  const bool far = ratio > kMisfitRatio, decisive = z > kDecisiveCauseZ;
  if (moved.empty() && !scaled && !far && !decisive) return;
  out->warnings.push_back(torque_warning(tc, ft,
                                         !moved.empty() ? moved
                                         : scaled ? "the friction estimates scale with the gains"
                                                  : moves_little()));
  // a common gain also reads as the encoders' zeros (model_check): only the inertias, which
  // scale the torques alike too, may explain more then
  const bool common = common_gain(tc, ft);
  const unsigned others = (1u << kCauseInertia) | (1u << kCauseMotors) | (1u << kCauseDelay) |
                          (common ? 0u : 1u << kCauseAngles);
  const std::string what =
      cause_explaining_most(cs, kCauseTorque, others,
                            (common ? "both logged torques' gains are off, a common scale ("
                                    : "the logged torques' zeros or gains are off (") +
                                torque_reading(tc, ft) + ")");
  if (!out->unusable.empty()) return;
  if (scaled) {
    out->unusable = what + ": the friction estimates scale with them (see the warnings)";
  } else if (!moved.empty()) {
    unusable_move(friction_at_bound(f, *out) ? 0 : largest, what, out);
  }
  if (!out->unusable.empty() || !(far || decisive)) return;
  out->unusable =
      what + ": " +
      (far ? "they explain the residual, " + format_significant(ratio, 3) +
                 " times its noise floor (more than " + format_significant(kMisfitRatio) + ")"
           : "the log evidences them by " + format_significant(z, 2) +
                 " std beyond the other causes (more than " +
                 format_significant(kDecisiveCauseZ) + ")") +
      "; see the warnings";
}

/// No cause named, but the torque readings alone are evidenced decisively (kDecisiveCauseZ) and
/// read a common gain beyond kUnusableGain: both torques scaled alike read as the links' masses
/// and inertias scaled alike (the friction's normal forces scale with them), which the log
/// cannot tell apart when the external loads are small. Either way the friction estimates are
/// off by that scale: the fit is unusable (a light mechanism's multi-sine log with rates, both
/// torques x 0.75: coulomb -4.8 std, viscous +5.0 std, residual 1.2 times its floor, evidence
/// alone 1520 std for the readings, 871 for the inertias). True when it says so.
bool scale_ambiguity(const CauseSteps& cs, const ReadingStep& rs, IdentifyResult* out) {
  if (!out->unusable.empty() || cs.slot[kCauseTorque] < 0 || !rs.fs.ok ||
      !(cs.z(kCauseTorque) > kDecisiveCauseZ) || !common_gain(rs.tc, rs.fs) ||
      !(largest_gain(rs.tc, rs.fs) > kUnusableGain)) {
    return false;
  }
  out->unusable = "both logged torques' gains are off alike (" + torque_reading(rs.tc, rs.fs) +
                  "), or the links' masses and inertias are by that scale: the log cannot tell "
                  "them apart (evidence alone, in std: torque_readings " +
                  format_significant(cs.z(kCauseTorque), 2) + ", inertia " +
                  format_significant(cs.z(kCauseInertia), 2) +
                  "); either way the friction estimates scale with them. Check the torque "
                  "sensors' gains and the scene's masses";
  out->warnings.push_back(out->unusable);
  return true;
}

/// model_check on the inertias: the warning when the log evidences them (or, no cause
/// evidenced, by the earlier rule: `candidate`, the inertias are among the columns) and the
/// friction would move; named, unusable by the rule of the other causes (unusable_move): else
/// masses 6 % off a heavy mechanism, named, passed with a warning where 5 %, not named, failed
void inertia_check(const Fit& f, const CauseSteps& cs, bool candidate, IdentifyResult* out) {
  const detail::FreedStep& fi = cs.alone[kCauseInertia];
  const bool masses = cs.named(kCauseInertia);
  const bool old_rule = !cs.any() && candidate && fi.ok;
  double largest = 0;
  std::string moved;
  if (!(masses || old_rule) ||
      (moved = friction_clause(f, *out, fi, old_rule, masses, &largest)).empty()) {
    return;
  }
  out->warnings.push_back(
      "with the links' inertial parameters free (one linearized refit, prior std " +
      format_significant(f.opt->inertia_prior) + " of the scene's values) " +
      (masses ? drop_clause(fi) + " and " : std::string()) + moved +
      ". The scene's masses or inertias may not match the mechanism; try --estimate "
      "friction,inertia");
  if (!masses) return;
  unusable_by_named(f, cs, kCauseInertia, largest, out);
}

/// The delay's column (the logged torques' rates at the fit's samples, rows whitened by the
/// floors) appended to J, its score bias 0 (the rates' noise at a sample is independent of the
/// torque's there: a centred derivative's middle tap is 0; the angles' noise does not enter it)
void add_delay_column(const Fit& f, const double fl[2], Eigen::MatrixXd* J, Eigen::VectorXd* bias,
                      std::vector<int>* cols) {
  std::vector<double> g1, g2;
  delay_regressor(f, &g1, &g2);
  const Eigen::Index c = J->cols();
  J->conservativeResize(Eigen::NoChange, c + 1);
  for (size_t u = 0; u < f.index.size(); ++u) {
    (*J)(2 * u, c) = g1[f.index[u]] / fl[0];
    (*J)(2 * u + 1, c) = g2[f.index[u]] / fl[1];
  }
  bias->conservativeResize(c + 1);
  (*bias)(c) = 0;
  cols->push_back(static_cast<int>(c));
}

/// The delay's evidence bar when no model cause is evidenced alone (kCauseZ): measured on 10 s
/// logs of three mechanisms, the delay's evidence was at most -0.1 std on every clean log and on
/// every mass, zero or gain error that left the model causes below kCauseZ, and 3.2 std (2.9
/// beyond the model causes) for a heavy mechanism's 1 ms lag, 6.0 (5.4) for a light one's 8 ms
/// lead
constexpr double kDelayAloneZ = 2.5;

/// Whether the delay alone is evidenced (kCauseZ) and lowers the cost more than every other
/// cause evidenced alone: `clearly` more (clearly_more), or at least as much. Clearly more, the
/// torques' shift comes first, and the model causes are judged on the log with it corrected
/// (the refit's own check): beyond the model causes its evidence can be nothing, as the links'
/// inertial parameters absorb most of its column (a light five-bar's 4 ms lag: the delay alone
/// 305 std, a fall of 431; the inertias 71 std, a fall of 382; the delay beyond the model causes
/// -0.7 std). A model error is explained at least as well by its own cause's parameters as by
/// the delay's column, so its fall is not clearly below the delay's.
bool delay_explains_most(const CauseSteps& cs, bool clearly) {
  if (!(cs.z(kCauseDelay) > detail::kCauseZ) || !cs.alone[kCauseDelay].ok) return false;
  const double fall = cs.report[cs.slot[kCauseDelay]].drop;
  for (int k = 0; k < kCauseDelay; ++k) {
    if (!competes(cs, k)) continue;
    if (clearly ? !clearly_more(cs, kCauseDelay, k) : cs.report[cs.slot[k]].drop > fall) {
      return false;
    }
  }
  return true;
}

/// The delay judged as the causes are: evidenced alone and beyond the model causes (kCauseZ, or
/// kDelayAloneZ when no model cause is evidenced alone),
/// and its fall beyond every other evidenced cause's by more than kCauseZ times the larger of
/// their noise-alone std (cause_explaining_most's "clearly more"); or, not evidenced beyond the
/// model causes, evidenced alone with its fall clearly beyond every other evidenced cause's
/// (delay_explains_most). *rival: the cause with the largest fall that the delay does not clearly
/// exceed (kNotMost). *tied: kNotMost for a delay evidenced alone whose fall is the largest but
/// not clearly, and nothing beyond the model causes: a delay or a model error, the log cannot
/// tell which (named, not corrected).
ModelVerdict::Delay delay_verdict(const CauseSteps& cs, int* rival, bool* tied) {
  using D = ModelVerdict::Delay;
  const int d = cs.slot[kCauseDelay];
  if (d < 0) return D::kUnchecked;
  const IdentifyResult::MisfitCause& m = cs.report[d];
  bool alone = true;  // no model cause evidenced alone
  for (int k = 0; k < kCauseDelay; ++k) {
    alone = alone && !competes(cs, k);
  }
  const double bar = alone ? kDelayAloneZ : detail::kCauseZ;
  if (!cs.alone[kCauseDelay].ok) return D::kNotEvidenced;
  *tied = !(m.z > bar && m.z_given > bar) && !delay_explains_most(cs, true);
  if (*tied && !delay_explains_most(cs, false)) return D::kNotEvidenced;
  *rival = kCauseCount;
  for (int k = 0; k < kCauseDelay; ++k) {
    if (!competes(cs, k)) continue;
    const double margin =
        detail::kCauseZ * std::max(cs.alone[k].drop_sd, cs.alone[kCauseDelay].drop_sd);
    const double fall = cs.report[cs.slot[k]].drop;
    if (!(m.drop - fall > margin) &&
        (*rival == kCauseCount || fall > cs.report[cs.slot[*rival]].drop)) {
      *rival = k;
    }
  }
  return *rival == kCauseCount ? D::kExplainsMost : D::kNotMost;
}

namespace {

/// A model error the check names (`what`) makes the fit unusable, whatever the linearized move
/// of the friction, when that move cannot bound the friction's error:
/// - a friction coefficient's std exceeds its value: a move "within k std" then says nothing
///   (light links 6 % heavier than the scene: inertias named at 88 std, coulomb 0.019 +- 0.19);
/// - the data-driven window was the smallest (the order raised): the window rule read the model
///   error as smoothing bias at every larger window, so the rates, the noise floor and the std
///   are those of the noisiest window, whose acceleration noise biases the friction (an encoder
///   zero 0.005 rad off a heavy mechanism: floor 9.7 N m against 2.0 at the clean log's window,
///   the zeros' move of coulomb 1 std, coulomb 10 std off; the clean log at that window: 11 std).
/// The first reason stays.
void unbounded_error(const Fit& f, const std::string& what, IdentifyResult* out) {
  if (!out->unusable.empty()) return;
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    const ParameterEstimate& e = out->parameters[i];
    if (e.at_bound || !(e.std > std::abs(e.value))) continue;
    // (the value is not repeated: the smoothing-bias correction may still move it)
    out->unusable = what + ": " + e.name + " is not determined (std " +
                    format_significant(e.std, 2) +
                    ", more than its value), so the fit cannot bound how far the error moves it "
                    "(see the warnings)";
    return;
  }
  if (f.source != detail::RateSource::kLogged && f.opt->auto_window &&
      f.sg.order > f.opt->sg.order) {
    out->unusable = what +
                    ": the rates' window was chosen with this error in the residual "
                    "(every window but the smallest read it as smoothing bias), so the noise "
                    "floor, the std and the friction are those of the noisiest window; correct "
                    "it and rerun (see the warnings)";
  }
}

/// The five-bar's decisive model error (decisive_model_error): its named cause's move judged on
/// the fit's std.
void decisive_error(const Fit& f, const CauseSteps& cs, IdentifyResult* out) {
  if (!out->unusable.empty()) return;
  const int named = named_cause(cs);
  double largest = 0;
  const bool moves = named < kCauseCount &&
                     !friction_clause(f, *out, cs.alone[named], false, true, &largest).empty() &&
                     (largest == 0 || largest > kFreedMove);
  decisive_model_error(cs, moves, largest, out);
}

/// Whether the check's steps evidence a model cause alone (inertias, encoders' zeros, torque
/// readings, the motors' friction, or all of them together, beyond kCauseZ): what the smoothing
/// error of the fit's window could have made
bool model_error_evidenced(const CauseSteps& cs) {
  bool any = cs.all.ok && detail::evidence(cs.all, cs.all.drop) > detail::kCauseZ;
  for (int id = 0; id < kCauseDelay; ++id) {
    any = any || competes(cs, id);
  }
  return any;
}

}  // namespace

/// The delay's verdict (delay_verdict) and, where another cause explains as much, the words
/// naming it (ModelVerdict::delay_falls).
void judge_delay(const CauseSteps& cs, ModelVerdict* verdict) {
  int rival = kCauseCount;
  verdict->delay = delay_verdict(cs, &rival, &verdict->delay_tied);
  if (verdict->delay != ModelVerdict::Delay::kNotMost) return;
  verdict->delay_falls = std::string(verdict->delay_tied ? "it explains the most of the misfit, "
                                                           "though not clearly more than "
                                                         : "it does not explain clearly more "
                                                           "of the misfit than ") +
                         kCauseText[rival].what + " (" + falls_clause(cs, rival) + ")";
}

/// model_check on the fit f, its residual whitened by the noise floors fl (an: its own data
/// residuals and Jacobian, check_inputs; nullptr for a fit other than the solved one);
/// *evidenced: model_error_evidenced.
ModelVerdict check_at(const Fit& fit, const double fl[2], const Analysis* an, IdentifyResult* out,
                      bool* evidenced) {
  ModelVerdict verdict;
  *evidenced = false;
  Eigen::MatrixXd J;
  Eigen::VectorXd r, info, bias;
  CauseColumns idx;  // fitted, inertial, angle offsets, torque offsets and gains, motors, delay
  TorqueColumns tc;
  Fit spare;
  const Fit* checked =
      check_inputs(fit, fl, an, &spare, out, &J, &r, idx, &info, &tc, &bias, &verdict);
  if (!checked) {
    if (verdict.short_log) {
      out->notes.push_back("model check: not run, " + verdict.unchecked);
    } else {
      out->warnings.push_back("the model check did not run: " + verdict.unchecked +
                              "; no cause of a misfit is named, and no delay is corrected");
    }
    return verdict;
  }
  const Fit& f = *checked;
  if (f.opt->estimate_delay && f.method->checks_readings()) {
    add_delay_column(f, fl, &J, &bias, &idx[kCauseDelay + 1]);
  }
  const CauseSteps cs = cause_steps(J, r, idx, info, bias, !f.rates_biased);
  *evidenced = model_error_evidenced(cs);
  judge_delay(cs, &verdict);
  out->model_check = cs.report;
  if (cs.slot[kCauseDelay] >= 0) {
    out->model_check[cs.slot[kCauseDelay]].evidenced =
        verdict.delay == ModelVerdict::Delay::kExplainsMost;
  }
  verdict.negative_readings = torque_signs(tc, cs.alone[kCauseTorque]);
  const ReadingStep rs{cs.alone[kCauseTorque], tc};
  // both torques' gains off alike also read as the encoders' zeros (a common scale of the
  // logged torques on the light mechanism read theta1, theta2 2.4, 1.3 rad off): the gains come
  // first, so that the verdict names them
  const bool open = out->unusable.empty();  // (a bound's rule may have decided before)
  motors_check(f, cs, tc.motor_terms, out);
  if (cs.named(kCauseTorque) && common_gain(rs.tc, rs.fs)) {
    torque_check(f, cs, rs, out);
    angles_check(f, cs, out);
  } else {
    angles_check(f, cs, out);
    torque_check(f, cs, rs, out);
  }
  verdict.cause_decided = open && !out->unusable.empty();
  if (!cs.any() && scale_ambiguity(cs, rs, out)) verdict.cause_decided = true;
  verdict.cause_decided = verdict.cause_decided && verdict.negative_readings == 0;
  std::string moved;
  double largest = 0;  // [std] the cause's largest move of the friction (0: at its bound)
  const int top = most_explaining_cause(cs);
  if (!cs.any() && top < kCauseCount &&
      !(moved = friction_clause(f, *out, cs.alone[top], false, true, &(largest = 0))).empty()) {
    out->warnings.push_back(unresolved_warning(cs, top, moved, f.rates_biased));
    const std::string what = "a model error the log cannot attribute (" +
                             std::string(kCauseText[top].what) +
                             " explain most of it: " + falls_clause(cs, top) + ")";
    const double ratio = misfit_ratio(*out);
    if (out->unusable.empty() && ratio > kMisfitRatio) {  // an error the misfit shows, no cause
      out->unusable = what + ": it moves the friction while the torque residual is " +
                      format_significant(ratio, 3) + " times its noise floor (more than " +
                      format_significant(kMisfitRatio) + "; see the warnings)";
    }
    unusable_move(largest, what, out);
    unbounded_error(f, what, out);
    decisive_error(f, cs, out);
    if (open) verdict.unattributed = out->unusable;
    return verdict;
  }
  inertia_check(f, cs, !idx[kCauseInertia + 1].empty(), out);
  const int cause = named_cause(cs);
  if (cause < kCauseCount) unbounded_error(f, attributed_what(cs, cause), out);
  decisive_error(f, cs, out);
  return verdict;
}

}  // namespace fivebar::identification::stages
