// The volume correction on the cell-centred grid, 2D and 3D: the particles' volume on the
// cell centres, its Poisson system and the displacement on the cell faces
// (kernels/volume.py; see mpmflow.volume_correction).
//
// Cells are the points of this grid (flat index axis 0 fastest). The faces normal to axis k
// carry that component of the displacement: face (i_0, ..., i_{D-1}) with i_k = 0 to
// cells[k] lies between cells i_k - 1 and i_k along k; its flat index runs over
// cells[k] + 1 values along k and cells[j] along the others, axis 0 fastest
// (transfer.hpp's face_displacement interpolates them).
#pragma once

#include <array>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// A cell at least this full is half full (the volume correction's wet cells; the outputs'
// front, height and wetted cells read the same, diagnostics/measures.py, as state.HALF_FULL).
// A cell's theta is its particles' volume over its own, so half a cell of particles reads 1/2
// only to rounding (0.49999999999999994 in the 3D dam break's cells, 0.5 in the 2D one's):
// within 1e-12 of 1/2 a cell is half full. Read exactly, such a cell made its neighbours
// surface rows of the correction in 3D but not in 2D, and the 3D dam break across a slip
// tank left the 2D one by 0.07 a (tests/schemes/test_3d.py).
constexpr double HALF_FULL = 0.5 - 1e-12;

// sum_p N_c(x_p) V_p on every cell centre (m^3; transfer.hpp's scatter_cell_volume), over
// all particles; particles_to_grid computes the same during a step.
template <int D>
void cell_volume(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                 View<double> out);

// Whether the cell with coordinates cx lies against a wall that does not hold the material
// there (one of the nodes of its wall face is out of contact for that wall: contact, one
// flag per node and wall axis): the material has left that wall, which is then a free
// surface.
template <int D>
bool wall_released(const Grid<D>& g, const std::array<index_t, D>& cx, View<const bool, 2> contact);

// assemble's result: the number of rows, and whether any row touches air (an empty
// neighbour cell, held at q = 0).
struct VolumeSystem {
  index_t n;
  bool anchored;
};

// The Poisson system of the correction on the cells holding material (theta > 0).
// Numbers those cells (cell_row, -1 elsewhere; rows[r]: the cell of row r) and writes the
// (2D + 1)-point Laplacian in unit spacing in the 3^D-slot ELL form of the multigrid
// (cols, vals: rows x 3^D): an empty neighbour cell is held at q = 0 (air), a wall is a
// Neumann boundary. rhs_r = density - 1, the excess volume fraction. Near a free surface the
// density reads low because part of the kernel lies in air, so only an excess counts in a
// cell whose 3^D neighbourhood holds a cell with theta < wet, or that lies against a wall
// the material has left (wall_released). A cell inside an obstacle (static_slot < 0) is a
// wall; in a cell an obstacle cuts, or next to one, only an excess counts too.
template <int D>
VolumeSystem assemble(const Grid<D>& g, View<const double> theta, View<const double> density,
                      double wet, View<const bool, 2> contact, View<const index_t> static_slot,
                      View<index_t> cell_row, View<index_t, 2> cols, View<double, 2> vals,
                      View<double> rhs, View<index_t> rows);

// d = -scale grad q on the inner faces normal to each axis (m; scale, dmax in m: the
// displacement is limited to [-dmax, dmax]), 0 on the walls and on the faces of cells
// inside obstacles (static_slot < 0); faces[k]: the faces normal to axis k. q: the solution
// by row (cell_row numbers the rows), air q = 0.
template <int D>
void face_displacements(const Grid<D>& g, View<const index_t> cell_row,
                        View<const index_t> static_slot, View<const double> q, double scale,
                        double dmax, const std::array<View<double>, D>& faces);

}  // namespace mpmflow
