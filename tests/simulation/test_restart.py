"""Checkpoints and restart: a continued run is the uninterrupted run, bit for bit."""

import json
import shutil
import signal

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.checkpoint import CheckpointError, checkpoints, piece_path, read, write_piece
from mpmflow.checkpoint import write as checkpoint_write
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.particles import Particles

COMMON = [
    "grid.spacing=0.01",
    "time.end=0.1",
    "checkpoint.interval=0.03",
    "output.snapshot_interval=0.02",
]
SCHEMES = {
    "projection": [],
    "apic": ["solver.transfer=apic"],  # the particles' affine matrices are in the checkpoint
    "explicit": [
        "solver.scheme=explicit",
        "time.dt=auto",
        "material.bulk_modulus=4e5",
        "bodies.0.initial_pressure=hydrostatic",
    ],
    # water leaves through an outlet from about 0.05 s: the particles removed, the outflow
    # and the affine matrices of those kept are in the checkpoint
    "outlet": ["domain.size=[0.16, 0.44]", 'domain.walls={x_max="outlet"}', "solver.transfer=apic"],
    # water enters through an inlet at about 0.4 of a spacing a step: the inlet's travel and
    # inflow, and the particles it emitted in each chunk, are in the checkpoint
    "inlet": [
        "domain.size=[0.16, 0.44]",
        'domain.walls={x_max="outlet"}',
        'inlets=[{side="x_min", speed=0.5, level=0.05}]',
    ],
    # a gate lifted at 1 m/s from the water's face (obstacles.0.motion): the flow time that
    # places it is in the checkpoint, its pose and force in bodies.csv
    "gate": [
        'obstacles=[{type="box", min=[0.114, 0.0], max=[0.134, 0.3], '
        'motion={type="velocity", velocity=[0.0, 1.0]}}]'
    ],
    # a free box falling towards the flow: its pose and velocity are in the checkpoint
    "free": [
        'obstacles=[{type="box", min=[0.2, 0.25], max=[0.26, 0.31], '
        'motion={type="free", density=500.0}}]'
    ],
}


def _case(scheme, *more):
    return load_case(EXAMPLES / "dam_break.toml", COMMON + SCHEMES[scheme] + list(more))


@pytest.fixture(scope="module", params=list(SCHEMES))
def uninterrupted(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param) / "whole"
    sim = Simulation(_case(request.param), out)
    sim.run()
    return request.param, sim, out


def _stop_at(sim, t):
    """Ask ``sim`` to stop at its output time t, as the SIGINT handler does."""

    def hook(s):
        if s.time >= t - 1e-12:
            s.stop_signal = signal.SIGINT

    sim.on_output = hook


def _assert_same_run(a, b, out_a, out_b):
    for name in Particles.FIELDS:
        assert np.array_equal(getattr(a.particles, name), getattr(b.particles, name)), name
    affine = getattr(a.scheme, "affine", None)  # APIC's matrices
    if affine is not None:
        assert affine.any() and np.array_equal(affine, b.scheme.affine)
    assert a.scheme.outflow == b.scheme.outflow
    assert a.scheme.inflow == b.scheme.inflow
    assert a.steps == b.steps and a.time == b.time
    for name in ("timeseries.csv", "particles.pvd", "bodies.csv"):
        if name == "bodies.csv" and not (out_a / name).exists():
            continue
        assert (out_a / name).read_text() == (out_b / name).read_text(), name
    snaps = sorted(p.name for p in out_a.glob("particles_*.vtu"))
    assert snaps and snaps == sorted(p.name for p in out_b.glob("particles_*.vtu"))
    for name in snaps:  # VTU snapshots are written uncompressed: the bytes must agree
        assert (out_a / name).read_bytes() == (out_b / name).read_bytes(), name


