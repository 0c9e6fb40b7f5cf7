"""``mpirun -n N mpmflow run``: the command line over 4 and 2 ranks against one process,
and a run written on 4 ranks continued on 2 (``parallel.run``). Run from the one-process
invocation of ``make test-mpi`` (it starts mpirun itself); skipped where mpirun or the MPI
environment is missing, and under mpirun.

Tolerances: the acceptance's 0.002 a (a = 0.114 m, the column's width) for the surge front
and the column height against one process; the restart to the pressure solver's tolerance
(relative 1e-8; the particles then agree to far better than 1e-8 m)."""

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES, mpmflow_on_ranks

from mpmflow import checkpoint, load_case
from mpmflow.simulation import Simulation

pytest.importorskip("petsc4py")
mpi = pytest.importorskip("mpi4py.MPI")
if mpi.COMM_WORLD.size > 1 or shutil.which("mpirun") is None:
    pytest.skip("starts mpirun itself: run on one process", allow_module_level=True)

A = 0.114  # m


def sets(*settings: str) -> list[str]:
    """``--set KEY=VALUE`` for each setting."""
    return [word for setting in settings for word in ("--set", setting)]


# two chunks of 0.1 s, a checkpoint at each end
TIMES = ("time.end=0.2", "checkpoint.interval=0.1", "output.snapshots=false")
# shallow_fraction = 0.3: the sub-cell surface's shallow nodes at every step (by default
# only at small steps), decided by their owners and sent to the halo with their pressure
SETTINGS = sets("solver.shallow_fraction=0.3", "solver.volume_correction=0", *TIMES)


def mpirun(ranks: int, out: Path, *extra: str) -> None:
    done = mpmflow_on_ranks(
        ranks, "run", EXAMPLES / "dam_break.toml", "--out", out, "-q", *SETTINGS, *extra
    )
    assert done.returncode == 0, done.stderr[-3000:]


