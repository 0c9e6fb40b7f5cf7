"""The memory of a run over ranks, per rank (``parallel.memory``; issue 42, item 4): the
split found from the geometry is the run's split, each term is its formula, and
``mpmflow run CASE --dry-run --ranks N`` prints the estimate of a case far beyond this
machine (10^8 particles on 64 ranks) at once, allocating nothing of its size. None of it
needs MPI: it runs in the one-process suite."""

import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import load_case, memory
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid
from mpmflow.parallel import memory as per_rank
from mpmflow.parallel.boxes import bisect, cell_weights
from mpmflow.parallel.subgrid import extended, subgrid

DAM_3D = EXAMPLES / "dam_break_3d.toml"
DAM_2D = EXAMPLES / "dam_break.toml"
# 100,111,614 particles, 964 x 92 x 1010 cells
HUGE = ["grid.spacing=0.000436"]


def plain_env(**extra):
    """This environment without an MPI launcher's variables: the commands below are one
    process even when the suite runs under mpirun (make test-mpi)."""
    launcher = ("OMPI_", "PMI_", "PMIX_", "SLURM_")
    env = {k: v for k, v in os.environ.items() if not k.startswith(launcher)}
    return dict(env, **extra)


@pytest.mark.parametrize(
    "path, overrides",
    [
        (DAM_3D, ["grid.spacing=0.008"]),
        (DAM_3D, ["grid.spacing=0.004"]),
        (DAM_2D, []),
        (EXAMPLES / "lobovsky.toml", []),
    ],
)
def test_the_split_from_the_geometry_is_the_runs_split(path, overrides):
    """The boxes the run makes from its seeded particles (``bisect`` on ``cell_weights``),
    and every rank's particles, from the bodies' lattice alone, at 1 to 9 ranks."""
    case = load_case(path, overrides)
    grid = Grid.of_case(case)
    x = build_particles(case, grid).x
    weights = cell_weights(x, grid.spacing, grid.cells)
    for ranks in range(1, 10):
        run = bisect(weights, ranks)
        est = per_rank.estimate(case, ranks)
        assert np.array_equal(est.boxes.lo, run.lo) and np.array_equal(est.boxes.hi, run.hi)
        owned = np.bincount(run.owner_of_points(x, grid.spacing), minlength=ranks)
        assert [r.particles for r in est.per_rank] == owned.tolist()
        assert not est.approximate


def test_each_term_is_its_formula():
    """The 3D dam break at 0.004 m on 3 ranks: each rank's terms from counts made here
    on the seeded particles and the run's own local grids."""
    case = load_case(DAM_3D, ["grid.spacing=0.004"])
    grid = Grid.of_case(case)
    x = build_particles(case, grid).x
    ranks = 3
    boxes = bisect(cell_weights(x, grid.spacing, grid.cells), ranks)
    est = per_rank.estimate(case, ranks)
    N = x.shape[0]
    fields = 8 * (2 * 3 + 3)  # x, v, pressure, mass, volume
    ijk = np.floor(x / grid.spacing).astype(int)
    one = memory.estimate(case)
    for r, mine in enumerate(est.per_rank):
        lo, hi = extended(boxes, r)
        in_box = np.all((ijk >= boxes.lo[r]) & (ijk < boxes.hi[r]), axis=1)
        in_ext = np.all((ijk >= lo) & (ijk < hi), axis=1)
        own, halo = int(in_box.sum()), int((in_ext & ~in_box).sum())
        assert (mine.particles, mine.halo) == (own, halo)
        assert mine.local_nodes == subgrid(grid, boxes, r).grid.nnodes
        # the unknowns: the owned nodes of the cells holding particles, with room to spread
        sub = subgrid(grid, boxes, r)
        nodes = np.stack(np.unravel_index(sub.node_global, grid.nodes, order="F"), 1)
        wet = np.all((nodes >= ijk.min(0)) & (nodes <= ijk.max(0) + 1), axis=1)
        seeded = int((wet & sub.owned_nodes).sum())
        assert mine.unknowns == min(int(sub.owned_nodes.sum()), memory.SPREAD * seeded)
        expected = {
            "program": per_rank.PROGRAM,
            "seeding (a chunk of the lattice)": min(N, 2**20) * fields + 24 * grid.ncells,
            "the whole grid's arrays": 24 * grid.nnodes,
            "own particles": per_rank.LOCAL_COPIES[3] * fields * own,
            "halo": per_rank.LOCAL_COPIES[3] * fields * halo,
            "local grid (box and ghost layer)": per_rank.LOCAL_PER_NODE[3] * mine.local_nodes,
            "pressure system (PETSc, hypre)": per_rank.PETSC_PER_UNKNOWN[3] * mine.unknowns,
            "time series": one.rows_bytes,
            "the measures at an output time": 24 * grid.nnodes,
        }
        assert mine.terms == pytest.approx(expected, rel=1e-12)
        assert mine.total == pytest.approx(sum(expected.values()), rel=1e-12)
    assert est.total == pytest.approx(sum(r.total for r in est.per_rank))


