#pragma once

// Lock-free handoff between the server's threads (design.md §2): a seqlock for "latest value"
// mailboxes (device state, configuration snapshot) and a single-producer/single-consumer ring
// for streams (wrenches, contact events). Neither allocates after construction, locks or
// blocks; the writer of a seqlock never waits for readers.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <type_traits>

namespace tangent::server {

/// One writer, any number of readers. Read copies the value out and retries while a write was
/// in progress (odd sequence) or happened during the copy (sequence changed).
template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>, "Seqlock holds plain data");

 public:
  void Write(const T& value) {
    const unsigned s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    CopyIn(value);
    seq_.store(s + 2, std::memory_order_release);
  }
  /// @return the number of writes so far (even), so a reader can tell a new value from one it
  /// has seen; 0 before the first write (then *out is untouched).
  unsigned Read(T* out) const {
    for (;;) {
      const unsigned s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return 0;
      if (s0 & 1u) continue;
      CopyOut(out);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s0) return s0;
    }
  }
  unsigned version() const { return seq_.load(std::memory_order_acquire); }

 private:
  // Byte-wise copies through relaxed atomics would be the pedantic form; a memcpy bracketed by
  // the fences is the standard seqlock (the torn copy is discarded by the sequence check).
  void CopyIn(const T& v) { std::memcpy(static_cast<void*>(&data_), &v, sizeof(T)); }
  void CopyOut(T* v) const { std::memcpy(static_cast<void*>(v), &data_, sizeof(T)); }

  alignas(64) std::atomic<unsigned> seq_{0};
  alignas(64) T data_{};
};

/// Single producer, single consumer, capacity N − 1. Push fails (returns false) when full: the
/// producer counts the drop and goes on.
template <typename T, size_t N>
class SpscRing {
  static_assert((N & (N - 1)) == 0, "capacity must be a power of two");
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds plain data");

 public:
  bool Push(const T& v) {
    const size_t h = head_.load(std::memory_order_relaxed);
    const size_t next = (h + 1) & (N - 1);
    if (next == tail_.load(std::memory_order_acquire)) return false;
    buffer_[h] = v;
    head_.store(next, std::memory_order_release);
    return true;
  }
  bool Pop(T* v) {
    const size_t t = tail_.load(std::memory_order_relaxed);
    if (t == head_.load(std::memory_order_acquire)) return false;
    *v = buffer_[t];
    tail_.store((t + 1) & (N - 1), std::memory_order_release);
    return true;
  }

 private:
  alignas(64) std::atomic<size_t> head_{0};
  alignas(64) std::atomic<size_t> tail_{0};
  std::array<T, N> buffer_{};
};

}  // namespace tangent::server
