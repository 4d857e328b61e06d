"""fivebar.identify and fivebar.optimize return their results as dicts."""
import numpy as np

import fivebar


def test_identify_paper_log(root, paper_scene):
    result = fivebar.identify(paper_scene, root / "datasets/logs/paper_rates.csv")
    values = {p["name"]: p for p in result["parameters"]}
    assert set(values) == {"coulomb", "viscous"}
    for name, true in (("coulomb", 0.12), ("viscous", 0.02)):
        p = values[name]
        assert abs(p["value"] - true) <= 0.01 * true
        assert abs(p["value"] - true) <= 3 * p["std"]
    assert result["correlation"].shape == (2, 2)
    assert result["samples"] == 10001
    assert result["predicted_tau1"].shape == (10001,)
    assert result["solver"]["converged"]
    fitted = result["fitted_scene"]
    assert isinstance(fitted, fivebar.Scene)
    assert f"coulomb: {values['coulomb']['value']!r}" in fitted.to_yaml()


def test_identify_from_a_dict_of_arrays(root, paper_scene):
    text = (root / "datasets/logs/paper_rates.csv").read_text().splitlines()
    lines = [line for line in text if not line.startswith("#")][:3001]
    log = np.genfromtxt(lines, delimiter=",", names=True)
    columns = {name: log[name] for name in log.dtype.names}
    result = fivebar.identify(paper_scene, columns)
    coulomb = result["parameters"][0]
    assert coulomb["name"] == "coulomb" and abs(coulomb["value"] - 0.12) < 0.005


def test_optimize_one_task(root, paper_scene, tmp_path):
    tasks = tmp_path / "tasks.yaml"
    tasks.write_text("tasks:\n  - name: swing_left\n    duration: 0.5\n"
                     "    start: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}\n"
                     "    goal: {theta1: 2.6, theta2: 2.2}\n    torque_limit: 30.0\n")
    result = fivebar.optimize(paper_scene, tasks, threads=1)
    task = result["swing_left"]
    assert task["status"] == "ok"
    assert task["dissipated_energy"] < task["baseline_dissipated_energy"]
    assert isinstance(task["evaluations"], int)
    trajectory = task["trajectory"]
    assert trajectory["t"][-1] == 0.5
    assert abs(trajectory["theta1"][-1] - 2.6) < 1e-9
    assert task["baseline"]["M1"].shape == trajectory["M1"].shape
    assert result.swing_left.trajectory.M1 is trajectory["M1"]  # Records, as simulate's


def test_identify_options_are_the_command_lines(root, paper_scene):
    # a given sg_window is used (not the window chosen from the log); unknown options are refused
    log = root / "datasets/logs/paper_angles.csv"
    chosen = fivebar.identify(paper_scene, log)
    given = fivebar.identify(paper_scene, log, sg_window=0.02)
    assert given["sg_half_window_s"] != chosen["sg_half_window_s"]
    assert abs(given["sg_half_window_s"] - 0.02) < 1e-3
    try:
        fivebar.identify(paper_scene, log, sg_windw=0.02)
    except TypeError as e:
        assert "sg_windw" in str(e)
    else:
        raise AssertionError("an unknown option was accepted")
    assert "no_delay=False" in fivebar.identify.__doc__


def test_identify_has_the_log_conditioning_delay_and_window_choice(root, paper_scene):
    # the dict has log_conditioning, torque_delay and window_choice, as
    # identification.json has; a glitch put into the log is named by its line there
    text = (root / "datasets/logs/paper_angles.csv").read_text().splitlines()
    lines = [line for line in text if not line.startswith("#")][:2001]
    log = np.genfromtxt(lines, delimiter=",", names=True)
    columns = {name: np.array(log[name]) for name in log.dtype.names}
    columns["theta1"][700] += 0.1
    result = fivebar.identify(paper_scene, columns)
    cond = result["log_conditioning"]
    assert set(cond) >= {"unwrapped_turns", "angle_noise", "torque_noise", "rejected_glitches",
                         "notes"}
    assert [(g["line"], g["column"]) for g in cond["rejected_glitches"]] == [(702, "theta1")]
    assert cond["torque_noise"].shape == (2,) and cond["torque_noise"][0] > 0
    delay = result["torque_delay"]
    assert set(delay) == {"value_s", "std_s", "corrected"} and delay["std_s"] > 0
    assert result["window_choice"]  # the text is that of identification.json


