// Views of arrays owned elsewhere (NumPy, a Buffer, later device memory): a pointer and a
// shape, row-major, no ownership. Indices are bounds-checked in debug builds (NDEBUG unset).
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <memory>

namespace mpmflow {

using index_t = std::int64_t;

// Functions that kernels call run on the host and, in a CUDA build (nvcc: __CUDACC__), on
// the device too: the same bodies for both backends (src/core/cuda/).
#if defined(__CUDACC__)
#define MPMFLOW_HD __host__ __device__
#else
#define MPMFLOW_HD
#endif

#ifndef NDEBUG
#define MPMFLOW_BOUNDS(cond) assert(cond)
#else
#define MPMFLOW_BOUNDS(cond) ((void)0)
#endif

// A view of R dimensions over T (R = 1: a vector, R = 2: rows of equal length, ...).
template <class T, int R = 1>
class View {
 public:
  MPMFLOW_HD View() : shape_{} {}
  MPMFLOW_HD View(T* data, std::array<index_t, R> shape) : data_(data), shape_(shape) {}

  MPMFLOW_HD index_t size() const {
    index_t n = 1;
    for (int k = 0; k < R; ++k) n *= shape_[k];
    return n;
  }
  MPMFLOW_HD index_t extent(int k) const { return shape_[k]; }
  MPMFLOW_HD bool empty() const { return size() == 0; }
  MPMFLOW_HD T* data() const { return data_; }

  MPMFLOW_HD T& operator[](index_t i) const {  // flat index
    MPMFLOW_BOUNDS(i >= 0 && i < size());
    return data_[i];
  }
  MPMFLOW_HD T& operator()(index_t i) const {
    static_assert(R == 1, "one index for a view of one dimension");
    MPMFLOW_BOUNDS(i >= 0 && i < shape_[0]);
    return data_[i];
  }
  MPMFLOW_HD T& operator()(index_t i, index_t j) const {
    static_assert(R == 2, "two indices for a view of two dimensions");
    MPMFLOW_BOUNDS(i >= 0 && i < shape_[0] && j >= 0 && j < shape_[1]);
    return data_[i * shape_[1] + j];
  }
  MPMFLOW_HD T& operator()(index_t i, index_t j, index_t k) const {
    static_assert(R == 3, "three indices for a view of three dimensions");
    MPMFLOW_BOUNDS(i >= 0 && i < shape_[0] && j >= 0 && j < shape_[1] && k >= 0 && k < shape_[2]);
    return data_[(i * shape_[1] + j) * shape_[2] + k];
  }
  MPMFLOW_HD T& operator()(index_t i, index_t j, index_t k, index_t l) const {
    static_assert(R == 4, "four indices for a view of four dimensions");
    MPMFLOW_BOUNDS(i >= 0 && i < shape_[0] && j >= 0 && j < shape_[1] && k >= 0 && k < shape_[2] &&
                   l >= 0 && l < shape_[3]);
    return data_[((i * shape_[1] + j) * shape_[2] + k) * shape_[3] + l];
  }
  // Row i of a view of two or more dimensions, as a view of one dimension fewer.
  MPMFLOW_HD View<T, R - 1> row(index_t i) const {
    static_assert(R >= 2, "a row of a view of two or more dimensions");
    MPMFLOW_BOUNDS(i >= 0 && i < shape_[0]);
    std::array<index_t, R - 1> s{};
    for (int k = 1; k < R; ++k) s[k - 1] = shape_[k];
    return View<T, R - 1>(data_ + i * (size() / (shape_[0] ? shape_[0] : 1)), s);
  }
  // The first n rows (n <= extent(0)).
  MPMFLOW_HD View head(index_t n) const {
    MPMFLOW_BOUNDS(n >= 0 && n <= shape_[0]);
    auto s = shape_;
    s[0] = n;
    return View(data_, s);
  }
  MPMFLOW_HD operator View<const T, R>() const { return View<const T, R>(data_, shape_); }

 private:
  T* data_ = nullptr;
  std::array<index_t, R> shape_;
};

// Storage the core owns: sized to a capacity outside the step and grown (never shrunk)
// when a run needs more; kernels see it only through views. A device backend replaces
// the host array by device memory behind the same interface.
//
// New storage reads as zeros. It comes from calloc, whose large blocks are pages the system
// maps on first write: a buffer sized to a bound (the volume correction's rows for every
// cell of the grid) costs memory only for the part a run writes, as NumPy's empty arrays
// did before the core.
template <class T>
class Buffer {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                "a Buffer holds plain numbers");
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };

 public:
  // Make room for n elements, keeping the first capacity() ones; returns true if the
  // storage moved (views taken before are then stale).
  bool reserve(index_t n) {
    if (n <= capacity_) return false;
    T* grown = static_cast<T*>(std::calloc(static_cast<std::size_t>(n), sizeof(T)));
    if (grown == nullptr) throw std::bad_alloc();
    std::copy(data_.get(), data_.get() + capacity_, grown);
    data_.reset(grown);
    capacity_ = n;
    return true;
  }
  index_t capacity() const { return capacity_; }
  const T* data() const { return data_.get(); }
  View<T> view(index_t n) {
    MPMFLOW_BOUNDS(n <= capacity());
    return View<T>(data_.get(), {n});
  }
  template <int R>
  View<T, R> view(std::array<index_t, R> shape) {
    View<T, R> v(data_.get(), shape);
    MPMFLOW_BOUNDS(v.size() <= capacity());
    return v;
  }
  // Grow to the shape if needed, then view it.
  template <int R>
  View<T, R> sized(std::array<index_t, R> shape) {
    index_t n = 1;
    for (auto s : shape) n *= s;
    reserve(n);
    return view<R>(shape);
  }
  View<T> sized(index_t n) {
    reserve(n);
    return view(n);
  }

 private:
  std::unique_ptr<T, Free> data_;
  index_t capacity_ = 0;
};

}  // namespace mpmflow
