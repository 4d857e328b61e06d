// Torque-driven excitation design (`excite --family torque`): the motor torques are
// sums of tones clipped at the torque limit, the motion is the mechanism's free response to them
// (the simulator), and a seeded evolution strategy chooses the tones for information. The
// built-in multi-sine of synth-log is one member of the family (multisine_tones) and the first
// start, so the search's best is never worse than it on the design's objective. The search
// simulates at loosened settings (search_settings); its finalists are evaluated again at the
// scene's (finish_torque_design).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "fivebar/identification/excitation.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::identification {

/// Motor torques M_j(t) = clip(b_j + sum_k a_jk sin(2 pi f_jk t + phi_jk), +-limit), j = 1, 2.
/// Variables per motor: b, a_1..a_K, f_1..f_K [Hz], phi_1..phi_K [rad]; motor 1's first.
class ToneTorques {
 public:
  ToneTorques(int tones, double limit) : k_(tones), limit_(limit) {}
  int tones() const { return k_; }
  double limit() const { return limit_; }
  int per_motor() const { return 1 + 3 * k_; }
  int num_variables() const { return 2 * per_motor(); }
  /// The unclipped sum of motor j (0, 1) at t.
  double raw(const std::vector<double>& x, int j, double t) const;
  /// The applied torque: raw clipped at +-limit.
  double torque(const std::vector<double>& x, int j, double t) const;
  /// The scene's loads with M1, M2 replaced by the torques of x.
  sim::LoadFunction loads(const std::vector<double>& x, const sim::LoadFunction& scene) const;
  /// A typical step of each variable for the search (torques: limit / 4, frequencies 0.3 Hz,
  /// phases 1 rad).
  std::vector<double> steps() const;
  /// Keeps biases in [-limit, limit], amplitudes in [0, 4 limit], frequencies in [0.02, 8] Hz.
  void bound(std::vector<double>* x) const;

 private:
  int k_;
  double limit_;
};

/// The variables of synth-log's built-in multi-sine (4 tones per motor, no clip reached at its
/// 13.4 N m peak): multisine_loads is ToneTorques(4, infinity) at these.
std::vector<double> multisine_tones();

/// How the multi-sine is fitted to a mechanism and a torque limit (fit_multisine).
struct MultisineFitOptions {
  double torque_limit = std::numeric_limits<double>::infinity();  ///< |M1|, |M2| at most [N m]
  double duration = 10;         ///< the motion that must run [s]
  /// least |sin(theta4 - theta3)| along it (the scene's if larger)
  double singular_margin = kMotionSingularMargin;
  sim::Options sim;             ///< the scene's solver settings (duration, output step overridden)
};

/// The multi-sine's tones as fitted to one mechanism (multisine_tones' layout, 4 tones).
struct FittedMultisine {
  std::vector<double> tones;
  double factor = 1;          ///< the amplitudes' scale against multisine_tones
  bool holding_bias = false;  ///< biases replaced by the start pose's holding torques
  Status status;              ///< not ok: no scale runs the duration (the last failure)
};

/// The one rule that fits synth-log's multi-sine (tuned on the paper scene) to another mechanism:
/// every tone and bias times one factor, at most 1 and at most the torque limit over the tones'
/// peak on [0, duration] (so the paper scene's multi-sine is unchanged); then the free motion from
/// `initial` must run the duration at the singularity margin. If it does not (the mechanism's
/// inertia and loads make the tones too strong for its geometry), the same factor is tried with
/// the biases replaced by the torques that hold the start pose (a bias that no load balances
/// spins the cranks), then both with the factor halved, at most kMultisineHalvings times.
FittedMultisine fit_multisine(const Params<double>& scene, const sim::LoadFunction& loads,
                              const sim::Initial& initial, const MultisineFitOptions& options);

/// Halvings of the factor fit_multisine tries before it gives up (1/256 of the first factor).
inline constexpr int kMultisineHalvings = 8;

/// `x` with `tones` tones per motor: the extra tones at zero amplitude (frequencies spread above
/// the given ones), or the first `tones` ones.
std::vector<double> resize_tones(const std::vector<double>& x, int from, int tones);

/// The search's default tolerance (TorqueDesignOptions::search_tolerance)
inline constexpr double kSearchTolerance = 1e-6;
/// The search's best candidates evaluated again at the scene's settings by default
/// (TorqueDesignOptions::finalists)
inline constexpr int kFinalists = 2;
/// The search keeps this many times `finalists` of its best candidates: the spares are evaluated
/// when none of the first runs and meets the constraints at the scene's settings
inline constexpr int kFinalistSpares = 3;

/// The settings of the search's simulations (`tolerance` 0: `scene` unchanged): `scene` with rtol
/// and atol loosened to at least `tolerance`, and for a friction law without internal states
/// the explicit arkode_erk45 (a tone-driven motion switches a joint's slip direction some 20
/// times a second: the explicit steps go on at full size after each switch, where Adams
/// restarts at order 1; LuGre's stiff bristles keep the scene's method).
sim::Options search_settings(const sim::Options& scene, double tolerance, FrictionLaw law);

