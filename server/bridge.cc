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

namespace {

DeviceFilterOptions FilterOptions(const DeviceSpec& device, const BridgeOptions& options,
                                  double device_timeout) {
  DeviceFilterOptions fo;
  fo.device_id = options.device_id ? options.device_id : device.id;
  fo.any_device = options.any_device && !fo.device_id;
  fo.owner_timeout = device_timeout;
  for (int i = 0; i < 3; ++i) {
    fo.workspace_min[i] = device.workspace_min[i];
    fo.workspace_max[i] = device.workspace_max[i];
  }
  return fo;
}

/// The loop statistics message from the servo's counters and the bridge's own counts (the
/// window fields — rate, compute quantiles, window maxima — are filled by the caller).
void FillLoopStats(const LoopCounters& c, const DeviceFilterCounts& f, const BridgeSummary& b,
                   tangent::loop_stats_t* stats) {
  stats->ticks = c.ticks;
  stats->overruns = c.overruns;
  stats->iterations_mean =
      c.ticks > 0 ? static_cast<double>(c.iterations) / static_cast<double>(c.ticks) : 0.0;
  stats->max_violation_total = c.max_violation;
  stats->num_contacts = c.num_contacts;
  stats->force_norm = c.force_norm;
  stats->device_messages = f.accepted;
  stats->sessions = f.sessions;
  stats->undecodable = b.undecodable;
  stats->wrong_type = b.wrong_type;
  stats->lost_before_filter = f.lost;
  stats->unanswered = c.unanswered;
  stats->rejected_non_finite = f.non_finite;
  stats->rejected_quaternion = f.quaternion;
  stats->rejected_workspace = f.workspace;
  stats->rejected_device = f.device;
  stats->rejected_session = f.session;
  stats->rejected_sequence = f.sequence;
  stats->rejected_jump = f.jump;
  stats->rejected_pending = f.pending;
  stats->sequence_resets = f.seq_resets;
  stats->device_timeouts = c.device_timeouts;
  stats->faults = c.faults;
  stats->wrenches_sent = b.wrenches_sent;
  stats->contact_events = c.events_applied;
  stats->events_dropped = c.events_dropped;
  stats->contacts_tracked = c.contacts_tracked;
  stats->contacts_solved = c.contacts_solved;
  stats->contacts_lost = c.contacts_lost;
}

}  // namespace

/// The bridge thread's state and its steps: receive (device states, pings), answer (wrenches),
/// publish for viewers (scene, contacts, statistics) and log (journal, status line).
class Bridge::Impl {
 public:
  Impl(Engine* engine, const std::string& url, const Channels& channels, std::FILE* log,
       bool status_line, const BridgeOptions& options, BridgeSummary* summary)
      : engine_(engine),
        ch_(channels),
        log_(log),
        status_(status_line),
        lcm_(OpenLcm(url)),
        view_lcm_(options.view_url.empty() ? nullptr : OpenLcm(options.view_url)),
        filter_(FilterOptions(engine->servo().scene().device, options,
                              engine->options().servo.device_timeout)),
        summary_(summary),
        window_prev_(DurationHistogram::kBins + 1, 0),
        window_now_(DurationHistogram::kBins + 1, 0),
        window_(DurationHistogram::kBins + 1, 0),
        stats_period_ns_(static_cast<int64_t>(1e9 / options.stats_rate_hz)) {
    subs_ = std::make_unique<LcmSubscriptions>(lcm_.get());
    subs_->Raw(channels.device,
               [this](const void* data, uint32_t size) { OnDevicePacket(data, size); });
    subs_->Raw(channels.ping, [this](const void* data, uint32_t size) { OnPing(data, size); });
  }

  void Run(const std::atomic<bool>& stop, double duration_s) {
    start_ns_ = MonotonicNs();
    last_stats_ns_ = start_ns_;
    int64_t next_scene = start_ns_, next_stats = start_ns_ + stats_period_ns_;
    pollfd fds[2] = {{lcm_->getFileno(), POLLIN, 0}, {engine_->wake_fd(), POLLIN, 0}};
    while (!stop.load()) {
      const int64_t now = MonotonicNs();
      if (duration_s > 0 && now - start_ns_ > static_cast<int64_t>(duration_s * 1e9)) break;
      const int64_t until = std::min(next_scene, next_stats) - now;
      WaitForTraffic(fds, static_cast<int>(std::clamp<int64_t>(until / 1000000, 0, 10)));
      if (awaiting_) AwaitAnswer();
      const int64_t t = MonotonicNs();
      if (t >= next_scene) {
        PublishScene(t);
        next_scene = t + kScenePeriodNs;
      }
      if (t >= next_scene || t >= next_stats) DrainJournal();
      if (t >= next_stats) {
        PublishStats(t);
        next_stats += stats_period_ns_;
        if (next_stats < t) next_stats = t + stats_period_ns_;
      }
    }
    PublishWrenches();
    if (status_) std::fprintf(stderr, "\n");
    summary_->filter = filter_.counts();
  }

