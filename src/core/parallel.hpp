// The backend seam: every parallel loop of the core goes through the few functions here.
// Kernel bodies are element functions (lambdas of an index or of a chunk's range); this
// header launches them with OpenMP. A CUDA or HIP backend implements the same functions
// (a grid-stride kernel for parallel_for, a two-pass block reduction for reduce_chunks, a
// device scan for exclusive_scan) and compiles the same bodies.
//
// Determinism: a loop is cut into CHUNKS pieces (more than any thread count), and sums are
// taken chunk by chunk then over the chunks in order, so results do not depend on the number
// of threads. The chunks are dealt to the threads in turn (schedule(static, 1)), not in
// contiguous blocks: the work of a loop over nodes or particles is often where the material
// is, in one part of the index range (SPHERIC's water fills the lower half of its tank's
// slabs: with blocks, one of two threads held nearly all of it).
#pragma once

#include <algorithm>
#include <cstdint>

#include "view.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mpmflow {

constexpr index_t CHUNKS = 64;
// Loops shorter than this run on the calling thread: waking the team costs more.
constexpr index_t SERIAL_BELOW = 4096;

inline int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

inline void set_threads(int n) {
#ifdef _OPENMP
  omp_set_num_threads(std::max(1, n));
#else
  (void)n;
#endif
}

// body(i) for i in [0, n).
template <class F>
void parallel_for(index_t n, F&& body) {
  if (n < SERIAL_BELOW) {
    for (index_t i = 0; i < n; ++i) body(i);
    return;
  }
#pragma omp parallel for schedule(static)
  for (index_t i = 0; i < n; ++i) body(i);
}

// body(t, lo, hi) for the chunks t of [0, n): min(CHUNKS, max(n, 1)) chunks, chunk t
// covering [t n / nchunks, (t + 1) n / nchunks). ``work`` estimates the total work (for
// the serial cut-off; n by default).
template <class F>
void for_each_chunk(index_t n, F&& body, index_t work = -1) {
  const index_t nchunks = std::min(CHUNKS, std::max<index_t>(n, 1));
  if (work < 0) work = n;
  if (work < SERIAL_BELOW) {  // no parallel region at all: even an if(false) one costs ~1 us
    for (index_t t = 0; t < nchunks; ++t) body(t, t * n / nchunks, (t + 1) * n / nchunks);
    return;
  }
#pragma omp parallel for schedule(static, 1)
  for (index_t t = 0; t < nchunks; ++t) body(t, t * n / nchunks, (t + 1) * n / nchunks);
}

// body(t) for t in [0, count): a few tasks of unequal work whose results do not depend on
// which thread runs them (the strips of a scatter), each taken by the next free thread.
// ``work`` estimates the total work (for the serial cut-off).
template <class F>
void for_each_task(index_t count, F&& body, index_t work) {
  if (work < SERIAL_BELOW) {
    for (index_t t = 0; t < count; ++t) body(t);
    return;
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (index_t t = 0; t < count; ++t) body(t);
}

// The same for bodies whose result does not depend on how [0, n) is cut (no per-chunk
// partials): on the calling thread (work < SERIAL_BELOW) one call body(0, 0, n) instead of
// one per chunk (the small levels of a multigrid cycle would pay a call per row or two).
template <class F>
void for_each_range(index_t n, F&& body, index_t work = -1) {
  if (work < 0) work = n;
  if (work < SERIAL_BELOW) {
    body(index_t(0), index_t(0), n);
    return;
  }
  for_each_chunk(n, body, work);
}

// The partials of the chunks of [0, n), body(lo, hi), combined by an associative operation
// (e.g. the largest) in chunk order.
template <class T, class F, class C>
T reduce_chunks(index_t n, F&& body, C&& combine) {
  const index_t nchunks = std::min(CHUNKS, std::max<index_t>(n, 1));
  T part[CHUNKS];
  if (n < SERIAL_BELOW) {
    for (index_t t = 0; t < nchunks; ++t) part[t] = body(t * n / nchunks, (t + 1) * n / nchunks);
  } else {
#pragma omp parallel for schedule(static, 1)
    for (index_t t = 0; t < nchunks; ++t) part[t] = body(t * n / nchunks, (t + 1) * n / nchunks);
  }
  T total = part[0];
  for (index_t t = 1; t < nchunks; ++t) total = combine(total, part[t]);
  return total;
}

// The sum over the chunks of [0, n) of body(lo, hi) (each chunk's partial, then the
// partials in chunk order): the same bits on any number of threads.
template <class T, class F>
T reduce_chunks(index_t n, F&& body) {
  return reduce_chunks<T>(n, body, [](const T& a, const T& b) { return a + b; });
}

// out[i] = sum of in[j] for j < i, for i in [0, n]; out has n + 1 entries (in and out
// may be the same storage shifted by one: out[i + 1] += out[i]). Returns out[n].
template <class T>
T exclusive_scan(View<const T> in, View<T> out) {
  const index_t n = in.size();
  T total = 0;
  for (index_t i = 0; i < n; ++i) {
    const T v = in[i];
    out[i] = total;
    total += v;
  }
  out[n] = total;
  return total;
}

}  // namespace mpmflow
