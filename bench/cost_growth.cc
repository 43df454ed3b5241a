// How the servo's cost grows with the scene (issue 18): chains of 1, 2, 5, 10 and 20 moving
// paperclips hanging from a fixed one (testing/paperclip_scene.h), each dragged by its last clip
// along the servo benchmarks' path (lift, then circles) on one thread: four ticks per device
// state and one global pass after them, its events applied. Per chain: the servo tick p50 / mean
// / p99, the global pass mean, the active contacts on average, and the resident memory the
// scene and servo hold (heap in use). Then least-squares fits: the exponent of the mean tick in the
// number of bodies and of active contacts (log–log), and the cost of one more active contact
// (linear). Then the spatial four-bar with 0–8 extra contacts (testing/fourbar_contacts.h: balls
// spinning in place on plates, always active), its hand circling 1 cm: the same figures and the
// cost of one more active contact on a mechanism whose bodies do not change.
//
//   ./build/bench/cost_growth [--steps 3000] [--chains 1,2,5,10,20] [--extra 0,1,2,4,8]
//                             [--csv out.csv]

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench/sample_stats.h"
#include "server/global_link.h"
#include "server/servo.h"
#include "testing/drag_path.h"
#include "testing/fourbar_contacts.h"
#include "testing/paperclip_scene.h"

using namespace tangent::server;

