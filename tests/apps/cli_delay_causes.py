#!/usr/bin/env python3
"""End-to-end check (ctest apps.delay_causes.<case>): identify's torque delay judged as one more
candidate cause of the model check, against the others in one comparison of falls.
- mass: a heavy mechanism whose masses and inertias are 3 % above the scene's, no delay, read a
  lead of 2.4-2.9 ms: not corrected, and the inertias named (in their warning, beside the
  delay's falls, or as the reason the fit is rejected);
  the same 6 % off, the inertias named, exits 3 (as 5 %, unattributed, does);
- delay: an odd mechanism's torques 5 ms late, the fit at its noise floor: corrected, 5 ms
  within 3 std; a heavy mechanism's encoder 0.005 rad off: the encoders' zeros named, no shift;
  the zeros' error read as smoothing bias at every window but the smallest, the noise's bias
  there moves the window up, where the zeros are evidenced 1877 std beyond the other causes and
  would move viscous 5.2 std: the fit exits 3 naming the zeros;
- light: the light mechanism's links 6 % heavier than the scene: the inertias named (beside the
  torque readings, too close to tell apart) while coulomb's std is 3 times its value: exits 3
  (the move in std bounds nothing; or, neither cause standing out beyond the other, by the
  decisive evidence, 94 std);
- clean: the heavy mechanism's clean log: no delay warning, exit 0;
- unchecked: the heavy mechanism's masses 3 % below the scene's, driven a hair from its stretched
  singular pose (t = 8.711 s), read a lag of 2.7 ms at 3.4 std: the model check leaves out the
  sample where its small changes do not evaluate and runs (before, it returned early and the
  delay was corrected without it); no shift;
- small_heavy, small_light: delays alone ahead of the model causes, evidenced below 8 std: a
  heavy mechanism's torques 1 ms late, corrected, and a light one's 8 ms early, corrected or,
  where the window chosen leaves the check's evidence in the rates' noise, named in a warning
  (each within 3 std + 0.5 ms);
- cover: the heavy mechanism's clean logs (seeds 2-4): the 95 % intervals of coulomb and viscous
  hold the truth (the angle noise's bias through the reactions, coulomb -2.5 to -3.5 std at the
  window the residual's rule picks, predicted and the window moved up from it, the bias taken off);
- scaled: the heavy mechanism's masses and inertias 4 % below the scene's (viscous 68 std off) and
  the odd one's 5 % above (coulomb 3.9 std off): the inertias and the torque readings evidenced
  alone far beyond noise, neither beyond the other: exit 3, the masses or inertias named.
Usage: cli_delay_causes.py FIVEBAR PAPER_YAML WORK_DIR CASE"""
import json
import os
import re
import sys

FIVEBAR, PAPER, WORK, CASE = sys.argv[1:5]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Cli, rewrite_log, shift_torques, zero  # noqa: E402

os.makedirs(WORK, exist_ok=True)
cli = Cli(FIVEBAR)
LINKS = [(0.2, 8.0, 0.4, 0.1, 0.1), (0.15, 6.0, 0.3, 0.07, 0.0), (0.45, 5.0, 0.2, 0.2, 0.0),
         (0.4, 4.0, 0.15, 0.2, -0.1)]


def heavy(scale=1.0):
    """A heavy five-bar (links of 4-8 kg, loads of 20 N m), masses and inertias times scale"""
    links = "".join("    - {length: %g, mass: %.17g, inertia: %.17g, com_offset: %g, "
                    "com_angle: %g}\n" % (l, m * scale, i * scale, c, a)
                    for l, m, i, c, a in LINKS)
    return ("mechanism:\n  ground_length: 0.5\n  links:\n" + links +
            "  point_p: 0.3\n  assembly: elbow_up\ngravity: 9.81\n"
            "friction: {model: coulomb_viscous, pin_radius: 0.015, coulomb: 0.1, viscous: 0.05}\n"
            "loads: {M1: \"20*sin(3*t)+5\", M2: \"15*cos(2*t)\", M3: \"0\", F: \"20\", "
            "F_angle: 1.0}\n" + INITIAL)


INITIAL = ("initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966, omega1: 0.0, "
           "omega2: 0.0}\nsimulation: {duration: 3.0, output_step: 0.001}\n")
ODD = ("mechanism:\n  ground_length: 0.12\n  links:\n"
       "    - {length: 0.03, mass: 0.2, inertia: 0.0005, com_offset: 0.015, com_angle: 0.0}\n"
       "    - {length: 0.05, mass: 0.3, inertia: 0.001, com_offset: 0.02, com_angle: 0.0}\n"
       "    - {length: 0.16, mass: 0.4, inertia: 0.002, com_offset: 0.08, com_angle: 0.0}\n"
       "    - {length: 0.13, mass: 0.35, inertia: 0.0015, com_offset: 0.06, com_angle: 0.0}\n"
       "  point_p: 0.1\n  assembly: elbow_up\ngravity: 0\n"
       "friction: {model: coulomb_viscous, pin_radius: 0.003, coulomb: 0.15, viscous: 0.001}\n"
       "loads: {M1: \"0.05*sin(5*t)\", M2: \"0.04*cos(4*t)\", M3: \"0\", F: \"0\", F_angle: 0}\n" +
       INITIAL)


