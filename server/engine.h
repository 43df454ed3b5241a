#pragma once

// The server's two compute threads (design.md §2): the servo loop on one core (hybrid
// sleep-then-spin timing, no allocation, no locks, no I/O) and the global contact stage on the
// other, joined by lock-free mailboxes. The LCM bridge (bridge.h) and the rate benchmark both
// drive an Engine.

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <thread>

#include "server/lockfree.h"
#include "server/servo.h"

namespace tangent::server {

class GlobalLink;

struct EngineOptions {
  double rate_hz = 4000.0;  ///< servo ticks per second
  /// Hybrid timing: sleep (timer slack 1 ns) until this long before each deadline, then spin.
  /// A new device state is answered at once (an extra tick): during the spin the servo sees it,
  /// during the sleep Publish wakes it (a futex wait with the sleep's deadline).
  double spin_us = 150.0;
  /// Spin also from this long before the device's next expected state (its period estimated
  /// from arrivals) until device_lag_us after it, so the state is seen without a wake-up.
  bool spin_for_device = true;
  double device_lead_us = 100.0;
  double device_lag_us = 200.0;
  int servo_cpu = 0;   ///< core for the servo loop (−1: not pinned)
  int global_cpu = 1;  ///< core for the global contact stage (−1: not pinned)
  double global_rate_hz = 1000.0;
  /// Nice value of the global-stage thread: below the bridge that shares its core (engine.cc).
  int global_nice = 10;
  double journal_violation = 1e-6;  ///< a tick's violation above this is journalled
  /// A gap between two global passes longer than this is a stall: counted (global_stalls) and
  /// logged by the bridge. The servo keeps tracking its contacts meanwhile; only new contacts
  /// wait for the next pass.
  double global_stall_ms = 50.0;
  /// Fault injection (tangentd --fault-injection, SIGUSR1): the global stage sleeps this long.
  double injected_global_stall_ms = 100.0;
  ServoOptions servo;
};

/// A histogram of durations in 0.25 µs bins up to 1 ms (plus overflow), written by one thread
/// with relaxed atomics and read by others (never blocks either).
class DurationHistogram {
 public:
  static constexpr int kBins = 4000;
  static constexpr double kBinUs = 0.25;
  void Add(double us) {
    const int b = us < 0 ? 0 : (us >= kBins * kBinUs ? kBins : static_cast<int>(us / kBinUs));
    bins_[b].fetch_add(1, std::memory_order_relaxed);
    const double m = max_.load(std::memory_order_relaxed);
    if (us > m) max_.store(us, std::memory_order_relaxed);
  }
  /// Copies the counts (for windows: subtract an earlier copy).
  void Copy(uint64_t* out) const {
    for (int b = 0; b <= kBins; ++b) out[b] = bins_[b].load(std::memory_order_relaxed);
  }
  double max() const { return max_.load(std::memory_order_relaxed); }
  /// Quantile (0..1) of counts (kBins + 1 entries), in µs (upper edge of the bin).
  static double Quantile(const uint64_t* counts, double q);
  static uint64_t Total(const uint64_t* counts);

