// The frictionless paper scene in MuJoCo beside fivebar, in one run: error against
// datasets/reference/paper_frictionless.csv over the first second and wall time.
//   build-peers/tests/bench/peers/bench_peers_mujoco
// Model: an MJCF string built here: four bodies on hinges about z (gravity along -y), the loop
// closed by an equality `connect` at C, inertias set exactly by `inertial`, no geoms (no contacts).
// The bodies are placed in the assembled start pose, so qpos = 0 is the start and `connect` takes
// its second anchor from that pose. Loads are applied by mjcb_control, which MuJoCo calls at every
// right-hand-side evaluation (every RK4 stage), as qfrc_applied: M1, M2 on the crank hinges, M3
// and F at P through mj_applyFT.
#include <mujoco/mujoco.h>

#include <cstdio>
#include <string>

#include "peers_common.h"

namespace fivebar::peers {
namespace {

/// Ids the control callback needs (mjcb_control is a plain function pointer).
struct Ids {
  int link3 = -1, dof_o = -1, dof_d0 = -1;
  int qpos[4] = {-1, -1, -1, -1};  ///< hinge O, D0, B, D
  double lp = 0;
} g_ids;

/// Loads at d->time, as generalized forces (model.md, M_d).
void apply_loads(const mjModel* m, mjData* d) {
  const Loads<double> L = paper_loads(d->time);
  mju_zero(d->qfrc_applied, m->nv);
  d->qfrc_applied[g_ids.dof_o] += L.M1;
  d->qfrc_applied[g_ids.dof_d0] += L.M2;
  // link 3's body frame: origin at B, x axis along B->C (xmat is row-major)
  const mjtNum* R = d->xmat + 9 * g_ids.link3;
  const mjtNum* B = d->xpos + 3 * g_ids.link3;
  const double c = std::cos(L.F_angle), s = std::sin(L.F_angle);
  mjtNum force[3] = {L.F * (c * R[0] + s * R[1]), L.F * (c * R[3] + s * R[4]), 0};
  mjtNum torque[3] = {0, 0, L.M3};
  mjtNum P[3] = {B[0] + g_ids.lp * R[0], B[1] + g_ids.lp * R[3], B[2] + g_ids.lp * R[6]};
  mj_applyFT(m, d, force, torque, P, g_ids.link3, d->qfrc_applied);
}

/// The MJCF of the mechanism in its assembled start pose.
std::string mjcf() {
  const Params<double> p = frictionless_params();
  const std::array<double, 4> th = initial_angles();
  auto inertial = [](const Link<double>& k) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "<inertial pos='%.17g %.17g 0' mass='%.17g' diaginertia='%.17g %.17g %.17g'/>",
                  k.com_offset * std::cos(k.com_angle), k.com_offset * std::sin(k.com_angle),
                  k.mass, k.inertia, k.inertia, k.inertia);
    return std::string(buf);
  };
  auto num = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  std::string x;
  x += "<mujoco model='fivebar'>\n";
  x += "  <compiler angle='radian'/>\n";
  x += "  <option gravity='0 " + num(-p.gravity) + " 0'><flag contact='disable'/></option>\n";
  x += "  <worldbody>\n";
  x += "    <body name='link1' pos='0 0 0' euler='0 0 " + num(th[0]) + "'>\n";
  x += "      <joint name='O' type='hinge' axis='0 0 1'/>" + inertial(p.links[0]) + "\n";
  x += "      <body name='link3' pos='" + num(p.links[0].length) + " 0 0' euler='0 0 " +
       num(th[2] - th[0]) + "'>\n";
  x += "        <joint name='B' type='hinge' axis='0 0 1'/>" + inertial(p.links[2]) + "\n";
  x += "      </body>\n    </body>\n";
  x += "    <body name='link2' pos='" + num(p.ground_length) + " 0 0' euler='0 0 " + num(th[1]) +
       "'>\n";
  x += "      <joint name='D0' type='hinge' axis='0 0 1'/>" + inertial(p.links[1]) + "\n";
  x += "      <body name='link4' pos='" + num(p.links[1].length) + " 0 0' euler='0 0 " +
       num(th[3] - th[1]) + "'>\n";
  x += "        <joint name='D' type='hinge' axis='0 0 1'/>" + inertial(p.links[3]) + "\n";
  x += "      </body>\n    </body>\n";
  x += "  </worldbody>\n";
  x += "  <equality><connect body1='link3' body2='link4' anchor='" + num(p.links[2].length) +
       " 0 0'/></equality>\n";
  x += "</mujoco>\n";
  return x;
}

mjModel* load_model(const std::string& xml) {
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  if (mj_makeEmptyFileVFS(&vfs, "fivebar.xml", static_cast<int>(xml.size())) != 0) {
    throw std::runtime_error("mujoco: cannot make the virtual file");
  }
  std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs.filedata[vfs.nfile - 1]));
  char err[1000] = "";
  mjModel* m = mj_loadXML("fivebar.xml", &vfs, err, sizeof err);
  mj_deleteVFS(&vfs);
  if (!m) throw std::runtime_error(std::string("mujoco: ") + err);
  return m;
}

/// One set of solver settings.
struct Config {
  const char* label;
  int integrator;    ///< mjINT_EULER or mjINT_RK4
  double timestep;   ///< [s], divides 1 ms
  double solref[2];  ///< of the connect constraint
  double solimp[5];
  bool refsafe;      ///< MuJoCo's clamp timeconst >= 2 timestep
  double tolerance;  ///< constraint solver
  int iterations;
};

