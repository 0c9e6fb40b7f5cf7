"""Compiled kernels (Numba): array in, array out, no orchestration.

Each module holds the kernels of one concept, written once for 2D and 3D; the fused step
(``step``) calls them in the order of the method, and the orchestration modules one level
up (``mpmflow.schemes.projection``, ``mpmflow.pressure``, ...) own the arrays.

Conventions (``geometry`` has the details)
------------------------------------------
* Uniform grid of square (cubic) cells of side ``h`` covering [0, cells[k] h] along each
  axis k. The grid comes to a kernel as ``cells``, the tuple of cell counts: its length D is
  part of the Numba type, so each kernel compiles once per dimension with constant-bound
  loops over axes and corners; sums over D components start from ``geometry.zeros_of``.
  (No factories closing over compiled functions: Numba cannot cache those across runs.)
* Flat indices run along axis 0 fastest: node (i_0, ..., i_{D-1}) is sum_k i_k ns_k with
  ns_k the product of (cells[j] + 1) for j < k; cells likewise with cells[j].
* The 2^D corners of a cell are numbered a = sum_k l_k 2^k, l_k in {0, 1}; the multilinear
  shape function of corner a is prod_k (l_k ? xi_k : 1 - xi_k) at local coordinates xi.
* Parallel kernels follow ``parallel``: results do not depend on the number of threads.
* ``explicit2d`` (the explicit comparator) is 2D only and keeps its own copies.
"""
