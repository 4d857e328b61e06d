// The frictionless paper scene in Simbody beside fivebar, in one run: error against
// datasets/reference/paper_frictionless.csv over the first second and wall time.
//   build-peers/tests/bench/peers/bench_peers_simbody
// Model: Pin mobilizers for the cranks on ground and for the couplers on the cranks (their q is the
// relative angle th3 - th1, th4 - th2), the loop closed by Constraint::Ball at C, the loads by a
// Force::Custom, gravity by Force::UniformGravity.
#include <Simbody.h>

#include <cstdio>
#include <memory>

#include "peers_common.h"

namespace fivebar::peers {
namespace {

using SimTK::Vec3;

/// M1, M2 (mobility forces of the two crank pins), M3 on link 3 and F at P (model.md, M_d).
class PaperLoads : public SimTK::Force::Custom::Implementation {
 public:
  PaperLoads(const SimTK::MobilizedBody& l1, const SimTK::MobilizedBody& l2,
             const SimTK::MobilizedBody& l3, double lp)
      : l1_(l1), l2_(l2), l3_(l3), lp_(lp) {}

  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>& body_forces,
                 SimTK::Vector_<Vec3>& /*particle_forces*/,
                 SimTK::Vector& mobility_forces) const override {
    const Loads<double> L = paper_loads(s.getTime());
    // motor torques: generalized forces of the ground pins at O and D0
    l1_.applyOneMobilityForce(s, 0, L.M1, mobility_forces);
    l2_.applyOneMobilityForce(s, 0, L.M2, mobility_forces);
    // moment on the coupler B-C, counter-clockwise positive
    l3_.applyBodyTorque(s, Vec3(0, 0, L.M3), body_forces);
    // F at P, at F_angle from the direction of link 3 (its body x axis)
    const SimTK::Rotation& R = l3_.getBodyRotation(s);
    const Vec3 dir = std::cos(L.F_angle) * R.x() + std::sin(L.F_angle) * R.y();
    l3_.applyForceToBodyPoint(s, Vec3(lp_, 0, 0), L.F * dir, body_forces);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

 private:
  const SimTK::MobilizedBody &l1_, &l2_, &l3_;
  double lp_;
};

/// The mechanism as a Simbody system, with its assembled initial state.
struct SimbodyFiveBar {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::MobilizedBody::Pin l1, l2, l3, l4;
  SimTK::State initial;

  SimbodyFiveBar() {
    const Params<double> p = frictionless_params();
    // a link along its body x axis, proximal joint at the body origin, J about the COM (izz)
    auto body = [](const Link<double>& k) {
      const Vec3 com(k.com_offset * std::cos(k.com_angle), k.com_offset * std::sin(k.com_angle), 0);
      return SimTK::Body::Rigid(SimTK::MassProperties(
          k.mass, com, SimTK::Inertia(k.inertia).shiftFromMassCenter(com, k.mass)));
    };
    SimTK::MobilizedBody& ground = matter.updGround();
    l1 =
        SimTK::MobilizedBody::Pin(ground, SimTK::Transform(), body(p.links[0]), SimTK::Transform());
    l2 = SimTK::MobilizedBody::Pin(ground, SimTK::Transform(Vec3(p.ground_length, 0, 0)),
                                   body(p.links[1]), SimTK::Transform());
    l3 = SimTK::MobilizedBody::Pin(l1, SimTK::Transform(Vec3(p.links[0].length, 0, 0)),
                                   body(p.links[2]), SimTK::Transform());
    l4 = SimTK::MobilizedBody::Pin(l2, SimTK::Transform(Vec3(p.links[1].length, 0, 0)),
                                   body(p.links[3]), SimTK::Transform());
    // loop closure at C: end of link 3 on end of link 4 (the z row is redundant in the plane)
    SimTK::Constraint::Ball(l3, Vec3(p.links[2].length, 0, 0), l4, Vec3(p.links[3].length, 0, 0));
    SimTK::Force::UniformGravity(forces, matter, Vec3(0, -p.gravity, 0));
    SimTK::Force::Custom(forces, new PaperLoads(l1, l2, l3, p.point_p));
    system.setUseUniformBackground(true);

    // assembled start: th1 = th2 = pi/2, elbow_up, at rest (couplers' q are relative angles)
    initial = system.realizeTopology();
    const std::array<double, 4> th = initial_angles();
    l1.setOneQ(initial, 0, th[0]);
    l2.setOneQ(initial, 0, th[1]);
    l3.setOneQ(initial, 0, th[2] - th[0]);
    l4.setOneQ(initial, 0, th[3] - th[1]);
    system.realize(initial, SimTK::Stage::Position);
  }

