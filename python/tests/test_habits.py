"""Python habits: results with attributes, parameters by name, Scene.replace, keyword overrides,
warnings through warnings.warn, signatures and type stubs."""
import inspect
import pathlib
import warnings

import numpy as np
import pytest

import fivebar


def test_results_read_as_attributes_and_keys(paper_run):
    assert paper_run.theta1 is paper_run["theta1"]
    assert paper_run.summary.steps == paper_run["summary"]["steps"]
    assert paper_run.summary.status == "ok" and paper_run.summary.target_met
    with pytest.raises(AttributeError, match="no field 'nonsense'"):
        paper_run.nonsense


def test_scene_replace_changes_a_copy(paper_scene):
    short = paper_scene.replace({"simulation.duration": 0.25})
    same = paper_scene.with_(simulation__duration=0.25)
    assert short.duration == same.duration == 0.25
    assert paper_scene.duration == 2.0
    assert short.sets == ["simulation.duration=0.25"]
    assert short.path == paper_scene.path
    heavier = short.replace({"mechanism.links.2.mass": 1.5})
    assert "mass: 1.5" in heavier.to_yaml() and heavier.duration == 0.25
    with pytest.raises(ValueError, match=r"simulation.duration: .*> 0"):
        paper_scene.replace(simulation__duration=-1.0)


def test_a_scene_built_from_a_dict(paper_scene):
    link = {"length": 0.25, "mass": 1.0, "inertia": 0.1, "com_offset": 0.2}
    data = {"mechanism": {"ground_length": 0.29, "point_p": 0.2,
                          "links": [dict(link, length=0.08, com_offset=0.05),
                                    dict(link, length=0.05, com_offset=0.03), link,
                                    dict(link, com_offset=0.15)]},
            "friction": {"model": "coulomb_viscous", "pin_radius": 0.01, "coulomb": 0.12,
                         "viscous": np.float64(0.02)},
            "loads": {"M1": "2 + 5*sin(8*pi*t)", "M2": "3 + 5*cos(pi*t)", "M3": "6", "F": "50",
                      "F_angle": np.pi / 2},
            "initial": {"theta1": np.pi / 2, "theta2": np.pi / 2}}
    scene = fivebar.parse_scene(data, name="mine")
    assert scene.to_yaml() == paper_scene.to_yaml()
    data["mechanism"]["links"][0]["mass"] = -1.0
    with pytest.raises(ValueError, match=r"^mine: mechanism.links.0.mass: "):
        fivebar.parse_scene(data, name="mine")


def test_simulate_takes_simulation_keywords(paper_scene):
    run = fivebar.simulate(paper_scene, duration=0.2, output_step=0.01)
    assert run.t[-1] == pytest.approx(0.2) and len(run.t) == 21
    assert run.summary.duration == 0.2
    assert run.summary.sets == ["simulation.duration=0.2", "simulation.output_step=0.01"]
    with pytest.raises(ValueError, match="simulation.nonsense"):
        fivebar.simulate(paper_scene, nonsense=1)


def test_parameters_by_name_and_in_order(root, paper_scene):
    fit = fivebar.identify(paper_scene, root / "datasets/logs/paper_rates.csv")
    assert fit.parameters.keys() == ["coulomb", "viscous"]
    assert fit.parameters["viscous"] is fit.parameters[1]
    assert "coulomb" in fit.parameters and "mu" not in fit.parameters
    coulomb = fit.parameters["coulomb"]
    assert coulomb.value == coulomb["value"] and coulomb.std > 0 and isinstance(coulomb.unit, str)
    assert coulomb.error == pytest.approx(coulomb.value - coulomb.true)
    assert fit.condition_number > 1 and fit.residual_to_noise_ratio.shape == (2,)
    assert fit.model_check and all(isinstance(c.cause, str) for c in fit.model_check)
    with pytest.raises(KeyError, match="no parameter 'mu'"):
        fit.parameters["mu"]


def test_warnings_go_through_warnings_warn(root):
    with pytest.warns(fivebar.FivebarWarning, match="mass"):
        fivebar.load_scene(root / "datasets/scenes/paper.yaml",
                           overrides={"mechanism.links.0.mass": 5.0e4})


def test_signatures_and_stubs():
    assert list(inspect.signature(fivebar.simulate).parameters)[:2] == ["scene", "overrides"]
    assert list(inspect.signature(fivebar.inverse).parameters) == [
        "scene", "theta", "omega", "alpha", "t", "threads"]
    package = pathlib.Path(fivebar.__file__).parent
    assert (package / "py.typed").exists()
    stub = (package / "__init__.pyi").read_text()
    for name in fivebar.__all__:
        assert name in stub, name
