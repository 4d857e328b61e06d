// The five-bar's excitation design: its information columns (sample_terms: the friction columns
// in closed form, the inertial ones by Jets, the actuators' in closed form), its design parameters
// and the five-bar as an ExcitationMechanism (five_bar_excitation).
#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "excitation_shared.h"
#include "fivebar/identification/excitation.h"
#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "fivebar/model/inertial.h"
#include "fivebar/model/rest_rule.h"
#include "jet_dynamics.h"
#include "noise_model.h"
#include "setup_shared.h"

namespace fivebar::identification {

namespace {

using detail::kNaN;

/// The Jet part of sample_terms: friction and inertial columns of dM/dparameter.
template <int N>
Status jet_columns(const Params<double>& scene, const DesignParameters& dp, const Loads<double>& L,
                   const MotionState& s, const JointModes* slip, SampleTerms* out) {
  using J = ceres::Jet<double, N>;
  Params<J> p = scene.template cast<J>();
  std::vector<J> x(std::max(1, dp.jet_size()));
  for (int i = 0; i < dp.jet_size(); ++i) x[i] = J(dp.nominal[i], i);
  if (dp.friction > 0) dp.layout.apply(x.data(), &p.friction);
  if (dp.inertial > 0) set_standard_inertial(x.data() + dp.friction, &p);
  EvalOptions eo;
  eo.want_angles = false;
  Evaluation<J> ev;
  const Status st = inverse_dynamics(p, L.template cast<J>(), J(s.th1), J(s.th2), J(s.w1), J(s.w2),
                                     J(s.a1), J(s.a2), slip, eo, &ev);
  if (!st.ok()) return st;
  out->M1 = ev.M1.a;
  out->M2 = ev.M2.a;
  for (int c = 0; c < dp.jet_size(); ++c) {
    out->J(0, c) = ev.M1.v[c];
    out->J(1, c) = ev.M2.v[c];
  }
  out->sine = std::abs(ev.kin.sin43.a);
  for (int k = 0; k < kJoints; ++k) out->w[k] = ev.w[k].a;
  out->slip = ev.slip;
  return Status::Ok();
}

/// Jet width of the closed-form friction columns: the per-joint Coulomb-viscous layout's 10
/// coefficients (design_parameters lays friction out so, per joint or lumped).
constexpr int kFrictionWidth = 10;

/// The friction columns in closed form, from one double inverse dynamics: the friction loop
/// N = |F0 + dF Mf|, Mf = phi(x) N + motor(x), differentiated by the implicit function theorem
/// at its solution (what the Jets' implicit loop derivative gives):
///   dMf = dMf0 + diag(phi) dN,  dN = B dMf,  dM = G dMf,
/// with dMf0 = N dphi + dmotor (Jets through the friction laws only), B(k, j) = u_k . dF_j[k]
/// (u_k: F_k's direction), dF the reactions' and G the motor torques' response to unit friction
/// torques at the given accelerations (reaction_torque_response, drive_torques). The reactions
/// and torques without friction do not depend on the coefficients. Prepared once per scene and
/// design parameters (the Jet coefficients); applies() false (use the Jets through the whole
/// inverse dynamics) for inertial parameters, the LuGre law, or a layout wider than
/// kFrictionWidth.
class FrictionColumns {
 public:
  using J = ceres::Jet<double, kFrictionWidth>;

  FrictionColumns(const Params<double>& scene, const DesignParameters& dp)
      : applies_(dp.inertial == 0 && dp.friction <= kFrictionWidth &&
                 scene.friction.law != FrictionLaw::kLuGre),
        P_(dp.friction),
        p_(scene) {
    if (!applies_ || P_ == 0) return;
    // the scene at the design's nominal coefficients (a lumped layout takes one value per kind)
    dp.layout.apply(dp.nominal.data(), &p_.friction);
    std::array<J, kFrictionWidth> x{};
    for (int i = 0; i < P_; ++i) x[i] = J(dp.nominal[i], i);
    fp_ = scene.friction.template cast<J>();
    dp.layout.apply(x.data(), &fp_);
    act_ = p_.actuators.template cast<J>();
  }
  bool applies() const { return applies_; }

