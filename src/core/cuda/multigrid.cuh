// The multigrid-preconditioned CG on a CUDA device (multigrid.hpp: Multigrid<D>::pcg and
// vcycle). The host builds the hierarchy (Multigrid<D>::setup: coarsening, Galerkin
// products, colours, the coarsest Cholesky factor); upload() copies it and pcg() iterates
// on the device with the host's element functions (ell_row_product, gs_row, prolong_row,
// cholesky_solve_dense), in the same order:
//   - a colour's Gauss-Seidel rows do not couple: a thread a row, the host's values;
//   - the restriction r_c = P^T r_f gathers instead of scattering: P^T is built at upload
//     with each coarse row's fine rows in increasing order, the order in which the host's
//     serial restriction adds them, so the same bits;
//   - the coarsest solve is one thread (at most COARSEST unknowns);
// so one V-cycle gives the host's bits. The CG's dot products are the device's
// deterministic sums (parallel.cuh): they differ from the host's chunk order by rounding,
// so host and device iterates agree to rounding and both meet the tolerance.
//
// Not yet on the device (issue 41): the setup itself (a step sets the hierarchy up anew, on
// the host here) and periodic axes (their rows are the host's, but untested here).
#pragma once

#include <vector>

#include "../multigrid.hpp"
#include "memory.hpp"
#include "parallel.cuh"

namespace mpmflow::gpu {

// The kernels of one level (free functions: device lambdas may not sit in private members).
template <int D>
struct LevelKernels {
  static constexpr int NS = stencil_size(D);
  static constexpr int NP = 1 << D;
  struct Slots {
    int s[stencil_size(D)];
    int n;
  };
  // y = b - A x
  static void residual(View<const index_t, 2> cols, View<const double, 2> vals,
                       View<const double> x, View<const double> b, View<double> y) {
    gpu::parallel_for(cols.extent(0), [=] __device__(index_t r) {
      y(r) = b(r) - ell_row_product<NS>(cols, vals, x, r, NS);
    });
  }
  static void matvec(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
                     View<double> y) {
    gpu::parallel_for(cols.extent(0), [=] __device__(index_t r) {
      y(r) = ell_row_product<NS>(cols, vals, x, r, NS);
    });
  }
  // rows[lo:hi] of one colour; slots: the first sweep's (first_sweep_slots), or all
  static void gs(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> b,
                 View<double> x, View<const index_t> rows, index_t lo, index_t hi, Slots slots,
                 bool first) {
    gpu::parallel_for(hi - lo, [=] __device__(index_t k) {
      gs_row<NS>(cols, vals, b, x, rows(lo + k), first ? slots.s : nullptr, slots.n);
    });
  }
  // r_c(c) = sum of tw[t] r_f(tfine[t]) for t in [tstart[c], tstart[c + 1])
  static void restrict_to(View<const index_t> tstart, View<const index_t> tfine,
                          View<const double> tw, View<const double> rf, View<double> rc) {
    gpu::parallel_for(rc.size(), [=] __device__(index_t c) {
      double acc = 0.0;
      for (index_t t = tstart(c); t < tstart(c + 1); ++t) acc += tw(t) * rf(tfine(t));
      rc(c) = acc;
    });
  }
  static void prolong(View<const index_t, 2> pcols, View<const double, 2> pw, View<const double> ec,
                      View<double> xf) {
    gpu::parallel_for(pcols.extent(0),
                      [=] __device__(index_t r) { prolong_row<NP>(pcols, pw, ec, xf, r); });
  }
  static void coarse_solve(View<const double, 2> L, View<const double> b, View<double> x) {
    gpu::parallel_for(
        1, [=] __device__(index_t) { cholesky_solve_dense(L.data(), L.extent(0), b, x); });
  }
  static void fill(View<double> v, double value) {
    gpu::parallel_for(v.size(), [=] __device__(index_t i) { v(i) = value; });
  }
  static void copy(View<const double> from, View<double> to) {
    gpu::parallel_for(to.size(), [=] __device__(index_t i) { to(i) = from(i); });
  }
  // x += alpha p, r -= alpha q (step), or p = z + beta p
  static void cg_update(View<double> x, View<double> r, View<double> p, View<const double> q,
                        View<const double> z, double alpha, double beta, bool step) {
    gpu::parallel_for(r.size(), [=] __device__(index_t i) {
      if (step) {
        x(i) += alpha * p(i);
        r(i) -= alpha * q(i);
      } else {
        p(i) = z(i) + beta * p(i);
      }
    });
  }
  static double dot(Workspace& ws, View<const double> a, View<const double> b) {
    return gpu::reduce_sum<double>(ws, a.size(),
                                   [=] __device__(index_t i) -> double { return a(i) * b(i); });
  }
};

template <int D>
class Multigrid {
  static constexpr int NS = stencil_size(D);
  static constexpr int NP = 1 << D;
  static constexpr int NCOL = 1 << D;
  using K = LevelKernels<D>;

