#include "server/bridge.h"

#include <poll.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <tangent/contact_states_t.hpp>
#include <tangent/device_state_t.hpp>
#include <tangent/loop_stats_t.hpp>
#include <tangent/scene_state_t.hpp>
#include <tangent/wrench_t.hpp>

#include "server/lcm_convert.h"
#include "server/lcm_subscriptions.h"

namespace tangent::server {

std::unique_ptr<lcm::LCM> OpenLcm(const std::string& url) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    throw LcmError(
        "LCM could not start on \"" + url +
        "\". With a udpm:// URL this means UDP multicast is not routed on this host (no default "
        "route, or loopback without multicast). Fix, as root:\n"
        "  ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo\n"
        "or run inside a private network namespace:\n"
        "  unshare -rn sh -c 'ip link set lo up; ip route add 224.0.0.0/4 dev lo; <command>'");
  }
  return lcm;
}

struct Bridge::Impl {
  Engine* engine;
  Channels ch;
  std::FILE* log;
  bool status;
  std::unique_ptr<lcm::LCM> lcm;
  std::unique_ptr<LcmSubscriptions> subs;
  DeviceFilter filter;
  tangent::device_state_t device_msg;
  BridgeSummary* summary;
  std::vector<uint64_t> window_prev, window_now, window;
  int64_t last_ticks = 0;
  int64_t last_stats_ns = 0;
  int64_t stats_period_ns = 1000000000LL;
  int64_t start_ns = 0;
  tangent::wrench_t wrench;
  tangent::contact_states_t contacts;
  tangent::scene_state_t scene_msg;
  tangent::loop_stats_t stats;
  Snapshot snap;
  // The server's share of each round trip: receipt → the answering tick's start (waiting for
  // the servo), the tick, its end → the wrench published (hand-off to this thread and LCM).
  DurationHistogram waited, computed, handed;
  bool awaiting = false;  ///< a device state was handed to the servo and is not answered yet
  int64_t awaited_seq = -1;
  double answer_wait_us = 300.0;

  /// Waits (spinning, bounded by answer_wait_us) for the answer to the device state just handed
  /// to the servo and publishes it at once: a second wake-up of this thread through the eventfd
  /// costs ~40 µs here (measured: answer_handoff p50 42 µs). Messages arriving meanwhile are
  /// handled too (a ping is not kept waiting behind the spin).
  void AwaitAnswer() {
    const int64_t until = MonotonicNs() + static_cast<int64_t>(answer_wait_us * 1e3);
    engine->set_consumer_watching(true);
    pollfd fd{lcm->getFileno(), POLLIN, 0};
    while (awaiting && MonotonicNs() < until) {
      PublishWrenches();
      fd.revents = 0;
      if (poll(&fd, 1, 0) > 0) lcm->handleTimeout(0);
    }
    engine->set_consumer_watching(false);
    std::atomic_thread_fence(std::memory_order_seq_cst);
    PublishWrenches();  // (pushed after the last look, before the servo saw the flag cleared)
    awaiting = false;
  }

  /// Every packet on the device channel: decoded here (not by LCM's typed handler, which only
  /// prints a failure) so that undecodable and wrong-type packets are counted.
  void OnDevicePacket(const void* data, uint32_t size) {
    if (device_msg.decode(data, 0, static_cast<int>(size)) < 0) {
      ++summary->undecodable;
      if (size >= 8 && IsOtherTangentType(data)) ++summary->wrong_type;
      return;
    }
    OnDevice(device_msg);
  }

  /// Whether a packet starts with the fingerprint of another Tangent message type.
  static bool IsOtherTangentType(const void* data) {
    int64_t hash = 0;
    const auto* b = static_cast<const uint8_t*>(data);
    for (int i = 0; i < 8; ++i)
      hash = static_cast<int64_t>((static_cast<uint64_t>(hash) << 8) | b[i]);
    const int64_t others[] = {tangent::wrench_t::getHash(), tangent::loop_stats_t::getHash(),
                              tangent::scene_state_t::getHash(),
                              tangent::contact_states_t::getHash()};
    for (int64_t h : others) {
      if (hash == h) return true;
    }
    return false;
  }

