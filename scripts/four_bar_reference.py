#!/usr/bin/env python3
"""Reference trajectories of four-bar scenes, computed independently of fivebar's C++ model.

Formulation (different from fivebar's reduced one-coordinate model in four_bar.h):
- maximal coordinates: each of the three moving links has its centre of mass (x, y) and its angle;
- Newton-Euler equations of the three links with the four joint reactions as unknowns and the four
  joint closures imposed at acceleration level: one 17 x 17 linear system per evaluation;
- the load-dependent friction torque r_k N_k f(w_k) of every joint, with the reaction/friction loop
  solved by fixed-point iteration to rounding (a relative change of 4e-16);
- classical Runge-Kutta 4 at a fixed step (default 2e-5 s) on the crank angle and rate and the three
  energy integrals; every zero of a joint's relative rate is located by bisection and the
  integration restarted there, with the Coulomb sign of the new direction. A joint at rest takes the
  direction of its relative acceleration; if no direction is consistent the mechanism sticks and the
  script stops (the shipped scenes do not stick).

Usage: four_bar_reference.py SCENE.yaml OUT.csv [--step H]
Writes t, theta1..theta3, omega1..omega3, E_diss, W_in, W_ext every simulation.output_step, and
prints the energy balance's largest error and the number of located switches.
"""
import argparse
import itertools
import math
import sys

import numpy as np
import yaml

GROUND = -1


def perp(v):
    return np.array([-v[1], v[0]])


