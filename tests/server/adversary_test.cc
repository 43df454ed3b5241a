// An adversarial device client against a real tangentd over real LCM (issue 12), run inside a
// private network namespace (tests/server/in_netns.sh): one tangentd per scene serves the whole
// suite, so "no attack needs a restart to recover" is part of what passes.
//
//   adversary_test --tangentd PATH --scene FILE.json [--flood-seconds S] [gtest flags]
//
// The floods (A14, A15) last 5 s by default; ctest runs them for 2 s (the same checks, and a
// 100 kHz flood is 200,000 states either way).
//
// The tests run in order against the same server: each attack, then a settle period of normal
// states, then its checks. Every wrench received is checked in its session: finite, |F| ≤
// max_force, |ΔF| ≤ max_force_rate · Δt on the server's clock (server_utime). After each attack
// the scene satisfies its constraints (violation ≤ 1e-6 over the settle window), keeps the
// contacts it had before, and each counter in loop_stats_t moved by exactly what was injected.
// Randomness (garbage packets) is seeded.
//
// What is asserted holds on any machine, however slow or loaded (docs/reliability.md, "What the
// real-time tests assert"): safety, the counters' accounting, no state answered twice, and the
// protocol's timing on the server's own clock (a restarted client served within one ramp, a
// ramp that ends). How many states a second the server answered depends on the machine: it is
// printed, and judged by the rate benchmarks (bench/server_rate) and scripts/faults.sh.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <tangent/device_state_t.hpp>
#include <tangent/loop_stats_t.hpp>
#include <tangent/wrench_t.hpp>

#include "server/lcm_subscriptions.h"

namespace {

std::string g_tangentd, g_scene;
double g_flood_seconds = 5.0;
constexpr const char* kUrl = "udpm://239.255.76.68:7668?ttl=0";
constexpr int64_t kDevice = 1;
constexpr double kDeviceTimeout = 0.1;  ///< s: ServoOptions::device_timeout, tangentd's default

int64_t NowNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000LL + t.tv_nsec;
}

