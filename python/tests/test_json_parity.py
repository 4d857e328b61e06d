"""Every field of the command line's JSON outputs is in the Python results.

Walks identification.json (identify) and summary.json (simulate) written by the `fivebar`
executable, and looks each field up, at the same place, in what fivebar.identify and
fivebar.simulate return. `python3 test_json_parity.py` prints the missing fields.
"""
import json
import subprocess
import sys

import pytest

import fivebar


def fields(value, prefix=""):
    """Dotted paths of every object member in `value` (list elements as [i])."""
    if isinstance(value, dict):
        for key, item in value.items():
            path = f"{prefix}.{key}" if prefix else key
            yield path
            yield from fields(item, path)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from fields(item, f"{prefix}[{i}]")


def lookup(value, path):
    """The member at `path` in `value`, or raises KeyError/IndexError."""
    for part in path.replace("[", ".[").split("."):
        if part.startswith("["):
            value = value[int(part[1:-1])]
        elif isinstance(value, dict):
            value = value[part]
        else:
            raise KeyError(part)
    return value


def missing(json_record, python_result):
    out = []
    for path in fields(json_record):
        try:
            lookup(python_result, path)
        except (KeyError, IndexError, TypeError):
            out.append(path)
    return out


def cli_json(cli, args, out_dir, name):
    subprocess.run([cli, *args, "--out", str(out_dir), "--no-plots"], check=True,
                   capture_output=True, text=True)
    return json.loads((out_dir / name).read_text())


IDENTIFY_CASES = {
    "rates in the log, validation": ("paper_rates.csv", [], {"validate": True}),
    "angles only, Huber loss": ("paper_angles.csv", ["--loss", "huber", "--no-validation"],
                                {"loss": "huber"}),
}


@pytest.mark.parametrize("case", IDENTIFY_CASES)
def test_identify_has_every_field_of_identification_json(root, paper_scene, cli, tmp_path, case):
    if cli is None:
        pytest.skip("no fivebar executable")
    log, args, options = IDENTIFY_CASES[case]
    path = root / "datasets" / "logs" / log
    record = cli_json(cli, ["identify", str(root / "datasets/scenes/paper.yaml"), "--log",
                            str(path), *args], tmp_path, "identification.json")
    with pytest.warns() if record["warnings"] else _no_warning():
        result = fivebar.identify(paper_scene, path, **options)
    assert missing(record, result) == []
    assert record["truth_in_log"] and result.truth_in_log
    assert result.parameters["coulomb"].true == record["parameters"][0]["true"]


def test_simulate_has_every_field_of_summary_json(root, cli, tmp_path):
    if cli is None:
        pytest.skip("no fivebar executable")
    scene = root / "datasets/scenes/paper.yaml"
    record = cli_json(cli, ["simulate", str(scene), "--set", "simulation.duration=0.5"], tmp_path,
                      "summary.json")
    run = fivebar.simulate(fivebar.load_scene(scene), duration=0.5, twin=True)
    assert missing(record, run.summary) == []
    assert run.summary.sets == record["sets"]
    assert run.summary.estimated_max_error_rad == pytest.approx(
        record["estimated_max_error_rad"], rel=1e-6)


class _no_warning:
    def __enter__(self):
        import warnings
        self._catch = warnings.catch_warnings()
        self._catch.__enter__()
        warnings.simplefilter("error", fivebar.FivebarWarning)

    def __exit__(self, *exc):
        self._catch.__exit__(*exc)


if __name__ == "__main__":  # the missing fields, for a report: CLI Python
    import pathlib
    import tempfile
    cli_path, root = sys.argv[1], pathlib.Path(sys.argv[2])
    scene_path = root / "datasets/scenes/paper.yaml"
    scene = fivebar.load_scene(scene_path)
    with tempfile.TemporaryDirectory() as d:
        for case, (log, args, options) in IDENTIFY_CASES.items():
            out = pathlib.Path(d) / case.replace(" ", "_")
            record = cli_json(cli_path, ["identify", str(scene_path), "--log",
                                         str(root / "datasets/logs" / log), *args], out,
                              "identification.json")
            result = fivebar.identify(scene, str(root / "datasets/logs" / log), **options)
            gone = missing(record, result)
            print(f"identify ({case}): {len(gone)} of {len(list(fields(record)))} missing:",
                  " ".join(gone))
        out = pathlib.Path(d) / "simulate"
        record = cli_json(cli_path, ["simulate", str(scene_path), "--set",
                                     "simulation.duration=0.5"], out, "summary.json")
        short = fivebar.load_scene(scene_path, {"simulation.duration": 0.5})
        try:
            run = fivebar.simulate(short, twin=True)
        except TypeError:  # a module without the twin
            run = fivebar.simulate(short)
        gone = missing(record, run["summary"])
        print(f"simulate: {len(gone)} of {len(list(fields(record)))} missing:", " ".join(gone))
