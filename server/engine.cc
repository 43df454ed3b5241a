#include "server/engine.h"

#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <vector>

#include "server/global_link.h"

namespace tangent::server {

int64_t MonotonicNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

bool PinToCore(int cpu) {
  if (cpu < 0) return true;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof(set), &set) == 0;
}

namespace {

void SleepUntil(int64_t t_ns) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000LL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

// Sleeps until t_ns (CLOCK_MONOTONIC) unless *word no longer holds `expected` or is woken
// (FUTEX_WAIT_BITSET takes an absolute CLOCK_MONOTONIC deadline; timer slack applies as for
// clock_nanosleep). Not a lock: nothing is held, the sleep is only cut short.
void SleepUntilOrWoken(std::atomic<uint32_t>* word, uint32_t expected, int64_t t_ns) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000LL);
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(word), FUTEX_WAIT_BITSET | FUTEX_PRIVATE_FLAG,
          expected, &ts, nullptr, FUTEX_BITSET_MATCH_ANY);
}

void Wake(std::atomic<uint32_t>* word) {
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(word), FUTEX_WAKE | FUTEX_PRIVATE_FLAG, 1, nullptr,
          nullptr, 0);
}

inline void CpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

void FormatJournalEntry(const JournalEntry& j, int64_t start_ns, char* out, size_t size) {
  const double t = 1e-9 * static_cast<double>(j.time_ns - start_ns);
  if (j.kind == JournalEntry::kFaultTick) {
    std::snprintf(out, size,
                  "t=%.4fs tick %lld: fault (non-finite or absurd intermediate): scene restored, "
                  "force to zero",
                  t, static_cast<long long>(j.tick));
  } else if (j.kind == JournalEntry::kViolation) {
    std::snprintf(out, size,
                  "t=%.4fs tick %lld: violation %.1e after %d iterations, %d contacts, lowest "
                  "beta %.1e m",
                  t, static_cast<long long>(j.tick), j.violation, j.iterations, j.contacts,
                  j.min_beta);
  } else {
    std::snprintf(out, size,
                  "t=%.4fs tick %lld: contact %s %s, surfaces %d-%d at (%.4f %.4f %.4f %.4f)", t,
                  static_cast<long long>(j.tick), j.added ? "added" : "removed",
                  j.kind == JournalEntry::kEventApplied ? "applied" : "dropped", j.surface_a,
                  j.surface_b, j.u[0], j.u[1], j.u[2], j.u[3]);
  }
}

double DurationHistogram::Quantile(const uint64_t* counts, double q) {
  const uint64_t total = Total(counts);
  if (total == 0) return 0.0;
  const double target = q * static_cast<double>(total);
  uint64_t seen = 0;
  for (int b = 0; b <= kBins; ++b) {
    seen += counts[b];
    if (static_cast<double>(seen) >= target) return (b + 1) * kBinUs;
  }
  return kBins * kBinUs;
}

uint64_t DurationHistogram::Total(const uint64_t* counts) {
  uint64_t t = 0;
  for (int b = 0; b <= kBins; ++b) t += counts[b];
  return t;
}

Engine::Engine(const Scene& scene, const EngineOptions& options) : options_(options) {
  servo_ = std::make_unique<ServoLoop>(scene, options.servo);
  link_ = std::make_unique<GlobalLink>(*servo_);
  clearance_trees_ = link_->Prepare();
  Snapshot s;
  servo_->FillSnapshot(&s);
  snapshot_.Write(s);
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
}

Engine::~Engine() {
  Stop();
  if (wake_fd_ >= 0) close(wake_fd_);
}

void Engine::Start() {
  if (running_.exchange(true)) return;
  servo_thread_ = std::thread([this] { ServoThread(); });
  global_thread_ = std::thread([this] { GlobalThread(); });
}