void SleepUntil(int64_t t_ns) {
  if (t_ns - 200000 > NowNs()) {
    timespec ts{static_cast<time_t>((t_ns - 200000) / 1000000000LL),
                static_cast<long>((t_ns - 200000) % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
    }
  }
  while (NowNs() < t_ns) {
  }
}

struct Received {
  tangent::wrench_t w;
  int64_t at_ns;
};

/// The scene's device limits and the pull the scene resists (so the force is not zero).
struct SceneFacts {
  double max_force = 3.3, max_force_rate = 500.0;
  bool declares_device = false;  ///< the scene names its device (else --device-id 1 is passed)
  Eigen::Vector3d pull = Eigen::Vector3d::Zero();
  Eigen::Vector3d jump = Eigen::Vector3d::Zero();  ///< a sustained jump the scene resists
};

SceneFacts ReadScene(const std::string& path) {
  std::ifstream f(path);
  const nlohmann::json j = nlohmann::json::parse(f);
  SceneFacts s;
  if (j.contains("device")) {
    s.max_force = j["device"].value("max_force", s.max_force);
    s.max_force_rate = j["device"].value("max_force_rate", s.max_force_rate);
    s.declares_device = j["device"].contains("id");
    if (s.declares_device && j["device"]["id"] != kDevice) {
      ADD_FAILURE() << path << " serves device " << j["device"]["id"] << ", this client is "
                    << kDevice;
    }
  }
  // A pull each example scene resists (tests/server/servo_safety_test.cc measured them), and a
  // 6 cm jump further that way, inside the workspace (docs/server.md: a sideways pull of the
  // paperclip chain at full force is a known tracking limit, not exercised here).
  const bool clips = path.find("paperclips") != std::string::npos;
  s.pull = clips ? Eigen::Vector3d(0, 4e-3, 0) : Eigen::Vector3d(30e-3, 0, 0);
  s.jump = clips ? Eigen::Vector3d(0, 0.06, 0) : Eigen::Vector3d(0.06, 0, 0);
  return s;
}

/// The server process and the client's LCM: sends device states, records every wrench and
/// statistics message.
class Harness {
 public:
  void Start() {
    facts_ = ReadScene(g_scene);
    dir_ = "/tmp/tangent_adversary_XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
    out_ = dir_ + "/tangentd.out";
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      const std::string log = dir_ + "/tangentd.log";
      const std::string id = std::to_string(kDevice);
      if (facts_.declares_device) {
        execl(g_tangentd.c_str(), g_tangentd.c_str(), "--scene", g_scene.c_str(), "--stats-rate",
              "20", "--log", log.c_str(), static_cast<char*>(nullptr));
      } else {
        execl(g_tangentd.c_str(), g_tangentd.c_str(), "--scene", g_scene.c_str(), "--stats-rate",
              "20", "--log", log.c_str(), "--device-id", id.c_str(), static_cast<char*>(nullptr));
      }
      _exit(127);
    }
    ASSERT_GT(pid_, 0);
    bool up = false;
    for (int k = 0; k < 1200 && !up; ++k) {  // the scene loads (offset meshes certified)
      std::ifstream f(out_);
      std::stringstream text;
      text << f.rdbuf();
      up = text.str().find("tangentd: scene") != std::string::npos;
      if (!up) {
        ASSERT_EQ(waitpid(pid_, nullptr, WNOHANG), 0) << "tangentd died:\n" << text.str();
        usleep(100000);
      }
    }
    ASSERT_TRUE(up) << "tangentd did not start";
    lcm_ = std::make_unique<lcm::LCM>(kUrl);
    ASSERT_TRUE(lcm_->good()) << "LCM did not start: run inside tests/server/in_netns.sh";
    subs_ = std::make_unique<tangent::server::LcmSubscriptions>(lcm_.get());
    subs_->Typed<tangent::wrench_t>(
        "TANGENT_WRENCH", [this](const tangent::wrench_t& m) { OnWrench(m); }, 1000000);
    subs_->Typed<tangent::loop_stats_t>("TANGENT_STATS",
                                        [this](const tangent::loop_stats_t& m) { OnStats(m); });
    rx_ = std::thread([this] {
      while (!stop_.load()) lcm_->handleTimeout(5);
    });
  }

  void Stop() {
    if (rx_.joinable()) {
      stop_.store(true);
      rx_.join();
    }
    if (pid_ > 0) {
      kill(pid_, SIGINT);
      int status = 0;
      waitpid(pid_, &status, 0);
      std::ifstream f(out_);
      std::stringstream text;
      text << f.rdbuf();
      std::printf("tangentd output (load log omitted):\n");
      std::istringstream lines(text.str());
      for (std::string line; std::getline(lines, line);) {
        if (line.rfind("load:", 0) != 0) std::printf("  %s\n", line.c_str());
      }
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "tangentd exit " << status;
      pid_ = -1;
    }
  }

  // --- sending ---------------------------------------------------------------------------------
  /// A well-formed state of `session` at position p (device frame, m), next seq of that session.
  tangent::device_state_t State(int64_t of_session, const Eigen::Vector3d& p,
                                int64_t device = kDevice) {
    tangent::device_state_t m{};
    m.utime = NowNs() / 1000 + utime_offset_;
    m.device_id = device;
    m.session = of_session;
    m.seq = ++seq_[of_session];
    for (int i = 0; i < 3; ++i) m.position[i] = p[i];
    m.orientation[0] = 1.0;
    m.buttons = 1;
    return m;
  }
  void Publish(const tangent::device_state_t& m) {
    NoteSend();
    lcm_->publish("TANGENT_DEVICE", &m);
    states_published_.fetch_add(1, std::memory_order_relaxed);
  }
  void PublishRaw(const void* data, size_t n) {
    NoteSend();
    lcm_->publish("TANGENT_DEVICE", data, static_cast<unsigned>(n));
  }
  /// The longest pause between two messages this client sent since ResetGap(): a pause of the
  /// client itself (this process descheduled on a busy machine). A pause longer than the
  /// server's device timeout must be answered by a timeout; the tests that expect none check
  /// that the client did not pause for half of it.
  int64_t max_gap_ns() const { return max_gap_ns_; }
  void ResetGap() {
    max_gap_ns_ = 0;
    last_send_ns_ = NowNs();
  }
  /// Calls tick(k) at `rate_hz` for `seconds` (sleep then spin to each deadline).
  int64_t Drive(double seconds, double rate_hz, const std::function<void(int64_t)>& tick) {
    const int64_t period = static_cast<int64_t>(1e9 / rate_hz);
    const int64_t start = NowNs();
    const int64_t n = static_cast<int64_t>(seconds * rate_hz);
    for (int64_t k = 0; k < n; ++k) {
      if (period >= 50000)
        SleepUntil(start + k * period);
      else
        while (NowNs() < start + k * period) {
        }
      tick(k);
    }
    return n;
  }
  /// Normal states of `session` at the pull pose for `seconds` at 1 kHz.
  void Hold(int64_t of_session, double seconds) {
    Drive(seconds, 1000.0, [&](int64_t) { Publish(State(of_session, facts_.pull)); });
  }

  // --- receiving -------------------------------------------------------------------------------
  size_t WrenchCount() {
    std::lock_guard<std::mutex> l(mutex_);
    return wrenches_.size();
  }
  std::vector<Received> WrenchesSince(size_t from) {
    std::lock_guard<std::mutex> l(mutex_);
    return {wrenches_.begin() + static_cast<std::ptrdiff_t>(from), wrenches_.end()};
  }
  /// Whether a wrench answering a state of `of_session` (not a timeout wrench) has arrived since
  /// wrench `from`.
  bool Answered(int64_t of_session, size_t from) {
    std::lock_guard<std::mutex> l(mutex_);
    for (size_t i = from; i < wrenches_.size(); ++i) {
      if (wrenches_[i].w.session == of_session && wrenches_[i].w.state != 2) return true;
    }
    return false;
  }
  /// The first answer (not a timeout wrench) to `of_session` that arrived after t_ns, or null.
  std::optional<Received> FirstAnswerAfter(int64_t of_session, int64_t t_ns) {
    std::lock_guard<std::mutex> l(mutex_);
    for (const Received& r : wrenches_) {
      if (r.at_ns > t_ns && r.w.session == of_session && r.w.state != 2) return r;
    }
    return std::nullopt;
  }
  /// A statistics message that reflects everything sent before now: received more than 150 ms
  /// after now (the servo publishes its counters every 256 ticks, 64 ms at 4 kHz).
  /// The served client keeps sending meanwhile (a pause would be a device timeout).
  /// *published (if given) is the number of device states this client had published when the
  /// message arrived.
  tangent::loop_stats_t FreshStats(int64_t* published = nullptr) {
    const int64_t after = NowNs() + 150'000'000;
    for (int k = 0; k < 400; ++k) {
      {
        std::lock_guard<std::mutex> l(mutex_);
        if (!stats_.empty() && stats_.back().at_ns > after) {
          if (published) *published = stats_.back().published;
          return stats_.back().m;
        }
      }
      Hold(session, 0.005);
    }
    ADD_FAILURE() << "no statistics from tangentd";
    return {};
  }
  /// The largest window violation and the last contact count over statistics received since t.
  std::pair<double, int> ViolationSince(int64_t t_ns) {
    std::lock_guard<std::mutex> l(mutex_);
    double v = 0.0;
    int contacts = -1;
    for (const StatsReceived& s : stats_) {
      if (s.at_ns <= t_ns) continue;
      v = std::max(v, s.m.max_violation);
      contacts = s.m.num_contacts;
    }
    return {v, contacts};
  }

  /// Checks every wrench since `from`, per session: finite, within max_force, and within the
  /// rate limit of the previous wrench of the same session on the server's clock.
  void CheckWrenches(size_t from, const char* what) {
    const std::vector<Received> all = WrenchesSince(from);
    int non_finite = 0, over = 0, steps = 0, twice = 0;
    std::map<std::pair<int64_t, int64_t>, int> answers;  // (session, seq) -> answers
    double worst_excess = -1e300, max_force = 0.0;
    for (const Received& r : all) {
      const Eigen::Vector3d f(r.w.force[0], r.w.force[1], r.w.force[2]);
      if (!f.allFinite() || !std::isfinite(r.w.torque[0] + r.w.torque[1] + r.w.torque[2])) {
        ++non_finite;
        continue;
      }
      max_force = std::max(max_force, f.norm());
      if (f.norm() > facts_.max_force + 1e-9) ++over;
      auto it = last_.find(r.w.session);
      if (it != last_.end()) {
        const tangent::wrench_t& p = it->second;
        const double dt = 1e-6 * static_cast<double>(r.w.server_utime - p.server_utime + 1);
        const double step = (f - Eigen::Vector3d(p.force[0], p.force[1], p.force[2])).norm();
        const double excess = step - facts_.max_force_rate * dt;
        worst_excess = std::max(worst_excess, excess);
        if (excess > 1e-9) ++steps;
      }
      last_[r.w.session] = r.w;
      // Timeout wrenches (state 2) repeat the last answer's seq by design; answers never do.
      if (r.w.state != 2 && ++answers[{r.w.session, r.w.seq}] == 2) ++twice;
    }
    std::printf(
        "[%s] %zu wrenches: %d non-finite, %d above %.2f N (max %.3f N), %d steps "
        "beyond the rate limit (worst margin %.3g N), %d states answered twice\n",
        what, all.size(), non_finite, over, facts_.max_force, max_force, steps, worst_excess,
        twice);
    EXPECT_EQ(non_finite, 0) << what;
    EXPECT_EQ(over, 0) << what;
    EXPECT_EQ(steps, 0) << what;
    EXPECT_EQ(twice, 0) << what;
    total_wrenches_ += static_cast<int64_t>(all.size());
    total_non_finite_ += non_finite;
    total_over_ += over + steps;
  }

  const SceneFacts& facts() const { return facts_; }
  void set_utime_offset(int64_t us) { utime_offset_ = us; }
  int64_t sent(int64_t of_session) { return seq_[of_session]; }
  /// Makes the next state of `of_session` skip `n` sequence numbers (never sent).
  void SkipSeq(int64_t of_session, int64_t n) { seq_[of_session] += n; }
  int64_t total_wrenches() const { return total_wrenches_; }
  int64_t total_bad() const { return total_non_finite_ + total_over_; }

  int baseline_contacts = -1;
  int64_t session = 0x5e55'1001;  ///< the served client's current session

 private:
  void OnWrench(const tangent::wrench_t& m) {
    std::lock_guard<std::mutex> l(mutex_);
    wrenches_.push_back({m, NowNs()});
  }
  void OnStats(const tangent::loop_stats_t& m) {
    const int64_t published = states_published_.load(std::memory_order_relaxed);
    std::lock_guard<std::mutex> l(mutex_);
    stats_.push_back({m, NowNs(), published});
  }

  SceneFacts facts_;
  std::string dir_, out_;
  pid_t pid_ = -1;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<tangent::server::LcmSubscriptions> subs_;
  std::thread rx_;
  int64_t last_send_ns_ = 0, max_gap_ns_ = 0;  // (the test thread's only)
  void NoteSend() {
    const int64_t now = NowNs();
    if (last_send_ns_ > 0) max_gap_ns_ = std::max(max_gap_ns_, now - last_send_ns_);
    last_send_ns_ = now;
  }
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<Received> wrenches_;
  /// A statistics message, when it arrived, and how many device states this client had
  /// published then (so a count of states sent matches the counters the message carries, up to
  /// the states in flight between its publication and its arrival, not the time the test
  /// thread took to look).
  struct StatsReceived {
    tangent::loop_stats_t m;
    int64_t at_ns;
    int64_t published;
  };
  std::vector<StatsReceived> stats_;
  std::atomic<int64_t> states_published_{0};
  std::map<int64_t, int64_t> seq_;
  std::map<int64_t, tangent::wrench_t> last_;
  int64_t utime_offset_ = 0;
  int64_t total_wrenches_ = 0, total_non_finite_ = 0, total_over_ = 0;
};

