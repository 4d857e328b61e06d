#include "fivebar/trajectory/path_search.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <unordered_map>

#include "fivebar/model/format.h"
#include "fivebar/model/kinematics.h"

namespace fivebar::trajectory {
namespace {

using Pose2 = std::array<double, 2>;

// why a pose is not usable: the closure fails with the couplers stretched (|BD| > l3 + l4) or
// folded (|BD| < |l3 - l4|)
enum class Why { kUsable, kStretched, kFolded };

// |sin(th4 - th3)| by the model's closure, -1 when it cannot close (and why)
double pose_sine(const Params<double>& params, double th1, double th2, Why* why = nullptr) {
  Kinematics<double> k;
  if (!solve_kinematics(params, th1, th2, &k, 0.0, false).ok()) {
    if (why) {
      const double reach = params.links[2].length + params.links[3].length;
      *why = (k.D - k.B).norm() >= reach ? Why::kStretched : Why::kFolded;
    }
    return -1.0;
  }
  if (why) *why = Why::kUsable;
  return std::abs(k.sin43);
}

double distance(const Pose2& a, const Pose2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

// the grid: nodes (i, j) at lo + (i h0, j h1), the coupler sine of each computed once
struct Grid {
  std::array<double, 2> lo{}, h{};
  std::array<int, 2> n{};
  std::vector<double> sine;
  std::vector<Why> why;

  int size() const { return n[0] * n[1]; }
  Pose2 pose(int id) const { return {lo[0] + (id / n[1]) * h[0], lo[1] + (id % n[1]) * h[1]}; }
  int id(int i, int j) const { return i * n[1] + j; }
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < n[0] && j < n[1]; }
};

// at most this many poses in a grid (memory and time stay bounded for goals many turns away:
// the step grows instead)
constexpr double kMaxGridPoses = 1e6;

Grid make_grid(const Params<double>& params, const Pose2& start, const Pose2& goal,
               const PathSearchOptions& o) {
  Grid g;
  std::array<double, 2> span{};
  for (int j = 0; j < kDof; ++j) span[j] = std::abs(goal[j] - start[j]) + 2 * o.reach;
  const double step = std::max(o.step, std::sqrt(span[0] * span[1] / kMaxGridPoses));
  for (int j = 0; j < kDof; ++j) {
    g.lo[j] = std::min(start[j], goal[j]) - o.reach;
    const double hi = std::max(start[j], goal[j]) + o.reach;
    g.n[j] = std::max(2, static_cast<int>(std::ceil((hi - g.lo[j]) / step)) + 1);
    g.h[j] = (hi - g.lo[j]) / (g.n[j] - 1);
  }
  g.sine.resize(g.size());
  g.why.resize(g.size());
  for (int id = 0; id < g.size(); ++id) {
    const Pose2 p = g.pose(id);
    g.sine[id] = pose_sine(params, p[0], p[1], &g.why[id]);
  }
  return g;
}

// grid nodes near pose p (two cells around it) joined to p by a clear segment, with distances
std::vector<std::pair<int, double>> attach(const Params<double>& params, const Grid& g,
                                           const Pose2& p, double margin, double spacing) {
  std::vector<std::pair<int, double>> out;
  const int i0 = static_cast<int>(std::floor((p[0] - g.lo[0]) / g.h[0]));
  const int j0 = static_cast<int>(std::floor((p[1] - g.lo[1]) / g.h[1]));
  for (int i = i0 - 1; i <= i0 + 2; ++i) {
    for (int j = j0 - 1; j <= j0 + 2; ++j) {
      if (!g.inside(i, j) || g.sine[g.id(i, j)] < margin) continue;
      const Pose2 q = g.pose(g.id(i, j));
      if (segment_clear(params, p, q, margin, spacing)) out.push_back({g.id(i, j), distance(p, q)});
    }
  }
  return out;
}

// A* from start to goal through grid nodes with sine >= margin; the waypoints (start and goal
// included), or empty. `seen` (optional) receives the nodes reached from the start.
std::vector<Pose2> astar(const Params<double>& params, const Grid& g, const Pose2& start,
                         const Pose2& goal, double margin, std::vector<char>* seen = nullptr) {
  const double spacing = 0.25 * std::min(g.h[0], g.h[1]);
  const int N = g.size(), kStart = N, kGoal = N + 1;
  std::unordered_map<int, double> to_goal;
  for (const auto& [id, d] : attach(params, g, goal, margin, spacing)) to_goal[id] = d;
  std::vector<double> cost(N + 2, std::numeric_limits<double>::infinity());
  std::vector<int> parent(N + 2, -1);
  std::vector<char> closed(N + 2, 0);
  using Item = std::pair<double, int>;  // (cost + heuristic, node)
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  auto pose = [&](int v) { return v == kStart ? start : (v == kGoal ? goal : g.pose(v)); };
  auto relax = [&](int from, int to, double d) {
    if (cost[from] + d < cost[to]) {
      cost[to] = cost[from] + d;
      parent[to] = from;
      open.push({cost[to] + distance(pose(to), goal), to});
    }
  };
  cost[kStart] = 0;
  if (segment_clear(params, start, goal, margin, spacing)) relax(kStart, kGoal, distance(start, goal));
  for (const auto& [id, d] : attach(params, g, start, margin, spacing)) relax(kStart, id, d);
  while (!open.empty()) {
    const int v = open.top().second;
    open.pop();
    if (closed[v]) continue;
    closed[v] = 1;
    if (v == kGoal) break;
    if (seen) (*seen)[v] = 1;
    if (const auto it = to_goal.find(v); it != to_goal.end()) relax(v, kGoal, it->second);
    const int i = v / g.n[1], j = v % g.n[1];
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        const int u = g.id(i + di, j + dj);
        if ((di == 0 && dj == 0) || !g.inside(i + di, j + dj) || closed[u] || g.sine[u] < margin) {
          continue;
        }
        const Pose2 a = g.pose(v), b = g.pose(u);
        const Pose2 mid = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])};
        if (pose_sine(params, mid[0], mid[1]) < margin) continue;
        relax(v, u, distance(a, b));
      }
    }
  }
  std::vector<Pose2> path;
  if (parent[kGoal] < 0) return path;
  for (int v = kGoal; v >= 0; v = parent[v]) path.push_back(pose(v));
  std::reverse(path.begin(), path.end());
  return path;
}

