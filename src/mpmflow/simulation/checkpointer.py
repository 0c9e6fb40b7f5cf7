"""The checkpointer, one more writer: a checkpoint (``mpmflow.checkpoint``) at the first
output time at or after each multiple of ``checkpoint.interval`` (the end of the run and a
stop have their own), and resuming a run from one.

A checkpoint holds the state, not the history: of the outputs written so far only where
each file ends (those files are fsynced first, so that what it counts is on the disk), and
the phase of every schedule: the built-in ones as ``k_out``, ``k_snap`` and
``k_checkpoint``, those of writers and callbacks added to the run under ``schedules`` by
their names.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import checkpoint
from .._version import __version__
from ..boundaries import outlets
from ..case import Case, resolved, revalidate
from ..errors import CaseError
from ..fallbacks import Fallbacks
from ..particles import Particles

if TYPE_CHECKING:
    from .loop import Simulation

# Simulation's progress callable(t, step, end)
Progress = Callable[[float, int, float], None] | None

# what a checkpoint's meta must hold
META = (
    "case",
    "time",
    "steps",
    "dt",
    "k_out",
    "k_snap",
    "k_checkpoint",
    "counters",
    "outputs",
    "mass0",
    "volume0",
    "count0",
    "wall_seconds",
)


class Checkpointer:
    """The periodic checkpoints (not at time.end: the end of the run writes its own)."""

    def __call__(self, sim: Simulation) -> None:
        if sim.checkpoint_dir is not None and sim.time < sim.case.time.end:
            write(sim)


def write(sim: Simulation) -> Path:
    """Write a checkpoint of the current state of ``sim`` (after its outputs). Over MPI
    ranks (a scheme with ``particle_state``) every rank calls it: each writes its piece of
    the particles, then rank 0 the main file (``mpmflow.checkpoint``); a rank's failure to
    write is every rank's OSError."""
    folder = sim.checkpoint_dir
    if folder is None:  # (the TypeError that Path(None) gave, with its reason)
        raise TypeError("a checkpoint needs an output folder: the Simulation has no out_dir")
    particles = {name: getattr(sim.particles, name) for name in Particles.FIELDS}
    arrays = {f"scheme.{k}": v for k, v in sim.scheme.state().items()}
    in_pieces = getattr(sim.scheme, "particle_state", None)
    if in_pieces is None:
        sim.last_checkpoint = checkpoint.write(
            folder, sim.steps, {**particles, **arrays}, meta_of(sim)
        )
        return sim.last_checkpoint
    from ..parallel.comm import agreed

    comm = sim.comm
    own = {**particles, **{f"scheme.{k}": v for k, v in in_pieces().items()}}
    count = sim.particle_count()
    agreed(
        comm, lambda: checkpoint.write_piece(folder, sim.steps, comm.rank, own), errors=(OSError,)
    )
    whole = {**meta_of(sim), "pieces": comm.size, "particles": count}
    # the main file once every piece is written (the agreement above waits for them)
    agreed(
        comm,
        lambda: checkpoint.write(folder, sim.steps, arrays, whole) if comm.rank == 0 else None,
        errors=(OSError,),
    )
    sim.last_checkpoint = checkpoint.path_for(folder, sim.steps)
    return sim.last_checkpoint


def meta_of(sim: Simulation) -> dict[str, object]:
    """A checkpoint's meta: the run's time, schedules, counters and outputs' positions (its
    writers' files fsynced first)."""
    for action in sim.actions:
        if action.writer and hasattr(action.func, "sync"):
            action.func.sync()
    # where each built-in writer's file stands (a resumed run cuts it back there)
    outputs = {name: w.position() for name, w in sim.builtin_writers.items()}
    meta = {
        "mpmflow_version": __version__,
        "case": resolved(sim.case),
        "time": sim.time,
        "steps": sim.steps,
        "dt": sim.dt,
        "k_out": sim.output_times.k,
        "k_snap": sim.snapshot_times.k,
        "k_checkpoint": sim.checkpoint_times.k,
        "counters": asdict(sim.counters),
        "fallbacks": sim.fallbacks.rows(),
        "outputs": outputs,
        "mass0": sim.mass0,
        "volume0": sim.volume0,
        "count0": sim.count0,
        "wall_seconds": sim.wall_seconds(),
        "files": sim.files,
    }
    added = {a.name: a.schedule.state() for a in sim.actions if not a.builtin}
    if added:  # only then: the meta of a run without them is as before
        meta["schedules"] = added
    return meta