def test_optimize_takes_a_list_of_tasks_with_the_command_lines_defaults(root):
    # a list of task dicts as in a tasks file; the command line's defaults: refinement on, and
    # total_dissipation on a scene with the motors' winding data
    scene = fivebar.load_scene(root / "datasets/scenes/paper_motors.yaml")
    tasks = [{"name": "swing_right", "duration": 0.5,
              "start": {"theta1": 1.5707963267948966, "theta2": 1.5707963267948966},
              "goal": {"theta1": 0.7, "theta2": 0.6}, "torque_limit": 30.0}]
    task = fivebar.optimize(scene, tasks, threads=1, trajectories=False)["swing_right"]
    assert task["status"] == "ok"
    assert task["refinement"].startswith("10:") and ";15:" in task["refinement"]
    assert abs(task["total_dissipation"] - task["dissipated_energy"] - task["winding_heat"]) < 1e-12
    assert task["refinement_change"] < 1e-4
    try:
        fivebar.optimize(scene, [{"name": "x", "duration": 0.5}], threads=1)
    except Exception as e:  # the tasks file's own checks
        assert "start" in str(e) or "goal" in str(e)
    else:
        raise AssertionError("a task without start and goal was accepted")


def test_optimize_a_four_bar_task_from_a_list(root):
    # the crank-rocker's P lowered to y = 0.10 m: the crank's columns, the limit held, energy
    # below the minimum-jerk start's, and a five-bar key refused naming the mechanism
    import pytest
    scene = fivebar.load_scene(root / "datasets/reference/four_bar/crank_rocker.yaml")
    task = {"name": "lower_p", "duration": 0.4, "start": {"theta1": 1.5707963267948966},
            "goal": {"y": 0.10}, "torque_limit": 1.5}
    result = fivebar.optimize(scene, [task], threads=1, refine=False)["lower_p"]
    assert result["status"] == "ok"
    assert result["dissipated_energy"] < result["baseline_dissipated_energy"]
    rows = result["trajectory"]
    assert "theta3" in rows and "theta4" not in rows and "M2" not in rows
    assert np.max(np.abs(rows["M1"])) <= 1.5 * (1 + 1e-6)
    bad = dict(task, goal={"theta1": 2.0, "theta2": 1.0})
    with pytest.raises(ValueError, match="theta2: a five_bar key"):
        fivebar.optimize(scene, [bad], threads=1)


def test_identify_a_four_bar_motor(root, cli, tmp_path):
    # the crank motor's terms through the module: a double-rocker log (its crank reverses) made
    # with synth-log's actuator options, identify's actuator group after the friction, each truth
    # (the log's true.offset, ...) inside its interval
    import subprocess
    import pytest
    if not cli:
        pytest.skip("no fivebar executable")
    scene_path = root / "datasets/reference/four_bar/double_rocker.yaml"
    log = tmp_path / "motor.csv"
    subprocess.run([cli, "synth-log", str(scene_path), "--out", str(log), "--duration", "4",
                    "--seed", "1", "--torque-offset", "0.03", "--actuator-coulomb", "0.04",
                    "--actuator-viscous", "0.005"], check=True, capture_output=True)
    result = fivebar.identify(fivebar.load_scene(scene_path), log, estimate="friction,actuator")
    assert result["status"] == "ok"
    names = [p["name"] for p in result["parameters"]]
    assert names == ["coulomb", "viscous", "offset_1", "actuator_coulomb_1", "actuator_viscous_1"]
    for p in result["parameters"]:
        assert p["ci95_low"] <= p["true"] <= p["ci95_high"], p["name"]


def test_identify_a_four_bar_log(root, cli, tmp_path):
    # a synthetic crank-rocker log (the CLI's synth-log): the truths inside the 95 % intervals,
    # one torque channel; the validation run of its crank angle
    import subprocess
    import pytest
    if not cli:
        pytest.skip("no fivebar executable")
    scene_path = root / "datasets/reference/four_bar/crank_rocker.yaml"
    log = tmp_path / "log.csv"
    subprocess.run([cli, "synth-log", str(scene_path), "--out", str(log), "--duration",
                    "2", "--seed", "5"], check=True, capture_output=True)
    scene = fivebar.load_scene(scene_path)
    result = fivebar.identify(scene, log)
    assert result["status"] == "ok" and result["mechanism"] == "four_bar"
    for p in result["parameters"]:
        assert p["ci95_low"] <= p["true"] <= p["ci95_high"], p["name"]
    assert result["fitted_scene"].mechanism == "four_bar"
    assert result["predicted_tau1"].shape == result["omega1"].shape
    validated = fivebar.identify(scene, log, validate=True)
    validation = validated["validation"]
    assert len(validation["windowed_rms_angle_error"]) == 1
    assert validation["windowed_theta1"].shape == result["omega1"].shape
    assert "windowed_theta2" not in validation
    # the inertial group passes through: the three links' 12 standard parameters after the
    # friction, the truth of each (the log's true.inertial) inside its interval (the CLI's fit of
    # this log, tests/apps/cli_four_bar.py: every |z| below 1)
    with_links = fivebar.identify(scene, log, estimate="friction,inertia")
    names = [p["name"] for p in with_links["parameters"]]
    assert names[:3] == ["coulomb", "viscous", "m_1"] and names[-1] == "J_3" and len(names) == 14
    assert with_links["inertial"]["prior_relative_std"] == 0.2
    for p in with_links["parameters"]:
        assert p["ci95_low"] <= p["true"] <= p["ci95_high"], p["name"]
