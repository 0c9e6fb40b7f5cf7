#include "solid.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "parallel.hpp"
#include "periodic.hpp"
#include "plasticity.hpp"
#include "strips.hpp"

namespace mpmflow {

namespace {

// body(p) for every binned particle (order, start: binning.hpp), cell by cell in the order
// of their bins, over strips of cell slabs as particles_to_grid scatters them (strips.hpp):
// the even strips in parallel, then the odd ones, so a body that adds into the nodes of p's
// cell gives the same sums on any number of threads.
template <int D, class F>
void scatter_particles(const Grid<D>& g, View<const index_t> order, View<const index_t> start,
                       F&& body) {
  std::array<index_t, 2 * STRIPS + 1> bounds;
  const index_t slab = g.cs[D - 1];
  const index_t nstrips = strips(
      g.cells[D - 1], [&](index_t r) { return start(r * slab); },
      g.periodic[D - 1] ? 1 : 2 * STRIPS, 2, bounds.data());
  for_strips(bounds.data(), nstrips, order.size(), [&](index_t r0, index_t r1) {
    for (index_t c = r0 * slab; c < r1 * slab; ++c)
      for (index_t s = start(c); s < start(c + 1); ++s) body(order(s));
  });
}

}  // namespace

template <int D>
void cell_mean(const Grid<D>& g, View<const double> mass, View<const double> value,
               View<const index_t> order, View<const index_t> start, View<double> mean) {
  parallel_for(g.ncells, [&](index_t c) {
    double m = 0.0, y = 0.0;
    for (index_t s = start(c); s < start(c + 1); ++s) {
      const index_t p = order(s);
      m += mass(p);
      y += mass(p) * value(p);
    }
    mean(c) = m > 0.0 ? y / m : 0.0;
  });
}

template <int D>
void water_share(const Grid<D>& g, View<const double> mass, View<const double> volume,
                 double water_density, View<const index_t> order, View<const index_t> start,
                 View<double> share) {
  const double par[4] = {0.0, 0.0, 0.0, water_density};
  parallel_for(g.ncells, [&](index_t c) {
    double m = 0.0, w = 0.0;
    for (index_t s = start(c); s < start(c + 1); ++s) {
      const index_t p = order(s);
      m += mass(p);
      if (free_water(POROELASTIC, par, mass(p), volume(p))) w += mass(p);
    }
    share(c) = m > 0.0 ? w / m : 0.0;
  });
}

template <int D>
void stress_forces(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                   View<const double, 3> stress, View<const index_t> order,
                   View<const index_t> start, View<double, 2> acc, View<const double> scale) {
  constexpr int NC = Grid<D>::NC;
  parallel_for(g.nnodes, [&](index_t i) {
    for (int k = 0; k < D; ++k) acc(i, k) = 0.0;
  });
  // f_i = -sum_p V_p s_p grad N_i(x_p)
  scatter_particles<D>(g, order, start, [&](index_t p) {
    double w[NC], frac[D];
    const index_t base = g.weights_at(&x(p, 0), w);
    g.locate(&x(p, 0), frac);
    for (int a = 0; a < NC; ++a) {
      double grad[D];
      for (int j = 0; j < D; ++j) grad[j] = g.corner_gradient(a, j, frac);
      for (int k = 0; k < D; ++k) {
        double f = 0.0;
        for (int j = 0; j < D; ++j) f += stress(p, k, j) * grad[j];
        acc(base + g.corner[a], k) -= (scale.size() > 0 ? scale(p) * volume(p) : volume(p)) * f;
      }
    }
  });
  if (g.any_periodic) fold_images<D>(g, acc);
}

template <int D>
void internal_forces(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                     View<const double, 3> stress, View<const index_t> order,
                     View<const index_t> start, View<const double> node_mass, double dt,
                     View<double, 2> acc, View<double, 2> v_star, View<const double> scale) {
  stress_forces<D>(g, x, volume, stress, order, start, acc, scale);
  parallel_for(g.nnodes, [&](index_t i) {
    const double m = node_mass[i];
    if (m > 0.0)
      for (int k = 0; k < D; ++k) v_star(i, k) += dt * acc(i, k) / m;
  });
}

namespace {

// the velocity gradient L (D x D, L[k * D + j] = dv_k/dx_j) of v_grid (nn x D) and the
// pressure of p_node (nn) at particle p's position
template <int D>
double gradient_at(const Grid<D>& g, View<const double, 2> x, index_t p,
                   View<const double, 2> v_grid, View<const double> p_node, double* L) {
  constexpr int NC = Grid<D>::NC;
  double w[NC], frac[D];
  const index_t base = g.weights_at(&x(p, 0), w);
  g.locate(&x(p, 0), frac);
  for (int k = 0; k < D * D; ++k) L[k] = 0.0;
  double pp = 0.0;
  for (int a = 0; a < NC; ++a) {
    const index_t i = base + g.corner[a];
    pp += w[a] * p_node(i);
    for (int j = 0; j < D; ++j) {
      const double gr = g.corner_gradient(a, j, frac);
      for (int k = 0; k < D; ++k) L[k * D + j] += v_grid(i, k) * gr;
    }
  }
  return pp;
}

}  // namespace

template <int D>
index_t update_stresses(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                        View<const double> volume, View<const double, 2> v_grid,
                        View<const double> p_node, double dt, int model, View<const double> par,
                        View<double, 3> stress, View<double> plastic_strain,
                        View<double> yielding) {
  return reduce_chunks<index_t>(x.extent(0), [&](index_t lo, index_t hi) {
    index_t yielded = 0;
    for (index_t p = lo; p < hi; ++p) {
      if (mass(p) == 0.0 || free_water(model, par.data(), mass(p), volume(p))) continue;
      double L[D * D], s[D * D];
      const double pp = gradient_at<D>(g, x, p, v_grid, p_node, L);
      for (int k = 0; k < D; ++k)
        for (int j = 0; j < D; ++j) s[k * D + j] = stress(p, k, j);
      const double plastic = update_stress<D>(model, par.data(), L, dt, pp, x(p, D - 1), s);
      for (int k = 0; k < D; ++k)
        for (int j = 0; j < D; ++j) stress(p, k, j) = s[k * D + j];
      plastic_strain(p) += plastic;
      yielding(p) = plastic > 0.0 ? 1.0 : 0.0;
      yielded += plastic > 0.0 ? 1 : 0;
    }
    return yielded;
  });
}

template <int D>
double return_factors(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                      View<const double, 2> v_grid, View<const double> p_node, double dt, int model,
                      View<const double> par, View<const double, 3> stress, View<double> factor) {
  struct Sizes {
    double change, largest;  // Pa
  };
  const Sizes sizes = reduce_chunks<Sizes>(
      x.extent(0),
      [&](index_t lo, index_t hi) {
        Sizes z{0.0, 0.0};
        for (index_t p = lo; p < hi; ++p) {
          if (mass(p) == 0.0) {
            factor(p) = 1.0;
            continue;
          }
          double L[D * D], s[D * D], t[D * D];
          const double pp = gradient_at<D>(g, x, p, v_grid, p_node, L);
          for (int k = 0; k < D; ++k)
            for (int j = 0; j < D; ++j) s[k * D + j] = stress(p, k, j);
          trial_stress<D>(model, par.data(), L, dt, s, t);
          const Return r = radial_return<D>(model, par.data(), t, pp, x(p, D - 1));
          z.change = std::max(z.change, std::abs(r.factor - factor(p)) * r.q);
          z.largest = std::max(z.largest, r.factor * r.q);
          factor(p) = r.factor;
        }
        return z;
      },
      [](const Sizes& a, const Sizes& b) {
        return Sizes{std::max(a.change, b.change), std::max(a.largest, b.largest)};
      });
  return sizes.largest > 0.0 ? sizes.change / sizes.largest : 0.0;
}

#define MPMFLOW_SOLID(D)                                                                          \
  template void cell_mean<D>(const Grid<D>&, View<const double>, View<const double>,              \
                             View<const index_t>, View<const index_t>, View<double>);             \
  template void water_share<D>(const Grid<D>&, View<const double>, View<const double>, double,    \
                               View<const index_t>, View<const index_t>, View<double>);           \
  template void stress_forces<D>(const Grid<D>&, View<const double, 2>, View<const double>,       \
                                 View<const double, 3>, View<const index_t>, View<const index_t>, \
                                 View<double, 2>, View<const double>);                            \
  template void internal_forces<D>(const Grid<D>&, View<const double, 2>, View<const double>,     \
                                   View<const double, 3>, View<const index_t>,                    \
                                   View<const index_t>, View<const double>, double,               \
                                   View<double, 2>, View<double, 2>, View<const double>);         \
  template index_t update_stresses<D>(const Grid<D>&, View<const double, 2>, View<const double>,  \
                                      View<const double>, View<const double, 2>,                  \
                                      View<const double>, double, int, View<const double>,        \
                                      View<double, 3>, View<double>, View<double>);               \
  template double return_factors<D>(const Grid<D>&, View<const double, 2>, View<const double>,    \
                                    View<const double, 2>, View<const double>, double, int,       \
                                    View<const double>, View<const double, 3>, View<double>);
MPMFLOW_SOLID(2)
MPMFLOW_SOLID(3)
#undef MPMFLOW_SOLID

}  // namespace mpmflow
