#include "view/model.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "view/display.h"

namespace tangent::view {
namespace {

std::unique_ptr<server::Scene> Paperclips() {
  server::SceneLoadOptions o;
  o.offset_meshes = false;
  return server::ParseScene(
      R"({"name":"two clips","length_unit":"mm",
          "bodies":[{"name":"a","fixed":true},{"name":"b","position":[0,31.35,0]}],
          "surfaces":[{"name":"wa","body":"a","type":"paperclip"},
                      {"name":"wb","body":"b","type":"paperclip"}],
          "grasp":{"body":"b","point":[0,20,0]}})",
      "two_clips.json", ".", o);
}

scene_state_t SceneState(const server::Scene& s) {
  scene_state_t m;
  m.utime = 10;
  m.num_bodies = s.mechanism.num_bodies();
  for (int b = 0; b < m.num_bodies; ++b) {
    const optimizer::Vector7d& x = s.mechanism.body(b).pose;
    m.names.push_back(s.mechanism.body(b).name);
    m.position.push_back({x[0], x[1], x[2]});
    m.orientation.push_back({x[3], x[4], x[5], x[6]});
  }
  m.grasp_target[0] = m.grasp_target[1] = m.grasp_target[2] = 0.0;
  return m;
}

TEST(ViewModelTest, AppliesPosesAndRejectsAnotherScenesOrGarbage) {
  const auto scene = Paperclips();
  ViewModel model(*scene);
  scene_state_t m = SceneState(*scene);
  m.position[1][0] = 0.01;
  std::string why;
  ASSERT_TRUE(model.Apply(m, &why)) << why;
  EXPECT_EQ(model.state().poses[1][0], 0.01);
  EXPECT_EQ(model.state().utime, 10);
  const uint64_t version = model.version();

  scene_state_t other = m;
  other.names[1] = "clip7";
  EXPECT_FALSE(model.Apply(other, &why));
  EXPECT_EQ(why, "scene_state_t.names[1] is \"clip7\", the loaded scene has \"b\"");
  other = m;
  other.num_bodies = 3;
  other.names.push_back("c");
  other.position.push_back({0, 0, 0});
  other.orientation.push_back({1, 0, 0, 0});
  EXPECT_FALSE(model.Apply(other, &why));
  EXPECT_NE(why.find("has 2 bodies"), std::string::npos) << why;
  other = m;
  other.orientation[1] = {0, 0, 0, 0};
  EXPECT_FALSE(model.Apply(other, &why));
  EXPECT_NE(why.find("non-unit orientation"), std::string::npos) << why;
  other = m;
  other.grasp_target[2] = NAN;
  EXPECT_FALSE(model.Apply(other, &why));
  EXPECT_EQ(why, "scene_state_t.grasp_target is not finite");
  EXPECT_EQ(model.version(), version);  // nothing rejected changed the state
  EXPECT_EQ(model.state().poses[1][0], 0.01);
  EXPECT_EQ(model.rejected(), 4);
}

TEST(ViewModelTest, ContactNormalIsTheSurfacesAndBadContactsAreRejected) {
  const auto scene = Paperclips();
  ViewModel model(*scene);
  ASSERT_TRUE(model.Apply(SceneState(*scene), nullptr));
  const nurbs::NurbsSurface& s = scene->surfaces[0].surface;
  const double u = 0.5 * (s.knots_u().domain_begin() + s.knots_u().domain_end());
  const double v = 0.3 * s.knots_v().domain_end() + 0.7 * s.knots_v().domain_begin();
  const nurbs::SurfacePoint p = s.Evaluate(u, v, 2);
  const Eigen::Vector3d n = nurbs::UnitNormal(s, u, v, p);
  contact_states_t m;
  m.utime = 11;
  m.num_contacts = 1;
  contact_state_t c{};
  c.surface_a = 0;
  c.surface_b = 1;
  c.params[0] = u;
  c.params[1] = v;
  c.distance = 1e-4;
  for (int i = 0; i < 3; ++i) {
    c.point_a[i] = p.S[i];
    c.point_b[i] = p.S[i] - 1e-4 * n[i];  // b lies on the side opposite to n: normal flips
  }
  m.contacts.push_back(c);
  std::string why;
  ASSERT_TRUE(model.Apply(m, &why)) << why;
  ASSERT_EQ(model.state().contacts.size(), 1u);
  EXPECT_NEAR((model.state().contacts[0].n_W + n).norm(), 0.0, 1e-12);

  m.contacts[0].surface_b = 2;
  EXPECT_FALSE(model.Apply(m, &why));
  EXPECT_EQ(why,
            "contact_states_t.contacts[0]: surface index out of range (the scene has 2 surfaces)");
  m.contacts[0].surface_b = 1;
  m.contacts[0].params[1] = INFINITY;
  EXPECT_FALSE(model.Apply(m, &why));
  EXPECT_EQ(why, "contact_states_t.contacts[0]: a field is not finite");
  EXPECT_EQ(model.state().contacts.size(), 1u);

  const nlohmann::json j = StateMessage(model.state());
  EXPECT_EQ(j["type"], "state");
  EXPECT_EQ(j["contacts"].size(), 1u);
  EXPECT_EQ(j["poses"].size(), 2u);
}

