// tangent-view: a live 3D view of a Tangent scene in the browser. Subscribes to the server's
// scene, contact, wrench, device and statistics channels over LCM (or replays an lcm-logger
// log), and serves the page (three.js, from npm) and its WebSocket over HTTP. docs/viewer.md.

#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "server/bridge.h"
#include "server/lcm_subscriptions.h"
#include "view/display.h"
#include "view/model.h"
#include "view/protocol.h"
#include "view/timeline.h"
#include "view/web_server.h"

#ifndef TANGENT_VIEW_WEB_ROOT
#define TANGENT_VIEW_WEB_ROOT "view/web"
#endif

namespace tangent::view {
namespace {

using nlohmann::json;
using ClientId = WebServer::ClientId;

struct Options {
  std::string scene, lcm_url = server::kDefaultViewLcmUrl, web_root = TANGENT_VIEW_WEB_ROOT;
  std::string bind = "127.0.0.1", log, chromium = "chromium";
  int port = 8737;
  double fps = 30.0, tolerance = 0.0, timeout = 60.0;
  std::vector<std::string> snapshots;
  std::vector<double> at;
  std::vector<double> camera;  ///< eye then target, metres (6 numbers), or empty
  int width = 960, height = 640;
  bool open_browser = false, headless_browser = false;
  std::string priority = "idle";
  int avoid_cpu = 0;  ///< tangentd's default --servo-cpu
};

/// A browser connected to the view.
struct Client {
  uint64_t sent_version = 0;
  int64_t dropped_frames = 0;  ///< frames skipped because the socket was still busy
};

/// A frame is skipped for a client whose socket still holds this much unsent data: a slow or
/// stalled browser then costs no memory growth and no time here (the next frame is newer).
constexpr size_t kMaxBuffered = 4u << 20;

class ViewServer {
 public:
  ViewServer(const Options& o, const server::Scene& scene, std::vector<DisplayMesh> meshes,
             const Timeline* timeline)
      : o_(o),
        scene_(scene),
        meshes_(std::move(meshes)),
        model_(scene),
        timeline_(timeline),
        web_(o.web_root, kMaxClientMessageBytes,
             {[this](ClientId c) { OnOpen(c); }, [this](ClientId c) { OnClose(c); },
              [this](ClientId c, const std::string& text) { OnMessage(c, text); }}) {
    for (const DisplayMesh& m : meshes_) mesh_text_[m.hash] = MeshMessage(m).dump();
    if (o.camera.size() == 6) {
      camera_ = {{"position", {o.camera[0], o.camera[1], o.camera[2]}},
                 {"target", {o.camera[3], o.camera[4], o.camera[5]}},
                 {"fixed", true}};
    }
    if (timeline_) SeekTo(SnapshotTime(0));
  }

  /// Serves until SIGINT/SIGTERM, or until every snapshot is written. @return the exit code.
  int Run() {
    std::string error;
    const int port = web_.Listen(o_.bind, o_.port, &error);
    if (port < 0) return Fail(error);
    url_ = "http://" + o_.bind + ":" + std::to_string(port) + "/";
    std::printf("tangent-view: %s (scene \"%s\", %zu surfaces, %s)\n", url_.c_str(),
                scene_.name.c_str(), meshes_.size(),
                timeline_ ? ("replaying " + o_.log).c_str() : ("live on " + o_.lcm_url).c_str());
    std::fflush(stdout);
    if (!timeline_) {
      try {
        lcm_ = server::OpenLcm(o_.lcm_url);
      } catch (const server::LcmError& e) {
        return Fail(e.what());
      }
      Subscribe();
    }
    web_.OnStopSignal([this] { Stop(0); });
    last_frame_ = std::chrono::steady_clock::now();
    web_.Every(1.0 / o_.fps, [this] { SendFrames(); });
    if (!o_.snapshots.empty()) {
      web_.After(o_.timeout, [this] {
        std::fprintf(stderr,
                     "tangent-view: no snapshot within %.0f s (browser connected: %s, server "
                     "state received: %s, snapshots written: %zu of %zu)\n",
                     o_.timeout, ever_connected_ ? "yes" : "no",
                     model_.state().utime >= 0 || timeline_ ? "yes" : "no", next_snapshot_,
                     o_.snapshots.size());
        Stop(1);
      });
      if (!LaunchBrowser(true, true)) return Fail("could not start " + o_.chromium);
    } else if (o_.open_browser || o_.headless_browser) {
      if (!LaunchBrowser(o_.headless_browser, false)) return Fail("could not start " + o_.chromium);
    }
    web_.Run();
    StopBrowser();
    std::printf("tangent-view summary: frames_sent=%lld server_states=%llu\n",
                static_cast<long long>(frames_sent_),
                static_cast<unsigned long long>(model_.version()));
    if (bad_messages_ > 0 || model_rejected_ > 0) {
      std::fprintf(stderr,
                   "tangent-view: %lld bad browser messages, %lld server messages skipped\n",
                   static_cast<long long>(bad_messages_),
                   static_cast<long long>(model_rejected_ + model_.rejected()));
    }
    return exit_code_;
  }

