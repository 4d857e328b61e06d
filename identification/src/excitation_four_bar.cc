// The four-bar as an ExcitationMechanism (excitation.h): the crank's torque M1 and its
// derivatives by Jets of the four-bar's inverse dynamics (mech::inverse<FourBar>, one Jet width
// for both the parameter and the motion derivatives), its friction and its links' standard
// inertial parameters (with identify's prior on them), its crank motor's offset and friction (in
// closed form), and identify's rules on four-bars
// (identify_four_bar.cc): its window walked by predicted bias from its filter, and its rest rule.
#include <ceres/jet.h>

#include <algorithm>
#include <cmath>

#include "fivebar/identification/excitation.h"
#include "fivebar/identification/identify.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/inertial.h"
#include "excitation_shared.h"
#include "four_bar_rules.h"
#include "inertia.h"

namespace fivebar::identification {
namespace {

/// One Jet width W for every derivative of a design: its friction coefficients (2 shared, 8 per
/// joint) and inertial parameters (12), or the crank's angle, rate and acceleration (3): one
/// instantiation of the four-bar's inverse dynamics per layout
constexpr int kSharedWidth = 3, kPerJointWidth = 2 * kFourBarJoints;
constexpr int kFourBarInertial = kInertialPerLink * kFourBarLinks;

/// identify_four_bar.cc's rate filter order and rest rule (four_bar_rules.h)
using four_bar_rules::kRestSigmas;
using four_bar_rules::kWindowOrder;

template <int W>
class FourBarExcitation : public ExcitationMechanism {
  using Jet = ceres::Jet<double, W>;

 public:
  FourBarExcitation(const FourBarParams& scene, bool per_joint, bool inertia, bool actuator,
                    std::function<FourBarLoads(double)> loads)
      : scene_(scene),
        dp_(four_bar_design_parameters(scene, per_joint, inertia, actuator)),
        loads_(std::move(loads)) {}
  int dof() const override { return FourBar::kDof; }
  int joints() const override { return kFourBarJoints; }
  std::string joint_name(int k) const override {
    static const char* const kNames[] = {"O", "B", "C", "D0"};
    return kNames[k];
  }
  std::string type() const override { return "four_bar"; }
  const DesignParameters& parameters() const override { return dp_; }

  Status terms(double t, const MotionState& s, const JointModes* slip,
               SampleTerms* out) const override {
    FourBarParamsT<Jet> p = scene_.cast<Jet>();
    std::vector<Jet> x(dp_.jet_size());
    for (int i = 0; i < dp_.jet_size(); ++i) x[i] = Jet(dp_.nominal[i], i);
    dp_.layout.apply(x.data(), &p.friction);
    if (dp_.inertial > 0)
      set_standard_inertial_links(x.data() + dp_.friction, kFourBarLinks, p.links.data());
    FourBarEvaluationT<Jet> ev;
    const Status st = four_bar_inverse(p, loads_(t).cast<Jet>(), Jet(s.th1), Jet(s.w1), Jet(s.a1),
                                       EvalOptions{}, &ev, slip);
    if (!st.ok()) return st;
    out->J = Eigen::MatrixXd::Zero(2, dp_.size());
    for (int c = 0; c < dp_.jet_size(); ++c) out->J(0, c) = ev.M1.v[c];
    detail::actuator_columns(dp_, s, out);  // the crank's motor at O
    out->M1 = ev.M1.a;
    out->M2 = 0;
    out->sine = std::abs(ev.kin.sin32.a);
    out->w = {};
    for (int k = 0; k < kFourBarJoints; ++k) out->w[k] = ev.w[k].a;
    out->slip = ev.slip;
    return Status::Ok();
  }

  Status kinematic_jacobian(double t, const MotionState& s,
                            Eigen::Matrix<double, 2, 6>* D) const override {
    FourBarEvaluationT<Jet> ev;
    const Status st = four_bar_inverse(scene_.cast<Jet>(), loads_(t).cast<Jet>(), Jet(s.th1, 0),
                                       Jet(s.w1, 1), Jet(s.a1, 2), EvalOptions{}, &ev);
    if (!st.ok()) return st;
    D->setZero();
    // columns th1, w1, a1 of (th1, th2, w1, w2, a1, a2)
    for (int c = 0; c < 3; ++c) (*D)(0, 2 * c) = ev.M1.v[c];
    return Status::Ok();
  }

