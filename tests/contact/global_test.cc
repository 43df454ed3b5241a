// The global contact stage on three interlocked paperclips: over 1000 seeded random
// configurations near contact, the contacts found with β > −0.3 mm match a brute-force reference
// (dense samples of both wires, local minima of their distance, the same Newton solver): none
// missed, none duplicated, none extra, positions within 1e-9 m. The inner/outer-loop case gives two
// contacts; grazing, hysteresis and deep interpenetration give the right events; near misses are
// carried and skip their blocks; a fresh pass skips the blocks round what it finds; filters and
// bad input.

#include "contact/global.h"
#include "contact/global_minima.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <random>
#include <tuple>

#include "nurbs/primitives.h"
#include "testing/contact_scenes.h"
#include "testing/paperclip_chain.h"

namespace tangent::contact {
namespace {

constexpr double mm = 1e-3;

struct Clips {
  nurbs::NurbsSurface wire = nurbs::MakeTube(nurbs::PaperclipPath(), nurbs::kPaperclipWireRadius);
  nurbs::OffsetMesh mesh = nurbs::MakeOffsetMesh(wire, 20e-6, 0.25e-3, 0.5e-3);
  std::vector<GlobalSurface> Surfaces(int n) const {
    std::vector<GlobalSurface> s;
    for (int k = 0; k < n; ++k) s.push_back({k, &wire, &mesh});
    return s;
  }
};

std::vector<BodyPose> Poses(const std::vector<Vector7d>& q) {
  std::vector<BodyPose> p;
  for (const Vector7d& c : q) p.push_back(BodyPose::FromCoordinates(c));
  return p;
}

// Brute force: 440 x 16 samples per wire; for each sample of a the nearest sample of b within
// 1.5 mm; the local minima of that distance over a's sample grid seed Newton; extrema that
// converge with facing normals and −max_penetration < β < activation are the reference.
std::vector<GlobalContact> Reference(const Clips& c, const std::vector<BodyPose>& poses, int a,
                                     int b, const GlobalOptions& opt) {
  const int nu = 440, nv = 16;
  auto samples = [&](int body) {
    std::vector<Eigen::Vector3d> x(static_cast<size_t>(nu * nv));
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nv; ++j) {
        x[static_cast<size_t>(i * nv + j)] = poses[static_cast<size_t>(body)].Point(
            c.wire.Evaluate((i + 0.5) / nu, (j + 0.5) / nv, 0).S);
      }
    }
    return x;
  };
  const std::vector<Eigen::Vector3d> xa = samples(a), xb = samples(b);
  // b's samples hashed in 1.5 mm cells: a's nearest within 1.5 mm is in the 27 cells around.
  const double cell = 1.5 * mm;
  auto key = [&](const Eigen::Vector3d& x, int dx, int dy, int dz) {
    return std::make_tuple(static_cast<long>(std::floor(x.x() / cell)) + dx,
                           static_cast<long>(std::floor(x.y() / cell)) + dy,
                           static_cast<long>(std::floor(x.z() / cell)) + dz);
  };
  std::map<std::tuple<long, long, long>, std::vector<int>> grid;
  for (size_t j = 0; j < xb.size(); ++j) grid[key(xb[j], 0, 0, 0)].push_back(static_cast<int>(j));
  std::vector<double> best(xa.size(), 1e300);
  std::vector<int> arg(xa.size(), -1);
  for (size_t i = 0; i < xa.size(); ++i) {
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(xa[i], dx, dy, dz));
          if (it == grid.end()) continue;
          for (int j : it->second) {
            const double d = (xa[i] - xb[static_cast<size_t>(j)]).squaredNorm();
            if (d < best[i] && d < cell * cell) {
              best[i] = d;
              arg[i] = j;
            }
          }
        }
      }
    }
  }
  std::vector<GlobalContact> out;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const size_t k = static_cast<size_t>(i * nv + j);
      if (arg[k] < 0) continue;
      bool minimum = true;
      for (int di = -1; di <= 1 && minimum; ++di) {
        for (int dj = -1; dj <= 1; ++dj) {
          const int ii = i + di, jj = (j + dj + nv) % nv;
          if (ii < 0 || ii >= nu || (di == 0 && dj == 0)) continue;
          if (best[static_cast<size_t>(ii * nv + jj)] < best[k]) minimum = false;
        }
      }
      if (!minimum) continue;
      const int jb = arg[k];
      const Eigen::Vector4d seed((i + 0.5) / nu, (j + 0.5) / nv, (jb / nv + 0.5) / nu,
                                 (jb % nv + 0.5) / nv);
      const SurfaceSurfaceExtremum e = SolveSurfaceSurface(
          c.wire, poses[static_cast<size_t>(a)], c.wire, poses[static_cast<size_t>(b)], seed);
      if (e.status != ExtremalStatus::kConverged || !(e.beta < opt.activation) ||
          !(e.beta > -opt.max_penetration) || !(e.alignment < 0.0)) {
        continue;
      }
      bool dup = false;
      for (const GlobalContact& o : out) dup = dup || (o.p_a - e.p_f).norm() < 1e-8;
      if (!dup) out.push_back({a, b, e.u, e.beta, e.p_f, e.p_g});
    }
  }
  return out;
}

