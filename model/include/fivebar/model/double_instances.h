// The double kinematics, mass matrix, reactions and holding of the five-bar and the four-bar,
// compiled once in fivebar::sim (model/src/double_instances.cc). A unit that includes this header
// calls those copies instead of compiling its own: the command-line layer (apps/), compiled at a
// lower optimization level, force-includes it so that the executable's hot paths are the
// libraries' optimized code (the linker keeps the first copy of a template it meets).
#pragma once

#include "fivebar/model/appell.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/reactions.h"
#include "fivebar/model/rest.h"

namespace fivebar {
extern template Status close_loop<double>(const Params<double>&, const double&, const double&,
                                          Kinematics<double>*, double, bool);
extern template void place_points<double>(const Params<double>&, Kinematics<double>*);
extern template void first_order_coefficients<double>(const Params<double>&, Kinematics<double>*);
extern template Status solve_kinematics<double>(const Params<double>&, const double&,
                                                const double&, Kinematics<double>*, double, bool);
extern template void compute_bias<double>(const Params<double>&, const Kinematics<double>&,
                                          const double&, const double&, Bias<double>*);
extern template void mass_and_forces<double>(const Params<double>&, const Kinematics<double>&,
                                             const Bias<double>&, const Loads<double>&,
                                             const Vec2<double>&, Mat2<double>*, Vec2<double>*);
extern template void reactions<double>(const Params<double>&, const Kinematics<double>&,
                                       const Bias<double>&, const Loads<double>&,
                                       const Vec2<double>&, const Vec2<double>&,
                                       const std::array<double, kJoints>&,
                                       std::array<Vec2<double>, kJoints>*, double*, double*);
extern template void reaction_norms<double>(const std::array<Vec2<double>, kJoints>&,
                                            std::array<double, kJoints>*);
extern template Status holding_torques<double>(const Params<double>&, const Loads<double>&,
                                               const double&, const double&, const EvalOptions&,
                                               Holding<double>*);
extern template Status four_bar_close<double>(const FourBarParamsT<double>&, const double&,
                                              FourBarKinematicsT<double>*, double);
extern template Status four_bar_kinematics<double>(const FourBarParamsT<double>&, const double&,
                                                   FourBarKinematicsT<double>*, double);
}  // namespace fivebar