void Engine::Stop() {
  if (!running_.exchange(false)) return;
  doorbell_.fetch_add(1);  // a sleeping servo stops now, not at its next deadline
  Wake(&doorbell_);
  if (servo_thread_.joinable()) servo_thread_.join();
  if (global_thread_.joinable()) global_thread_.join();
}

static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t) &&
                  std::atomic<uint32_t>::is_always_lock_free,
              "the doorbell is used as a futex word");

void Engine::Publish(const DeviceSample& s) {
  device_.Write(s);
  // Dekker pairing with the servo (sleeping = true; read the doorbell; check the device): either
  // the servo sees the new ring, or this thread sees it sleeping and wakes it.
  doorbell_.fetch_add(1);
  if (servo_sleeping_.load()) Wake(&doorbell_);
}

void Engine::set_consumer_watching(bool watching) { consumer_watching_.store(watching); }

// The servo thread's own state, on its stack: the tick's buffers and its clock.
struct Engine::ServoState {
  LoopCounters counters;
  TickResult result;
  DeviceSample sample;
  bool have_sample = false;
  unsigned seen_version = 0;
  bool was_fresh = false;
  Snapshot snap;
  ContactEventMsg event;
  ClearanceMsg clearance;
  unsigned clearance_version = 0;
  int64_t period = 0, spin = 0;  ///< ns
  int64_t next = 0;              ///< the next deadline
  // The device's own rhythm (a 1 kHz stream arrives every millisecond give or take the
  // machine's jitter): the servo also spins from device_lead before the next expected arrival
  // to device_lag after it, so a state is seen at once instead of through a futex wake-up
  // (measured: answer_wait p50 25 µs through the doorbell).
  int64_t device_lead = 0, device_lag = 0;
  int64_t last_arrival = 0, device_period = 0;
};

void Engine::ServoThread() {
  // Timer slack 1 ns: the default 50 µs lets the kernel coalesce our wake-up that late.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  PinToCore(options_.servo_cpu);
  ServoState s;
  s.period = static_cast<int64_t>(1e9 / options_.rate_hz);
  s.spin = static_cast<int64_t>(options_.spin_us * 1e3);
  s.device_lead = static_cast<int64_t>(options_.device_lead_us * 1e3);
  s.device_lag = static_cast<int64_t>(options_.device_lag_us * 1e3);
  s.next = MonotonicNs() + s.period;
  while (running_.load(std::memory_order_relaxed)) {
    const bool early = WaitForTick(&s);
    const int64_t start = MonotonicNs();
    if (!early && start > s.next + s.period) ++s.counters.overruns;
    // The certificate is read before the events and taken after them: every event of its pass
    // was pushed before it was written, so the contacts it leaves out are tracked when it holds.
    // (TryRead: a 6 kB copy the servo never waits on; a torn one is read again next tick.)
    unsigned cv = 0;
    if (clearances_.version() != s.clearance_version) cv = clearances_.TryRead(&s.clearance);
    ApplyEvents(&s, start);
    if (cv != 0) {
      s.clearance_version = cv;
      if (servo_->AdoptClearances(s.clearance)) {
        ++s.counters.clearances_taken;
      } else {
        ++s.counters.clearances_refused;
      }
    }
    ReadDevice(&s);
    servo_->Tick(s.have_sample ? &s.sample : nullptr, start, &s.result);
    CountTick(&s, start);
    if (s.result.answered) SendWrench(&s);
    if (s.result.violation > options_.journal_violation) JournalViolation(&s, start);
    CloseTick(&s, early);
    if ((s.counters.ticks & 3) == 0 || early) {
      servo_->FillSnapshot(&s.snap);
      s.snap.events_taken = s.counters.events_applied + s.counters.events_dropped;
      snapshot_.Write(s.snap);
    }
    Pace(&s, start, early);
    // Every tick (a ~200-byte copy, after the tick's timing): the statistics then agree with
    // the bridge's own counts (answers, unanswered, accepted) to within the states in flight.
    counters_.Write(s.counters);
  }
  counters_.Write(s.counters);
}