  void OnDevice(const tangent::device_state_t& m) {
    const int64_t received = MonotonicNs();
    const DeviceFilter::Verdict v = filter.Check(ToReading(m), received);
    if (!DeviceFilter::Accepted(v)) return;
    engine->Publish(ToSample(m, filter.session_index(), filter.counts().accepted, received));
    awaiting = true;
    awaited_seq = m.seq;
  }
  void OnPing(const void* data, uint32_t size) {
    lcm->publish(ch.pong, data, size);
    ++summary->pings;
  }

  /// Publishes the wrenches the servo has pushed; clears `awaiting` when the awaited one went.
  void PublishWrenches() {
    WrenchSample w;
    while (engine->wrenches().Pop(&w)) {
      if (w.seq >= awaited_seq) awaiting = false;
      ToWrenchMsg(w, &wrench);
      lcm->publish(ch.wrench, &wrench);
      ++summary->wrenches_sent;
      // Where the server's share of the round trip goes.
      const int64_t sent = MonotonicNs();
      waited.Add(1e-3 * static_cast<double>(w.tick_start_ns - w.received_ns));
      computed.Add(1e-3 * static_cast<double>(w.tick_end_ns - w.tick_start_ns));
      handed.Add(1e-3 * static_cast<double>(sent - w.tick_end_ns));
    }
  }

  void PublishScene(int64_t now) {
    engine->snapshot().Read(&snap);
    const Scene& sc = engine->servo().scene();
    ToContactStates(snap, now / 1000, &contacts);
    lcm->publish(ch.contacts, &contacts);
    ToSceneState(snap, sc, now / 1000, &scene_msg);
    lcm->publish(ch.scene, &scene_msg);
  }

  /// The servo's journal into the log file (contact events, violation excursions).
  void DrainJournal() {
    JournalEntry j;
    char line[200];
    while (engine->journal().Pop(&j)) {
      if (!log) continue;
      FormatJournalEntry(j, start_ns, line, sizeof(line));
      std::fprintf(log, "%s\n", line);
    }
  }

  void PublishStats(int64_t now) {
    LoopCounters c;
    engine->counters().Read(&c);
    engine->compute_histogram().Copy(window_now.data());
    for (size_t b = 0; b < window.size(); ++b) window[b] = window_now[b] - window_prev[b];
    window_prev.swap(window_now);
    const double seconds = 1e-9 * static_cast<double>(now - last_stats_ns);
    stats.utime = now / 1000;
    stats.loop_rate_hz = seconds > 0 ? static_cast<double>(c.ticks - last_ticks) / seconds : 0.0;
    last_ticks = c.ticks;
    last_stats_ns = now;
    stats.ticks = c.ticks;
    stats.overruns = c.overruns;
    stats.compute_p50_us = DurationHistogram::Quantile(window.data(), 0.5);
    stats.compute_p99_us = DurationHistogram::Quantile(window.data(), 0.99);
    stats.compute_max_us = DurationHistogram::Quantile(window.data(), 1.0);
    stats.iterations_mean =
        c.ticks > 0 ? static_cast<double>(c.iterations) / static_cast<double>(c.ticks) : 0.0;
    engine->TakeWindowMax(&stats.max_violation, &stats.max_force_window);
    stats.max_violation_total = c.max_violation;
    stats.num_contacts = c.num_contacts;
    stats.force_norm = c.force_norm;
    const DeviceFilterCounts& f = filter.counts();
    stats.device_messages = f.accepted;
    stats.sessions = f.sessions;
    stats.undecodable = summary->undecodable;
    stats.wrong_type = summary->wrong_type;
    stats.lost_before_filter = f.lost;
    stats.unanswered = c.unanswered;
    stats.rejected_non_finite = f.non_finite;
    stats.rejected_quaternion = f.quaternion;
    stats.rejected_workspace = f.workspace;
    stats.rejected_device = f.device;
    stats.rejected_session = f.session;
    stats.rejected_sequence = f.sequence;
    stats.rejected_jump = f.jump;
    stats.device_timeouts = c.device_timeouts;
    stats.faults = c.faults;
    stats.wrenches_sent = summary->wrenches_sent;
    stats.global_passes = engine->global_passes();
    stats.global_pass_us = engine->global_histogram().max();
    stats.contact_events = c.events_applied;
    stats.events_dropped = c.events_dropped;
    stats.contacts_tracked = c.contacts_tracked;
    stats.contacts_solved = c.contacts_solved;
    stats.contacts_lost = c.contacts_lost;
    lcm->publish(ch.stats, &stats);
    char line[256];
    std::snprintf(line, sizeof(line),
                  "t=%.1fs rate=%.0fHz compute p50=%.1fus p99=%.1fus contacts=%d force=%.2fN "
                  "iter=%.2f violation=%.1e accepted=%lld rejected=%lld timeouts=%lld",
                  1e-9 * static_cast<double>(now - start_ns), stats.loop_rate_hz,
                  stats.compute_p50_us, stats.compute_p99_us, stats.num_contacts, stats.force_norm,
                  stats.iterations_mean, stats.max_violation, static_cast<long long>(f.accepted),
                  static_cast<long long>(f.rejected()), static_cast<long long>(c.device_timeouts));
    if (log) {
      std::fprintf(log, "%s\n", line);
      std::fflush(log);
    }
    if (status) std::fprintf(stderr, "\r%s", line);
  }
};