TEST(GlobalTest, ThreeClipsMatchTheBruteForceReferenceOverAThousandConfigurations) {
  const Clips c;
  const testing::PaperclipChainPoses chain;
  GlobalOptions opt;
  GlobalContactStage stage(c.Surfaces(3), {{0, 1}, {1, 2}, {0, 2}}, opt);
  std::mt19937_64 rng(51);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int configurations = 0, reference_total = 0, found_total = 0, missed = 0, duplicates = 0,
      extra = 0;
  double worst_position = 0.0, beta_lo = 1.0, beta_hi = -1.0;
  int deep_reference = 0, deep_found = 0;
  std::vector<ContactEvent> events;
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<Vector7d> q(chain.clip, chain.clip + 3);
    for (int k = 1; k < 3; ++k) {  // clips 1 and 2 jiggled around their hooks
      const Eigen::Quaterniond r0(q[k][3], q[k][4], q[k][5], q[k][6]);
      const Eigen::Quaterniond r =
          Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * u(rng), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(0.05 * u(rng), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.05 * u(rng), Eigen::Vector3d::UnitZ())) *
          r0;
      q[k] = testing::Coordinates(
          q[k].head<3>() + 0.3 * mm * Eigen::Vector3d(u(rng), u(rng), u(rng)), r);
    }
    const std::vector<BodyPose> poses = Poses(q);
    stage.Run(poses, {}, &events);
    ++configurations;
    std::vector<GlobalContact> reference;
    for (const auto& [a, b] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{0, 2}}) {
      const std::vector<GlobalContact> r = Reference(c, poses, a, b, opt);
      reference.insert(reference.end(), r.begin(), r.end());
    }
    reference_total += static_cast<int>(reference.size());
    for (const GlobalContact& r : reference) {
      beta_lo = std::min(beta_lo, r.beta);
      beta_hi = std::max(beta_hi, r.beta);
    }
    found_total += static_cast<int>(stage.found().size());
    // Matching over near contacts, −0.3 mm < β: deeper, several extremal pairs with facing
    // normals can exist and which one a seed reaches is not unique (counted apart).
    const double near = -0.3 * mm;
    for (const GlobalContact& r : reference) {
      if (r.beta <= near) {
        ++deep_reference;
        continue;
      }
      int matches = 0;
      for (const GlobalContact& f : stage.found()) {
        if (f.a == r.a && f.b == r.b && (f.p_a - r.p_a).norm() < 1e-6) {
          ++matches;
          worst_position =
              std::max({worst_position, (f.p_a - r.p_a).norm(), (f.p_b - r.p_b).norm()});
        }
      }
      missed += matches == 0;
      if (matches == 0 && missed <= 8) {
        GlobalStats gs;
        stage.Run(poses, {}, &events, &gs);
        std::printf(
            "  missed: pair %d-%d beta %.3e u %.4f %.4f %.4f %.4f; stage: tri pairs %d "
            "neglected %d refined %d found %d\n",
            r.a, r.b, r.beta, r.u[0], r.u[1], r.u[2], r.u[3], gs.triangle_pairs, gs.seeds_neglected,
            gs.seeds_refined, gs.found);
      }
      duplicates += matches > 1;
    }
    for (const GlobalContact& f : stage.found()) {
      if (f.beta <= near) {
        ++deep_found;
        continue;
      }
      bool in_reference = false;
      for (const GlobalContact& r : reference) {
        in_reference = in_reference || (f.a == r.a && f.b == r.b && (f.p_a - r.p_a).norm() < 1e-6);
      }
      extra += !in_reference;
    }
    ASSERT_EQ(events.size(), stage.found().size());  // nothing tracked: every contact is new
  }
  std::printf(
      "global stage, %d configurations: %d reference contacts, %d found, %d missed, %d "
      "duplicated, %d not in the reference, worst position difference %.1e m, beta from %.3f to "
      "%.3f mm; deeper than 0.3 mm: %d in the reference, %d found\n",
      configurations, reference_total, found_total, missed, duplicates, extra, worst_position,
      beta_lo / mm, beta_hi / mm, deep_reference, deep_found);
  EXPECT_GE(configurations, 1000);
  EXPECT_GT(reference_total, 1000);  // most configurations are in contact
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(duplicates, 0);
  EXPECT_EQ(extra, 0);
  EXPECT_LE(worst_position, 1e-9);
}

// Clip b standing upright across clip a's inner loop: b's plane is vertical (its x down, its y
// along world x), so its lowest leg (own x = 1.5 mm) runs along world x at y = 10 mm and crosses
// a's two inner legs, at x = 0 and x = 1.5 mm (1.5 mm apart), touching both from above; the rest
// of b is higher.
std::vector<BodyPose> AcrossTheInnerLoop(double gap) {
  Eigen::Matrix3d R;
  R.col(0) = -Eigen::Vector3d::UnitZ();
  R.col(1) = Eigen::Vector3d::UnitX();
  R.col(2) = R.col(0).cross(R.col(1));
  return Poses({testing::Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()),
                testing::Coordinates(Eigen::Vector3d(4 * mm, 10 * mm, 2.4 * mm + gap),
                                     Eigen::Quaterniond(R))});
}