  /// The sample's torques, coupler sine, rates and modes, and the friction columns of out->J
  /// (already sized).
  Status operator()(const Loads<double>& L, const MotionState& s, const JointModes* slip,
                    SampleTerms* out) const {
    EvalOptions eo;
    eo.want_angles = false;
    Evaluation<double> ev;
    const Status st = inverse_dynamics(p_, L, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, slip, eo, &ev);
    if (!st.ok()) return st;
    out->M1 = ev.M1;
    out->M2 = ev.M2;
    out->sine = std::abs(ev.kin.sin43);
    out->w = ev.w;
    out->slip = ev.slip;
    if (P_ == 0) return Status::Ok();
    Joints phi = Joints::Zero();
    Columns dMf = Columns::Zero();  // dMf0 here
    for (int j = 0; j < kJoints; ++j) {
      if (ev.slip[j] == kStuck) continue;  // no friction torque: the motors hold the joint
      const int sign = coulomb_sign(ev.slip[j]);
      const J f = fp_.pin_radius[j] * friction_law(fp_, j, J(ev.w[j]), sign);
      const J m = actuator_friction(fp_, act_, j, J(ev.w[j]), sign);
      phi(j) = f.a;
      dMf.row(j) = ev.N[j] * f.v.transpose() + m.v.transpose();
    }
    const ReactionResponse<double> dF = reaction_torque_response(ev.kin);
    Square B;
    for (int k = 0; k < kJoints; ++k) {
      const Vec2<double> u = ev.N[k] > 0 ? Vec2<double>(ev.F[k] / ev.N[k]) : Vec2<double>::Zero();
      for (int j = 0; j < kJoints; ++j) B(k, j) = u.dot(dF[j][k]);
    }
    loop_derivative(B, phi, &dMf);
    out->J.leftCols(P_) = (drive_response(ev, dF) * dMf).leftCols(P_);
    return Status::Ok();
  }

 private:
  using Joints = Eigen::Matrix<double, kJoints, 1>;
  using Square = Eigen::Matrix<double, kJoints, kJoints>;
  using Columns = Eigen::Matrix<double, kJoints, kFrictionWidth>;

  /// dMf from dMf0 (in place): (I - diag(phi) B) dMf = dMf0. The cranks' friction torques (O,
  /// D0) move no reaction (B's columns 0 and 4 vanish): then the coupler joints' three rows are
  /// solved alone and the cranks' follow.
  static void loop_derivative(const Square& B, const Joints& phi, Columns* dMf) {
    if (B.col(0).isZero(0) && B.col(kJoints - 1).isZero(0)) {
      const Eigen::Matrix3d C =
          Eigen::Matrix3d::Identity() - phi.segment<3>(1).asDiagonal() * B.block<3, 3>(1, 1);
      dMf->middleRows<3>(1) = C.inverse() * dMf->middleRows<3>(1);
      const Columns dN = B.middleCols<3>(1) * dMf->middleRows<3>(1);
      dMf->row(0) += phi(0) * dN.row(0);
      dMf->row(kJoints - 1) += phi(kJoints - 1) * dN.row(kJoints - 1);
      return;
    }
    const Square H = Square::Identity() - phi.asDiagonal() * B;
    *dMf = H.partialPivLu().solve(*dMf);
  }
  /// G: the motor torques' change per unit friction torque at the sample's accelerations (they
  /// are affine in the reactions and friction torques: drive_torques at each unit response less
  /// drive_torques at none)
  Eigen::Matrix<double, 2, kJoints> drive_response(const Evaluation<double>& ev,
                                                   const ReactionResponse<double>& dF) const {
    Evaluation<double> e;
    e.F.fill(Vec2<double>::Zero());
    FiveBar::drive_torques(p_, ev.kin, ev.thdd, &e);
    const Vec2<double> base(e.M1, e.M2);
    Eigen::Matrix<double, 2, kJoints> G;
    for (int j = 0; j < kJoints; ++j) {
      e.F = dF[j];
      e.Mf.fill(0.0);
      e.Mf[j] = 1.0;
      FiveBar::drive_torques(p_, ev.kin, ev.thdd, &e);
      G.col(j) = Vec2<double>(e.M1, e.M2) - base;
    }
    return G;
  }