Bridge::Bridge(Engine* engine, const std::string& url, const Channels& channels, std::FILE* log,
               bool status_line, const BridgeOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const DeviceSpec& dv = engine->servo().scene().device;
  DeviceFilterOptions fo;
  fo.device_id = options.device_id;
  for (int i = 0; i < 3; ++i) {
    fo.workspace_min[i] = dv.workspace_min[i];
    fo.workspace_max[i] = dv.workspace_max[i];
  }
  m.filter = DeviceFilter(fo);
  m.stats_period_ns = static_cast<int64_t>(1e9 / options.stats_rate_hz);
  m.engine = engine;
  m.ch = channels;
  m.log = log;
  m.status = status_line;
  m.summary = &summary_;
  m.lcm = OpenLcm(url);
  m.subs = std::make_unique<LcmSubscriptions>(m.lcm.get());
  m.subs->Raw(channels.device,
              [&m](const void* data, uint32_t size) { m.OnDevicePacket(data, size); });
  m.subs->Raw(channels.ping, [&m](const void* data, uint32_t size) { m.OnPing(data, size); });
  m.window_prev.assign(DurationHistogram::kBins + 1, 0);
  m.window_now.assign(DurationHistogram::kBins + 1, 0);
  m.window.assign(DurationHistogram::kBins + 1, 0);
}

Bridge::~Bridge() = default;

void Bridge::Run(const std::atomic<bool>& stop, double duration_s) {
  Impl& m = *impl_;
  m.start_ns = MonotonicNs();
  m.last_stats_ns = m.start_ns;
  int64_t next_scene = m.start_ns, next_stats = m.start_ns + m.stats_period_ns;
  pollfd fds[2] = {{m.lcm->getFileno(), POLLIN, 0}, {m.engine->wake_fd(), POLLIN, 0}};
  while (!stop.load()) {
    const int64_t now = MonotonicNs();
    if (duration_s > 0 && now - m.start_ns > static_cast<int64_t>(duration_s * 1e9)) break;
    const int64_t until = std::min(next_scene, next_stats) - now;
    const int timeout_ms = static_cast<int>(std::clamp<int64_t>(until / 1000000, 0, 10));
    fds[0].revents = fds[1].revents = 0;
    poll(fds, 2, timeout_ms);
    if (fds[1].revents & POLLIN) {
      uint64_t count;
      [[maybe_unused]] const ssize_t r = read(m.engine->wake_fd(), &count, sizeof(count));
    }
    m.PublishWrenches();
    if (fds[0].revents & POLLIN) {
      while (m.lcm->handleTimeout(0) > 0) {
        m.PublishWrenches();
      }
    }
    if (m.awaiting) m.AwaitAnswer();
    const int64_t t = MonotonicNs();
    if (t >= next_scene) {
      m.PublishScene(t);
      next_scene = t + 33000000LL;
    }
    if (t >= next_scene || t >= next_stats) m.DrainJournal();
    if (t >= next_stats) {
      m.PublishStats(t);
      next_stats += m.stats_period_ns;
      if (next_stats < t) next_stats = t + m.stats_period_ns;
    }
  }
  m.PublishWrenches();
  if (m.status) std::fprintf(stderr, "\n");
  summary_.filter = m.filter.counts();
}

