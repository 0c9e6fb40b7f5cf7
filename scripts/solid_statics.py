"""The solids' spatial discretisation checked statically, without the step: the cantilever of
examples/cantilever.toml (L = 1 m, H = 0.1 m, G = 3.68e7 Pa, rho = 1000 kg/m^3, clamped at
x = 0) solved directly for its small-strain static deflection under gravity, with the
step's ingredients: Q1 displacements on the grid's cells, the 2 x 2 particles a cell as the
quadrature points (at h/4 and 3h/4), the deviatoric stiffness 2 G dev (plane strain, the
out-of-plane deviator 0), and incompressibility imposed in one of four ways:

- "cell": one constraint per cell, int_cell div u = 0 (Q1-P0: src/core/cell_pressure.hpp);
- "node": one per node, int N_j div u = 0, the surface nodes' included (Q1-Q1, the surface
  natural);
- "node, lumped surface": the same with the divergence's surface term lumped to the nodes,
  c_j . u_j with c_j = int grad N_j;
- "node, fluid's rows": the surface nodes' rows left out (p = 0 there, the fluid's).

Prints the tip deflection over Timoshenko's (docs/method.md, "Solids" quotes the table).

    python scripts/solid_statics.py        (about a minute on 2 cores)
"""

import numpy as np

L, H, G, RHO, GRAV = 1.0, 0.1, 3.68e7, 1000.0, 9.81
DELTA = 3 * RHO * GRAV * L**4 / (8 * G * H**2) + RHO * GRAV * L**2 / (2 * (5 / 6) * G)
# the deviatoric stiffness on (exx, eyy, gxy): s = 2 G (e - tr(e) / 2 I), engineering shear
DEV = 2 * G * np.array([[0.5, -0.5, 0.0], [-0.5, 0.5, 0.0], [0.0, 0.0, 0.5]])


def tip_ratio(n: int, mode: str) -> float:
    """The tip's static deflection over Timoshenko's with n cells through the depth."""
    h = H / n
    nx, ny = round(L / h), n
    nn = (nx + 1) * (ny + 1)

    def node(i: int, j: int) -> int:
        return j * (nx + 1) + i

    K = np.zeros((2 * nn, 2 * nn))
    f = np.zeros(2 * nn)
    Q = np.zeros((nn, 2 * nn))  # int N_j div u (the strong divergence, tested by N_j)
    Qw = np.zeros((nn, 2 * nn))  # -int grad N_j . u (its weak part)
    Qc = np.zeros((nx * ny, 2 * nn))  # int_cell div u
    for cj in range(ny):
        for ci in range(nx):
            ids = [node(ci, cj), node(ci + 1, cj), node(ci, cj + 1), node(ci + 1, cj + 1)]
            dofs = np.ravel([[2 * i, 2 * i + 1] for i in ids])
            for a in (0.25, 0.75):
                for b in (0.25, 0.75):
                    V = h * h / 4
                    N = np.array([(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b])
                    dx = np.array([-(1 - b), 1 - b, -b, b]) / h
                    dy = np.array([-(1 - a), -a, 1 - a, a]) / h
                    B = np.zeros((3, 8))
                    B[0, 0::2], B[1, 1::2] = dx, dy
                    B[2, 0::2], B[2, 1::2] = dy, dx
                    K[np.ix_(dofs, dofs)] += V * B.T @ DEV @ B
                    f[[2 * i + 1 for i in ids]] -= RHO * GRAV * V * N
                    div = np.zeros(8)
                    div[0::2], div[1::2] = dx, dy
                    Qc[cj * nx + ci, dofs] += V * div
                    for m in range(4):
                        Q[ids[m], dofs] += V * N[m] * div
                        Qw[ids[m], dofs[0::2]] -= V * N * dx[m]
                        Qw[ids[m], dofs[1::2]] -= V * N * dy[m]
    if mode == "cell":
        C = Qc
    elif mode == "node":
        C = Q
    elif mode == "node, lumped surface":
        C = Qw.copy()
        for j in range(nn):  # c_j = int grad N_j = -sum_b Qw[j, (b, k)]
            C[j, 2 * j] -= Qw[j, 0::2].sum()
            C[j, 2 * j + 1] -= Qw[j, 1::2].sum()
    else:  # the fluid's rows: the nodes off the top and bottom faces
        C = Q[[node(i, j) for j in range(1, ny) for i in range(nx + 1)]]
    free = np.ones(2 * nn, dtype=bool)
    for j in range(ny + 1):  # clamped at x = 0
        free[2 * node(0, j)] = free[2 * node(0, j) + 1] = False
    Kf, Cf = K[np.ix_(free, free)], C[:, free]
    s = G / h  # the constraint's rows scaled to the stiffness's size
    m = Cf.shape[0]
    A = np.block([[Kf, -s * Cf.T], [-s * Cf, np.zeros((m, m))]])
    rhs = np.concatenate([f[free], np.zeros(m)])
    sol = np.linalg.lstsq(A, rhs, rcond=None)[0]  # Q1-Q1's chequerboard: least squares
    u = np.zeros(2 * nn)
    u[free] = sol[: Kf.shape[0]]
    tip = -0.5 * (u[2 * node(nx, ny // 2) + 1] + u[2 * node(nx, (ny + 1) // 2) + 1])
    return tip / DELTA


def main() -> None:
    modes = ("cell", "node", "node, lumped surface", "node, fluid's rows")
    print("| constraint | H / 4 | H / 8 |")
    print("|---|---|---|")
    for mode in modes:
        print(f"| {mode} | {tip_ratio(4, mode):.3f} | {tip_ratio(8, mode):.3f} |")


if __name__ == "__main__":
    main()