 private:
  int Fail(const std::string& why) {
    std::fprintf(stderr, "tangent-view: %s\n", why.c_str());
    return 2;
  }

  void Stop(int code) {
    exit_code_ = code;
    web_.Stop();
  }

  // ---- LCM (live) ----

  void Subscribe() {
    subs_ = std::make_unique<server::LcmSubscriptions>(lcm_.get());
    const server::Channels ch;
    Typed<scene_state_t>(ch.scene, "scene_state_t");
    Typed<contact_states_t>(ch.contacts, "contact_states_t");
    Typed<wrench_t>(ch.wrench, "wrench_t");
    Typed<device_state_t>(ch.device, "device_state_t");
    Typed<loop_stats_t>(ch.stats, "loop_stats_t");
  }

  /// Decodes and applies every message on `channel`; what does not decode or fit the scene is
  /// counted and its first few reasons printed.
  template <class Msg>
  void Typed(const std::string& channel, const char* type) {
    auto msg = std::make_shared<Msg>();
    subs_->Raw(channel, [this, msg, channel, type](const void* data, uint32_t size) {
      std::string why;
      if (msg->decode(data, 0, static_cast<int>(size)) < 0) {
        why = std::string("does not decode as ") + type;
        ++model_rejected_;
      } else if (model_.Apply(*msg, &why)) {
        return;
      }
      if (rejections_logged_ < 10) {
        ++rejections_logged_;
        std::fprintf(stderr, "tangent-view: %s: message skipped: %s\n", channel.c_str(),
                     why.c_str());
      }
    });
  }

  // ---- frames ----

  const ViewState& Current() const { return timeline_ ? timeline_->At(replay_t_) : model_.state(); }
  uint64_t CurrentVersion() const { return timeline_ ? replay_version_ : model_.version(); }

  json StateJson() const {
    json j = StateMessage(Current());
    if (timeline_) {
      j["replay"] = {{"t", replay_t_}, {"duration", timeline_->duration()}, {"playing", playing_}};
    }
    return j;
  }