  /// identify_four_bar.cc's filter before its window choice (filter_options) and its walk
  bool window_by_bias(SgOptions* sg) const override {
    *sg = SgOptions{};
    sg->order = std::max(sg->order, kWindowOrder);
    return true;
  }

  bool at_rest(double, const MotionState& s, double g1, double, double angle_noise) const override {
    FourBarKinematics k;
    if (!four_bar_kinematics(scene_, s.th1, &k).ok()) return false;
    const std::array<double, kFourBarJoints> row = four_bar_joint_rows(k);
    const double rate_noise = angle_noise * g1;
    for (int j = 0; j < kFourBarJoints; ++j) {
      const double rest = kRestSigmas * rate_noise * std::abs(row[j]);
      if (std::abs(row[j] * s.w1) <= std::max(rest, 1e-12)) return true;
    }
    return false;
  }

 private:
  FourBarParams scene_;
  DesignParameters dp_;
  std::function<FourBarLoads(double)> loads_;
};

}  // namespace

DesignParameters four_bar_design_parameters(const FourBarParams& scene, bool per_joint,
                                            bool inertia, bool actuator) {
  DesignParameters dp;
  dp.layout.law = FrictionLaw::kCoulombViscous;
  dp.layout.per_joint = per_joint;
  dp.layout.set_four_bar();
  dp.names = dp.layout.names();
  dp.nominal = dp.layout.extract(scene.friction);
  dp.friction = static_cast<int>(dp.names.size());
  dp.prior_std.assign(dp.friction, 0.0);
  if (inertia) {  // identify's prior (--inertia-prior at its default) holds them
    const detail::InertialPrior prior =
        detail::inertial_prior(scene.links.data(), kFourBarLinks, IdentifyOptions{}.inertia_prior);
    for (int i = 0; i < kFourBarInertial; ++i) {
      dp.names.push_back(inertial_name(i));
      dp.nominal.push_back(prior.centre[i]);
      dp.prior_std.push_back(prior.sigma[i]);
    }
    dp.inertial = kFourBarInertial;
  }
  for (double v : dp.nominal) dp.scale.push_back(std::abs(v) > 0 ? std::abs(v) : 1e-3);
  if (actuator) {  // the crank's motor (actuators.M1), a typical scale where the scene has none
    const ActuatorParams<double>& a = scene.actuators;
    const std::pair<const char*, double> terms[] = {{"offset_1", a.offset[0]},
                                                    {"actuator_coulomb_1", a.coulomb[0]},
                                                    {"actuator_viscous_1", a.viscous[0]}};
    const double typical[] = {0.1, 0.1, 0.01};
    for (int i = 0; i < 3; ++i) {
      dp.names.push_back(terms[i].first);
      dp.nominal.push_back(terms[i].second);
      dp.scale.push_back(std::abs(terms[i].second) > 0 ? std::abs(terms[i].second) : typical[i]);
      dp.prior_std.push_back(0.0);
    }
    dp.actuator = kActuatorPerMotor;
  }
  return dp;
}

std::shared_ptr<const ExcitationMechanism> four_bar_excitation(
    const FourBarParams& scene, std::function<FourBarLoads(double)> loads, bool per_joint,
    bool inertia, bool actuator) {
  if (per_joint && inertia) {
    return std::make_shared<FourBarExcitation<kPerJointWidth + kFourBarInertial>>(
        scene, true, true, actuator, std::move(loads));
  }
  if (inertia) {
    return std::make_shared<FourBarExcitation<2 + kFourBarInertial>>(scene, false, true, actuator,
                                                                     std::move(loads));
  }
  if (per_joint) {
    return std::make_shared<FourBarExcitation<kPerJointWidth>>(scene, true, false, actuator,
                                                               std::move(loads));
  }
  return std::make_shared<FourBarExcitation<kSharedWidth>>(scene, false, false, actuator,
                                                           std::move(loads));
}

}  // namespace fivebar::identification