Harness* g_h = nullptr;

class ServerEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    g_h = new Harness;
    g_h->Start();
  }
  void TearDown() override {
    std::printf(
        "whole suite: %lld wrenches checked, %lld non-finite, over the limit or too "
        "steep\n",
        static_cast<long long>(g_h->total_wrenches()), static_cast<long long>(g_h->total_bad()));
    EXPECT_EQ(g_h->total_bad(), 0);
    g_h->Stop();
    delete g_h;
  }
};

/// The counters an attack may move, from two statistics messages.
struct Delta {
  int64_t accepted, sessions, undecodable, wrong_type, lost, non_finite, quaternion, workspace,
      device, session, sequence, jump, pending, resets, timeouts, faults, unanswered, wrenches;
  /// Device states published (every session) between the two snapshots' arrivals.
  int64_t published = 0;
  double client_pause_ms = 0.0;  ///< the client's longest pause between sends (Harness)
  int64_t timeout_wrenches = 0;  ///< timeout wrenches (state 2) received over the attack
  static Delta Of(const tangent::loop_stats_t& a, const tangent::loop_stats_t& b) {
    return {b.device_messages - a.device_messages,
            b.sessions - a.sessions,
            b.undecodable - a.undecodable,
            b.wrong_type - a.wrong_type,
            b.lost_before_filter - a.lost_before_filter,
            b.rejected_non_finite - a.rejected_non_finite,
            b.rejected_quaternion - a.rejected_quaternion,
            b.rejected_workspace - a.rejected_workspace,
            b.rejected_device - a.rejected_device,
            b.rejected_session - a.rejected_session,
            b.rejected_sequence - a.rejected_sequence,
            b.rejected_jump - a.rejected_jump,
            b.rejected_pending - a.rejected_pending,
            b.sequence_resets - a.sequence_resets,
            b.device_timeouts - a.device_timeouts,
            b.faults - a.faults,
            b.unanswered - a.unanswered,
            b.wrenches_sent - a.wrenches_sent};
  }
  void Print(const char* what) const {
    std::printf(
        "[%s] counters moved: accepted %lld, sessions %lld, undecodable %lld (wrong type "
        "%lld), lost %lld, non-finite %lld, quaternion %lld, workspace %lld, device %lld, "
        "stale session %lld, sequence %lld, jump %lld, pending %lld, seq resets %lld, "
        "timeouts %lld, faults %lld, unanswered %lld, wrenches %lld\n",
        what, L(accepted), L(sessions), L(undecodable), L(wrong_type), L(lost), L(non_finite),
        L(quaternion), L(workspace), L(device), L(session), L(sequence), L(jump), L(pending),
        L(resets), L(timeouts), L(faults), L(unanswered), L(wrenches));
  }
  static long long L(int64_t x) { return static_cast<long long>(x); }
};

/// Runs an attack between two statistics snapshots, then settles with normal states and checks
/// the wrenches, the constraints and the contacts. Returns the counters' movement.
Delta Attack(const char* what, const std::function<void()>& attack, double settle_s = 0.6) {
  Harness& h = *g_h;
  int64_t published_before = 0, published_after = 0;
  const tangent::loop_stats_t before = h.FreshStats(&published_before);
  const size_t from = h.WrenchCount();
  h.ResetGap();
  attack();
  const int64_t settle_start = NowNs();
  h.Hold(h.session, settle_s);
  const tangent::loop_stats_t after = h.FreshStats(&published_after);
  h.CheckWrenches(from, what);
  // The constraints over the last part of the settle (after the scene has caught up).
  const auto [violation, contacts] =
      h.ViolationSince(settle_start + static_cast<int64_t>(0.5 * settle_s * 1e9));
  std::printf(
      "[%s] after: violation %.1e (window max), contacts %d (before the attacks %d), "
      "faults %lld\n",
      what, violation, contacts, h.baseline_contacts, static_cast<long long>(after.faults));
  EXPECT_LE(violation, 1e-6) << what;
  EXPECT_EQ(contacts, h.baseline_contacts) << what;
  EXPECT_EQ(after.faults, 0) << what << ": the filter let a state through that broke a tick";
  Delta d = Delta::Of(before, after);
  d.published = published_after - published_before;
  d.client_pause_ms = 1e-6 * static_cast<double>(h.max_gap_ns());
  for (const Received& r : h.WrenchesSince(from)) d.timeout_wrenches += r.w.state == 2;
  d.Print(what);
  if (d.timeouts > 0) {
    std::printf("[%s] the client itself paused up to %.1f ms (%lld timeout wrenches received)\n",
                what, d.client_pause_ms, static_cast<long long>(d.timeout_wrenches));
  }
  return d;
}

