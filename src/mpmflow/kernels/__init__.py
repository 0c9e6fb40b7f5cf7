"""Compiled kernels (Numba): array in, array out, no orchestration.

Each module holds the kernels of one concept; the orchestration modules one level up
(`mpmflow.transfers`, `mpmflow.quadrature`, `mpmflow.pressure`, ...) call them and own
the arrays. Kernels here are written for 2D; the dimension is dispatched by the callers.

Conventions shared by all 2D kernels
------------------------------------
* Uniform grid of square cells of side ``h`` covering ``[0, ncx*h] x [0, ncy*h]``.
* Cell ``(cx, cy)`` has flat index ``cx + ncx*cy``; node ``(ix, iy)`` has flat index
  ``ix + (ncx+1)*iy`` (x varies fastest).
* The four nodes of a cell are numbered locally ``a = lx + 2*ly`` with ``lx, ly in {0, 1}``.
* Bilinear shape functions: ``N_a(xi, eta) = (lx ? xi : 1-xi) * (ly ? eta : 1-eta)`` with
  local coordinates ``xi, eta`` in [0, 1].
* Parallel kernels follow ``parallel``: results do not depend on the number of threads.
"""
