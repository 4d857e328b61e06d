"""Shared fixtures: the repository root, the paper scene and one simulation of it."""
import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(os.environ.get("FIVEBAR_SOURCE_DIR",
                                   pathlib.Path(__file__).resolve().parents[2]))
PAPER = ROOT / "datasets" / "scenes" / "paper.yaml"


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def paper_scene():
    import fivebar
    return fivebar.load_scene(PAPER)


@pytest.fixture(scope="session")
def paper_run(paper_scene):
    import fivebar
    return fivebar.simulate(paper_scene)


@pytest.fixture(scope="session")
def cli():
    """The `fivebar` executable of this build (ctest sets FIVEBAR_EXECUTABLE), or None."""
    exe = os.environ.get("FIVEBAR_EXECUTABLE") or shutil.which("fivebar")
    candidate = ROOT / "build" / "release" / "apps" / "fivebar"
    if not exe and candidate.exists():
        exe = str(candidate)
    return exe
