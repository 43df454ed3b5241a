// Writes the seed corpora that are not files in scenes/: NURBS documents for the surface
// fuzzer (made by our own writer, so they follow the format as it is) and device scripts for
// the device fuzzer (the script format is in device_fuzzer.cc).
//   tangent-fuzz-seeds surface|device DIR

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <tangent/device_state_t.hpp>

#include "nurbs/json_io.h"
#include "nurbs/primitives.h"
#include "nurbs/trim.h"

namespace {

namespace nurbs = tangent::nurbs;

void Write(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  if (!out) {
    std::fprintf(stderr, "tangent-fuzz-seeds: cannot write %s\n", path.c_str());
    std::exit(1);
  }
}

void SurfaceSeeds(const std::string& dir) {
  const nurbs::NurbsSurface sheared = nurbs::MakeShearedPatch(0.3, 1.0, 0.2, /*rational=*/true);
  Write(dir + "/sheared_rational.json", nurbs::ToJson(sheared).dump(1));
  Write(dir + "/sphere.json", nurbs::ToJson(nurbs::MakeSphere({0, 0, 0}, 0.02)).dump(1));
  Write(dir + "/torus.json", nurbs::ToJson(nurbs::MakeTorus(0.03, 0.01)).dump(1));
  // A plate with a round hole and a square outer loop: the trimmed document.
  const nurbs::NurbsSurface plate = nurbs::MakePlanePatch({0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0});
  const Eigen::Vector2d lo(plate.knots_u().domain_begin(), plate.knots_v().domain_begin());
  const Eigen::Vector2d hi(plate.knots_u().domain_end(), plate.knots_v().domain_end());
  const Eigen::Vector2d mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  nurbs::TrimLoop outer{
      {nurbs::MakePolyline2d({mid + Eigen::Vector2d(-0.9, -0.9).cwiseProduct(half),
                              mid + Eigen::Vector2d(0.9, -0.9).cwiseProduct(half),
                              mid + Eigen::Vector2d(0.9, 0.9).cwiseProduct(half),
                              mid + Eigen::Vector2d(-0.9, 0.9).cwiseProduct(half),
                              mid + Eigen::Vector2d(-0.9, -0.9).cwiseProduct(half)})}};
  nurbs::TrimLoop hole{{nurbs::MakeCircle2d(mid, 0.3 * half.minCoeff(), /*clockwise=*/true)}};
  const nurbs::TrimmedDomain trim(lo, hi, outer, {hole});
  nlohmann::json doc = nurbs::ToJson(plate);
  doc["trim"] = nurbs::ToJson(trim);
  Write(dir + "/plate_with_hole.json", doc.dump(1));
  Write(dir + "/circle2d.json", nurbs::ToJson(nurbs::MakeCircle2d({0.5, 0.5}, 0.25)).dump(1));
}

/// A device script (device_fuzzer.cc's format) built record by record.
struct Script {
  std::string bytes;
  int64_t seq = 0;
  void State(int session, double x, double y, double z, int seq_step = 1) {
    bytes += static_cast<char>(1);  // structured state, int16 position, small rotation
    bytes += static_cast<char>(1);  // device id 1
    bytes += static_cast<char>(session);
    bytes += static_cast<char>(seq_step);
    bytes += static_cast<char>(1);  // buttons
    for (double c : {x, y, z}) {
      const auto q = static_cast<int16_t>(std::lround(c / 1e-5));
      bytes.append(reinterpret_cast<const char*>(&q), 2);
    }
    bytes += static_cast<char>(128);  // no rotation
  }
  void Ticks(int n) {
    bytes += static_cast<char>(2);
    bytes += static_cast<char>(n);
  }
  void Gap(int units_of_50us) {  // one tick after a gap (a late servo, or silence in few ticks)
    bytes += static_cast<char>(3);
    bytes += static_cast<char>(units_of_50us);
  }
  void Raw(int64_t session, double x) {
    tangent::device_state_t m{};
    m.device_id = 1;
    m.session = session;
    m.seq = ++seq;
    m.position[0] = x;
    m.orientation[0] = 1.0;
    uint8_t buf[256];
    const int n = m.encode(buf, 0, sizeof buf);
    bytes += static_cast<char>(0);
    bytes += static_cast<char>(n);
    bytes.append(reinterpret_cast<const char*>(buf), static_cast<size_t>(n));
  }
};

void DeviceSeeds(const std::string& dir) {
  // Short scripts (a few hundred ticks): an input's cost is its ticks, and mutations keep length.
  Script drag;  // a 1 kHz drag along x and back, four ticks per state
  for (int k = 0; k < 60; ++k) {
    drag.State(0, 0.02 * std::sin(0.1 * k), 0.005 * k / 60.0, 0.0);
    drag.Ticks(3);
  }
  Write(dir + "/drag", drag.bytes);
  Script jump;  // at rest, a 6 cm jump, then on from there
  for (int k = 0; k < 20; ++k) (jump.State(0, 0, 0, 0), jump.Ticks(3));
  for (int k = 0; k < 20; ++k) (jump.State(0, 0.06, 0, 0), jump.Ticks(3));
  Write(dir + "/jump", jump.bytes);
  Script takeover;  // a second session takes over, then the first one's states come late
  for (int k = 0; k < 15; ++k) (takeover.State(0, 0.01, 0, 0), takeover.Ticks(3));
  for (int k = 0; k < 15; ++k) (takeover.State(1, 0.012, 0, 0), takeover.Ticks(3));
  for (int k = 0; k < 5; ++k) (takeover.State(0, 0.01, 0, 0), takeover.Ticks(3));
  Write(dir + "/takeover", takeover.bytes);
  Script silence;  // pulled, then silent past the timeout (ten 12.75 ms gaps), then back
  for (int k = 0; k < 20; ++k) (silence.State(0, 0.03, 0, 0), silence.Ticks(3));
  for (int k = 0; k < 10; ++k) silence.Gap(255);
  for (int k = 0; k < 20; ++k) (silence.State(0, 0.03, 0, 0), silence.Ticks(3));
  Write(dir + "/silence", silence.bytes);
  Script raw;  // LCM-encoded packets as a client sends them
  for (int k = 0; k < 20; ++k) (raw.Raw(0x5eed, 0.001 * k), raw.Ticks(3));
  Write(dir + "/raw_packets", raw.bytes);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || (std::string(argv[1]) != "surface" && std::string(argv[1]) != "device")) {
    std::fprintf(stderr, "usage: tangent-fuzz-seeds surface|device DIR\n");
    return 2;
  }
  if (std::string(argv[1]) == "surface") {
    SurfaceSeeds(argv[2]);
  } else {
    DeviceSeeds(argv[2]);
  }
  return 0;
}