def series(folder: Path, name: str) -> np.ndarray:
    with open(folder / "timeseries.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    return np.array([float(r[name]) for r in rows])


@pytest.fixture(scope="module")
def four(tmp_path_factory):
    out = tmp_path_factory.mktemp("mpi") / "four"
    mpirun(4, out)
    return out


def test_four_ranks_follow_one_process(four):
    over = [s for s in SETTINGS if s != "--set"]
    one = Simulation(load_case(EXAMPLES / "dam_break.toml", over))
    one.run()
    for name in ("front", "height"):
        assert series(four, name).size == one.series(name).size == 21
        assert np.abs(series(four, name) - one.series(name)).max() <= 0.002 * A
    summary = (four / "summary.json").read_text()
    assert '"ranks": 4' in summary
    # each rank's memory estimate (parallel.memory), the split the run made
    per_rank = json.loads(summary)["memory_estimate_bytes"]["per_rank"]
    assert per_rank["ranks"] == 4 and len(per_rank["per_rank"]) == 4
    # at the start (the run's own counts are at its end, after the particles moved)
    particles = sum(json.loads(summary)["mpi"]["particles"])
    assert sum(r["counts"]["particles"] for r in per_rank["per_rank"]) == particles
    # the water's run along the floor unbalanced the boxes: split again, the particles sent
    # from their parts to their new ranks (the front and height above followed one process)
    assert json.loads(summary)["mpi"]["splits"] > 1


def test_no_rank_writes_the_whole_run_into_a_checkpoint(four):
    """A checkpoint of 4 ranks is a main file of the grid's arrays and the meta, and one
    piece a rank of its own particles, each particle in one piece."""
    main = four / "checkpoint_000000200.npz"
    with np.load(main) as data:
        assert "x" not in data.files and "scheme.p_node" in data.files
    meta = checkpoint.read(main)[1]
    assert meta["pieces"] == 4
    ids = []
    for rank in range(4):
        with np.load(checkpoint.piece_path(main, rank)) as piece:
            assert 0 < piece["x"].shape[0] < meta["particles"]  # a part, not the run
            ids.append(piece[checkpoint.NUMBERS])
    every = np.sort(np.concatenate(ids))
    assert np.array_equal(every, np.arange(meta["particles"]))
    # the two checkpoints of the run (t = 0.1 s and its end), each with its pieces
    assert sorted(p.name for p in four.glob("checkpoint_*.npz")) == [
        f"checkpoint_000000{s}{r}.npz"
        for s in ("100", "200")
        for r in ("", *(f"_r000{k}" for k in range(4)))
    ]


def test_a_run_written_on_four_ranks_continues_on_two(four, tmp_path):
    again = tmp_path / "again"
    shutil.copytree(four, again)
    (again / "checkpoint_000000200.npz").unlink()  # continue from t = 0.1 s
    (again / "summary.json").unlink()
    mpirun(2, again, "--restart")
    a = checkpoint.read(four / "checkpoint_000000200.npz")[0]
    b = checkpoint.read(again / "checkpoint_000000200.npz")[0]
    assert np.abs(a["x"] - b["x"]).max() < 1e-8  # m
    assert np.array_equal(a["mass"], b["mass"])
    assert np.abs(series(four, "front") - series(again, "front")).max() < 1e-8


def test_a_one_process_run_with_apic_continues_on_two_ranks(tmp_path):
    """A one-process checkpoint (one file of the whole run) read on every rank, each
    keeping its own particles and their affine matrices at its first split: the run's end
    is the one-process run's, to the pressure solves' tolerance."""
    apic = ("--set", "solver.transfer=apic")
    one = tmp_path / "one"
    mpirun(1, one, *apic)
    again = tmp_path / "again"
    shutil.copytree(one, again)
    (again / "checkpoint_000000200.npz").unlink()  # continue from t = 0.1 s
    (again / "summary.json").unlink()
    mpirun(2, again, "--restart", *apic)
    a = checkpoint.read(one / "checkpoint_000000200.npz")[0]
    b = checkpoint.read(again / "checkpoint_000000200.npz")[1]["pieces"]
    assert b == 2  # written on the ranks, in pieces
    b = checkpoint.read(again / "checkpoint_000000200.npz")[0]
    assert np.abs(a["x"] - b["x"]).max() < 1e-8  # m
    # the affine matrices (1/s) as test_scheme bounds them: C h within 1e-5 m/s
    assert np.abs(a["scheme.affine"] - b["scheme.affine"]).max() * 0.004 < 1e-5


@pytest.mark.parametrize("extra", [["--restart"], []])
def test_a_refusal_of_rank_0_alone_stops_every_rank(tmp_path, extra):
    """No checkpoint to continue from, or a folder that holds another run: rank 0 alone
    finds it, and every rank stops with its message (exit 2) instead of the others
    waiting for ever in their next collective call."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "timeseries.csv").write_text("time\n")  # the folder holds a run's outputs
    done = mpmflow_on_ranks(
        2, "run", EXAMPLES / "dam_break.toml", "--out", out, "-q", *extra, timeout=120
    )
    assert done.returncode == 2, done.stderr[-2000:]
    said = "holds no checkpoint" if extra else "already holds the results of a run"
    assert said in done.stderr and "Traceback" not in done.stderr


# a free box in water 0.1 m deep, straddling the ranks' cut (tests/parallel/test_split_bodies.py)
FLOAT = sets(
    "domain.size=[0.2, 0.15]",
    "bodies.0.max=[0.2, 0.1]",
    "bodies.0.around_obstacles=true",
    "obstacles=[{type='box', min=[0.08, 0.085], max=[0.12, 0.125], "
    "motion={type='free', density=500.0}}]",
    *TIMES,
)


@pytest.fixture(scope="module")
def floating(tmp_path_factory):
    """A free box (tests/parallel/test_split_bodies.py) run on 2 ranks to 0.2 s, a
    checkpoint at 0.1 s and at the end; and the end's file name."""
    two = tmp_path_factory.mktemp("floating") / "two"
    done = mpmflow_on_ranks(2, "run", EXAMPLES / "hydrostatic.toml", "--out", two, "-q", *FLOAT)
    assert done.returncode == 0, done.stderr[-3000:]
    last = max(p.name for p in two.glob("checkpoint_*.npz") if "_r" not in p.name)
    return two, last


def continued(floating, again: Path, ranks: int) -> tuple[dict, dict]:
    """The floating run continued from its checkpoint at 0.1 s on ``ranks`` ranks: the
    end's checkpoint arrays of the first run and of the continued one."""
    two, last = floating
    shutil.copytree(two, again)
    for f in again.glob(last.replace(".npz", "*")):
        f.unlink()
    (again / "summary.json").unlink()
    done = mpmflow_on_ranks(
        ranks, "run", EXAMPLES / "hydrostatic.toml", "--out", again, "-q", "--restart", *FLOAT
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return checkpoint.read(two / last)[0], checkpoint.read(again / last)[0]


def test_a_floating_body_written_on_two_ranks_continues_on_one(floating, tmp_path):
    """The floating run continued on one process from the checkpoint at 0.1 s: its body
    state (pose, velocity) is in the checkpoint, and the continued run ends where the 2
    ranks' does, to the solves' tolerance (the body's height 1e-8 m, the particles' places
    1e-8 m)."""
    a, b = continued(floating, tmp_path / "again", 1)
    assert a["scheme.body_state"][0, 1] < 0.105 - 1e-3  # m: the box sank from its start
    assert np.abs(a["scheme.body_state"] - b["scheme.body_state"]).max() < 1e-8
    assert np.abs(a["x"] - b["x"]).max() < 1e-8  # m


def test_a_floating_body_written_on_two_ranks_continues_on_two_to_the_bit(floating, tmp_path):
    """Continued on the same 2 ranks, the run is the one that never stopped (issue 44's
    "restart bit-identical"): the same boxes, the same solves in the same order, so the
    body's state and every particle's place, velocity and pressure are equal to the bit."""
    a, b = continued(floating, tmp_path / "again", 2)
    for key in ("scheme.body_state", "x", "v", "pressure", "volume"):
        assert np.array_equal(a[key], b[key]), key
