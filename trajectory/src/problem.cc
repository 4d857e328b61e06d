// The five-bar's trajectory problem (TrajectoryProblemT<FiveBar>, its Jet inverse dynamics), the
// mechanism-independent members of TrajectoryProblemBase and the names of the settings.
#include "fivebar/trajectory/problem.h"

#include <cmath>

#include "fivebar/model/names.h"
#include "problem_impl.h"

namespace fivebar::trajectory {

namespace {
constexpr Named<Objective> kObjectiveNames[] = {
    {Objective::kTotalDissipation, "total_dissipation"},
    {Objective::kSupplyEnergy, "supply_energy"},
    {Objective::kDissipatedEnergy, "dissipated_energy"},
    {Objective::kInputEnergy, "input_energy"},
    {Objective::kDissipatedEnergy, "dissipated"},
    {Objective::kInputEnergy, "input"}};
constexpr Named<Regeneration> kRegenerationNames[] = {{Regeneration::kNone, "none"},
                                                      {Regeneration::kSharedBus, "shared_bus"}};
constexpr Named<EndAcceleration> kEndAccelerationNames[] = {{EndAcceleration::kFree, "free"},
                                                            {EndAcceleration::kZero, "zero"}};
}  // namespace

const char* objective_name(Objective o) { return name_in(kObjectiveNames, o); }

bool parse_objective(const std::string& name, Objective* out) {
  return parse_in(kObjectiveNames, name, out);
}

std::string objective_names() {
  return "total_dissipation, supply_energy, dissipated_energy, input_energy";
}

double TrajectoryProblemBase::heat_share(const double* x) const {
  const ProblemOptions& o = options();
  if (!needs_winding(o.objective)) return 0.0;
  Energies e;
  if (!energies(x, o.quadrature_points, &e).ok()) return NAN;
  const double objective = o.objective == Objective::kSupplyEnergy ? e.supply : e.total();
  return objective > 0.0 ? e.winding_heat / objective : NAN;
}

bool needs_winding(Objective o) {
  return o == Objective::kTotalDissipation || o == Objective::kSupplyEnergy;
}

const char* regeneration_name(Regeneration r) { return name_in(kRegenerationNames, r); }

bool parse_regeneration(const std::string& name, Regeneration* out) {
  return parse_in(kRegenerationNames, name, out);
}

const char* end_acceleration_name(EndAcceleration e) { return name_in(kEndAccelerationNames, e); }

bool parse_end_acceleration(const std::string& name, EndAcceleration* out) {
  return parse_in(kEndAccelerationNames, name, out);
}

double Energies::of(Objective o) const {
  switch (o) {
    case Objective::kDissipatedEnergy: return dissipated;
    case Objective::kInputEnergy: return input;
    case Objective::kTotalDissipation: return total();
    case Objective::kSupplyEnergy: return supply;
  }
  return dissipated;
}

Status TrajectoryProblemBase::objective(const double* x, double* value) const {
  Evaluated e;
  const Status st = evaluate(x, false, &e);
  if (st.ok()) *value = e.objective;
  return st;
}

template class TrajectoryProblemT<FiveBar>;

}  // namespace fivebar::trajectory