/// Every other rejection counter unmoved, nothing lost, no session change.
void ExpectOnly(const Delta& d, int64_t non_finite, int64_t quaternion, int64_t workspace,
                int64_t sequence, int64_t jump, bool may_lose = false) {
  EXPECT_EQ(d.non_finite, non_finite);
  EXPECT_EQ(d.quaternion, quaternion);
  EXPECT_EQ(d.workspace, workspace);
  EXPECT_EQ(d.sequence, sequence);
  EXPECT_EQ(d.jump, jump);
  EXPECT_EQ(d.device, 0);
  EXPECT_EQ(d.session, 0);
  EXPECT_EQ(d.sessions, 0);
  EXPECT_EQ(d.pending, 0);
  EXPECT_EQ(d.resets, 0);
  if (!may_lose) {
    EXPECT_EQ(d.lost, 0);
  }
  // No device timeout while the client kept sending. A client descheduled for half the
  // timeout or more (a busy machine: CI saw one such pause) may leave the server silent for
  // the whole timeout, and then a timeout, its force ramped to zero, is the right answer.
  if (d.client_pause_ms < 0.5 * 1e3 * kDeviceTimeout) {
    EXPECT_EQ(d.timeouts, 0) << "with the client's longest pause " << d.client_pause_ms << " ms";
  }
}

/// For 1 s at 1 kHz, every `every`-th state of the served client is corrupted by `corrupt(k, m)`
/// in place of a good one; returns the counters' movement and sets *injected.
Delta Corrupted(const char* what, int every,
                const std::function<void(int64_t, tangent::device_state_t*)>& corrupt,
                int64_t* injected) {
  Harness& h = *g_h;
  *injected = 0;
  return Attack(what, [&] {
    h.Drive(1.0, 1000.0, [&](int64_t k) {
      tangent::device_state_t m = h.State(h.session, h.facts().pull);
      if (k % every == every / 2) {
        corrupt(k, &m);
        ++*injected;
      }
      h.Publish(m);
    });
  });
}

// Issue 39: without a declared device the first device id heard owned the server, and the real
// device got 0 of 3001 answers. The server serves the device its scene names (or --device-id);
// a stray device speaking first, and on throughout, claims nothing. (First: the server has
// heard no one yet.)
TEST(Adversary, A00a_AStrayDeviceSpeakingFirstClaimsNothing) {
  Harness& h = *g_h;
  const int64_t stray_session = 0x5e55'0bad;
  int64_t stray = 0, real = 0;
  const size_t from = h.WrenchCount();
  h.Drive(0.5, 1000.0, [&](int64_t) {  // the stray alone
    h.Publish(h.State(stray_session, h.facts().pull, /*device=*/2));
    ++stray;
  });
  h.Drive(3.0, 1000.0, [&](int64_t) {  // the real device, the stray still talking
    h.Publish(h.State(h.session, h.facts().pull));
    ++real;
    h.Publish(h.State(stray_session, h.facts().pull, 2));
    ++stray;
  });
  const tangent::loop_stats_t s = h.FreshStats();  // (more of the real device's states)
  h.CheckWrenches(from, "stray device first");
  const int64_t real_sent = h.sent(h.session);
  int64_t answered = 0, to_stray = 0;
  for (const Received& r : h.WrenchesSince(from)) {
    answered += r.w.session == h.session && r.w.state != 2;
    to_stray += r.w.device_id == 2;
  }
  std::printf(
      "[stray device first] stray: %lld states, rejected_device %lld; real device: %lld states, "
      "accepted %lld (%.2f %%), earning %lld, answers %lld (%.2f %%, reported), sessions %lld\n",
      static_cast<long long>(stray), static_cast<long long>(s.rejected_device),
      static_cast<long long>(real_sent), static_cast<long long>(s.device_messages),
      100.0 * static_cast<double>(s.device_messages) / static_cast<double>(real_sent),
      static_cast<long long>(s.rejected_pending), static_cast<long long>(answered),
      100.0 * static_cast<double>(answered) / static_cast<double>(real_sent),
      static_cast<long long>(s.sessions));
  // The stray never claims the server and is never answered; every state of the real device
  // that reached the server was accepted but those that earned the device (19; more when a
  // pause broke the streak). What fraction of the real device's states was served depends on
  // how many reached the server, which a loaded machine decides (UDP drops): reported above,
  // 99.4 % on a quiet machine (docs/server.md); the rule itself is DeviceFilterTest's.
  EXPECT_GE(s.rejected_device, 1);
  EXPECT_LE(s.rejected_device, stray);
  EXPECT_EQ(to_stray, 0);
  EXPECT_EQ(s.sessions, 1);
  EXPECT_GE(s.rejected_pending, 19);
  EXPECT_EQ(s.rejected_non_finite + s.rejected_quaternion + s.rejected_workspace +
                s.rejected_session + s.rejected_sequence + s.rejected_jump,
            0);
  EXPECT_LE(s.device_messages + s.rejected_pending, real_sent);
  EXPECT_GE(answered, 1);
}

TEST(Adversary, A00b_BaselineClientIsServed) {
  Harness& h = *g_h;
  const size_t from = h.WrenchCount();
  h.ResetGap();
  h.Hold(h.session, 2.0);  // past the 1 s ramp
  const tangent::loop_stats_t s = h.FreshStats();
  // (Set first: the attacks below compare against it whatever happens here.)
  h.baseline_contacts = s.num_contacts;
  h.CheckWrenches(from, "baseline");
  const std::vector<Received> w = h.WrenchesSince(from);
  // 2000 states sent over 2 s: how many were answered is the machine's (reported; the rate
  // benchmarks judge it); that the client is served, at full force once the ramp is over, is not.
  const double pause_ms = 1e-6 * static_cast<double>(h.max_gap_ns());
  std::printf("[baseline] the client's longest pause between states: %.1f ms\n", pause_ms);
  ASSERT_FALSE(w.empty());
  const Eigen::Vector3d f(w.back().w.force[0], w.back().w.force[1], w.back().w.force[2]);
  std::printf(
      "[baseline] %zu answers to %lld states (reported), |F| %.3f N, contacts %d, "
      "violation %.1e\n",
      w.size(), static_cast<long long>(h.sent(h.session)), f.norm(), s.num_contacts,
      s.max_violation);
  // The parts resist the pull: the hand feels it once the ramp is done. (Two CI runs found the
  // paperclip chain come apart here, 0 N and no contacts: its hooks rest touching unloaded, and
  // the first solve's Newton step, with no contact curvature, turned clip 1 into the other
  // wire. The solver now estimates such contacts' multipliers first: ServoTest's
  // ThePaperclipChainPulledFromRestHolds.)
  EXPECT_GT(f.norm(), 0.3);
  EXPECT_EQ(w.back().w.state, 0);
  EXPECT_EQ(s.sessions, 1);
  EXPECT_LE(s.max_violation, 1e-6);
  EXPECT_GE(h.baseline_contacts, 1);
}