def resume_latest(
    cls: type[Simulation], case: Case, out_dir: str | Path, progress: Progress
) -> Simulation:
    """The run of ``out_dir`` continued from its latest readable checkpoint."""
    checkpoint.latest(out_dir)  # CaseError when there is none
    damaged: list[checkpoint.CheckpointError] = []
    for path in reversed(checkpoint.checkpoints(out_dir)):
        try:
            sim = resume_from(cls, case, out_dir, path, progress)
        except checkpoint.CheckpointError as err:
            damaged.append(err)
            continue
        sim.notices[:0] = [
            f"checkpoint {err.path} cannot be read ({err.why}); it is damaged, e.g. cut "
            f"short by a crash. Continuing from the one before it, {path.name}."
            for err in damaged
        ]
        return sim
    if len(damaged) == 1:
        raise damaged[0]
    raise CaseError(
        f"--restart: no checkpoint in {out_dir} can be read: "
        + "; ".join(f"{e.path.name} ({e.why})" for e in damaged)
        + ". They are damaged, e.g. cut short by a crash. Start the run again "
        "with --overwrite instead of --restart."
    )


def resume_from(
    cls: type[Simulation], case: Case, out_dir: str | Path, path: str | Path, progress: Progress
) -> Simulation:
    """The run of ``out_dir`` continued from the checkpoint ``path``: a new ``cls`` (a
    Simulation) with the checkpoint's particles, scheme state, counters and schedules. Under
    mpirun each rank reads its share of a checkpoint in pieces (``checkpoint.read``)."""
    from ..parallel.comm import launched_rank, launched_size

    ranks = launched_size()
    arrays, meta = checkpoint.read(path, (launched_rank(), ranks) if ranks > 1 else None)
    missing = [f"meta {k}" for k in META if k not in meta]
    missing += [f"array {k}" for k in Particles.FIELDS if k not in arrays]
    if missing:
        raise checkpoint.CheckpointError(path, "it lacks " + ", ".join(missing))
    case = revalidate(case)
    checkpoint.check_same_case(meta["case"], resolved(case), path)
    checkpoint.check_same_files(meta.get("files"), checkpoint.file_hashes(case), path)
    if meta["time"] >= case.time.end:
        raise CaseError(
            f"--restart: checkpoint {path} is at t = {meta['time']:.6g} s, which already "
            f"reaches time.end = {case.time.end:g} s. To extend the run give a later end, "
            f"e.g. --set time.end={2 * case.time.end:g}."
        )
    sim = cls(case, out_dir, progress)
    P = sim.particles
    count = getattr(sim.scheme, "total", P.count)  # over ranks: the whole run's
    # with outlets (domain.walls = "outlet") the particles that left are not in it; with
    # inlets ([[inlets]]) those that entered are; a rank's share of pieces: some of them
    fewer = bool(outlets.sides(case).any()) and arrays["x"].shape[0] <= count
    share = checkpoint.NUMBERS in arrays and meta.get("particles") == count
    other = fewer or bool(case.inlets) or share
    replaced = False  # the particles' arrays are new ones: the scheme's follow
    for name in Particles.FIELDS:
        saved = arrays[name]
        if saved.shape[1:] != getattr(P, name).shape[1:] or not (saved.shape[0] == count or other):
            raise CaseError(
                f"--restart: checkpoint {path} holds {saved.shape[0]} "
                f"particles, the case {count}; it belongs to another case."
            )
        if saved.shape == getattr(P, name).shape:
            np.copyto(getattr(P, name), saved)
        else:
            setattr(P, name, np.array(saved))
            replaced = True
    if replaced or share:
        sim.scheme.particles = P  # the scheme's arrays of the particles follow (APIC, outlets)
    try:
        sim.scheme.restore(
            {k.removeprefix("scheme."): v for k, v in arrays.items() if k.startswith("scheme.")}
        )
        sim.counters = type(sim.counters)(**meta["counters"])
        sim.fallbacks = Fallbacks(meta.get("fallbacks", ()))
    except (KeyError, TypeError, ValueError) as err:
        raise checkpoint.CheckpointError(
            path, f"its scheme state or counters do not fit: {type(err).__name__}: {err}"
        ) from None
    sim.time, sim.steps, sim.dt = meta["time"], meta["steps"], meta["dt"]
    sim.output_times.restore({"k": meta["k_out"]})
    sim.snapshot_times.restore({"k": meta["k_snap"]})
    sim.checkpoint_times.restore({"k": meta["k_checkpoint"]})
    sim.resume_state = {"outputs": meta["outputs"], "schedules": meta.get("schedules", {})}
    sim.mass0, sim.volume0, sim.count0 = meta["mass0"], meta["volume0"], meta["count0"]
    sim.wall_before = meta["wall_seconds"]
    sim.resumed_from = Path(path)
    return sim
