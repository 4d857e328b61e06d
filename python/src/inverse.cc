// fivebar.inverse: friction-aware inverse dynamics of N states, vectorized in C++ with the GIL
// released, on several threads for large N.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <thread>

#include <pybind11/stl.h>

#include "bindings.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/rest.h"

namespace fivebar::python {
namespace {

constexpr size_t kNone = SIZE_MAX;
constexpr size_t kMinStatesPerThread = 4096;  // below, a thread costs more than it saves

// the inputs as contiguous float64 buffers (owned by the arrays kept alive by the caller)
struct States {
  const double *theta, *omega, *alpha, *t;  // (n, 2), (n, 2), (n, 2), (n,) or nullptr
  size_t n;
};

struct Outputs {
  double *M, *N, *Mf;  // (n, 2), (n, 5), (n, 5)
};

// the first state of a range that failed, and why
struct Failure {
  size_t index = kNone;
  Status status;
};

bool finite_state(const States& s, size_t i) {
  for (const double* a : {s.theta, s.omega, s.alpha}) {
    if (!std::isfinite(a[2 * i]) || !std::isfinite(a[2 * i + 1])) return false;
  }
  return s.t == nullptr || std::isfinite(s.t[i]);
}

// Inverse dynamics of states [begin, end). `loads` evaluates time-dependent loads (nullptr:
// `constant` holds them).
Failure inverse_range(const Params<double>& p, const io::LoadExpressions* loads,
                      const Loads<double>& constant, const EvalOptions& eval, const States& s,
                      const Outputs& out, size_t begin, size_t end) {
  for (size_t i = begin; i < end; ++i) {
    if (!finite_state(s, i)) return {i, Status::Error(StatusCode::kInvalidInput, "not finite")};
    const Loads<double> L = loads ? (*loads)(s.t[i]) : constant;
    const double* th = s.theta + 2 * i;
    const double* om = s.omega + 2 * i;
    const double* al = s.alpha + 2 * i;
    Evaluation<double> ev;
    const Status st =
        inverse_dynamics(p, L, th[0], th[1], om[0], om[1], al[0], al[1], nullptr, eval, &ev);
    if (!st.ok()) return {i, st};
    out.M[2 * i] = ev.M1;
    out.M[2 * i + 1] = ev.M2;
    std::copy(ev.N.begin(), ev.N.end(), out.N + 5 * i);
    std::copy(ev.Mf.begin(), ev.Mf.end(), out.Mf + 5 * i);
  }
  return {};
}

// the ValueError of a bad array argument: what was expected and what came
[[noreturn]] void bad_array(const char* name, py::ssize_t n, int cols, const std::string& got) {
  const std::string shape = cols > 0 ? "(N, " + std::to_string(cols) + ")" : "(N,)";
  throw InputError(name, "(argument)",
                   "expected a float64 array of shape " + shape +
                       (n >= 0 ? " with N = " + std::to_string(n) + " (the rows of theta)"
                               : std::string()) +
                       ", got " + got);
}

// `name` as a C-contiguous float64 array of shape (n, cols) (cols 0: shape (n,)); n < 0 takes
// the array's. Raises ValueError naming the argument and the expected shape.
py::array_t<double, py::array::c_style> checked_array(const py::object& obj, const char* name,
                                                      py::ssize_t n, int cols) {
  if (!py::isinstance<py::array>(obj)) {
    bad_array(name, n, cols, py::str(obj.get_type().attr("__name__")));
  }
  const py::array& a = static_cast<const py::array&>(obj);
  if (!a.dtype().is(py::dtype::of<double>())) {
    bad_array(name, n, cols, "dtype " + std::string(py::str(a.dtype())));
  }
  const bool ok = a.ndim() == (cols > 0 ? 2 : 1) && (n < 0 || a.shape(0) == n) &&
                  (cols == 0 || a.shape(1) == cols);
  if (!ok) bad_array(name, n, cols, "shape " + std::string(py::str(obj.attr("shape"))));
  using Contiguous = py::array_t<double, py::array::c_style>;
  if (Contiguous::check_(a)) return py::reinterpret_borrow<Contiguous>(a);  // no copy, no call
  return Contiguous::ensure(a);
}

// the error of a failed state, in the command line's words (cmd_inverse: a pose that cannot
// assemble or is too close to a singular configuration is bad input)
[[noreturn]] void raise_failure(const PyScene& s, const States& in, const Failure& f) {
  const std::string row = "row " + std::to_string(f.index);
  const double th1 = in.theta[2 * f.index], th2 = in.theta[2 * f.index + 1];
  if (!finite_state(in, f.index)) {
    for (const auto& [name, a] : {std::pair{"theta", in.theta}, {"omega", in.omega},
                                   {"alpha", in.alpha}}) {
      if (!std::isfinite(a[2 * f.index]) || !std::isfinite(a[2 * f.index + 1])) {
        throw InputError(name, row, "expected finite numbers");
      }
    }
    throw InputError("t", row, "expected a finite number");
  }
  const double sine = io::coupler_sine(s.scene.params, th1, th2);
  if (sine < s.scene.options.singular_margin) {
    throw InputError("theta", row,
                     std::string(sine < 0 ? "the mechanism cannot assemble"
                                          : "too close to a singular configuration") +
                         " at theta1 = " + io::format_double(th1) +
                         ", theta2 = " + io::format_double(th2));
  }
  throw NumericalError(s.scene.path, "inverse dynamics", row + ": " + f.status.message);
}


// all states on `threads` threads (0: the machine's cores); the first failure by index
Failure inverse_all(const PyScene& s, const States& in, const Outputs& out, int threads) {
  // the rest rule of `fivebar inverse` (docs/hold.md): the thresholds for computed rates, or
  // the scene's where it sets them
  EvalOptions eval = with_rest(EvalOptions{}, s.scene.rest_thresholds({}));
  eval.singular_margin = s.scene.options.singular_margin;
  const bool fixed = s.loads_constant;
  const Loads<double>& constant = s.constant_loads;
  // (hardware_concurrency reads /sys: only asked when there is work for two threads)
  size_t workers = std::max<size_t>(1, in.n / kMinStatesPerThread);
  if (workers > 1) {
    workers = std::min<size_t>(
        workers, threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency()));
  }
  if (workers == 1) {
    return inverse_range(s.scene.params, fixed ? nullptr : s.loads.get(), constant, eval, in, out,
                         0, in.n);
  }
  std::vector<Failure> failures(workers);
  std::vector<std::thread> pool;
  for (size_t w = 0; w < workers; ++w) {
    pool.emplace_back([&, w] {
      const size_t begin = in.n * w / workers, end = in.n * (w + 1) / workers;
      std::unique_ptr<io::LoadExpressions> own;  // parsers of this thread
      if (!fixed) own = std::make_unique<io::LoadExpressions>(*s.loads);
      failures[w] = inverse_range(s.scene.params, own.get(), constant, eval, in, out, begin, end);
    });
  }
  for (std::thread& t : pool) t.join();
  for (const Failure& f : failures) {
    if (f.index != kNone) return f;  // ranges are in index order
  }
  return {};
}

// raises ValueError when the scene's loads depend on t and `t` is None
void require_times(const PyScene& s, const py::object& t) {
  if (!t.is_none() || s.loads_constant) return;
  throw InputError("t", "(argument)",
                   "the loads of " + s.scene.path +
                       " depend on t (loads.M3 or loads.F): pass t, a float64 array of shape (N,)");
}

// `name` of a one-crank mechanism: shape (N,) or (N, 1), as a contiguous (N,) array
py::array_t<double, py::array::c_style> crank_array(const py::object& obj, const char* name,
                                                    py::ssize_t n) {
  const bool column = py::isinstance<py::array>(obj) && py::array(obj).ndim() == 2;
  if (!column) return checked_array(obj, name, n, 0);
  const auto a = checked_array(obj, name, n, 1);
  return py::array_t<double, py::array::c_style>::ensure(a.attr("reshape")(a.shape(0)));
}

// The four-bar (one crank): sim::inverse_rows over the states, its rest rule included. Returns
// M (N, 1), N and Mf (N, 4) of joints O, B, C, D0.
py::dict inverse_four_bar(const PyScene& s, const py::object& theta, const py::object& omega,
                          const py::object& alpha, const py::object& t) {
  const auto th = crank_array(theta, "theta", -1);
  const py::ssize_t n = th.shape(0);
  const auto om = crank_array(omega, "omega", n), al = crank_array(alpha, "alpha", n);
  require_times(s, t);
  const auto times = t.is_none() ? py::array_t<double, py::array::c_style>()
                                 : checked_array(t, "t", n, 0);
  std::vector<sim::Row> motion(static_cast<size_t>(n)), rows;
  for (py::ssize_t i = 0; i < n; ++i) {
    sim::Row& r = motion[size_t(i)];
    r.t = t.is_none() ? 0.0 : times.at(i);
    r.theta[0] = th.at(i), r.omega[0] = om.at(i), r.alpha[0] = al.at(i);
    for (const auto& [name, v] : {std::pair{"theta", r.theta[0]}, {"omega", r.omega[0]},
                                  {"alpha", r.alpha[0]}, {"t", r.t}}) {
      if (!std::isfinite(v)) {
        throw InputError(name, "row " + std::to_string(i), "expected a finite number");
      }
    }
  }
  Status st;
  {
    py::gil_scoped_release release;
    st = sim::inverse_rows(s.scene.four_bar, s.loads->four_bar_function(), motion, &rows,
                           s.scene.rest_thresholds({}));
  }
  if (!st.ok()) throw NumericalError(s.scene.path, "inverse dynamics", st.message);
  py::array_t<double> M({n, py::ssize_t(1)}), N({n, py::ssize_t(4)}), Mf({n, py::ssize_t(4)});
  for (py::ssize_t i = 0; i < n; ++i) {
    const sim::Row& r = rows[size_t(i)];
    M.mutable_at(i, 0) = r.M1;
    for (int k = 0; k < 4; ++k) N.mutable_at(i, k) = r.N[k], Mf.mutable_at(i, k) = r.Mf[k];
  }
  py::dict d;
  d["M"] = std::move(M);
  d["N"] = std::move(N);
  d["Mf"] = std::move(Mf);
  return d;
}

py::dict inverse(const PyScene& s, const py::object& theta, const py::object& omega,
                 const py::object& alpha, const py::object& t, int threads) {
  if (s.scene.type == io::MechanismType::kFourBar) {
    return inverse_four_bar(s, theta, omega, alpha, t);
  }
  const auto th = checked_array(theta, "theta", -1, 2);
  const py::ssize_t n = th.shape(0);
  const auto om = checked_array(omega, "omega", n, 2);
  const auto al = checked_array(alpha, "alpha", n, 2);
  py::array_t<double, py::array::c_style> times;
  if (!t.is_none()) {
    times = checked_array(t, "t", n, 0);
  } else {
    require_times(s, t);
  }
  const States in{th.data(), om.data(), al.data(), t.is_none() ? nullptr : times.data(),
                  static_cast<size_t>(n)};
  py::array_t<double> M({n, py::ssize_t(2)}), N({n, py::ssize_t(5)}), Mf({n, py::ssize_t(5)});
  const Outputs out{M.mutable_data(), N.mutable_data(), Mf.mutable_data()};
  Failure failure;
  {
    py::gil_scoped_release release;
    failure = inverse_all(s, in, out, threads);
  }
  if (failure.index != kNone) raise_failure(s, in, failure);
  py::dict d;
  d["M"] = std::move(M);
  d["N"] = std::move(N);
  d["Mf"] = std::move(Mf);
  return d;
}

// seconds per call of the C++ work behind a one-state fivebar.inverse (inverse_range on one
// state), the fastest of `repeats` batches of `calls` calls: the baseline of the overhead figure.
// `cpu_time`: process CPU time (std::clock) instead of wall time.
double time_inverse_cpp(const PyScene& s, std::array<double, 6> state, int calls, int repeats,
                        bool cpu_time) {
  py::gil_scoped_release release;
  s.require_five_bar("_time_inverse_cpp");
  if (!s.loads_constant) throw InputError("scene", "loads", "must not depend on t");
  const Loads<double>& constant = s.constant_loads;
  EvalOptions eval;
  eval.singular_margin = s.scene.options.singular_margin;
  const double theta[2] = {state[0], state[1]}, omega[2] = {state[2], state[3]},
               alpha[2] = {state[4], state[5]};
  double M[kActuators], N[kJoints], Mf[kJoints];
  const States in{theta, omega, alpha, nullptr, 1};
  const Outputs out{M, N, Mf};
  const auto now = [cpu_time] {
    return cpu_time ? double(std::clock()) / CLOCKS_PER_SEC
                    : std::chrono::duration<double>(
                          std::chrono::steady_clock::now().time_since_epoch())
                          .count();
  };
  std::vector<double> times;
  for (int r = 0; r < repeats; ++r) {
    const double start = now();
    for (int c = 0; c < calls; ++c) {
      inverse_range(s.scene.params, nullptr, constant, eval, in, out, 0, 1);
      asm volatile("" : : "r"(M) : "memory");  // keep the calls
    }
    times.push_back((now() - start) / calls);
  }
  return *std::min_element(times.begin(), times.end());
}

}  // namespace

