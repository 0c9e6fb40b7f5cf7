// The CUDA backend's check and benchmark (issue 41; docs/architecture.md, "The backend
// seam"): the dam break's column, 2D and 3D, seeded as examples/dam_break*.toml seed it
// (2 particles per cell and direction), moved through the transfers on the host (OpenMP,
// src/core/transfer.cpp) and on the device (cuda/transfer.cuh), compared and timed.
//
//   mpmflow_cuda_check [OUT.jsonl]
//
// MPMFLOW_CHECK_BIG=1: also 66 M particles and the pressure system of 8.5 M unknowns in 3D
// (the host's runs once each); MPMFLOW_CHECK_SMALL=1: the smallest cases
// only (for compute-sanitizer).
//
// Without a device it times the host's phases only (the same particles, for a baseline on
// a machine without a GPU) and checks nothing.
// Checks, per dimension and size (exit 1 if one fails):
//   - binning: order and start equal to the host's counting sort, entry for entry;
//   - particle-to-grid: node mass, volume, momentum, v_old and v_star within 1e-12 of the
//     largest value (the host adds the same terms in another order);
//   - grid-to-particle from the host's grid values: positions, velocities, pressures and
//     APIC matrices bit for bit equal to the host's (the same element function; built with
//     --fmad=false, as the host's -O3 without -march contracts nothing);
//   - determinism: particle-to-grid twice, the same bits;
//   - the multigrid-preconditioned CG on the column's pressure system (the Q1 Laplacian,
//     p = 0 on top): one V-cycle bit for bit the host's; the solve to 1e-8 within one
//     iteration of the host's count, its true residual (on the host) within the tolerance.
// Times: each phase's median of 10 runs (CUDA events on the device; steady clock on the
// host, all its threads), and particle-steps per second of the two transfers with binning.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../binning.hpp"
#include "../multigrid.hpp"
#include "../transfer.hpp"
#include "memory.hpp"
#include "multigrid.cuh"
#include "transfer.cuh"

using namespace mpmflow;

namespace {

template <class F>
double host_ms(F&& f, int reps = 5) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

template <class F>
double device_ms(F&& f, int reps = 10) {
  cudaEvent_t a, b;
  cudaEventCreate(&a);
  cudaEventCreate(&b);
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    cudaEventRecord(a);
    f();
    cudaEventRecord(b);
    cudaEventSynchronize(b);
    float ms = 0;
    cudaEventElapsedTime(&ms, a, b);
    t.push_back(ms);
  }
  cudaEventDestroy(a);
  cudaEventDestroy(b);
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

bool have_device = false;

// One case's JSON line, to the terminal (at once: the big cases take minutes) and to OUT.
void emit(const char* line, FILE* out) {
  std::fputs(line, stdout);
  std::fflush(stdout);
  if (out) std::fputs(line, out);
}

// Host and device copies of one array (the device's only where there is one).
template <class T>
struct Pair {
  std::vector<T> host;
  gpu::DeviceBuffer<T> dev;
  std::vector<index_t> shape;
  explicit Pair(std::vector<index_t> s) : shape(std::move(s)) {
    index_t n = 1;
    for (auto k : shape) n *= k;
    host.assign(n, T(0));
    if (have_device) dev.sized(n);
  }
  template <int R>
  View<T, R> h() {
    std::array<index_t, R> s{};
    for (int k = 0; k < R; ++k) s[k] = shape[k];
    return View<T, R>(host.data(), s);
  }
  template <int R>
  View<T, R> d() {
    std::array<index_t, R> s{};
    for (int k = 0; k < R; ++k) s[k] = shape[k];
    return dev.template sized<R>(s);
  }
  View<T> flat() { return dev.sized(static_cast<index_t>(host.size())); }
  void up() {
    MPMFLOW_CUDA_CHECK(
        cudaMemcpy(flat().data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice));
  }
  std::vector<T> down() {
    std::vector<T> out(host.size());
    MPMFLOW_CUDA_CHECK(
        cudaMemcpy(out.data(), flat().data(), host.size() * sizeof(T), cudaMemcpyDeviceToHost));
    return out;
  }
};

// Largest |a - b| over the largest |a| (0 when both are zero).
double rel_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0.0, m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d = std::max(d, std::abs(a[i] - b[i]));
    m = std::max(m, std::abs(a[i]));
  }
  return m > 0.0 ? d / m : d;
}
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

