#include "server/scene.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <numbers>
#include <set>
#include <sstream>
#include <thread>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "base/json_node.h"
#ifdef TANGENT_WITH_CAD
#include "cad/import.h"
#endif
#include "nurbs/json_io.h"
#include "nurbs/primitives.h"
#include "optimizer/goals.h"
#include "optimizer/joints.h"

namespace tangent::server {

namespace {

using nlohmann::json;

// A JSON value with its path for messages ("scenes/x.json: bodies[1].mass: ...").
using Node = JsonNode<SceneError>;

Eigen::Quaterniond Quaternion(const Node& n) {
  const Eigen::Vector4d q = n.Vector<4>();
  if (std::abs(q.norm() - 1.0) > 1e-6) {
    n.Fail("must be a unit quaternion (w, x, y, z), its norm is " + Node::Format(q.norm()));
  }
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}

Eigen::Isometry3d Placement(const Node& n, double unit) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  if (n.Has("position")) x.translation() = unit * n.At("position").Vector<3>();
  if (n.Has("quaternion")) x.linear() = Quaternion(n.At("quaternion")).toRotationMatrix();
  return x;
}

// A NURBS document's own "trim" (docs/trimming.md), and where it was, for messages.
struct DocumentTrim {
  std::optional<nlohmann::json> json;
  std::string where;
};

nurbs::NurbsSurface MakeSurface(const Node& n, double unit, const std::string& base_dir,
                                DocumentTrim* trim) {
  const std::string type = n.At("type").String();
  try {
    if (type == "paperclip") {
      const double r = n.Number("wire_radius", nurbs::kPaperclipWireRadius / unit) * unit;
      if (!(r > 0.0)) n.At("wire_radius").Fail("must be positive");
      return nurbs::MakeTube(nurbs::PaperclipPath(), r);
    }
    if (type == "sphere") {
      return nurbs::MakeSphere(
          unit * (n.Has("center") ? n.At("center").Vector<3>() : Eigen::Vector3d::Zero()),
          unit * n.Positive("radius", 0.0));
    }
    if (type == "cylinder") {
      return nurbs::MakeCylinder(unit * n.Positive("radius", 0.0),
                                 unit * n.Positive("height", 0.0));
    }
    if (type == "barrel") {
      return nurbs::MakeBarrel(unit * n.Positive("radius", 0.0), unit * n.Positive("height", 0.0),
                               unit * n.Positive("crown", 0.0));
    }
    if (type == "torus") {
      const double R = unit * n.Positive("major", 0.0), r = unit * n.Positive("minor", 0.0);
      if (!(r < R)) n.At("minor").Fail("must be less than \"major\"");
      return nurbs::MakeTorus(R, r);
    }
    if (type == "plane_patch") {
      return nurbs::MakePlanePatch(unit * n.At("origin").Vector<3>(),
                                   unit * n.At("edge_u").Vector<3>(),
                                   unit * n.At("edge_v").Vector<3>());
    }
    if (type == "sheared_patch") {
      return nurbs::MakeShearedPatch(n.Positive("angle_deg", 0.0) * std::numbers::pi / 180.0,
                                     unit * n.Positive("size", 0.0), unit * n.Number("bump", 0.0),
                                     n.Bool("rational", false));
    }
    if (type == "height_grid") {
      const Node h = n.At("heights");
      std::vector<std::vector<double>> heights(h.Size());
      for (size_t i = 0; i < heights.size(); ++i) {
        const Node row = h.At(i);
        for (size_t k = 0; k < row.Size(); ++k) heights[i].push_back(unit * row.At(k).Number());
        if (heights[i].size() != heights[0].size()) row.Fail("rows must have equal lengths");
      }
      if (heights.size() < 4 || heights[0].size() < 4) h.Fail("needs at least 4 x 4 heights");
      const Eigen::Vector2d lo = unit * n.At("corner").Vector<2>();
      const Eigen::Vector2d size = unit * n.At("size").Vector<2>();
      if (!(size.minCoeff() > 0.0)) n.At("size").Fail("must be positive");
      return nurbs::MakeHeightGridPatch(lo[0], lo[1], size[0], size[1], heights);
    }
    if (type == "nurbs") {  // metres, from a file or inline (nurbs/json_io format)
      if (n.Has("file")) {
        std::filesystem::path p = n.At("file").String();
        if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
        const nlohmann::json doc = nurbs::LoadDocument(p.string());  // (read once)
        if (doc.is_object() && doc.contains("trim")) *trim = {doc["trim"], p.string() + ": /trim"};
        return nurbs::SurfaceFromJson(doc, p.string());
      }
      if (n.At("nurbs").Has("trim")) {
        *trim = {n.At("nurbs").At("trim").j, n.where + ": " + n.path + ".nurbs.trim"};
      }
      return nurbs::SurfaceFromJson(n.At("nurbs").j, n.where + ": " + n.path + ".nurbs");
    }
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    n.Fail(e.what());
  }
  n.At("type").Fail("unknown surface type \"" + type +
                    "\" (paperclip, sphere, cylinder, barrel, torus, plane_patch, sheared_patch, "
                    "height_grid, nurbs)");
}

optimizer::Attachment ParseAttachment(const Node& n, const Scene& s, double unit) {
  optimizer::Attachment a;
  const std::string body = n.At("body").String();
  a.body = s.BodyIndex(body);
  if (a.body < 0) n.At("body").Fail("no body named \"" + body + "\"");
  if (n.Has("point")) a.point = unit * n.At("point").Vector<3>();
  if (n.Has("axis")) {
    a.axis = n.At("axis").Vector<3>();
    if (!(a.axis.norm() > 0.0)) n.At("axis").Fail("must not be zero");
    a.axis.normalize();
  }
  if (n.Has("reference")) {
    a.reference = n.At("reference").Vector<3>();
    if (!(a.reference.norm() > 0.0)) n.At("reference").Fail("must not be zero");
    a.reference.normalize();
  }
  return a;
}

}  // namespace