  /// One frame to every browser that has not seen the current state: the view follows at the
  /// display rate whatever the server's message rate.
  void SendFrames() {
    // The server's messages are taken here, at the display rate, not on each packet: the
    // device and wrench channels carry 2 kHz, and a view that woke for each would take the
    // server's cores that often (LCM's own receive thread still wakes; it only queues).
    if (lcm_) {
      while (lcm_->handleTimeout(0) > 0) {
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (timeline_ && playing_) {
      replay_t_ += std::chrono::duration<double>(now - last_frame_).count();
      if (replay_t_ >= timeline_->duration()) {
        replay_t_ = timeline_->duration();
        playing_ = false;
      }
      ++replay_version_;
    }
    last_frame_ = now;
    const uint64_t version = CurrentVersion();
    std::string text;
    for (auto& [id, c] : clients_) {
      if (c.sent_version == version) continue;
      if (web_.Buffered(id) > kMaxBuffered) {
        ++c.dropped_frames;
        continue;
      }
      if (text.empty()) text = StateJson().dump();
      web_.Send(id, text);
      c.sent_version = version;
      ++frames_sent_;
    }
    MaybeRequestSnapshot();
  }

  // ---- snapshots ----

  /// Asks the first browser for the next snapshot once the state it needs has been sent: the
  /// first state for the first snapshot, then a state whose poses differ from the previous
  /// snapshot's (live), or the state at --at (replay).
  void MaybeRequestSnapshot() {
    if (next_snapshot_ >= o_.snapshots.size() || clients_.empty() || awaiting_png_) return;
    const ViewState& s = Current();
    if (!timeline_) {
      if (s.utime < 0) return;
      if (next_snapshot_ > 0 && s.poses == last_snapshot_poses_) return;
    }
    required_utime_ = s.utime;
    requested_poses_ = s.poses;
    awaiting_png_ = true;
    asked_ = clients_.begin()->first;
    web_.Send(asked_, json{{"type", "snapshot"}, {"utime", s.utime}}.dump());
  }

  void OnPng(const ClientMessage& m) {
    if (!awaiting_png_ || next_snapshot_ >= o_.snapshots.size()) return;
    awaiting_png_ = false;
    if (m.utime < required_utime_) return;  // An older frame: asked again on the next frame.
    const std::string& path = o_.snapshots[next_snapshot_];
    std::ofstream f(path, std::ios::binary);
    f.write(m.png.data(), static_cast<std::streamsize>(m.png.size()));
    f.close();
    if (!f) {
      std::fprintf(stderr, "tangent-view: cannot write %s\n", path.c_str());
      Stop(1);
      return;
    }
    std::printf("tangent-view: wrote %s (state at server time %lld us)\n", path.c_str(),
                static_cast<long long>(m.utime));
    std::fflush(stdout);
    last_snapshot_poses_ = requested_poses_;
    ++next_snapshot_;
    if (timeline_ && next_snapshot_ < o_.snapshots.size()) SeekTo(SnapshotTime(next_snapshot_));
    if (next_snapshot_ == o_.snapshots.size()) Stop(0);
  }

  double SnapshotTime(size_t k) const {
    if (o_.at.empty()) return 0.0;
    return o_.at[std::min(k, o_.at.size() - 1)];
  }

  void SeekTo(double t) {
    replay_t_ = std::clamp(t, 0.0, timeline_->duration());
    ++replay_version_;
  }

  bool LaunchBrowser(bool headless, bool snapshot) {
    std::string url = url_;
    if (snapshot) {
      url += "?snapshot=1&w=" + std::to_string(o_.width) + "&h=" + std::to_string(o_.height);
    }
    char dir[] = "/tmp/tangent-view-chromium-XXXXXX";
    if (!mkdtemp(dir)) return false;
    profile_dir_ = dir;
    std::vector<std::string> args = {o_.chromium, "--user-data-dir=" + profile_dir_,
                                     "--no-first-run", "--no-default-browser-check"};
    if (headless) {
      // SwiftShader: WebGL on the CPU, so snapshots need no GPU and no display.
      for (const char* a :
           {"--headless=new", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--hide-scrollbars", "--force-device-scale-factor=1"}) {
        args.emplace_back(a);
      }
      args.push_back("--window-size=" + std::to_string(o_.width) + "," + std::to_string(o_.height));
    }
    if (geteuid() == 0) args.emplace_back("--no-sandbox");  // Chromium refuses root otherwise.
    args.push_back(url);
    const pid_t pid = fork();
    if (pid < 0) return false;
    if (pid == 0) {
      setpgid(0, 0);  // (the browser inherits the view's scheduling class: see Main)
      // A view killed outright (a test's timeout, SIGKILL) leaves no browser behind: it would
      // hold a core and its profile's lock.
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() == 1) _exit(0);  // the view died before the line above
      // The browser's own chatter (GPU, DBus) is not ours to print.
      if (FILE* null = std::fopen("/dev/null", "w")) {
        dup2(fileno(null), 1);
        dup2(fileno(null), 2);
      }
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execvp(argv[0], argv.data());
      _exit(127);
    }
    browser_ = pid;
    return true;
  }

  void StopBrowser() {
    if (browser_ <= 0) return;
    kill(-browser_, SIGTERM);
    for (int i = 0; i < 50; ++i) {
      if (waitpid(browser_, nullptr, WNOHANG) == browser_) break;
      usleep(100000);
      if (i == 30) kill(-browser_, SIGKILL);
    }
    browser_ = -1;
    std::error_code ec;
    std::filesystem::remove_all(profile_dir_, ec);
  }

  // ---- the browser's messages ----

  /// A client gone. If it was the one asked for a snapshot, the next state asks another: a
  /// client that closed just as the first state came (the order of the two events is the
  /// machine's) would otherwise leave the snapshot awaited forever (seen under load: 90 s).
  void OnClose(ClientId id) {
    clients_.erase(id);
    if (awaiting_png_ && id == asked_) awaiting_png_ = false;
  }

  void OnOpen(ClientId id) {
    clients_[id] = Client{};
    ever_connected_ = true;
    std::printf("tangent-view: a browser connected (%zu now)\n", clients_.size());
    std::fflush(stdout);
    json meshes = json::array();
    for (const DisplayMesh& m : meshes_) {
      meshes.push_back({{"hash", m.hash}, {"surface", m.surface}, {"body", m.body}});
    }
    json bodies = json::array();
    for (int b = 0; b < scene_.mechanism.num_bodies(); ++b) {
      bodies.push_back(scene_.mechanism.body(b).name);
    }
    json scene = {{"type", "scene"},
                  {"name", scene_.name},
                  {"bodies", bodies},
                  {"meshes", meshes},
                  {"camera", camera_},
                  {"max_force", scene_.device.max_force},
                  {"mode", timeline_ ? "replay" : "live"}};
    if (timeline_) scene["duration"] = timeline_->duration();
    web_.Send(id, scene.dump());
  }

  void Error(ClientId id, const std::string& what) {
    web_.Send(id, json{{"type", "error"}, {"message", what}}.dump());
  }

  void OnMessage(ClientId id, const std::string& text) {
    ClientMessage m;
    try {
      m = ParseClientMessage(text);
    } catch (const ProtocolError& e) {
      ++bad_messages_;
      if (bad_logged_ < 10) {
        ++bad_logged_;
        std::fprintf(stderr, "tangent-view: bad message from a browser: %s\n", e.what());
      }
      Error(id, e.what());
      return;
    }
    switch (m.kind) {
      case ClientMessage::Kind::kNeed: {
        const auto it = mesh_text_.find(m.hash);
        if (it == mesh_text_.end()) {
          Error(id, "no mesh with hash " + m.hash);
        } else {
          web_.Send(id, it->second);
        }
        break;
      }
      case ClientMessage::Kind::kCamera:
        // Kept for the next page that connects (a reload keeps its view), unless --camera
        // fixed it.
        if (!camera_.is_object() || !camera_.value("fixed", false)) {
          camera_ = {
              {"position", {m.camera_position[0], m.camera_position[1], m.camera_position[2]}},
              {"target", {m.camera_target[0], m.camera_target[1], m.camera_target[2]}}};
        }
        break;
      case ClientMessage::Kind::kPng:
        OnPng(m);
        break;
      case ClientMessage::Kind::kPlay:
      case ClientMessage::Kind::kPause:
      case ClientMessage::Kind::kSeek:
        if (!timeline_) {
          Error(id, "not replaying a log: play, pause and seek need --log");
        } else if (m.kind == ClientMessage::Kind::kSeek) {
          SeekTo(m.t);
        } else {
          playing_ = m.kind == ClientMessage::Kind::kPlay;
          if (playing_ && replay_t_ >= timeline_->duration()) replay_t_ = 0.0;
          ++replay_version_;
        }
        break;
    }
  }

  const Options& o_;
  const server::Scene& scene_;
  std::vector<DisplayMesh> meshes_;
  std::map<std::string, std::string> mesh_text_;
  ViewModel model_;
  const Timeline* timeline_;
  WebServer web_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<server::LcmSubscriptions> subs_;
  std::map<ClientId, Client> clients_;
  json camera_;
  std::string url_, profile_dir_;
  pid_t browser_ = -1;
  int exit_code_ = 0;
  bool ever_connected_ = false;
  int64_t bad_messages_ = 0, model_rejected_ = 0, frames_sent_ = 0;
  int bad_logged_ = 0, rejections_logged_ = 0;
  // Replay.
  double replay_t_ = 0.0;
  bool playing_ = false;
  uint64_t replay_version_ = 1;
  std::chrono::steady_clock::time_point last_frame_;
  // Snapshots.
  size_t next_snapshot_ = 0;
  bool awaiting_png_ = false;
  ClientId asked_ = 0;  ///< the client asked for the PNG awaited
  int64_t required_utime_ = 0;
  std::vector<std::array<double, 7>> requested_poses_, last_snapshot_poses_;
};

int Main(int argc, char** argv) {
  Options o;
  CLI::App app{"tangent-view: the live 3D view of a Tangent scene in the browser"};
  app.add_option("--scene", o.scene, "scene file the server runs (JSON)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--lcm-url", o.lcm_url,
                 "LCM URL to listen on (default: tangentd's viewer URL, --view-lcm-url)");
  app.add_option("--port", o.port, "HTTP and WebSocket port (0: any free port)")
      ->check(CLI::Range(0, 65535));
  app.add_option("--bind", o.bind, "address to serve on (127.0.0.1: this host only)");
  app.add_option("--web-root", o.web_root, "folder of index.html, view.js and node_modules/three");
  app.add_option("--log", o.log, "replay this lcm-logger log instead of listening")
      ->check(CLI::ExistingFile);
  app.add_option("--snapshot", o.snapshots,
                 "write the view to this PNG through headless Chromium and exit; repeat for more "
                 "(live: each after the bodies have moved; replay: at each --at)");
  app.add_option("--at", o.at, "replay: seconds from the log's start of each snapshot");
  app.add_option("--camera", o.camera, "camera eye and target, metres: ex ey ez tx ty tz")
      ->expected(6);
  app.add_option("--width", o.width, "snapshot width, pixels")->check(CLI::Range(64, 4096));
  app.add_option("--height", o.height, "snapshot height, pixels")->check(CLI::Range(64, 4096));
  app.add_option("--fps", o.fps, "frames per second sent to each browser")
      ->check(CLI::Range(1.0, 240.0));
  app.add_option("--tolerance", o.tolerance,
                 "display tessellation bound, metres (0: 1/2000 of the scene)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--timeout", o.timeout, "snapshots: give up after this many seconds")
      ->check(CLI::PositiveNumber);
  app.add_option("--chromium", o.chromium, "browser program for snapshots and --open");
  app.add_flag("--open", o.open_browser, "open the view in a browser window");
  app.add_flag("--headless", o.headless_browser,
               "attach a headless browser that renders the live view (to measure the view's cost)");
  app.add_option("--priority", o.priority,
                 "CPU scheduling of the live view and the browser it starts: idle (SCHED_IDLE: "
                 "only CPU time nothing else wants, so never the servo's) or normal; snapshots "
                 "always run normal")
      ->check(CLI::IsMember({"idle", "normal"}));
  app.add_option("--avoid-cpu", o.avoid_cpu,
                 "keep the view and its browser off this core: the servo's (tangentd --servo-cpu; "
                 "-1: any core)")
      ->check(CLI::Range(-1, 1023));
  CLI11_PARSE(app, argc, argv);
  // Before any thread starts (LCM's receive thread, the browser's processes inherit it): a view
  // must never take CPU time from the haptic server. Under SCHED_IDLE it runs only where a core
  // would otherwise idle, and a busy machine makes it drop frames, never the servo late.
  // And off the servo's core: tangentd pins its servo thread to core 0 by default
  // (--servo-cpu), so the view and its browser keep to the other cores where there are any.
  if (o.avoid_cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    for (long c = 0; c < cores; ++c) {
      if (c != o.avoid_cpu) CPU_SET(static_cast<int>(c), &set);
    }
    if (cores > 1 && sched_setaffinity(0, sizeof(set), &set) != 0) {
      std::fprintf(stderr, "tangent-view: could not keep off core %d (%s)\n", o.avoid_cpu,
                   std::strerror(errno));
    }
  }
  // Snapshots are one-offs that must finish: they keep the normal class (still off the servo's
  // core), since an idle-class browser on a machine whose other cores are busy never starts.
  if (o.priority == "idle" && o.snapshots.empty()) {
    sched_param none{};
    if (sched_setscheduler(0, SCHED_IDLE, &none) != 0) {
      std::fprintf(stderr, "tangent-view: could not switch to SCHED_IDLE (%s); running normal\n",
                   std::strerror(errno));
    }
  }

  // The page imports three.js from npm (index.html's import map): without it a browser would
  // load a page that never connects, and a snapshot would only time out.
  const std::string three = o.web_root + "/node_modules/three/build/three.module.js";
  if (!std::filesystem::exists(three)) {
    std::fprintf(stderr,
                 "tangent-view: %s is missing (three.js comes from npm: run "
                 "scripts/install-web.sh)\n",
                 three.c_str());
    return 2;
  }

  std::unique_ptr<server::Scene> scene;
  try {
    std::ifstream in(o.scene);
    std::stringstream text;
    text << in.rdbuf();
    const size_t slash = o.scene.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : o.scene.substr(0, slash);
    server::SceneLoadOptions lo;
    lo.offset_meshes = false;  // The view draws surfaces; it needs no collision meshes.
    scene = server::ParseScene(text.str(), o.scene, dir, lo);
  } catch (const server::SceneError& e) {
    std::fprintf(stderr, "tangent-view: %s\n", e.what());
    return 2;
  }
  std::unique_ptr<Timeline> timeline;
  if (!o.log.empty()) {
    try {
      timeline = std::make_unique<Timeline>(o.log, *scene, server::Channels{});
    } catch (const TimelineError& e) {
      std::fprintf(stderr, "tangent-view: %s\n", e.what());
      return 2;
    }
  }
  const double tol = o.tolerance > 0.0 ? o.tolerance : DefaultDisplayTolerance(*scene);
  std::vector<DisplayMesh> meshes = BuildDisplayMeshes(*scene, tol);
  ViewServer server(o, *scene, std::move(meshes), timeline.get());
  return server.Run();
}

}  // namespace
}  // namespace tangent::view

int main(int argc, char** argv) { return tangent::view::Main(argc, argv); }