int failures = 0;
void expect(bool ok, const char* what, int dim, index_t n) {
  if (!ok) {
    std::printf("FAIL %dD n=%lld: %s\n", dim, static_cast<long long>(n), what);
    ++failures;
  }
}

template <int D>
void run(double h, bool apic, FILE* out) {
  // the tank 0.42 m (x) by 0.04 m (y, 3D only) by 0.44 m (up), the column 0.114 m by 0.228 m
  const double size3[3] = {0.42, 0.04, 0.44}, col3[3] = {0.114, 0.04, 0.228};
  double size[D], col[D];
  for (int k = 0; k < D; ++k) {
    const int src = D == 2 ? (k == 0 ? 0 : 2) : k;
    size[k] = size3[src];
    col[k] = col3[src];
  }
  std::array<index_t, D> cells;
  for (int k = 0; k < D; ++k) cells[k] = static_cast<index_t>(std::llround(size[k] / h));
  const Grid<D> g(h, cells);
  index_t per[D], n = 1;
  for (int k = 0; k < D; ++k) {
    per[k] = 2 * static_cast<index_t>(std::llround(col[k] / h));
    n *= per[k];
  }
  const double rho = 1000.0, vp = std::pow(h / 2, D), dt = 1e-3;
  Pair<double> x({n, D}), v({n, D}), mass({n}), volume({n}), pressure({n}),
      affine({apic ? n : 0, D, D});
  for (index_t p = 0; p < n; ++p) {
    index_t r = p;
    for (int k = 0; k < D; ++k) {
      x.host[p * D + k] = (static_cast<double>(r % per[k]) + 0.5) * h / 2;
      r /= per[k];
    }
    for (int k = 0; k < D; ++k)  // a smooth field that is not affine
      v.host[p * D + k] = 0.3 * std::sin(9.0 * x.host[p * D + (k + 1) % D]) + 0.1 * k;
    mass.host[p] = rho * vp;
    volume.host[p] = vp;
    if (apic)
      for (int k = 0; k < D * D; ++k) affine.host[p * D * D + k] = 0.5 * std::cos(3.0 * k + p % 7);
  }
  const index_t nn = g.nnodes;
  Pair<double> node_mass({nn}), node_vol({nn}), node_mom({nn, D}), v_old({nn, D}), v_star({nn, D}),
      v_new({nn, D}), p_node({nn});
  Pair<index_t> cell({n}), order({n}), start({g.ncells + 1});
  std::array<double, D> gravity{};
  gravity[D - 1] = -9.81;
  Pair<double> grav({D}), lower({D}), upper({D});
  for (int k = 0; k < D; ++k) {
    grav.host[k] = gravity[k];
    upper.host[k] = size[k];
  }
  const double margin = 1e-3 * h;
  // --- host
  const double t_bin_h = host_ms([&] {
    cell_index<D>(g, x.h<2>(), cell.h<1>());
    counting_sort(cell.h<1>(), g.ncells, start.h<1>(), order.h<1>());
  });
  auto p2g_host = [&] {
    particles_to_grid<D>(g, x.h<2>(), v.h<2>(), mass.h<1>(), volume.h<1>(), order.h<1>(),
                         start.h<1>(), grav.h<1>(), dt, node_mass.h<1>(), node_mom.h<2>(),
                         node_vol.h<1>(), v_old.h<2>(), v_star.h<2>(), View<double>(),
                         apic ? View<const double, 3>(affine.h<3>()) : View<const double, 3>());
  };
  const double t_p2g_h = host_ms(p2g_host);
  // the projection's stand-in: v_new = v_star plus a smooth field, a hydrostatic-like pressure
  for (index_t i = 0; i < nn; ++i) {
    index_t ix[D];
    g.node_coords(i, ix);
    for (int k = 0; k < D; ++k)
      v_new.host[i * D + k] =
          v_star.host[i * D + k] + (node_mass.host[i] > 0 ? 0.01 * std::cos(0.7 * ix[k]) : 0.0);
    p_node.host[i] = node_mass.host[i] > 0 ? rho * 9.81 * (size[D - 1] - ix[D - 1] * h) : 0.0;
  }
  // grid-to-particle moves the particles: time it on copies, check it once from the start
  Pair<double> x2({n, D}), v2({n, D}), pr2({n}), af2({apic ? n : 0, D, D});
  auto g2p_on = [&](Pair<double>& X, Pair<double>& V, Pair<double>& PR, Pair<double>& AF,
                    bool dev) {
    GridToParticle<D> one;
    one.g = g;
    one.x = dev ? X.d<2>() : X.h<2>();
    one.v = dev ? V.d<2>() : V.h<2>();
    one.pressure = dev ? PR.d<1>() : PR.h<1>();
    one.v_old = dev ? v_old.d<2>() : v_old.h<2>();
    one.v_new = dev ? v_new.d<2>() : v_new.h<2>();
    one.p_node = dev ? p_node.d<1>() : p_node.h<1>();
    one.dt = dt;
    one.flip = 0.99;
    one.margin = margin;
    one.lower = dev ? lower.d<1>() : lower.h<1>();
    one.upper = dev ? upper.d<1>() : upper.h<1>();
    if (apic) one.affine = dev ? AF.d<3>() : AF.h<3>();
    return one;
  };
  auto reset_host = [&] {
    x2.host = x.host;
    v2.host = v.host;
    pr2.host.assign(n, 0.0);
    af2.host = affine.host;
  };
  reset_host();
  GridToParticle<D> host_one = g2p_on(x2, v2, pr2, af2, false);
  index_t moved_h = 0;
  const double t_g2p_h = host_ms([&] {
    reset_host();
    moved_h =
        grid_to_particles<D>(g, host_one.x, host_one.v, host_one.pressure, host_one.v_old,
                             host_one.v_new, host_one.p_node, dt, host_one.flip, host_one.lower,
                             host_one.upper, margin, host_one.faces, host_one.affine);
  });
  if (!have_device) {
    char line[512];
    std::snprintf(line, sizeof line,
                  "{\"dim\": %d, \"h\": %g, \"particles\": %lld, \"apic\": %s, "
                  "\"host_threads\": %d, \"host_ms\": {\"binning\": %.3f, \"p2g\": %.3f, "
                  "\"g2p\": %.3f}}\n",
                  D, h, static_cast<long long>(n), apic ? "true" : "false", omp_get_max_threads(),
                  t_bin_h, t_p2g_h, t_g2p_h);
    emit(line, out);
    return;
  }
  // --- device
  for (auto* a : {&x, &v, &mass, &volume, &affine, &v_old, &v_new, &p_node, &grav, &lower, &upper})
    a->up();
  gpu::Transfers<D> dev;
  dev.reserve(g, n);
  const double t_bin_d = device_ms([&] { dev.bin(g, x.d<2>()); });
  {
    std::vector<index_t> o(n), s(g.ncells + 1);
    MPMFLOW_CUDA_CHECK(
        cudaMemcpy(o.data(), dev.order(n).data(), n * sizeof(index_t), cudaMemcpyDeviceToHost));
    MPMFLOW_CUDA_CHECK(cudaMemcpy(s.data(), dev.start(g).data(), s.size() * sizeof(index_t),
                                  cudaMemcpyDeviceToHost));
    expect(o == order.host, "binning: order differs from the host's", D, n);
    expect(s == start.host, "binning: start differs from the host's", D, n);
  }
  auto p2g_dev = [&] {
    dev.particles_to_grid(g, x.d<2>(), v.d<2>(), mass.d<1>(), volume.d<1>(), gravity, dt,
                          node_mass.d<1>(), node_mom.d<2>(), node_vol.d<1>(), v_old.d<2>(),
                          v_star.d<2>(),
                          apic ? View<const double, 3>(affine.d<3>()) : View<const double, 3>());
  };
  const double t_p2g_d = device_ms(p2g_dev);
  double worst = 0.0;
  for (auto* a : {&node_mass, &node_vol, &node_mom, &v_star})
    worst = std::max(worst, rel_diff(a->host, a->down()));
  expect(worst <= 1e-12, "particle-to-grid: node values differ from the host's", D, n);
  {
    const auto first = node_mom.down();
    p2g_dev();
    cudaDeviceSynchronize();
    expect(same_bits(first, node_mom.down()), "particle-to-grid: not deterministic", D, n);
  }
  // v_old back to the host's, so that grid-to-particle starts from the same grid values
  v_old.up();
  Pair<double> x3({n, D}), v3({n, D}), pr3({n}), af3({apic ? n : 0, D, D});
  auto reset_dev = [&] {
    x3.host = x.host;
    v3.host = v.host;
    pr3.host.assign(n, 0.0);
    af3.host = affine.host;
    x3.up();
    v3.up();
    pr3.up();
    af3.up();
  };
  reset_dev();
  const GridToParticle<D> dev_one = g2p_on(x3, v3, pr3, af3, true);
  const index_t moved_d = dev.grid_to_particles(dev_one);
  bool g2p_same = same_bits(x3.down(), x2.host) && same_bits(v3.down(), v2.host) &&
                  same_bits(pr3.down(), pr2.host) && moved_d == moved_h;
  if (apic) g2p_same = g2p_same && same_bits(af3.down(), af2.host);
  expect(g2p_same, "grid-to-particle: not bit for bit the host's", D, n);
  const double t_g2p_d = device_ms([&] { dev.grid_to_particles(dev_one); });
  const double host_total = t_bin_h + t_p2g_h + t_g2p_h, dev_total = t_bin_d + t_p2g_d + t_g2p_d;
  cudaDeviceProp prop;
  cudaGetDeviceProperties(&prop, 0);
  char line[1024];
  std::snprintf(line, sizeof line,
                "{\"dim\": %d, \"h\": %g, \"particles\": %lld, \"nodes\": %lld, \"apic\": %s, "
                "\"device\": \"%s\", \"host_threads\": %d, "
                "\"host_ms\": {\"binning\": %.3f, \"p2g\": %.3f, \"g2p\": %.3f}, "
                "\"device_ms\": {\"binning\": %.3f, \"p2g\": %.3f, \"g2p\": %.3f}, "
                "\"p2g_rel_diff\": %.3e, \"g2p_bitwise\": %s, "
                "\"device_particle_steps_per_s\": %.4g, \"host_particle_steps_per_s\": %.4g}\n",
                D, h, static_cast<long long>(n), static_cast<long long>(nn),
                apic ? "true" : "false", prop.name, omp_get_max_threads(), t_bin_h, t_p2g_h,
                t_g2p_h, t_bin_d, t_p2g_d, t_g2p_d, worst, g2p_same ? "true" : "false",
                n / (dev_total * 1e-3), n / (host_total * 1e-3));
  emit(line, out);
}

