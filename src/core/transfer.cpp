#include "transfer.hpp"

#include <cmath>

#include "parallel.hpp"
#include "strips.hpp"

namespace mpmflow {

template <int D>
void scatter_mass_pressure(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                           View<const double> pressure, View<const index_t> order,
                           View<const index_t> start, View<double> work_m, View<double> work_mp) {
  constexpr int NC = Grid<D>::NC;
  parallel_for(g.nnodes, [&](index_t i) {
    work_m[i] = 0.0;
    work_mp[i] = 0.0;
  });
  // cell by cell over strips of cell slabs, as particles_to_grid (one strip when the last
  // axis is periodic)
  std::array<index_t, 2 * STRIPS + 1> bounds;
  const index_t slab = g.cs[D - 1];
  const index_t nstrips = strips(
      g.cells[D - 1], [&](index_t r) { return start(r * slab); },
      g.periodic[D - 1] ? 1 : 2 * STRIPS, 2, bounds.data());
  for_strips(bounds.data(), nstrips, x.extent(0), [&](index_t r0, index_t r1) {
    std::array<double, NC> w;
    for (index_t c = r0 * slab; c < r1 * slab; ++c)
      for (index_t s = start(c); s < start(c + 1); ++s) {
        const index_t p = order(s);
        const index_t base = g.weights_at(&x(p, 0), w.data());
        for (int a = 0; a < NC; ++a) {
          work_m[base + g.corner[a]] += w[a] * mass(p);
          work_mp[base + g.corner[a]] += w[a] * mass(p) * pressure(p);
        }
      }
  });
  fold_images<D>(g, work_m);
  fold_images<D>(g, work_mp);
}

template <int D>
double pressure_deviation(const Grid<D>& g, View<const double, 2> x, View<const double> pressure,
                          View<const double> work_m, View<const double> work_mp) {
  constexpr int NC = Grid<D>::NC;
  return reduce_chunks<double>(x.extent(0), [&](index_t lo, index_t hi) {
    std::array<double, NC> w;
    double total = 0.0;
    for (index_t p = lo; p < hi; ++p) {
      const index_t base = g.weights_at(&x(p, 0), w.data());
      double smooth = 0.0;
      for (int a = 0; a < NC; ++a)
        if (w[a] > 0.0)  // then the node has mass from this particle at least
          smooth += w[a] * work_mp[base + g.corner[a]] / work_m[base + g.corner[a]];
      const double d = pressure(p) - smooth;
      total += d * d;
    }
    return total;
  });
}

namespace {

// Cell j at stencil slot b (0 <= b < 3^D) around cell c with coordinates cx (wrapped round
// periodic axes); false when it lies beyond the grid.
template <int D, bool P>
inline bool neighbour_cell(const Grid<D>& g, index_t c, const std::array<index_t, D>& cx, int b,
                           index_t& j) {
  j = c;
  bool inside = true;
  for (int k = 0; k < D; ++k) {
    index_t jk = cx[k] + b % 3 - 1;
    b /= 3;
    if constexpr (P) {
      jk = g.wrap_cell(k, jk);
      inside = inside && jk >= 0;
    } else {
      inside = inside && jk >= 0 && jk < g.cells[k];
    }
    j += (jk - cx[k]) * g.cs[k];
  }
  return inside;
}

// scatter_cell_volume for the particles of one cell c (coordinates cx), with the 3^D cell
// centres around c held in acell (stencil slots; beyond the grid: unused): a particle of
// cell c reaches only these (its lower centre along each axis is c - 1 or c, clamped). The
// same additions in the same order as scatter_cell_volume, particle after particle.
template <int D, bool P>
inline void load_cell_volume(const Grid<D>& g, index_t c, std::array<index_t, D>& cx,
                             std::array<double, Grid<D>::NS>& acell, View<const double> cell_vol) {
  g.cell_coords(c, cx.data());
  for (int b = 0; b < Grid<D>::NS; ++b) {
    index_t j;
    acell[b] = neighbour_cell<D, P>(g, c, cx, b, j) ? cell_vol[j] : 0.0;
  }
}

template <int D, bool P>
inline void store_cell_volume(const Grid<D>& g, index_t c, const std::array<index_t, D>& cx,
                              const std::array<double, Grid<D>::NS>& acell, View<double> cell_vol) {
  for (int b = 0; b < Grid<D>::NS; ++b) {
    index_t j;
    if (neighbour_cell<D, P>(g, c, cx, b, j)) cell_vol[j] = acell[b];
  }
}

template <int D, bool P>
inline void add_cell_volume(const Grid<D>& g, const double* x, double volume,
                            const std::array<index_t, D>& cx,
                            std::array<double, Grid<D>::NS>& acell) {
  cell_centre_hat<D, P>(g, x, volume, [&](const std::array<index_t, D>& i, double w) {
    int b = 0, p3 = 1;
    for (int k = 0; k < D; ++k) {
      index_t d = i[k] - cx[k];  // -1, 0 or 1, or a whole period less or more
      if constexpr (P) {
        if (d > 1)
          d -= g.cells[k];
        else if (d < -1)
          d += g.cells[k];
      }
      b += static_cast<int>(d + 1) * p3;
      p3 *= 3;
    }
    acell[b] += w;
  });
}

// Particle-to-grid of the particles of cell slabs r0 to r1 - 1, cell by cell. The particles
// of one cell share their 2^D nodes: the nodes' sums are held in registers while the cell's
// particles are added (from the nodes' values, in particle order, so the same additions in
// the same order as one node update per particle), then stored once.
template <int D, bool P>
void scatter_slabs(index_t r0, index_t r1, const Grid<D>& g, View<const double, 2> x,
                   View<const double, 2> v, View<const double> mass, View<const double> volume,
                   View<const index_t> order, View<const index_t> start, View<double> node_mass,
                   View<double, 2> node_mom, View<double> node_vol, View<double> cell_vol,
                   View<const double, 3> affine) {
  constexpr int NC = Grid<D>::NC;
  constexpr int NS = Grid<D>::NS;
  std::array<double, NC> w;
  const index_t slab = g.cs[D - 1];
  const bool cells_too = cell_vol.size() > 0;
  const bool apic = affine.size() > 0;
  std::array<index_t, D> cx;
  std::array<index_t, D> nx{};   // APIC: the coordinates of the cell's first node
  std::array<double, NS> acell;  // the cell centres around cell c: stencil slots
  for (index_t c = r0 * slab; c < r1 * slab; ++c) {
    const index_t s0 = start(c), s1 = start(c + 1);
    if (s0 == s1) continue;
    // every particle of cell c has the cell's first node as its base (cell_index and
    // weights_at clamp alike)
    const index_t base = g.cell_first_node(c);
    if (apic) g.cell_coords(c, nx.data());
    if (cells_too) load_cell_volume<D, P>(g, c, cx, acell, cell_vol);
    std::array<double, NC> am, av;
    std::array<std::array<double, D>, NC> amom;
    for (int a = 0; a < NC; ++a) {
      const index_t i = base + g.corner[a];
      am[a] = node_mass[i];
      av[a] = node_vol[i];
      for (int k = 0; k < D; ++k) amom[a][k] = node_mom(i, k);
    }
    for (index_t s = s0; s < s1; ++s) {
      const index_t p = order(s);
      g.weights_at(&x(p, 0), w.data());
      for (int a = 0; a < NC; ++a)
        p2g_corner<D>(g, p, a, w[a], nx.data(), x, v, mass, volume, affine, am[a], av[a],
                      amom[a].data());
      if (cells_too) add_cell_volume<D, P>(g, &x(p, 0), volume(p), cx, acell);
    }
    if (cells_too) store_cell_volume<D, P>(g, c, cx, acell, cell_vol);
    for (int a = 0; a < NC; ++a) {
      const index_t i = base + g.corner[a];
      node_mass[i] = am[a];
      node_vol[i] = av[a];
      for (int k = 0; k < D; ++k) node_mom(i, k) = amom[a][k];
    }
  }
}

}  // namespace

template <int D>
void particles_to_grid(const Grid<D>& g, View<const double, 2> x, View<const double, 2> v,
                       View<const double> mass, View<const double> volume,
                       View<const index_t> order, View<const index_t> start,
                       View<const double> gravity, double dt, View<double> node_mass,
                       View<double, 2> node_mom, View<double> node_vol, View<double, 2> v_old,
                       View<double, 2> v_star, View<double> cell_vol,
                       View<const double, 3> affine) {
  const index_t nn = g.nnodes;
  parallel_for(nn, [&](index_t i) {
    node_mass[i] = 0.0;
    node_vol[i] = 0.0;
    for (int k = 0; k < D; ++k) node_mom(i, k) = 0.0;
  });
  parallel_for(cell_vol.size(), [&](index_t c) { cell_vol[c] = 0.0; });
  std::array<index_t, 2 * STRIPS + 1> bounds;
  const index_t slab = g.cs[D - 1];
  // (one strip when the last axis is periodic: the cell volumes of its first and last
  // strips meet across it)
  const index_t nstrips = strips(
      g.cells[D - 1], [&](index_t r) { return start(r * slab); },
      g.periodic[D - 1] ? 1 : 2 * STRIPS, 2, bounds.data());
  with_periodic(g, [&](auto periodic) {
    constexpr bool P = decltype(periodic)::value;
    for_strips(bounds.data(), nstrips, x.extent(0), [&](index_t r0, index_t r1) {
      scatter_slabs<D, P>(r0, r1, g, x, v, mass, volume, order, start, node_mass, node_mom,
                          node_vol, cell_vol, affine);
    });
  });
  if (g.any_periodic) {  // an image's particles belong to its master
    fold_images<D>(g, node_mass);
    fold_images<D>(g, node_vol);
    fold_images<D>(g, node_mom);
  }
  parallel_for(nn, [&](index_t i) {
    const double m = node_mass[i];
    for (int k = 0; k < D; ++k) {
      if (m > 0.0) {
        v_old(i, k) = node_mom(i, k) / m;
        v_star(i, k) = v_old(i, k) + dt * gravity(k);
      } else {
        v_old(i, k) = 0.0;
        v_star(i, k) = 0.0;
      }
    }
  });
}

template <int D>
index_t grid_to_particles(const Grid<D>& g, View<double, 2> x, View<double, 2> v,
                          View<double> pressure, View<const double, 2> v_old,
                          View<const double, 2> v_new, View<const double> p_node, double dt,
                          double flip, View<const double> lower, View<const double> upper,
                          double margin, const std::array<View<const double>, D>& faces,
                          View<double, 3> affine, const Outlets& outlets) {
  const GridToParticle<D> one{g,    x,      v,     pressure, v_old, v_new,  p_node, dt,
                              flip, margin, lower, upper,    faces, affine, outlets};
  return reduce_chunks<index_t>(x.extent(0), [&](index_t lo, index_t hi) {
    index_t moved = 0;
    for (index_t p = lo; p < hi; ++p) moved += one(p) ? 1 : 0;
    return moved;
  });
}

#define MPMFLOW_TRANSFER(D)                                                                        \
  template void scatter_mass_pressure<D>(                                                          \
      const Grid<D>&, View<const double, 2>, View<const double>, View<const double>,               \
      View<const index_t>, View<const index_t>, View<double>, View<double>);                       \
  template double pressure_deviation<D>(const Grid<D>&, View<const double, 2>, View<const double>, \
                                        View<const double>, View<const double>);                   \
  template void particles_to_grid<D>(const Grid<D>&, View<const double, 2>, View<const double, 2>, \
                                     View<const double>, View<const double>, View<const index_t>,  \
                                     View<const index_t>, View<const double>, double,              \
                                     View<double>, View<double, 2>, View<double>, View<double, 2>, \
                                     View<double, 2>, View<double>, View<const double, 3>);        \
  template index_t grid_to_particles<D>(                                                           \
      const Grid<D>&, View<double, 2>, View<double, 2>, View<double>, View<const double, 2>,       \
      View<const double, 2>, View<const double>, double, double, View<const double>,               \
      View<const double>, double, const std::array<View<const double>, D>&, View<double, 3>,       \
      const Outlets&);
MPMFLOW_TRANSFER(2)
MPMFLOW_TRANSFER(3)
#undef MPMFLOW_TRANSFER

}  // namespace mpmflow