 private:
  std::atomic<uint64_t> bins_[kBins + 1] = {};
  std::atomic<double> max_{0.0};
};

/// Counters the servo publishes every tick (Seqlock), plus the last wrench's size. Window
/// maxima since the bridge's last statistics message are kept apart (Engine::TakeWindowMax).
struct LoopCounters {
  int64_t ticks = 0;
  int64_t early_ticks = 0;     ///< extra ticks for a device state that arrived during the spin
  int64_t overruns = 0;        ///< ticks that started more than one period after their deadline
  int64_t late = 0;            ///< scheduled ticks that finished after their deadline + ½ period
  int64_t iterations = 0;      ///< solver iterations, total
  double max_violation = 0.0;  ///< since the start
  double force_norm = 0.0;
  int32_t num_contacts = 0;
  int64_t device_timeouts = 0;
  int64_t events_applied = 0;
  int64_t events_dropped = 0;
  int64_t wrenches_dropped = 0;
  int64_t faults = 0;            ///< ticks with a non-finite or absurd intermediate
  int64_t contacts_tracked = 0;  ///< contact evaluations the tracker answered
  int64_t contacts_solved = 0;   ///< contact evaluations that needed a full extremal solve
  int64_t contacts_lost = 0;     ///< tracker steps that reported `lost` (then re-solved)
  int64_t unanswered = 0;        ///< accepted device states the servo never answered
  int64_t last_accepted = 0;     ///< accepted index of the last device state answered
  int64_t timeout_wrenches = 0;  ///< wrenches sent while the device was silent (state 2)
  /// The global stage's clearance certificates the servo took, and those it refused (moved
  /// beyond since their snapshot: it kept the one it had). docs/stability.md, "No tunnelling".
  int64_t clearances_taken = 0, clearances_refused = 0;
};

/// Maxima over a window that a reader closes (lock free: the servo raises them with a CAS, the
/// reader exchanges them for zero).
struct WindowMax {
  std::atomic<double> violation{0.0};
  std::atomic<double> force{0.0};
  static void Raise(std::atomic<double>* m, double x) {
    double seen = m->load(std::memory_order_relaxed);
    while (x > seen && !m->compare_exchange_weak(seen, x, std::memory_order_relaxed)) {
    }
  }
};

/// A line of the servo's journal (plain data, SPSC ring to whoever reads it: tangentd's log,
/// the rate benchmark): contact events as applied, and ticks whose solve left a violation above
/// EngineOptions::journal_violation.
struct JournalEntry {
  enum Kind : int32_t { kEventApplied = 0, kEventDropped = 1, kViolation = 2, kFaultTick = 3 };
  int64_t tick = 0;
  int64_t time_ns = 0;
  int32_t kind = kEventApplied;
  int32_t added = 0, surface_a = 0, surface_b = 0;  ///< events
  double u[4] = {0, 0, 0, 0};
  double violation = 0.0;  ///< kViolation: the tick's; min_beta: the lowest tracked β (m)
  double min_beta = 0.0;
  int32_t iterations = 0, contacts = 0;
};

/// One line for a journal entry (no newline), times relative to start_ns; snprintf into a
/// caller's buffer (no allocation).
void FormatJournalEntry(const JournalEntry& j, int64_t start_ns, char* out, size_t size);

class Engine {
 public:
  Engine(const Scene& scene, const EngineOptions& options);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  void Start();
  void Stop();

  /// Bridge → servo: the latest accepted device state. Publish() writes it and rings the
  /// servo's doorbell: a servo sleeping before its deadline wakes at once and answers it.
  const Seqlock<DeviceSample>& device() const { return device_; }
  void Publish(const DeviceSample& s);
  /// Set by a consumer that is watching wrenches() itself (the bridge waiting for an answer):
  /// the servo then skips the eventfd write.
  void set_consumer_watching(bool watching);
  /// Servo → bridge: wrenches answering device states.
  SpscRing<WrenchSample, 1024>& wrenches() { return wrenches_; }
  /// Servo → one reader: contact events applied and violation excursions (full: dropped).
  SpscRing<JournalEntry, 256>& journal() { return journal_; }
  /// Servo → global stage and bridge.
  const Seqlock<Snapshot>& snapshot() const { return snapshot_; }
  const Seqlock<LoopCounters>& counters() const { return counters_; }
  /// Closes the statistics window: the largest violation (m) and |force| (N) since the last call.
  void TakeWindowMax(double* violation, double* force) {
    *violation = window_.violation.exchange(0.0);
    *force = window_.force.exchange(0.0);
  }
  const DurationHistogram& compute_histogram() const { return compute_; }
  const DurationHistogram& global_histogram() const { return global_; }
  int64_t global_passes() const { return global_passes_.load(std::memory_order_relaxed); }
  /// Gaps between global passes longer than global_stall_ms, and the longest gap (ms).
  int64_t global_stalls() const { return global_stalls_.load(std::memory_order_relaxed); }
  double global_longest_gap_ms() const {
    return 1e-6 * static_cast<double>(global_longest_gap_ns_.load(std::memory_order_relaxed));
  }
  /// How many clearance trees the engine built before serving (GlobalLink::Prepare).
  int clearance_trees() const { return clearance_trees_; }
  /// The smallest β of any contact the global stage added (GlobalLink::deepest_added; +∞ before
  /// the first): a penetration the servo's rows missed shows here.
  double stage_deepest_added() const {
    return stage_deepest_added_.load(std::memory_order_relaxed);
  }
  /// Fault injection: the global stage's next pass starts injected_global_stall_ms late. A
  /// lock-free atomic store, so a signal handler may call it.
  void InjectGlobalStall() { inject_global_stall_.store(true, std::memory_order_relaxed); }
  /// eventfd the servo signals after pushing a wrench (non-blocking write; the bridge polls it).
  int wake_fd() const { return wake_fd_; }
  const ServoLoop& servo() const { return *servo_; }
  const EngineOptions& options() const { return options_; }