int64_t Bridge::Unanswered(const LoopCounters& c) const {
  // The servo counts the accepted states it skipped between two answers; those after its last
  // answer (at most the one in the mailbox when the engine stopped) are unanswered too.
  const int64_t accepted = impl_->filter.counts().accepted;
  return c.unanswered + std::max<int64_t>(0, accepted - std::max<int64_t>(c.last_accepted, 0));
}

std::string Bridge::Report() const {
  const Impl& m = *impl_;
  LoopCounters c;
  m.engine->counters().Read(&c);
  std::vector<uint64_t> h(DurationHistogram::kBins + 1), g(DurationHistogram::kBins + 1);
  m.engine->compute_histogram().Copy(h.data());
  m.engine->global_histogram().Copy(g.data());
  const DeviceFilterCounts& f = m.filter.counts();
  std::ostringstream s;
  const double seconds = 1e-9 * static_cast<double>(MonotonicNs() - m.start_ns);
  s << "ticks=" << c.ticks << "\nrate_hz=" << static_cast<double>(c.ticks) / seconds
    << "\nearly_ticks=" << c.early_ticks
    << "\ncompute_p50_us=" << DurationHistogram::Quantile(h.data(), 0.5)
    << "\ncompute_p99_us=" << DurationHistogram::Quantile(h.data(), 0.99)
    << "\ncompute_p999_us=" << DurationHistogram::Quantile(h.data(), 0.999)
    << "\ncompute_max_us=" << m.engine->compute_histogram().max() << "\noverruns=" << c.overruns
    << "\nlate=" << c.late << "\niterations_mean="
    << (c.ticks ? static_cast<double>(c.iterations) / static_cast<double>(c.ticks) : 0.0)
    << "\ncontacts=" << c.num_contacts << "\nmax_violation=" << c.max_violation
    << "\ndevice_messages=" << f.accepted << "\nsessions=" << f.sessions
    << "\nundecodable=" << summary_.undecodable << "\nwrong_type=" << summary_.wrong_type
    << "\nlost_before_filter=" << f.lost << "\nunanswered=" << Unanswered(c)
    << "\nrejected_non_finite=" << f.non_finite << "\nrejected_quaternion=" << f.quaternion
    << "\nrejected_workspace=" << f.workspace << "\nrejected_device=" << f.device
    << "\nrejected_session=" << f.session << "\nrejected_sequence=" << f.sequence
    << "\nrejected_jump=" << f.jump << "\ndevice_timeouts=" << c.device_timeouts
    << "\nfaults=" << c.faults << "\nwrenches_sent=" << summary_.wrenches_sent
    << "\ntimeout_wrenches=" << c.timeout_wrenches << "\nwrenches_dropped=" << c.wrenches_dropped
    << "\nglobal_passes=" << m.engine->global_passes()
    << "\nglobal_pass_p50_us=" << DurationHistogram::Quantile(g.data(), 0.5)
    << "\nglobal_pass_max_us=" << m.engine->global_histogram().max()
    << "\ncontact_events=" << c.events_applied << "\nevents_dropped=" << c.events_dropped
    << "\ncontacts_tracked=" << c.contacts_tracked << "\ncontacts_solved=" << c.contacts_solved
    << "\ncontacts_lost=" << c.contacts_lost << "\npings_answered=" << summary_.pings;
  std::vector<uint64_t> d(DurationHistogram::kBins + 1);
  const std::pair<const char*, const DurationHistogram*> shares[] = {
      {"answer_wait", &m.waited}, {"answer_tick", &m.computed}, {"answer_handoff", &m.handed}};
  for (const auto& [name, hist] : shares) {
    hist->Copy(d.data());
    s << "\n"
      << name << "_p50_us=" << DurationHistogram::Quantile(d.data(), 0.5) << "\n"
      << name << "_p99_us=" << DurationHistogram::Quantile(d.data(), 0.99);
  }
  s << "\n";
  return s.str();
}

}  // namespace tangent::server