  struct Level {
    index_t n = 0;
    std::array<index_t, NCOL + 1> cstart{};
    View<const index_t, 2> cols, pcols;
    View<const double, 2> vals, pw;
    View<const index_t> rows, tstart, tfine;
    View<const double> tw;
    View<double> b, x, r;
    DeviceBuffer<index_t> cols_s, rows_s, pcols_s, tstart_s, tfine_s;
    DeviceBuffer<double> vals_s, pw_s, tw_s, b_s, x_s, r_s;
  };

 public:
  // Copy the hierarchy of host's last setup to the device (storage grown, never shrunk).
  void upload(const mpmflow::Multigrid<D>& host) {
    nlev_ = host.levels();
    if (static_cast<index_t>(level_.size()) < nlev_) level_.resize(nlev_);
    for (index_t l = 0; l < nlev_; ++l) {
      const auto h = host.level(l);
      Level& lv = level_[l];
      lv.n = h.n;
      lv.cstart = h.cstart;
      lv.cols = copy_up<index_t, 2>(h.cols, lv.cols_s);
      lv.vals = copy_up<double, 2>(h.vals, lv.vals_s);
      lv.rows = copy_up<index_t, 1>(h.rows, lv.rows_s);
      lv.r = lv.r_s.sized(h.n);
      if (l > 0) {
        lv.b = lv.b_s.sized(h.n);
        lv.x = lv.x_s.sized(h.n);
      }
      if (l + 1 < nlev_) {
        lv.pcols = copy_up<index_t, 2>(h.pcols, lv.pcols_s);
        lv.pw = copy_up<double, 2>(h.pw, lv.pw_s);
        transpose(h.pcols, h.pw, host.level(l + 1).n, lv);
      }
    }
    factor_ = copy_up<double, 2>(host.coarsest_factor(), factor_s_);
    const index_t n = level_[0].n;
    r_ = r_s_.sized(n);
    p_ = p_s_.sized(n);
    q_ = q_s_.sized(n);
    z_ = z_s_.sized(n);
    ws_.reserve(n);
  }

  // One V-cycle with zero initial guess (device views of the finest level's n values).
  void vcycle(View<const double> b, View<double> x, int sweeps) {
    auto bl = [&](index_t l) -> View<const double> { return l == 0 ? b : level_[l].b; };
    auto xl = [&](index_t l) -> View<double> { return l == 0 ? x : level_[l].x; };
    for (index_t l = 0; l + 1 < nlev_; ++l) {
      Level& lv = level_[l];
      const View<double> xv = xl(l);
      if (sweeps > 0)
        sweep(lv, bl(l), xv, true, true);
      else
        K::fill(xv, 0.0);
      for (int s = 1; s < sweeps; ++s) sweep(lv, bl(l), xv, true, false);
      K::residual(lv.cols, lv.vals, xv, bl(l), lv.r);
      K::restrict_to(lv.tstart, lv.tfine, lv.tw, lv.r, level_[l + 1].b);
    }
    K::coarse_solve(factor_, bl(nlev_ - 1), xl(nlev_ - 1));
    for (index_t l = nlev_ - 2; l >= 0; --l) {
      Level& lv = level_[l];
      K::prolong(lv.pcols, lv.pw, level_[l + 1].x, xl(l));
      for (int s = 0; s < sweeps; ++s) sweep(lv, bl(l), xl(l), false, false);
    }
  }

