"""Shared helpers: paths, a quick case builder, and the check for the reference data."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mpmflow.case import validate
from mpmflow.studies.reference_data import data_dir

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def make_case(
    size=(0.1, 0.3),
    spacing=0.01,
    body=((0.0, 0.0), (0.1, 0.2)),
    ppc=4,
    dt=1e-3,
    end=0.01,
    **sections,
):
    data = dict(
        domain=dict(size=list(size)),
        grid=dict(spacing=spacing),
        bodies=[dict(min=list(body[0]), max=list(body[1]), particles_per_cell=ppc)],
        time=dict(dt=dt, end=end),
        output=dict(interval=max(dt, 0.01)),
    )
    for key, value in sections.items():
        data.setdefault(key, {}).update(value)
    return validate(data)


# a small 2D case that runs two steps without snapshots: the input tests write it and change
# one thing (tests/case/)
TINY_CASE = """
[domain]
size = [0.2, 0.2]
[grid]
spacing = 0.02
[[bodies]]
min = [0.0, 0.0]
max = [0.1, 0.1]
[time]
dt = 1e-3
end = 2e-3
[output]
interval = 1e-3
snapshots = false
"""


@pytest.fixture
def tiny_case_file(tmp_path):
    """TINY_CASE written to tmp_path / "case.toml"."""
    path = tmp_path / "case.toml"
    path.write_text(TINY_CASE)
    return path


# water trapped between a disc and two walls: a sealed pocket at every step
# (tests/boundaries/test_obstacles.py, tests/state/)
POCKET_2D = """
title = "disc in the corner of a pool"
[domain]
size = [0.4, 0.4]
[grid]
spacing = 0.01
[[bodies]]
type = "box"
min = [0.0, 0.0]
max = [0.4, 0.2]
particles_per_cell = 2
around_obstacles = true
[[obstacles]]
type = "disc"
centre = [0.06, 0.06]
radius = 0.06
[physics]
gravity = [0.0, -9.81]
[time]
dt = 1e-3
end = 0.1
[output]
interval = 0.01
snapshots = false
"""


@pytest.fixture(scope="session")
def shared_data():
    """The reference data folder; a test that needs it fails (not skips) without it."""
    try:
        return data_dir()
    except FileNotFoundError as err:
        pytest.fail(str(err))


def mpmflow_on_ranks(ranks, *args, timeout=300):
    """`mpmflow ARGS` (this environment's command line) on ``ranks`` MPI processes under
    mpirun, one process without it; one thread each (Open MPI told it may run as root and
    on more ranks than cores). Returns the finished process, its output captured."""
    cli = Path(sys.executable).parent / "mpmflow"
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    env["OMP_NUM_THREADS"] = "1"
    command = ["mpirun", "--oversubscribe", "-n", str(ranks)] if ranks > 1 else []
    command += [str(cli), *(str(a) for a in args)]
    return subprocess.run(command, env=env, capture_output=True, text=True, timeout=timeout)
