"""The granular columns' set-up and measures (mpmflow.validation.granular_3d, materials):
the quarter column's body and case, the deposit's profile."""

import math

import numpy as np
import pytest
import trimesh

from mpmflow import load_case
from mpmflow.validation import granular_3d as g3
from mpmflow.validation.materials import deposit_profile


def test_the_quarter_cylinder_is_closed_outward_and_holds_a_quarter_of_the_column():
    r0, H0 = 0.05, 0.15
    path_text = g3.quarter_cylinder_obj(r0, H0)
    mesh = trimesh.load(trimesh.util.wrap_as_stream(path_text), file_type="obj")
    assert mesh.is_watertight and mesh.is_winding_consistent
    # outward faces give a positive volume; 128 facets on the arc lose (1 - sin(x)/x) of it
    exact = 0.25 * math.pi * r0 * r0 * H0
    assert mesh.volume == pytest.approx(exact, rel=1e-4)
    lo, hi = mesh.bounds
    assert np.allclose(lo, [0.0, 0.0, 0.0]) and np.allclose(hi, [r0, r0, H0])


def test_the_quarter_column_case_sits_on_the_symmetry_planes(tmp_path):
    col = g3.Column3D(3.0, 10.0)
    case = load_case(col.write(tmp_path), col.overrides())
    assert case.domain.size[0] == case.domain.size[1] == pytest.approx(col.side)
    # the far walls are 1.5 laws beyond the law's run-out and on whole cells
    assert col.side >= g3.R0 * (1 + 2.5 * g3.lube_3d(3.0))
    assert col.side / col.h == pytest.approx(round(col.side / col.h))
    assert case.physics.gravity == [0.0, 0.0, -9.81]
    assert case.material.model == "mu_i"  # the 2D example's material


def test_the_deposit_profile_reads_the_top_of_each_particle_column():
    s, c = 0.002, 0.5
    # a heap of particles on both sides of c: columns k (distance (k + 1/2) s) k + 1 high
    pts = [
        (c + side * (k + 0.5) * s, (j + 0.5) * s)
        for side in (1, -1)
        for k in range(5)
        for j in range(k + 1)
    ]
    d, top = deposit_profile(np.array(pts), c, s)
    assert np.allclose(d, (np.arange(5) + 0.5) * s)
    assert np.allclose(top, (np.arange(5) + 1) * s)


def test_the_deposit_toe_is_the_last_ring_one_particle_layer_thick():
    h = 0.01
    # a quarter disc of uniform thickness 2 h out to 0.05 m, then a layer h / 4 thick to 0.08 m
    rng = np.random.default_rng(0)
    r = np.sqrt(rng.uniform(0.0, 0.08**2, 200000))
    area = 0.25 * np.pi * 0.08**2 / r.size  # the quarter's area per particle
    volume = np.where(r < 0.05, 2 * h, h / 4) * area
    assert g3.deposit_toe(r, volume, h, 0.25) == pytest.approx(0.05)
    assert g3.deposit_toe(r, 4 * volume, h, 1.0) == pytest.approx(0.05)  # the whole circle


@pytest.mark.slow
def test_the_quarter_column_is_the_whole_column():
    """The slip symmetry planes make the quarter column (395 particles at 5 cells across r0)
    the whole column in a no-slip tank (1580): measured run-outs 0.250 and 0.248 r0, toes
    both 0.20, H_inf / H0 0.823 and 0.825. They may differ by the lattice at the axis and
    the far walls' kind, which the deposit does not reach: 0.01 r0 and 0.5% of H0."""
    quarter = g3.measure_column(0.5, 5.0)
    whole = g3.measure_column(0.5, 5.0, whole=True)
    assert whole["particles"] == 4 * quarter["particles"]
    assert abs(quarter["runout"] - whole["runout"]) < 0.01
    assert quarter["toe"] == pytest.approx(whole["toe"])
    assert abs(quarter["height"] - whole["height"]) < 0.005
    assert not quarter["far"] and not whole["far"]
