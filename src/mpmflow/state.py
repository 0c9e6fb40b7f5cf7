"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import numpy as np

from . import _core

CHUNKS = _core.CHUNKS


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))


# --- binning ---

def cell_index(x, h, cells, out):
    """Flat cell index of every particle (x: n x D, m) into ``out`` (int64)."""
    _core.cell_index(x, float(h), [int(c) for c in cells], out)


def counting_sort(cell, ncells, start, order):
    """Particles grouped by cell: cell c holds ``order[start[c]:start[c + 1]]``."""
    _core.counting_sort(cell, int(ncells), start, order)


def cell_volume_fraction(order, start, volume, cell_volume, open_, theta):
    """theta per cell: particle volume / cell volume, over the fluid part ``open_``."""
    _core.cell_volume_fraction(order, start, volume, float(cell_volume), open_, theta)


# --- cut_cells ---
# Cells cut by fixed obstacles (src/core/cut_cells.hpp; ``mpmflow.obstacles``).

SLIVER = _core.SLIVER  # a cut cell with less fluid takes its volume fraction from beside


def cut_cell_tensors(phi_node, h, cells, candidates, nsub, K, C, V, F, Wf, solid_parts):
    """The element integrals K, C, V, the obstacle face term F and the wall face term Wf of
    the candidate cells (flat indices), with nsub sub-cells per axis; ``solid_parts[m]``:
    solid sub-cells and sub-faces of candidate m (0: not cut). Outputs are filled."""
    _core.cut_cell_tensors(np.ascontiguousarray(phi_node, dtype=float), float(h),
                           [int(c) for c in cells],
                           np.ascontiguousarray(candidates, dtype=np.int64), int(nsub), K, C,
                           V, F, Wf, solid_parts)


def face_mass(h, dim, Wf):
    """``Wf[f, a, b]`` (2 dim x 2^dim x 2^dim) of a whole cell: int N_a N_b over face f."""
    _core.face_mass(float(h), int(dim), Wf)


def push_out(x, v, phi_node, h, cells, margin):
    """Particles inside an obstacle moved out to phi = margin (x, v in place); returns how
    many were moved."""
    return _core.push_out(x, v, phi_node, float(h), [int(c) for c in cells], float(margin))


def sliver_fractions(cells, open_, theta):
    """theta of sliver cut cells (0 < open < SLIVER) from their face neighbours (in place)."""
    _core.sliver_fractions([int(c) for c in cells], open_, theta)


def extend_velocity(onode, cells, node_mass, v_old, v_star):
    """Velocities of the massless obstacle nodes from their neighbours' (in place)."""
    _core.extend_velocity(onode, [int(c) for c in cells], node_mass, v_old, v_star)