// The pressure system of the column at rest: the Q1 Laplacian (eq. 13's matrix) on the
// column's nodes, p = 0 on its top plane (the free surface), ELL rows in node order.
template <int D>
void run_pcg(double h, FILE* out, int reps = 5) {
  constexpr int NC = 1 << D, NS = stencil_size(D);
  const double col3[3] = {0.114, 0.04, 0.228};
  std::array<index_t, D> cells, dims;
  for (int k = 0; k < D; ++k) {
    cells[k] = static_cast<index_t>(std::llround(col3[D == 2 && k == 1 ? 2 : k] / h));
    dims[k] = cells[k] + 1;
  }
  const Grid<D> g(h, cells);
  // the element matrix h^(D-2) int grad N_a . grad N_b, by 2-point Gauss per axis
  double Ke[NC][NC] = {};
  const Grid<D> unit(1.0, [] {
    std::array<index_t, D> one;
    one.fill(1);
    return one;
  }());
  for (int q = 0; q < NC; ++q) {
    double frac[D];
    for (int k = 0; k < D; ++k) frac[k] = 0.5 + (((q >> k) & 1) ? 0.5 : -0.5) / std::sqrt(3.0);
    for (int a = 0; a < NC; ++a)
      for (int b = 0; b < NC; ++b) {
        double gg = 0.0;
        for (int k = 0; k < D; ++k)
          gg += unit.corner_gradient(a, k, frac) * unit.corner_gradient(b, k, frac);
        Ke[a][b] += gg / NC * std::pow(h, D - 2);
      }
  }
  std::vector<index_t> row_of(g.nnodes, -1), node;
  for (index_t i = 0; i < g.nnodes; ++i) {
    index_t ix[D];
    g.node_coords(i, ix);
    if (ix[D - 1] < cells[D - 1]) {
      row_of[i] = static_cast<index_t>(node.size());
      node.push_back(i);
    }
  }
  const index_t n = static_cast<index_t>(node.size());
  std::vector<index_t> cols(n * NS, -1);
  std::vector<double> vals(n * NS, 0.0), rhs(n);
  for (index_t c = 0; c < g.ncells; ++c) {
    const index_t base = g.cell_first_node(c);
    for (int a = 0; a < NC; ++a) {
      const index_t r = row_of[base + g.corner[a]];
      if (r < 0) continue;
      for (int b = 0; b < NC; ++b) {
        int s = 0;
        for (int k = 0, p3 = 1; k < D; ++k, p3 *= 3)
          s += (((b >> k) & 1) - ((a >> k) & 1) + 1) * p3;
        const index_t cb = row_of[base + g.corner[b]];
        if (cb < 0) continue;
        cols[r * NS + s] = cb;
        vals[r * NS + s] += Ke[a][b];
      }
    }
  }
  for (index_t r = 0; r < n; ++r) {  // gravity's divergence-like source, smooth, not uniform
    index_t ix[D];
    g.node_coords(node[r], ix);
    rhs[r] = std::pow(h, D) * (1.0 + 0.5 * std::sin(0.3 * ix[0]) * std::cos(0.2 * ix[D - 1]));
  }
  View<const index_t, 2> C(cols.data(), {n, NS});
  View<const double, 2> V(vals.data(), {n, NS});
  View<const index_t> N(node.data(), {n});
  View<const double> B(rhs.data(), {n});
  const double tol = 1e-8;
  const index_t maxiter = 500;
  const int sweeps = 1;
  Multigrid<D> mg;
  const double t_setup = host_ms([&] { mg.setup(C, V, N, dims); }, reps < 3 ? reps : 3);
  std::vector<double> xh(n), zh(n);
  SolveResult rh;
  const double t_pcg_h = host_ms(
      [&] {
        std::fill(xh.begin(), xh.end(), 0.0);
        rh = mg.pcg(B, View<double>(xh.data(), {n}), tol, maxiter, sweeps);
      },
      reps);
  mg.vcycle(B, View<double>(zh.data(), {n}), sweeps);
  if (!have_device) {
    char line[512];
    std::snprintf(line, sizeof line,
                  "{\"solve\": \"pcg\", \"dim\": %d, \"h\": %g, \"unknowns\": %lld, "
                  "\"levels\": %lld, \"host_threads\": %d, \"host_ms\": {\"setup\": %.3f, "
                  "\"pcg\": %.3f}, \"iterations\": %lld}\n",
                  D, h, static_cast<long long>(n), static_cast<long long>(mg.levels()),
                  omp_get_max_threads(), t_setup, t_pcg_h, static_cast<long long>(rh.iterations));
    emit(line, out);
    return;
  }
  gpu::Multigrid<D> dmg;
  const double t_upload = host_ms([&] { dmg.upload(mg); }, reps < 3 ? reps : 3);
  Pair<double> b({n}), x({n}), z({n});
  b.host = rhs;
  b.up();
  // one V-cycle: the host's bits
  dmg.vcycle(b.d<1>(), z.d<1>(), sweeps);
  expect(same_bits(z.down(), zh), "multigrid: a V-cycle is not bit for bit the host's", D, n);
  SolveResult rd;
  const double t_pcg_d = device_ms([&] {
    x.host.assign(n, 0.0);
    x.up();
    rd = dmg.pcg(b.d<1>(), x.d<1>(), tol, maxiter, sweeps);
  });
  // the device's answer checked on the host: its true residual, and against the host's
  const std::vector<double> xd = x.down();
  std::vector<double> res(n);
  residual(C, V, View<const double>(xd.data(), {n}), B, View<double>(res.data(), {n}));
  const double bn = std::sqrt(dot(B, B));
  const double true_res =
      std::sqrt(dot(View<const double>(res.data(), {n}), View<const double>(res.data(), {n}))) / bn;
  expect(true_res <= tol, "multigrid: the device's solution misses the tolerance", D, n);
  expect(std::abs(rd.iterations - rh.iterations) <= 1,
         "multigrid: the device took other iterations than the host", D, n);
  const double diff = rel_diff(xh, xd);
  cudaDeviceProp prop;
  cudaGetDeviceProperties(&prop, 0);
  char line[1024];
  std::snprintf(line, sizeof line,
                "{\"solve\": \"pcg\", \"dim\": %d, \"h\": %g, \"unknowns\": %lld, "
                "\"levels\": %lld, \"device\": \"%s\", \"host_threads\": %d, "
                "\"host_ms\": {\"setup\": %.3f, \"pcg\": %.3f}, \"device_ms\": "
                "{\"upload\": %.3f, \"pcg\": %.3f}, \"iterations\": [%lld, %lld], "
                "\"device_true_residual\": %.3e, \"solution_rel_diff\": %.3e}\n",
                D, h, static_cast<long long>(n), static_cast<long long>(mg.levels()), prop.name,
                omp_get_max_threads(), t_setup, t_pcg_h, t_upload, t_pcg_d,
                static_cast<long long>(rh.iterations), static_cast<long long>(rd.iterations),
                true_res, diff);
  emit(line, out);
}

}  // namespace