@pytest.mark.slow
def test_interrupted_then_restarted_run_is_bit_identical(uninterrupted, tmp_path):
    scheme, whole, whole_out = uninterrupted
    out = tmp_path / "parts"
    first = Simulation(_case(scheme), out)
    _stop_at(first, 0.05)  # between checkpoints (0.03, 0.06): the stop writes its own
    summary = first.run()
    assert summary["status"] == "interrupted" and summary["time"] == pytest.approx(0.05)
    assert "interrupted by SIGINT at t = 0.05 s" in summary["message"]
    saved = checkpoints(out)  # the periodic one at 0.03 s and the one of the stop
    assert len(saved) == 2 and saved[-1].name == f"checkpoint_{first.steps:09d}.npz"
    rest = Simulation.resume(_case(scheme), out, checkpoints(out)[-1])
    assert rest.time == first.time and rest.steps == first.steps
    assert rest.run()["status"] == "completed"
    _assert_same_run(whole, rest, whole_out, out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["restarted_from"] == saved[-1].name
    assert summary["steps"] == whole.steps


@pytest.mark.slow
def test_restart_from_an_older_checkpoint_truncates_the_later_outputs(uninterrupted, tmp_path):
    scheme, whole, whole_out = uninterrupted
    out = tmp_path / "copy"
    shutil.copytree(whole_out, out)
    older, final = checkpoints(out)  # at 0.09 s and at the end (0.1 s)
    final.unlink()
    rest = Simulation.resume(_case(scheme), out, older)
    assert rest.time == pytest.approx(0.09)
    # on resuming, the rows and snapshots after the checkpoint are dropped at once: a
    # writer added to the resumed run opens after the built-in ones and sees the folder
    seen = {}

    class Look:
        def open(self, sim, resume):
            rows = (out / "timeseries.csv").read_text().split()[1:]
            seen["times"] = [float(r.split(",")[0]) for r in rows]
            seen["snapshot"] = (out / "particles_000005.vtu").exists()  # the one at 0.1 s

        def __call__(self, sim):
            pass

    rest.add_writer(Look(), name="look")
    rest.run()
    assert seen["times"][-1] == pytest.approx(0.09) and len(seen["times"]) == 10
    assert seen["snapshot"] is False
    _assert_same_run(whole, rest, whole_out, out)


@pytest.mark.slow
def test_a_later_end_extends_a_finished_run(uninterrupted, tmp_path):
    scheme, whole, whole_out = uninterrupted
    out = tmp_path / "copy"
    shutil.copytree(whole_out, out)
    longer = _case(scheme, "time.end=0.12")
    rest = Simulation.resume(longer, out, checkpoints(out)[-1])
    rest.run()
    rows = (out / "timeseries.csv").read_text().split()[1:]
    assert [round(float(r.split(",")[0]), 9) for r in rows] == [
        round(0.01 * k, 9) for k in range(13)
    ]  # no duplicate row at 0.1 s
    assert rest.steps > whole.steps


@pytest.mark.slow
def test_restart_refuses_other_settings_naming_the_key(uninterrupted):
    scheme, _, whole_out = uninterrupted
    with pytest.raises(CaseError) as err:
        Simulation.resume(_case(scheme, "solver.flip=0.5"), whole_out, checkpoints(whole_out)[-1])
    msg = str(err.value)
    assert "`solver.flip` = 0.5 now" in msg and "in the checkpoint" in msg
    assert "--set solver.flip=" in msg
    with pytest.raises(CaseError, match="already reaches time.end = 0.1 s"):
        Simulation.resume(_case(scheme), whole_out, checkpoints(whole_out)[-1])


def test_cli_restart_without_checkpoint_and_with_overwrite(tmp_path, capsys):
    case = EXAMPLES / "hydrostatic.toml"
    (tmp_path / "empty").mkdir()
    assert main(["run", str(case), "--out", str(tmp_path / "empty"), "--restart"]) == 2
    assert "holds no checkpoint" in capsys.readouterr().err
    assert (
        main(["run", str(case), "--out", str(tmp_path / "empty"), "--restart", "--overwrite"]) == 2
    )
    assert "give one of them" in capsys.readouterr().err


@pytest.mark.slow
def test_checkpoints_keep_the_latest_two(uninterrupted):
    _, whole, whole_out = uninterrupted
    names = [p.name for p in checkpoints(whole_out)]
    assert len(names) == 2 and names[-1] == f"checkpoint_{whole.steps:09d}.npz"
    assert not list(whole_out.glob(".*.tmp"))


def _cli_args(scheme, out):
    args = ["run", str(EXAMPLES / "dam_break.toml"), "--out", str(out), "-q", "--restart"]
    for item in COMMON + SCHEMES[scheme]:
        args += ["--set", item]
    return args


@pytest.mark.parametrize("damage", [b"", b"not a zip file", "truncated"])
@pytest.mark.slow
def test_a_damaged_latest_checkpoint_falls_back_to_the_one_before(
    uninterrupted, tmp_path, capsys, damage
):
    """An empty or cut-short checkpoint (a crash before its data reached the disk) is passed
    over with a notice; the run continues from the one before and ends as the whole run."""
    scheme, whole, whole_out = uninterrupted
    out = tmp_path / "copy"
    shutil.copytree(whole_out, out)
    older, final = checkpoints(out)  # at 0.09 s and at the end (0.1 s)
    data = final.read_bytes()
    final.write_bytes(data[: len(data) // 2] if damage == "truncated" else damage)
    assert main(_cli_args(scheme, out)) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"checkpoint {final} cannot be read" in err
    assert f"Continuing from the one before it, {older.name}" in err
    arrays, meta = read(checkpoints(out)[-1])
    assert meta["steps"] == whole.steps
    for name in Particles.FIELDS:
        assert np.array_equal(arrays[name], getattr(whole.particles, name)), name
    for name in ("timeseries.csv", "particles.pvd"):
        assert (out / name).read_text() == (whole_out / name).read_text(), name


@pytest.mark.slow
def test_no_readable_checkpoint_is_a_clear_error(uninterrupted, tmp_path, capsys):
    scheme, _, whole_out = uninterrupted
    out = tmp_path / "copy"
    shutil.copytree(whole_out, out)
    older, final = checkpoints(out)
    older.write_bytes(b"")
    final.write_bytes(b"")
    assert main(_cli_args(scheme, out)) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.startswith("mpmflow: error: ")
    assert f"no checkpoint in {out} can be read" in err
    assert older.name in err and final.name in err and "--overwrite" in err
    final.unlink()  # only one checkpoint, and it is damaged: its own message
    assert main(_cli_args(scheme, out)) == 2
    err = capsys.readouterr().err
    assert f"Checkpoint {older} cannot be read (EOFError" in err and "Traceback" not in err


@pytest.mark.slow
def test_a_checkpoint_without_an_entry_is_a_case_error(uninterrupted, tmp_path):
    scheme, _, whole_out = uninterrupted
    arrays, meta = read(checkpoints(whole_out)[0])
    del arrays["v"]
    del meta["k_out"]
    path = checkpoint_write(tmp_path, 1, arrays, meta)
    with pytest.raises(CheckpointError, match="it lacks meta k_out, array v"):
        Simulation.resume(_case(scheme, "time.end=0.2"), tmp_path, path)


def test_an_apic_checkpoint_without_the_affine_matrices_is_refused(tmp_path):
    """An APIC run cannot continue from a checkpoint without its particles' affine matrices
    (one written by a FLIP run, or damaged): that would restart the transfers from C = 0."""
    out = tmp_path / "flip"
    Simulation(_case("projection", "time.end=0.04"), out).run()
    assert "scheme.affine" not in read(checkpoints(out)[-1])[0]
    arrays, meta = read(checkpoints(out)[-1])
    meta["case"]["solver"]["transfer"] = "apic"  # as if an APIC run had written it
    (tmp_path / "apic").mkdir()
    path = checkpoint_write(tmp_path / "apic", 1, arrays, meta)
    with pytest.raises(CheckpointError, match="scheme state .* KeyError: 'affine'"):
        Simulation.resume(_case("apic", "time.end=0.2"), tmp_path / "apic", path)


@pytest.mark.slow
def test_extending_a_run_whose_end_is_not_an_output_time(tmp_path):
    """A run to 0.105 s (not a multiple of output.interval = 0.01 s) extended to 0.12 s
    writes rows at 0.11 and 0.12 s, one per interval after the old end.

    Against a run made to 0.12 s from the start: the extended run has the extra output (and
    end snapshot) at 0.105 s, and its chunks 0.1-0.105-0.11 take the same 1 ms steps as the
    chunk 0.1-0.11 of the other, but the step size is (t_next - t)/n, which rounds
    differently (last bits), so the states agree to rounding, not bit for bit. The
    comparable parts are compared: the steps, and the rows at the shared times."""
    out = tmp_path / "o"
    Simulation(_case("projection", "time.end=0.105"), out).run()
    rest = Simulation.resume(_case("projection", "time.end=0.12"), out, checkpoints(out)[-1])
    rest.run()
    times = [
        round(float(r.split(",")[0]), 9) for r in (out / "timeseries.csv").read_text().split()[1:]
    ]
    assert times == [round(0.01 * k, 9) for k in range(11)] + [0.105, 0.11, 0.12]
    whole = Simulation(_case("projection", "time.end=0.12"))
    whole.run()
    assert rest.steps == whole.steps and rest.time == whole.time
    shared = {round(r["time"], 9): r for r in whole.rows}
    for row in rest.rows:
        if round(row["time"], 9) in shared:
            other = shared[round(row["time"], 9)]
            assert row["step"] == other["step"]
            for key in ("front", "height", "kinetic_energy", "max_pressure"):
                assert row[key] == pytest.approx(other[key], rel=1e-6, abs=1e-9), key


def _probe_case(data, *more):
    return load_case(
        EXAMPLES / "dam_break.toml",
        COMMON
        + [
            "time.end=0.06",
            f"probes=[{{name='p', quantity='pressure', position=[0.05, 0.0], "
            f"data={{path='{data}', column='p [Pa]'}}}}]",
            *more,
        ],
    )


@pytest.mark.slow
def test_restart_refuses_a_case_file_whose_content_changed(tmp_path):
    """A checkpoint records the content of every file the case reads (here a probe's
    measured series); a restart after that file changed is refused, naming the file, while
    the unchanged file restarts (issue 24: an STL moved between run and restart was read
    without a word)."""
    data = tmp_path / "measured.csv"
    data.write_text("time [s],p [Pa]\n0.0,0.0\n1.0,100.0\n")
    out = tmp_path / "run"
    Simulation(_probe_case(data), out).run()
    saved = read(checkpoints(out)[-1])[1]["files"]
    assert (
        list(saved) == ["probes.0.data.path"] and len(saved["probes.0.data.path"]["sha256"]) == 64
    )
    later = _probe_case(data, "time.end=0.09")
    Simulation.resume(later, out).close()  # same file: accepted
    data.write_text("time [s],p [Pa]\n0.0,0.0\n1.0,200.0\n")  # the same size, other values
    with pytest.raises(CaseError) as err:
        Simulation.resume(_probe_case(data, "time.end=0.09"), out)
    msg = str(err.value)
    assert "`probes.0.data.path`" in msg and str(data) in msg and "changed" in msg


@pytest.mark.slow
def test_restart_refuses_a_moved_mesh(tmp_path):
    """The issue's case: an obstacle's STL moved by 0.05 m between the run and its restart."""
    import trimesh

    stl = tmp_path / "cube.stl"
    trimesh.creation.box(extents=[0.02, 0.02, 0.02]).apply_translation([0.3, 0.02, 0.01]).export(
        stl
    )
    args = [
        "time.end=0.02",
        "time.dt=1e-3",
        "grid.spacing=0.008",
        "checkpoint.interval=0.01",
        "output.snapshots=false",
        f"obstacles=[{{type='mesh', path='{stl}'}}]",
    ]
    out = tmp_path / "run"
    Simulation(load_case(EXAMPLES / "dam_break_3d.toml", args), out).run()
    trimesh.creation.box(extents=[0.02, 0.02, 0.02]).apply_translation([0.35, 0.02, 0.01]).export(
        stl
    )
    with pytest.raises(CaseError, match=r"`obstacles\.0\.path`"):
        Simulation.resume(load_case(EXAMPLES / "dam_break_3d.toml", [*args, "time.end=0.04"]), out)


def pieces_of(tmp_path, arrays, ranks):
    """A checkpoint of ``arrays`` (the particles' and a grid array) written as ``ranks``
    ranks write it: rank r holding the particles r, r + ranks, ... (a run over ranks
    holds its box's, any subset)."""
    n = arrays["x"].shape[0]
    for r in range(ranks):
        mine = np.arange(r, n, ranks)
        own = {k: arrays[k][mine] for k in Particles.FIELDS}
        own["scheme.id"] = mine
        write_piece(tmp_path, 7, r, own)
    meta = {"time": 0.5, "pieces": ranks, "particles": n}
    return checkpoint_write(tmp_path, 7, {"scheme.p_node": arrays["scheme.p_node"]}, meta)


def test_a_checkpoint_in_pieces_reads_back_whole_or_in_shares(tmp_path):
    """One process reads a checkpoint of 3 ranks' pieces as a one-process checkpoint holds
    the run (every particle in its order, no numbers); 2 ranks each read their share of the
    pieces with the particles' numbers; a fourth rank of 4 reads none, in the right shapes."""
    rng = np.random.default_rng(3)
    n = 11
    arrays = {
        "x": rng.random((n, 2)),
        "v": rng.random((n, 2)),
        "pressure": rng.random(n),
        "mass": rng.random(n),
        "volume": rng.random(n),
        "scheme.p_node": rng.random(20),
    }
    path = pieces_of(tmp_path, arrays, 3)
    whole, meta = read(path)
    assert meta["pieces"] == 3 and "scheme.id" not in whole
    for name, a in arrays.items():
        assert np.array_equal(whole[name], a)
    shares = [read(path, (r, 2))[0] for r in range(2)]
    ids = np.concatenate([s["scheme.id"] for s in shares])
    assert np.array_equal(np.sort(ids), np.arange(n))
    for s in shares:
        assert np.array_equal(s["x"], arrays["x"][s["scheme.id"]])
    none = read(path, (3, 4))[0]
    assert none["x"].shape == (0, 2) and none["scheme.id"].size == 0


def test_a_checkpoint_missing_a_piece_is_damaged_and_old_ones_go_with_their_pieces(tmp_path):
    arrays = {k: np.ones((4, 2) if k in ("x", "v") else 4) for k in Particles.FIELDS}
    arrays["scheme.p_node"] = np.zeros(3)
    path = pieces_of(tmp_path, arrays, 2)
    piece_path(path, 1).unlink()
    with pytest.raises(CheckpointError, match="piece checkpoint_000000007_r0001.npz"):
        read(path)
    # a later checkpoint and one after it: the first (KEEP = 2) goes, pieces and all
    for step in (8, 9):
        checkpoint_write(tmp_path, step, {"x": np.zeros((1, 2))}, {"time": 1.0})
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == [
        "checkpoint_000000008.npz",
        "checkpoint_000000009.npz",
    ]
