"""APIC transfers (solver.transfer = "apic"; Jiang et al. 2015): the kernels carry an affine
velocity field exactly and conserve angular momentum; a spinning disc of water keeps its
angular momentum with APIC and loses it with PIC."""

import numpy as np
import pytest

from mpmflow import Simulation, state
from mpmflow.case.loading import validate
from mpmflow.cells import bin_particles
from mpmflow.errors import CaseError
from mpmflow.grid import Grid
from mpmflow.particles import Particles


def _affine_field(dim, rng):
    """v(x) = a + B x with random a, B."""
    return rng.normal(size=dim), rng.normal(size=(dim, dim))


def _p2g(grid, x, v, m, affine):
    n, dim = x.shape
    nn = grid.nnodes
    out = {k: np.zeros(nn) for k in ("mass", "vol")}
    mom, v_old, v_star = (np.zeros((nn, dim)) for _ in range(3))
    bins = bin_particles(grid, Particles(x, v, np.zeros(n), m, m / 1000))
    state.particles_to_grid(
        grid,
        x,
        v,
        m,
        m / 1000,
        bins.order,
        bins.start,
        np.zeros(dim),
        0.0,
        out["mass"],
        mom,
        out["vol"],
        v_old,
        v_star,
        np.empty(0),
        affine=affine,
    )
    return out["mass"], mom, v_old


@pytest.mark.parametrize("dim", [2, 3])
def test_apic_carries_an_affine_velocity_field_exactly(dim):
    """Particles anywhere, carrying v(x) = a + B x with C_p = B, give every node with mass
    v(x_i) exactly; FLIP/PIC's particle-to-grid does not (the mass-weighted mean of the
    particles' velocities is off where the particles around a node are not symmetric).
    Back from the grid, APIC gives each particle v(x_p) and C_p = B exactly."""
    rng = np.random.default_rng(3)
    cells = (6,) * dim
    grid = Grid(0.1, cells)
    n = 400 if dim == 2 else 1500
    x = rng.uniform(0.0, 0.6, (n, dim))
    m = rng.uniform(0.5, 2.0, n)
    a, B = _affine_field(dim, rng)
    v = a + x @ B.T
    C = np.tile(B, (n, 1, 1))
    mass, _, v_grid = _p2g(grid, x, v, m, C)
    nodes = grid.node_coordinates()
    has = mass > 0
    exact = a + nodes @ B.T
    np.testing.assert_allclose(v_grid[has], exact[has], atol=1e-12)
    _, _, v_pic = _p2g(grid, x, v, m, None)
    assert np.abs(v_pic[has] - exact[has]).max() > 1e-2  # measurably off without C_p

    # grid to particles (dt = 0: no motion) at new points
    y = rng.uniform(0.0, 0.6, (n, dim))
    u = np.zeros((n, dim))
    Cp = np.zeros((n, dim, dim))
    still = np.zeros_like(exact)
    state.grid_to_particles(
        grid,
        y,
        u,
        np.zeros(n),
        still,
        exact,
        np.zeros(grid.nnodes),
        0.0,
        0.99,
        np.full(dim, 0.6),
        1e-9,
        affine=Cp,
    )
    np.testing.assert_allclose(u, a + y @ B.T, atol=1e-12)  # the PIC velocity, no FLIP part
    np.testing.assert_allclose(Cp, np.tile(B, (n, 1, 1)), atol=1e-11)


def _angular(x, v, m, C, h):
    """Jiang et al.'s angular momentum about the origin (2D): sum_p m_p (x_p x v_p) plus the
    affine part m_p eps : (C_p D_p)^T, D_p = sum_i N_i (x_i - x_p)(x_i - x_p)^T, diagonal for
    multilinear N_i with entries h^2 f (1 - f) (f: x_p's place in its cell)."""
    L = np.sum(m * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]))
    f = x / h - np.floor(x / h)
    D = h * h * f * (1 - f)
    return L + np.sum(m * (C[:, 1, 0] * D[:, 0] - C[:, 0, 1] * D[:, 1]))


def test_apic_transfers_conserve_angular_momentum():
    """Particle to grid and back keep the angular momentum sum_i M_i x_i x v_i of the grid
    equal to the particles' (with their affine part), to rounding, for any velocities."""
    rng = np.random.default_rng(4)
    h, n = 0.1, 300
    grid = Grid(h, (8, 8))
    x = rng.uniform(0.05, 0.75, (n, 2))
    v = rng.normal(size=(n, 2))
    m = rng.uniform(0.5, 2.0, n)
    C = rng.normal(size=(n, 2, 2))
    nodes = grid.node_coordinates()

    def grid_L(mass, vel):
        return np.sum(mass * (nodes[:, 0] * vel[:, 1] - nodes[:, 1] * vel[:, 0]))

    mass, mom, v_grid = _p2g(grid, x, v, m, C)
    before = _angular(x, v, m, C, h)
    assert grid_L(mass, v_grid) == pytest.approx(before, rel=1e-12)
    # back to the same particles from an arbitrary grid velocity on the nodes with mass
    w = np.where(mass[:, None] > 0, rng.normal(size=v_grid.shape), 0.0)
    u, Cp = np.zeros((n, 2)), np.zeros((n, 2, 2))
    state.grid_to_particles(
        grid,
        x.copy(),
        u,
        np.zeros(n),
        w,
        w,
        np.zeros(grid.nnodes),
        0.0,
        1.0,
        np.array([0.8, 0.8]),
        1e-9,
        affine=Cp,
    )
    assert _angular(x, u, m, Cp, h) == pytest.approx(grid_L(mass, w), rel=1e-12)
    # PIC (the same velocities, no affine part) loses the part the particles' spread carries
    u_pic = np.zeros((n, 2))
    state.grid_to_particles(
        grid,
        x.copy(),
        u_pic,
        np.zeros(n),
        w,
        w,
        np.zeros(grid.nnodes),
        0.0,
        0.0,
        np.array([0.8, 0.8]),
        1e-9,
    )
    np.testing.assert_array_equal(u_pic, u)


