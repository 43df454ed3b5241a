// The lock-free handoffs under real concurrency: a seqlock reader never sees a torn value, an
// SPSC ring delivers every element once and in order.

#include "server/lockfree.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <thread>

namespace tangent::server {
namespace {

struct Big {
  long a[64];
};

constexpr long kMinWrites = 200000, kMinReads = 20000;

// A reader racing a writer that writes Big{k, k, ...} for k = 1, 2, ...: the writer goes on
// until the reader has overlapped it many times (on a loaded machine the reader thread may not
// be scheduled at all during a fixed number of writes). `read(Big*)` returns the version read
// (0: nothing read).
struct Race {
  long reads = 0, refused = 0, torn = 0, backwards = 0;
};
template <class Read>
Race RaceAWriter(Seqlock<Big>* lock, Read&& read) {
  std::atomic<bool> done{false};
  std::atomic<long> reads{0};
  std::thread writer([&] {
    Big w;
    for (long k = 1; k <= kMinWrites || reads.load(std::memory_order_relaxed) < kMinReads; ++k) {
      for (long& x : w.a) x = k;
      lock->Write(w);
    }
    done = true;
  });
  Race r;
  long last = 0;
  Big b;
  while (!done) {
    if (read(&b) == 0) {
      ++r.refused;
      continue;
    }
    reads.fetch_add(1, std::memory_order_relaxed);
    for (long x : b.a) r.torn += x != b.a[0];
    r.backwards += b.a[0] < last;
    last = b.a[0];
  }
  writer.join();
  r.reads = reads.load();
  return r;
}

TEST(LockFreeTest, SeqlockReadersNeverSeeATornValue) {
  Seqlock<Big> lock;
  const Race r = RaceAWriter(&lock, [&](Big* b) { return lock.Read(b); });
  EXPECT_GE(r.reads, kMinReads);
  EXPECT_EQ(r.torn, 0);
  EXPECT_EQ(r.backwards, 0);
}

TEST(LockFreeTest, SeqlockTryReadNeverWaitsAndNeverReportsATornValue) {
  // TryRead (the servo's read of the clearance certificate): one attempt; a copy it reports as
  // read (version ≠ 0) is whole, one overlapped by a write is reported as not read.
  Seqlock<Big> lock;
  Big b;
  EXPECT_EQ(lock.TryRead(&b), 0u);  // nothing written yet
  const Race r = RaceAWriter(&lock, [&](Big* out) { return lock.TryRead(out); });
  EXPECT_GE(r.reads, kMinReads);
  EXPECT_EQ(r.torn, 0);
  EXPECT_EQ(r.backwards, 0);
  std::printf("TryRead: %ld reads whole, %ld refused (a write in progress or overlapping)\n",
              r.reads, r.refused);
  EXPECT_EQ(lock.TryRead(&b), lock.version());
}

TEST(LockFreeTest, SpscRingDeliversEveryElementInOrder) {
  SpscRing<long, 64> ring;
  constexpr long kCount = 500000;
  // A full or empty ring yields the core: on a busy machine the two threads may share one,
  // and spinning there moves at most 63 elements per time slice (this test took 15–29 s in CI).
  std::thread producer([&] {
    for (long k = 0; k < kCount;) {
      if (ring.Push(k)) {
        ++k;
      } else {
        std::this_thread::yield();
      }
    }
  });
  long expected = 0, wrong = 0, v;
  while (expected < kCount) {
    if (ring.Pop(&v)) {
      wrong += v != expected;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(wrong, 0);
  EXPECT_FALSE(ring.Pop(&v));
  SpscRing<int, 4> small;
  EXPECT_TRUE(small.Push(1) && small.Push(2) && small.Push(3));
  EXPECT_FALSE(small.Push(4));  // capacity N − 1: full, the producer counts the drop
}

}  // namespace
}  // namespace tangent::server