  const DeviceFilterCounts& filter_counts() const { return filter_.counts(); }

  /// Accepted device states never answered (final: call after the engine stopped).
  int64_t Unanswered(const LoopCounters& c) const {
    // The servo counts the accepted states it skipped between two answers; those after its last
    // answer (at most the one in the mailbox when the engine stopped) are unanswered too.
    const int64_t accepted = filter_.counts().accepted;
    return c.unanswered + std::max<int64_t>(0, accepted - std::max<int64_t>(c.last_accepted, 0));
  }

  std::string Report() const;

  std::string Serving() const {
    const DeviceFilterOptions& o = filter_.options();
    if (o.device_id) return "serving device " + std::to_string(*o.device_id);
    if (o.any_device) {
      return "serving the first device that earns a session (--device-id any), and only it";
    }
    return "NO DEVICE DECLARED: every device state is rejected (rejected_device). Name the "
           "device served in the scene (\"device\": {\"id\": N}) or with --device-id N, or "
           "choose --device-id any to serve the first device that earns a session";
  }

 private:
  static constexpr int64_t kScenePeriodNs = 33'000'000;  ///< scene and contacts at ~30 Hz

  /// Waits up to timeout_ms for a packet or the servo's eventfd; publishes the wrenches the
  /// servo has pushed and handles every packet waiting.
  void WaitForTraffic(pollfd* fds, int timeout_ms) {
    fds[0].revents = fds[1].revents = 0;
    poll(fds, 2, timeout_ms);
    if (fds[1].revents & POLLIN) {
      uint64_t count;
      [[maybe_unused]] const ssize_t r = read(engine_->wake_fd(), &count, sizeof(count));
    }
    PublishWrenches();
    if (fds[0].revents & POLLIN) {
      while (lcm_->handleTimeout(0) > 0) PublishWrenches();
    }
  }

  /// Waits (spinning, bounded by answer_wait_us_) for the answer to the device state just handed
  /// to the servo and publishes it at once: a second wake-up of this thread through the eventfd
  /// costs ~40 µs here (measured: answer_handoff p50 42 µs). Messages arriving meanwhile are
  /// handled too (a ping is not kept waiting behind the spin).
  void AwaitAnswer() {
    const int64_t until = MonotonicNs() + static_cast<int64_t>(answer_wait_us_ * 1e3);
    engine_->set_consumer_watching(true);
    pollfd fd{lcm_->getFileno(), POLLIN, 0};
    while (awaiting_ && MonotonicNs() < until) {
      PublishWrenches();
      fd.revents = 0;
      if (poll(&fd, 1, 0) > 0) lcm_->handleTimeout(0);
    }
    engine_->set_consumer_watching(false);
    std::atomic_thread_fence(std::memory_order_seq_cst);
    PublishWrenches();  // (pushed after the last look, before the servo saw the flag cleared)
    awaiting_ = false;
  }

  /// Every packet on the device channel: decoded here (not by LCM's typed handler, which only
  /// prints a failure) so that undecodable and wrong-type packets are counted.
  void OnDevicePacket(const void* data, uint32_t size) {
    DeviceSample sample;
    bool wrong_type = false;
    const PacketFate fate =
        ReadDevicePacket(data, size, MonotonicNs(), &filter_, &device_msg_, &sample, &wrong_type);
    if (fate == PacketFate::kUndecodable) {
      ++summary_->undecodable;
      if (wrong_type) ++summary_->wrong_type;
      return;
    }
    if (fate != PacketFate::kAccepted) return;
    last_device_ = device_msg_;  // (fixed-size fields: a copy, no allocation)
    have_device_ = true;
    engine_->Publish(sample);
    awaiting_ = true;
    awaited_seq_ = device_msg_.seq;
  }

  void OnPing(const void* data, uint32_t size) {
    lcm_->publish(ch_.pong, data, size);
    ++summary_->pings;
  }

  /// Publishes the wrenches the servo has pushed; clears `awaiting_` when the awaited one went.
  void PublishWrenches() {
    WrenchSample w;
    while (engine_->wrenches().Pop(&w)) {
      if (w.seq >= awaited_seq_) awaiting_ = false;
      ToWrenchMsg(w, &wrench_);
      lcm_->publish(ch_.wrench, &wrench_);
      ++summary_->wrenches_sent;
      // Where the server's share of the round trip goes.
      const int64_t sent = MonotonicNs();
      waited_.Add(1e-3 * static_cast<double>(w.tick_start_ns - w.received_ns));
      computed_.Add(1e-3 * static_cast<double>(w.tick_end_ns - w.tick_start_ns));
      handed_.Add(1e-3 * static_cast<double>(sent - w.tick_end_ns));
    }
  }