def scaled_odd(scale):
    """ODD with every link's mass and inertia times scale"""
    return re.sub(r"mass: ([0-9.]+), inertia: ([0-9.]+)",
                  lambda m: "mass: %.17g, inertia: %.17g" % (float(m.group(1)) * scale,
                                                             float(m.group(2)) * scale), ODD)


def scene(name, text):
    path = os.path.join(WORK, name + ".yaml")
    with open(path, "w") as f:
        f.write(text)
    return path


def synth(truth, name, torque_noise, excitation=("--excitation", "scene"), seed=1):
    """A 10 s log at 1 kHz of the scene file `truth`"""
    out = os.path.join(WORK, name + ".csv")
    code, _, err = cli.run(["synth-log", truth, "--out", out, "--rate", "1000", "--duration",
                            "10", "--torque-noise", str(torque_noise), "--angle-noise", "1e-5",
                            "--seed", str(seed)] + list(excitation))
    if code != 0:
        cli.failures.append("synth-log %s: exit %d %s" % (name, code, err))
    return out


def identify(name, scene_path, log):
    out = os.path.join(WORK, "out_" + name)
    code, _, err = cli.run(["identify", scene_path, "--log", log, "--out", out, "--no-plots",
                            "--no-validation"])
    try:
        with open(os.path.join(out, "identification.json")) as f:
            return code, err, json.load(f)
    except OSError:
        cli.failures.append("%s: no identification.json (exit %d): %s" % (name, code, err))
        return code, err, {}


def check(cond, what):
    if not cond:
        cli.failures.append(what)


def small_delay(name, scene_path, log, true, named=False):
    """A delay alone ahead of the model causes: corrected, within 3 std + 0.5 ms of `true`; with
    `named`, corrected or named in a warning at that estimate (a light mechanism's window whose
    rates' noise drowns the delay's evidence in the model check)"""
    code, err, j = identify(name, scene_path, log)
    d = j.get("torque_delay", {})
    close = "value_s" in d and abs(d["value_s"] - true) < 3 * d["std_s"] + 5e-4
    told = named and "does not evidence it beyond the noise; not corrected" in err
    check(code == 0 and (d.get("corrected") or told) and close,
          "%s: exit %d, %s, %s" % (name, code, d, err))


if CASE == "mass":
    base = scene("heavy", heavy())
    code, err, j = identify("m103", base, synth(scene("heavy_m103", heavy(1.03)), "m103", 0.02))
    d = j.get("torque_delay", {})
    check(not d.get("corrected", True), "masses 3 %% off: shifted %s" % d)
    check("refitted with the torques shifted" not in err, "masses 3 %% off: %s" % err)
    # the delay beside the inertias in the falls, or the fit rejected naming the masses (the
    # window moved up from the noise's bias shows the misfit: the inertias evidenced beyond the
    # other causes)
    check("the links' inertial parameters" in err and (
        "the torque readings' times (a delay)" in err or
        "The scene's masses or inertias may not match" in err or
        (code == 3 and j.get("status_reason", "").startswith("the scene's masses or inertias"))),
          "masses 3 %% off: neither the delay's falls nor the masses named: %s" % err)
    code, err, j = identify("m106", base, synth(scene("heavy_m106", heavy(1.06)), "m106", 0.02))
    check(code == 3 and "masses or inertias" in j.get("status_reason", ""),
          "masses 6 %% off: exit %d, %s" % (code, j.get("status_reason")))
    check(not j.get("torque_delay", {}).get("corrected", True), "masses 6 %% off: shifted")
elif CASE == "delay":
    odd = scene("odd", ODD)
    log = rewrite_log(synth(odd, "odd", 0.001), os.path.join(WORK, "odd_d5.csv"),
                      shift_torques(5))
    code, err, j = identify("odd_d5", odd, log)
    d = j.get("torque_delay", {})
    check(code == 0 and d.get("corrected") and abs(d["value_s"] - 5e-3) < 3 * d["std_s"] + 2e-4,
          "odd, 5 ms late: exit %d, %s, %s" % (code, d, err))
    base = scene("heavy", heavy())
    log = rewrite_log(synth(base, "heavy", 0.02), os.path.join(WORK, "heavy_zero.csv"), zero(0.005))
    code, err, j = identify("zero", base, log)
    check("an encoder's zero may be off" in err, "theta1 0.005 rad off: zeros not named: %s" % err)
    check(not j.get("torque_delay", {}).get("corrected", True), "theta1 0.005 rad off: shifted")
    reason = j.get("status_reason", "")
    check(code == 3 and "angles' zeros are off" in reason,
          "theta1 0.005 rad off: exit %d, %s" % (code, reason))
