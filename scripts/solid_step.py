"""The solids' step linearised: how far past the shear wave's crossing of a cell it is stable.

The cantilever of examples/cantilever.toml (L = 1 m, H = 0.1 m, G = 3.68e7 Pa, rho = 1000
kg/m^3, clamped at x = 0) at h = H / n with 2 x 2 particles a cell, the particles frozen at
their places and PIC transfers, so that one step of src/core/step.cpp is a linear map of
the particles' deviatoric stress, the grid velocity and the cells' pressure:

    v* = v + dt M^-1 f(s)                       the old stress's force at the nodes
    x = (M / dt + K_g)^-1 M / dt (v* - M^-1 C^T q_old)      the elastic solve (eta = G dt)
    v_new = v* + x - base - M^-1 C^T q, C v_new = 0         the cells' projection
    s_new = s + dt 2 G dev(grad v_new)          the stress from the corrected velocity

(K_g: the viscous solve's Gauss stiffness, 2 eta D:D; C: int_cell grad N_i; M: the nodes'
lumped mass, which the projection takes). Prints the spectral radius of that map (above 1:
the step grows a mode) against the step in units of h / c_s, beside the same step with the
elastic solve and the projection solved as one system (the incompressible backward-Euler
step), and the iterations a conjugate-gradient solve of that system's pressure Schur
complement would take to 1e-6, preconditioned by the projection's Poisson operator alone
and with eta / V_cell added (Cahouet and Chabard 1988). docs/method.md, "Solids", quotes it.

    python scripts/solid_step.py         (about a minute on 2 cores)
"""

import numpy as np
import scipy.linalg as sl

L, H, G, RHO = 1.0, 0.1, 3.68e7, 1000.0
GAUSS = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))


