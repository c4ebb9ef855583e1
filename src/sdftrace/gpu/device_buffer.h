// Device memory and timing helpers of the .cu files: an array in GPU memory freed with its owner,
// and a pair of CUDA events timing the work between them. For .cu files only.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "cuda_check.h"

namespace sdft::cuda {

template <class T>
class DeviceArray {
  public:
    DeviceArray() = default;
    explicit DeviceArray(size_t n) : m_size(n) {
        if (n) SDFT_CUDA_CHECK(cudaMalloc(&m_ptr, n * sizeof(T)));
    }
    // A device copy of `host`.
    explicit DeviceArray(const std::vector<T>& host) : DeviceArray(host.size()) {
        if (m_size)
            SDFT_CUDA_CHECK(
                cudaMemcpy(m_ptr, host.data(), m_size * sizeof(T), cudaMemcpyHostToDevice));
    }
    ~DeviceArray() { cudaFree(m_ptr); }
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    DeviceArray(DeviceArray&& o) noexcept : m_ptr(o.m_ptr), m_size(o.m_size) {
        o.m_ptr = nullptr;
        o.m_size = 0;
    }
    DeviceArray& operator=(DeviceArray&& o) noexcept {
        std::swap(m_ptr, o.m_ptr);
        std::swap(m_size, o.m_size);
        return *this;
    }

    // `host` copied in, into this allocation where the sizes agree, else a new one.
    void upload(const std::vector<T>& host) {
        if (host.size() != m_size) {
            *this = DeviceArray(host);
            return;
        }
        if (m_size)
            SDFT_CUDA_CHECK(
                cudaMemcpy(m_ptr, host.data(), m_size * sizeof(T), cudaMemcpyHostToDevice));
    }

    T* get() const { return m_ptr; }
    size_t size() const { return m_size; }
    // The first `n` elements back into `host` (resized to n).
    void download(std::vector<T>& host, size_t n) const {
        host.resize(n);
        if (n)
            SDFT_CUDA_CHECK(cudaMemcpy(host.data(), m_ptr, n * sizeof(T), cudaMemcpyDeviceToHost));
    }

  private:
    T* m_ptr = nullptr;
    size_t m_size = 0;
};

// Page-locked host memory (cudaMallocHost), grown on demand and never shrunk: the staging area of
// asynchronous copies from the device (a pageable destination makes CUDA stage them itself).
template <class T>
class PinnedArray {
  public:
    PinnedArray() = default;
    ~PinnedArray() { cudaFreeHost(m_ptr); }
    PinnedArray(const PinnedArray&) = delete;
    PinnedArray& operator=(const PinnedArray&) = delete;

    // At least n elements (the old contents are not kept when it grows).
    void reserve(size_t n) {
        if (n <= m_capacity) return;
        cudaFreeHost(m_ptr);
        m_ptr = nullptr;
        m_capacity = 0;
        SDFT_CUDA_CHECK(cudaMallocHost(&m_ptr, n * sizeof(T)));
        m_capacity = n;
    }
    T* get() const { return m_ptr; }
    size_t capacity() const { return m_capacity; }

  private:
    T* m_ptr = nullptr;
    size_t m_capacity = 0;
};

// Milliseconds of GPU time between record(start) and record(stop).
struct EventTimer {
    cudaEvent_t start = nullptr, stop = nullptr;
    EventTimer() {
        SDFT_CUDA_CHECK(cudaEventCreate(&start));
        SDFT_CUDA_CHECK(cudaEventCreate(&stop));
    }
    ~EventTimer() {
        cudaEventDestroy(start);
        cudaEventDestroy(stop);
    }
    EventTimer(const EventTimer&) = delete;
    EventTimer& operator=(const EventTimer&) = delete;
    float elapsedMs() const {
        SDFT_CUDA_CHECK(cudaEventSynchronize(stop));
        float ms = 0;
        SDFT_CUDA_CHECK(cudaEventElapsedTime(&ms, start, stop));
        return ms;
    }
};

}  // namespace sdft::cuda
