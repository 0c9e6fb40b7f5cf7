"""Prototype of the first slice's solver half: the pressure system of one dam-break step
(assembled by the core on one grid), rows split by node x-index into rank boxes, numbered
rank-contiguously, solved by petsc4py KSP (CG + GAMG/hypre), compared with the core's
multigrid solve. Every rank builds the same (small, deterministic) state."""

# ruff: noqa: E402 (petsc4py.init must run before PETSc is imported)
import sys
import time

import numpy as np
import petsc4py

petsc4py.init(sys.argv[:1])
from mpi4py import MPI
from petsc4py import PETSc

from mpmflow import load_case
from mpmflow.linalg.solvers import LinearSolver, PressureMatrix
from mpmflow.simulation import Simulation

comm = MPI.COMM_WORLD
rank, size = comm.rank, comm.size
case = load_case(
    str(__import__("pathlib").Path(__file__).resolve().parents[3] / "examples" / "dam_break.toml"),
    ["time.end=0.06"],
)
sim = Simulation(case)
sch = sim.scheme
sch.advance(sim.dt, 60)  # 0.06 s of flow, identical on every rank
O = sch.options(sim.dt)
core = sch.core
core.predict(*sch._particles(), O, False, affine=sch.affine)
core.warm_start()
x0 = core.x0.copy()
assert core.pressure_matrix(O)
core.pressure_rhs(O)
cols, vals, rows, b = (
    core.matrix_cols.copy(),
    core.matrix_vals.copy(),
    core.rows.copy(),
    core.rhs.copy(),
)
n = rows.size
nx = sim.grid.nodes[0]
ref = LinearSolver("multigrid", 1e-10, 500)
ref.prepare(PressureMatrix(cols, vals, rows, sim.grid.nodes))
xr = ref.solve(b, x0).x
# the split: node column ix in [a_r, a_{r+1}) belongs to rank r
ix = rows % nx
# balanced cuts: equal unknowns per rank (1D recursive bisection on the column histogram)
cum = np.cumsum(np.bincount(ix, minlength=nx))
cuts = np.concatenate(
    ([0], np.searchsorted(cum, n * np.arange(1, size) / size, side="right"), [nx])
)
owner = np.searchsorted(cuts, ix, side="right") - 1
order = np.argsort(owner, kind="stable")  # rank-contiguous global numbering
g = np.empty(n, np.int64)
g[order] = np.arange(n)
mine = np.flatnonzero(owner == rank)
lo = int(g[mine[0]]) if mine.size else 0
c = cols[mine]
v = vals[mine]
mask = c >= 0
gc = np.where(mask, g[np.where(mask, c, 0)], np.iinfo(np.int64).max)
srt = np.argsort(gc, axis=1, kind="stable")  # PETSc wants sorted columns per row
gc = np.take_along_axis(gc, srt, 1)
v = np.take_along_axis(v, srt, 1)
mask = np.take_along_axis(mask, srt, 1)
indptr = np.concatenate(([0], np.cumsum(mask.sum(1)))).astype(PETSc.IntType)
A = PETSc.Mat().createAIJ(
    size=((mine.size, n), (mine.size, n)),
    csr=(indptr, gc[mask].astype(PETSc.IntType), v[mask]),
    comm=PETSc.COMM_WORLD,
)
A.assemble()
bv = A.createVecLeft()
bv.setArray(b[mine])
xv = A.createVecRight()
off = int((~((gc >= lo) & (gc < lo + mine.size)) & mask).sum())
for pc in ("gamg", "hypre"):
    ksp = PETSc.KSP().create(PETSc.COMM_WORLD)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType(pc)
    ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
    ksp.setTolerances(rtol=1e-10, max_it=500)
    ksp.setInitialGuessNonzero(True)
    xv.setArray(x0[mine])
    t = time.perf_counter()
    ksp.solve(bv, xv)
    t = time.perf_counter() - t
    its, reason = ksp.getIterationNumber(), ksp.getConvergedReason()
    ksp.destroy()
    full = np.zeros(n)
    full[mine] = xv.getArray()
    full = comm.allreduce(full)
    res = np.linalg.norm(
        b - (np.where(cols >= 0, vals * full[np.where(cols >= 0, cols, 0)], 0)).sum(1)
    ) / np.linalg.norm(b)
    if rank == 0:
        print(
            f"ranks={size} pc={pc} unknowns={n} its={its} reason={reason} true_rel_res={res:.2e} "
            f"|x-x_mg|/|x_mg|={np.linalg.norm(full - xr) / np.linalg.norm(xr):.2e} solve={t * 1e3:.1f} ms",
            flush=True,
        )
print(
    f"rank {rank}: columns [{cuts[rank]}, {cuts[rank + 1]}) rows {mine.size}, couplings to other ranks {off}",
    flush=True,
)
A.destroy()
