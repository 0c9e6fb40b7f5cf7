"""Snapshots written in pieces (a run over ranks; issue 42, item 3): the .pvtu names its
pieces, a restart keeps the pieces of the snapshots it keeps and deletes the later ones,
and ``open_run`` reads a .pvtu's pieces back in the particles' order. The run over ranks
itself: tests/parallel/test_snapshot_pieces.py."""

import numpy as np

from mpmflow.output.folder import _LEFTOVER
from mpmflow.output.snapshots import (
    SnapshotWriter,
    piece_name,
    read_index,
    read_pvtu,
    write_pvtu,
    write_vtu,
)
from mpmflow.results import Snapshot


def pieces_of(folder, index, n=10, ranks=3, dim=2, seed=0):
    """A snapshot of n particles cut into pieces, each piece's particles shuffled."""
    rng = np.random.default_rng(seed)
    x, v = rng.random((n, dim)), rng.random((n, dim))
    p, m = rng.random(n), rng.random(n)
    owner = rng.integers(0, ranks, n)
    names = []
    for r in range(ranks):
        ids = rng.permutation(np.flatnonzero(owner == r))
        name = piece_name("particles", index, r)
        write_vtu(folder / name, x[ids], v[ids], p[ids], m[ids], ids)
        names.append(name)
    pvtu = f"particles_{index:06d}.pvtu"
    write_pvtu(folder / pvtu, names)
    return pvtu, (x, v, p, m)


def test_a_pvtu_names_its_pieces_and_reads_back_in_order(tmp_path):
    pvtu, (x, v, p, m) = pieces_of(tmp_path, 3)
    assert read_pvtu(tmp_path / pvtu) == [piece_name("particles", 3, r) for r in range(3)]
    text = (tmp_path / pvtu).read_text()
    assert 'type="PUnstructuredGrid"' in text and 'Name="id"' in text
    data = Snapshot(0.1, tmp_path / pvtu, 2).read()
    assert np.array_equal(data["x"], x) and np.array_equal(data["velocity"], v)
    assert np.array_equal(data["pressure"], p) and np.array_equal(data["mass"], m)


def test_a_restart_keeps_the_pieces_it_keeps_and_deletes_the_later(tmp_path):
    index = SnapshotWriter(tmp_path)
    for k in range(3):
        pvtu, _ = pieces_of(tmp_path, k, seed=k)
        index.add(0.1 * k, pvtu)
    # continued after the second snapshot (on any number of ranks)
    SnapshotWriter(tmp_path, resume=2)
    entries, complete = read_index(tmp_path / "particles.pvd")
    assert complete and [f for _, f in entries] == [
        "particles_000000.pvtu",
        "particles_000001.pvtu",
    ]
    left = sorted(f.name for f in tmp_path.glob("particles_*"))
    assert left == sorted(
        ["particles_000000.pvtu", "particles_000001.pvtu"]
        + [piece_name("particles", k, r) for k in range(2) for r in range(3)]
    )


def test_a_killed_pieces_temporary_files_are_known_as_leftovers():
    assert _LEFTOVER.match(".particles_000012_r0003.vtu.abc123.tmp")
    assert _LEFTOVER.match(".particles_000012.pvtu.abc123.tmp")
    assert _LEFTOVER.match(".particles_000012.vtu.abc123.tmp")
    assert not _LEFTOVER.match(".particles_000012_x.vtu.abc123.tmp")