// drops via points: from each kept point, straight on to the farthest point still in view, at
// most kLookAhead grid moves on (each test samples the whole segment: unbounded, a long straight
// path would cost its length squared)
constexpr size_t kLookAhead = 64;

std::vector<Pose2> shorten(const Params<double>& params, const std::vector<Pose2>& path,
                           double margin, double spacing) {
  std::vector<Pose2> out = {path.front()};
  size_t i = 0;
  while (i + 1 < path.size()) {
    size_t j = i + 1;
    while (j + 1 < path.size() && j + 1 - i <= kLookAhead &&
           segment_clear(params, path[i], path[j + 1], margin, spacing)) {
      ++j;
    }
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

// why no path joins start and goal: the poses that bound the start's region
std::string why_unreachable(const Params<double>& params, const Grid& g, const Pose2& start,
                            const Pose2& goal, double margin) {
  const double eps = 1e-9;  // any pose that closes
  std::vector<char> seen(g.size() + 2, 0);
  if (!astar(params, g, start, goal, eps, &seen).empty()) {
    return "every path passes nearer than the margin " + format_significant(margin, 4) +
           " to a singular pose (|sin(theta4 - theta3)| < margin)";
  }
  int stretched = 0, folded = 0;
  std::array<bool, 2> edge = {false, false};
  for (int v = 0; v < g.size(); ++v) {
    if (!seen[v]) continue;
    const int i = v / g.n[1], j = v % g.n[1];
    edge[0] = edge[0] || i == 0 || i == g.n[0] - 1;
    edge[1] = edge[1] || j == 0 || j == g.n[1] - 1;
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        if (!g.inside(i + di, j + dj)) continue;
        const int u = g.id(i + di, j + dj);
        if (g.sine[u] >= 0) continue;
        (g.why[u] == Why::kStretched ? stretched : folded) += 1;
      }
    }
  }
  const double l3 = params.links[2].length, l4 = params.links[3].length;
  std::string curve;
  if (stretched > 0) {
    curve = "couplers stretched, |BD| = l3 + l4 = " + format_significant(l3 + l4, 4) + " m";
  }
  if (folded > 0) {
    curve +=
        (curve.empty() ? "" : "; ") +
        ("couplers folded, |BD| = |l3 - l4| = " + format_significant(std::abs(l3 - l4), 4) + " m");
  }
  std::string why = "the goal lies across the singular curve (" + curve +
                    ") that bounds the start's region of the workspace in the " +
                    (params.assembly == kElbowUp ? "elbow_up" : "elbow_down") + " assembly";
  if (edge[0] || edge[1]) {
    why += std::string("; that region reaches the box's edge in ") +
           (edge[0] && edge[1] ? "theta1 and theta2" : (edge[0] ? "theta1" : "theta2")) +
           " (paths turning further were not searched)";
  }
  return why;
}

}  // namespace

