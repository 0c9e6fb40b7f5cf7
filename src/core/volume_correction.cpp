#include "volume_correction.hpp"

#include "parallel.hpp"
#include "transfer.hpp"

namespace mpmflow {

template <int D>
void cell_volume(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                 View<double> out) {
  for (index_t c = 0; c < out.size(); ++c) out[c] = 0.0;
  const index_t n = x.extent(0);
  for (index_t p = 0; p < n; ++p) scatter_cell_volume<D>(g, x, p, volume(p), out);
}

template <int D>
bool wall_released(const Grid<D>& g, const std::array<index_t, D>& cx,
                   View<const bool, 2> contact) {
  index_t first = 0;
  for (int k = 0; k < D; ++k) first += cx[k] * g.ns[k];
  for (int k = 0; k < D; ++k)
    for (int side = 0; side < 2; ++side) {
      if (g.periodic[k] || cx[k] != (side == 0 ? 0 : g.cells[k] - 1)) continue;
      for (int a = 0; a < Grid<D>::NC; ++a) {
        if (((a >> k) & 1) != side) continue;
        if (!contact(first + g.corner[a], k)) return true;
      }
    }
  return false;
}

template <int D>
VolumeSystem assemble(const Grid<D>& g, View<const double> theta, View<const double> density,
                      double wet, View<const bool, 2> contact, View<const index_t> static_slot,
                      View<index_t> cell_row, View<index_t, 2> cols, View<double, 2> vals,
                      View<double> rhs, View<index_t> rows) {
  constexpr int NS = Grid<D>::NS;
  constexpr int centre = NS / 2;
  index_t n = 0;
  for (index_t c = 0; c < g.ncells; ++c) {
    if (theta(c) > 0.0 && static_slot(c) >= 0) {
      cell_row(c) = n;
      rows(n) = c;
      ++n;
    } else {
      cell_row(c) = -1;
    }
  }
  // rows are independent: any row touching air anchors the system
  const index_t anchored = reduce_chunks<index_t>(n, [&](index_t lo, index_t hi) {
    index_t air = 0;
    std::array<index_t, D> cx;
    for (index_t r = lo; r < hi; ++r) {
      const index_t c = rows(r);
      g.cell_coords(c, cx.data());
      for (int s = 0; s < NS; ++s) {
        cols(r, s) = -1;
        vals(r, s) = 0.0;
      }
      double diag = 0.0;
      index_t p3 = 1;
      for (int k = 0; k < D; ++k) {
        for (int step = 1; step >= -1; step -= 2) {
          const index_t j = g.wrap_cell(k, cx[k] + step);
          const index_t other = c + (j - cx[k]) * g.cs[k];
          if (j < 0 || static_slot(other) < 0) continue;  // a wall or a solid: no flux
          diag += 1.0;
          const index_t nb = cell_row(other);
          if (nb >= 0) {
            const index_t s = centre + step * p3;
            cols(r, s) = nb;
            vals(r, s) = -1.0;
          } else {
            air = 1;
          }
        }
        p3 *= 3;
      }
      cols(r, centre) = r;
      vals(r, centre) = diag;
      bool surface = wall_released<D>(g, cx, contact);
      if (!surface) {
        for (int b = 0; b < NS; ++b) {
          index_t j = 0;
          bool inside = true;
          int rem = b;
          for (int k = 0; k < D; ++k) {
            const index_t jk = g.wrap_cell(k, cx[k] + rem % 3 - 1);
            rem /= 3;
            if (jk < 0) {
              inside = false;
              break;
            }
            j += jk * g.cs[k];
          }
          if (inside && (theta(j) < wet || static_slot(j) != 0)) {
            surface = true;
            break;
          }
        }
      }
      const double excess = density(c) - 1.0;
      rhs(r) = surface ? (0.0 > excess ? 0.0 : excess) : excess;  // max(excess, 0)
    }
    return air;
  });
  return VolumeSystem{n, anchored > 0};
}

namespace {

// Displacement (m) across the face from cell a to cell b: -scale (q_b - q_a), air q = 0,
// limited to dmax; 0 between two cells without material.
inline double face_value(View<const index_t> cell_row, View<const double> q, index_t a, index_t b,
                         double scale, double dmax) {
  const index_t ra = cell_row(a);
  const index_t rb = cell_row(b);
  if (ra < 0 && rb < 0) return 0.0;
  const double qa = ra >= 0 ? q(ra) : 0.0;
  const double qb = rb >= 0 ? q(rb) : 0.0;
  const double d = -scale * (qb - qa);
  const double up = -dmax > d ? -dmax : d;  // Python's max(d, -dmax), NaN kept
  return dmax < up ? dmax : up;
}

}  // namespace

template <int D>
void face_displacements(const Grid<D>& g, View<const index_t> cell_row,
                        View<const index_t> static_slot, View<const double> q, double scale,
                        double dmax, const std::array<View<double>, D>& faces) {
  for (int k = 0; k < D; ++k) {
    const View<double> f = faces[k];
    // faces normal to k: cells[j] + (j == k) along each axis j, axis 0 fastest; slabs along
    // the last axis in chunks, the coordinates stepped face by face (no division)
    std::array<index_t, D> n;
    for (int j = 0; j < D; ++j) n[j] = g.cells[j] + (j == k ? 1 : 0);
    index_t per = 1;
    for (int j = 0; j < D - 1; ++j) per *= n[j];
    for_each_chunk(
        n[D - 1],
        [&](index_t, index_t lo, index_t hi) {
          std::array<index_t, D> ix{};
          ix[D - 1] = lo;
          for (index_t idx = lo * per; idx < hi * per; ++idx) {
            // b: the cell above the face along k (ix[k] < cells[k]), a = b - cs[k] below it
            const index_t ik = ix[k];
            if (!g.periodic[k] && (ik == 0 || ik == g.cells[k])) {
              f[idx] = 0.0;
            } else {
              // b above the face, a below it (across a periodic axis's end: the last cell)
              index_t b = 0;
              for (int j = 0; j < D; ++j) b += ix[j] * g.cs[j];
              if (ik == g.cells[k]) b -= g.cells[k] * g.cs[k];  // the face at a periodic end
              const index_t a =
                  ik == 0 || ik == g.cells[k] ? b + (g.cells[k] - 1) * g.cs[k] : b - g.cs[k];
              if (static_slot(b) < 0 || static_slot(a) < 0)
                f[idx] = 0.0;
              else
                f[idx] = face_value(cell_row, q, a, b, scale, dmax);
            }
            for (int j = 0; j < D; ++j) {
              if (++ix[j] < n[j] || j == D - 1) break;
              ix[j] = 0;
            }
          }
        },
        f.size());
  }
}

#define MPMFLOW_VOLUME(D)                                                                       \
  template void cell_volume<D>(const Grid<D>&, View<const double, 2>, View<const double>,       \
                               View<double>);                                                   \
  template bool wall_released<D>(const Grid<D>&, const std::array<index_t, D>&,                 \
                                 View<const bool, 2>);                                          \
  template VolumeSystem assemble<D>(const Grid<D>&, View<const double>, View<const double>,     \
                                    double, View<const bool, 2>, View<const index_t>,           \
                                    View<index_t>, View<index_t, 2>, View<double, 2>,           \
                                    View<double>, View<index_t>);                               \
  template void face_displacements<D>(const Grid<D>&, View<const index_t>, View<const index_t>, \
                                      View<const double>, double, double,                       \
                                      const std::array<View<double>, D>&);
MPMFLOW_VOLUME(2)
MPMFLOW_VOLUME(3)
#undef MPMFLOW_VOLUME

}  // namespace mpmflow