  void PublishScene(int64_t now) {
    engine_->snapshot().Read(&snap_);
    ToContactStates(snap_, now / 1000, &contacts_);
    lcm_->publish(ch_.contacts, &contacts_);
    ToSceneState(snap_, engine_->servo().scene(), now / 1000, &scene_msg_);
    lcm_->publish(ch_.scene, &scene_msg_);
    if (view_lcm_) {
      view_lcm_->publish(ch_.contacts, &contacts_);
      view_lcm_->publish(ch_.scene, &scene_msg_);
      if (summary_->wrenches_sent > 0) view_lcm_->publish(ch_.wrench, &wrench_);
      if (have_device_) view_lcm_->publish(ch_.device, &last_device_);
    }
  }

  /// The servo's journal into the log file (contact events, violation excursions), and a line
  /// when the global stage has stalled since the last look.
  void DrainJournal() {
    JournalEntry j;
    char line[200];
    const int64_t stalls = engine_->global_stalls();
    if (stalls != stalls_logged_ && log_) {
      std::fprintf(log_, "%.3f: global stage stalled (%lld so far, longest gap %.1f ms)\n",
                   1e-9 * static_cast<double>(MonotonicNs() - start_ns_),
                   static_cast<long long>(stalls), engine_->global_longest_gap_ms());
    }
    stalls_logged_ = stalls;
    while (engine_->journal().Pop(&j)) {
      if (!log_) continue;
      FormatJournalEntry(j, start_ns_, line, sizeof(line));
      std::fprintf(log_, "%s\n", line);
    }
  }

  void PublishStats(int64_t now) {
    LoopCounters c;
    engine_->counters().Read(&c);
    engine_->compute_histogram().Copy(window_now_.data());
    for (size_t b = 0; b < window_.size(); ++b) window_[b] = window_now_[b] - window_prev_[b];
    window_prev_.swap(window_now_);
    const double seconds = 1e-9 * static_cast<double>(now - last_stats_ns_);
    FillLoopStats(c, filter_.counts(), *summary_, &stats_);
    stats_.utime = now / 1000;
    stats_.loop_rate_hz = seconds > 0 ? static_cast<double>(c.ticks - last_ticks_) / seconds : 0.0;
    last_ticks_ = c.ticks;
    last_stats_ns_ = now;
    stats_.compute_p50_us = DurationHistogram::Quantile(window_.data(), 0.5);
    stats_.compute_p99_us = DurationHistogram::Quantile(window_.data(), 0.99);
    stats_.compute_max_us = DurationHistogram::Quantile(window_.data(), 1.0);
    engine_->TakeWindowMax(&stats_.max_violation, &stats_.max_force_window);
    stats_.global_passes = engine_->global_passes();
    stats_.global_pass_us = engine_->global_histogram().max();
    lcm_->publish(ch_.stats, &stats_);
    if (view_lcm_) view_lcm_->publish(ch_.stats, &stats_);
    WriteStatusLine(now, c);
  }

  void WriteStatusLine(int64_t now, const LoopCounters& c) {
    const DeviceFilterCounts& f = filter_.counts();
    char line[256];
    std::snprintf(line, sizeof(line),
                  "t=%.1fs rate=%.0fHz compute p50=%.1fus p99=%.1fus contacts=%d force=%.2fN "
                  "iter=%.2f violation=%.1e accepted=%lld rejected=%lld timeouts=%lld",
                  1e-9 * static_cast<double>(now - start_ns_), stats_.loop_rate_hz,
                  stats_.compute_p50_us, stats_.compute_p99_us, stats_.num_contacts,
                  stats_.force_norm, stats_.iterations_mean, stats_.max_violation,
                  static_cast<long long>(f.accepted), static_cast<long long>(f.rejected()),
                  static_cast<long long>(c.device_timeouts));
    if (log_) {
      std::fprintf(log_, "%s\n", line);
      std::fflush(log_);
    }
    if (status_) std::fprintf(stderr, "\r%s", line);
  }

  Engine* engine_;
  Channels ch_;
  std::FILE* log_;
  int64_t stalls_logged_ = 0;
  bool status_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<lcm::LCM> view_lcm_;  ///< publish only (no receive thread is started)
  std::unique_ptr<LcmSubscriptions> subs_;
  DeviceFilter filter_;
  BridgeSummary* summary_;
  // Message buffers (reused: the bridge's loop does not allocate per message).
  tangent::device_state_t device_msg_;
  tangent::device_state_t last_device_;  ///< the last accepted, for viewers
  bool have_device_ = false;
  tangent::wrench_t wrench_;
  tangent::contact_states_t contacts_;
  tangent::scene_state_t scene_msg_;
  tangent::loop_stats_t stats_;
  Snapshot snap_;
  // The compute histogram at the last statistics message and now; their difference, the window.
  std::vector<uint64_t> window_prev_, window_now_, window_;
  int64_t stats_period_ns_;
  int64_t last_ticks_ = 0;
  int64_t last_stats_ns_ = 0;
  int64_t start_ns_ = 0;
  // The server's share of each round trip: receipt → the answering tick's start (waiting for
  // the servo), the tick, its end → the wrench published (hand-off to this thread and LCM).
  DurationHistogram waited_, computed_, handed_;
  bool awaiting_ = false;  ///< a device state was handed to the servo and is not answered yet
  int64_t awaited_seq_ = -1;
  double answer_wait_us_ = 300.0;
};