namespace {

using tangent::bench::Mean;
using tangent::bench::Quantile;

// Heap in use (glibc's count of allocated bytes): what a scene and its servo hold, unlike the
// resident size, which keeps what earlier chains freed.
double HeapMb() { return static_cast<double>(mallinfo2().uordblks) / 1048576.0; }

// Least-squares slope and intercept of y on x.
std::pair<double, double> Fit(const std::vector<double>& x, const std::vector<double>& y) {
  const double mx = Mean(x), my = Mean(y);
  double sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  const double b = sxx > 0.0 ? sxy / sxx : 0.0;
  return {b, my - b * mx};
}

struct Row {
  int moving = 0, bodies = 0;
  double tick_p50 = 0, tick_mean = 0, tick_p99 = 0, pass_mean = 0, contacts = 0, memory_mb = 0;
  int budget_ticks = 0, ticks = 0;
};

// `moving`: the chain's moving clips, or (four_bar) the four-bar's extra contacts.
Row Measure(int moving, int steps, bool four_bar = false) {
  Row row;
  row.moving = moving;
  const double before = HeapMb();
  // Slots per pair: two (a split hook's minima), within the servo's 32 contact slots.
  const int per_pair = std::max(1, std::min(2, kMaxContacts / std::max(1, moving)));
  auto scene = four_bar
                   ? ParseScene(tangent::testing::FourBarWithContacts(TANGENT_SCENES_DIR, moving),
                                "four-bar + " + std::to_string(moving), TANGENT_SCENES_DIR)
                   : ParseScene(tangent::testing::PaperclipChainScene(moving, per_pair),
                                std::to_string(moving) + " clips", TANGENT_SCENES_DIR);
  ServoLoop servo(*scene, ServoOptions{});
  GlobalLink link(servo);
  row.memory_mb = HeapMb() - before;
  row.bodies = scene->mechanism.num_bodies();
  std::vector<double> ticks, passes;
  ticks.reserve(static_cast<size_t>(4 * steps));
  Snapshot snap;
  TickResult r;
  int64_t now = 1'000'000'000;
  double contacts = 0.0;
  for (int k = 0; k < steps; ++k) {
    DeviceSample s = tangent::bench::DragSample(k + 1, 1e-3 * k, now);
    if (four_bar) {  // circles of 1 cm, 4 s a turn
      const double a = 2 * 3.141592653589793 * 1e-3 * k / 4.0;
      s.position[0] = 1e-2 * std::sin(a);
      s.position[1] = 1e-2 * (std::cos(a) - 1.0);
      s.position[2] = 0.0;
    }
    for (int tick = 0; tick < 4; ++tick) {
      const auto t0 = std::chrono::steady_clock::now();
      servo.Tick(&s, now, &r);
      ticks.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      row.budget_ticks += r.iterations >= ServoOptions{}.max_iterations;
      contacts += r.num_contacts;
      now += 250'000;
    }
    const auto t0 = std::chrono::steady_clock::now();
    servo.FillSnapshot(&snap);
    link.PassInto(&servo, snap);
    passes.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  row.ticks = static_cast<int>(ticks.size());
  row.tick_p50 = Quantile(ticks, 0.5);
  row.tick_mean = Mean(ticks);
  row.tick_p99 = Quantile(ticks, 0.99);
  row.pass_mean = Mean(passes);
  row.contacts = contacts / static_cast<double>(ticks.size());
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  int steps = 3000;
  std::vector<int> chains = {1, 2, 5, 10, 20}, extras = {0, 1, 2, 4, 8};
  std::string csv;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--csv")) csv = argv[i + 1];
    for (auto [flag, list] : {std::pair{"--chains", &chains}, std::pair{"--extra", &extras}}) {
      if (std::strcmp(argv[i], flag)) continue;
      list->clear();
      std::stringstream items(argv[i + 1]);
      for (std::string item; std::getline(items, item, ',');) list->push_back(std::stoi(item));
    }
  }
  Measure(1, 10);  // warm-up: one-time allocations (libraries, caches) outside the figures
  std::vector<Row> rows;
  for (int n : chains) rows.push_back(Measure(n, steps));
  std::printf("cost_growth: %d device steps (%d ticks) per chain, drag path, one thread\n", steps,
              4 * steps);
  std::printf(
      "| moving clips | bodies | active contacts (mean) | tick p50 (us) | tick mean (us) | "
      "tick p99 (us) | ticks at the budget | global pass mean (us) | memory (MB) |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const Row& r : rows) {
    std::printf("| %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f %% | %.1f | %.1f |\n", r.moving,
                r.bodies, r.contacts, r.tick_p50, r.tick_mean, r.tick_p99,
                100.0 * r.budget_ticks / r.ticks, r.pass_mean, r.memory_mb);
  }
  if (rows.size() >= 2) {
    std::vector<double> lb, lc, lt, lp, c, t;
    for (const Row& r : rows) {
      lb.push_back(std::log(r.bodies));
      lc.push_back(std::log(std::max(r.contacts, 1e-3)));
      lt.push_back(std::log(r.tick_mean));
      lp.push_back(std::log(r.pass_mean));
      c.push_back(r.contacts);
      t.push_back(r.tick_mean);
    }
    const auto [per_contact, base] = Fit(c, t);
    std::printf(
        "fits: mean tick ~ bodies^%.2f, ~ active contacts^%.2f; global pass ~ bodies^%.2f; "
        "mean tick = %.2f us + %.2f us per active contact\n",
        Fit(lb, lt).first, Fit(lc, lt).first, Fit(lb, lp).first, base, per_contact);
    const double exponent = Fit(lc, lt).first;
    std::printf(
        "growth of the mean tick in active contacts: exponent %.2f (target <= 1, at most "
        "linear: %s)\n",
        exponent, exponent <= 1.0 ? "met" : "NOT MET");
  }
  // The four-bar with extra contacts: the bodies fixed, only the active contacts grow.
  std::vector<Row> four;
  for (int n : extras) four.push_back(Measure(n, steps, true));
  if (!four.empty()) {
    std::printf(
        "\nfour-bar + extra contacts: %d device steps (%d ticks) each, hand circling 1 cm\n", steps,
        4 * steps);
    std::printf(
        "| extra contacts | active contacts (mean) | tick p50 (us) | tick mean (us) | tick p99 "
        "(us) "
        "| ticks at the budget | global pass mean (us) | memory (MB) |\n");
    std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
    for (const Row& r : four) {
      std::printf("| %d | %.2f | %.2f | %.2f | %.2f | %.2f %% | %.1f | %.1f |\n", r.moving,
                  r.contacts, r.tick_p50, r.tick_mean, r.tick_p99, 100.0 * r.budget_ticks / r.ticks,
                  r.pass_mean, r.memory_mb);
    }
    if (four.size() >= 2) {
      std::vector<double> c, t, p99;
      for (const Row& r : four) {
        c.push_back(r.contacts);
        t.push_back(r.tick_mean);
        p99.push_back(r.tick_p99);
      }
      const auto [per, base] = Fit(c, t);
      const auto [per99, base99] = Fit(c, p99);
      std::printf(
          "four-bar fits: mean tick = %.2f us + %.2f us per active contact; p99 = %.2f us + "
          "%.2f us per active contact\n",
          base, per, base99, per99);
    }
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "moving,bodies,contacts,tick_p50_us,tick_mean_us,tick_p99_us,budget_ticks,ticks,"
           "pass_mean_us,memory_mb\n";
    for (const Row& r : rows) {
      out << r.moving << ',' << r.bodies << ',' << r.contacts << ',' << r.tick_p50 << ','
          << r.tick_mean << ',' << r.tick_p99 << ',' << r.budget_ticks << ',' << r.ticks << ','
          << r.pass_mean << ',' << r.memory_mb << '\n';
    }
  }
  return 0;
}