/// One run of the first second; angles on the 1 ms grid.
Trajectory mujoco_run(mjModel* m, mjData* d, const Config& c) {
  m->opt.integrator = c.integrator;
  m->opt.timestep = c.timestep;
  m->opt.tolerance = c.tolerance;
  m->opt.iterations = c.iterations;
  if (c.refsafe) {
    m->opt.disableflags &= ~mjDSBL_REFSAFE;
  } else {
    m->opt.disableflags |= mjDSBL_REFSAFE;
  }
  for (int i = 0; i < mjNREF; ++i) m->eq_solref[i] = c.solref[i];
  for (int i = 0; i < mjNIMP; ++i) m->eq_solimp[i] = c.solimp[i];
  mj_resetData(m, d);
  const int per_output = static_cast<int>(std::lround(kOutputStep / c.timestep));
  const std::array<double, 4> th0 = initial_angles();
  auto angles = [&] {
    const double q1 = d->qpos[g_ids.qpos[0]], q2 = d->qpos[g_ids.qpos[1]];
    return std::array<double, 4>{th0[0] + q1, th0[1] + q2, th0[2] + q1 + d->qpos[g_ids.qpos[2]],
                                 th0[3] + q2 + d->qpos[g_ids.qpos[3]]};
  };
  Trajectory tr = on_output_grid(
      [&](int) {
        for (int k = 0; k < per_output; ++k) mj_step(m, d);
      },
      angles);
  // MuJoCo resets the state on a diverged acceleration and goes on: report no trajectory instead
  for (int w = 0; w < mjNWARNING; ++w) {
    if (d->warning[w].number > 0) return {};
  }
  return tr;
}

}  // namespace
}  // namespace fivebar::peers

/// The MuJoCo rows: the model's defaults, then ever stiffer constraint settings.
std::vector<fivebar::peers::Measured> mujoco_rows(const fivebar::peers::Trajectory& ref) {
  using namespace fivebar::peers;
  mjModel* m = load_model(mjcf());
  mjData* d = mj_makeData(m);
  g_ids.link3 = mj_name2id(m, mjOBJ_BODY, "link3");
  const char* joints[4] = {"O", "D0", "B", "D"};
  for (int j = 0; j < 4; ++j) {
    const int id = mj_name2id(m, mjOBJ_JOINT, joints[j]);
    g_ids.qpos[j] = m->jnt_qposadr[id];
    if (j == 0) g_ids.dof_o = m->jnt_dofadr[id];
    if (j == 1) g_ids.dof_d0 = m->jnt_dofadr[id];
  }
  g_ids.lp = frictionless_params().point_p;
  mjcb_control = apply_loads;

  // MuJoCo's defaults: solref (0.02, 1), solimp (0.9, 0.95, 0.001, 0.5, 2), tolerance 1e-8
  const double def_ref[2] = {0.02, 1};
  const double def_imp[5] = {0.9, 0.95, 0.001, 0.5, 2};
  const double hard_imp[5] = {0.9999, 0.9999, 0.001, 0.5, 2};
  std::vector<Config> configs;
  auto add = [&](const char* label, int integ, double dt, const double* ref2, const double* imp,
                 bool refsafe, double tol) {
    Config c{label, integ, dt, {ref2[0], ref2[1]}, {}, refsafe, tol, 100};
    for (int i = 0; i < 5; ++i) c.solimp[i] = imp[i];
    configs.push_back(c);
  };
  add("defaults: Euler, dt 1 ms, solref 0.02 1, solimp 0.9 0.95", mjINT_EULER, 1e-3, def_ref,
      def_imp, true, 1e-8);
  add("RK4, dt 1e-4, default solref/solimp", mjINT_RK4, 1e-4, def_ref, def_imp, true, 1e-8);
  const double ref_1e4[2] = {2e-4, 1};
  add("RK4, dt 1e-4, solref 2e-4 1, solimp 0.9999 0.9999, tol 1e-15", mjINT_RK4, 1e-4, ref_1e4,
      hard_imp, true, 1e-15);
  const double ref_1e5[2] = {2e-5, 1};
  add("RK4, dt 1e-5, solref 2e-5 1, solimp 0.9999 0.9999, tol 1e-15", mjINT_RK4, 1e-5, ref_1e5,
      hard_imp, true, 1e-15);
  const double ref_1e5b[2] = {1e-5, 1};
  add("RK4, dt 1e-5, solref 1e-5 1 (refsafe off), solimp 0.9999 0.9999, tol 1e-15", mjINT_RK4,
      1e-5, ref_1e5b, hard_imp, false, 1e-15);
  // best found: solref below 2 dt needs refsafe off; solimp 0.9999 is MuJoCo's cap (mjMAXIMP);
  // solref 2e-6 at dt 1e-5 is unstable; o_solref/o_solimp (override) act on contacts only
  const double ref_5e6[2] = {5e-6, 1};
  add("RK4, dt 1e-5, solref 5e-6 1 (refsafe off), solimp 0.9999 0.9999, tol 1e-15", mjINT_RK4,
      1e-5, ref_5e6, hard_imp, false, 1e-15);
  add("RK4, dt 5e-6, solref 5e-6 1 (refsafe off), solimp 0.9999 0.9999, tol 1e-15", mjINT_RK4,
      5e-6, ref_5e6, hard_imp, false, 1e-15);

  std::vector<Measured> peer_rows;
  for (const Config& c : configs) {
    const Measured r = measure("MuJoCo 2.2.2", c.label, ref, [&] { return mujoco_run(m, d, c); });
    peer_rows.push_back(r);
    std::fprintf(stderr, "mujoco: %s: error %.3e rad, %.3f ms\n", c.label, r.error, 1e3 * r.wall);
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return peer_rows;
}

int main() { return fivebar::peers::run_peer_bench("bench_peers_mujoco", "MuJoCo", mujoco_rows); }