TEST(GlobalTest, InnerAndOuterLoopGiveTwoContactsNotOne) {
  const Clips c;
  GlobalOptions opt;
  opt.neglect_radius = 4 * mm;  // every seed of both crossings inside one sphere of neglect
  GlobalContactStage stage(c.Surfaces(2), {{0, 1}}, opt);
  std::vector<ContactEvent> events;
  GlobalStats st;
  stage.Run(AcrossTheInnerLoop(0.0), {}, &events, &st);
  ASSERT_EQ(stage.found().size(), 2u);
  EXPECT_NEAR((stage.found()[0].p_a - stage.found()[1].p_a).norm(), 1.5 * mm, 0.05 * mm);
  EXPECT_GT(st.seeds_neglected, 0);
  // With one crossing tracked, the blocks around it are skipped (any contact there would be the
  // tracked one) and the other crossing, 1.5 mm away in space but on the other loop, is added.
  const std::vector<GlobalContact> both = stage.found();
  for (int k = 0; k < 2; ++k) {
    stage.Run(AcrossTheInnerLoop(0.0), {both[static_cast<size_t>(k)]}, &events, &st);
    EXPECT_GT(st.chunk_pairs_skipped, 0);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, ContactEvent::Kind::kAdded);
    EXPECT_LT((events[0].contact.p_a - both[static_cast<size_t>(1 - k)].p_a).norm(), 1e-9);
  }
}

TEST(GlobalTest, GrazingHysteresisAndDeepInterpenetrationEvents) {
  const Clips c;
  const GlobalOptions opt;  // activation 0.1 mm, release 0.2 mm
  GlobalContactStage stage(c.Surfaces(2), {{0, 1}}, opt);
  std::vector<ContactEvent> events;
  auto run = [&](double gap, const std::vector<GlobalContact>& tracked) {
    stage.Run(AcrossTheInnerLoop(gap), tracked, &events);
    return events;
  };
  // Grazing (β = 0): both crossings added.
  std::vector<ContactEvent> e = run(0.0, {});
  ASSERT_EQ(e.size(), 2u);
  std::vector<GlobalContact> tracked;
  for (const ContactEvent& ev : e) {
    EXPECT_EQ(ev.kind, ContactEvent::Kind::kAdded);
    EXPECT_NEAR(ev.contact.beta, 0.0, 1e-12);
    tracked.push_back(ev.contact);
  }
  // Between activation and release: nothing happens (hysteresis), whether tracked or not.
  EXPECT_TRUE(run(0.15 * mm, tracked).empty());
  EXPECT_TRUE(run(0.15 * mm, {}).empty());
  // Beyond release: both removed as separated.
  e = run(0.25 * mm, tracked);
  ASSERT_EQ(e.size(), 2u);
  for (size_t i = 0; i < e.size(); ++i) {
    EXPECT_EQ(e[i].kind, ContactEvent::Kind::kRemoved);
    EXPECT_EQ(e[i].reason, ContactEvent::Reason::kSeparated);
    // Named by the parameters it is tracked at (its owner matches it by them), distance now.
    EXPECT_EQ(e[i].contact.u, tracked[i].u);
    EXPECT_NEAR(e[i].contact.beta, 0.25 * mm, 1e-9);
  }
  // Deep interpenetration (centre lines 0.5 mm apart, β = −0.4 mm, the wires overlapping by
  // almost half their diameter): found and added; the far sides' pairs (β ≈ −1.3 mm) are not.
  e = run(-0.4 * mm, {});
  ASSERT_EQ(e.size(), 2u);
  for (const ContactEvent& ev : e) {
    EXPECT_EQ(ev.kind, ContactEvent::Kind::kAdded);
    EXPECT_NEAR(ev.contact.beta, -0.4 * mm, 1e-9);
  }
}