# --- a spinning disc of water -------------------------------------------------------------

OMEGA, R, H = 2.0, 0.1, 0.02  # rad/s, m, m


def _disc(transfer, flip, end):
    """A disc of water of radius R in zero gravity, in rigid rotation at OMEGA: an exact
    steady solution (p = rho OMEGA^2 (r^2 - R^2) / 2, 0 on its free surface). Its free
    surface is Rayleigh-Taylor unstable (the centrifugal acceleration points out of the
    water); at OMEGA = 2 rad/s it breaks up at about 2.7 s (measured), beyond these runs."""
    case = validate(
        {
            "domain": {"size": [0.4, 0.4]},
            "grid": {"spacing": H},
            "bodies": [{"type": "disc", "centre": [0.2, 0.2], "radius": R}],
            "physics": {"gravity": [0.0, 0.0]},
            "time": {"dt": 1e-3, "end": end},
            "output": {"interval": 0.05, "snapshots": False},
            "solver": {"transfer": transfer, "flip": flip},
        },
        source="disc",
    )
    sim = Simulation(case)
    P = sim.particles
    r = P.x - 0.2
    P.v[:] = OMEGA * np.stack([-r[:, 1], r[:, 0]], axis=1)
    if sim.scheme.affine is not None:
        sim.scheme.affine[:] = [[0.0, -OMEGA], [OMEGA, 0.0]]  # its velocity gradient
    history = []

    def measure(s):
        P = s.particles
        c = np.sum(P.mass[:, None] * P.x, axis=0) / P.mass.sum()
        C = s.scheme.affine if s.scheme.affine is not None else np.zeros((P.count, 2, 2))
        # about the centre of mass: D_p depends on x_p's place in its cell, not on c
        L = _angular(P.x, P.v, P.mass, C, H) - (
            c[0] * np.sum(P.mass * P.v[:, 1]) - c[1] * np.sum(P.mass * P.v[:, 0])
        )
        r = P.x - c
        # the rigid rotation closest to the particles' velocities
        spin = np.sum(P.mass * (r[:, 0] * P.v[:, 1] - r[:, 1] * P.v[:, 0]))
        rigid = spin / np.sum(P.mass * (r**2).sum(axis=1)) * np.stack([-r[:, 1], r[:, 0]], 1)
        history.append((s.time, L, np.sqrt(np.mean(((P.v - rigid) ** 2).sum(axis=1)))))

    sim.on_output = measure
    sim.run()
    return np.array(history)


def test_a_spinning_disc_keeps_its_angular_momentum_with_apic_and_loses_it_with_pic():
    """Half a second (a sixth of a turn, 500 steps) at 10 cells across the radius. APIC: the
    transfers conserve angular momentum exactly (above); what changes it is the step between
    them (the pressure at the free surface, positions moved along straight lines), measured
    at 0.4% (the first step) and flat after: 1% allowed. PIC (solver.flip = 0) damps the
    rotation at a rate set by h^2 / dt, not by the flow: measured 2e-5 of it left. The
    default FLIP blend loses 1% per millisecond of the difference from PIC: measured 11%.
    APIC keeps the rotation rigid (0.45% of OMEGA R off it, rms) where pure FLIP carries
    particle noise (2%)."""
    apic = _disc("apic", 0.99, 0.5)
    L0 = apic[0, 1]
    assert L0 == pytest.approx(OMEGA * np.pi * R**4 / 2 * 1000, rel=0.05)  # rho pi R^4 w / 2
    drift = np.abs(apic[:, 1] / L0 - 1)
    assert drift.max() < 0.01
    pic = _disc("flip", 0.0, 0.5)
    assert pic[-1, 1] / pic[0, 1] < 0.01
    default = _disc("flip", 0.99, 0.5)
    lost = 1 - default[-1, 1] / default[0, 1]
    assert lost > 0.05 and drift[-1] < lost / 5
    flip = _disc("flip", 1.0, 0.5)
    assert apic[-1, 2] < 0.01 * OMEGA * R and apic[-1, 2] < 0.5 * flip[-1, 2]


def test_transfer_setting_is_checked():
    base = {
        "domain": {"size": [0.4, 0.4]},
        "grid": {"spacing": 0.02},
        "bodies": [{"min": [0, 0], "max": [0.1, 0.1]}],
        "time": {"end": 0.01, "dt": 1e-3},
    }
    with pytest.raises(CaseError, match="solver.transfer"):
        validate({**base, "solver": {"transfer": "mls"}}, source="t")
    with pytest.raises(
        CaseError,
        match=r'solver.scheme = "explicit" does not support APIC '
        r'transfers \(solver.transfer = "apic"; it transfers by FLIP/PIC only\); '
        r'set solver.scheme = "projection", or set solver.transfer = "flip"',
    ):
        validate(
            {
                **base,
                "solver": {"transfer": "apic", "scheme": "explicit"},
                "material": {"bulk_modulus": 4e5},
                "time": {"end": 0.01, "dt": "auto"},
            },
            source="t",
        )
    assert validate(base, source="t").solver.transfer == "flip"  # the default