def rot(phi, v):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class FourBar:
    """A four-bar scene: ground O=(0,0), D0=(l0,0); crank O->B, coupler B->C, rocker D0->C."""

    def __init__(self, scene):
        m = scene["mechanism"]
        self.l0 = float(m["ground_length"])
        self.lp = float(m.get("point_p", 0.0))
        self.side = 1.0 if m.get("assembly", "elbow_up") == "elbow_up" else -1.0
        self.g = float(scene.get("gravity", 9.81))
        fr = scene.get("friction", {"model": "none"})
        self.friction = fr["model"] != "none"
        if fr["model"] not in ("none", "coulomb_viscous"):
            sys.exit("four_bar_reference: only friction.model none | coulomb_viscous")
        def as_list(v):
            return [float(x) for x in v] if isinstance(v, list) else [float(v)] * 4

        self.r = as_list(fr.get("pin_radius", 0.0))
        self.mu = as_list(fr.get("coulomb", 0.0))
        self.cv = as_list(fr.get("viscous", 0.0))
        loads = scene.get("loads", {})
        self.load = {k: self._expr(loads.get(k, "0")) for k in ("M1", "M3", "F")}
        self.F_angle = float(loads.get("F_angle", 0.0))
        links = links_of(m)
        self.mass = [float(l["mass"]) for l in links]
        self.inertia = [float(l["inertia"]) for l in links]
        com = [float(l["com_offset"]) * np.array([math.cos(float(l.get("com_angle", 0.0))),
                                                  math.sin(float(l.get("com_angle", 0.0)))])
               for l in links]
        L = [float(l["length"]) for l in links]
        self.L, self.com = L, com
        # body-fixed vectors from each centre of mass to the body's joints and to P
        start = [-com[i] for i in range(3)]
        end = [np.array([L[i], 0.0]) - com[i] for i in range(3)]
        self.p_local = np.array([self.lp, 0.0]) - com[1]
        # joints (body i, point on i, body j, point on j): force F_k of i on j
        self.joints = [(GROUND, np.zeros(2), 0, start[0]),              # O
                       (0, end[0], 1, start[1]),                         # B
                       (1, end[1], 2, end[2]),                           # C
                       (GROUND, np.array([self.l0, 0.0]), 2, start[2])]  # D0

    @staticmethod
    def _expr(text):
        env = {k: getattr(math, k) for k in ("sin", "cos", "tan", "exp", "sqrt", "pi", "tanh")}
        code = compile(str(text).replace("^", "**"), "<load>", "eval")
        return lambda t: float(eval(code, {"__builtins__": {}}, dict(env, t=t)))

    def pose(self, th1):
        """The link angles th1, th2, th3 of the closed pose."""
        B = self.L[0] * np.array([math.cos(th1), math.sin(th1)])
        D0 = np.array([self.l0, 0.0])
        d = D0 - B
        dist = math.hypot(*d)
        l2, l3 = self.L[1], self.L[2]
        a = (l2 * l2 + dist * dist - l3 * l3) / (2 * dist)
        h2 = l2 * l2 - a * a
        if h2 < 0:
            raise RuntimeError(f"cannot assemble at theta1={th1}")
        u = d / dist
        C = B + a * u + self.side * math.sqrt(h2) * perp(u)
        th2 = math.atan2(*(C - B)[::-1])
        th3 = math.atan2(*(C - D0)[::-1])
        return np.array([th1, th2, th3]), B, C

    def rates(self, th, w1):
        """omega2, omega3 from vB + w2 x (C-B) = w3 x (C-D0)."""
        e = [np.array([math.cos(a), math.sin(a)]) for a in th]
        vB = w1 * self.L[0] * perp(e[0])
        A = np.column_stack([self.L[1] * perp(e[1]), -self.L[2] * perp(e[2])])
        w23 = np.linalg.solve(A, -vB)
        return np.array([w1, w23[0], w23[1]])

    def joint_rates(self, w):
        rate = lambda b: 0.0 if b == GROUND else w[b]
        return np.array([rate(j) - rate(i) for (i, _, j, _) in self.joints])

    def assemble(self, th, w, t):
        """The 17 x 17 system matrix and the right-hand side without friction, and the load data."""
        K = np.zeros((17, 17))
        rhs = np.zeros(17)
        for b in range(3):
            K[3 * b, 3 * b] = K[3 * b + 1, 3 * b + 1] = self.mass[b]
            K[3 * b + 2, 3 * b + 2] = self.inertia[b]
            rhs[3 * b + 1] -= self.mass[b] * self.g
        # reactions: unknown F_k (columns 9+2k, 10+2k) acts +F on j and -F on i at the joint point
        arm = lambda b, s: rot(th[b], s)
        for k, (i, si, j, sj) in enumerate(self.joints):
            for body, s, sign in ((i, si, -1.0), (j, sj, +1.0)):
                if body == GROUND:
                    continue
                r = arm(body, s)
                K[3 * body, 9 + 2 * k] -= sign
                K[3 * body + 1, 10 + 2 * k] -= sign
                K[3 * body + 2, 9 + 2 * k] -= sign * -r[1]
                K[3 * body + 2, 10 + 2 * k] -= sign * r[0]
            # closure at acceleration level: a_point(j) - a_point(i) = 0
            for body, s, sign in ((j, sj, +1.0), (i, si, -1.0)):
                if body == GROUND:
                    continue
                r = arm(body, s)
                row = 9 + 2 * k
                K[row, 3 * body] += sign
                K[row + 1, 3 * body + 1] += sign
                K[row, 3 * body + 2] += sign * -r[1]
                K[row + 1, 3 * body + 2] += sign * r[0]
                rhs[row:row + 2] -= sign * (-w[body] ** 2 * r)
        M1, M3, F = (self.load[k](t) for k in ("M1", "M3", "F"))
        rhs[2] += M1
        rhs[5] += M3
        Fv = F * np.array([math.cos(th[1] + self.F_angle), math.sin(th[1] + self.F_angle)])
        rP = arm(1, self.p_local)
        rhs[3] += Fv[0]
        rhs[4] += Fv[1]
        rhs[5] += rP[0] * Fv[1] - rP[1] * Fv[0]
        vP = self._point_velocity(th, w, 1, self.p_local)
        return K, rhs, (M1, M3, Fv, vP)

    def _point_velocity(self, th, w, b, s):
        vc = self._com_velocity(th, w, b)
        return vc + w[b] * perp(rot(th[b], s))

    def _com_velocity(self, th, w, b):
        # the centre of mass of body b from the chain O -> ... (crank, coupler) or D0 (rocker)
        if b == 0:
            return w[0] * perp(rot(th[0], self.com[0]))
        if b == 1:
            vB = w[0] * self.L[0] * perp(np.array([math.cos(th[0]), math.sin(th[0])]))
            return vB + w[1] * perp(rot(th[1], self.com[1]))
        return w[2] * perp(rot(th[2], self.com[2]))

    def solve(self, t, th1, w1, slip):
        """Accelerations, reactions and friction torques at (t, th1, w1); slip: the Coulomb sign
        of each joint (+1, -1, or 0 for no Coulomb term)."""
        th, _, _ = self.pose(th1)
        w = self.rates(th, w1)
        wj = self.joint_rates(w)
        K, rhs0, loads = self.assemble(th, w, t)
        phi = [self.r[k] * (self.mu[k] * slip[k] + self.cv[k] * wj[k]) if self.friction else 0.0
               for k in range(4)]
        Mf = np.zeros(4)
        for _ in range(60):
            rhs = rhs0.copy()
            for k, (i, _, j, _) in enumerate(self.joints):
                if j != GROUND:
                    rhs[3 * j + 2] -= Mf[k]
                if i != GROUND:
                    rhs[3 * i + 2] += Mf[k]
            x = np.linalg.solve(K, rhs)
            N = np.hypot(x[9::2], x[10::2])
            new = np.array(phi) * N
            change = np.max(np.abs(new - Mf)) / max(1e-300, np.max(np.abs(new)))
            Mf = new
            if change <= 4e-16:
                break
        else:
            if change > 1e-14:  # rounding keeps the last bits moving; beyond that is divergence
                raise RuntimeError(f"friction loop did not converge at t={t}: change {change:.1e}")
        return x, Mf, th, w, wj, loads

    def derivative(self, t, y, slip):
        x, Mf, th, w, wj, (M1, M3, Fv, vP) = self.solve(t, y[0], y[1], slip)
        return np.array([y[1], x[2], Mf @ wj, M1 * w[0], M3 * w[1] + Fv @ vP])

    def energy(self, th1, w1):
        th, _, _ = self.pose(th1)
        w = self.rates(th, w1)
        ke = pe = 0.0
        for b in range(3):
            v = self._com_velocity(th, w, b)
            ke += 0.5 * self.mass[b] * (v @ v) + 0.5 * self.inertia[b] * w[b] ** 2
            y = {0: 0.0, 1: self.L[0] * math.sin(th[0]), 2: 0.0}[b] + rot(th[b], self.com[b])[1]
            pe += self.mass[b] * self.g * y
        return ke + pe