elif CASE == "light":
    with open(os.path.join(os.path.dirname(PAPER), "light.yaml")) as f:
        light = f.read()
    base = scene("light", light)
    heavier = scene("light_m106", light.replace("mass: 1.0, inertia: 0.1,",
                                                "mass: 1.06, inertia: 0.106,"))
    out = os.path.join(WORK, "light_m106.csv")
    code, _, err = cli.run(["synth-log", heavier, "--out", out, "--rate", "1000", "--duration",
                            "10", "--torque-noise", "0.002", "--angle-noise", "1e-5", "--seed",
                            "1", "--excitation", "multisine", "--torque-limit", "0.2"])
    check(code == 0, "synth-log light_m106: exit %d %s" % (code, err))
    code, err, j = identify("light_m106", base, out)
    reason = j.get("status_reason", "")
    # the inertias named, alone or tied with the torque readings (a light mechanism's inertial
    # torques scale with its masses as a torque gain scales the reading), evidenced far beyond
    # clean logs' 16 std with coulomb undetermined (its std 0.18 above its value): neither
    # cause stands out beyond the other (the refit with every cause free falls by 291, as the
    # inertias' alone), so the decisive evidence names them
    check(code == 3 and "inertia" in reason and
          ("is not determined" in reason or "evidences a model error" in reason),
          "light links 6 %% heavy: exit %d, %s" % (code, reason))
elif CASE == "clean":
    base = scene("heavy", heavy())
    code, err, j = identify("clean", base, synth(base, "heavy", 0.02))
    check(code == 0 and "delay" not in err and "lead the angles" not in err
          and "lag the angles" not in err, "clean heavy log: exit %d, %s" % (code, err))
elif CASE == "unchecked":
    base = scene("heavy", heavy())
    code, err, j = identify("m097", base, synth(scene("heavy_m097", heavy(0.97)), "m097", 0.02))
    d = j.get("torque_delay", {})
    check(not d.get("corrected", True) and "refitted with the torques shifted" not in err,
          "masses 3 %% below: shifted %s, %s" % (d, err))
    check(j.get("model_check") and "model check did not run" not in err,
          "masses 3 %% below: the model check did not run: %s" % err)
elif CASE == "small_heavy":
    base = scene("heavy", heavy())
    log = rewrite_log(synth(base, "heavy", 0.02), os.path.join(WORK, "heavy_d1.csv"), shift_torques(1))
    small_delay("heavy_d1", base, log, 1e-3)
elif CASE == "small_light":
    light = os.path.join(os.path.dirname(sys.argv[2]), "light.yaml")
    log = synth(light, "light", 0.002, ("--excitation", "multisine", "--torque-limit", "0.2"))
    lead8 = rewrite_log(log, os.path.join(WORK, "light_lead8.csv"), shift_torques(-8))
    small_delay("light_lead8", light, lead8, -8e-3, named=True)
elif CASE == "cover":
    base = scene("heavy", heavy())
    for seed in (2, 3, 4):
        code, err, j = identify("cover%d" % seed, base, synth(base, "heavy%d" % seed, 0.02,
                                                               seed=seed))
        p = {e["name"]: e for e in j.get("parameters", [])}
        for name, truth in (("coulomb", 0.1), ("viscous", 0.05)):
            e = p.get(name, {})
            check(code == 0 and e.get("std") and e["ci95_low"] <= truth <= e["ci95_high"],
                  "clean heavy log, seed %d: exit %d, %s %s +- %s, interval %s..%s (truth %g)"
                  % (seed, code, name, e.get("value"), e.get("std"), e.get("ci95_low"),
                     e.get("ci95_high"), truth))
elif CASE == "scaled":
    base = scene("heavy", heavy())
    code, err, j = identify("m096", base, synth(scene("heavy_m096", heavy(0.96)), "m096", 0.02))
    reason = j.get("status_reason", "")
    check(code == 3 and reason.startswith("the scene's masses or inertias"),
          "heavy masses 4 %% below: exit %d, %s" % (code, reason))
    odd = scene("odd", ODD)
    code, err, j = identify("odd105", odd, synth(scene("odd105", scaled_odd(1.05)), "odd105",
                                                 0.001))
    reason = j.get("status_reason", "")
    check(code == 3 and reason.startswith("the scene's masses or inertias"),
          "odd masses 5 %% above: exit %d, %s" % (code, reason))
else:
    cli.failures.append("unknown case " + CASE)

for f in cli.failures:
    print("FAIL:", f)
sys.exit(1 if cli.failures else 0)