  // Multigrid<D>::pcg on the device: the same iteration (rhs, x: device views).
  SolveResult pcg(View<const double> rhs, View<double> x, double tol, index_t maxiter, int sweeps) {
    const Level& f = level_[0];
    const index_t n = f.n;
    if (rhs.size() != n || x.size() != n)
      throw std::invalid_argument("multigrid: rhs and x must have one value per row");
    // the device's vector operations (LevelKernels), the same iteration as the host's
    struct DeviceOps {
      Multigrid& mg;
      const Level& f;
      int sweeps;
      double dot(View<const double> a, View<const double> b) { return K::dot(mg.ws_, a, b); }
      void residual(View<const double> x, View<const double> b, View<double> r) {
        K::residual(f.cols, f.vals, x, b, r);
      }
      void matvec(View<const double> p, View<double> q) { K::matvec(f.cols, f.vals, p, q); }
      void vcycle(View<const double> r, View<double> z) { mg.vcycle(r, z, sweeps); }
      void fill(View<double> v, double value) { K::fill(v, value); }
      void copy(View<const double> from, View<double> to) { K::copy(from, to); }
      void cg_update(View<double> x, View<double> r, View<double> p, View<const double> q,
                     View<const double> z, double alpha, double beta, bool step) {
        K::cg_update(x, r, p, q, z, alpha, beta, step);
      }
    } ops{*this, f, sweeps};
    return pcg_iterate(ops, rhs, x, r_, p_, q_, z_, tol, maxiter);
  }

  index_t levels() const { return nlev_; }

 private:
  template <class T, int R>
  static View<const T, R> copy_up(View<const T, R> host, DeviceBuffer<T>& store) {
    std::array<index_t, R> shape;
    for (int k = 0; k < R; ++k) shape[k] = host.extent(k);
    View<T, R> dev = store.template sized<R>(shape);
    if (host.size() > 0) to_device<T, R>(host, dev);
    return dev;
  }

  // One colour sweep over the level: forward or backward, the first one from x = 0.
  void sweep(Level& lv, View<const double> b, View<double> x, bool forward, bool first) {
    for (int k = 0; k < NCOL; ++k) {
      const int colour = forward ? k : NCOL - 1 - k;
      typename K::Slots slots{};
      if (first) slots.n = first_sweep_slots<D>(colour, slots.s);
      K::gs(lv.cols, lv.vals, b, x, lv.rows, lv.cstart[colour], lv.cstart[colour + 1], slots,
            first);
    }
  }

  // P^T as gathers: coarse row c's fine rows in increasing order, with their weights.
  void transpose(View<const index_t, 2> pcols, View<const double, 2> pw, index_t nc, Level& lv) {
    const index_t n = pcols.extent(0);
    tstart_h_.assign(nc + 1, 0);
    for (index_t r = 0; r < n; ++r)
      for (int a = 0; a < NP; ++a)
        if (pcols(r, a) >= 0) tstart_h_[pcols(r, a) + 1] += 1;
    for (index_t c = 0; c < nc; ++c) tstart_h_[c + 1] += tstart_h_[c];
    const index_t nnz = tstart_h_[nc];
    tfine_h_.resize(nnz);
    tw_h_.resize(nnz);
    fill_h_.assign(tstart_h_.begin(), tstart_h_.end() - 1);
    for (index_t r = 0; r < n; ++r)
      for (int a = 0; a < NP; ++a) {
        const index_t c = pcols(r, a);
        if (c < 0) continue;
        tfine_h_[fill_h_[c]] = r;
        tw_h_[fill_h_[c]++] = pw(r, a);
      }
    lv.tstart = copy_up<index_t, 1>(View<const index_t>(tstart_h_.data(), {nc + 1}), lv.tstart_s);
    lv.tfine = copy_up<index_t, 1>(View<const index_t>(tfine_h_.data(), {nnz}), lv.tfine_s);
    lv.tw = copy_up<double, 1>(View<const double>(tw_h_.data(), {nnz}), lv.tw_s);
  }

  std::vector<Level> level_;
  index_t nlev_ = 0;
  View<const double, 2> factor_;
  DeviceBuffer<double> factor_s_, r_s_, p_s_, q_s_, z_s_;
  View<double> r_, p_, q_, z_;
  Workspace ws_;
  std::vector<index_t> tstart_h_, tfine_h_, fill_h_;  // upload's scratch, grown
  std::vector<double> tw_h_;
};

}  // namespace mpmflow::gpu
