// The backend seam on a CUDA device: the functions of src/core/parallel.hpp for memory that
// lives on the device (memory.hpp), launching the same element functions (MPMFLOW_HD bodies)
// as the host's OpenMP loops.
//
//   parallel_for      a grid-stride kernel, body(i) for i in [0, n)
//   reduce_sum        a deterministic sum: a fixed launch (REDUCE_BLOCKS blocks of
//                     REDUCE_THREADS threads) whatever the device, each thread summing a fixed
//                     stride of [0, n) in order, the block's partials by a fixed tree, the
//                     blocks' partials by one block in the same tree: the same bits on every
//                     run and every device (not the host's chunk order: host and device agree
//                     to rounding, not bit for bit)
//   exclusive_scan    CUB's device scan (exact for the integer scans the core takes)
//   sort_by_key       CUB's radix sort of (key, value) pairs, stable: particles binned by
//                     cell in their own order, the same order as the host's counting sort
//
// The particle-to-grid scatter has no atomics: particles sorted by cell, each node gathers
// from the particles of its 2^D cells (cuda/transfer.cuh), so it is deterministic too.
// CUB's temporary storage is a Workspace sized before the step (no allocation in a step).
#pragma once

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include "../view.hpp"
#include "memory.hpp"

namespace mpmflow::gpu {

constexpr int THREADS = 256;
constexpr int REDUCE_BLOCKS = 1024;
constexpr int REDUCE_THREADS = 256;

template <class F>
__global__ void for_kernel(index_t n, F body) {
  const index_t stride = static_cast<index_t>(gridDim.x) * blockDim.x;
  for (index_t i = static_cast<index_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride)
    body(i);
}

inline int blocks_for(index_t n) {
  const index_t b = (n + THREADS - 1) / THREADS;
  return static_cast<int>(b < 65535 * 8 ? (b > 0 ? b : 1) : 65535 * 8);
}

// body(i) for i in [0, n), on the device (asynchronous on the default stream).
template <class F>
void parallel_for(index_t n, F body) {
  if (n <= 0) return;
  for_kernel<<<blocks_for(n), THREADS>>>(n, body);
  MPMFLOW_CUDA_CHECK(cudaGetLastError());
}

// A block's REDUCE_THREADS values summed by a fixed tree; thread 0 gets the sum.
template <class T>
__device__ T block_sum(T v) {
  __shared__ T part[REDUCE_THREADS];
  part[threadIdx.x] = v;
  __syncthreads();
  for (int s = REDUCE_THREADS / 2; s > 0; s >>= 1) {
    if (static_cast<int>(threadIdx.x) < s)
      part[threadIdx.x] = part[threadIdx.x] + part[threadIdx.x + s];
    __syncthreads();
  }
  return part[0];
}

template <class T, class F>
__global__ void reduce_kernel(index_t n, F body, T* partial) {
  const index_t stride = static_cast<index_t>(REDUCE_BLOCKS) * REDUCE_THREADS;
  T acc = T(0);
  for (index_t i = static_cast<index_t>(blockIdx.x) * REDUCE_THREADS + threadIdx.x; i < n;
       i += stride)
    acc = acc + body(i);
  const T s = block_sum<T>(acc);
  if (threadIdx.x == 0) partial[blockIdx.x] = s;
}

template <class T>
__global__ void reduce_partials(const T* partial, T* out) {
  T acc = T(0);
  for (int b = threadIdx.x; b < REDUCE_BLOCKS; b += REDUCE_THREADS) acc = acc + partial[b];
  const T s = block_sum<T>(acc);
  if (threadIdx.x == 0) *out = s;
}

// Device scratch for the reductions, scans and sorts of a step: sized once, reused.
class Workspace {
 public:
  // Room for scans and sorts of up to n elements (CUB's temporary storage for both, plus
  // the reductions' partials).
  void reserve(index_t n) {
    std::size_t scan = 0, sort = 0;
    MPMFLOW_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, scan, (const index_t*)nullptr,
                                                     (index_t*)nullptr, static_cast<int>(n)));
    MPMFLOW_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, sort, (const index_t*)nullptr,
                                                       (index_t*)nullptr, (const index_t*)nullptr,
                                                       (index_t*)nullptr, static_cast<int>(n)));
    temp_bytes_ = scan > sort ? scan : sort;
    temp_.sized(static_cast<index_t>(temp_bytes_));
    partial_.sized(REDUCE_BLOCKS + 1);
  }
  void* temp() { return temp_.sized(static_cast<index_t>(temp_bytes_)).data(); }
  std::size_t temp_bytes() const { return temp_bytes_; }
  double* partial() { return partial_.sized(REDUCE_BLOCKS + 1).data(); }

 private:
  DeviceBuffer<unsigned char> temp_;
  DeviceBuffer<double> partial_;  // REDUCE_BLOCKS partials and the total (8-byte numbers)
  std::size_t temp_bytes_ = 0;
};

// The sum of body(i) over [0, n) (T: double or index_t), deterministic; waits for it.
template <class T, class F>
T reduce_sum(Workspace& ws, index_t n, F body) {
  static_assert(sizeof(T) == sizeof(double), "the partials hold 8-byte numbers");
  T* partial = reinterpret_cast<T*>(ws.partial());
  reduce_kernel<T><<<REDUCE_BLOCKS, REDUCE_THREADS>>>(n, body, partial);
  MPMFLOW_CUDA_CHECK(cudaGetLastError());
  reduce_partials<T><<<1, REDUCE_THREADS>>>(partial, partial + REDUCE_BLOCKS);
  MPMFLOW_CUDA_CHECK(cudaGetLastError());
  T total;
  MPMFLOW_CUDA_CHECK(
      cudaMemcpy(&total, partial + REDUCE_BLOCKS, sizeof(T), cudaMemcpyDeviceToHost));
  return total;
}

// out[i] = sum of in[j] for j < i, i in [0, n) (n = in.size(), out at least n entries).
inline void exclusive_scan(Workspace& ws, View<const index_t> in, View<index_t> out) {
  std::size_t bytes = ws.temp_bytes();
  MPMFLOW_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(ws.temp(), bytes, in.data(), out.data(),
                                                   static_cast<int>(in.size())));
}

// (keys, values) sorted by key, stable; keys in [0, 2^bits).
inline void sort_by_key(Workspace& ws, View<const index_t> keys_in, View<index_t> keys_out,
                        View<const index_t> values_in, View<index_t> values_out, int bits) {
  std::size_t bytes = ws.temp_bytes();
  MPMFLOW_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(
      ws.temp(), bytes, keys_in.data(), keys_out.data(), values_in.data(), values_out.data(),
      static_cast<int>(keys_in.size()), 0, bits));
}

}  // namespace mpmflow::gpu