 private:
  // The servo thread's loop, one named step per concern (engine.cc).
  struct ServoState;
  void ServoThread();
  bool WaitForTick(ServoState* s);  ///< true: woken early by a device state
  void ApplyEvents(ServoState* s, int64_t start);
  void ReadDevice(ServoState* s);
  void CountTick(ServoState* s, int64_t start);
  void SendWrench(ServoState* s);
  void JournalViolation(ServoState* s, int64_t start);
  void CloseTick(ServoState* s, bool early);
  void Pace(ServoState* s, int64_t start, bool early);
  void GlobalThread();

  EngineOptions options_;
  std::unique_ptr<ServoLoop> servo_;
  /// The global stage's link, made (and its clearance trees built) with the engine, before any
  /// thread runs: nothing of megabytes is allocated mid-run (docs/reliability.md, "Soak").
  std::unique_ptr<GlobalLink> link_;
  int clearance_trees_ = 0;
  Seqlock<DeviceSample> device_;
  SpscRing<WrenchSample, 1024> wrenches_;
  SpscRing<ContactEventMsg, 256> events_;
  Seqlock<Snapshot> snapshot_;
  /// Global stage → servo: the clearance certificate of its last pass (written after that
  /// pass's events are pushed, so a servo that reads it before taking the events has them).
  Seqlock<ClearanceMsg> clearances_;
  Seqlock<LoopCounters> counters_;
  WindowMax window_;
  SpscRing<JournalEntry, 256> journal_;
  DurationHistogram compute_, global_;
  std::atomic<int64_t> global_passes_{0};
  std::atomic<int64_t> global_stalls_{0};
  std::atomic<int64_t> global_longest_gap_ns_{0};
  std::atomic<double> stage_deepest_added_{std::numeric_limits<double>::infinity()};
  std::atomic<bool> inject_global_stall_{false};
  static_assert(std::atomic<bool>::is_always_lock_free);
  std::atomic<int64_t> events_pushed_{0};
  std::atomic<bool> running_{false};
  // The servo's doorbell (a futex word): rung by Publish, waited on while the servo sleeps.
  alignas(64) std::atomic<uint32_t> doorbell_{0};
  std::atomic<bool> servo_sleeping_{false};
  std::atomic<bool> consumer_watching_{false};
  std::thread servo_thread_, global_thread_;
  int wake_fd_ = -1;
};

/// CLOCK_MONOTONIC in ns.
int64_t MonotonicNs();
/// Pins the calling thread to a core (−1: no-op). @return false if the kernel refused.
bool PinToCore(int cpu);

}  // namespace tangent::server