int main(int argc, char** argv) {
  FILE* out = argc > 1 ? std::fopen(argv[1], "w") : nullptr;
  int count = 0;
  have_device = cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
  if (!have_device) std::printf("no CUDA device: the host's times only, nothing checked\n");
  try {
    // 2D: the paper's 0.004 m and finer; 3D: examples/dam_break_3d.toml's 0.008 m, the
    // benchmark's 1.04 M particles at 0.002 m, and 66 M at 0.0005 m
    const char* small = std::getenv("MPMFLOW_CHECK_SMALL");
    const bool only_small = small && std::string(small) == "1";
    for (bool apic : {false, true}) {
      run<2>(0.004, apic, out);
      run<3>(0.008, apic, out);
    }
    run_pcg<2>(0.004, out);
    run_pcg<3>(0.008, out);
    if (!only_small) {
      run<2>(0.001, false, out);
      run<2>(0.00025, false, out);
      run<3>(0.002, false, out);
      run<3>(0.002, true, out);
      // the column's pressure system: 2D at 0.001 and 0.00025 m; 3D at 0.002 (1.04 M
      // particles' mesh) and 0.001 m
      for (double hp : {0.001, 0.00025}) run_pcg<2>(hp, out);
      for (double hp : {0.002, 0.001}) run_pcg<3>(hp, out);
      const char* big = std::getenv("MPMFLOW_CHECK_BIG");
      if (big && std::string(big) == "1") {  // one host run each: minutes on the host
        run<3>(0.0005, false, out);
        run_pcg<3>(0.0005, out, 1);
      }
    }
  } catch (const std::exception& e) {
    std::printf("FAIL: %s\n", e.what());
    return 2;
  }
  if (out) std::fclose(out);
  if (have_device) std::printf(failures ? "%d checks failed\n" : "all checks passed\n", failures);
  return failures ? 1 : 0;
}