TEST(Adversary, A01_UndecodableAndWrongTypePackets) {
  Harness& h = *g_h;
  std::mt19937 rng(12);
  int64_t garbage = 0, wrong = 0;
  const Delta d = Attack("garbage packets", [&] {
    h.Drive(1.0, 1000.0, [&](int64_t k) {
      h.Publish(h.State(h.session, h.facts().pull));
      if (k % 10 == 0) {  // random bytes, 0 to 200 of them
        std::vector<uint8_t> bytes(std::uniform_int_distribution<size_t>(0, 200)(rng));
        for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng());
        h.PublishRaw(bytes.data(), bytes.size());
        ++garbage;
      } else if (k % 10 == 5) {  // another Tangent message on the device channel
        tangent::wrench_t w{};
        w.frame = "device";
        std::vector<uint8_t> buffer(static_cast<size_t>(w.getEncodedSize()));
        w.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
        h.PublishRaw(buffer.data(), buffer.size());
        ++wrong;
      }
    });
  });
  EXPECT_EQ(d.undecodable, garbage + wrong);
  EXPECT_EQ(d.wrong_type, wrong);
  ExpectOnly(d, 0, 0, 0, 0, 0);
}

TEST(Adversary, A02_NonFiniteFields) {
  int64_t injected = 0;
  const Delta d = Corrupted(
      "non-finite fields", 10,
      [](int64_t k, tangent::device_state_t* m) {
        const double bad[] = {NAN, INFINITY, -INFINITY};
        const double x = bad[(k / 10) % 3];
        switch ((k / 30) % 3) {
          case 0:
            m->position[k % 3] = x;
            break;
          case 1:
            m->orientation[k % 4] = x;
            break;
          case 2:
            m->velocity[k % 3] = x;
            break;
        }
      },
      &injected);
  ExpectOnly(d, injected, 0, 0, 0, 0);
}

TEST(Adversary, A03_NonUnitQuaternions) {
  int64_t injected = 0;
  const Delta d = Corrupted(
      "non-unit quaternions", 10,
      [](int64_t k, tangent::device_state_t* m) {
        const double scale[] = {0.0, 0.5, 1.01, 1e300};
        for (double& q : m->orientation) q *= scale[(k / 10) % 4];
      },
      &injected);
  ExpectOnly(d, 0, injected, 0, 0, 0);
}

TEST(Adversary, A04_RepeatedAndStaleSequenceNumbers) {
  Harness& h = *g_h;
  int64_t injected = 0;
  const Delta d = Attack("repeated and stale seq", [&] {
    h.Drive(1.0, 1000.0, [&](int64_t k) {
      tangent::device_state_t m = h.State(h.session, h.facts().pull);
      h.Publish(m);
      if (k % 10 == 6) {  // the same state again, or one from 5 states ago
        if ((k / 10) % 2) m.seq -= 5;
        h.Publish(m);
        ++injected;
      }
    });
    // A jump of 1e6 in seq (issue 39: it counted 1,002,001 states lost): a reset.
    h.SkipSeq(h.session, 1'000'000);
  });
  Delta e = d;
  e.resets = 0;
  ExpectOnly(e, 0, 0, 0, injected, 0);
  EXPECT_EQ(d.resets, 1);
}

TEST(Adversary, A05_HugeAndFarPositions) {
  int64_t injected = 0;
  const Delta d = Corrupted(
      "huge and far positions", 10,
      [](int64_t k, tangent::device_state_t* m) {
        const double far[] = {1e308, -1e308, 1e9, -1e9, 1.0, 0.5};
        m->position[k % 3] = far[(k / 10) % 6];
      },
      &injected);
  ExpectOnly(d, 0, 0, injected, 0, 0);
}

TEST(Adversary, A06_ASessionOpeningFarAwayIsRejectedThenServed) {
  Harness& h = *g_h;
  const int64_t old_session = h.session;
  const int64_t fresh = 0x5e55'2002;
  size_t takeover_index = 0;
  int64_t stale = 0;
  const Delta d = Attack("new session opening at 1e308 m", [&] {
    tangent::device_state_t m = h.State(fresh, h.facts().pull);
    m.position[0] = 1e308;
    h.Publish(m);  // the first state of the new session: rejected, no takeover
    h.Drive(0.2, 1000.0, [&](int64_t) { h.Publish(h.State(old_session, h.facts().pull)); });
    takeover_index = h.WrenchCount();
    h.session = fresh;
    bool answered = false;
    h.Drive(1.5, 1000.0, [&](int64_t k) {
      h.Publish(h.State(fresh, h.facts().pull));
      // The old client, still talking once the new one is served: stale. (Before that it is
      // still the owner: the new session earns the device in 20 steady states.)
      answered = answered || h.Answered(fresh, takeover_index);
      if (answered && k % 50 == 0) {
        h.Publish(h.State(old_session, h.facts().pull));
        ++stale;
      }
    });
  });
  EXPECT_EQ(d.workspace, 1);
  EXPECT_EQ(d.sessions, 1);
  EXPECT_EQ(d.session, stale);
  EXPECT_GE(stale, 1);
  EXPECT_GE(d.pending, 19);  // (more when a pause of the client broke the streak)
  EXPECT_EQ(d.lost, 0);
  // The new session's first answer starts from zero force and ramps.
  const std::vector<Received> w = h.WrenchesSince(takeover_index);
  const Received* first = nullptr;
  for (const Received& r : w) {
    if (r.w.session == fresh) {
      first = &r;
      break;
    }
  }
  ASSERT_NE(first, nullptr);
  // Seq 1 was the far one, 2..20 earned the device; the first answer is to seq 21, or to a later
  // one when the servo's tick found a newer state in the mailbox (the machine's timing).
  EXPECT_GE(first->w.seq, 21);
  EXPECT_EQ(first->w.state, 1);
  EXPECT_EQ(Eigen::Vector3d(first->w.force[0], first->w.force[1], first->w.force[2]).norm(), 0.0);
  int after_takeover_old = 0;
  for (const Received& r : w) {
    if (r.at_ns > first->at_ns + 5'000'000 && r.w.session == old_session) ++after_takeover_old;
  }
  EXPECT_EQ(after_takeover_old, 0) << "the old session was answered after the takeover";
}

