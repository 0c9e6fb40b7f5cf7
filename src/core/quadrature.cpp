#include "quadrature.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "parallel.hpp"

namespace mpmflow {

namespace {

// accumulate_point on raw rows (K: NC*NC or null, C: NC*NC*D, V: NC), the products in the
// order of the Numba kernel.
template <int D>
inline void accumulate(double inv_h, const double* local, double w, double* K, double* C,
                       double* V) {
  constexpr int NC = 1 << D;
  std::array<double, NC> N;
  std::array<double, NC * D> dN;
  for (int a = 0; a < NC; ++a) {
    double n = 1.0;
    for (int k = 0; k < D; ++k) n *= ((a >> k) & 1) ? local[k] : 1.0 - local[k];
    N[a] = n;
    for (int k = 0; k < D; ++k) {
      double gk = ((a >> k) & 1) ? 1.0 : -1.0;
      for (int j = 0; j < D; ++j)
        if (j != k) gk *= ((a >> j) & 1) ? local[j] : 1.0 - local[j];
      dN[a * D + k] = gk * inv_h;
    }
  }
  for (int a = 0; a < NC; ++a) {
    V[a] += w * N[a];
    for (int b = 0; b < NC; ++b) {
      if (K) {
        double kk = 0.0;
        for (int k = 0; k < D; ++k) kk += dN[a * D + k] * dN[b * D + k];
        K[a * NC + b] += w * kk;
      }
      for (int k = 0; k < D; ++k) C[(a * NC + b) * D + k] += w * N[a] * dN[b * D + k];
    }
  }
}

}  // namespace

template <int D>
void accumulate_point(const Grid<D>& g, const double* local, double w, View<double, 2> K,
                      View<double, 3> C, View<double> V) {
  [[maybe_unused]] constexpr int NC = 1 << D;
  MPMFLOW_BOUNDS(V.size() == NC && C.size() == NC * NC * D);
  MPMFLOW_BOUNDS(K.size() == 0 || K.size() == NC * NC);
  accumulate<D>(1.0 / g.h, local, w, K.size() ? K.data() : nullptr, C.data(), V.data());
}

template <int D>
void gauss_cell_tensors(const Grid<D>& g, View<double, 2> K, View<double, 3> C, View<double> V) {
  constexpr int NC = 1 << D;
  for (index_t i = 0; i < K.size(); ++i) K[i] = 0.0;
  for (index_t i = 0; i < C.size(); ++i) C[i] = 0.0;
  for (index_t i = 0; i < V.size(); ++i) V[i] = 0.0;
  const double gp = 0.5 / std::sqrt(3.0);
  const double w = int_power(g.h, D) / NC;
  std::array<double, D> local;
  for (int q = 0; q < NC; ++q) {  // the last axis fastest
    for (int k = 0; k < D; ++k) local[k] = ((q >> (D - 1 - k)) & 1) ? 0.5 + gp : 0.5 - gp;
    accumulate_point<D>(g, local.data(), w, K, C, V);
  }
}

template <int D>
void particle_cell_tensors(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                           View<const index_t> order, View<const index_t> start,
                           View<const index_t> cells_list, View<double, 3> K, View<double, 4> C,
                           View<double, 2> V) {
  constexpr int NC = 1 << D;
  const double inv_h = 1.0 / g.h;
  const bool with_k = K.extent(0) > 0;
  const index_t n = cells_list.size();
  // work: the particles of the listed cells (the grid's mean per cell, empty cells counted,
  // would call a list of surface cells with 8 particles each serial work)
  index_t work = 0;
  for (index_t m = 0; m < n; ++m) work += start(cells_list(m) + 1) - start(cells_list(m));
  for_each_chunk(
      n,
      [&](index_t, index_t lo, index_t hi) {
        for (index_t m = lo; m < hi; ++m) {
          const index_t c = cells_list(m);
          std::array<index_t, D> first;
          g.cell_coords(c, first.data());
          double* Km = with_k ? &K(m, 0, 0) : nullptr;
          double* Cm = &C(m, 0, 0, 0);
          double* Vm = &V(m, 0);
          if (Km)
            for (int i = 0; i < NC * NC; ++i) Km[i] = 0.0;
          for (int i = 0; i < NC * NC * D; ++i) Cm[i] = 0.0;
          for (int i = 0; i < NC; ++i) Vm[i] = 0.0;
          std::array<double, D> local;
          for (index_t s = start(c); s < start(c + 1); ++s) {
            const index_t p = order(s);
            for (int k = 0; k < D; ++k)
              local[k] =
                  std::min(std::max(x(p, k) * inv_h - static_cast<double>(first[k]), 0.0), 1.0);
            accumulate<D>(inv_h, local.data(), volume(p), Km, Cm, Vm);
          }
        }
      },
      work);
}

template void accumulate_point<2>(const Grid<2>&, const double*, double, View<double, 2>,
                                  View<double, 3>, View<double>);
template void accumulate_point<3>(const Grid<3>&, const double*, double, View<double, 2>,
                                  View<double, 3>, View<double>);
template void gauss_cell_tensors<2>(const Grid<2>&, View<double, 2>, View<double, 3>, View<double>);
template void gauss_cell_tensors<3>(const Grid<3>&, View<double, 2>, View<double, 3>, View<double>);
template void particle_cell_tensors<2>(const Grid<2>&, View<const double, 2>, View<const double>,
                                       View<const index_t>, View<const index_t>,
                                       View<const index_t>, View<double, 3>, View<double, 4>,
                                       View<double, 2>);
template void particle_cell_tensors<3>(const Grid<3>&, View<const double, 2>, View<const double>,
                                       View<const index_t>, View<const index_t>,
                                       View<const index_t>, View<double, 3>, View<double, 4>,
                                       View<double, 2>);

}  // namespace mpmflow
