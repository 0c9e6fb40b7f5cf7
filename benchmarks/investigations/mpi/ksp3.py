# ruff: noqa: E402 (petsc4py.init must run before PETSc is imported)
import faulthandler

faulthandler.dump_traceback_later(10, exit=True)
import sys
import time

import petsc4py

petsc4py.init(sys.argv)
from petsc4py import PETSc

comm = PETSc.COMM_WORLD
n = 64
da = PETSc.DMDA().create([n, n], stencil_width=1, comm=comm)
A = da.createMatrix()
b = da.createGlobalVec()
x = b.duplicate()
r = b.duplicate()
(xs, xe), (ys, ye) = da.getRanges()
print(comm.rank, "ranges", (xs, xe), (ys, ye), "owned", b.getOwnershipRange(), flush=True)
for j in range(ys, ye):
    for i in range(xs, xe):
        row = PETSc.Mat.Stencil()
        row.index = (i, j)
        for di, dj, v in ((0, 0, 4.0), (-1, 0, -1.0), (1, 0, -1.0), (0, -1, -1.0), (0, 1, -1.0)):
            if 0 <= i + di < n and 0 <= j + dj < n:
                col = PETSc.Mat.Stencil()
                col.index = (i + di, j + dj)
                A.setValueStencil(row, col, v)
A.assemble()
b.set(1.0)
fro = A.norm(PETSc.NormType.FROBENIUS)
for pc in sys.argv[1].split(","):
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType(pc)
    ksp.setTolerances(rtol=1e-10)
    x.set(0)
    t = time.perf_counter()
    ksp.solve(b, x)
    A.mult(x, r)
    r.axpy(-1.0, b)
    its = ksp.getIterationNumber()
    ksp.destroy()
    xn = x.norm()
    rn = r.norm()
    if comm.rank == 0:
        print(
            f"{pc}: its={its} |x|={xn:.12e} |Ax-b|={rn:.2e} |A|F={fro:.6f} t={time.perf_counter() - t:.3f}s",
            flush=True,
        )