def test_apic_carries_its_matrices_in_every_copy():
    case = load_case(DAM_3D, ["grid.spacing=0.008"])
    apic = load_case(DAM_3D, ["grid.spacing=0.008", "solver.transfer='apic'"])
    a, b = per_rank.estimate(case, 2).per_rank[0], per_rank.estimate(apic, 2).per_rank[0]
    ratio = (72 + 72) / 72  # the fields and a 3 x 3 matrix of doubles
    for term in ("own particles", "halo"):
        assert b.terms[term] == pytest.approx(ratio * a.terms[term])


def test_a_body_that_is_not_a_box_is_told_approximate():
    case = load_case(EXAMPLES / "obstacle_2d.toml")
    est = per_rank.estimate(case, 2)
    assert est.approximate and "polygon" in est.approximate[0]
    # the particles are all counted, spread over the body's bounding box
    assert sum(r.particles for r in est.per_rank) == pytest.approx(est.particles)


def test_the_dry_run_of_a_case_beyond_this_machine_is_printed_at_once(tmp_path):
    """10^8 particles on 64 ranks: printed with each term of the largest rank, its peak
    memory that of the program (the child's VmHWM: the run would need tens
    of GB a rank, so nothing of the run was allocated), and nothing written. (It takes 0.2 s
    of work, measured in benchmarks' diary; a wall-clock bound here failed under load.)"""
    script = (
        "import sys\n"
        "from mpmflow.cli import main\n"
        f"code = main(['run', {str(DAM_3D)!r}, '--dry-run', '--ranks', '64', '--set', "
        f"{HUGE[0]!r}])\n"
        # VmHWM: this program's own peak (getrusage's ru_maxrss keeps the forking pytest
        # process's, hundreds of MB once other tests ran in it)
        "peak = next(int(line.split()[1]) for line in open('/proc/self/status')\n"
        "            if line.startswith('VmHWM:'))\n"
        "print('PEAK', peak * 1024)\n"
        "sys.exit(code)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
        env=plain_env(MPMFLOW_MEMORY_LIMIT="4G"),
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "100,111,614 particles" in out and "964 x 92 x 1010 cells" in out
    assert "memory per rank on 64 ranks: largest rank" in out
    for term in ("program", "seeding", "halo", "local grid", "pressure system"):
        assert term in out
    assert "the run does not fit here" in out
    peak = float(out.split("PEAK ")[1].split()[0])
    assert peak < 250 * 2**20, peak  # the program and the split's factors, no particles
    assert list(tmp_path.iterdir()) == []


def test_the_dry_run_on_one_process_is_the_one_process_estimate():
    done = subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", "run", str(DAM_2D), "--dry-run"],
        capture_output=True,
        text=True,
        timeout=60,
        env=plain_env(),
    )
    assert done.returncode == 0, done.stderr
    est = memory.estimate(load_case(DAM_2D))
    assert f"memory on one process: {est.text()}" in done.stdout
    assert "the run fits here" in done.stdout


@pytest.mark.parametrize(
    "args, words",
    [
        (["--out", "x", "--ranks", "2"], "--ranks 2 goes with --dry-run"),
        ([], "mpmflow run needs --out DIR"),
        (["--dry-run", "--ranks", "0"], "--ranks 0: give a number of processes of 1 or more"),
        (["--dry-run", "--ranks", "100000"], "run on fewer ranks"),
        (["--dry-run", "--ranks", "two"], "invalid int value"),
    ],
)
def test_bad_dry_run_arguments_are_refused(args, words, tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", "run", str(DAM_2D), *args],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
        env=plain_env(),
    )
    assert done.returncode == 2
    assert words in done.stderr and "Traceback" not in done.stderr
    assert list(tmp_path.iterdir()) == []