  bool applies_;
  int P_;
  Params<double> p_;
  FrictionParams<J> fp_;
  ActuatorParams<J> act_;
};

/// sample_terms with prepared friction columns (`friction`: of the same scene and dp).
Status sample_terms_with(const FrictionColumns& friction, const Params<double>& scene,
                         const DesignParameters& dp, const Loads<double>& L, const MotionState& s,
                         const JointModes* slip, SampleTerms* out) {
  if (!friction.applies()) return detail::jet_sample_terms(scene, dp, L, s, slip, out);
  out->J = Eigen::MatrixXd::Zero(2, dp.size());
  const Status st = friction(L, s, slip, out);
  if (!st.ok()) return st;
  detail::actuator_columns(dp, s, out);
  return Status::Ok();
}

}  // namespace

Status detail::jet_sample_terms(const Params<double>& scene, const DesignParameters& dp,
                                const Loads<double>& L, const MotionState& s,
                                const JointModes* slip, SampleTerms* out) {
  out->J = Eigen::MatrixXd::Zero(2, dp.size());
  // the Jet widths instantiated: the active parameters of each group combination (the actuator
  // terms alone, 0 Jet parameters, take the narrowest: their columns are in closed form)
  using Columns = Status (*)(const Params<double>&, const DesignParameters&, const Loads<double>&,
                             const MotionState&, const JointModes*, SampleTerms*);
  static const std::pair<int, Columns> kWidths[] = {{2, &jet_columns<2>},
                                                    {10, &jet_columns<10>},
                                                    {16, &jet_columns<16>},
                                                    {18, &jet_columns<18>},
                                                    {26, &jet_columns<26>}};
  Columns columns = &jet_columns<26>;  // the widest: every group
  for (const auto& [width, fn] : kWidths) {
    if (dp.jet_size() <= width) {
      columns = fn;
      break;
    }
  }
  const Status st = columns(scene, dp, L, s, slip, out);
  if (!st.ok()) return st;
  detail::actuator_columns(dp, s, out);
  return Status::Ok();
}

DesignParameters design_parameters(const Params<double>& scene, const DesignGroups& g) {
  DesignParameters dp;
  dp.layout.law = FrictionLaw::kCoulombViscous;
  dp.layout.per_joint = g.per_joint;
  auto add = [&](const std::string& name, double nominal, double typical) {
    dp.names.push_back(name);
    dp.nominal.push_back(nominal);
    dp.scale.push_back(std::abs(nominal) > 0 ? std::abs(nominal) : typical);
  };
  if (g.friction) {
    const std::vector<std::string> names = dp.layout.names();
    const std::vector<double> x = dp.layout.extract(scene.friction);
    for (size_t i = 0; i < names.size(); ++i) add(names[i], x[i], 1e-3);
    dp.friction = static_cast<int>(names.size());
  }
  if (g.inertia) {
    const std::array<double, kInertialParams> pi = standard_inertial(scene);
    for (int i = 0; i < kInertialParams; ++i) add(inertial_name(i), pi[i], 1e-3);
    dp.inertial = kInertialParams;
  }
  if (g.actuator) {
    // the scene's values (`actuators:`), a typical scale where it has none
    const ActuatorParams<double>& a = scene.actuators;
    for (int j = 0; j < kActuators; ++j) {
      const std::string n = std::to_string(j + 1);
      add("offset_" + n, a.offset[j], 0.1);
      add("actuator_coulomb_" + n, a.coulomb[j], 0.1);
      add("actuator_viscous_" + n, a.viscous[j], 0.01);
    }
    dp.actuator = 2 * kActuatorPerMotor;
  }
  return dp;
}

Status sample_terms(const Params<double>& scene, const DesignParameters& dp, const Loads<double>& L,
                    const MotionState& s, const JointModes* slip, SampleTerms* out) {
  return sample_terms_with(FrictionColumns(scene, dp), scene, dp, L, s, slip, out);
}

// ---------------------------------------------------------------------------------------------
// The five-bar as an ExcitationMechanism

namespace {

class FiveBarExcitation : public ExcitationMechanism {
 public:
  FiveBarExcitation(const Params<double>& scene, DesignParameters dp,
                    std::function<Loads<double>(double)> loads)
      : scene_(scene), dp_(std::move(dp)), loads_(std::move(loads)), friction_(scene_, dp_) {}
  int dof() const override { return kDof; }
  int joints() const override { return kJoints; }
  std::string joint_name(int k) const override {
    static const char* const kNames[] = {"O", "B", "C", "D", "D0"};
    return kNames[k];
  }
  std::string type() const override { return "five_bar"; }
  const DesignParameters& parameters() const override { return dp_; }
  Status terms(double t, const MotionState& s, const JointModes* slip,
               SampleTerms* out) const override {
    return sample_terms_with(friction_, scene_, dp_, loads_(t), s, slip, out);
  }
  Status kinematic_jacobian(double t, const MotionState& q,
                            Eigen::Matrix<double, 2, 6>* D) const override {
    Sample s;
    s.t = t, s.th1 = q.th1, s.th2 = q.th2, s.w1 = q.w1, s.w2 = q.w2, s.a1 = q.a1, s.a2 = q.a2;
    s.loads = loads_(t);
    const std::vector<double> x = dp_.layout.extract(scene_.friction);
    if (!detail::kinematic_jacobian(scene_, dp_.layout, x.data(), s, EvalOptions{}, D)) {
      return Status::Error(StatusCode::kSolverFailed,
                           "the torques' derivative along the motion failed");
    }
    return Status::Ok();
  }
  bool window_by_bias(SgOptions*) const override { return false; }
  /// identify (identify_window) on the log synth-log's sensors (sample_log) write along the
  /// motion, its layout the design's (the angles' unit is not checked: they are radians)
  bool identify_window(const ExcitationReport& r, double torque_noise, double angle_noise,
                       SgOptions* sg, std::string* choice) const override {
    std::vector<sim::Row> rows(r.t.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      const MotionState& q = r.states[i];
      rows[i].t = r.t[i];
      rows[i].theta[0] = q.th1, rows[i].theta[1] = q.th2;
      rows[i].omega[0] = q.w1, rows[i].omega[1] = q.w2;
      rows[i].M1 = r.M1[i], rows[i].M2 = r.M2[i];
    }
    SynthOptions so;
    so.torque_noise = torque_noise;
    so.angle_noise = angle_noise;
    SynthResult log;
    sample_log(scene_, rows, so, &log);
    log.log.path = "the log along the motion";
    IdentifyOptions opt;
    opt.layout = dp_.layout;
    opt.check_degrees = false;  // sample_log writes the motion's angles in radians
    try {
      return fivebar::identification::identify_window(scene_, loads_, log.log, opt, sg, choice);
    } catch (const LogError& e) {
      *choice = e.what();
      return false;
    }
  }
  /// identify's rule (stage_samples.cc: rest_rule, held_sample): thresholds kRestSigmas std of
  /// the filtered rates and accelerations, the angle noise through the joint rates' dependence
  /// on the pose
  bool at_rest(double t, const MotionState& q, double g1, double g2,
               double angle_noise) const override {
    if (!(angle_noise > 0)) return false;
    Sample s;
    s.t = t, s.th1 = q.th1, s.th2 = q.th2, s.w1 = q.w1, s.w2 = q.w2, s.a1 = q.a1, s.a2 = q.a2;
    return stages::held_sample(scene_, s, rest_thresholds(g1 * angle_noise, g2 * angle_noise),
                               angle_noise);
  }

 private:
  Params<double> scene_;
  DesignParameters dp_;
  std::function<Loads<double>(double)> loads_;
  FrictionColumns friction_;
};

}  // namespace

std::shared_ptr<const ExcitationMechanism> five_bar_excitation(
    const Params<double>& scene, const DesignParameters& dp,
    std::function<Loads<double>(double)> loads) {
  return std::make_shared<FiveBarExcitation>(scene, dp, std::move(loads));
}

}  // namespace fivebar::identification