bool Engine::WaitForTick(ServoState* s) {
  // Hybrid wait: sleep to just before the deadline (or the device's next state), then spin; a
  // device state arriving meanwhile is answered at once.
  bool early = false;
  int64_t wake = s->next - s->spin;
  if (options_.spin_for_device && s->device_period > 0) {
    const int64_t expected = s->last_arrival + s->device_period;
    if (MonotonicNs() < expected + s->device_lag) wake = std::min(wake, expected - s->device_lead);
  }
  if (wake > MonotonicNs()) {
    servo_sleeping_.store(true);
    const uint32_t bell = doorbell_.load();
    if (device_.version() == s->seen_version) SleepUntilOrWoken(&doorbell_, bell, wake);
    servo_sleeping_.store(false, std::memory_order_relaxed);
    early = device_.version() != s->seen_version;
  }
  while (!early && MonotonicNs() < s->next) {
    if (device_.version() != s->seen_version) return true;
    CpuRelax();
  }
  return early;
}

void Engine::ApplyEvents(ServoState* s, int64_t start) {
  while (events_.Pop(&s->event)) {
    const ContactEventMsg& event = s->event;
    const bool applied = servo_->Apply(event);
    if (applied) {
      ++s->counters.events_applied;
    } else {
      ++s->counters.events_dropped;
    }
    JournalEntry j;
    j.tick = s->counters.ticks;
    j.time_ns = start;
    j.kind = applied ? JournalEntry::kEventApplied : JournalEntry::kEventDropped;
    j.added = event.added;
    j.surface_a = event.surface_a;
    j.surface_b = event.surface_b;
    for (int i = 0; i < 4; ++i) j.u[i] = event.u[i];
    journal_.Push(j);
  }
}

void Engine::ReadDevice(ServoState* s) {
  const int64_t previous_arrival = s->have_sample ? s->sample.received_ns : 0;
  const unsigned v = device_.Read(&s->sample);
  if (v != 0 && v != s->seen_version) {
    // The device's period: a running estimate of the gaps (a pause or a first state resets).
    const int64_t gap = s->sample.received_ns - previous_arrival;
    if (previous_arrival > 0 && gap > 0 && gap < 20'000'000) {
      s->device_period = s->device_period > 0 ? (7 * s->device_period + gap) / 8 : gap;
    } else {
      s->device_period = 0;
    }
    s->last_arrival = s->sample.received_ns;
  }
  if (v != 0) {
    s->have_sample = true;
    s->seen_version = v;
  }
}

void Engine::CountTick(ServoState* s, int64_t start) {
  LoopCounters& c = s->counters;
  const TickResult& r = s->result;
  if (s->have_sample) {
    const bool fresh = !r.timed_out;
    if (s->was_fresh && !fresh) ++c.device_timeouts;
    s->was_fresh = fresh;
  }
  if (r.fault) {
    ++c.faults;
    JournalEntry j;
    j.tick = c.ticks;
    j.time_ns = start;
    j.kind = JournalEntry::kFaultTick;
    journal_.Push(j);
  }
  c.unanswered += r.unanswered;
  c.contacts_tracked += r.tracked;
  c.contacts_solved += r.solves;
  c.contacts_lost += r.lost;
  WindowMax::Raise(&window_.violation, r.violation);
}

void Engine::CloseTick(ServoState* s, bool early) {
  LoopCounters& c = s->counters;
  ++c.ticks;
  c.early_ticks += early;
  c.iterations += s->result.iterations;
  c.max_violation = std::max(c.max_violation, s->result.violation);
  c.num_contacts = s->result.num_contacts;
}