// Near misses (docs/contact.md, "Near misses"): clip b 0.15 mm over both of a's inner legs, apart
// by more than the activation distance (0.1 mm) and within the offsets' reach (2 x 0.27 mm).
TEST(GlobalTest, NearMissesAreCarriedFromPassToPassAndSkipTheirBlocks) {
  const Clips c;
  const GlobalOptions opt;
  GlobalContactStage stage(c.Surfaces(2), {{0, 1}}, opt);
  std::vector<ContactEvent> events;
  GlobalStats first, st;
  auto nearest = [&] {
    EXPECT_EQ(stage.viewed().size(), 1u);
    return stage.viewed().empty() ? 0.0 : stage.viewed()[0].nearest;
  };
  // First pass: the narrow phase and a refinement per crossing find both near misses.
  stage.Run(AcrossTheInnerLoop(0.15 * mm), {}, &events, &first);
  EXPECT_TRUE(stage.found().empty());
  EXPECT_EQ(first.near_misses, 0);
  EXPECT_GT(first.chunk_pairs_tested, 0);
  EXPECT_GE(first.seeds_refined, 2);
  EXPECT_NEAR(nearest(), 0.15 * mm, 1e-9);
  // Then each is re-solved where it moved, and the blocks round it skip the narrow phase.
  for (double gap : {0.15 * mm, 0.12 * mm, 0.18 * mm}) {
    stage.Run(AcrossTheInnerLoop(gap), {}, &events, &st);
    EXPECT_TRUE(stage.found().empty());
    EXPECT_EQ(st.near_misses, 2);
    EXPECT_EQ(st.chunk_pairs_tested, 0);
    EXPECT_EQ(st.seeds_refined, 0);
    EXPECT_NEAR(nearest(), gap, 1e-9);
  }
  // Nearer than the activation distance they are contacts, on the points a stage that carries
  // nothing finds from its seeds.
  GlobalOptions fresh_options = opt;
  fresh_options.near_misses = false;
  GlobalContactStage fresh(c.Surfaces(2), {{0, 1}}, fresh_options);
  stage.Run(AcrossTheInnerLoop(0.05 * mm), {}, &events, &st);
  fresh.Run(AcrossTheInnerLoop(0.05 * mm), {}, &events);
  EXPECT_EQ(st.near_misses, 2);
  EXPECT_EQ(st.chunk_pairs_tested, 0);
  ASSERT_EQ(stage.found().size(), 2u);
  ASSERT_EQ(fresh.found().size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(stage.found()[k].beta, 0.05 * mm, 1e-12);
    EXPECT_LT((stage.found()[k].p_a - fresh.found()[k].p_a).norm(), 1e-12);
    EXPECT_LT((stage.found()[k].p_b - fresh.found()[k].p_b).norm(), 1e-12);
  }
  // Beyond the offsets' reach nothing is carried: back within it, the pass starts afresh.
  stage.Run(AcrossTheInnerLoop(1.0 * mm), {}, &events, &st);
  EXPECT_EQ(st.near_misses, 0);
  stage.Run(AcrossTheInnerLoop(0.15 * mm), {}, &events, &st);
  EXPECT_EQ(st.near_misses, 0);
  EXPECT_EQ(st.chunk_pairs_tested, first.chunk_pairs_tested);
  // Without near misses every pass is the first.
  for (int k = 0; k < 2; ++k) {
    fresh.Run(AcrossTheInnerLoop(0.15 * mm), {}, &events, &st);
    EXPECT_EQ(st.near_misses, 0);
    EXPECT_EQ(st.chunk_pairs_tested, first.chunk_pairs_tested);
  }
}

TEST(GlobalTest, ATrackedContactRemovedAsSeparatedIsCarriedAsANearMiss) {
  const Clips c;
  GlobalContactStage stage(c.Surfaces(2), {{0, 1}}, GlobalOptions{});
  std::vector<ContactEvent> events;
  GlobalStats st;
  stage.Run(AcrossTheInnerLoop(0.0), {}, &events);
  ASSERT_EQ(events.size(), 2u);
  std::vector<GlobalContact> tracked;
  for (const ContactEvent& e : events) tracked.push_back(e.contact);
  // Beyond the release distance both are removed; the next pass re-solves them rather than
  // searching their blocks again, and finds them in contact.
  stage.Run(AcrossTheInnerLoop(0.25 * mm), tracked, &events);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].reason, ContactEvent::Reason::kSeparated);
  stage.Run(AcrossTheInnerLoop(0.05 * mm), {}, &events, &st);
  EXPECT_EQ(st.near_misses, 2);
  EXPECT_EQ(st.chunk_pairs_tested, 0);
  ASSERT_EQ(events.size(), 2u);
  for (const ContactEvent& e : events) {
    EXPECT_EQ(e.kind, ContactEvent::Kind::kAdded);
    EXPECT_NEAR(e.contact.beta, 0.05 * mm, 1e-12);
  }
}

// A pass tests the block pairs nearest first and refines each new cluster at once: what it
// finds skips the blocks round it, in a pass that carries nothing and tracks nothing.
TEST(GlobalTest, AFreshPassSkipsTheBlocksRoundWhatItFinds) {
  const Clips c;
  GlobalOptions opt;
  opt.near_misses = false;
  GlobalContactStage stage(c.Surfaces(2), {{0, 1}}, opt);
  std::vector<ContactEvent> events;
  GlobalStats st;
  stage.Run(AcrossTheInnerLoop(-0.2 * mm), {}, &events, &st);
  ASSERT_EQ(stage.found().size(), 2u);
  EXPECT_GT(st.chunk_pairs_skipped, st.chunk_pairs_tested);
  EXPECT_EQ(st.seeds_refined, 2);
  std::printf(
      "fresh pass, two crossings 0.2 mm deep: %d block pairs tested, %d skipped, %d "
      "refinements\n",
      st.chunk_pairs_tested, st.chunk_pairs_skipped, st.seeds_refined);
}