Bridge::Bridge(Engine* engine, const std::string& url, const Channels& channels, std::FILE* log,
               bool status_line, const BridgeOptions& options)
    : impl_(std::make_unique<Impl>(engine, url, channels, log, status_line, options, &summary_)) {}

Bridge::~Bridge() = default;

void Bridge::Run(const std::atomic<bool>& stop, double duration_s) { impl_->Run(stop, duration_s); }

int64_t Bridge::Unanswered(const LoopCounters& c) const { return impl_->Unanswered(c); }

std::string Bridge::Report() const { return impl_->Report(); }

std::string Bridge::Serving() const { return impl_->Serving(); }

std::string Bridge::Impl::Report() const {
  LoopCounters c;
  engine_->counters().Read(&c);
  std::vector<uint64_t> h(DurationHistogram::kBins + 1), g(DurationHistogram::kBins + 1);
  engine_->compute_histogram().Copy(h.data());
  engine_->global_histogram().Copy(g.data());
  const DeviceFilterCounts& f = filter_.counts();
  const BridgeSummary& b = *summary_;
  std::ostringstream s;
  const double seconds = 1e-9 * static_cast<double>(MonotonicNs() - start_ns_);
  s << "ticks=" << c.ticks << "\nrate_hz=" << static_cast<double>(c.ticks) / seconds
    << "\nearly_ticks=" << c.early_ticks
    << "\ncompute_p50_us=" << DurationHistogram::Quantile(h.data(), 0.5)
    << "\ncompute_p99_us=" << DurationHistogram::Quantile(h.data(), 0.99)
    << "\ncompute_p999_us=" << DurationHistogram::Quantile(h.data(), 0.999)
    << "\ncompute_max_us=" << engine_->compute_histogram().max() << "\noverruns=" << c.overruns
    << "\nlate=" << c.late << "\niterations_mean="
    << (c.ticks ? static_cast<double>(c.iterations) / static_cast<double>(c.ticks) : 0.0)
    << "\ncontacts=" << c.num_contacts << "\nmax_violation=" << c.max_violation
    << "\ndevice_messages=" << f.accepted << "\nsessions=" << f.sessions
    << "\nundecodable=" << b.undecodable << "\nwrong_type=" << b.wrong_type
    << "\nlost_before_filter=" << f.lost << "\nunanswered=" << Unanswered(c)
    << "\nrejected_non_finite=" << f.non_finite << "\nrejected_quaternion=" << f.quaternion
    << "\nrejected_workspace=" << f.workspace << "\nrejected_device=" << f.device
    << "\nrejected_session=" << f.session << "\nrejected_sequence=" << f.sequence
    << "\nrejected_jump=" << f.jump << "\nrejected_pending=" << f.pending
    << "\nsequence_resets=" << f.seq_resets << "\ndevice_timeouts=" << c.device_timeouts
    << "\nfaults=" << c.faults << "\nwrenches_sent=" << b.wrenches_sent
    << "\ntimeout_wrenches=" << c.timeout_wrenches << "\nwrenches_dropped=" << c.wrenches_dropped
    << "\nglobal_passes=" << engine_->global_passes()
    << "\nglobal_stalls=" << engine_->global_stalls()
    << "\nglobal_longest_gap_ms=" << engine_->global_longest_gap_ms()
    << "\nglobal_pass_p50_us=" << DurationHistogram::Quantile(g.data(), 0.5)
    << "\nglobal_pass_max_us=" << engine_->global_histogram().max()
    << "\nstage_deepest_added_m=" << engine_->stage_deepest_added()
    << "\ncontact_events=" << c.events_applied << "\nevents_dropped=" << c.events_dropped
    << "\ncontacts_tracked=" << c.contacts_tracked << "\ncontacts_solved=" << c.contacts_solved
    << "\ncontacts_lost=" << c.contacts_lost << "\npings_answered=" << b.pings;
  std::vector<uint64_t> d(DurationHistogram::kBins + 1);
  const std::pair<const char*, const DurationHistogram*> shares[] = {
      {"answer_wait", &waited_}, {"answer_tick", &computed_}, {"answer_handoff", &handed_}};
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