TEST(Adversary, A07_SingleSampleGlitches) {
  int64_t injected = 0;
  const Delta d = Corrupted(
      "single-sample 3 cm glitches", 20,
      [](int64_t, tangent::device_state_t* m) { m->position[1] += 0.03; },  // 30 m/s, inside
      &injected);
  // At the device's 1 ms period each glitch is refused once (DeviceFilterTest's
  // ASingleSampleGlitchIsRefusedOnceAtTheDeviceRate, on an exact clock). Here the filter judges
  // on the bridge's clock when it handles each state: a bridge or client descheduled for 6 ms
  // before a glitch makes it plausible (3 cm at 5 m/s), and then the return to the hand is the
  // refused jump, for up to 6 ms of states. So the count equals the glitches on a machine that
  // kept the period (reported), and on any machine the glitches are refused as jumps and as
  // nothing else, with every wrench within the limits (CheckWrenches).
  std::printf(
      "[single-sample 3 cm glitches] %lld refused as jumps for %lld glitches (equal when "
      "client and bridge kept the 1 ms period; the client's longest pause %.1f ms)\n",
      static_cast<long long>(d.jump), static_cast<long long>(injected), d.client_pause_ms);
  EXPECT_GE(d.jump, 1);
  ExpectOnly(d, 0, 0, 0, 0, d.jump);
}

TEST(Adversary, A08_SustainedJumpsAreFollowedAtBoundedSpeed) {
  Harness& h = *g_h;
  const Eigen::Vector3d pull = h.facts().pull;
  const Eigen::Vector3d jumped = pull + h.facts().jump;  // inside the workspace
  const Delta d = Attack(
      "jumps (6 cm held, back, 1 m held)",
      [&] {
        h.Drive(1.0, 1000.0, [&](int64_t) { h.Publish(h.State(h.session, jumped)); });
        h.Drive(1.0, 1000.0, [&](int64_t) { h.Publish(h.State(h.session, pull)); });
        h.Drive(0.3, 1000.0, [&](int64_t) {
          h.Publish(h.State(h.session, pull + Eigen::Vector3d(0, 1.0, 0)));  // outside: 1 m
        });
      },
      1.5);
  // A held jump is refused for d / (5 m/s) = 12 ms on the server's clock and then followed at
  // 1 m/s (the force, not the scene, jumps toward the hand; CheckWrenches held it to the rate
  // limit). At 1 kHz that is about 11 refusals per jump, 22 for both; a client that stalls
  // during the refusal window (a busy machine: CI saw 9 with one timeout) sends fewer samples
  // inside it, so the count is bounded below only by one refusal per jump. The exact timing is
  // DeviceFilterTest's (on a simulated clock, with the window's exact length); here, on real
  // LCM, each jump must be refused at least once. How many states fall in each window depends
  // on when the bridge handled them (a stalled bridge handles a burst at one instant): reported.
  std::printf("[jumps] %lld refusals for the two held jumps (about 11 each at the device rate)\n",
              static_cast<long long>(d.jump));
  EXPECT_GE(d.jump, 2);
  EXPECT_EQ(d.workspace, 300);
  EXPECT_EQ(d.lost, 0);
  EXPECT_EQ(d.sessions, 0);
}

TEST(Adversary, A09_ClientClockJumps) {
  Harness& h = *g_h;
  const Delta d = Attack("client clock jumps of +-1 s", [&] {
    // 8 mm further (below the jump filter's 1 cm): the force saturates and comes back.
    const Eigen::Vector3d far = h.facts().pull + Eigen::Vector3d(0, 0.008, 0);
    h.Drive(1.0, 1000.0, [&](int64_t k) {
      h.set_utime_offset(((k / 100) % 3 - 1) * 1'000'000);  // −1 s, 0, +1 s in turn
      h.Publish(h.State(h.session, (k / 100) % 2 ? far : h.facts().pull));
    });
    h.set_utime_offset(0);
  });
  ExpectOnly(d, 0, 0, 0, 0, 0);
}

TEST(Adversary, A10_DropoutAndReturn) {
  Harness& h = *g_h;
  const size_t from = h.WrenchCount();
  const Delta d = Attack(
      "dropout of 0.5 s and return", [&] { usleep(500000); }, 1.5);
  EXPECT_EQ(d.timeouts, 1);
  EXPECT_EQ(d.lost, 0);
  const std::vector<Received> w = h.WrenchesSince(from);
  // During the silence the server sends timeout wrenches (state 2), one per device period while
  // its servo runs (how many is the machine's: reported), and their force only falls; after the
  // return the answers ramp up (state 1), and are at full force again within the settle (1.5 s,
  // the ramp being 1 s on the server's clock).
  int timeout_wrenches = 0, ramping_after = 0, rises = 0;
  double last_timeout_force = std::numeric_limits<double>::infinity();
  for (const Received& r : w) {
    const double f = Eigen::Vector3d(r.w.force[0], r.w.force[1], r.w.force[2]).norm();
    if (r.w.state == 2) {
      ++timeout_wrenches;
      rises += f > last_timeout_force + 1e-12;  // (rounding of the ramp's scaling: far below)
      last_timeout_force = f;
    }
    ramping_after += r.w.state == 1;
  }
  std::printf(
      "[dropout] %d timeout wrenches (state 2, reported), %d of them raised the force, "
      "%d ramping answers after the return (reported)\n",
      timeout_wrenches, rises, ramping_after);
  EXPECT_GE(timeout_wrenches, 1);
  EXPECT_EQ(rises, 0);
  EXPECT_GE(ramping_after, 1);
  EXPECT_EQ(w.back().w.state, 0);
}

