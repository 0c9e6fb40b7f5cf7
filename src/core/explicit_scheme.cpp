#include "explicit_scheme.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "parallel.hpp"
#include "transfer.hpp"

namespace mpmflow {

namespace {

// Add one particle at xp (reference volume v0, current volume vol) to its cell's sums.
template <int D>
inline void add_to_cell(const Grid<D>& g, const double* xp, double v0, double vol,
                        View<double> sum_v, View<double> sum_v0, View<double, 2> sum_xi) {
  double frac[D];
  g.locate(xp, frac);
  const index_t c = g.cell_at(xp);
  sum_v(c) += vol;
  sum_v0(c) += v0;
  for (int k = 0; k < D; ++k) sum_xi(c, k) += v0 * frac[k];
}

// From the sums to the cell state (see cell_state in the header); volumes in m^3.
template <int D>
void finish_cells(double bulk, double tension, double full_volume, double sparse_volume,
                  View<double> cell_j, View<double> cell_vol, View<double> cell_v0,
                  View<double, 2> cell_xi, View<double> cell_p) {
  const double jmax = 1.0 + tension / bulk;
  parallel_for(cell_v0.size(), [&](index_t c) {
    const double v0 = cell_v0(c);
    if (v0 > 0.0 && v0 >= sparse_volume) {
      const double j = std::min(cell_j(c) / v0, jmax);
      if (v0 >= full_volume) {
        for (int k = 0; k < D; ++k) cell_xi(c, k) = 0.5;
      } else {
        for (int k = 0; k < D; ++k) cell_xi(c, k) /= v0;
      }
      cell_j(c) = j;
      cell_vol(c) = v0 * j;
      cell_p(c) = bulk * (1.0 - j);
    } else {
      cell_j(c) = 1.0;
      cell_vol(c) = 0.0;
      cell_p(c) = 0.0;
    }
  });
}

// f(c, a) for each cell c around node i (node i is its corner a), in increasing cell order
// (the order in which a scatter over the cells would reach the node).
template <int D, class F>
inline void cells_around_node(const Grid<D>& g, index_t i, F&& f) {
  index_t n[D];
  g.node_coords(i, n);
  for (int a = Grid<D>::NC - 1; a >= 0; --a) {
    index_t c = 0;
    bool inside = true;
    for (int k = 0; k < D; ++k) {
      const index_t ck = n[k] - ((a >> k) & 1);
      if (ck < 0 || ck >= g.cells[k]) {
        inside = false;
        break;
      }
      c += ck * g.cs[k];
    }
    if (inside) f(c, a);
  }
}

// div u at local point frac of cell c, from the nodal velocities u (1/s).
template <int D>
inline double divergence(const Grid<D>& g, index_t c, const double* frac, View<const double, 2> u) {
  const index_t base = g.cell_first_node(c);
  double d = 0.0;
  for (int a = 0; a < Grid<D>::NC; ++a) {
    const index_t i = base + g.corner[a];
    double t = g.corner_gradient(a, 0, frac) * u(i, 0);
    for (int k = 1; k < D; ++k) t += g.corner_gradient(a, k, frac) * u(i, k);
    d += t;
  }
  return d;
}

// f(node, axis, sign) for every wall node and wall: the walls normal to axis 0 first, then
// axis 1, ...; along each, the nodes in node order, the lower wall (sign -1) before the upper.
template <int D, class F>
void for_each_wall(const Grid<D>& g, F&& f) {
  for (int k = 0; k < D; ++k) {
    const index_t nface = g.nnodes / (g.cells[k] + 1);
    const index_t across = g.cells[k] * g.ns[k];
    for (index_t e = 0; e < nface; ++e) {
      index_t r = e, node = 0;
      for (int m = 0; m < D; ++m) {
        if (m == k) continue;
        const index_t nm = g.cells[m] + 1;
        node += (r % nm) * g.ns[m];
        r /= nm;
      }
      f(node, k, -1.0);
      f(node + across, k, 1.0);
    }
  }
}

// Wall nodes where the velocity points into the wall are in contact: normal velocity 0 (and
// tangential too at a no-slip wall: no_slip(2 k + (sign > 0)), one flag per side, x_min,
// x_max, y_min, ...); elsewhere the material leaves the wall freely. (The rule of
// kernels/walls.py, apply_walls, with the wall pairs enumerated in wall_pairs' order; the
// core's walls can take its place when they land.)
template <int D>
void wall_contact(const Grid<D>& g, View<double, 2> u, View<bool, 2> contact,
                  View<const bool> no_slip) {
  for (index_t e = 0; e < contact.size(); ++e) contact[e] = false;
  for_each_wall(g, [&](index_t i, int k, double sign) { contact(i, k) = sign * u(i, k) > 0.0; });
  for_each_wall(g, [&](index_t i, int k, double sign) {
    if (contact(i, k) || sign * u(i, k) > 0.0) {
      u(i, k) = 0.0;
      if (no_slip(2 * k + (sign > 0.0 ? 1 : 0)) && contact(i, k))
        for (int m = 0; m < D; ++m)
          if (m != k) u(i, m) = 0.0;
    }
  });
}

// |v_p| (m/s).
template <class V>
inline double speed(const V& v, index_t p) {
  double s = 0.0;
  for (index_t k = 0; k < v.extent(1); ++k) s += v(p, k) * v(p, k);
  return std::sqrt(s);
}

// scale h^D (m^D).
template <int D>
inline double times_cell_volume(double scale, double h) {
  for (int k = 0; k < D; ++k) scale *= h;
  return scale;
}

}  // namespace

template <int D>
void cell_state(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                View<const double> volume, double density, double bulk, double tension, double full,
                double sparse, View<double> cell_j, View<double> cell_vol, View<double> cell_v0,
                View<double, 2> cell_xi, View<double> cell_p) {
  parallel_for(cell_j.size(), [&](index_t c) {
    cell_j(c) = 0.0;
    cell_v0(c) = 0.0;
    for (int k = 0; k < D; ++k) cell_xi(c, k) = 0.0;
  });
  for (index_t p = 0; p < x.extent(0); ++p)
    add_to_cell(g, &x(p, 0), mass(p) / density, volume(p), cell_j, cell_v0, cell_xi);
  finish_cells<D>(bulk, tension, times_cell_volume<D>(full, g.h), times_cell_volume<D>(sparse, g.h),
                  cell_j, cell_vol, cell_v0, cell_xi, cell_p);
}

template <int D>
void particle_state(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                    View<double> volume, View<double> pressure, double density, bool smoothing,
                    View<const double> cell_j, View<const double> cell_vol,
                    View<const double> cell_p, View<double> node_w, View<double> node_p) {
  constexpr int NC = Grid<D>::NC;
  if (smoothing) {
    parallel_for(g.nnodes, [&](index_t i) {
      double w = 0.0, s = 0.0;
      cells_around_node(g, i, [&](index_t c, int) {
        if (cell_vol(c) > 0.0) {
          w += cell_vol(c);
          s += cell_vol(c) * cell_p(c);
        }
      });
      node_w(i) = w;
      node_p(i) = w > 0.0 ? s / w : s;
    });
  }
  parallel_for(x.extent(0), [&](index_t p) {
    std::array<double, NC> w;
    const index_t base = g.weights_at(&x(p, 0), w.data());
    const index_t c = g.cell_at(&x(p, 0));
    volume(p) = cell_j(c) * mass(p) / density;
    if (smoothing) {
      double s = 0.0;
      for (int a = 0; a < NC; ++a) s += w[a] * node_p(base + g.corner[a]);
      pressure(p) = s;
    } else {
      pressure(p) = cell_p(c);
    }
  });
}

double max_speed(View<const double, 2> v) {
  // per chunk as the serial loop (NaN returned at once), then the chunks in order
  double part[CHUNKS];
  const index_t n = v.extent(0);
  for_each_chunk(n, [&](index_t t, index_t lo, index_t hi) {
    double top = 0.0;
    for (index_t p = lo; p < hi; ++p) {
      const double s = speed(v, p);
      if (!(s <= top)) {
        top = s;
        if (s != s) break;
      }
    }
    part[t] = top;
  });
  const index_t nchunks = std::min(CHUNKS, std::max<index_t>(n, 1));
  double top = 0.0;
  for (index_t t = 0; t < nchunks; ++t) {
    if (part[t] != part[t]) return part[t];
    if (part[t] > top) top = part[t];
  }
  return top;
}

template <int D>
ExplicitStats explicit_steps(const Grid<D>& g, double span, index_t nsteps, double safety,
                             View<double, 2> x, View<double, 2> v, View<double> pressure,
                             View<const double> mass, View<double> volume, double density,
                             double bulk, View<const double> gravity, double flip_ms,
                             View<const bool> no_slip, bool smoothing, double full, double sparse,
                             double mass_cut, double q_lin, double q_quad, double tension,
                             double max_speed, View<const double> upper, double margin,
                             View<double> node_mass, View<double, 2> node_mom,
                             View<double, 2> v_old, View<double, 2> v_new, View<bool, 2> contact,
                             View<double> cell_j, View<double> cell_vol, View<double> cell_v0,
                             View<double, 2> cell_xi, View<double> cell_p, View<double> cell_q,
                             View<double> node_w, View<double> node_p) {
  constexpr int NC = Grid<D>::NC;
  const double h = g.h;
  const double full_volume = times_cell_volume<D>(full, h);
  const double sparse_volume = times_cell_volume<D>(sparse, h);
  const double light = times_cell_volume<D>(mass_cut * density, h);
  const double c = std::sqrt(bulk / density);
  const index_t n = x.extent(0);
  const std::array<double, D> origin{};  // the box [0, upper] particles are put back inside
  const View<const double> lower(origin.data(), {D});
  const index_t nnode = node_mass.size();
  const index_t ncell = g.ncells;
  index_t moved = 0;
  double done = 0.0;
  index_t steps = 0;
  double smallest = std::numeric_limits<double>::infinity();
  bool stopped = false;
  double vmax = mpmflow::max_speed(v);
  if (!(vmax <= max_speed)) stopped = true;
  double part[CHUNKS];
  index_t count[CHUNKS];
  while (!stopped && (safety <= 0.0 ? steps < nsteps : done < span)) {
    // (1) particle to grid (serial: the particles' order), nodal velocity
    parallel_for(nnode, [&](index_t i) {
      node_mass(i) = 0.0;
      for (int k = 0; k < D; ++k) node_mom(i, k) = 0.0;
    });
    for (index_t p = 0; p < n; ++p) {
      std::array<double, NC> w;
      const index_t base = g.weights_at(&x(p, 0), w.data());
      for (int a = 0; a < NC; ++a) {
        const index_t i = base + g.corner[a];
        const double wm = w[a] * mass(p);
        node_mass(i) += wm;
        for (int k = 0; k < D; ++k) node_mom(i, k) += wm * v(p, k);
      }
    }
    parallel_for(nnode, [&](index_t i) {
      if (node_mass(i) > 0.0) {
        for (int k = 0; k < D; ++k) v_old(i, k) = node_mom(i, k) / node_mass(i);
      } else {
        for (int k = 0; k < D; ++k) v_old(i, k) = 0.0;
      }
    });
    // artificial bulk viscosity from the current strain rate
    double qmax = 0.0;
    if (q_lin > 0.0 || q_quad > 0.0) {
      for_each_chunk(ncell, [&](index_t t, index_t lo, index_t hi) {
        double top = 0.0;
        for (index_t cc = lo; cc < hi; ++cc) {
          cell_q(cc) = 0.0;
          if (cell_vol(cc) > 0.0) {
            const double d = divergence(g, cc, &cell_xi(cc, 0), View<const double, 2>(v_old));
            if (d < 0.0) {
              const double sig = q_lin * c + q_quad * h * (-d);
              cell_q(cc) = density / cell_j(cc) * h * (-d) * sig;
              if (sig > top) top = sig;
            }
          }
        }
        part[t] = top;
      });
      const index_t nchunks = std::min(CHUNKS, std::max<index_t>(ncell, 1));
      for (index_t t = 0; t < nchunks; ++t)
        if (part[t] > qmax) qmax = part[t];
    } else {
      parallel_for(ncell, [&](index_t cc) { cell_q(cc) = 0.0; });
    }
    // the step
    double dt;
    if (safety > 0.0) {
      const double limit = h / (vmax + qmax + std::sqrt(qmax * qmax + c * c));
      const double left = span - done;
      const double k = std::max(1.0, std::ceil(left / (safety * limit) - 1e-9));
      dt = left / k;
      if (k == 1.0) dt = left;
    } else {
      dt = span / static_cast<double>(nsteps);
    }
    if (dt < smallest) smallest = dt;
    const double flip = flip_per_step(flip_ms, dt);
    // (2) nodal forces (gathered per node over its cells, in cell order), grid update
    parallel_for(nnode, [&](index_t i) {
      double f[D];
      for (int k = 0; k < D; ++k) f[k] = 0.0;
      cells_around_node(g, i, [&](index_t cc, int a) {
        const double vp = cell_vol(cc) * (cell_p(cc) + cell_q(cc));
        if (vp != 0.0) {
          const double* frac = &cell_xi(cc, 0);
          for (int k = 0; k < D; ++k) f[k] += vp * g.corner_gradient(a, k, frac);
        }
      });
      const double m = node_mass(i);
      if (m > 0.0) {
        if (m >= light) {
          for (int k = 0; k < D; ++k) v_new(i, k) = v_old(i, k) + dt * (gravity(k) + f[k] / m);
        } else {
          for (int k = 0; k < D; ++k) v_new(i, k) = v_old(i, k) + dt * gravity(k);
        }
      } else {
        for (int k = 0; k < D; ++k) {
          v_old(i, k) = 0.0;
          v_new(i, k) = 0.0;
        }
      }
    });
    wall_contact(g, v_new, contact, no_slip);
    // the new J of each cell from the strain rate of v_new (in cell_p until (4))
    parallel_for(ncell, [&](index_t cc) {
      if (cell_vol(cc) > 0.0) {
        const double d = divergence(g, cc, &cell_xi(cc, 0), View<const double, 2>(v_new));
        cell_p(cc) = cell_j(cc) * (1.0 + dt * d);
      } else {
        cell_p(cc) = 1.0;
      }
    });
    // (3) grid to particle; then the cell sums of the moved particles (serial)
    for_each_chunk(n, [&](index_t t, index_t lo, index_t hi) {
      index_t out = 0;
      for (index_t p = lo; p < hi; ++p) {
        std::array<double, NC> w;
        const index_t base = g.weights_at(&x(p, 0), w.data());
        volume(p) = cell_p(g.cell_at(&x(p, 0))) * (mass(p) / density);
        double pic[D], dv[D];
        for (int k = 0; k < D; ++k) pic[k] = dv[k] = 0.0;
        for (int a = 0; a < NC; ++a) {
          const index_t i = base + g.corner[a];
          for (int k = 0; k < D; ++k) {
            pic[k] += w[a] * v_new(i, k);
            dv[k] += w[a] * (v_new(i, k) - v_old(i, k));
          }
        }
        for (int k = 0; k < D; ++k) {
          v(p, k) = flip * (v(p, k) + dv[k]) + (1.0 - flip) * pic[k];
          x(p, k) += dt * pic[k];
        }
        if (put_inside<D>(x, v, p, lower, upper, margin)) ++out;
      }
      count[t] = out;
    });
    {
      const index_t nchunks = std::min(CHUNKS, std::max<index_t>(n, 1));
      for (index_t t = 0; t < nchunks; ++t) moved += count[t];
    }
    parallel_for(ncell, [&](index_t cc) {
      cell_j(cc) = 0.0;
      cell_v0(cc) = 0.0;
      for (int k = 0; k < D; ++k) cell_xi(cc, k) = 0.0;
    });
    vmax = 0.0;
    for (index_t p = 0; p < n; ++p) {
      const double s = speed(v, p);
      if (!(s <= vmax)) vmax = s;
      add_to_cell(g, &x(p, 0), mass(p) / density, volume(p), cell_j, cell_v0, cell_xi);
    }
    // (4) the cell state of the moved particles
    finish_cells<D>(bulk, tension, full_volume, sparse_volume, cell_j, cell_vol, cell_v0, cell_xi,
                    cell_p);
    steps += 1;
    done = (safety > 0.0 && dt == span - done) ? span : done + dt;
    if (!(vmax <= max_speed)) stopped = true;
  }
  particle_state(g, View<const double, 2>(x), mass, volume, pressure, density, smoothing,
                 View<const double>(cell_j), View<const double>(cell_vol),
                 View<const double>(cell_p), node_w, node_p);
  ExplicitStats st;
  st.steps = steps;
  st.time = safety > 0.0 ? done : static_cast<double>(steps) * (span / static_cast<double>(nsteps));
  st.smallest = smallest;
  st.moved = moved;
  st.stopped = stopped;
  st.vmax = vmax;
  return st;
}

#define MPMFLOW_EXPLICIT(D)                                                                        \
  template void cell_state<D>(const Grid<D>&, View<const double, 2>, View<const double>,           \
                              View<const double>, double, double, double, double, double,          \
                              View<double>, View<double>, View<double>, View<double, 2>,           \
                              View<double>);                                                       \
  template void particle_state<D>(const Grid<D>&, View<const double, 2>, View<const double>,       \
                                  View<double>, View<double>, double, bool, View<const double>,    \
                                  View<const double>, View<const double>, View<double>,            \
                                  View<double>);                                                   \
  template ExplicitStats explicit_steps<D>(                                                        \
      const Grid<D>&, double, index_t, double, View<double, 2>, View<double, 2>, View<double>,     \
      View<const double>, View<double>, double, double, View<const double>, double,                \
      View<const bool>, bool, double, double, double, double, double, double, double,              \
      View<const double>, double, View<double>, View<double, 2>, View<double, 2>, View<double, 2>, \
      View<bool, 2>, View<double>, View<double>, View<double>, View<double, 2>, View<double>,      \
      View<double>, View<double>, View<double>);

MPMFLOW_EXPLICIT(2)
MPMFLOW_EXPLICIT(3)

#undef MPMFLOW_EXPLICIT

}  // namespace mpmflow