// The broad phase's sweep over many near blocks pairs the same blocks as every one against
// every other: over 200 seeded configurations of three clips, the same block pairs tested and
// skipped and the same contacts found, with the sweep always and never.
TEST(GlobalTest, TheBlockSweepPairsWhatEveryOneAgainstEveryOtherPairs) {
  const Clips c;
  const testing::PaperclipChainPoses chain;
  GlobalOptions always, never;
  always.sweep_above = 0;
  never.sweep_above = 1 << 30;
  GlobalContactStage swept(c.Surfaces(3), {{0, 1}, {1, 2}, {0, 2}}, always);
  GlobalContactStage all(c.Surfaces(3), {{0, 1}, {1, 2}, {0, 2}}, never);
  std::mt19937_64 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<ContactEvent> events;
  int blocks = 0, found = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vector7d> q(chain.clip, chain.clip + 3);
    for (int k = 1; k < 3; ++k) {
      q[k].head<3>() += 0.3 * mm * Eigen::Vector3d(u(rng), u(rng), u(rng));
    }
    const std::vector<BodyPose> poses = Poses(q);
    GlobalStats a, b;
    swept.Run(poses, {}, &events, &a);
    all.Run(poses, {}, &events, &b);
    ASSERT_EQ(a.chunk_pairs_tested + a.chunk_pairs_skipped,
              b.chunk_pairs_tested + b.chunk_pairs_skipped);
    ASSERT_EQ(swept.found().size(), all.found().size());
    for (size_t k = 0; k < all.found().size(); ++k) {
      EXPECT_LT((swept.found()[k].p_a - all.found()[k].p_a).norm(), 1e-12);
    }
    blocks += b.chunk_pairs_tested + b.chunk_pairs_skipped;
    found += static_cast<int>(all.found().size());
  }
  EXPECT_GT(blocks, 1000);
  EXPECT_GT(found, 100);
}

TEST(GlobalTest, OnlyDeclaredPairsAreTested) {
  const Clips c;
  GlobalContactStage stage(c.Surfaces(2), {}, GlobalOptions{});
  std::vector<ContactEvent> events;
  GlobalStats st;
  stage.Run(AcrossTheInnerLoop(0.0), {}, &events, &st);
  EXPECT_EQ(st.candidate_pairs, 0);
  EXPECT_TRUE(stage.found().empty());
}

TEST(GlobalTest, ABodyPairTestsEveryFacePairOfItsBodiesAndNoOther) {
  // Body 0 has one wire, body 1 two (the same wire twice): a body pair (0, 1) finds what the
  // surface pairs (0, 1) and (0, 2) find, declared one by one, and never tests (1, 2).
  const Clips c;
  std::vector<GlobalSurface> surfaces = c.Surfaces(2);
  surfaces.push_back({1, &c.wire, &c.mesh});
  GlobalContactStage bodies(surfaces, {}, {{1, 0}}, GlobalOptions{});
  GlobalContactStage faces(surfaces, {{0, 1}, {2, 0}}, GlobalOptions{});
  std::vector<ContactEvent> e_bodies, e_faces;
  GlobalStats st_bodies, st_faces;
  bodies.Run(AcrossTheInnerLoop(0.0), {}, &e_bodies, &st_bodies);
  faces.Run(AcrossTheInnerLoop(0.0), {}, &e_faces, &st_faces);
  EXPECT_EQ(st_bodies.candidate_pairs, 2);
  EXPECT_EQ(st_faces.candidate_pairs, 2);
  ASSERT_EQ(e_bodies.size(), 4u);  // two contacts on each face pair
  ASSERT_EQ(e_bodies.size(), e_faces.size());
  for (size_t i = 0; i < e_bodies.size(); ++i) {
    EXPECT_EQ(e_bodies[i].contact.a, e_faces[i].contact.a);
    EXPECT_EQ(e_bodies[i].contact.b, e_faces[i].contact.b);
    EXPECT_EQ(e_bodies[i].contact.u, e_faces[i].contact.u);
    EXPECT_EQ(e_bodies[i].contact.a, 0);
  }
  // A body pair needs the offset meshes of all its bodies' surfaces; it names two bodies.
  surfaces[2].mesh = nullptr;
  try {
    GlobalContactStage s(surfaces, {}, {{0, 1}}, GlobalOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "global contact: surface 2 is in a declared pair but has no offset mesh");
  }
  GlobalContactStage without(surfaces, {{0, 1}}, {}, GlobalOptions{});  // not needed otherwise
  try {
    GlobalContactStage s(c.Surfaces(2), {}, {{1, 1}}, GlobalOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "global contact: body pair (1, 1) does not name two bodies");
  }
}

