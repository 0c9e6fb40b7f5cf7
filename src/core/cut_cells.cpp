#include "cut_cells.hpp"

#include <cmath>

#include "parallel.hpp"
#include "quadrature.hpp"

namespace mpmflow {

namespace {

constexpr double FLAT_GRADIENT = 1e-2;  // |grad phi| below this: no direction to push along
constexpr double MAX_PUSH = 2.0;        // cells: the longest push-out step

// Gauss point gp (of 2^(D-1)) of the face normal to axis k on `side` (0, 1) of the
// (sub-)cell with local centre `centre` (its offsets +-gs already scaled), into `local`.
template <int D>
void face_gauss_point(int gp, int k, int side, const std::array<double, D>& centre, double gs,
                      std::array<double, D>& local) {
  int bit = 0;
  for (int kk = 0; kk < D; ++kk) {
    if (kk == k) {
      local[kk] = static_cast<double>(side);
    } else {
      local[kk] = centre[kk] + (((gp >> bit) & 1) ? gs : -gs);
      ++bit;
    }
  }
}

// A face quadrature point: M[a, b] += w N_a N_b (M: NC x NC, flat).
template <int D>
void face_point(const std::array<double, D>& local, double w, double* M) {
  constexpr int NC = 1 << D;
  std::array<double, NC> N;
  for (int a = 0; a < NC; ++a) N[a] = Grid<D>::corner_weight(a, local.data());
  for (int a = 0; a < NC; ++a)
    for (int b = 0; b < NC; ++b) M[a * NC + b] += w * N[a] * N[b];
}

}  // namespace

template <int D>
double phi_at(const Grid<D>& g, View<const double> phi_node, const std::array<double, D>& local,
              index_t first) {
  double val = 0.0;
  for (int a = 0; a < Grid<D>::NC; ++a)
    val += Grid<D>::corner_weight(a, local.data()) * phi_node[first + g.corner[a]];
  return val;
}

template <int D>
void cut_cell_tensors(const Grid<D>& g, View<const double> phi_node, View<const index_t> candidates,
                      index_t nsub, View<double, 3> K, View<double, 4> C, View<double, 2> V,
                      View<double, 4> F, View<double, 4> Wf, View<index_t> solid_parts) {
  constexpr int NC = 1 << D;
  const double h = g.h;
  const double gauss = 0.5 / std::sqrt(3.0);
  const double sub = h / static_cast<double>(nsub);
  const double dsub = static_cast<double>(nsub);
  index_t total = 1;
  for (int k = 0; k < D; ++k) total *= nsub;
  const index_t nface = total / nsub;
  const index_t m_count = candidates.size();
  for_each_chunk(
      m_count,
      [&](index_t, index_t lo, index_t hi) {
        for (index_t m = lo; m < hi; ++m) {
          std::array<index_t, D> cx;
          g.cell_coords(candidates(m), cx.data());
          index_t first = 0;
          for (int k = 0; k < D; ++k) first += cx[k] * g.ns[k];
          std::array<double, D> local, centre;
          double M[NC * NC];
          View<double, 2> Km = K.row(m);
          View<double, 3> Cm = C.row(m);
          View<double, 1> Vm = V.row(m);
          View<double, 3> Fm = F.row(m);
          View<double, 3> Wm = Wf.row(m);
          for (index_t i = 0; i < Km.size(); ++i) Km[i] = 0.0;
          for (index_t i = 0; i < Cm.size(); ++i) Cm[i] = 0.0;
          for (index_t i = 0; i < Vm.size(); ++i) Vm[i] = 0.0;
          for (index_t i = 0; i < Fm.size(); ++i) Fm[i] = 0.0;
          for (index_t i = 0; i < Wm.size(); ++i) Wm[i] = 0.0;
          index_t solid = 0;
          // volume: 2^D Gauss points in each fluid sub-cell
          const double wvol = int_power(sub, D) / NC;
          for (index_t q = 0; q < total; ++q) {
            index_t rq = q;
            for (int k = 0; k < D; ++k) {
              const index_t si = rq % nsub;
              rq /= nsub;
              centre[k] = (static_cast<double>(si) + 0.5) / dsub;
            }
            if (!(phi_at<D>(g, phi_node, centre, first) > 0.0)) {
              ++solid;
              continue;
            }
            for (int gp = 0; gp < NC; ++gp) {
              for (int k = 0; k < D; ++k)
                local[k] = centre[k] + (((gp >> k) & 1) ? gauss : -gauss) / dsub;
              accumulate_point<D>(g, local.data(), wvol, Km, Cm, Vm);
            }
          }
          // faces: 2^(D-1) Gauss points on each sub-face
          const double wface = int_power(sub, D - 1) / (1 << (D - 1));
          for (int k = 0; k < D; ++k) {
            for (int side = 0; side < 2; ++side) {
              const index_t j = cx[k] + (side == 1 ? 1 : -1);
              const bool wall = j < 0 || j >= g.cells[k];
              const index_t other_first = first + (side == 1 ? g.ns[k] : -g.ns[k]);
              const double sign = side == 1 ? 1.0 : -1.0;
              for (index_t q = 0; q < nface; ++q) {
                index_t rq = q;
                for (int kk = 0; kk < D; ++kk) {
                  if (kk == k) {
                    centre[kk] = side == 0 ? 0.5 / dsub : 1.0 - 0.5 / dsub;
                  } else {
                    centre[kk] = (static_cast<double>(rq % nsub) + 0.5) / dsub;
                    rq /= nsub;
                  }
                }
                if (!(phi_at<D>(g, phi_node, centre, first) > 0.0))
                  continue;  // solid on this side: part of the obstacle's face, or no face
                if (!wall) {
                  centre[k] = 1.0 - centre[k];  // the mirrored sub-cell across the face
                  const bool fluid_other = phi_at<D>(g, phi_node, centre, other_first) > 0.0;
                  if (!fluid_other) {
                    ++solid;
                    continue;  // fluid here, solid there: a piece of obstacle face
                  }
                }
                for (int i = 0; i < NC * NC; ++i) M[i] = 0.0;
                for (int gp = 0; gp < (1 << (D - 1)); ++gp) {
                  face_gauss_point<D>(gp, k, side, centre, gauss / dsub, local);
                  face_point<D>(local, wface, M);
                }
                for (int a = 0; a < NC; ++a)
                  for (int b = 0; b < NC; ++b) {
                    Fm(a, b, k) -= sign * M[a * NC + b];
                    if (wall) Wm(2 * k + side, a, b) += M[a * NC + b];
                  }
              }
            }
          }
          for (int a = 0; a < NC; ++a)
            for (int b = 0; b < NC; ++b)
              for (int k = 0; k < D; ++k) Fm(a, b, k) += Cm(a, b, k) + Cm(b, a, k);
          solid_parts(m) = solid;
        }
      },
      m_count * total);
}

template <int D>
void face_mass(const Grid<D>& g, View<double, 3> Wf) {
  for (index_t i = 0; i < Wf.size(); ++i) Wf[i] = 0.0;
  const double gauss = 0.5 / std::sqrt(3.0);
  std::array<double, D> local, centre;
  centre.fill(0.5);
  const double w = int_power(g.h, D - 1) / (1 << (D - 1));
  for (int k = 0; k < D; ++k)
    for (int side = 0; side < 2; ++side)
      for (int gp = 0; gp < (1 << (D - 1)); ++gp) {
        face_gauss_point<D>(gp, k, side, centre, gauss, local);
        face_point<D>(local, w, &Wf(2 * k + side, 0, 0));
      }
}

template <int D>
double interpolate_phi(const Grid<D>& g, View<const double> phi_node, View<const double, 2> x,
                       index_t p, double* grad) {
  double local[D];
  const index_t first = g.locate(&x(p, 0), local);
  double val = 0.0;
  for (int k = 0; k < D; ++k) grad[k] = 0.0;
  for (int a = 0; a < Grid<D>::NC; ++a) {
    const double phi = phi_node[first + g.corner[a]];
    val += Grid<D>::corner_weight(a, local) * phi;
    for (int k = 0; k < D; ++k) grad[k] += g.corner_gradient(a, k, local) * phi;
  }
  return val;
}

namespace {
// held (nnodes x D) interpolated multilinearly at particle p into u
template <int D>
void held_at(const Grid<D>& g, View<const double, 2> held, View<const double, 2> x, index_t p,
             double* u) {
  index_t i0[D];
  double w[D];
  for (int k = 0; k < D; ++k) {
    const double s = x(p, k) * g.inv_h;
    index_t i = static_cast<index_t>(std::floor(s));
    i = std::min<index_t>(std::max<index_t>(i, 0), g.cells[k] - 1);
    i0[k] = i;
    w[k] = std::min(std::max(s - static_cast<double>(i), 0.0), 1.0);
  }
  for (int k = 0; k < D; ++k) u[k] = 0.0;
  for (int a = 0; a < (1 << D); ++a) {
    double weight = 1.0;
    index_t node = 0;
    for (int k = 0; k < D; ++k) {
      const int bit = (a >> k) & 1;
      weight *= bit ? w[k] : 1.0 - w[k];
      node += (i0[k] + bit) * g.ns[k];
    }
    for (int k = 0; k < D; ++k) u[k] += weight * held(node, k);
  }
}
}  // namespace

template <int D>
index_t push_out(const Grid<D>& g, View<double, 2> x, View<double, 2> v,
                 View<const double> phi_node, double margin, View<const double, 2> held) {
  View<const double, 2> xc = x;
  return reduce_chunks<index_t>(x.extent(0), [&](index_t lo, index_t hi) {
    index_t moved = 0;
    for (index_t p = lo; p < hi; ++p) {
      double grad[D];
      double phi = interpolate_phi<D>(g, phi_node, xc, p, grad);
      if (phi >= margin) continue;
      ++moved;
      for (int it = 0; it < 4; ++it) {
        double g2 = 0.0;
        for (int k = 0; k < D; ++k) g2 += grad[k] * grad[k];
        // phi is a distance: |grad phi| is about 1 across a face the grid resolves. Where
        // it is far below (a cell whose corners all read one value, as the wall shift of
        // obstacles.node_distance makes the corner cell of an obstacle touching two or three
        // walls), the gradient is round-off (5.6e-17 measured) and gives no direction: a
        // Newton step along it threw a particle 1.6e15 m. The particle stays where it is.
        if (g2 < FLAT_GRADIENT * FLAT_GRADIENT) break;
        double step = (margin - phi) / g2;
        // nor does one step move a particle further than MAX_PUSH cells
        const double length = std::abs(step) * std::sqrt(g2);
        if (length > MAX_PUSH * g.h) step *= MAX_PUSH * g.h / length;
        for (int k = 0; k < D; ++k) x(p, k) += step * grad[k];
        phi = interpolate_phi<D>(g, phi_node, xc, p, grad);
        if (phi >= margin) break;
      }
      double u[D] = {};
      if (held.size() > 0) held_at<D>(g, held, xc, p, u);
      double g2 = 0.0, vn = 0.0;
      for (int k = 0; k < D; ++k) {
        g2 += grad[k] * grad[k];
        vn += (v(p, k) - u[k]) * grad[k];
      }
      if (g2 > 0.0 && vn < 0.0)
        for (int k = 0; k < D; ++k) v(p, k) -= vn * grad[k] / g2;
    }
    return moved;
  });
}

namespace {
// f(nb) for each face neighbour nb of cell c inside the domain, until f returns false;
// returns whether every call returned true
template <int D, class F>
bool each_face_neighbour(const Grid<D>& g, index_t c, F&& f) {
  index_t cx[D];
  g.cell_coords(c, cx);
  for (int k = 0; k < D; ++k)
    for (int step = -1; step <= 1; step += 2) {
      const index_t j = cx[k] + step;
      if (j >= 0 && j < g.cells[k] && !f(c + step * g.cs[k])) return false;
    }
  return true;
}
}  // namespace

template <int D>
void sliver_fractions(const Grid<D>& g, View<const double> open_, View<double> theta, bool swept) {
  // only sliver cells are written, only cells with open >= SLIVER read: no race
  parallel_for(g.ncells, [&](index_t c) {
    if (!(0.0 < open_(c) && open_(c) < SLIVER)) return;
    double best = -1.0;
    each_face_neighbour<D>(g, c, [&](index_t nb) {
      if (open_(nb) >= SLIVER && theta(nb) > best) best = theta(nb);
      return true;
    });
    if (best >= 0.0) theta(c) = best;
  });
  if (!swept) return;
  // empty cut cells ahead of a face: marked with minus their value first, read only where
  // positive, so that no cell reads a neighbour written in the same pass
  parallel_for(g.ncells, [&](index_t c) {
    if (!(SLIVER <= open_(c) && open_(c) < 1.0 && theta(c) == 0.0)) return;
    double best = 0.0;
    const bool no_air = each_face_neighbour<D>(g, c, [&](index_t nb) {
      if (open_(nb) >= 1.0 && theta(nb) == 0.0) return false;  // air beside it
      if (open_(nb) > 0.0 && theta(nb) > best) best = theta(nb);
      return true;
    });
    if (no_air) theta(c) = -best;
  });
  parallel_for(g.ncells, [&](index_t c) {
    if (theta(c) < 0.0) theta(c) = -theta(c);
  });
}

template <int D>
void extend_velocity(const Grid<D>& g, View<const index_t> onode, View<const double> node_mass,
                     View<double, 2> v_old, View<double, 2> v_star) {
  // only massless nodes are written, only nodes with mass read: no race
  parallel_for(onode.size(), [&](index_t e) {
    const index_t i = onode(e);
    if (node_mass(i) > 0.0) return;
    index_t ix[D];
    g.node_coords(i, ix);
    double total = 0.0;
    for (int k = 0; k < D; ++k) {
      v_old(i, k) = 0.0;
      v_star(i, k) = 0.0;
    }
    for (int s = 0; s < Grid<D>::NS; ++s) {
      index_t j = i;
      int rs = s;
      bool inside = true;
      for (int k = 0; k < D; ++k) {
        const int d = rs % 3 - 1;
        rs /= 3;
        if (ix[k] + d < 0 || ix[k] + d > g.cells[k]) {
          inside = false;
          break;
        }
        j += d * g.ns[k];
      }
      if (!inside || node_mass(j) <= 0.0) continue;
      const double m = node_mass(j);
      total += m;
      for (int k = 0; k < D; ++k) {
        v_old(i, k) += m * v_old(j, k);
        v_star(i, k) += m * v_star(j, k);
      }
    }
    if (total > 0.0)
      for (int k = 0; k < D; ++k) {
        v_old(i, k) /= total;
        v_star(i, k) /= total;
      }
  });
}

#define MPMFLOW_INSTANTIATE(D)                                                                  \
  template double phi_at<D>(const Grid<D>&, View<const double>, const std::array<double, D>&,   \
                            index_t);                                                           \
  template void cut_cell_tensors<D>(const Grid<D>&, View<const double>, View<const index_t>,    \
                                    index_t, View<double, 3>, View<double, 4>, View<double, 2>, \
                                    View<double, 4>, View<double, 4>, View<index_t>);           \
  template void face_mass<D>(const Grid<D>&, View<double, 3>);                                  \
  template double interpolate_phi<D>(const Grid<D>&, View<const double>, View<const double, 2>, \
                                     index_t, double*);                                         \
  template index_t push_out<D>(const Grid<D>&, View<double, 2>, View<double, 2>,                \
                               View<const double>, double, View<const double, 2>);              \
  template void sliver_fractions<D>(const Grid<D>&, View<const double>, View<double>, bool);    \
  template void extend_velocity<D>(const Grid<D>&, View<const index_t>, View<const double>,     \
                                   View<double, 2>, View<double, 2>);

MPMFLOW_INSTANTIATE(2)
MPMFLOW_INSTANTIATE(3)
#undef MPMFLOW_INSTANTIATE

}  // namespace mpmflow