  std::array<double, 4> angles(const SimTK::State& s) const {
    const double q1 = l1.getOneQ(s, 0), q2 = l2.getOneQ(s, 0);
    return {q1, q2, q1 + l3.getOneQ(s, 0), q2 + l4.getOneQ(s, 0)};
  }
};

/// Simbody's error-controlled integrators. CPodes (BDF/Newton and Adams/functional) is left out:
/// Debian's Simbody 3.7 aborts in it on this system ("nvector_SimTK.h:84: Assertion
/// `!treatAsConst' failed").
enum class Kind { kRkMerson, kRkFeldberg };

struct Config {
  Kind kind;
  double accuracy, constraint_tolerance;
  const char* label;
};

std::unique_ptr<SimTK::Integrator> make_integrator(const SimTK::MultibodySystem& sys, Kind kind) {
  switch (kind) {
    case Kind::kRkMerson:
      return std::make_unique<SimTK::RungeKuttaMersonIntegrator>(sys);
    case Kind::kRkFeldberg:
      return std::make_unique<SimTK::RungeKuttaFeldbergIntegrator>(sys);
  }
  return nullptr;
}

/// One run of the first second, reported on the 1 ms grid by TimeStepper::stepTo.
Trajectory simbody_run(const SimbodyFiveBar& fb, const Config& c, int* steps = nullptr) {
  std::unique_ptr<SimTK::Integrator> integ = make_integrator(fb.system, c.kind);
  if (c.accuracy > 0) integ->setAccuracy(c.accuracy);
  if (c.constraint_tolerance > 0) integ->setConstraintTolerance(c.constraint_tolerance);
  integ->setInternalStepLimit(100000000);
  SimTK::TimeStepper ts(fb.system, *integ);
  ts.initialize(fb.initial);
  Trajectory tr = on_output_grid([&](int i) { ts.stepTo(kOutputStep * i); },
                                 [&] { return fb.angles(ts.getState()); });
  if (steps) *steps = integ->getNumStepsTaken();
  return tr;
}

}  // namespace
}  // namespace fivebar::peers

/// The Simbody rows: Runge-Kutta-Merson from its defaults to tight accuracies, and Feldberg.
std::vector<fivebar::peers::Measured> simbody_rows(const fivebar::peers::Trajectory& ref) {
  using namespace fivebar::peers;
  SimbodyFiveBar fb;
  const Config configs[] = {
      {Kind::kRkMerson, 0, 0, "RungeKuttaMerson, defaults (accuracy 1e-3)"},
      {Kind::kRkMerson, 1e-6, 1e-8, "RungeKuttaMerson, accuracy 1e-6, constraint tol 1e-8"},
      {Kind::kRkMerson, 1e-8, 1e-10, "RungeKuttaMerson, accuracy 1e-8, constraint tol 1e-10"},
      {Kind::kRkMerson, 1e-10, 1e-12, "RungeKuttaMerson, accuracy 1e-10, constraint tol 1e-12"},
      {Kind::kRkFeldberg, 1e-10, 1e-12,
       "RungeKuttaFeldberg, accuracy 1e-10, constraint tol 1e-12"},
      {Kind::kRkMerson, 1e-12, 1e-14, "RungeKuttaMerson, accuracy 1e-12, constraint tol 1e-14"},
  };
  std::vector<Measured> peer_rows;
  for (const Config& c : configs) {
    int steps = 0;
    Measured m = measure("Simbody 3.7", c.label, ref, [&] { return simbody_run(fb, c, &steps); });
    m.note = std::to_string(steps) + " steps";
    m.settings += " (" + m.note + ")";
    peer_rows.push_back(m);
    std::fprintf(stderr, "simbody: %s: error %.3e rad, %.3f ms\n", m.settings.c_str(), m.error,
                 1e3 * m.wall);
  }
  return peer_rows;
}

int main() {
  return fivebar::peers::run_peer_bench("bench_peers_simbody", "Simbody", simbody_rows);
}