TEST(GlobalTest, AContactHeldOnATrimmedFacesBorderIsKeptNotRefound) {
  // A cylinder wall (radius 5 mm, 10 mm high) whose material is its whole domain, as an
  // imported face's, and a 2 mm ball 0.05 mm off its top rim from outside and above: the wall's
  // extremum is held on its border v = 1, the material's edge there. Found once, then kept pass
  // after pass (it was removed as gone from the domain and found again every pass). The same
  // surface untrimmed has no edge there: its border is where the surface ends.
  const nurbs::NurbsSurface wall = nurbs::MakeCylinder(5 * mm, 10 * mm);
  const nurbs::TrimmedDomain whole({0, 0}, {1, 1}, std::nullopt, {});
  const nurbs::OffsetMesh wall_mesh = nurbs::MakeOffsetMesh(wall, 20e-6, 0.25e-3, 0.5e-3);
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 2 * mm);
  const nurbs::OffsetMesh ball_mesh = nurbs::MakeOffsetMesh(ball, 20e-6, 0.25e-3, 0.5e-3);
  Vector7d q_wall, q_ball;
  q_wall << 0, 0, 0, 1, 0, 0, 0;
  const Eigen::Vector3d rim(5 * mm, 0, 10 * mm);
  const Eigen::Vector3d out = Eigen::Vector3d(1 * mm, 0, std::sqrt(3.0) * mm).normalized();
  q_ball << rim + (2 * mm + 0.05 * mm) * out, 1, 0, 0, 0;
  const std::vector<BodyPose> poses = Poses({q_wall, q_ball});
  for (const bool trimmed : {true, false}) {
    SCOPED_TRACE(trimmed ? "trimmed" : "untrimmed");
    GlobalContactStage stage(
        {{0, &wall, &wall_mesh, trimmed ? &whole : nullptr}, {1, &ball, &ball_mesh, nullptr}},
        {{0, 1}}, GlobalOptions{});
    std::vector<ContactEvent> events;
    stage.Run(poses, {}, &events);
    if (!trimmed) {
      EXPECT_TRUE(events.empty());
      continue;
    }
    ASSERT_EQ(events.size(), 1u);
    const GlobalContact c = events[0].contact;
    EXPECT_EQ(events[0].kind, ContactEvent::Kind::kAdded);
    EXPECT_NEAR(c.beta, 0.05 * mm, 1e-12);
    EXPECT_NEAR(c.u[1], 1.0, 1e-12);  // on the wall's top border
    EXPECT_LT((c.p_a - rim).norm(), 1e-12);
    for (int pass = 0; pass < 3; ++pass) {
      stage.Run(poses, {c}, &events);
      EXPECT_TRUE(events.empty()) << pass;
    }
  }
}

TEST(GlobalTest, BadInputIsRejectedWithAMessage) {
  const Clips c;
  GlobalOptions bad;
  bad.release = bad.activation;
  try {
    GlobalContactStage s(c.Surfaces(2), {{0, 1}}, bad);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "global contact: release must exceed activation (hysteresis)");
  }
  try {
    GlobalContactStage s(c.Surfaces(2), {{0, 2}}, GlobalOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "global contact: pair (0, 2) does not name two of the 2 surfaces");
  }
  // A pair's offsets together must reach twice the release distance: one offset may be below it
  // (a face's, reduced below a concave radius of its) if the other makes up for it.
  const nurbs::OffsetMesh thin = nurbs::MakeOffsetMesh(c.wire, 50e-6, 0.05e-3);
  const nurbs::OffsetMesh thick = nurbs::MakeOffsetMesh(c.wire, 50e-6, 0.5e-3);
  ASSERT_LT(thin.offset, GlobalOptions{}.release);
  ASSERT_GE(thin.offset + thick.offset, 2.0 * GlobalOptions{}.release);
  EXPECT_NO_THROW(
      GlobalContactStage({{0, &c.wire, &thin}, {1, &c.wire, &thick}}, {{0, 1}}, GlobalOptions{}));
  try {
    GlobalContactStage s({{0, &c.wire, &thin}, {1, &c.wire, &thin}}, {{0, 1}}, GlobalOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "global contact: surfaces 0 and 1: offsets together below twice the release "
                 "distance");
  }
}

