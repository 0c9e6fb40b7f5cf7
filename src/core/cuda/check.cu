// The CUDA backend's check and benchmark (issue 41; docs/architecture.md, "The backend
// seam"): the dam break's column, 2D and 3D, seeded as examples/dam_break*.toml seed it
// (2 particles per cell and direction), moved through the transfers on the host (OpenMP,
// src/core/transfer.cpp) and on the device (cuda/transfer.cuh), compared and timed.
//
//   mpmflow_cuda_check [OUT.jsonl]      (MPMFLOW_CHECK_BIG=1: also 66 M particles in 3D)
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
//   - determinism: particle-to-grid twice, the same bits.
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
#include "../transfer.hpp"
#include "memory.hpp"
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
    std::fputs(line, stdout);
    if (out) std::fputs(line, out);
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
  std::fputs(line, stdout);
  std::fflush(stdout);
  if (out) std::fputs(line, out);
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
    for (bool apic : {false, true}) {
      run<2>(0.004, apic, out);
      run<3>(0.008, apic, out);
    }
    run<2>(0.001, false, out);
    run<2>(0.00025, false, out);
    run<3>(0.002, false, out);
    run<3>(0.002, true, out);
    const char* big = std::getenv("MPMFLOW_CHECK_BIG");
    if (big && std::string(big) == "1") run<3>(0.0005, false, out);
  } catch (const std::exception& e) {
    std::printf("FAIL: %s\n", e.what());
    return 2;
  }
  if (out) std::fclose(out);
  if (have_device) std::printf(failures ? "%d checks failed\n" : "all checks passed\n", failures);
  return failures ? 1 : 0;
}
