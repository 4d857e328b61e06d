// A project outside fivebar, built against an installed tree (tests/consumer.cmake): the
// header-only model, plus one call into each of the identification and trajectory libraries.
#include <cstdio>

#include "fivebar/identification/torque_log.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"
#include "fivebar/trajectory/tasks.h"

int main() {
  const fivebar::Params<double> p = fivebar::paper_params();
  const fivebar::Loads<double> loads{0.0, 0.0, 6.0, 50.0, 1.5707963267948966};
  fivebar::Evaluation<double> ev;
  const fivebar::Status st = fivebar::inverse_dynamics(
      p, loads, 1.5707963267948966, 1.5707963267948966, 0.5, -0.2, 1.0, 2.0, nullptr,
      fivebar::EvalOptions{}, &ev);
  std::array<double, 2> c{};
  const bool closes = fivebar::trajectory::point_c(p, 1.5707963267948966, 1.5707963267948966, &c);
  if (!st.ok() || !closes) return 1;
  std::printf("M1 %s N m, M2 %.6g N m, C = (%.6g, %.6g) m\n",
              fivebar::format_shortest(ev.M1).c_str(), ev.M2, c[0], c[1]);
  return 0;
}
