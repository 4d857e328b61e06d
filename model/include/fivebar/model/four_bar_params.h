// The four-bar's constants and loads (four_bar.h holds its model): what a scene describes.
#pragma once

#include <array>

#include "fivebar/model/friction.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

inline constexpr int kFourBarJoints = 4;  ///< O, B, C, D0
inline constexpr int kFourBarLinks = 3;   ///< crank, coupler, rocker

/// Every constant of a four-bar (links at index 0..2: crank O->B, coupler B->C, rocker D0->C),
/// templated on the scalar like the five-bar's Params (FourBarParams: double).
template <typename T>
struct FourBarParamsT {
  T ground_length{};  ///< l0 [m]: O at (0,0), D0 at (l0,0)
  std::array<Link<T>, kFourBarLinks> links;
  T point_p{};                 ///< P on the coupler, from B [m]
  int assembly = kElbowUp;     ///< kElbowUp: C left of the directed line B->D0
  T gravity{};                 ///< along -y [m/s^2]
  FrictionParams<T> friction;  ///< slots 0..3: joints O, B, C, D0
  /// the crank's motor at O (entry 0: M1, kFourBarActuators); entry 1 stays zero
  ActuatorParams<T> actuators;

  template <typename U>
  FourBarParamsT<U> cast() const {
    FourBarParamsT<U> out;
    out.ground_length = scalar_cast<U>(ground_length);
    for (int i = 0; i < kFourBarLinks; ++i) out.links[i] = links[i].template cast<U>();
    out.point_p = scalar_cast<U>(point_p);
    out.assembly = assembly;
    out.gravity = scalar_cast<U>(gravity);
    out.friction = friction.template cast<U>();
    out.actuators = actuators.template cast<U>();
    return out;
  }
};
using FourBarParams = FourBarParamsT<double>;

/// Loads of one instant: M1 on the crank, M3 on the coupler, F at P at F_angle from the coupler.
template <typename T>
struct FourBarLoadsT {
  T M1{}, M3{}, F{}, F_angle{};

  template <typename U>
  FourBarLoadsT<U> cast() const {
    return {scalar_cast<U>(M1), scalar_cast<U>(M3), scalar_cast<U>(F), scalar_cast<U>(F_angle)};
  }
};
using FourBarLoads = FourBarLoadsT<double>;

}  // namespace fivebar
