#include "multigrid.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "strips.hpp"

namespace mpmflow {

namespace {

template <int D>
void coords_of(index_t i, const std::array<index_t, D>& dims, std::array<index_t, D>& out) {
  for (int k = 0; k < D; ++k) {
    out[k] = i % dims[k];
    i /= dims[k];
  }
}

// y = A x (subtract: y = b - A x) for rows lo to hi - 1; NS slots a row (0: cols' width);
// I: the columns' type.
template <int NS, class I>
void matvec_rows(View<const I, 2> cols, View<const double, 2> vals, View<const double> x,
                 const double* b, View<double> y, index_t lo, index_t hi, bool subtract) {
  const index_t ns = NS > 0 ? NS : cols.extent(1);
  for (index_t r = lo; r < hi; ++r) {
    if (ns == 0) {
      y(r) = subtract ? b[r] : 0.0;
      continue;
    }
    const double acc = ell_row_product<NS, I>(cols, vals, x, r, ns);
    y(r) = subtract ? b[r] - acc : acc;
  }
}

// y = A x or b - A x over all rows, by CHUNKS chunks on all threads when n >= PARALLEL_ROWS.
template <class I>
void apply(View<const I, 2> cols, View<const double, 2> vals, View<const double> x, const double* b,
           View<double> y, bool subtract) {
  static_assert(PARALLEL_ROWS == SERIAL_BELOW, "for_each_chunk's cut-off is the levels'");
  const index_t n = cols.extent(0);
  const index_t ns = cols.extent(1);
  for_each_range(n, [&](index_t, index_t lo, index_t hi) {
    if (ns == 9)
      matvec_rows<9, I>(cols, vals, x, b, y, lo, hi, subtract);
    else if (ns == 27)
      matvec_rows<27, I>(cols, vals, x, b, y, lo, hi, subtract);
    else if (ns == 5)  // the stars of star_slots
      matvec_rows<5, I>(cols, vals, x, b, y, lo, hi, subtract);
    else if (ns == 7)
      matvec_rows<7, I>(cols, vals, x, b, y, lo, hi, subtract);
    else
      matvec_rows<0, I>(cols, vals, x, b, y, lo, hi, subtract);
  });
}

// Gauss-Seidel update of rows[lo:hi] (one colour: the rows do not couple).
template <int NS, class I>
void gs_rows(View<const I, 2> cols, View<const double, 2> vals, View<const double> b,
             View<double> x, View<const index_t> rows, index_t lo, index_t hi) {
  for (index_t k = lo; k < hi; ++k) gs_row<NS, I>(cols, vals, b, x, rows(k), nullptr, 0);
}

// One 2^D-colour Gauss-Seidel sweep, colours in order (forward) or in reverse; NS: the
// slots of a row of cols (3^D, or the star's 2D + 1).
template <int D, int NS, class I>
void gauss_seidel(View<const I, 2> cols, View<const double, 2> vals, View<const double> b,
                  View<double> x, View<const index_t> rows,
                  const std::array<index_t, (1 << D) + 1>& cstart, bool forward) {
  constexpr int NCOL = 1 << D;
  const index_t n = cols.extent(0);
  for (int k = 0; k < NCOL; ++k) {
    const int colour = forward ? k : NCOL - 1 - k;
    const index_t lo = cstart[colour], hi = cstart[colour + 1];
    for_each_range(
        hi - lo,
        [&](index_t, index_t a, index_t z) {
          gs_rows<NS, I>(cols, vals, b, x, rows, lo + a, lo + z);
        },
        n);
  }
}

// The first forward sweep from x = 0 (no fill needed): a row of colour c reads only its
// neighbours of colours before c (updated in this sweep; first_sweep_slots); the others
// still hold 0, and subtracting v 0 leaves the sum as it was, so skipping them gives the
// values of a sweep after x = 0. NS as gauss_seidel's: on the star's slots, those of
// first_sweep_slots the star holds, as indices into it (in the same ascending order).
template <int D, int NS, class I>
void gauss_seidel_first(View<const I, 2> cols, View<const double, 2> vals, View<const double> b,
                        View<double> x, View<const index_t> rows,
                        const std::array<index_t, (1 << D) + 1>& cstart) {
  constexpr int NCOL = 1 << D;
  constexpr int FULL = stencil_size(D);
  static_assert(NS == FULL || NS == 2 * D + 1, "a row of 3^D slots or of the star's");
  const index_t n = cols.extent(0);
  for (int colour = 0; colour < NCOL; ++colour) {
    int full[FULL], slots[FULL];
    const int nfull = first_sweep_slots<D>(colour, full);
    int nslots = 0;
    if constexpr (NS == FULL) {
      for (int u = 0; u < nfull; ++u) slots[nslots++] = full[u];
    } else {
      constexpr auto star = star_slots<D>();
      for (int t = 0; t < NS; ++t)
        for (int u = 0; u < nfull; ++u)
          if (full[u] == star[t]) slots[nslots++] = t;
    }
    const index_t lo = cstart[colour], hi = cstart[colour + 1];
    for_each_range(
        hi - lo,
        [&](index_t, index_t a, index_t z) {
          for (index_t k = lo + a; k < lo + z; ++k)
            gs_row<NS, I>(cols, vals, b, x, rows(k), slots, nslots);
        },
        n);
  }
}

// r_c = P^T r_f from P's transpose (Level::tstart, trow, tw): each coarse row sums its fine
// rows' terms in their order, from 0 (the bits of the serial scatter over the fine rows,
// on any number of threads).
void restrict_to(View<const index_t> tstart, View<const index_t> trow, View<const double> tw,
                 View<const double> rf, View<double> rc) {
  const index_t nc = rc.size();
  for_each_range(
      nc,
      [&](index_t, index_t lo, index_t hi) {
        for (index_t I = lo; I < hi; ++I) {
          double acc = 0.0;
          for (index_t k = tstart(I); k < tstart(I + 1); ++k) acc += tw(k) * rf(trow(k));
          rc(I) = acc;
        }
      },
      rf.size());
}

// x_f += P e_c (rows independent: in parallel on large levels, the same bits).
template <int NP>
void prolong_add(View<const index_t, 2> pcols, View<const double, 2> pw, View<const double> ec,
                 View<double> xf) {
  for_each_range(pcols.extent(0), [&](index_t, index_t lo, index_t hi) {
    for (index_t r = lo; r < hi; ++r) prolong_row<NP>(pcols, pw, ec, xf, r);
  });
}

// CG updates: x += alpha p, r -= alpha q (step), or p = z + beta p.
void cg_update(View<double> x, View<double> r, View<double> p, View<const double> q,
               View<const double> z, double alpha, double beta, bool step) {
  for_each_range(r.size(), [&](index_t, index_t lo, index_t hi) {
    if (step) {
      for (index_t i = lo; i < hi; ++i) {
        x(i) += alpha * p(i);
        r(i) -= alpha * q(i);
      }
    } else {
      for (index_t i = lo; i < hi; ++i) p(i) = z(i) + beta * p(i);
    }
  });
}

void fill(View<double> v, double value) {
  for_each_range(v.size(), [&](index_t, index_t lo, index_t hi) {
    for (index_t i = lo; i < hi; ++i) v(i) = value;
  });
}

void copy(View<const double> from, View<double> to) {
  for_each_range(to.size(), [&](index_t, index_t lo, index_t hi) {
    for (index_t i = lo; i < hi; ++i) to(i) = from(i);
  });
}

// The contributions of fine rows r0 to r1 - 1 to P^T A P; the slot of coarse column J in
// coarse row I from their coarse coordinates, sum_k (J_k - I_k + 1) 3^k = NS / 2 + h(J) - h(I)
// with h(I) = sum_k I_k 3^k (chash) (the Numba kernel's slot table gives the same
// slots where it is used).
//
// On periodic coarse axes (cperiod[k] > 0) the coordinates' differences wrap round, so the
// slot comes from the coordinates themselves (ccoord).
template <int D, bool PERIODIC>
inline index_t coarse_slot(index_t I, index_t J, View<const index_t> chash,
                           View<const index_t, 2> ccoord, const std::array<index_t, D>& cperiod) {
  constexpr int NS = stencil_size(D);
  if constexpr (!PERIODIC) return NS / 2 - chash(I) + chash(J);
  index_t slot = 0, p3 = 1;
  for (int k = 0; k < D; ++k) {
    index_t d = ccoord(J, k) - ccoord(I, k);
    if (cperiod[k] > 0) {
      if (d > 1)
        d -= cperiod[k];
      else if (d < -1)
        d += cperiod[k];
    }
    slot += (d + 1) * p3;
    p3 *= 3;
  }
  return slot;
}

template <int D, bool PERIODIC>
void galerkin_rows(index_t r0, index_t r1, View<const index_t, 2> cols, View<const double, 2> vals,
                   View<const index_t, 2> pcols, View<const double, 2> pw,
                   View<const index_t> chash, View<const index_t, 2> ccoord,
                   const std::array<index_t, D>& cperiod, View<index_t, 2> ccols,
                   View<double, 2> cvals) {
  constexpr int NP = 1 << D;
  constexpr int NS = stencil_size(D);
  for (index_t r = r0; r < r1; ++r) {
    for (int a = 0; a < NP; ++a) {
      const index_t I = pcols(r, a);
      if (I < 0) break;  // P's entries of a row come first, then -1
      const double wa = pw(r, a);
      for (int s = 0; s < NS; ++s) {
        const index_t j = cols(r, s);
        if (j < 0) continue;
        const double v = wa * vals(r, s);
        for (int b = 0; b < NP; ++b) {
          const index_t J = pcols(j, b);
          if (J < 0) break;
          const index_t slot = coarse_slot<D, PERIODIC>(I, J, chash, ccoord, cperiod);
          ccols(I, slot) = J;
          cvals(I, slot) += v * pw(j, b);
        }
      }
    }
  }
}

}  // namespace

void matvec(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
            View<double> y) {
  apply<index_t>(cols, vals, x, nullptr, y, false);
}

void residual(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
              View<const double> b, View<double> r) {
  apply<index_t>(cols, vals, x, b.data(), r, true);
}

double dot(View<const double> a, View<const double> b) {
  const index_t n = a.size();
  if (n < PARALLEL_ROWS) {
    double acc = 0.0;
    for (index_t i = 0; i < n; ++i) acc += a(i) * b(i);
    return acc;
  }
  return reduce_chunks<double>(n, [&](index_t lo, index_t hi) {
    double acc = 0.0;
    for (index_t i = lo; i < hi; ++i) acc += a(i) * b(i);
    return acc;
  });
}

index_t largest_magnitude(View<const double> r) {
  index_t worst = 0;
  double big = -1.0;
  for (index_t i = 0; i < r.size(); ++i) {
    const double a = std::abs(r(i));
    if (!(a <= big)) {
      big = a;
      worst = i;
      if (a != a) break;
    }
  }
  return worst;
}

index_t worst_row(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
                  View<const double> b, View<double> r) {
  residual(cols, vals, x, b, r);
  return largest_magnitude(r);
}

template <int D>
void Multigrid<D>::setup(View<const index_t, 2> cols, View<const double, 2> vals,
                         View<const index_t> node, const std::array<index_t, D>& dims,
                         index_t coarsest, const std::array<index_t, D>& period) {
  static_assert(std::is_nothrow_move_constructible_v<Level>,
                "levels keep views of their own storage: moving must not copy it");
  if (cols.extent(1) != NS || vals.extent(1) != NS || vals.extent(0) != cols.extent(0) ||
      node.size() != cols.extent(0))
    throw std::invalid_argument("multigrid: cols, vals must be n x 3^D and node n long");
  if (level_.empty()) level_.emplace_back();
  {
    Level& f = level_[0];
    f.n = cols.extent(0);
    f.dims = dims;
    f.period = period;
    f.cols = cols;
    f.vals = vals;
    f.node = node;
  }
  nlev_ = 1;
  coordinates(level_[0]);
  while (level_[nlev_ - 1].n > coarsest) {
    coarse_level(nlev_ - 1);
    // nothing left, or no axis coarsened any more (periodic axes of few points)
    if (level_[nlev_].n == 0 || level_[nlev_].n >= level_[nlev_ - 1].n) break;
    galerkin(nlev_ - 1);
    ++nlev_;
  }
  for (index_t l = 0; l < nlev_; ++l) {
    Level& lv = level_[l];
    colour_rows(lv);
    compact(lv);
    lv.r = lv.r_store.sized(lv.n);
    if (l > 0) {
      lv.b = lv.b_store.sized(lv.n);
      lv.x = lv.x_store.sized(lv.n);
    }
  }
  factor();
  const index_t n = level_[0].n;
  r_store_.reserve(n);
  p_store_.reserve(n);
  q_store_.reserve(n);
  z_store_.reserve(n);
}

template <int D>
void Multigrid<D>::coarse_level(index_t l) {
  if (static_cast<index_t>(level_.size()) < l + 2) level_.emplace_back();
  Level& f = level_[l];
  Level& c = level_[l + 1];
  std::array<index_t, D> cdims{}, ix{}, cperiod{};
  // a periodic axis is halved while its coarse period stays even and at least 4; kept
  // whole (every fine point is a coarse one along it) after that
  std::array<bool, D> halve{}, whole{};
  index_t ncn = 1;
  for (int k = 0; k < D; ++k) {
    const index_t P = f.period[k];
    whole[k] = P > 0 && !(P % 4 == 0 && P >= 8);
    halve[k] = P > 0 && !whole[k];
    cdims[k] = whole[k] ? P : halve[k] ? P / 2 : f.dims[k] / 2 + 1;
    cperiod[k] = P > 0 ? cdims[k] : 0;
    ncn *= cdims[k];
  }
  View<index_t> crow = crow_store_.sized(ncn);
  for (index_t i = 0; i < ncn; ++i) crow(i) = -1;
  const index_t n = f.n;
  for (index_t r = 0; r < n; ++r) {
    for (int k = 0; k < D; ++k) ix[k] = f.coord(r, k);
    bool even = true;
    index_t ci = 0, stride = 1;
    for (int k = 0; k < D; ++k) {
      if (whole[k]) {
        ci += ix[k] * stride;
      } else {
        if (ix[k] % 2 != 0) even = false;
        ci += (ix[k] / 2) * stride;
      }
      stride *= cdims[k];
    }
    if (even) crow(ci) = 0;
  }
  index_t nc = 0;
  for (index_t i = 0; i < ncn; ++i)
    if (crow(i) == 0) ++nc;
  View<index_t> cnode = c.node_store.sized(nc);
  nc = 0;
  for (index_t i = 0; i < ncn; ++i)
    if (crow(i) == 0) {
      crow(i) = nc;
      cnode(nc) = i;
      ++nc;
    }
  c.n = nc;
  c.dims = cdims;
  c.period = cperiod;
  c.node = cnode;
  f.pcols = f.pcols_store.template sized<2>({n, NP});
  f.pw = f.pw_store.template sized<2>({n, NP});
  for (index_t r = 0; r < n; ++r) {
    for (int k = 0; k < D; ++k) ix[k] = f.coord(r, k);
    int m = 0;
    for (int a = 0; a < NP; ++a) {
      f.pcols(r, a) = -1;
      f.pw(r, a) = 0.0;
    }
    for (int combo = 0; combo < NP; ++combo) {  // axis 0 fastest
      index_t ci = 0, stride = 1;
      double w = 1.0;
      bool ok = true;
      for (int k = 0; k < D; ++k) {
        const int up = (combo >> k) & 1;
        index_t ck;
        if (whole[k]) {
          if (up) {
            ok = false;
            break;
          }
          ck = ix[k];
        } else if (ix[k] % 2 == 0) {
          if (up) {
            ok = false;
            break;
          }
          ck = ix[k] / 2;
        } else {
          ck = ix[k] / 2 + up;
          w *= 0.5;
          if (halve[k] && ck == cdims[k]) ck = 0;  // across the periodic axis's end
        }
        if (ck >= cdims[k]) {
          ok = false;
          break;
        }
        ci += ck * stride;
        stride *= cdims[k];
      }
      if (!ok) continue;
      if (crow(ci) >= 0) {
        f.pcols(r, m) = crow(ci);
        f.pw(r, m) = w;
        ++m;
      }
    }
  }
  // P's transpose: a counting sort of P's entries by coarse row, the fine rows ascending
  f.tstart = f.tstart_store.sized(nc + 1);
  for (index_t I = 0; I <= nc; ++I) f.tstart(I) = 0;
  index_t nnz = 0;
  for (index_t r = 0; r < n; ++r)
    for (int a = 0; a < NP && f.pcols(r, a) >= 0; ++a) {
      ++f.tstart(f.pcols(r, a) + 1);
      ++nnz;
    }
  for (index_t I = 0; I < nc; ++I) f.tstart(I + 1) += f.tstart(I);
  f.trow = f.trow_store.sized(nnz);
  f.tw = f.tw_store.sized(nnz);
  View<index_t> fill_at = crow_store_.sized(nc);  // crow is spent: the next free slot
  for (index_t I = 0; I < nc; ++I) fill_at(I) = f.tstart(I);
  for (index_t r = 0; r < n; ++r)
    for (int a = 0; a < NP && f.pcols(r, a) >= 0; ++a) {
      const index_t k = fill_at(f.pcols(r, a))++;
      f.trow(k) = r;
      f.tw(k) = f.pw(r, a);
    }
  coordinates(c);
  View<index_t> chash = ccoord_store_.sized(nc);
  for (index_t I = 0; I < nc; ++I) {
    index_t h = 0, p3 = 1;
    for (int k = 0; k < D; ++k) {
      h += c.coord(I, k) * p3;
      p3 *= 3;
    }
    chash(I) = h;
  }
}

template <int D>
void Multigrid<D>::galerkin(index_t l) {
  Level& f = level_[l];
  Level& c = level_[l + 1];
  const index_t nc = c.n, n = f.n;
  View<index_t, 2> ccols = c.cols_store.template sized<2>({nc, NS});
  View<double, 2> cvals = c.vals_store.template sized<2>({nc, NS});
  for (index_t i = 0; i < nc * NS; ++i) {
    ccols[i] = -1;
    cvals[i] = 0.0;
  }
  c.cols = ccols;
  c.vals = cvals;
  View<const index_t> chash = ccoord_store_.view(nc);
  View<const index_t, 2> ccoord = c.coord;
  bool periodic = false;
  for (int k = 0; k < D; ++k) periodic = periodic || c.period[k] > 0;
  // serial when small, or when the last axis is periodic (its first and last slabs meet)
  if (n < PARALLEL_ROWS || c.period[D - 1] > 0) {
    if (periodic)
      galerkin_rows<D, true>(0, n, f.cols, f.vals, f.pcols, f.pw, chash, ccoord, c.period, ccols,
                             cvals);
    else
      galerkin_rows<D, false>(0, n, f.cols, f.vals, f.pcols, f.pw, chash, ccoord, c.period, ccols,
                              cvals);
    return;
  }
  // strips of whole slabs (nodes of equal last coordinate), at least 2 each: fine row r adds
  // only to coarse rows within one slab of it, so strips two apart never meet
  index_t per = 1;
  for (int k = 0; k < D - 1; ++k) per *= f.dims[k];
  const index_t y0 = f.node(0) / per;
  const index_t y1 = f.node(n - 1) / per + 1;
  View<index_t> row_cum = row_cum_store_.sized(y1 - y0 + 1);
  index_t i = 0;
  for (index_t s = 0; s <= y1 - y0; ++s) {  // np.searchsorted(node, (y0 + s) per)
    const index_t target = (y0 + s) * per;
    while (i < n && f.node(i) < target) ++i;
    row_cum(s) = i;
  }
  std::array<index_t, STRIPS + 1> strip{}, bounds{};
  const index_t k = strips(row_cum, STRIPS, 2, View<index_t>(strip.data(), {STRIPS + 1}));
  for (index_t u = 0; u <= k; ++u) bounds[u] = row_cum(strip[u]);
  for_strips(bounds.data(), k, n, [&](index_t lo, index_t hi) {
    if (periodic)
      galerkin_rows<D, true>(lo, hi, f.cols, f.vals, f.pcols, f.pw, chash, ccoord, c.period, ccols,
                             cvals);
    else
      galerkin_rows<D, false>(lo, hi, f.cols, f.vals, f.pcols, f.pw, chash, ccoord, c.period, ccols,
                              cvals);
  });
}

template <int D>
void Multigrid<D>::colour_rows(Level& lv) {
  constexpr int NCOL = 1 << D;
  lv.rows = lv.rows_store.sized(lv.n);
  lv.cstart.fill(0);
  auto colour = [&](index_t r) {  // sum_k (i_k mod 2) 2^k
    int c = 0;
    for (int k = 0; k < D; ++k) c += static_cast<int>(lv.coord(r, k) % 2) << k;
    return c;
  };
  for (index_t r = 0; r < lv.n; ++r) lv.cstart[colour(r) + 1] += 1;
  for (int k = 0; k < NCOL; ++k) lv.cstart[k + 1] += lv.cstart[k];
  std::array<index_t, NCOL> fill{};
  for (int k = 0; k < NCOL; ++k) fill[k] = lv.cstart[k];
  for (index_t r = 0; r < lv.n; ++r) lv.rows(fill[colour(r)]++) = r;
}

template <int D>
void Multigrid<D>::coordinates(Level& lv) {
  lv.coord = lv.coord_store.template sized<2>({lv.n, D});
  std::array<index_t, D> ix{};
  for (index_t r = 0; r < lv.n; ++r) {
    coords_of<D>(lv.node(r), lv.dims, ix);
    for (int k = 0; k < D; ++k) lv.coord(r, k) = ix[k];
  }
}

// The dense coarsest operator and its Cholesky factor L (A = L L^T, lower, row-major), by
// the unblocked algorithm of LAPACK's potf2 (column j: the diagonal, then the column below
// it scaled by 1 / L_jj); NumPy's LAPACK (np.linalg.cholesky in the Numba kernel) sums in
// its own blocked order, so the factors agree to rounding.
template <int D>
void Multigrid<D>::factor() {
  const Level& c = level_[nlev_ - 1];
  const index_t n = c.n;
  View<double, 2> L = factor_store_.template sized<2>({n, n});
  for (index_t i = 0; i < n * n; ++i) L[i] = 0.0;
  for (index_t r = 0; r < n; ++r)
    for (int s = 0; s < NS; ++s)
      if (c.cols(r, s) >= 0) L(r, c.cols(r, s)) += c.vals(r, s);
  for (index_t j = 0; j < n; ++j) {
    double ajj = L(j, j);
    for (index_t k = 0; k < j; ++k) ajj -= L(j, k) * L(j, k);
    if (!(ajj > 0.0))
      throw std::runtime_error(
          "multigrid: the coarsest operator is not positive definite (Cholesky failed)");
    ajj = std::sqrt(ajj);
    L(j, j) = ajj;
    const double inv = 1.0 / ajj;
    for (index_t i = j + 1; i < n; ++i) {
      double acc = L(i, j);
      for (index_t k = 0; k < j; ++k) acc -= L(i, k) * L(j, k);
      L(i, j) = acc * inv;
    }
  }
  for (index_t i = 0; i < n; ++i)  // the upper triangle held A: clear it, as NumPy's L
    for (index_t j = i + 1; j < n; ++j) L(i, j) = 0.0;
}

template <int D>
void Multigrid<D>::cholesky_solve(View<const double> b, View<double> x) {
  const index_t n = level_[nlev_ - 1].n;
  cholesky_solve_dense(factor_store_.template view<2>({n, n}).data(), n, b, x);
}

template <int D>
void Multigrid<D>::compact(Level& lv) {
  constexpr auto star = star_slots<D>();
  constexpr int NK = 2 * D + 1;
  lv.icols = {};
  lv.kvals = {};
  const index_t n = lv.n;
  if (n == 0 || n > std::numeric_limits<std::int32_t>::max()) return;
  bool in_star[NS] = {};
  for (int s : star) in_star[s] = true;
  const auto off = [&](index_t lo, index_t hi) {  // a row in [lo, hi) fills a slot off it
    for (index_t r = lo; r < hi; ++r)
      for (int s = 0; s < NS; ++s)
        if (!in_star[s] && lv.cols(r, s) >= 0) return index_t(1);
    return index_t(0);
  };
  // most operators (the pressure's, the coarse levels') fill a corner slot in their first
  // row: only a star's operator is scanned whole
  if (off(0, 1) || reduce_chunks<index_t>(n, off) > 0) {  // all 3^D slots, 32-bit columns
    auto ic = lv.icols_store.template sized<2>({n, NS});
    for_each_range(n, [&](index_t, index_t lo, index_t hi) {
      for (index_t r = lo; r < hi; ++r)
        for (int s = 0; s < NS; ++s) ic(r, s) = static_cast<std::int32_t>(lv.cols(r, s));
    });
    lv.icols = ic;
    return;
  }
  auto ic = lv.icols_store.template sized<2>({n, NK});
  for_each_range(n, [&](index_t, index_t lo, index_t hi) {
    for (index_t r = lo; r < hi; ++r)
      for (int t = 0; t < NK; ++t) ic(r, t) = static_cast<std::int32_t>(lv.cols(r, star[t]));
  });
  lv.icols = ic;
  lv.kvals = lv.kvals_store.template sized<2>({n, NK});
  star_values(lv);
}

template <int D>
void Multigrid<D>::star_values(Level& lv) {
  constexpr auto star = star_slots<D>();
  constexpr int NK = 2 * D + 1;
  if (lv.kvals.size() == 0) return;
  auto kv = lv.kvals_store.template view<2>({lv.n, NK});
  for_each_range(lv.n, [&](index_t, index_t lo, index_t hi) {
    for (index_t r = lo; r < hi; ++r)
      for (int t = 0; t < NK; ++t) kv(r, t) = lv.vals(r, star[t]);
  });
}

template <int D>
void Multigrid<D>::refresh() {
  if (nlev_ > 0) star_values(level_[0]);
}

template <int D>
void Multigrid<D>::iterate_apply(const Level& lv, View<const double> x, const double* b,
                                 View<double> y, bool subtract) const {
  with_form(lv, [&](auto, auto cols, auto vals) { apply(cols, vals, x, b, y, subtract); });
}

template <int D>
void Multigrid<D>::vcycle(View<const double> b, View<double> x, int sweeps) {
  if (nlev_ == 0) throw std::logic_error("multigrid: vcycle before setup");
  auto bl = [&](index_t l) -> View<const double> { return l == 0 ? b : level_[l].b; };
  auto xl = [&](index_t l) -> View<double> { return l == 0 ? x : level_[l].x; };
  // a level's sweeps on its iteration form (compact: the same sums)
  const auto first = [&](const Level& lv, View<double> xv, View<const double> bv) {
    with_form(lv, [&](auto ns, auto cols, auto vals) {
      gauss_seidel_first<D, decltype(ns)::value>(cols, vals, bv, xv, lv.rows, lv.cstart);
    });
  };
  const auto sweep = [&](const Level& lv, View<double> xv, View<const double> bv, bool fwd) {
    with_form(lv, [&](auto ns, auto cols, auto vals) {
      gauss_seidel<D, decltype(ns)::value>(cols, vals, bv, xv, lv.rows, lv.cstart, fwd);
    });
  };
  for (index_t l = 0; l + 1 < nlev_; ++l) {
    Level& lv = level_[l];
    const View<double> xv = xl(l);
    if (sweeps > 0)
      first(lv, xv, bl(l));
    else
      fill(xv, 0.0);
    for (int s = 1; s < sweeps; ++s) sweep(lv, xv, bl(l), true);
    iterate_apply(lv, xv, bl(l).data(), lv.r, true);
    restrict_to(lv.tstart, lv.trow, lv.tw, lv.r, level_[l + 1].b);
  }
  cholesky_solve(bl(nlev_ - 1), xl(nlev_ - 1));
  for (index_t l = nlev_ - 2; l >= 0; --l) {
    Level& lv = level_[l];
    prolong_add<NP>(lv.pcols, lv.pw, level_[l + 1].x, xl(l));
    for (int s = 0; s < sweeps; ++s) sweep(lv, xl(l), bl(l), false);
  }
}

template <int D>
SolveResult Multigrid<D>::pcg(View<const double> rhs, View<double> x, double tol, index_t maxiter,
                              int sweeps) {
  if (nlev_ == 0) throw std::logic_error("multigrid: pcg before setup");
  const Level& f = level_[0];
  const index_t n = f.n;
  if (rhs.size() != n || x.size() != n)
    throw std::invalid_argument("multigrid: rhs and x must have one value per row");
  // the host's vector operations, on all threads for long vectors (the same bits on any
  // number of them)
  struct HostOps {
    Multigrid& mg;
    const Level& f;
    int sweeps;
    double dot(View<const double> a, View<const double> b) { return mpmflow::dot(a, b); }
    void residual(View<const double> x, View<const double> b, View<double> r) {
      mg.iterate_apply(f, x, b.data(), r, true);
    }
    void matvec(View<const double> p, View<double> q) { mg.iterate_apply(f, p, nullptr, q, false); }
    void vcycle(View<const double> r, View<double> z) { mg.vcycle(r, z, sweeps); }
    void fill(View<double> v, double value) { mpmflow::fill(v, value); }
    void copy(View<const double> from, View<double> to) { mpmflow::copy(from, to); }
    void cg_update(View<double> x, View<double> r, View<double> p, View<const double> q,
                   View<const double> z, double alpha, double beta, bool step) {
      mpmflow::cg_update(x, r, p, q, z, alpha, beta, step);
    }
  } ops{*this, f, sweeps};
  return pcg_iterate(ops, rhs, x, r_store_.sized(n), p_store_.sized(n), q_store_.sized(n),
                     z_store_.sized(n), tol, maxiter);
}

template <int D>
index_t Multigrid<D>::levels() const {
  return nlev_;
}

template <int D>
index_t Multigrid<D>::rows() const {
  return nlev_ > 0 ? level_[0].n : 0;
}

template <int D>
typename Multigrid<D>::LevelView Multigrid<D>::level(index_t l) const {
  if (l < 0 || l >= nlev_) throw std::out_of_range("multigrid: no such level");
  const Level& lv = level_[l];
  LevelView out;
  out.n = lv.n;
  out.cstart = lv.cstart;
  out.cols = lv.cols;
  out.vals = lv.vals;
  out.rows = lv.rows;
  if (l + 1 < nlev_) {
    out.pcols = lv.pcols;
    out.pw = lv.pw;
  }
  return out;
}

template <int D>
View<const double, 2> Multigrid<D>::coarsest_factor() const {
  if (nlev_ == 0) throw std::logic_error("multigrid: no factor before setup");
  const index_t n = level_[nlev_ - 1].n;
  return View<const double, 2>(factor_store_.data(), {n, n});
}

template class Multigrid<2>;
template class Multigrid<3>;

}  // namespace mpmflow