double coupler_sine(const Params<double>& params, double th1, double th2) {
  return pose_sine(params, th1, th2);
}

bool segment_clear(const Params<double>& params, const Pose2& a, const Pose2& b, double margin,
                   double spacing) {
  const int n = std::max(1, static_cast<int>(std::ceil(distance(a, b) / spacing)));
  for (int s = 0; s <= n; ++s) {
    const double u = static_cast<double>(s) / n;
    if (pose_sine(params, a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])) < margin) {
      return false;
    }
  }
  return true;
}

JointPath find_joint_path(const Params<double>& params, const Pose2& start, const Pose2& goal,
                          const PathSearchOptions& o) {
  JointPath out;
  const Grid g = make_grid(params, start, goal, o);
  out.grid_poses = g.size();
  const double margin = std::max(o.margin, 1e-9);
  for (double m : {margin + o.cushion, margin}) {
    out.feasible_poses = static_cast<int>(
        std::count_if(g.sine.begin(), g.sine.end(), [&](double s) { return s >= m; }));
    const std::vector<Pose2> raw = astar(params, g, start, goal, m);
    if (raw.empty()) continue;
    out.waypoints = shorten(params, raw, m, 0.25 * std::min(g.h[0], g.h[1]));
    out.margin = m;
    for (size_t i = 1; i < out.waypoints.size(); ++i) {
      out.length += distance(out.waypoints[i - 1], out.waypoints[i]);
    }
    return out;
  }
  out.status = "unreachable";
  // the same goal pose whole turns away, nearest to the start: a hint when it can be reached
  const Pose2 turned = {start[0] + std::remainder(goal[0] - start[0], 2 * M_PI),
                        start[1] + std::remainder(goal[1] - start[1], 2 * M_PI)};
  std::string hint;
  if (distance(turned, goal) > 1e-9 && distance(turned, start) <= 1e-9) {
    hint = "; the goal is the start pose itself, whole turns away";
  } else if (distance(turned, goal) > 1e-9 &&
             !astar(params, make_grid(params, start, turned, o), start, turned, margin).empty()) {
    hint = "; the same pose at theta = (" + format_significant(turned[0], 4) + ", " +
           format_significant(turned[1], 4) +
           ") rad (whole turns away) can be reached: give the goal so";
  }
  out.message =
      "no path of poses with |sin(theta4 - theta3)| >= " + format_significant(o.margin, 4) +
      " joins start (" + format_significant(start[0], 4) + ", " + format_significant(start[1], 4) +
      ") and goal (" + format_significant(goal[0], 4) + ", " + format_significant(goal[1], 4) +
      ") rad within theta1 in [" + format_significant(g.lo[0], 4) + ", " +
      format_significant(g.lo[0] + (g.n[0] - 1) * g.h[0], 4) + "], theta2 in [" +
      format_significant(g.lo[1], 4) + ", " +
      format_significant(g.lo[1] + (g.n[1] - 1) * g.h[1], 4) + "] (grid step " +
      format_significant(g.h[0], 4) +
      " rad): " + why_unreachable(params, g, start, goal, o.margin) + hint;
  return out;
}

std::vector<double> follow_path(const RestToRest& motion, const JointPath& path) {
  const std::vector<Pose2>& w = path.waypoints;
  std::vector<double> at(w.size(), 0.0);  // arc length at each waypoint
  for (size_t i = 1; i < w.size(); ++i) at[i] = at[i - 1] + distance(w[i - 1], w[i]);
  const double total = at.back();
  return motion.fit([&](double t) -> Pose2 {
    const double s = total * minimum_jerk_blend(t / motion.duration())[0];
    const size_t i = std::min<size_t>(
        w.size() - 2, std::upper_bound(at.begin(), at.end(), s) - at.begin() - 1);
    const double len = at[i + 1] - at[i];
    const double u = len > 0 ? std::clamp((s - at[i]) / len, 0.0, 1.0) : 0.0;
    return {w[i][0] + u * (w[i + 1][0] - w[i][0]), w[i][1] + u * (w[i + 1][1] - w[i][1])};
  });
}

double min_coupler_sine(const Params<double>& params, const RestToRest& motion,
                        const std::vector<double>& x, int points) {
  double worst = 1.0;
  points = std::max(points, 2);
  for (int i = 0; i < points; ++i) {
    const auto s = motion.state(x.data(), motion.duration() * i / (points - 1));
    const double sine = pose_sine(params, s[0][0], s[0][1]);
    if (sine < 0) return -1.0;
    worst = std::min(worst, sine);
  }
  return worst;
}

}  // namespace fivebar::trajectory