// A ball over a plate with a round hole (a trimmed plane): on the material the contact is the
// face's; over the rim it is the rim's (the trim edge against the ball), with β the ball's
// distance to the rim circle; over the middle of the hole there is none, though the plane
// itself is within reach; lifted off the rim, the tracked edge contact is released.
TEST(GlobalTest, ATrimmedPlateIsTouchedOnlyOnItsMaterialAndAtItsRim) {
  const nurbs::NurbsSurface plate =
      nurbs::MakePlanePatch({-20 * mm, -20 * mm, 0}, {40 * mm, 0, 0}, {0, 40 * mm, 0});
  const nurbs::TrimmedDomain trim(
      {0, 0}, {1, 1}, std::nullopt,
      {nurbs::TrimLoop{{nurbs::MakeCircle2d({0.5, 0.5}, 0.125, true)}}});
  nurbs::OffsetMesh plate_mesh = nurbs::MakeOffsetMesh(plate, 20e-6, 0.25e-3, 0.5e-3);
  plate_mesh.base = nurbs::CutAlongTrim(plate_mesh.base, trim);
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 4 * mm);
  const nurbs::OffsetMesh ball_mesh = nurbs::MakeOffsetMesh(ball, 20e-6, 0.25e-3, 0.5e-3);
  GlobalOptions options;
  options.neglect_radius = 3 * mm;
  GlobalContactStage stage({{0, &plate, &plate_mesh, &trim}, {1, &ball, &ball_mesh, nullptr}},
                           {{0, 1}}, options);
  const BodyPose ground = BodyPose::FromCoordinates(
      testing::Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
  auto at = [](const Eigen::Vector3d& c) {
    return BodyPose::FromCoordinates(testing::Coordinates(c, Eigen::Quaterniond::Identity()));
  };
  std::vector<ContactEvent> events;
  // On the material, 0.05 mm above the plate.
  stage.Run({ground, at({8 * mm, 1 * mm, 4.05 * mm})}, {}, &events);
  ASSERT_EQ(stage.found().size(), 1u);
  EXPECT_NEAR(stage.found()[0].beta, 0.05 * mm, 1e-12);
  EXPECT_TRUE(trim.Contains(stage.found()[0].u.head<2>()));
  // Over the rim: the ball 0.05 mm from the rim circle at (5, 0, 0) mm.
  const double z = std::sqrt(4.05 * 4.05 - 2.5 * 2.5) * mm;
  stage.Run({ground, at({2.5 * mm, 0, z})}, {}, &events);
  ASSERT_EQ(stage.found().size(), 1u);
  const GlobalContact rim = stage.found()[0];
  EXPECT_FALSE(trim.Contains(rim.u.head<2>()));  // the face's point lies over the hole
  EXPECT_NEAR(rim.beta, 0.05 * mm, 1e-12);
  EXPECT_LT((rim.p_a - Eigen::Vector3d(5 * mm, 0, 0)).norm(), 1e-12);  // on the rim
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, ContactEvent::Kind::kAdded);
  // Tracked where it is: kept, also where the rim's extremum lies on a joint of its pieces (the
  // rational circle's quarter points; here its start, and a quarter turn on).
  stage.Run({ground, at({2.5 * mm, 0, z})}, {rim}, &events);
  EXPECT_TRUE(events.empty()) << ToString(events[0].reason);
  stage.Run({ground, at({0, 2.5 * mm, z})}, {}, &events);
  ASSERT_EQ(stage.found().size(), 1u);
  const GlobalContact quarter = stage.found()[0];
  EXPECT_LT((quarter.p_a - Eigen::Vector3d(0, 5 * mm, 0)).norm(), 1e-12);
  stage.Run({ground, at({0, 2.5 * mm, z})}, {quarter}, &events);
  EXPECT_TRUE(events.empty()) << ToString(events[0].reason);
  // Tracked, then lifted 0.3 mm off the rim: released.
  stage.Run({ground, at({2.5 * mm, 0, z + 0.4 * mm})}, {rim}, &events);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, ContactEvent::Kind::kRemoved);
  EXPECT_EQ(events[0].reason, ContactEvent::Reason::kSeparated);
  // In the middle of the hole, its bottom 2 mm below the plate's plane: nothing (the plane
  // there is trimmed away, the rim 1.4 mm off).
  stage.Run({ground, at({0, 0, 2 * mm})}, {}, &events);
  EXPECT_TRUE(stage.found().empty());
  EXPECT_TRUE(events.empty());
}

// Issue 33: nested pairs. A 5 mm ball resting in a 5.05 mm socket, and a 5 mm rod lying in a
// 5.05 mm groove: their offsets contain one another and cross nowhere, so the narrow phase finds
// no triangles. The stage solves such a pair from its samples (FindNested): the ball's contact
// is found at rest, the rod's too (with accept_continuum, as line contacts run it), and nothing
// for a smaller ball nested beyond the activation distance. Without FindNested none is found.
TEST(GlobalTest, NestedPairsAreFoundAtRest) {
  const nurbs::NurbsSurface socket = nurbs::ReversedU(nurbs::MakeSphere({0, 0, 0}, 5.05 * mm));
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 5 * mm);
  const nurbs::OffsetMesh socket_mesh = nurbs::MakeOffsetMesh(socket, 20e-6, 0.25e-3, 0.5e-3);
  const nurbs::OffsetMesh ball_mesh = nurbs::MakeOffsetMesh(ball, 20e-6, 0.25e-3, 0.5e-3);
  GlobalOptions options;
  options.neglect_radius = 6 * mm;
  GlobalContactStage stage({{0, &socket, &socket_mesh, nullptr}, {1, &ball, &ball_mesh, nullptr}},
                           {{0, 1}}, options);
  auto at = [](const Eigen::Vector3d& c) {
    return BodyPose::FromCoordinates(testing::Coordinates(c, Eigen::Quaterniond::Identity()));
  };
  const BodyPose ground = at(Eigen::Vector3d::Zero());
  std::vector<ContactEvent> events;
  GlobalStats stats;
  for (const Eigen::Vector3d& rest :
       {Eigen::Vector3d(0, 0, -0.05 * mm), Eigen::Vector3d(0.03 * mm, 0, -0.04 * mm)}) {
    stage.Run({ground, at(rest)}, {}, &events, &stats);
    EXPECT_EQ(stats.triangle_pairs, 0);  // nothing crosses
    ASSERT_EQ(stage.found().size(), 1u);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].kind, ContactEvent::Kind::kAdded);
    EXPECT_NEAR(stage.found()[0].beta, 0.0, 1e-15);
    // The ball touches where its centre is off the socket's, on that side.
    const Eigen::Vector3d expected = rest + 5 * mm * rest.normalized();
    EXPECT_LT((stage.found()[0].p_b - expected).norm(), 1e-9);
  }
  // A 4.7 mm ball 0.1 mm off the socket's centre: 0.25 mm apart at the nearest, beyond the
  // activation (0.1 mm), and still nested (the offsets, 0.27 mm each, overlap all round): nothing.
  const nurbs::NurbsSurface small = nurbs::MakeSphere({0, 0, 0}, 4.7 * mm);
  const nurbs::OffsetMesh small_mesh = nurbs::MakeOffsetMesh(small, 20e-6, 0.25e-3, 0.5e-3);
  GlobalContactStage apart({{0, &socket, &socket_mesh, nullptr}, {1, &small, &small_mesh, nullptr}},
                           {{0, 1}}, options);
  apart.Run({ground, at({0, 0, -0.1 * mm})}, {}, &events, &stats);
  EXPECT_EQ(stats.triangle_pairs, 0);
  EXPECT_TRUE(apart.found().empty());
  EXPECT_TRUE(events.empty());

  // The rod along the groove: a continuum, taken only with accept_continuum.
  const Eigen::Quaterniond along_x(0.7071067811865476, 0, 0.7071067811865476, 0);
  const nurbs::NurbsSurface groove = nurbs::ReversedU(nurbs::MakeCylinder(5.05 * mm, 40 * mm));
  const nurbs::NurbsSurface rod = nurbs::MakeCylinder(5 * mm, 20 * mm);
  const nurbs::OffsetMesh groove_mesh = nurbs::MakeOffsetMesh(groove, 20e-6, 0.25e-3, 0.5e-3);
  const nurbs::OffsetMesh rod_mesh = nurbs::MakeOffsetMesh(rod, 20e-6, 0.25e-3, 0.5e-3);
  const BodyPose block = BodyPose::FromCoordinates(testing::Coordinates({-20 * mm, 0, 0}, along_x));
  const BodyPose lying =
      BodyPose::FromCoordinates(testing::Coordinates({-10 * mm, 0, -0.05 * mm}, along_x));
  options.accept_continuum = true;
  GlobalContactStage line({{0, &groove, &groove_mesh, nullptr}, {1, &rod, &rod_mesh, nullptr}},
                          {{0, 1}}, options);
  line.Run({block, lying}, {}, &events, &stats);
  EXPECT_EQ(stats.triangle_pairs, 0);
  ASSERT_EQ(line.found().size(), 1u);
  EXPECT_NEAR(line.found()[0].beta, 0.0, 1e-15);
}