TEST(ViewModelTest, WrenchIsTurnedIntoTheWorldAndStatisticsKept) {
  const auto scene = Paperclips();
  ViewModel model(*scene);
  wrench_t w{};
  w.force[0] = 1.0;
  w.force[1] = 2.0;
  w.force[2] = 3.0;
  ASSERT_TRUE(model.Apply(w, nullptr));
  EXPECT_NEAR((model.state().force_W - scene->device.R_WD * Eigen::Vector3d(1, 2, 3)).norm(), 0,
              1e-15);
  w.force[1] = NAN;
  std::string why;
  EXPECT_FALSE(model.Apply(w, &why));
  EXPECT_EQ(why, "wrench_t.force is not finite");
  device_state_t d{};
  d.orientation[0] = 2.0;
  EXPECT_FALSE(model.Apply(d, &why));
  EXPECT_EQ(why, "device_state_t.orientation is not a unit quaternion");
}

TEST(DisplayMeshTest, MeshesHoldTheCertifiedBoundWithUnitNormalsAndStableHashes) {
  const auto scene = Paperclips();
  const double tol = DefaultDisplayTolerance(*scene);
  EXPECT_GT(tol, 1e-6);
  EXPECT_LT(tol, 1e-4);  // two 40 mm clips: 1/2000 of ~70 mm
  const std::vector<DisplayMesh> a = BuildDisplayMeshes(*scene, tol);
  ASSERT_EQ(a.size(), 2u);
  for (const DisplayMesh& m : a) {
    EXPECT_LE(m.error_bound, tol);
    ASSERT_EQ(m.positions.size(), m.normals.size());
    ASSERT_EQ(m.indices.size() % 3, 0u);
    for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size() / 3);
    for (size_t k = 0; k < m.normals.size(); k += 3) {
      const double n = std::hypot(m.normals[k], m.normals[k + 1], m.normals[k + 2]);
      ASSERT_NEAR(n, 1.0, 1e-6);
    }
    EXPECT_EQ(m.hash.size(), 16u);
  }
  // Same surface, different body colour: different content, different hash. Same build: same.
  EXPECT_NE(a[0].hash, a[1].hash);
  EXPECT_EQ(BuildDisplayMeshes(*scene, tol)[0].hash, a[0].hash);
  EXPECT_THROW(BuildDisplayMeshes(*scene, 0.0), std::invalid_argument);
}

/// Whether uv lies in the triangle (a, b, c) of the parameter plane (boundary included).
bool InTriangle(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                const Eigen::Vector2d& c) {
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& x, const Eigen::Vector2d& y) {
    return (x - o).x() * (y - o).y() - (x - o).y() * (y - o).x();
  };
  const double d1 = cross(a, b, p), d2 = cross(b, c, p), d3 = cross(c, a, p);
  return !((d1 < 0 || d2 < 0 || d3 < 0) && (d1 > 0 || d2 > 0 || d3 > 0));
}

TEST(DisplayMeshTest, TrimmedAwayMaterialIsNotDrawn) {
  const auto scene = server::LoadScene(std::string(TANGENT_SCENES_DIR) + "/peg_in_hole.json");
  const std::vector<DisplayMesh> meshes = BuildDisplayMeshes(*scene, 1e-4);
  int checked = 0;

  for (const DisplayMesh& m : meshes) {
    const server::SceneSurface& s = scene->surfaces[static_cast<size_t>(m.surface_index)];
    if (!s.trim) continue;
    ++checked;
    auto uv = [&](uint32_t i) { return Eigen::Vector2d(m.uv[2 * i], m.uv[2 * i + 1]); };
    auto diagonal = [&](size_t t) {
      Eigen::AlignedBox2d box;
      for (int k = 0; k < 3; ++k) box.extend(uv(m.indices[t + static_cast<size_t>(k)]));
      return box.diagonal().norm();
    };
    double largest = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3) largest = std::max(largest, diagonal(t));
    // A drawn triangle holding a point off the material lies in a cell the rim crosses (a cell
    // the rim does not cross is all material or dropped), so the rim is within the triangle's
    // diagonal of the point, and that cell was split (to 1/8 of its grid cell; grid cells
    // differ by up to 2x here, so at most a quarter of the largest).
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> ru(s.trim->lo().x(), s.trim->hi().x());
    std::uniform_real_distribution<double> rv(s.trim->lo().y(), s.trim->hi().y());
    int off_material = 0, drawn_off = 0;
    for (int k = 0; k < 10000; ++k) {
      const Eigen::Vector2d p(ru(rng), rv(rng));
      if (s.trim->Contains(p)) continue;
      ++off_material;
      const double d = std::abs(s.trim->Nearest(p).signed_distance);
      for (size_t t = 0; t < m.indices.size(); t += 3) {
        if (!InTriangle(p, uv(m.indices[t]), uv(m.indices[t + 1]), uv(m.indices[t + 2]))) continue;
        ++drawn_off;
        ASSERT_LE(d, diagonal(t) * (1 + 1e-12))
            << m.surface << ": (" << p.x() << ", " << p.y() << ") is off the material, drawn";
        ASSERT_LE(diagonal(t), largest / 4) << m.surface << ": a rim cell was not split at ("
                                            << p.x() << ", " << p.y() << "), rim " << d;
      }
    }
    std::printf("%s: %d of %d sampled points off the material lie in drawn rim cells\n",
                m.surface.c_str(), drawn_off, off_material);
    EXPECT_GT(off_material, 100) << m.surface;
  }
  EXPECT_GT(checked, 0);
}

}  // namespace
}  // namespace tangent::view
