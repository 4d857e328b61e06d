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


def test_warnings_are_not_printed_and_filter_into_errors(root, capfd):
    overrides = {"initial.theta1": 90.0}  # degrees given as radians
    with pytest.warns(fivebar.FivebarWarning, match="degrees"):
        fivebar.load_scene(root / "datasets/scenes/paper.yaml", overrides=overrides)
    assert capfd.readouterr().err == ""  # warnings.warn only: the library prints nothing
    with warnings.catch_warnings():
        warnings.simplefilter("error", fivebar.FivebarWarning)
        with pytest.raises(fivebar.FivebarWarning, match="initial.theta1"):
            fivebar.load_scene(root / "datasets/scenes/paper.yaml", overrides=overrides)


def test_overrides_take_numpy_values(paper_scene):
    for value in (np.float32(0.5), np.float64(0.5), np.array(0.5)):
        assert paper_scene.replace(simulation__duration=value).duration == 0.5
    per_joint = paper_scene.replace(friction__coulomb=np.full(5, 0.1))
    assert per_joint.sets == ["friction.coulomb=[0.1, 0.1, 0.1, 0.1, 0.1]"]
    with pytest.raises(ValueError, match=r"simulation.duration: must be a finite number"):
        paper_scene.replace(simulation__duration=np.nan)


def test_a_scene_from_a_dict_errors_without_line_numbers():
    with pytest.raises(ValueError) as error:
        fivebar.parse_scene({"mechanism": {"ground_length": "x"}}, name="mine")
    assert str(error.value).startswith("mine: mechanism.ground_length: expected a number")
    assert "(line" not in str(error.value)


def test_scenes_and_results_pickle(paper_scene):
    import pickle
    short = paper_scene.replace(simulation__duration=0.1)
    again = pickle.loads(pickle.dumps(short))
    assert again.to_yaml() == short.to_yaml()
    assert (again.path, again.sets) == (short.path, short.sets)
    run = fivebar.simulate(again)
    copy = pickle.loads(pickle.dumps(run))
    assert isinstance(copy, fivebar.Record) and copy.summary.rows == run.summary.rows
    assert isinstance(run.copy(), fivebar.Record)


def test_results_as_json(paper_scene, root):
    import json
    run = fivebar.simulate(paper_scene, duration=0.05)
    with pytest.raises(TypeError):  # NumPy arrays: json.dumps alone refuses them
        json.dumps(run)
    back = json.loads(run.to_json())
    assert back["theta1"] == run.theta1.tolist() and back["summary"]["rows"] == run.summary.rows
    assert json.dumps(run.summary)  # a record of plain numbers dumps as it is
    record = fivebar.Record(x=np.array([1.0, np.nan]), s=paper_scene, n=np.float32(2.0))
    assert json.loads(record.to_json()) == {"x": [1.0, None], "s": paper_scene.to_yaml(),
                                            "n": 2.0}


def test_a_log_of_arrays_is_checked_by_row_and_column(paper_scene):
    t = np.arange(50) * 1e-3
    log = {"t": t, "theta1": np.full(50, 1.5), "theta2": np.full(50, 1.6),
           "tau1": np.zeros(50), "tau2": np.zeros(50)}
    tau1 = np.zeros(50)
    tau1[7] = np.nan
    with pytest.raises(ValueError, match=r"^log: row 7, column tau1: 'nan' is not a finite"):
        fivebar.identify(paper_scene, dict(log, tau1=tau1))
    with pytest.raises(ValueError, match=r"^log: tau2: \(argument\): expected a 1-D array"):
        fivebar.identify(paper_scene, dict(log, tau2=np.zeros((50, 2))))
    with pytest.raises(ValueError, match=r"^log: columns: unknown column 'tau3'"):
        fivebar.identify(paper_scene, dict(log, tau3=np.zeros(50)))


@pytest.mark.parametrize("option, value", [("min_rate", float("nan")), ("min_rate", -1.0),
                                           ("smooth_sign", float("nan")), ("smooth_sign", -0.5)])
def test_identify_refuses_an_option_out_of_range(paper_scene, root, option, value):
    with pytest.raises(ValueError, match="--" + option.replace("_", "-") + ": must be >= 0"):
        fivebar.identify(paper_scene, root / "datasets/logs/paper_angles.csv", **{option: value})


def test_the_stub_names_what_the_module_has():
    import ast
    package = pathlib.Path(fivebar.__file__).parent
    stub = ast.parse((package / "__init__.pyi").read_text())
    defined = {node.name: node for node in stub.body
               if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    public = {name for name in dir(fivebar) if not name.startswith("_")}
    assert set(fivebar.__all__) == set(defined) <= public
    for name, node in defined.items():
        if isinstance(node, ast.ClassDef):
            methods = {f.name for f in node.body if isinstance(f, ast.FunctionDef)}
            assert all(hasattr(getattr(fivebar, name), m) for m in methods), name
            continue
        args = node.args
        stubbed = [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs]
        real = inspect.signature(getattr(fivebar, name)).parameters
        named = [p for p, v in real.items() if v.kind != inspect.Parameter.VAR_KEYWORD]
        assert stubbed[:len(named)] == named, name  # identify's stub names its **options


def test_a_log_as_a_structured_array(paper_scene, root):
    path = root / "datasets/logs/paper_angles.csv"
    comments = sum(line.startswith("#") for line in path.read_text().splitlines())
    table = np.genfromtxt(path, delimiter=",", names=True, skip_header=comments)
    from_table = fivebar.identify(paper_scene, table)
    from_file = fivebar.identify(paper_scene, path)
    assert from_table.parameters["coulomb"].value == from_file.parameters["coulomb"].value
    with pytest.raises(ValueError, match="structured array with named columns"):
        fivebar.identify(paper_scene, np.zeros((10, 5)))
