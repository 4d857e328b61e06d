"""fivebar.load_scene and fivebar.simulate against the reference trajectory."""
import numpy as np

import fivebar

COLUMNS = (["t"] + [f"{q}{i}" for q in ("theta", "omega", "alpha") for i in range(1, 5)]
           + ["M1", "M2"] + [f"{q}{k}" for q in ("N", "Mf") for k in range(1, 6)]
           + ["P_diss", "E_diss", "W_in", "W_ext"])


def test_columns_are_those_of_trajectory_csv(paper_run):
    for name in COLUMNS:
        assert paper_run[name].dtype == np.float64
        assert paper_run[name].shape == (2001,)
    assert paper_run["mode"].shape == (2001, 5)
    summary = paper_run["summary"]
    assert summary["status"] == "ok"
    assert summary["friction_events"] == 11
    assert summary["energy_balance_relative"] < 1e-8
    assert summary["inverse_dynamics_max_abs_error"] < 1e-8


def test_paper_scene_matches_reference(paper_run, root):
    ref = np.genfromtxt(root / "datasets" / "reference" / "paper_friction.csv", delimiter=",",
                        names=True)
    np.testing.assert_allclose(paper_run["t"], ref["t"], rtol=0, atol=1e-12)
    error = max(np.max(np.abs(paper_run[f"theta{i}"] - ref[f"theta{i}"])) for i in range(1, 5))
    assert error <= 1e-6, f"max |d theta| = {error:.3g} rad"


def test_overrides_change_the_scene(root):
    base = fivebar.load_scene(root / "datasets/scenes/paper.yaml")
    heavy = fivebar.load_scene(root / "datasets/scenes/paper.yaml",
                               overrides={"mechanism.links.2.mass": 1.5,
                                          "simulation.duration": 0.1,
                                          "friction.coulomb": [0.1, 0.12, 0.12, 0.12, 0.2]})
    assert "mass: 1.5" in heavy.to_yaml()
    assert heavy.duration == 0.1
    short = fivebar.simulate(heavy)
    assert short["t"][-1] == 0.1
    again = fivebar.parse_scene(heavy.to_yaml(), name="heavy.yaml")
    np.testing.assert_array_equal(fivebar.simulate(again)["theta1"], short["theta1"])
    assert base.duration == 2.0


def test_numpy_values_as_overrides(root):
    plain = fivebar.load_scene(root / "datasets/scenes/paper.yaml",
                               overrides={"friction.coulomb": [0.1, 0.12, 0.12, 0.12, 0.2],
                                          "simulation.max_steps": 5000})
    numpy = fivebar.load_scene(root / "datasets/scenes/paper.yaml",
                               overrides={"friction.coulomb": np.array([0.1, 0.12, 0.12, 0.12,
                                                                        0.2]),
                                          "simulation.max_steps": np.int64(5000)})
    assert numpy.to_yaml() == plain.to_yaml()


def test_a_four_bar_scene_runs_with_its_own_columns(root):
    # the Grashof crank-rocker of datasets/reference/four_bar/ against its independent reference
    folder = root / "datasets" / "reference" / "four_bar"
    scene = fivebar.load_scene(folder / "crank_rocker.yaml")
    assert scene.mechanism == "four_bar"
    assert scene.initial == {"theta1": 1.5707963267948966, "omega1": 0.0}
    run = fivebar.simulate(scene, twin=True)
    assert "theta4" not in run and "M2" not in run and "Mf5" not in run
    assert run["mode"].shape == (2001, 4)
    assert run["summary"]["mechanism"] == "four_bar" and run["summary"]["status"] == "ok"
    assert run["frictionless"]["theta3"].shape == (2001,)
    ref = np.genfromtxt(folder / "crank_rocker.csv", delimiter=",", names=True)
    error = max(np.max(np.abs(run[f"theta{i}"] - ref[f"theta{i}"])) for i in range(1, 4))
    assert error <= 1e-7, f"max |d theta| = {error:.3g} rad"
    # friction never supplies power (joints O, B, C, D0 from the link rates)
    w = [run["omega1"], run["omega2"] - run["omega1"], run["omega3"] - run["omega2"],
         run["omega3"]]
    assert min(np.min(run[f"Mf{k + 1}"] * w[k]) for k in range(4)) >= -1e-9


def test_a_four_bar_scene_keeps_its_type_through_yaml_and_pickle(root):
    import pickle
    scene = fivebar.load_scene(root / "datasets/reference/four_bar/double_rocker.yaml")
    again = fivebar.parse_scene(scene.to_yaml())
    assert again.mechanism == "four_bar" and again.to_yaml() == scene.to_yaml()
    assert pickle.loads(pickle.dumps(scene)).to_yaml() == scene.to_yaml()
    assert scene.replace({"gravity": 0}).mechanism == "four_bar"


def test_four_bar_inverse_gives_back_the_simulated_torque(root):
    # the crank's motion of a simulated run: inverse dynamics returns its M1, reactions and
    # friction torques (the run's rates and accelerations are exact, slip directions the same
    # wherever the joints move)
    scene = fivebar.load_scene(root / "datasets/reference/four_bar/crank_rocker.yaml")
    run = fivebar.simulate(scene, duration=0.5)
    inv = fivebar.inverse(scene, run["theta1"], run["omega1"][:, None], run["alpha1"], t=run["t"])
    assert inv["M"].shape == (len(run["t"]), 1) and inv["N"].shape == (len(run["t"]), 4)
    moving = np.all(run["mode"] != 0, axis=1)
    assert np.count_nonzero(moving) > 0.9 * len(run["t"])
    assert np.max(np.abs(inv["M"][moving, 0] - run["M1"][moving])) <= 1e-9
    for k in range(4):
        assert np.max(np.abs(inv["N"][moving, k] - run[f"N{k + 1}"][moving])) <= 1e-7
        assert np.max(np.abs(inv["Mf"][moving, k] - run[f"Mf{k + 1}"][moving])) <= 1e-9


def test_four_bar_inverse_refuses_bad_arrays(root):
    import pytest
    scene = fivebar.load_scene(root / "datasets/reference/four_bar/crank_rocker.yaml")
    z = np.zeros((3, 2))
    with pytest.raises(ValueError, match=r"theta: \(argument\): expected a float64 array of shape \(N, 1\)"):
        fivebar.inverse(scene, z, z, z, t=np.zeros(3))
    bad = np.array([0.1, np.nan, 0.3])
    with pytest.raises(ValueError, match="omega: row 1: expected a finite number"):
        fivebar.inverse(scene, np.zeros(3), bad, np.zeros(3), t=np.zeros(3))
    with pytest.raises(ValueError, match="depend on t"):
        fivebar.inverse(scene.replace({"loads.M3": "0.2*t"}), np.zeros(3), np.zeros(3), np.zeros(3))
