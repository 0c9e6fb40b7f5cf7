"""Snapshots of a run over ranks in pieces (issue 42, item 3; ``parallel.snapshots``): on 2
ranks each .pvtu's pieces hold every particle exactly once, read back they are the run's
particles, and a restart on one process keeps the pieces it continues after. Run from the
one-process invocation of ``make test-mpi`` (it starts mpirun itself); skipped where
mpirun or the MPI environment is missing, and under mpirun."""

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES, mpmflow_on_ranks
from meshio import vtu

import mpmflow
from mpmflow import checkpoint
from mpmflow.output.snapshots import read_index, read_pvtu

pytest.importorskip("petsc4py")
mpi = pytest.importorskip("mpi4py.MPI")
if mpi.COMM_WORLD.size > 1 or shutil.which("mpirun") is None:
    pytest.skip("starts mpirun itself: run on one process", allow_module_level=True)

SETTINGS = [
    "--set",
    "time.end=0.03",
    "--set",
    "output.interval=0.01",
    "--set",
    "output.snapshot_interval=0.01",
    "--set",
    "checkpoint.interval=0.01",
]


def run(ranks: int, out: Path, *extra: str) -> None:
    done = mpmflow_on_ranks(
        ranks, "run", EXAMPLES / "dam_break.toml", "--out", out, "-q", *SETTINGS, *extra
    )
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    out = tmp_path_factory.mktemp("pieces") / "two"
    run(2, out)
    return out


def test_each_pvtu_holds_every_particle_once(two):
    entries, complete = read_index(two / "particles.pvd")
    assert complete and [t for t, _ in entries] == pytest.approx([0, 0.01, 0.02, 0.03])
    count = mpmflow.open_run(two).summary["particles"]
    for _, name in entries:
        assert name.endswith(".pvtu")
        root = ET.parse(two / name).getroot()  # well-formed XML, as ParaView reads it
        assert root.get("type") == "PUnstructuredGrid"
        pieces = read_pvtu(two / name)
        assert len(pieces) == 2  # one a rank: the dam break's water is split in two
        ids = np.concatenate([vtu.read(two / p).point_data["id"] for p in pieces])
        assert ids.size == count and np.array_equal(np.sort(ids), np.arange(count))
    # no file of every particle: the pieces are the ranks' own
    assert not list(two.glob("particles_??????.vtu"))


def test_the_pieces_read_back_are_the_runs_particles(two):
    last = mpmflow.open_run(two).snapshots[-1].read()
    saved = checkpoint.read(two / "checkpoint_000000030.npz")[0]
    assert np.array_equal(last["x"], saved["x"])
    assert np.array_equal(last["velocity"], saved["v"])
    assert np.array_equal(last["mass"], saved["mass"])


def test_a_restart_on_one_process_keeps_the_pieces_before_it(two, tmp_path):
    again = tmp_path / "again"
    shutil.copytree(two, again)
    (again / "checkpoint_000000030.npz").unlink()  # continue from t = 0.02 s
    (again / "summary.json").unlink()
    run(1, again, "--restart")
    entries, complete = read_index(again / "particles.pvd")
    names = [f for _, f in entries]
    assert complete and names[:3] == [f"particles_00000{k}.pvtu" for k in range(3)]
    assert names[3] == "particles_000003.vtu"  # one process writes one file
    assert not (again / "particles_000003.pvtu").exists()
    assert not list(again.glob("particles_000003_r*.vtu"))
    snaps = mpmflow.open_run(again).snapshots
    a, b = snaps[2].read(), mpmflow.open_run(two).snapshots[2].read()
    assert np.array_equal(a["x"], b["x"])  # the pieces kept, as written
    # the step after the restart: to the pressure solver's tolerance
    c, d = snaps[3].read(), mpmflow.open_run(two).snapshots[3].read()
    assert np.abs(c["x"] - d["x"]).max() < 1e-8