void Engine::SendWrench(ServoState* s) {
  LoopCounters& c = s->counters;
  WrenchSample& w = s->result.wrench;
  if (w.state == kTimeout) {
    ++c.timeout_wrenches;
  } else {
    c.last_accepted = s->sample.accepted;
  }
  w.tick_end_ns = MonotonicNs();
  if (!wrenches_.Push(w)) ++c.wrenches_dropped;
  // The eventfd only when the bridge is not watching the ring (Dekker pairing with
  // set_consumer_watching(false) followed by a last look at the ring).
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (!consumer_watching_.load()) {
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t written = write(wake_fd_, &one, sizeof(one));
  }
  c.force_norm =
      std::sqrt(w.force[0] * w.force[0] + w.force[1] * w.force[1] + w.force[2] * w.force[2]);
  WindowMax::Raise(&window_.force, c.force_norm);
}

void Engine::JournalViolation(ServoState* s, int64_t start) {
  servo_->FillSnapshot(&s->snap);
  JournalEntry j;
  j.tick = s->counters.ticks;
  j.time_ns = start;
  j.kind = JournalEntry::kViolation;
  j.violation = s->result.violation;
  j.iterations = s->result.iterations;
  j.contacts = s->snap.num_contacts;
  j.min_beta = 0.0;
  for (int k = 0; k < s->snap.num_contacts; ++k) {
    j.min_beta = std::min(j.min_beta, s->snap.contacts[k].beta);
  }
  journal_.Push(j);
}

void Engine::Pace(ServoState* s, int64_t start, bool early) {
  const int64_t end = MonotonicNs();
  compute_.Add(1e-3 * static_cast<double>(end - start));
  if (early) return;  // an early tick answered a device state; the deadline stands
  if (end > s->next + s->period / 2) ++s->counters.late;
  s->next += s->period;
  if (end > s->next + s->period) s->next = end + s->period;  // fell behind: skip ahead
}

void Engine::GlobalThread() {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  PinToCore(options_.global_cpu);
  // The global stage shares its core with the LCM bridge, and a pass can take tens of
  // milliseconds (eight contacts appearing at once: 23 ms). At nice 10 the scheduler wakes the
  // bridge at once when a device state arrives instead of letting the pass finish its slice
  // (scripts/faults.sh contact_burst).
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), options_.global_nice);
  GlobalLink& link = *link_;
  Snapshot snap;
  const int64_t period = static_cast<int64_t>(1e9 / options_.global_rate_hz);
  int64_t next = MonotonicNs();
  int64_t last_wake = next;
  const auto stall_ns = static_cast<int64_t>(options_.global_stall_ms * 1e6);
  unsigned last_version = 0;
  while (running_.load(std::memory_order_relaxed)) {
    next += period;
    if (inject_global_stall_.exchange(false, std::memory_order_relaxed)) {
      SleepUntil(MonotonicNs() + static_cast<int64_t>(options_.injected_global_stall_ms * 1e6));
    }
    const int64_t woke = MonotonicNs();
    const int64_t gap = woke - last_wake;
    last_wake = woke;
    if (gap > stall_ns) global_stalls_.fetch_add(1, std::memory_order_relaxed);
    if (gap > global_longest_gap_ns_.load(std::memory_order_relaxed)) {
      global_longest_gap_ns_.store(gap, std::memory_order_relaxed);
    }
    const unsigned v = snapshot_.Read(&snap);
    // Wait until the servo has applied every event pushed (else a contact just added would be
    // found again, untracked).
    if (v != last_version && snap.events_taken >= events_pushed_.load()) {
      last_version = v;
      const int64_t t0 = MonotonicNs();
      link.Pass(snap, [&](const ContactEventMsg& m) {
        if (events_.Push(m)) events_pushed_.fetch_add(1);
      });
      clearances_.Write(link.clearances());
      stage_deepest_added_.store(link.deepest_added(), std::memory_order_relaxed);
      global_.Add(1e-3 * static_cast<double>(MonotonicNs() - t0));
      global_passes_.fetch_add(1, std::memory_order_relaxed);
    }
    const int64_t now = MonotonicNs();
    if (next > now) {
      SleepUntil(next);
    } else {
      next = now;
    }
  }
}

}  // namespace tangent::server