TEST(Adversary, A11_ClientRestartIsServedWithinOneRamp) {
  Harness& h = *g_h;
  const int64_t old_session = h.session;
  const int64_t restarted = 0x5e55'3003;
  int64_t stale_after = 0, old_before = 0;
  int64_t restart_ns = 0;
  size_t from = 0;
  const Delta d = Attack("client restart (seq from 1)", [&] {
    from = h.WrenchCount();
    restart_ns = NowNs();
    h.session = restarted;
    bool answered = false;
    h.Drive(1.2, 1000.0, [&](int64_t k) {
      h.Publish(h.State(restarted, h.facts().pull));
      answered = answered || h.Answered(restarted, from);
      if (k < 200 && k % 2 == 0) {  // the old process's last states, still in flight
        h.Publish(h.State(old_session, h.facts().pull));
        ++(answered ? stale_after : old_before);
      }
    });
  });
  EXPECT_EQ(d.sessions, 1);
  // The old process is served until the restarted one has earned the device (20 steady
  // states), stale from then on: its states sent once the new one was answered are all stale.
  EXPECT_GE(d.session, stale_after);
  EXPECT_LE(d.session, stale_after + old_before);
  EXPECT_GE(d.pending, 19);
  int64_t first_ns = 0;
  for (const Received& r : h.WrenchesSince(from)) {
    if (r.w.session == restarted) {
      first_ns = r.at_ns;
      break;
    }
  }
  ASSERT_GT(first_ns, 0);
  std::printf(
      "[restart] first answer %.2f ms after the restart (20 states earn the device); the old "
      "process: %lld states before it, %lld after\n",
      1e-6 * static_cast<double>(first_ns - restart_ns), static_cast<long long>(old_before),
      static_cast<long long>(stale_after));
  EXPECT_LE(first_ns - restart_ns, 1'000'000'000);  // within one ramp time
}

TEST(Adversary, A12_TwoCompetingClientsOfOneDevice) {
  Harness& h = *g_h;
  const int64_t a = h.session, b = 0x5e55'4004;
  int64_t a_after = 0, a_earning = 0;
  size_t from = 0;
  const Delta d = Attack("two clients of one device, interleaved", [&] {
    h.Drive(0.2, 1000.0, [&](int64_t) { h.Publish(h.State(a, h.facts().pull)); });
    from = h.WrenchCount();
    h.session = b;
    bool answered = false;
    h.Drive(1.0, 1000.0, [&](int64_t) {
      h.Publish(h.State(b, h.facts().pull));
      answered = answered || h.Answered(b, from);
      h.Publish(h.State(a, h.facts().pull + Eigen::Vector3d(0, 0.005, 0)));
      ++(answered ? a_after : a_earning);
    });
  });
  // The newer earns the device (20 steady states) and keeps it: the older is stale from then
  // on, and cannot take it back while the newer is live (no chatter).
  EXPECT_EQ(d.sessions, 1);
  EXPECT_GE(d.session, a_after);
  EXPECT_LE(d.session, a_after + a_earning);
  // Answers go out in the order of the ticks that computed them, and LCM on loopback keeps it:
  // once the newer session is answered, the older one never is again. (Before that, the older
  // client's states still queued at the takeover may be answered: as many as the bridge had
  // waiting, which the machine decides; reported.)
  int a_before = 0, a_after_b = 0;
  bool b_answered = false;
  for (const Received& r : h.WrenchesSince(from)) {
    if (r.w.state == 2) continue;  // timeout wrenches answer no state
    b_answered = b_answered || r.w.session == b;
    if (r.w.session == a) ++(b_answered ? a_after_b : a_before);
  }
  std::printf(
      "[two clients] the older session answered %d times before the newer's first "
      "answer, %d after it\n",
      a_before, a_after_b);
  EXPECT_TRUE(b_answered);
  EXPECT_EQ(a_after_b, 0);
}

TEST(Adversary, A13_AnotherDeviceIsNeverServed) {
  Harness& h = *g_h;
  const int64_t intruder = 0x5e55'5005;
  int64_t sent = 0;
  size_t from = 0;
  const Delta d = Attack("another device id, interleaved", [&] {
    from = h.WrenchCount();
    h.Drive(1.0, 1000.0, [&](int64_t) {
      h.Publish(h.State(h.session, h.facts().pull));
      h.Publish(h.State(intruder, Eigen::Vector3d(0, 0.01, 0), /*device=*/2));
      ++sent;
    });
  });
  EXPECT_EQ(d.device, sent);
  EXPECT_EQ(d.sessions, 0);
  for (const Received& r : h.WrenchesSince(from)) EXPECT_NE(r.w.device_id, 2);
}

void Flood(double rate_hz, const char* what) {
  Harness& h = *g_h;
  int64_t flood = 0;
  const int64_t t0 = NowNs();
  double seconds = 0.0;
  const Delta d = Attack(what, [&] {
    h.Drive(g_flood_seconds, rate_hz, [&](int64_t k) {
      // The hand keeps moving (±1 mm at 2 Hz) so every state is a new, valid one.
      const double y = 1e-3 * std::sin(2 * M_PI * 2.0 * static_cast<double>(k) / rate_hz);
      h.Publish(h.State(h.session, h.facts().pull + Eigen::Vector3d(0, y, 0)));
      ++flood;
    });
    seconds = 1e-9 * static_cast<double>(NowNs() - t0);
  });
  // Accounting over the attack and its settle, up to the states in flight between each
  // snapshot's publication and its arrival here (the client keeps sending meanwhile): every
  // state sent was accepted or counted lost (a gap in seq); every accepted state was answered
  // or counted unanswered (CheckWrenches: none answered twice).
  const int64_t sent = d.published;
  std::printf(
      "[%s] %lld states in %.2f s (%.0f per second), %lld in all with the settle; "
      "accepted %lld, lost %lld, answered %lld, unanswered %lld\n",
      what, static_cast<long long>(flood), seconds, static_cast<double>(flood) / seconds,
      static_cast<long long>(sent), static_cast<long long>(d.accepted),
      static_cast<long long>(d.lost), static_cast<long long>(d.wrenches),
      static_cast<long long>(d.unanswered));
  EXPECT_NEAR(static_cast<double>(d.accepted + d.lost), static_cast<double>(sent), 10.0);
  // (Timeout wrenches answer no state: not counted.) The bridge counts a state accepted when it
  // passes the filter, the servo answered or unanswered when a tick takes it, so the counters
  // differ by the states in flight when each snapshot is taken: ±2 normally, more when the
  // servo was descheduled then (CI: 12 at the second snapshot; 3 at the first on a machine
  // running a second test suite). Both snapshots are taken while the client holds at 1 kHz
  // (FreshStats, the settle): fewer than a device timeout's worth of those states can be in
  // flight without a timeout, and none may be answered twice.
  const double handled = static_cast<double>(d.wrenches - d.timeout_wrenches + d.unanswered);
  EXPECT_LE(handled, static_cast<double>(d.accepted) + 2.0 + 1e3 * kDeviceTimeout);
  EXPECT_GE(handled, static_cast<double>(d.accepted) - 2.0 - 1e3 * kDeviceTimeout);
  // Still serving through the flood: states sent in its last second were answered (how many
  // is the machine's: reported, with the answers counted above).
  int64_t answered_late = 0;
  const int64_t flood_end = t0 + static_cast<int64_t>(seconds * 1e9);
  for (const Received& r : g_h->WrenchesSince(0)) {
    answered_late += r.w.state != 2 && r.w.session == h.session &&
                     r.at_ns > flood_end - 1'000'000'000 && r.at_ns <= flood_end;
  }
  std::printf("[%s] answers received in the flood's last second: %lld (reported)\n", what,
              static_cast<long long>(answered_late));
  EXPECT_GE(answered_late, 1);
  ExpectOnly(d, 0, 0, 0, 0, 0, /*may_lose=*/true);
}

TEST(Adversary, A14_Flood10xTheDeviceRate) { Flood(10000.0, "flood 10 kHz"); }
TEST(Adversary, A15_Flood100xTheDeviceRate) { Flood(100000.0, "flood 100 kHz"); }

// Issue 39: a client that started a new session every millisecond, each 10 cm from the hand,
// took over 254 times in 4 s, stepped the force by 1.37 N and left the real client stale. Now
// no session of the burst earns the device: the real client is served throughout.
TEST(Adversary, A16_ABurstOfNewSessions) {
  Harness& h = *g_h;
  int64_t burst = 0, owner = 0;
  int64_t burst_end = 0;
  size_t from = 0;
  // 10 cm from the hand, inside the workspace box (towards −x, −z).
  const Eigen::Vector3d away = h.facts().pull + Eigen::Vector3d(-0.09, 0.0, -0.0436);
  const Delta d = Attack("a new session every ms, 10 cm away", [&] {
    from = h.WrenchCount();
    h.Drive(g_flood_seconds, 1000.0, [&](int64_t k) {
      h.Publish(h.State(h.session, h.facts().pull));
      ++owner;
      h.Publish(h.State(0x5e55'6000'0000 + k, away));
      ++burst;
    });
    burst_end = NowNs();
  });
  const std::optional<Received> next = h.FirstAnswerAfter(h.session, burst_end);
  ASSERT_TRUE(next.has_value());
  int64_t owner_answers = 0;
  for (const Received& r : h.WrenchesSince(from)) {
    owner_answers += r.w.session == h.session && r.w.state != 2 && r.at_ns <= burst_end;
  }
  std::printf(
      "[burst of sessions] %lld one-state sessions 10 cm away: jump %lld, pending %lld, "
      "workspace %lld, sessions %lld; the owner's %lld states answered %lld times (reported), "
      "next answer %.2f ms after the burst\n",
      static_cast<long long>(burst), static_cast<long long>(d.jump),
      static_cast<long long>(d.pending), static_cast<long long>(d.workspace),
      static_cast<long long>(d.sessions), static_cast<long long>(owner),
      static_cast<long long>(owner_answers), 1e-6 * static_cast<double>(next->at_ns - burst_end));
  // Every state of the burst that reached the server refused (as a jump from the grasp point;
  // as earning, or outside the workspace, on a scene whose box or timing makes it so; a loaded
  // machine drops some on the way, and a new session has no sequence to count them by), and
  // nothing else refused.
  EXPECT_GE(d.jump + d.pending + d.workspace, 1);
  EXPECT_LE(d.jump + d.pending + d.workspace, burst);
  EXPECT_EQ(d.sessions, 0);
  EXPECT_EQ(d.non_finite + d.quaternion + d.device + d.session + d.sequence, 0);
  EXPECT_LE(next->at_ns - burst_end, 500'000'000);  // issue 39: served again within 0.5 s
}

// Issue 39: after a takeover by B and B's silence, the first client A was never served again
// until it restarted. A silent owner loses the device after the timeout; A takes it back.
TEST(Adversary, A17_ASilentOwnerLosesTheDevice) {
  Harness& h = *g_h;
  const int64_t a = h.session, b = 0x5e55'7007;
  int64_t b_last_ns = 0;
  size_t from = 0;
  double a_pause_ms = 0.0;
  const Delta d = Attack("the owner goes silent, the previous session takes it back", [&] {
    from = h.WrenchCount();
    h.session = b;
    h.Drive(1.0, 1000.0, [&](int64_t) {  // B earns the device; A keeps sending (stale)
      h.Publish(h.State(b, h.facts().pull));
      h.Publish(h.State(a, h.facts().pull));
    });
    b_last_ns = NowNs();
    h.session = a;  // B is silent from now on
    h.ResetGap();
    h.Hold(a, 0.3);
    a_pause_ms = 1e-6 * static_cast<double>(h.max_gap_ns());
  });
  EXPECT_EQ(d.sessions, 2);
  EXPECT_GE(d.session, 1);
  const std::optional<Received> back = h.FirstAnswerAfter(a, b_last_ns);
  ASSERT_TRUE(back.has_value());
  const double after_ms = 1e-6 * static_cast<double>(back->at_ns - b_last_ns);
  std::printf(
      "[silent owner] A served again %.1f ms after B's last state (bound: timeout %.0f ms + "
      "100 ms; A's longest pause %.1f ms)\n",
      after_ms, 1e3 * kDeviceTimeout, a_pause_ms);
  // The protocol's bound is the timeout, then 20 states at the device rate: 120 ms on a quiet
  // machine (reported; asserted exactly on a simulated clock by DeviceFilterTest's
  // ASilentOwnerLosesTheDeviceAndThePreviousSessionTakesItBack). Over real LCM the filter judges
  // on the bridge's receipt clock, which a loaded machine delays: asserted here is that A is
  // served again within the attack (0.3 s), with a fresh ramp.
  EXPECT_LE(after_ms, 300.0);
  EXPECT_EQ(back->w.state, 1);  // a fresh ramp
  EXPECT_EQ(Eigen::Vector3d(back->w.force[0], back->w.force[1], back->w.force[2]).norm(), 0.0);
}

TEST(Adversary, A18_StillServingNormally) {
  Harness& h = *g_h;
  const size_t from = h.WrenchCount();
  const Delta d = Attack("normal use after everything", [&] { h.Hold(h.session, 1.0); });
  ExpectOnly(d, 0, 0, 0, 0, 0);
  // Served, at full force (how many answers is the machine's: printed by CheckWrenches).
  const std::vector<Received> w = h.WrenchesSince(from);
  ASSERT_FALSE(w.empty());
  EXPECT_EQ(w.back().w.state, 0);
  EXPECT_EQ(w.back().w.session, h.session);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--tangentd") g_tangentd = argv[i + 1];
    if (std::string(argv[i]) == "--scene") g_scene = argv[i + 1];
    if (std::string(argv[i]) == "--flood-seconds") {
      char* end = nullptr;
      g_flood_seconds = std::strtod(argv[i + 1], &end);
      // At least 1 s: the checks look at the flood's last second.
      if (*end != '\0' || !(g_flood_seconds >= 1.0 && g_flood_seconds <= 600.0)) {
        std::fprintf(stderr, "adversary_test: --flood-seconds '%s' is not a number in [1, 600]\n",
                     argv[i + 1]);
        return 2;
      }
    }
  }
  if (g_tangentd.empty() || g_scene.empty()) {
    std::fprintf(stderr,
                 "usage: adversary_test --tangentd PATH --scene FILE.json [--flood-seconds S]\n");
    return 2;
  }
  ::testing::AddGlobalTestEnvironment(new ServerEnvironment);
  return RUN_ALL_TESTS();
}