int Scene::BodyIndex(const std::string& n) const {
  for (int i = 0; i < mechanism.num_bodies(); ++i) {
    if (mechanism.body(i).name == n) return i;
  }
  return -1;
}

int Scene::SurfaceIndex(const std::string& n) const {
  for (size_t i = 0; i < surfaces.size(); ++i) {
    if (surfaces[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

int Scene::JointIndex(const std::string& n) const {
  for (size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// The bodies: names, placements, masses, inertia, rigidity.
void ParseBodies(const Node& root, double unit, Scene* out) {
  Scene& s = *out;
  const Node bodies = root.At("bodies");
  if (bodies.Size() == 0) bodies.Fail("a scene needs at least one body");
  for (size_t i = 0; i < bodies.Size(); ++i) {
    const Node b = bodies.At(i);
    optimizer::Body body;
    body.name = b.At("name").String();
    if (s.BodyIndex(body.name) >= 0) b.At("name").Fail("duplicate body name \"" + body.name + "\"");
    body.fixed = b.Bool("fixed", false);
    const Eigen::Isometry3d x = Placement(b, unit);
    const Eigen::Quaterniond q(x.rotation());
    body.pose << x.translation(), q.w(), q.x(), q.y(), q.z();
    body.mass = b.Positive("mass", 1.0);
    if (b.Has("inertia")) {
      const Eigen::Vector3d d = b.At("inertia").Vector<3>();
      if (!(d.minCoeff() > 0.0)) b.At("inertia").Fail("principal moments must be positive");
      body.inertia = d.asDiagonal();
    }
    body.rigidity = b.Number("rigidity", 1.0);
    if (body.rigidity < 0.0) b.At("rigidity").Fail("must not be negative");
    try {
      s.mechanism.AddBody(body);
    } catch (const std::exception& e) {
      b.Fail(e.what());
    }
  }
  if (s.mechanism.num_moving() == 0) bodies.Fail("no moving body: nothing to manipulate");
}

// The surfaces, each on a body.
void ParseSurfaces(const Node& root, double unit, const std::string& base_dir, Scene* out) {
  Scene& s = *out;
  const Node surfaces = root.At("surfaces");
  for (size_t i = 0; i < surfaces.Size(); ++i) {
    const Node n = surfaces.At(i);
    const std::string name = n.At("name").String();
    if (s.SurfaceIndex(name) >= 0) n.At("name").Fail("duplicate surface name \"" + name + "\"");
    const std::string body = n.At("body").String();
    const int b = s.BodyIndex(body);
    if (b < 0) n.At("body").Fail("no body named \"" + body + "\"");
    DocumentTrim document_trim;
    nurbs::NurbsSurface local = MakeSurface(n, unit, base_dir, &document_trim);
    // Its outward side (the normal) turned over: a cylinder as the wall of a hole.
    if (n.Bool("reverse_normal", false)) local = nurbs::ReversedU(local);
    Eigen::Isometry3d X = Placement(n, unit);
    if (n.Has("centre_at")) {
      // Place the surface so its parameter-domain centre lands on this body-frame point.
      if (n.Has("position")) n.At("centre_at").Fail("give either \"position\" or \"centre_at\"");
      const double u = 0.5 * (local.knots_u().domain_begin() + local.knots_u().domain_end());
      const double v = 0.5 * (local.knots_v().domain_begin() + local.knots_v().domain_end());
      X.translation() =
          unit * n.At("centre_at").Vector<3>() - X.linear() * local.Evaluate(u, v, 0).S;
    }
    s.surfaces.push_back(SceneSurface{name, b, nurbs::Transformed(local, X), {}, false, {}});
    // Trims: in the entry, or in the NURBS document (a file's or the inline one's).
    std::optional<nlohmann::json> trim = document_trim.json;
    std::string trim_where = document_trim.where;
    if (n.Has("trim")) {
      trim = n.At("trim").j;
      trim_where = n.where + ": " + n.path + ".trim";
    }
    if (trim) {
      SceneSurface& ss = s.surfaces.back();
      try {
        ss.trim = nurbs::TrimFromJson(*trim, ss.surface, trim_where, &s.load_log);
      } catch (const nurbs::ParseError& e) {
        throw SceneError(e.what());
      }
      const int holes = static_cast<int>(ss.trim->loops().size()) - (ss.trim->has_outer() ? 1 : 0);
      s.load_log.push_back("surface " + name + ": trimmed (" +
                           (ss.trim->has_outer() ? "an outer loop, " : "") + std::to_string(holes) +
                           " hole(s), " + std::to_string(ss.trim->chords().size()) +
                           " certified chords)");
    }
  }
}

// Bodies made of a CAD part (docs/cad.md): every face of the file a trimmed surface on the body,
// its coordinates taken in the body's frame (metres, whatever the file's unit).
void ParseCadBodies(const Node& root, const std::string& base_dir, Scene* out) {
  [[maybe_unused]] Scene& s = *out;  // (unused without CAD import)
  const Node bodies = root.At("bodies");
  for (size_t i = 0; i < bodies.Size(); ++i) {
    const Node b = bodies.At(i);
    if (!b.Has("cad")) continue;
#ifndef TANGENT_WITH_CAD
    (void)base_dir;
    b.At("cad").Fail("this build has no CAD import (configure with -DTANGENT_WITH_OCCT=ON)");
#else
    std::filesystem::path p = b.At("cad").String();
    if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
    cad::ImportedPart part;
    try {
      part = cad::ImportCad(p.string());
    } catch (const cad::ImportError& e) {
      b.At("cad").Fail(e.what());
    }
    const std::string body = b.At("name").String();
    const int index = s.BodyIndex(body);
    int faces = 0;
    for (const cad::ImportedBody& ib : part.bodies) {
      for (const cad::ImportedFace& f : ib.faces) {
        const std::string name = body + "/" + f.name;
        if (s.SurfaceIndex(name) >= 0) b.At("cad").Fail("duplicate surface name \"" + name + "\"");
        s.surfaces.push_back(SceneSurface{name, index, f.surface, {}, false, f.trim});
        ++faces;
      }
    }
    char line[256];
    std::snprintf(line, sizeof line,
                  "body %s: %d faces from %s (%d skipped, largest deviation from Open CASCADE "
                  "%.2g m)",
                  body.c_str(), faces, p.string().c_str(), part.report.skipped,
                  part.report.largest_deviation);
    s.load_log.emplace_back(line);
    for (const std::string& w : part.report.warnings)
      s.load_log.push_back("body " + body + ": " + w);
#endif
  }
}

// The joints between bodies.
void ParseJoints(const Node& root, double unit, Scene* out) {
  Scene& s = *out;
  if (root.Has("joints")) {
    const Node joints = root.At("joints");
    for (size_t i = 0; i < joints.Size(); ++i) {
      const Node n = joints.At(i);
      JointSpec js;
      js.name = n.String("name", "joint " + std::to_string(i));
      if (s.JointIndex(js.name) >= 0) n.At("name").Fail("duplicate joint name \"" + js.name + "\"");
      js.type = n.At("type").String();
      const optimizer::Attachment a = ParseAttachment(n.At("a"), s, unit);
      const optimizer::Attachment b = ParseAttachment(n.At("b"), s, unit);
      js.a = a;
      js.b = b;
      if (a.body == b.body) n.Fail("joins a body to itself");
      try {
        js.term = optimizer::MakeJoint(js.type, a, b);
      } catch (const std::invalid_argument& e) {
        n.At("type").Fail(e.what());
      }
      if (n.Has("limits_deg")) {
        if (js.type != "revolute") n.At("limits_deg").Fail("limits apply to revolute joints only");
        const Eigen::Vector2d l = n.At("limits_deg").Vector<2>() * std::numbers::pi / 180.0;
        if (!(l[0] < l[1])) n.At("limits_deg").Fail("lower limit must be below the upper");
        js.limits = optimizer::RevoluteLimits(a, b, l[0], l[1]);
        js.limit_lo = l[0];
        js.limit_hi = l[1];
      }
      s.joints.push_back(std::move(js));
    }
  }
}

// A contact declaration's "max_contacts" (slots reserved), or `fallback`.
int MaxContacts(const Node& n, int fallback) {
  if (!n.Has("max_contacts")) return fallback;
  const double m = n.At("max_contacts").Number();
  if (!(m >= 1 && m <= 8 && m == std::floor(m))) {
    n.At("max_contacts").Fail("must be an integer from 1 to 8");
  }
  return static_cast<int>(m);
}

// A contact between two bodies ({"bodies": [A, B], "max_contacts": n}): all the faces of both
// are watched.
void ParseBodyPair(const Node& n, std::set<std::pair<int, int>>* seen, Scene* out) {
  Scene& s = *out;
  n.OnlyKeys({"bodies", "kind", "max_contacts", "comment"});
  const Node bodies = n.At("bodies");
  if (bodies.Size() != 2) bodies.Fail("must name two bodies");
  BodyPairSpec c;
  for (size_t k = 0; k < 2; ++k) {
    const std::string name = bodies.At(k).String();
    const int b = s.BodyIndex(name);
    if (b < 0) bodies.At(k).Fail("no body named \"" + name + "\"");
    bool has_surface = false;
    for (const SceneSurface& sf : s.surfaces) has_surface = has_surface || sf.body == b;
    if (!has_surface) bodies.At(k).Fail("body \"" + name + "\" has no surfaces");
    (k == 0 ? c.body_a : c.body_b) = b;
  }
  if (c.body_a == c.body_b) bodies.Fail("names one body twice");
  if (s.mechanism.body(c.body_a).fixed && s.mechanism.body(c.body_b).fixed) {
    n.Fail("both bodies are fixed: they can never meet");
  }
  if (!seen->insert({std::min(c.body_a, c.body_b), std::max(c.body_a, c.body_b)}).second) {
    n.Fail("body pair declared twice");
  }
  const std::string kind = n.String("kind", "unilateral");
  if (kind != "unilateral") {
    n.At("kind").Fail("a body pair is \"unilateral\" (non-penetration), got \"" + kind + "\"");
  }
  c.max_contacts = MaxContacts(n, c.max_contacts);
  for (SceneSurface& sf : s.surfaces) {
    if (sf.body == c.body_a || sf.body == c.body_b) sf.watched = true;
  }
  s.body_pairs.push_back(c);
}

// The contact pairs that may occur.
void ParsePairs(const Node& root, Scene* out) {
  Scene& s = *out;
  if (root.Has("contacts")) {
    const Node contacts = root.At("contacts");
    std::set<std::pair<int, int>> seen;
    std::set<std::pair<int, int>> body_pairs;
    std::vector<size_t> pair_nodes;
    for (size_t i = 0; i < contacts.Size(); ++i) {
      const Node n = contacts.At(i);
      if (n.Has("bodies")) {
        ParseBodyPair(n, &body_pairs, out);
        continue;
      }
      ContactPairSpec c;
      for (const char* key : {"a", "b"}) {
        const std::string name = n.At(key).String();
        const int k = s.SurfaceIndex(name);
        if (k < 0) n.At(key).Fail("no surface named \"" + name + "\"");
        (key[0] == 'a' ? c.surface_a : c.surface_b) = k;
      }
      const SceneSurface& sa = s.surfaces[static_cast<size_t>(c.surface_a)];
      const SceneSurface& sb = s.surfaces[static_cast<size_t>(c.surface_b)];
      if (sa.body == sb.body)
        n.Fail("both surfaces are on body \"" + s.mechanism.body(sa.body).name + "\"");
      if (s.mechanism.body(sa.body).fixed && s.mechanism.body(sb.body).fixed) {
        n.Fail("both surfaces are on fixed bodies: they can never meet");
      }
      if (!seen.insert({std::min(c.surface_a, c.surface_b), std::max(c.surface_a, c.surface_b)})
               .second) {
        n.Fail("pair declared twice");
      }
      const std::string kind = n.String("kind", "unilateral");
      if (kind == "floating") {
        c.kind = ContactPairSpec::Kind::kFloating;
        c.max_contacts = 1;
      } else if (kind != "unilateral") {
        n.At("kind").Fail("must be \"unilateral\" or \"floating\", got \"" + kind + "\"");
      }
      c.max_contacts = MaxContacts(n, c.max_contacts);
      s.surfaces[static_cast<size_t>(c.surface_a)].watched = true;
      s.surfaces[static_cast<size_t>(c.surface_b)].watched = true;
      s.pairs.push_back(c);
      pair_nodes.push_back(i);
    }
    // A face pair of two bodies declared as a pair is already theirs: declaring it again would
    // give one contact two slots. (pair_nodes[k]: the declaration of s.pairs[k].)
    for (size_t k = 0; k < s.pairs.size(); ++k) {
      const int ba = s.surfaces[static_cast<size_t>(s.pairs[k].surface_a)].body;
      const int bb = s.surfaces[static_cast<size_t>(s.pairs[k].surface_b)].body;
      if (body_pairs.count({std::min(ba, bb), std::max(ba, bb)})) {
        contacts.At(pair_nodes[k])
            .Fail("its bodies \"" + s.mechanism.body(ba).name + "\" and \"" +
                  s.mechanism.body(bb).name +
                  "\" are declared as a pair: their faces' contacts are theirs");
      }
    }
  }
}

// The grasp.
void ParseGrasp(const Node& root, double unit, Scene* out) {
  Scene& s = *out;
  {
    const Node g = root.At("grasp");
    const std::string body = g.At("body").String();
    s.grasp.body = s.BodyIndex(body);
    if (s.grasp.body < 0) g.At("body").Fail("no body named \"" + body + "\"");
    if (s.mechanism.body(s.grasp.body).fixed) g.At("body").Fail("the grasped body is fixed");
    if (g.Has("point")) s.grasp.point = unit * g.At("point").Vector<3>();
    s.grasp.hold_orientation = g.Number("hold_orientation", 0.0);
    if (s.grasp.hold_orientation < 0.0) g.At("hold_orientation").Fail("must not be negative");
    s.grasp.rotational_stiffness = g.Positive("rotational_stiffness", s.grasp.rotational_stiffness);
  }
}

// Objectives (weighted goals besides the grasp).
void ParseObjectives(const Node& root, double unit, Scene* out) {
  Scene& s = *out;
  if (root.Has("objectives")) {
    const Node objectives = root.At("objectives");
    for (size_t i = 0; i < objectives.Size(); ++i) {
      const Node n = objectives.At(i);
      const std::string type = n.At("type").String();
      const double w = n.Number("weight", 1.0);
      if (!(w >= 0.0)) n.At("weight").Fail("must not be negative");
      const optimizer::Attachment a = ParseAttachment(n, s, unit);
      if (type == "hold_orientation") {
        const contact::Vector7d& pose = s.mechanism.body(a.body).pose;
        s.objectives.push_back(
            {optimizer::OrientationGoal(
                 a.body, Eigen::Quaterniond(pose[3], pose[4], pose[5], pose[6]).toRotationMatrix(),
                 Eigen::Vector3d::Ones()),
             w});
      } else if (type == "position") {
        s.objectives.push_back({optimizer::PositionGoal(a, unit * n.At("target").Vector<3>()), w});
      } else if (type == "plane") {
        s.objectives.push_back({optimizer::PlaneGoal(a, unit * n.At("origin").Vector<3>(),
                                                     n.At("normal").Vector<3>().normalized()),
                                w});
      } else {
        n.At("type").Fail("unknown objective \"" + type + "\" (hold_orientation, position, plane)");
      }
    }
  }
}

// The device mapping and the coupling.
void ParseDevice(const Node& root, double unit, Scene* out) {
  Scene& s = *out;
  if (root.Has("device")) {
    const Node d = root.At("device");
    DeviceSpec& dv = s.device;
    dv.scale = d.Positive("scale", 1.0);
    if (d.Has("id")) {
      const Node id = d.At("id");
      if (!id.j.is_number_integer() ||
          (id.j.is_number_unsigned() && id.j.get<uint64_t>() > uint64_t{INT64_MAX})) {
        id.Fail("must be a 64-bit integer: the device_state_t.device_id the server serves");
      }
      dv.id = id.j.get<int64_t>();
    }
    if (d.Has("origin")) {
      dv.origin = unit * d.At("origin").Vector<3>();
      dv.origin_given = true;
    }
    if (d.Has("quaternion")) dv.R_WD = Quaternion(d.At("quaternion")).toRotationMatrix();
    if (d.Has("tool_offset")) dv.tool_offset = d.At("tool_offset").Vector<3>();
    dv.stiffness = d.Positive("stiffness", dv.stiffness);
    dv.damping = d.Positive("damping", dv.damping);
    dv.max_force = d.Positive("max_force", dv.max_force);
    dv.rated_stiffness = d.Positive("rated_stiffness", dv.rated_stiffness);
    dv.device_rate = d.Positive("device_rate", dv.device_rate);
    dv.max_force_rate = d.Positive("max_force_rate", dv.max_force_rate);
    dv.ramp_time = d.Number("ramp_time", dv.ramp_time);
    if (dv.ramp_time < 0.0) d.At("ramp_time").Fail("must not be negative");
    dv.follow_speed = d.Positive("follow_speed", dv.follow_speed);
    dv.follow_angular_speed = d.Positive("follow_angular_speed", dv.follow_angular_speed);
    if (d.Has("workspace")) {
      const Node w = d.At("workspace");
      dv.workspace_min = w.At("min").Vector<3>();
      dv.workspace_max = w.At("max").Vector<3>();
      for (int i = 0; i < 3; ++i) {
        if (!(dv.workspace_min[i] < 0.0 && dv.workspace_max[i] > 0.0)) {
          w.Fail("must contain the device origin strictly (min < 0 < max on each axis), got min " +
                 Node::Format(dv.workspace_min[i]) + ", max " + Node::Format(dv.workspace_max[i]) +
                 " on axis " + std::to_string(i));
        }
        if (dv.workspace_max[i] - dv.workspace_min[i] > 10.0) {
          w.Fail("is more than 10 m wide on axis " + std::to_string(i) +
                 ": a desk device's workspace is in metres (device frame), not scene units");
        }
      }
    }
    // Passivity of the virtual coupling rendered by a sampled device (Colgate): k < 2b/T, and
    // never above what the device itself can render.
    const double limit = 2.0 * dv.damping * dv.device_rate;
    if (dv.stiffness > limit) {
      d.At("stiffness")
          .Fail("exceeds the passivity limit 2 damping / period = " + Node::Format(limit) +
                " N/m (damping " + Node::Format(dv.damping) + " N s/m at " +
                Node::Format(dv.device_rate) + " Hz)");
    }
    if (dv.stiffness > dv.rated_stiffness) {
      d.At("stiffness")
          .Fail("exceeds the device's rated stiffness " + Node::Format(dv.rated_stiffness) +
                " N/m");
    }
  }

  if (root.Has("offset")) {
    const Node o = root.At("offset");
    s.offset_tolerance = o.Positive("tolerance", s.offset_tolerance / unit) * unit;
    s.offset_margin = o.Positive("margin", s.offset_margin / unit) * unit;
    s.offset_max_edge = o.Positive("max_edge", s.offset_max_edge / unit) * unit;
  }
  if (root.Has("global_stage")) {
    const Node g = root.At("global_stage");
    contact::GlobalOptions& x = s.global;
    x.activation = g.Positive("activation", x.activation / unit) * unit;
    x.release = g.Positive("release", x.release / unit) * unit;
    x.max_penetration = g.Positive("max_penetration", x.max_penetration / unit) * unit;
    x.neglect_radius = g.Positive("neglect_radius", x.neglect_radius / unit) * unit;
    if (!(x.release > x.activation)) g.At("release").Fail("must exceed \"activation\"");
  }
  if (s.global.release > s.offset_margin) {
    (root.Has("offset") ? root.At("offset") : root.At("global_stage").At("release"))
        .Fail("margin " + std::to_string(s.offset_margin / unit) +
              " is below the global stage's release " + std::to_string(s.global.release / unit) +
              ": contacts could part unseen");
  }
}

// Offset meshes for the surfaces the global stage watches, certified (load log). The surfaces
// are independent: one thread per core takes the next one (a 375-face part's meshes took 10 s
// on one core); the log keeps the surfaces' order.
void BuildOffsetMeshes(Scene* out) {
  Scene& s = *out;
  std::vector<size_t> watched;
  for (size_t i = 0; i < s.surfaces.size(); ++i) {
    if (s.surfaces[i].watched) watched.push_back(i);
  }
  std::vector<std::vector<std::string>> logs(watched.size());
  std::atomic<size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto work = [&] {
    for (size_t k = next++; k < watched.size(); k = next++) {
      try {
        SceneSurface& sf = s.surfaces[watched[k]];
        auto build = [&](double tolerance, double margin) {
          sf.mesh = nurbs::MakeOffsetMesh(sf.surface, tolerance, margin, s.offset_max_edge);
          if (sf.trim) {
            // Only the material is collided: cells that hold none are cut (the global stage
            // never seeds in trimmed-away regions), cells the trim crosses kept whole.
            const size_t before = sf.mesh.base.triangles.size();
            sf.mesh.base = nurbs::CutAlongTrim(sf.mesh.base, *sf.trim);
            logs[k].push_back("offset mesh " + sf.name + ": cut along its trim, " +
                              std::to_string(sf.mesh.base.triangles.size()) + " of " +
                              std::to_string(before) + " triangles kept");
          }
          return nurbs::CertifyOffsetMesh(sf.surface, sf.mesh, 60);
        };
        nurbs::OffsetCertificate c = build(s.offset_tolerance, s.offset_margin);
        if (c.offset_exceeds_curvature) {
          // An offset beyond a concave radius folds (a fillet smaller than the margin): this
          // face's offset is reduced to 0.9 of that radius, its tessellation bound to a quarter
          // of the offset. Its pairs are still seen if the other side's offset makes up for it
          // (GlobalContactStage checks that each declared pair's offsets reach twice the release).
          const double was = sf.mesh.offset, radius = c.min_concave_radius, r = 0.9 * radius;
          const double tolerance = std::min(s.offset_tolerance, 0.25 * r);
          c = build(tolerance, r - tolerance);
          char text[256];
          std::snprintf(text, sizeof text,
                        "offset mesh %s: its offset %.3g m exceeded a concave radius of %.3g m "
                        "(it folded); reduced to %.3g m for this face",
                        sf.name.c_str(), was, radius, sf.mesh.offset);
          logs[k].push_back(text);
        }
        logs[k].push_back(c.Report(sf.name));
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  const size_t threads =
      std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), watched.size());
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  for (std::vector<std::string>& l : logs) {
    for (std::string& line : l) s.load_log.push_back(std::move(line));
  }
}

}  // namespace

std::unique_ptr<Scene> ParseScene(const std::string& text, const std::string& where,
                                  const std::string& base_dir, const SceneLoadOptions& options) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // syntax, and a number beyond double range (406)
    throw SceneError(where + ": not valid JSON: " + e.what());
  }
  const Node root{j, where, ""};
  if (!j.is_object()) root.Fail("a scene must be a JSON object");
  auto scene = std::make_unique<Scene>();
  Scene& s = *scene;
  s.path = where;
  s.name = root.String("name", where);
  const std::string unit_name = root.String("length_unit", "m");
  double unit = 1.0;
  if (unit_name == "mm") {
    unit = 1e-3;
  } else if (unit_name == "cm") {
    unit = 1e-2;
  } else if (unit_name != "m") {
    root.At("length_unit").Fail("must be \"m\", \"cm\" or \"mm\", got \"" + unit_name + "\"");
  }

  s.least_astonishment = root.Positive("least_astonishment", s.least_astonishment);

  ParseBodies(root, unit, &s);
  ParseSurfaces(root, unit, base_dir, &s);
  ParseCadBodies(root, base_dir, &s);
  ParseJoints(root, unit, &s);
  ParsePairs(root, &s);
  ParseGrasp(root, unit, &s);
  ParseObjectives(root, unit, &s);
  ParseDevice(root, unit, &s);
  if (options.offset_meshes) BuildOffsetMeshes(&s);
  return scene;
}

std::unique_ptr<Scene> LoadScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  std::stringstream text;
  text << in.rdbuf();
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return ParseScene(text.str(), path, dir.empty() ? "." : dir);
}

}  // namespace tangent::server