void bind_inverse(py::module_& m) {
  m.def("inverse", &inverse, py::arg("scene"), py::arg("theta"), py::arg("omega"),
        py::arg("alpha"), py::arg("t") = py::none(), py::arg("threads") = 0,
        "Inverse dynamics with friction of N states: theta, omega, alpha are float64 arrays of "
        "shape (N, 2) (cranks 1 and 2). Returns {'M': (N, 2) driving torques [N m], 'N': (N, 5) "
        "joint reaction magnitudes [N], 'Mf': (N, 5) friction torques [N m]} (joints O, B, C, D, "
        "D0). A four-bar scene takes the crank's theta, omega, alpha of shape (N,) or (N, 1) and "
        "returns M (N, 1), N and Mf (N, 4) (joints O, B, C, D0). t, shape (N,), gives the time "
        "of each state for loads that depend on t. Runs with the GIL released, on `threads` "
        "threads (0: all cores) when N is large (five-bars).");
  m.def("_time_inverse_cpp", &time_inverse_cpp, py::arg("scene"), py::arg("state"),
        py::arg("calls") = 20000, py::arg("repeats") = 7, py::arg("cpu_time") = false,
        "Benchmark helper: seconds per call of the C++ work of a one-state inverse (state = "
        "(theta1, theta2, omega1, omega2, alpha1, alpha2)).");
}

}  // namespace fivebar::python
