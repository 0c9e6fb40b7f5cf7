"""What the parallel kernels share: how many chunks a loop is cut into, and strips of rows.

Parallel kernels split their loops into ``CHUNKS`` runs (more than any thread count, so a
static schedule still balances) and take every sum in an order fixed by the data alone, so
results do not depend on the number of threads. Scatters whose targets reach one row up or
down (particle-to-grid, Galerkin products) cut the grid into ``strips`` of whole rows:
strips two apart never write to the same place, so the even strips run in parallel, then
the odd ones.
"""

from numba import njit

CHUNKS = 64


@njit(cache=True)
def strips(row_cum, nstrips, min_rows, bounds):
    """Cut rows 0 to n - 1 into at most ``nstrips`` strips of at least ``min_rows`` rows each,
    holding about equal amounts of work: strip t is rows bounds[t] to bounds[t + 1] - 1.

    ``row_cum[r]`` is the work in rows 0 to r - 1 (n + 1 entries, non-decreasing); ``bounds``
    needs nstrips + 1 entries. Returns the number of strips (fewer when there are fewer
    rows; at least 1)."""
    nrows = row_cum.shape[0] - 1
    k = max(1, min(nstrips, nrows // min_rows))
    total = row_cum[nrows]
    bounds[0] = 0
    for t in range(1, k):
        target = total * t // k
        row = bounds[t - 1] + min_rows
        last = nrows - min_rows * (k - t)  # leave room for the strips still to come
        while row < last and row_cum[row] < target:
            row += 1
        bounds[t] = row
    bounds[k] = nrows
    return k
