// The standard (barycentric) inertial parameters of the four links, in which the equations of
// motion are linear: per link m_i, m_i c_x,i, m_i c_y,i and J_O,i, the moment of inertia about
// the proximal joint, with (c_x, c_y) the centre of mass in the link frame (x from the proximal
// joint towards the distal one). Identification and excitation design estimate these.
#pragma once

#include <array>
#include <cmath>
#include <string>

#include "fivebar/model/params.h"

namespace fivebar {

inline constexpr int kInertialPerLink = 4;
inline constexpr int kInertialParams = kLinks * kInertialPerLink;  // 16

/// Names in vector order: m_1, mx_1, my_1, J_1, m_2, ... (links 1..4, 1-based as in the docs).
inline std::string inertial_name(int i) {
  static const char* const kNames[] = {"m", "mx", "my", "J"};
  return std::string(kNames[i % kInertialPerLink]) + "_" + std::to_string(i / kInertialPerLink + 1);
}

/// Units of the parameters, in vector order.
inline const char* inertial_unit(int i) {
  static const char* const kUnits[] = {"kg", "kg m", "kg m", "kg m^2"};
  return kUnits[i % kInertialPerLink];
}

/// The standard parameters of the n links `links` into pi[0 .. 4 n) (the five-bar's four, the
/// four-bar's three: crank, coupler, rocker).
template <typename T>
void standard_inertial_links(const Link<T>* links, int n, T* pi) {
  using std::cos;
  using std::sin;
  for (int i = 0; i < n; ++i) {
    const Link<T>& L = links[i];
    const T cx = L.com_offset * cos(L.com_angle);
    const T cy = L.com_offset * sin(L.com_angle);
    pi[kInertialPerLink * i + 0] = L.mass;
    pi[kInertialPerLink * i + 1] = L.mass * cx;
    pi[kInertialPerLink * i + 2] = L.mass * cy;
    pi[kInertialPerLink * i + 3] = L.inertia + L.mass * (cx * cx + cy * cy);
  }
}

/// The 16 standard parameters of `p`.
template <typename T>
std::array<T, kInertialParams> standard_inertial(const Params<T>& p) {
  std::array<T, kInertialParams> pi{};
  standard_inertial_links(p.links.data(), kLinks, pi.data());
  return pi;
}

/// Writes the standard parameters pi[0 .. 4 n) into the n links `links` (mass, com_offset,
/// com_angle, inertia about the COM). Physically consistent only when m > 0 and
/// J_O - (mx^2 + my^2) / m > 0: check with inertial_consistent(). A COM at the joint
/// (mx = my = 0) keeps com_angle at 0.
template <typename T>
void set_standard_inertial_links(const T* pi, int n, Link<T>* links) {
  using std::atan2;
  using std::sqrt;
  for (int i = 0; i < n; ++i) {
    Link<T>& L = links[i];
    const T& m = pi[kInertialPerLink * i + 0];
    const T& mx = pi[kInertialPerLink * i + 1];
    const T& my = pi[kInertialPerLink * i + 2];
    const T& jo = pi[kInertialPerLink * i + 3];
    const T r2 = (mx * mx + my * my) / (m * m);
    L.mass = m;
    if (r2 > T(0)) {
      L.com_offset = sqrt(r2);
      L.com_angle = atan2(my, mx);
    } else {
      L.com_offset = T(0);
      L.com_angle = T(0);
    }
    L.inertia = jo - m * r2;
  }
}

/// Writes 16 standard parameters into the links of `p` (set_standard_inertial_links).
template <typename T>
void set_standard_inertial(const T* pi, Params<T>* p) {
  set_standard_inertial_links(pi, kLinks, p->links.data());
}

/// True when each of the n links of pi[0 .. 4 n) has m > 0 and an inertia about its COM > 0.
inline bool inertial_consistent(const double* pi, int n) {
  for (int i = 0; i < n; ++i) {
    const double m = pi[kInertialPerLink * i], mx = pi[kInertialPerLink * i + 1],
                 my = pi[kInertialPerLink * i + 2], jo = pi[kInertialPerLink * i + 3];
    if (!(m > 0) || !(jo - (mx * mx + my * my) / m > 0)) return false;
  }
  return true;
}

/// True when every link has m > 0 and an inertia about its COM > 0.
inline bool inertial_consistent(const std::array<double, kInertialParams>& pi) {
  return inertial_consistent(pi.data(), kLinks);
}

}  // namespace fivebar