// A singular extremum is a continuum the stage takes (accept_continuum) only where the servo
// would hold it as a line: its relative curvature line-like, λ_min < continuum_ratio · λ_max.
// The rod in its groove is (λ_min 0); the ball in its socket is not (λ_min = λ_max), nor a
// crowned peg's end on a hole's wall (λ 50 and 250 /m); with accept_continuum off nothing is.
// (Measured on the peg in hole with every singular extremum taken: the end's contact on the
// wall's border at the rim, singular there, was added and lost again every millisecond, and the
// servo's tick p99 doubled.)
TEST(GlobalTest, ASingularExtremumIsAContinuumOnlyWhereItIsLineLike) {
  const Eigen::Quaterniond along_x(0.7071067811865476, 0, 0.7071067811865476, 0);
  const nurbs::NurbsSurface groove = nurbs::ReversedU(nurbs::MakeCylinder(5.05 * mm, 40 * mm));
  const nurbs::NurbsSurface rod = nurbs::MakeCylinder(5 * mm, 20 * mm);
  const nurbs::NurbsSurface socket = nurbs::ReversedU(nurbs::MakeSphere({0, 0, 0}, 5.05 * mm));
  const nurbs::NurbsSurface ball = nurbs::MakeSphere({0, 0, 0}, 5 * mm);
  const nurbs::NurbsSurface wall = nurbs::ReversedU(nurbs::MakeCylinder(5 * mm, 10 * mm));
  const nurbs::NurbsSurface end = nurbs::MakeSphere({0, 0, 0}, 4 * mm);
  auto pose = [](const Eigen::Vector3d& c, const Eigen::Quaterniond& r) {
    return BodyPose::FromCoordinates(testing::Coordinates(c, r));
  };
  const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
  struct Case {
    const nurbs::NurbsSurface *f, *g;
    BodyPose pf, pg;
    bool line;
  };
  const std::vector<Case> cases = {
      {&groove, &rod, pose({-20 * mm, 0, 0}, along_x), pose({-10 * mm, 0, -0.05 * mm}, along_x),
       true},
      // (Off the spheres' poles: at a pole the relative curvature is not defined.)
      {&socket, &ball, pose({0, 0, 0}, identity), pose({0.05 * mm, 0, 0}, identity), false},
      {&wall, &end, pose({0, 0, 0}, identity), pose({0.9 * mm, 0, 5 * mm}, identity), false}};
  for (const Case& c : cases) {
    SurfacePairEval at;
    SurfaceSurfaceExtremum e = SolveSurfaceSurface(
        *c.f, c.pf, *c.g, c.pg, ClosestSamplePair(*c.f, c.pf, *c.g, c.pg, 8), {}, &at);
    e.status = ExtremalStatus::kSingular;  // (as the solve reports a continuum)
    GlobalOptions options;
    EXPECT_FALSE(internal::LineContinuum(options, e, at));
    options.accept_continuum = true;
    EXPECT_EQ(internal::LineContinuum(options, e, at), c.line);
    const RelativeCurvature rc = RelativeCurvatureOf(at);
    EXPECT_TRUE(rc.valid);
    std::printf("relative curvature %.3g, %.3g /m: %s\n", rc.eigenvalues[0], rc.eigenvalues[1],
                c.line ? "a line" : "no line");
  }
}

}  // namespace
}  // namespace tangent::contact
