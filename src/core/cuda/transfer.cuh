// The particle-grid transfers on a CUDA device (src/core/transfer.hpp's phases, steps 2 and 7
// of docs/method.md): particles binned by cell, particle-to-grid with the predictor, and
// grid-to-particle, each from the same element functions as the host's loops
// (Grid::cell_at, p2g_corner, GridToParticle). Arrays are device views (memory.hpp).
//
// Particle-to-grid gathers instead of scattering: the particles sorted by cell (a stable
// radix sort, so the same order as the host's counting sort), each node sums the shares of
// the particles of its 2^D cells, cell by cell in increasing index, particle by particle in
// their order. No atomics: the sums are the same on every run. The host adds the same terms
// in its slab order, so the two agree to rounding.
//
// Not yet on the device (issue 41): periodic axes and the cell-centred volumes of the
// volume correction (refused with a message), and every phase between the two transfers.
#pragma once

#include <stdexcept>

#include "../grid.hpp"
#include "../transfer.hpp"
#include "memory.hpp"
#include "parallel.cuh"

namespace mpmflow::gpu {

template <int D>
class Transfers {
 public:
  // Size the binning arrays for n particles on grid g (outside the step).
  void reserve(const Grid<D>& g, index_t n) {
    if (g.any_periodic)
      throw std::invalid_argument("the CUDA transfers do not take periodic axes yet");
    cell_.sized(n);
    sorted_.sized(n);
    iota_.sized(n);
    order_.sized(n);
    start_.sized(g.ncells + 1);
    ws_.reserve(n);
    bits_ = 1;
    while ((index_t(1) << bits_) < g.ncells) ++bits_;
  }

  // The particles of cell c are order[start[c]:start[c + 1]], in their own order
  // (binning.hpp's counting_sort).
  void bin(const Grid<D>& g, View<const double, 2> x) {
    const index_t n = x.extent(0);
    View<index_t> cell = cell_.sized(n), sorted = sorted_.sized(n), iota = iota_.sized(n),
                  order = order_.sized(n), start = start_.sized(g.ncells + 1);
    gpu::parallel_for(n, [=] __device__(index_t p) {
      cell(p) = g.cell_at(&x(p, 0));
      iota(p) = p;
    });
    gpu::sort_by_key(ws_, cell, sorted, iota, order, bits_);
    // start[c] = the first position whose cell is c or more: a binary search per cell (a
    // thread per position filling the cells its step passes would leave one thread all the
    // empty cells above the material)
    const index_t ncells = g.ncells;
    gpu::parallel_for(ncells + 1, [=] __device__(index_t c) {
      index_t lo = 0, hi = n;
      while (lo < hi) {
        const index_t mid = lo + (hi - lo) / 2;
        if (sorted(mid) < c)
          lo = mid + 1;
        else
          hi = mid;
      }
      start(c) = lo;
    });
  }
  View<const index_t> order(index_t n) { return order_.sized(n); }
  View<const index_t> start(const Grid<D>& g) { return start_.sized(g.ncells + 1); }

  // particles_to_grid (transfer.hpp) without cell volumes, after bin().
  void particles_to_grid(const Grid<D>& g, View<const double, 2> x, View<const double, 2> v,
                         View<const double> mass, View<const double> volume,
                         std::array<double, D> gravity, double dt, View<double> node_mass,
                         View<double, 2> node_mom, View<double> node_vol, View<double, 2> v_old,
                         View<double, 2> v_star, View<const double, 3> affine = {}) {
    constexpr int NC = Grid<D>::NC;
    const index_t n = x.extent(0);
    View<const index_t> order = order_.sized(n), start = start_.sized(g.ncells + 1);
    gpu::parallel_for(g.nnodes, [=] __device__(index_t i) {
      index_t ix[D];
      g.node_coords(i, ix);
      double am = 0.0, av = 0.0, amom[D] = {};
      // the cells round node i in increasing index: the node is corner a of cell i - (a's
      // offsets), highest a first
      for (int a = NC - 1; a >= 0; --a) {
        index_t cx[D];
        bool inside = true;
        index_t c = 0;
        for (int k = 0; k < D; ++k) {
          cx[k] = ix[k] - ((a >> k) & 1);
          inside = inside && cx[k] >= 0 && cx[k] < g.cells[k];
          c += cx[k] * g.cs[k];
        }
        if (!inside) continue;
        for (index_t s = start(c); s < start(c + 1); ++s) {
          const index_t p = order(s);
          double w[NC];
          g.weights_at(&x(p, 0), w);
          p2g_corner<D>(g, p, a, w[a], cx, x, v, mass, volume, affine, am, av, amom);
        }
      }
      node_mass[i] = am;
      node_vol[i] = av;
      for (int k = 0; k < D; ++k) {
        node_mom(i, k) = amom[k];
        if (am > 0.0) {
          v_old(i, k) = amom[k] / am;
          v_star(i, k) = v_old(i, k) + dt * gravity[k];
        } else {
          v_old(i, k) = 0.0;
          v_star(i, k) = 0.0;
        }
      }
    });
  }

  // grid_to_particles (transfer.hpp): the same element function per particle; returns how
  // many were put back inside the box.
  index_t grid_to_particles(const GridToParticle<D>& one) {
    return gpu::reduce_sum<index_t>(
        ws_, one.x.extent(0), [=] __device__(index_t p) -> index_t { return one(p) ? 1 : 0; });
  }

 private:
  DeviceBuffer<index_t> cell_, sorted_, iota_, order_, start_;
  Workspace ws_;
  int bits_ = 1;
};

}  // namespace mpmflow::gpu
