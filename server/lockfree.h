#pragma once

// Lock-free handoff between the server's threads (design.md §2): a seqlock for "latest value"
// mailboxes (device state, configuration snapshot) and a single-producer/single-consumer ring
// for streams (wrenches, contact events). Neither allocates after construction, locks or
// blocks; the writer of a seqlock never waits for readers.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace tangent::server {

/// One writer, any number of readers. Read copies the value out and retries while a write was
/// in progress (odd sequence) or happened during the copy (sequence changed).
///
/// The value is held as 64-bit words accessed with atomics, not by a plain memcpy: a reader's
/// copy overlaps the writer's, and in C++ concurrent plain accesses to the same bytes are a data
/// race, undefined behaviour even when the torn copy is then discarded. The writer stores the
/// words with release after marking the write in progress (odd sequence); the reader loads them
/// with acquire, so a reader that sees any word of a write in progress also sees the odd
/// sequence (or a later one) on its second look, and discards the copy. No standalone fences
/// (which ThreadSanitizer cannot model): on x86-64 these loads and stores are the plain `mov`s
/// a memcpy would use, and the sanitizer sees the synchronisation exactly.
template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>, "Seqlock holds plain data");

 public:
  void Write(const T& value) {
    const unsigned s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    CopyIn(value);  // release stores: each is ordered after the odd sequence above
    seq_.store(s + 2, std::memory_order_release);
  }
  /// @return the number of writes so far (even), so a reader can tell a new value from one it
  /// has seen; 0 before the first write (then *out is untouched).
  unsigned Read(T* out) const {
    for (;;) {
      const unsigned s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return 0;
      if (s0 & 1u) continue;
      CopyOut(out);  // acquire loads: the second look below is ordered after each
      if (seq_.load(std::memory_order_relaxed) == s0) return s0;
    }
  }
  /// One attempt, never waiting on the writer: the version read, or 0 when nothing was written
  /// yet or a write was in progress or overlapped the copy (then *out may be torn: discard it).
  unsigned TryRead(T* out) const {
    const unsigned s0 = seq_.load(std::memory_order_acquire);
    if (s0 == 0 || (s0 & 1u)) return 0;
    CopyOut(out);
    return seq_.load(std::memory_order_relaxed) == s0 ? s0 : 0;
  }
  unsigned version() const { return seq_.load(std::memory_order_acquire); }

 private:
  static constexpr size_t kWords = (sizeof(T) + 7) / 8;

  void CopyIn(const T& v) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(&v);
    for (size_t i = 0; i < kWords; ++i) {
      uint64_t w = 0;
      std::memcpy(&w, bytes + 8 * i, Bytes(i));
      words_[i].store(w, std::memory_order_release);
    }
  }
  void CopyOut(T* v) const {
    auto* bytes = reinterpret_cast<unsigned char*>(v);
    for (size_t i = 0; i < kWords; ++i) {
      const uint64_t w = words_[i].load(std::memory_order_acquire);
      std::memcpy(bytes + 8 * i, &w, Bytes(i));
    }
  }
  /// Bytes of the value in word i (the last word may be partial).
  static constexpr size_t Bytes(size_t i) { return i + 1 < kWords ? 8 : sizeof(T) - 8 * i; }

  static_assert(std::atomic<uint64_t>::is_always_lock_free);
  alignas(64) std::atomic<unsigned> seq_{0};
  alignas(64) std::array<std::atomic<uint64_t>, kWords> words_{};
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
