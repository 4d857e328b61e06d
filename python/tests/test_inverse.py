"""fivebar.inverse: the input torques back from simulated states, threads, bad arrays."""
import numpy as np
import pytest

import fivebar


def states(run):
    pick = lambda q: np.stack([run[f"{q}1"], run[f"{q}2"]], axis=1)
    return pick("theta"), pick("omega"), pick("alpha")


def test_inverse_of_simulated_states_returns_input_torques(paper_scene, paper_run):
    theta, omega, alpha = states(paper_run)
    out = fivebar.inverse(paper_scene, theta, omega, alpha, t=paper_run["t"])
    assert out["M"].shape == (2001, 2) and out["N"].shape == (2001, 5)
    assert out["Mf"].shape == (2001, 5)
    free = ~(paper_run["mode"] == 2).any(axis=1)  # a stuck joint's holding torque is indeterminate
    assert free.sum() > 1900
    torques = np.stack([paper_run["M1"], paper_run["M2"]], axis=1)
    error = np.max(np.abs(out["M"][free] - torques[free]))
    assert error <= 1e-8, f"max |M - M_input| = {error:.3g} N m"
    reactions = np.stack([paper_run[f"N{k}"] for k in range(1, 6)], axis=1)
    assert np.max(np.abs(out["N"][free] - reactions[free])) <= 1e-6


def test_threads_give_the_same_numbers(paper_scene, paper_run):
    theta, omega, alpha = (np.tile(a, (6, 1)) for a in states(paper_run))  # 12006 states
    one = fivebar.inverse(paper_scene, theta, omega, alpha, threads=1)
    two = fivebar.inverse(paper_scene, theta, omega, alpha, threads=2)
    for key in ("M", "N", "Mf"):
        np.testing.assert_array_equal(one[key], two[key])


def test_time_dependent_loads_need_t(root, paper_run):
    scene = fivebar.load_scene(root / "datasets/scenes/paper.yaml",
                               overrides={"loads.M3": "6 + sin(t)"})
    theta, omega, alpha = (a[:10] for a in states(paper_run))
    with pytest.raises(ValueError, match=r"^t: \(argument\): the loads of .* depend on t"):
        fivebar.inverse(scene, theta, omega, alpha)
    with_t = fivebar.inverse(scene, theta, omega, alpha, t=paper_run["t"][:10])
    assert np.all(np.isfinite(with_t["M"]))


@pytest.mark.parametrize("argument, value, message", [
    ("theta", np.zeros((3, 3)), r"^theta: \(argument\): expected a float64 array of shape \(N, 2\), got shape \(3, 3\)$"),
    ("theta", [["a", "b"]], r"^theta: \(argument\): expected a float64 array of shape \(N, 2\), got list$"),
    ("theta", [[1.0, 2.0]], r"^omega: \(argument\): expected a float64 array of shape \(N, 2\) with N = 1 \(the rows of theta\), got shape \(3, 2\)$"),
    ("omega", np.zeros((4, 2)), r"^omega: \(argument\): expected a float64 array of shape \(N, 2\) with N = 3 \(the rows of theta\), got shape \(4, 2\)$"),
    ("alpha", np.zeros(6), r"^alpha: \(argument\): expected a float64 array of shape \(N, 2\) with N = 3"),
    ("alpha", np.full((3, 2), "x"), r"^alpha: \(argument\): .* got dtype <U1$"),
    ("t", np.zeros((3, 1)), r"^t: \(argument\): expected a float64 array of shape \(N,\) with N = 3"),
])
def test_bad_arrays_raise_value_error(paper_scene, argument, value, message):
    args = {"theta": np.full((3, 2), np.pi / 2), "omega": np.zeros((3, 2)),
            "alpha": np.zeros((3, 2)), "t": np.zeros(3)}
    args[argument] = value
    with pytest.raises(ValueError, match=message):
        fivebar.inverse(paper_scene, **args)


def test_lists_and_other_dtypes_are_converted(paper_scene, paper_run):
    theta, omega, alpha = (a[:5] for a in states(paper_run))
    expected = fivebar.inverse(paper_scene, theta, omega, alpha)["M"]
    as_lists = fivebar.inverse(paper_scene, theta.tolist(), omega.tolist(), alpha.tolist())
    np.testing.assert_array_equal(as_lists.M, expected)
    single = fivebar.inverse(paper_scene, theta.astype(np.float32), omega.astype(np.float32),
                             alpha.astype(np.float32))
    np.testing.assert_allclose(single.M, expected, rtol=1e-4, atol=1e-4)
    zeros = np.zeros((1, 2), dtype=np.int64)
    assert fivebar.inverse(paper_scene, [[1, 2]], zeros, zeros).M.shape == (1, 2)


def test_non_contiguous_arrays_are_accepted(paper_scene, paper_run):
    theta, omega, alpha = states(paper_run)
    wide = np.asfortranarray(theta)
    np.testing.assert_array_equal(fivebar.inverse(paper_scene, wide, omega, alpha)["M"],
                                  fivebar.inverse(paper_scene, theta, omega, alpha)["M"])


def test_poses_that_cannot_assemble_are_bad_input(root):
    short = {"mechanism.links.2.length": 0.12, "mechanism.links.3.length": 0.12,
             "initial.theta1": 0.0, "initial.theta2": np.pi}  # l3 + l4 = 0.24 m
    scene = fivebar.load_scene(root / "datasets/scenes/paper.yaml", overrides=short)
    theta = np.array([[0.0, np.pi], [np.pi / 2, np.pi / 2]])  # row 1: |BD| = 0.29 m
    zeros = np.zeros((2, 2))
    with pytest.raises(ValueError, match=r"^theta: row 1: the mechanism cannot assemble at "
                                         r"theta1 = 1.5707963267948966, theta2 = 1.57079"):
        fivebar.inverse(scene, theta, zeros, zeros)
    with pytest.raises(ValueError, match=r"^omega: row 0: expected finite numbers$"):
        fivebar.inverse(scene, theta, np.full((2, 2), np.nan), zeros)


def test_a_pose_held_still_gets_its_equilibrium_torques(paper_scene):
    # rates of +-1e-14 rad/s are rounding, not slip: the rest rule of `fivebar inverse`
    # (docs/hold.md) holds the pose with the frictionless equilibrium torques on every row
    rng = np.random.default_rng(0)
    theta = np.full((11, 2), np.pi / 2)
    omega = rng.choice([-1.0, 1.0], (11, 2)) * 1e-14
    alpha = rng.choice([-1.0, 1.0], (11, 2)) * 1e-13
    M = fivebar.inverse(paper_scene, theta, omega, alpha)["M"]
    assert np.allclose(M, [-0.6917339630, -1.4378948566], atol=1e-9)
