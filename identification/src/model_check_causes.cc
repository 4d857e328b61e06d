// The model check's candidate causes compared, for every mechanism: the freed steps of the
// causes' columns (alone, together, beyond each other), the cause that explains most of a
// misfit, and the words that name it (model_check_causes.h).
#include "model_check_causes.h"

#include "identify_stages.h"

namespace fivebar::identification::stages {

/// The friction coefficients a freed step moves beyond kFreedMove std, as "name from a to b
/// (k std)": the std of the estimate, or with `own` the larger of it and the move's own std (the
/// test of Hausman); empty if none moves so, or one is at its bound (which has its own warning).
std::string friction_moves(const ParameterLayout& layout, const IdentifyResult& out,
                           const detail::FreedStep& fs, bool own, double* largest,
                           const Eigen::VectorXd* judged) {
  const int nf = layout.friction_size();
  const Eigen::MatrixXd T = to_public(layout).topLeftCorner(nf, nf);
  const Eigen::VectorXd move = T * fs.fitted_step.head(nf);
  const Eigen::MatrixXd cov = T * fs.fitted_cov.topLeftCorner(nf, nf) * T.transpose();
  std::string moved;
  for (int i = 0; i < nf; ++i) {
    const ParameterEstimate& e = out.parameters[i];
    if (e.at_bound) return "";
    const double std = judged ? (*judged)(i) : e.std;
    const double sd = own ? std::max(std::sqrt(std::max(0.0, cov(i, i))), std) : std;
    if (!(std::abs(move(i)) > kFreedMove * sd)) continue;
    if (largest) *largest = std::max(*largest, std::abs(move(i)) / sd);
    moved += (moved.empty() ? "" : ", ") + e.name + " from " + format_significant(e.value) +
             " to " + format_significant(e.value + move(i)) + " (" +
             format_significant(std::abs(move(i)) / sd, 2) + " std)";
  }
  return moved;
}

bool unlike_an_offset(const Eigen::Ref<const Eigen::VectorXd>& v) {
  const double mean = v.mean();
  const double spread = std::sqrt((v.array() - mean).square().mean());
  return spread > 0 && spread >= kOffsetSpread * std::abs(mean);
}

std::vector<int> motor_terms(const Eigen::MatrixXd& D, int actuators) {
  std::vector<int> terms;
  for (int c = 0; c < D.cols(); ++c) {
    if (unlike_an_offset(D.col(c))) terms.push_back(actuators + c);
  }
  return terms;
}

std::string motor_reading(const detail::FreedStep& fs, const std::vector<int>& terms,
                          int actuators) {
  std::string out;
  for (size_t k = 0; k < terms.size() && static_cast<Eigen::Index>(k) < fs.extra_step.size(); ++k) {
    const bool viscous = terms[k] >= 2 * actuators;
    out += (out.empty() ? "" : ", ") + actuator_term_name(terms[k], actuators) + " " +
           format_significant(fs.extra_step(k), 3) + " +- " +
           format_significant(fs.extra_std(k), 2) + (viscous ? " N m s/rad" : " N m");
  }
  return out;
}

Eigen::Vector2d motor_friction_columns(const FrictionParams<double>& fp, const EvalOptions& eval,
                                       double w, double a) {
  if (eval.rest_acceleration >= 0.0) mech::detail::still_drive(eval, &w, &a);
  const JointMode mode = mech::detail::inverse_slip(eval, w, a);
  if (mode == kStuck) return Eigen::Vector2d::Zero();
  return -Eigen::Vector2d(coulomb_direction(fp, w, coulomb_sign(mode)), w);
}

namespace {

/// The freed step with the columns of every cause in `mask` (bit id: CauseId) freed together.
detail::FreedStep freed_set(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                            const CauseColumns& idx, const Eigen::VectorXd& info,
                            const Eigen::VectorXd& bias, unsigned mask) {
  std::vector<int> cols;
  std::vector<double> prior;
  for (int id = 0; id < kCauseCount; ++id) {
    if (!(mask & (1u << id))) continue;
    const std::vector<int>& c = idx[id + 1];
    cols.insert(cols.end(), c.begin(), c.end());
    for (size_t e = 0; e < c.size(); ++e) {
      prior.push_back(id == kCauseInertia ? info(static_cast<Eigen::Index>(e)) : 0.0);
    }
  }
  const Eigen::Map<const Eigen::VectorXd> p(prior.data(), static_cast<Eigen::Index>(prior.size()));
  return detail::freed_step(J, r, idx[0], cols, p, bias);
}

/// A cause is named only when its parameters remove at least this fraction of the residual's
/// excess over its noise floor, when there is one (a scene with per-joint friction fitted with
/// the shared law leaves the residual 4 to 5 times its floor; every cause clears its evidence bar
/// by thousands of std, and without this the torque sensors would be blamed)
constexpr double kExplainedExcess = 0.5;

/// ... when the excess is at least this fraction of the residual's length (the residual's rms
/// 1.12 times its floor or more): below, the floor's own error is a large part of the excess
/// (measured: a 1 % torque gain on a 4 s angles-only log, ratio 1.02, explained 0.43 of it)
constexpr double kExcessShows = 0.25;

/// ... and, when the rates are biased at every window (Fit::rates_biased), a cause is named only
/// when it removes this fraction of the excess (a 5 N m torque offset, which also spoils the
/// window rule, explained 0.99 of it)
constexpr double kExplainsAll = 0.9;

IdentifyResult::MisfitCause misfit_cause(const char* name, const detail::FreedStep& fs, double z,
                                         double z_given, double excess) {
  IdentifyResult::MisfitCause m;
  m.name = name;
  m.checked = fs.ok;
  m.drop = fs.drop - fs.drop_mean;
  m.z = z;
  m.z_given = z_given;
  m.explained = excess > 0 ? fs.drop / excess : NAN;
  return m;
}

/// Whether the motors' friction (its step cs.alone[kCauseMotors], its report entry m) reads as a
/// cause: evidenced alone and beyond the model causes (kCauseZ), and read as a friction, no
/// coefficient below 0 by more than kFreedMove of its std. Its columns are nearly the crank
/// joints' own friction and the torque offsets: without these bars a Stribeck law fitted as
/// Coulomb-viscous read as motors' friction of 0.05 N m with a viscous one of -0.002 +- 0.0003,
/// and per-joint friction fitted with the shared law as motors too.
bool motors_plausible(const CauseSteps& cs, const IdentifyResult::MisfitCause& m) {
  const detail::FreedStep& fs = cs.alone[kCauseMotors];
  if (!fs.ok || !(m.z > detail::kCauseZ) || !(m.z_given > detail::kCauseZ)) return false;
  for (Eigen::Index k = 0; k < fs.extra_step.size(); ++k) {
    if (fs.extra_step(k) < -kFreedMove * fs.extra_std(k)) return false;
  }
  return true;
}

/// Whether the motors' friction is named: plausible (motors_plausible), removing
/// kExplainedExcess of the residual's excess where that shows (`shows`; with rates biased at
/// every window, kExplainsAll: `attributable`), and its fall clearly beyond every model cause's
/// evidenced alone (clearly_more)
bool motors_named(const CauseSteps& cs, const IdentifyResult::MisfitCause& m, bool shows,
                  bool attributable) {
  if (!motors_plausible(cs, m)) return false;
  if ((shows && m.explained < kExplainedExcess) || (!attributable && m.explained < kExplainsAll)) {
    return false;
  }
  for (int id = 0; id < kCauseDelay; ++id) {
    if (id != kCauseMotors && competes(cs, id) && !clearly_more(cs, kCauseMotors, id)) {
      return false;
    }
  }
  return true;
}

}  // namespace

bool counts_alone(const IdentifyResult::MisfitCause& c) {
  if (c.name == kCauseText[kCauseMotors].name) return c.evidenced;
  return c.name != kCauseText[kCauseDelay].name && c.name != "any";
}

bool competes(const CauseSteps& cs, int id) {
  if (cs.slot[id] < 0 || !cs.alone[id].ok || !(cs.z(id) > detail::kCauseZ)) return false;
  return id != kCauseMotors || motors_plausible(cs, cs.report[cs.slot[id]]);
}

CauseSteps cause_steps(const Eigen::MatrixXd& J, const Eigen::VectorXd& r, const CauseColumns& idx,
                       const Eigen::VectorXd& info, const Eigen::VectorXd& bias,
                       bool attributable) {
  const double excess = r.squaredNorm() - static_cast<double>(r.size());
  unsigned present = 0;
  std::vector<int> ids;
  std::vector<detail::FreedStep> alone, all_but;
  for (int id = 0; id < kCauseDelay; ++id) {
    if (id == kCauseMotors || idx[id + 1].empty()) continue;
    present |= 1u << id;
    ids.push_back(id);
    alone.push_back(freed_set(J, r, idx, info, bias, 1u << id));
  }
  CauseSteps cs;
  cs.all = freed_set(J, r, idx, info, bias, present);
  for (int id : ids) all_but.push_back(freed_set(J, r, idx, info, bias, present & ~(1u << id)));
  const detail::Causes c = detail::model_causes(alone, cs.all, all_but);
  for (size_t k = 0; k < ids.size(); ++k) {
    IdentifyResult::MisfitCause m =
        misfit_cause(kCauseText[ids[k]].name, alone[k], c.z[k], c.z_given[k], excess);
    m.evidenced = c.named[k] &&
                  !(excess > kExcessShows * r.size() && m.explained < kExplainedExcess) &&
                  (attributable || m.explained >= kExplainsAll);
    cs.alone[ids[k]] = alone[k];
    cs.slot[ids[k]] = static_cast<int>(cs.report.size());
    cs.report.push_back(m);
  }
  // the motors' friction and the delay: alone, and beyond the model causes, which they do not
  // enter (the motors' columns are nearly the crank joints' own friction and the torque offsets)
  for (int id : {kCauseMotors, kCauseDelay}) {
    if (idx[id + 1].empty()) continue;
    const detail::FreedStep fd = freed_set(J, r, idx, info, bias, 1u << id);
    const detail::FreedStep with = freed_set(J, r, idx, info, bias, present | 1u << id);
    const double z_given =
        cs.all.ok && with.ok ? detail::evidence(fd, with.drop - cs.all.drop) : 0.0;
    cs.alone[id] = fd;
    cs.slot[id] = static_cast<int>(cs.report.size());
    cs.report.push_back(
        misfit_cause(kCauseText[id].name, fd, detail::evidence(fd, fd.drop), z_given, excess));
  }
  if (cs.slot[kCauseMotors] >= 0) {
    IdentifyResult::MisfitCause& m = cs.report[cs.slot[kCauseMotors]];
    m.evidenced = motors_named(cs, m, excess > kExcessShows * r.size(), attributable);
  }
  const double z_all = detail::evidence(cs.all, cs.all.drop);
  cs.report.push_back(misfit_cause("any", cs.all, z_all, z_all, excess));
  return cs;
}

/// "falls by D (noise alone: m +- s)" of a freed step
std::string drop_clause(const detail::FreedStep& fs) {
  return "the residual falls by " + format_significant(fs.drop - fs.drop_mean, 3) +
         " (noise alone: " + format_significant(fs.drop_mean, 2) + " +- " +
         format_significant(fs.drop_sd, 2) + ")";
}

/// The candidate cause whose refit alone explains most of the misfit: the largest fall of the
/// whitened cost beyond what noise alone gives its parameters (MisfitCause::drop), among those
/// the log evidences alone (z above kCauseZ); kCauseCount: none. The falls are of one cost over
/// the same samples, so they compare like with like. The evidence z does not: each is in std of
/// its own parameters' noise (on a light mechanism whose links were 3-6 % off, the torque
/// readings' 4 parameters read 88 std and the 16 inertial parameters 72, though these lowered
/// the cost more, 267 against 249).
int most_explaining_cause(const CauseSteps& cs) {
  int best = kCauseCount;
  const auto drop = [&](int id) { return cs.report[cs.slot[id]].drop; };
  for (int id = 0; id < kCauseCount; ++id) {
    if (!competes(cs, id)) continue;
    if (best == kCauseCount || drop(id) > drop(best)) best = id;
  }
  return best;
}

/// "B with <other>, C with <other>": the falls of the other candidates checked than `best` (the
/// motors' friction only where it competes)
std::string other_falls(const CauseSteps& cs, int best) {
  std::string others;
  for (int id = 0; id < kCauseCount; ++id) {
    if (id == best || cs.slot[id] < 0 || !cs.alone[id].ok) continue;
    if (id == kCauseMotors && !competes(cs, id)) continue;  // (not read as a cause)
    others += (others.empty() ? "" : ", ") + format_significant(cs.report[cs.slot[id]].drop, 3) +
              " with " + kCauseText[id].what;
  }
  return others;
}

/// "the residual falls by A with <best> free, against B with <other>, ...": how much more the
/// cause `best` explains than each other candidate checked
std::string falls_clause(const CauseSteps& cs, int best) {
  const std::string others = other_falls(cs, best);
  return "the residual falls by " + format_significant(cs.report[cs.slot[best]].drop, 3) +
         " with " + kCauseText[best].what + " free" +
         (others.empty() ? std::string() : ", against " + others);
}

/// Whether candidate k, evidenced alone (z above kCauseZ), lowers the cost clearly more than
/// candidate id (cause_explaining_most's "clearly")
bool clearly_more(const CauseSteps& cs, int k, int id) {
  if (cs.slot[k] < 0 || !cs.alone[k].ok || !(cs.z(k) > detail::kCauseZ)) return false;
  const double margin = detail::kCauseZ * std::max(cs.alone[k].drop_sd, cs.alone[id].drop_sd);
  return cs.report[cs.slot[k]].drop - cs.report[cs.slot[id]].drop > margin;
}

/// The cause a reason names: `what`, the words of the cause `id` its check found; or, when
/// another candidate among `others` (bits: CauseId) evidenced alone (z above kCauseZ) explains
/// clearly more of the misfit, that one, with the falls of each (a reason must not blame the
/// torque readings where the inertias explain more). Clearly: its fall beyond the found cause's
/// by more than kCauseZ times the larger of their noise-alone std (a light mechanism's torques
/// both at 0.9 of the model's lowered the cost by 27 with the readings free, 32 with the
/// inertias: a tie, the readings stay). A candidate whose fall is within that margin of the
/// found cause's, above or below, is named beside it, with the falls: the log cannot tell them
/// apart (a light mechanism's masses 3 % off: 83.3 with the inertias, 79.3 with the encoders'
/// zeros; its links 6 % heavier: 292.1 with the readings, 291.2 with the inertias).
std::string cause_explaining_most(const CauseSteps& cs, int id, unsigned others,
                                  const std::string& what) {
  if (cs.slot[id] < 0 || !cs.alone[id].ok) return what;
  const auto drop = [&](int k) { return cs.report[cs.slot[k]].drop; };
  int most = id, tie = kCauseCount;
  for (int k = 0; k < kCauseCount; ++k) {
    if (!(others & (1u << k)) || k == id || !competes(cs, k)) {
      continue;
    }
    const double margin = detail::kCauseZ * std::max(cs.alone[k].drop_sd, cs.alone[most].drop_sd);
    if (drop(k) - drop(most) > margin) {
      most = k;
    } else if (drop(k) >= drop(id) - margin && (tie == kCauseCount || drop(k) > drop(tie))) {
      tie = k;
    }
  }
  if (most == id && tie != kCauseCount) {
    return what + ", or " + kCauseText[tie].what + " are off as much (" + falls_clause(cs, tie) +
           ": too close for the log to tell them apart)";
  }
  if (most == id) return what;
  return std::string(kCauseText[most].what) + " explain more of the misfit than " +
         kCauseText[id].what + " (" + falls_clause(cs, most) + ")";
}

int named_cause(const CauseSteps& cs) {
  int best = kCauseCount;
  for (int id = 0; id < kCauseDelay; ++id) {
    if (cs.named(id) &&
        (best == kCauseCount || cs.report[cs.slot[id]].drop > cs.report[cs.slot[best]].drop)) {
      best = id;
    }
  }
  return best;
}

std::string attributed_what(const CauseSteps& cs, int id) {
  return cause_explaining_most(cs, id, kAllCauses & ~(1u << id) & ~(1u << kCauseDelay),
                               kCauseText[id].off);
}

void decisive_model_error(const CauseSteps& cs, bool moves, double largest, IdentifyResult* out) {
  if (!out->unusable.empty()) return;
  const int named = named_cause(cs);
  if (named < kCauseCount && cs.report[cs.slot[named]].z_given > kDecisiveCauseZ && moves) {
    out->unusable = attributed_what(cs, named) + ": the log evidences it by " +
                    format_significant(cs.report[cs.slot[named]].z_given, 2) +
                    " std beyond the other causes (more than " +
                    format_significant(kDecisiveCauseZ) + "), and it would move the friction " +
                    (largest == 0 ? std::string("from a bound")
                                  : "by " + format_significant(largest, 2) + " std") +
                    " (see the warnings)";
    return;
  }
  bool decisive = false;
  for (int id = 0; id < kCauseDelay; ++id) {
    decisive = decisive || (competes(cs, id) && cs.z(id) > kDecisiveCauseZ);
  }
  int top = most_explaining_cause(cs);
  // (a delay that explains most is the delay stage's to correct)
  if (!decisive || top == kCauseCount || top == kCauseDelay || cs.named(top)) return;
  if (top != kCauseInertia && cs.slot[kCauseInertia] >= 0 && cs.alone[kCauseInertia].ok &&
      cs.z(kCauseInertia) > detail::kCauseZ && !clearly_more(cs, top, kCauseInertia)) {
    top = kCauseInertia;
  }
  const std::string what =
      cause_explaining_most(cs, top, kAllCauses & ~(1u << top), kCauseText[top].off);
  out->unusable = what + ": the log evidences a model error by " +
                  format_significant(cs.z(top), 2) + " std (more than " +
                  format_significant(kDecisiveCauseZ) +
                  "), which the friction estimates absorb (see the warnings)";
}

void unusable_move(double largest, const std::string& what, IdentifyResult* out) {
  if (!out->unusable.empty() || !(largest > kUnusableMove || largest == 0)) return;
  if (largest == 0) {
    out->unusable = what + ": it holds a friction coefficient at its bound (see the warnings)";
    return;
  }
  out->unusable = what + ": it would move the friction by " + format_significant(largest, 2) +
                  " std (more than " + format_significant(kUnusableMove) + "; see the warnings)";
}

}  // namespace fivebar::identification::stages
