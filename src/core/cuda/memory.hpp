// Memory that lives on the device: the CUDA backend's Buffer (view.hpp). Storage is taken
// with cudaMalloc (plain device memory, not managed memory: the host never dereferences
// it) outside the step and grown, never shrunk, when a run needs more; kernels see it only
// through Views, as on the host. Copies between host and device views are explicit.
#pragma once

#include <cuda_runtime.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "../view.hpp"

namespace mpmflow::gpu {

// Throws with CUDA's own message and the call that failed.
inline void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess)
    throw std::runtime_error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(status));
}
#define MPMFLOW_CUDA_CHECK(call) ::mpmflow::gpu::check((call), #call)

template <class T>
class DeviceBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "a DeviceBuffer holds plain numbers");
  struct Free {
    void operator()(T* p) const { cudaFree(p); }
  };

 public:
  // Make room for n elements (contents are not kept: a device buffer is sized before the
  // step that fills it); returns true if the storage moved.
  bool reserve(index_t n) {
    if (n <= capacity_) return false;
    T* grown = nullptr;
    MPMFLOW_CUDA_CHECK(cudaMalloc(&grown, static_cast<std::size_t>(n) * sizeof(T)));
    data_.reset(grown);
    capacity_ = n;
    return true;
  }
  index_t capacity() const { return capacity_; }
  View<T> sized(index_t n) {
    reserve(n);
    return View<T>(data_.get(), {n});
  }
  template <int R>
  View<T, R> sized(std::array<index_t, R> shape) {
    index_t n = 1;
    for (auto s : shape) n *= s;
    reserve(n);
    return View<T, R>(data_.get(), shape);
  }

 private:
  std::unique_ptr<T, Free> data_;
  index_t capacity_ = 0;
};

// Host to device and back (the views' sizes must match).
template <class T, int R>
void to_device(View<const T, R> host, View<T, R> device) {
  if (host.size() != device.size()) throw std::invalid_argument("to_device: sizes differ");
  MPMFLOW_CUDA_CHECK(
      cudaMemcpy(device.data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice));
}
template <class T, int R>
void to_host(View<const T, R> device, View<T, R> host) {
  if (host.size() != device.size()) throw std::invalid_argument("to_host: sizes differ");
  MPMFLOW_CUDA_CHECK(
      cudaMemcpy(host.data(), device.data(), host.size() * sizeof(T), cudaMemcpyDeviceToHost));
}

}  // namespace mpmflow::gpu
