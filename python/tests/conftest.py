"""Shared cases of the Python package's tests: the repository's own examples and decks."""

import os
import pathlib
import shutil
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
DECKS = REPO / "crates" / "grainflow-case" / "tests" / "mfix_decks"


def ball_case(integrator="velocity_verlet", t_stop=0.5, dt=1.0e-4, height=0.5, en=0.9, gravity=-9.81):
    """One 0.2 m ball in a 1 m box (MFIX's DEM01/02 set-up) as a dict of case tables."""
    return {
        "version": 1,
        "title": "ball",
        "domain": {"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
        "physics": {"gravity": [0.0, 0.0, gravity]},
        "phases": [{"name": "ball", "diameter": 0.2, "density": 2600.0}],
        "contact": {"model": "lsd", "particle": {"kn": 5.0e4}, "wall": {"kn": 5.0e4, "en": en}},
        "time": {"t_stop": t_stop, "dt": dt, "integrator": integrator},
        "output": {"interval": 0.01, "snapshots": False},
        "particles": {"list": [{"phase": "ball", "position": [0.5, 0.5, height]}]},
    }


def bits(a):
    """The bit patterns of an array of float64, for comparisons to the bit."""
    import numpy as np

    return np.ascontiguousarray(a).view(np.uint64).copy()


def assert_last_snapshot_is(out, sim):
    """The last CSV snapshot of the run folder `out` holds the particles of `sim`, positions
    to the bit."""
    import numpy as np

    last = sorted((out / "snapshots").iterdir())[-1]
    table = np.genfromtxt(last, delimiter=",", names=True)
    order = np.argsort(sim.particles.ids)
    x = np.asarray(sim.particles.position)[order]
    np.testing.assert_array_equal(table["id"], np.sort(sim.particles.ids))
    for k, name in enumerate("xyz"):
        np.testing.assert_array_equal(bits(table[name]), bits(x[:, k]))


@pytest.fixture
def settling_bed():
    """The settling-bed example (486 glass beads, linear spring-dashpot), shortened."""
    return EXAMPLES / "settling-bed" / "case.toml"


def cli_binary():
    """The `grainflow` program of this clone: $GRAINFLOW_BIN, or target/release/grainflow."""
    path = os.environ.get("GRAINFLOW_BIN") or str(REPO / "target" / "release" / "grainflow")
    if not os.path.isfile(path):
        found = shutil.which("grainflow")
        if found is None:
            pytest.fail(
                f"needs the grainflow program: build it (cargo build --release) or set GRAINFLOW_BIN; not at {path}"
            )
        path = found
    return path


def run_cli(*args):
    return subprocess.run([cli_binary(), *map(str, args)], capture_output=True, text=True, check=False)