def shape(a: float, b: float, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Q1's values and gradients at (a, b) in a cell of side h (corners 00, 10, 01, 11)."""
    N = np.array([(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b])
    dx = np.array([-(1 - b), 1 - b, -b, b]) / h
    dy = np.array([-(1 - a), -a, 1 - a, a]) / h
    return N, dx, dy


def beam(n: int) -> dict:
    """The frozen beam's operators on the free velocity components."""
    h = H / n
    nx, ny = round(L / h), n
    nn = (nx + 1) * (ny + 1)

    def corners(ci: int, cj: int) -> list[int]:
        return [
            cj * (nx + 1) + ci,
            cj * (nx + 1) + ci + 1,
            (cj + 1) * (nx + 1) + ci,
            (cj + 1) * (nx + 1) + ci + 1,
        ]

    s = (np.arange(2) + 0.5) / 2
    V = h * h / 4
    F = np.zeros((2 * nn, 2 * nx * ny * 4))  # force of (s_xx, s_xy) per particle; s_yy = -s_xx
    S = np.zeros((2 * nx * ny * 4, 2 * nn))  # their rate from the grid velocity
    M = np.zeros(nn)
    Mc = np.zeros((nn, nn))  # the particles' consistent mass
    Kg = np.zeros((2 * nn, 2 * nn))
    C = np.zeros((nx * ny, 2 * nn))
    p = 0
    for cj in range(ny):
        for ci in range(nx):
            ids = corners(ci, cj)
            for a in s:
                for b in s:
                    N, dx, dy = shape(a, b, h)
                    M[ids] += RHO * V * N
                    Mc[np.ix_(ids, ids)] += RHO * V * np.outer(N, N)
                    F[0::2][ids, 2 * p] -= V * dx
                    F[0::2][ids, 2 * p + 1] -= V * dy
                    F[1::2][ids, 2 * p + 1] -= V * dx
                    F[1::2][ids, 2 * p] += V * dy
                    S[2 * p, 0::2][ids] = G * dx
                    S[2 * p, 1::2][ids] = -G * dy
                    S[2 * p + 1, 0::2][ids] = G * dy
                    S[2 * p + 1, 1::2][ids] = G * dx
                    p += 1
            dofs = np.ravel([[2 * i, 2 * i + 1] for i in ids])
            for a in GAUSS:
                for b in GAUSS:
                    _, dx, dy = shape(a, b, h)
                    B = np.zeros((3, 8))
                    B[0, 0::2], B[1, 1::2] = dx, dy
                    B[2, 0::2], B[2, 1::2] = dy, dx
                    Kg[np.ix_(dofs, dofs)] += h * h / 4 * B.T @ np.diag([2.0, 2.0, 1.0]) @ B
                    C[cj * nx + ci, dofs[0::2]] += h * h / 4 * dx
                    C[cj * nx + ci, dofs[1::2]] += h * h / 4 * dy
    free = np.ones(2 * nn, dtype=bool)
    for j in range(ny + 1):  # clamped at x = 0
        free[2 * j * (nx + 1)] = free[2 * j * (nx + 1) + 1] = False
    f = np.flatnonzero(free)
    R = np.kron(Mc / M[:, None], np.eye(2))  # grid -> particles -> grid (PIC)
    return dict(
        h=h,
        M=np.repeat(M, 2)[f],
        F=F[f],
        S=S[:, f],
        Kg=Kg[np.ix_(f, f)],
        C=C[:, f],
        R=R[np.ix_(f, f)],
    )


def step_map(b: dict, dt: float, coupled: bool) -> np.ndarray:
    """The step's matrix on (s, v, q) (q = dt p / rho's multiplier)."""
    Mv, C = b["M"], b["C"]
    W = 1.0 / Mv
    Kg = G * dt * b["Kg"]
    A = np.linalg.solve(np.diag(Mv / dt) + Kg, np.diag(Mv / dt))
    ns, nv, nq = b["F"].shape[1], Mv.size, C.shape[0]
    Is, Iv, Iq = slice(0, ns), slice(ns, ns + nv), slice(ns + nv, ns + nv + nq)
    # PIC: the grid velocity at the step's start is the last one mapped through the
    # particles, M^-1 M_c v
    vstar = np.zeros((nv, ns + nv + nq))
    vstar[:, Is] = dt * W[:, None] * b["F"]
    vstar[:, Iv] = b["R"]
    if coupled:
        Z = sl.null_space(C)
        vnew = Z @ np.linalg.solve(
            Z.T @ (np.diag(Mv / dt) + Kg) @ Z, Z.T @ (Mv[:, None] / dt * vstar)
        )
        q = np.zeros((nq, vstar.shape[1]))
    else:
        base = vstar.copy()
        base[:, Iq] -= W[:, None] * C.T
        vss = vstar + A @ base - base
        q = np.linalg.solve(C @ (W[:, None] * C.T), C @ vss)
        vnew = vss - (W[:, None] * C.T) @ q
    T = np.zeros((ns + nv + nq, ns + nv + nq))
    T[Is] = dt * b["S"] @ vnew
    T[Is, Is] += np.eye(ns)
    T[Iv], T[Iq] = vnew, q
    return T


def schur_iterations(b: dict, dt: float, beta: float) -> float:
    """CG iterations to 1e-6 on the coupled system's Schur complement, preconditioned by
    the Poisson operator C M^-1 C^T plus beta G dt^2 / V_cell."""
    Mv, C = b["M"], b["C"]
    W = 1.0 / Mv
    A = np.linalg.solve(np.diag(Mv / dt) + G * dt * b["Kg"], np.diag(Mv / dt))
    S = C @ A @ (W[:, None] * C.T)
    P = np.linalg.inv(C @ (W[:, None] * C.T)) + beta * G * dt * dt / b["h"] ** 2 * np.eye(
        C.shape[0]
    )
    ev = np.linalg.eigvals(P @ S).real
    k = ev.max() / ev.min()
    return float(np.log(1e-6) / np.log((np.sqrt(k) - 1) / (np.sqrt(k) + 1)))


def main() -> None:
    b = beam(4)
    cs = np.sqrt(G / RHO)
    print(
        "| dt / (h / c_s) | split: spectral radius | coupled | CG its, Poisson | CG its, + eta / V |"
    )
    print("|---|---|---|---|---|")
    for f in (0.5, 1.0, 1.25, 1.5, 2.0, 4.0, 8.0, 30.0):
        dt = f * b["h"] / cs
        split = np.abs(np.linalg.eigvals(step_map(b, dt, False))).max()
        coupled = np.abs(np.linalg.eigvals(step_map(b, dt, True))).max()
        its = [schur_iterations(b, dt, beta) for beta in (0.0, 1.0)]
        print(f"| {f:g} | {split:.6f} | {coupled:.6f} | {its[0]:.0f} | {its[1]:.0f} |")


if __name__ == "__main__":
    main()
