"""Bad input raises ValueError with the command line's one-line message; failed numerics raise
fivebar.NumericalError (the command line's exit status 3)."""
import subprocess
import tempfile

import pytest

import fivebar

PAPER = "datasets/scenes/paper.yaml"


def cli_error(cli, root, *args):
    """Exit status and the message of `fivebar: error: <message>` for a command line."""
    if cli is None:
        pytest.skip("the fivebar executable is not built")
    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run([cli, *args, "--out", out], cwd=root, capture_output=True,
                              text=True, timeout=120)
    lines = done.stderr.strip().splitlines()
    assert lines and lines[-1].startswith("fivebar: error: "), done.stderr
    return done.returncode, lines[-1][len("fivebar: error: "):]


SCENE_CASES = [
    ("missing.yaml", {}),
    (PAPER, {"mechanism.links.2.mass": -1.0}),
    (PAPER, {"mechanism.links.7.mass": 1.0}),
    (PAPER, {"friction.coulomb": [0.1, 0.2]}),
    (PAPER, {"friction.nonsense": 1.0}),
    (PAPER, {"loads.M1": "2 + sin("}),
    (PAPER, {"simulation.integrator": "euler"}),
    (PAPER, {"mechanism.links.2.length": 0.12, "mechanism.links.3.length": 0.12}),
]


@pytest.mark.parametrize("path, overrides", SCENE_CASES)
def test_scene_errors_match_the_command_line(cli, root, path, overrides):
    with pytest.raises(ValueError) as python_error:
        fivebar.load_scene(root / path if path == PAPER else path, overrides=overrides)
    sets = []
    for key, value in overrides.items():
        if isinstance(value, list):
            value = "[" + ", ".join(repr(v) for v in value) + "]"
        elif isinstance(value, float):
            value = repr(value)
        sets += ["--set", f"{key}={value}"]
    status, message = cli_error(cli, root, "simulate", path, *sets)
    assert status == 2
    expected = message.replace(PAPER, str(root / PAPER)) if path == PAPER else message
    assert str(python_error.value) == expected


def test_identify_errors_match_the_command_line(cli, root, paper_scene):
    with pytest.raises(ValueError) as bad_law:
        fivebar.identify(paper_scene, root / "datasets/logs/paper_rates.csv", law="lugre")
    status, message = cli_error(cli, root, "identify", PAPER, "--log",
                                "datasets/logs/paper_rates.csv", "--law", "lugre")
    assert status == 2 and str(bad_law.value) == message
    with pytest.raises(ValueError) as missing:
        fivebar.identify(paper_scene, "no_such_log.csv")
    status, message = cli_error(cli, root, "identify", PAPER, "--log", "no_such_log.csv")
    assert status == 2 and str(missing.value) == message
    with pytest.raises(ValueError) as not_a_number:
        fivebar.identify(paper_scene, root / "datasets/logs/paper_rates.csv", min_rate=float("nan"))
    status, message = cli_error(cli, root, "identify", PAPER, "--log",
                                "datasets/logs/paper_rates.csv", "--min-rate", "nan")
    assert status == 2 and str(not_a_number.value) == message


def test_optimize_errors_match_the_command_line(cli, root, paper_scene):
    tasks = "datasets/tasks/paper_tasks.yaml"
    with pytest.raises(ValueError) as bad_method:
        fivebar.optimize(paper_scene, root / tasks, method="newton")
    status, message = cli_error(cli, root, "optimize", PAPER, "--tasks", tasks,
                                "--method", "newton")
    assert status == 2 and str(bad_method.value) == message
    with pytest.raises(ValueError) as missing:
        fivebar.optimize(paper_scene, "no_such_tasks.yaml")
    status, message = cli_error(cli, root, "optimize", PAPER, "--tasks", "no_such_tasks.yaml")
    assert status == 2 and str(missing.value) == message


def test_overrides_of_an_unusable_type(root):
    with pytest.raises(ValueError, match=r"^overrides: gravity: expected a number"):
        fivebar.load_scene(root / PAPER, overrides={"gravity": object()})


def test_numerical_failure_raises_numerical_error(cli, root):
    overrides = {"simulation.max_steps": 1}
    scene = fivebar.load_scene(root / PAPER, overrides=overrides)
    with pytest.raises(fivebar.NumericalError) as python_error:
        fivebar.simulate(scene)
    assert isinstance(python_error.value, RuntimeError)
    status, message = cli_error(cli, root, "simulate", PAPER, "--set", "simulation.max_steps=1",
                                "--no-plots")
    assert status == 3
    assert str(python_error.value) == message.replace(PAPER, str(root / PAPER))
