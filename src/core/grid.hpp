// Index arithmetic of the uniform grid, written once for 2D and 3D (D is a template
// parameter, so loops over axes and corners have constant bounds).
//
// Square (cubic) cells of side h cover [0, cells[k] h] along each axis k. Flat indices run
// along axis 0 fastest: node (i_0, ..., i_{D-1}) is sum_k i_k ns_k with ns_0 = 1,
// ns_k = ns_{k-1} (cells[k-1] + 1); cells likewise with cs_k. Corner a of a cell
// (0 <= a < 2^D) is offset (a >> k) & 1 along axis k. A neighbour at offset (d_0, ...) in
// {-1, 0, 1}^D of a node is stencil slot sum_k (d_k + 1) 3^k (9 slots in 2D, 27 in 3D).
//
// Periodic axes: along an axis k with periodic[k], cell cells[k] - 1 neighbours cell 0 and
// the last plane of nodes (i_k = cells[k]) is an image of the first (i_k = 0): arrays keep
// every node's plane, and every phase leaves an image's values equal to its master's
// (fold_images after a scatter, copy_images after a solve). A node's cells and its
// neighbours wrap round the axis (stencil.hpp); particles live in [0, cells[k] h).
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "view.hpp"

namespace mpmflow {

constexpr int corners(int D) { return 1 << D; }

// x^n for n >= 0 by repeated squaring (the roundings of Python's float ** int; for n <= 3
// every order of the products gives the same bits): cell volumes h^D, face areas h^(D-1).
MPMFLOW_HD inline double int_power(double x, int n) {
  double r = 1.0;
  while (true) {
    if (n & 1) r *= x;
    n >>= 1;
    if (!n) break;
    x *= x;
  }
  return r;
}
constexpr int stencil_size(int D) { return D == 2 ? 9 : 27; }

template <int D>
struct Grid {
  static constexpr int NC = 1 << D;           // corners of a cell
  static constexpr int NS = stencil_size(D);  // nodes of a node's stencil
  double h = 1.0;
  double inv_h = 1.0;
  std::array<index_t, D> cells{};
  std::array<index_t, D> ns{};       // node strides
  std::array<index_t, D> cs{};       // cell strides
  std::array<index_t, NC> corner{};  // flat offset of each corner from a cell's first node
  index_t nnodes = 0;
  index_t ncells = 0;
  std::array<bool, D> periodic{};
  bool any_periodic = false;

  Grid() = default;
  Grid(double spacing, const std::array<index_t, D>& c)
      : h(spacing), inv_h(1.0 / spacing), cells(c) {
    index_t n = 1, m = 1;
    for (int k = 0; k < D; ++k) {
      ns[k] = n;
      cs[k] = m;
      n *= cells[k] + 1;
      m *= cells[k];
    }
    nnodes = n;
    ncells = m;
    corner[0] = 0;
    for (int k = 0; k < D; ++k)
      for (int a = 0; a < (1 << k); ++a) corner[a + (1 << k)] = corner[a] + ns[k];
  }

  // The same grid, periodic along the axes where p[k] (a periodic axis needs an even number
  // of cells, at least 4: the multigrid's colours and stencils must not meet across it).
  Grid with_periodic(const std::array<bool, D>& p) const {
    Grid g = *this;
    g.periodic = p;
    g.any_periodic = false;
    for (int k = 0; k < D; ++k) g.any_periodic = g.any_periodic || p[k];
    return g;
  }

  // Cell coordinate j along axis k (j = -1 to cells[k]) wrapped round a periodic axis; -1
  // beyond a wall.
  MPMFLOW_HD index_t wrap_cell(int k, index_t j) const {
    if (j >= 0 && j < cells[k]) return j;
    if (!periodic[k]) return -1;
    return j < 0 ? j + cells[k] : j - cells[k];
  }
  // Node coordinate j along axis k (j = -1 to cells[k] + 1) wrapped round a periodic axis
  // (the last plane, an image, is kept); -1 beyond a wall.
  MPMFLOW_HD index_t wrap_node(int k, index_t j) const {
    if (j >= 0 && j <= cells[k]) return j;
    if (!periodic[k]) return -1;
    return j < 0 ? j + cells[k] : j - cells[k];
  }
  // True for a node on the last plane of a periodic axis (an image of one on the first).
  MPMFLOW_HD bool is_image(const index_t* ix) const {
    if (!any_periodic) return false;
    for (int k = 0; k < D; ++k)
      if (periodic[k] && ix[k] == cells[k]) return true;
    return false;
  }
  // The master of node i (coordinates ix): its images' planes moved to the first plane.
  MPMFLOW_HD index_t master(index_t i, const index_t* ix) const {
    for (int k = 0; k < D; ++k)
      if (periodic[k] && ix[k] == cells[k]) i -= cells[k] * ns[k];
    return i;
  }