def links_of(m):
    links = m["links"]
    if len(links) != 3:
        sys.exit("four_bar_reference: mechanism.links needs 3 links (crank, coupler, rocker)")
    return links


def joint_rates_at(fb, y):
    th, _, _ = fb.pose(y[0])
    return fb.joint_rates(fb.rates(th, y[1]))


def signs_at(fb, t, y, tiny=1e-12):
    """The Coulomb sign of each joint: sign(w_k), or for a joint at rest the direction of its
    relative acceleration under the friction that direction implies (every combination of the
    resting joints' directions is tried; exactly one must be consistent)."""
    wj = joint_rates_at(fb, y)
    slip = np.sign(wj)
    rest = np.abs(wj) <= tiny * max(1.0, np.max(np.abs(wj)))
    slip[rest] = 0
    idx = np.flatnonzero(rest)
    if idx.size == 0:
        return slip
    found = []
    for combo in itertools.product((1.0, -1.0), repeat=idx.size):
        s = slip.copy()
        s[idx] = combo
        d = fb.derivative(t, y, s)
        h = 1e-7  # the sign of d/dt w_k from a first-order step of the state
        wdot = (joint_rates_at(fb, y + h * d) - joint_rates_at(fb, y)) / h
        if np.all(np.sign(wdot[idx]) == s[idx]):
            found.append(s)
    if not found:
        raise RuntimeError(f"the mechanism sticks at t={t}: no consistent slip direction")
    if len(found) > 1:
        raise RuntimeError(f"{len(found)} consistent slip directions at t={t}")
    return found[0]


def rk4(fb, t, y, h, slip):
    k1 = fb.derivative(t, y, slip)
    k2 = fb.derivative(t + h / 2, y + h / 2 * k1, slip)
    k3 = fb.derivative(t + h / 2, y + h / 2 * k2, slip)
    k4 = fb.derivative(t + h, y + h * k3, slip)
    return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def crossing(fb, y, slip):
    """The joints whose rate has left the sign assumed for the step."""
    wj = joint_rates_at(fb, y)
    return [k for k in range(4) if slip[k] != 0 and np.sign(wj[k]) == -slip[k]]


def advance(fb, t, y, h, slip, switches):
    """One step of at most h; stops at a located zero of a joint rate (then the signs change)."""
    y1 = rk4(fb, t, y, h, slip)
    if not crossing(fb, y1, slip) or not fb.friction:
        return t + h, y1, slip
    lo, hi = 0.0, h
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if crossing(fb, rk4(fb, t, y, mid, slip), slip):
            hi = mid
        else:
            lo = mid
    y1 = rk4(fb, t, y, hi, slip)
    switches.append(t + hi)
    return t + hi, y1, signs_at(fb, t + hi, y1, tiny=1e-9)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--step", type=float, default=2e-5)
    args = ap.parse_args()
    with open(args.scene) as f:
        scene = yaml.safe_load(f)
    fb = FourBar(scene)
    ini = scene.get("initial", {})
    sim = scene.get("simulation", {})
    duration, dt_out = float(sim.get("duration", 2.0)), float(sim.get("output_step", 1e-3))
    t, y = 0.0, np.array([float(ini.get("theta1", 0.0)), float(ini.get("omega1", 0.0)), 0, 0, 0])
    slip = signs_at(fb, t, y) if fb.friction else np.zeros(4)
    e0 = fb.energy(y[0], y[1])
    rows, switches, worst = [], [], 0.0
    n_out = int(round(duration / dt_out))
    for n in range(n_out + 1):
        t_out = n * dt_out
        while t < t_out - 1e-15:
            t, y, slip = advance(fb, t, y, min(args.step, t_out - t), slip, switches)
        t = t_out
        th, _, _ = fb.pose(y[0])
        w = fb.rates(th, y[1])
        balance = fb.energy(y[0], y[1]) - e0 - (y[3] + y[4] - y[2])
        worst = max(worst, abs(balance) / max(1.0, abs(y[3]) + abs(y[4]) + abs(y[2])))
        rows.append([t_out, *th, *w, y[2], y[3], y[4]])
    with open(args.out, "w") as f:
        f.write("t,theta1,theta2,theta3,omega1,omega2,omega3,E_diss,W_in,W_ext\n")
        for r in rows:
            f.write(",".join(repr(float(v)) for v in r) + "\n")
    print(f"{args.out}: {len(rows)} rows; energy balance error {worst:.2e} (relative); "
          f"{len(switches)} switches" + (f", first at t = {switches[0]:.6f} s" if switches else ""))


if __name__ == "__main__":
    main()