struct TorqueDesignOptions {
  ExcitationOptions excitation;  ///< limits, noise, criterion, groups, duration, design_samples
  int tones = 4;
  int max_evaluations = 160;   ///< simulations in the search (the first is the start)
  int offspring = 4;           ///< candidates per generation (evaluated two at a time)
  double step = 0.3;           ///< initial mutation, in units of ToneTorques::steps()
  std::uint64_t seed = 1;
  sim::Options sim;            ///< the scene's solver settings (duration, output step overridden)
  /// rtol and atol of the search's simulations where the scene's are tighter, and their method
  /// (search_settings; 0: the scene's settings): the search only ranks candidates, its
  /// finalists are evaluated again at the scene's settings (finish_torque_design)
  double search_tolerance = kSearchTolerance;
  /// the search's best candidates finish_torque_design evaluates (at least 1; kFinalistSpares
  /// times as many are kept)
  int finalists = kFinalists;
};

/// One motion of the family on a grid: the simulated motion with its Fisher information,
/// torques by inverse dynamics, reversal counts, coupler sine and angle ranges (`report`), the
/// applied torques, and the design's objective (the criterion; NaN when the run failed).
struct TorqueCandidate {
  std::vector<double> x;
  Status status;
  double objective = 0;
  bool feasible = false;
  ExcitationReport report;
  std::vector<double> tau1, tau2;  ///< applied torques
  double peak_applied = 0;         ///< max |tau1|, |tau2|
};

/// Simulates the tones of x from rest at `start` over the duration with output every `step`
/// seconds, evaluates the design's criterion on that grid and its constraints (reversals >=
/// min_reversals, coupler sine >= singular margin (the run stops there), angle ranges).
TorqueCandidate evaluate_tones(const Params<double>& scene, const sim::LoadFunction& scene_loads,
                               std::array<double, 2> start, const TorqueDesignOptions& options,
                               const std::vector<double>& x, double step);

struct TorqueDesignResult {
  TorqueCandidate best;
  /// the candidate of the lowest objective whatever its constraints (a run that failed aside):
  /// when it is not `best`, what the constraints cost the design
  TorqueCandidate best_unconstrained;
  int best_start = 0;  ///< the start the search went on from
  std::vector<double> start_objectives;
  std::vector<bool> start_feasible;
  int evaluations = 0, improvements = 0;
  /// the tones of the search's best candidates that ran, best first (`best`'s the first): at
  /// most kFinalistSpares * options.finalists of them, ranked as `best` is
  std::vector<std::vector<double>> finalists;
  std::vector<double> finalist_objectives;  ///< their objectives in the search
};

/// The design the search's finalists give, at the scene's settings.
struct FinishedTorqueDesign {
  /// the chosen finalist on the log's grid (1 / rate_hz) at options.sim, with the std identify
  /// would report (predict_identified_std) in its report when `predicted` is ok
  TorqueCandidate design;
  Status predicted;
  int finalist = 0;   ///< its rank in the search (0: the search's best)
  int evaluated = 0;  ///< finalists evaluated at the scene's settings
};

/// Simulates the first options.finalists finalists again at options.sim (the scene's settings:
/// the search's tolerance only ranked them) on the log's grid, two at a time, and predicts the
/// std identify would report for a log along each (torque and angle noise); while none of those
/// evaluated runs, meets the constraints and has a prediction (a motion near a constraint may
/// cross it at the scene's tolerance), the next options.finalists, until none is left. The
/// chosen one: a run that failed last,
/// then the constraints as in the search (feasible first, among infeasible the smaller miss),
/// then a prediction that failed last, then the lowest worst relative std with the criterion
/// kWorstStd (the std the design is judged by), else the lowest objective; the search's rank
/// breaks ties. Deterministic whatever the threads.
FinishedTorqueDesign finish_torque_design(const Params<double>& scene,
                                          const sim::LoadFunction& scene_loads,
                                          std::array<double, 2> start,
                                          const TorqueDesignOptions& options,
                                          const std::vector<std::vector<double>>& finalists);

/// The starts of the search from x0 (the multi-sine's tones): x0 itself first, then x0 with its
/// amplitudes times 1, 3, 10 (clipped at the limit: towards bang-bang torques) and its
/// frequencies times 1, 0.7, 0.5 (longer spins between reversals): 9 starts.
std::vector<std::vector<double>> tone_starts(const ToneTorques& tones, const std::vector<double>& x0);

/// The search: every start is evaluated, then an elitist (1 + lambda) evolution strategy goes on
/// from the best one (normal mutations scaled by steps(), step size grown by 1.5 after an
/// improving generation and shrunk by 0.8 otherwise), seeded, on the design grid
/// (design_samples over the duration). Deterministic for a seed whatever the threads. The best
/// feasible candidate wins (feasible before infeasible; among infeasible, the smaller miss).
/// Its simulations use search_settings(options.sim, options.search_tolerance).
TorqueDesignResult design_torque_excitation(const Params<double>& scene,
                                            const sim::LoadFunction& scene_loads,
                                            std::array<double, 2> start,
                                            const TorqueDesignOptions& options,
                                            const std::vector<std::vector<double>>& starts);

}  // namespace fivebar::identification