  // The cell (0 to n - 1) holding grid coordinate s = x / h; points beyond the grid go to
  // the nearest cell, NaN to cell 0.
  MPMFLOW_HD static index_t cell_of(double s, index_t n) {
    if (!(s > 0.0)) return 0;
    if (s >= n - 1.0) return n - 1;
    return static_cast<index_t>(s);
  }

  // The first node of the cell holding point x (D coordinates) and the multilinear weights
  // of its 2^D corners into w (built axis by axis, in the order of the Numba kernels).
  MPMFLOW_HD index_t weights_at(const double* x, double* w) const {
    index_t base = 0;
    w[0] = 1.0;
    for (int k = 0; k < D; ++k) {
      const double s = x[k] * inv_h;
      const index_t c = cell_of(s, cells[k]);
      const double f = s - c;
      base += c * ns[k];
      for (int a = 0; a < (1 << k); ++a) {
        w[a + (1 << k)] = w[a] * f;
        w[a] *= 1.0 - f;
      }
    }
    return base;
  }

  // The first node of the cell holding x and the local coordinates in it (each in [0, 1]).
  MPMFLOW_HD index_t locate(const double* x, double* frac) const {
    index_t base = 0;
    for (int k = 0; k < D; ++k) {
      const double s = x[k] * inv_h;
      const index_t c = cell_of(s, cells[k]);
      frac[k] = s - c;
      base += c * ns[k];
    }
    return base;
  }

  // The flat cell holding x.
  MPMFLOW_HD index_t cell_at(const double* x) const {
    index_t c = 0;
    for (int k = 0; k < D; ++k) c += cell_of(x[k] * inv_h, cells[k]) * cs[k];
    return c;
  }

  MPMFLOW_HD void node_coords(index_t i, index_t* out) const {
    for (int k = 0; k < D; ++k) {
      const index_t n = cells[k] + 1;
      out[k] = i % n;
      i /= n;
    }
  }
  MPMFLOW_HD void cell_coords(index_t c, index_t* out) const {
    for (int k = 0; k < D; ++k) {
      out[k] = c % cells[k];
      c /= cells[k];
    }
  }
  // The first node of cell c.
  MPMFLOW_HD index_t cell_first_node(index_t c) const {
    index_t i = 0;
    for (int k = 0; k < D; ++k) {
      i += (c % cells[k]) * ns[k];
      c /= cells[k];
    }
    return i;
  }

  // Multilinear shape function of corner a at local coordinates frac.
  MPMFLOW_HD static double corner_weight(int a, const double* frac) {
    double w = 1.0;
    for (int k = 0; k < D; ++k) w *= ((a >> k) & 1) ? frac[k] : 1.0 - frac[k];
    return w;
  }
  // d N_a / d x_k at local coordinates frac (1/m).
  MPMFLOW_HD double corner_gradient(int a, int k, const double* frac) const {
    double g = ((a >> k) & 1) ? inv_h : -inv_h;
    for (int j = 0; j < D; ++j)
      if (j != k) g *= ((a >> j) & 1) ? frac[j] : 1.0 - frac[j];
    return g;
  }
};

// f(std::true_type{}) on a grid with a periodic axis, f(std::false_type{}) otherwise: a hot
// kernel compiles its loop twice, the common one free of the periodic axes' checks (their
// wrap tests cost a step about 7% when compiled into every loop).
template <int D, class F>
decltype(auto) with_periodic(const Grid<D>& g, F&& f) {
  if (g.any_periodic) return f(std::true_type{});
  return f(std::false_type{});
}

}  // namespace mpmflow
