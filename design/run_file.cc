#include "design/run_file.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/json_node.h"
#include "optimizer/contacts.h"
#include "optimizer/goals.h"

namespace tangent::design {

namespace {

using Node = JsonNode<RunError>;
constexpr double kDeg = std::numbers::pi / 180.0;

// The scene joint `name`, named at node n in errors.
int JointNamed(const Node& n, const std::string& name, const server::Scene& s, bool revolute,
               bool prismatic_too = false) {
  const int j = s.JointIndex(name);
  if (j < 0) {
    std::string names;
    for (const server::JointSpec& js : s.joints) names += (names.empty() ? "" : ", ") + js.name;
    n.Fail("no joint named \"" + name + "\" in the scene (joints: " + names + ")");
  }
  const std::string& type = s.joints[static_cast<size_t>(j)].type;
  if (revolute && type != "revolute" && !(prismatic_too && type == "prismatic")) {
    n.Fail("joint \"" + name + "\" is " + type +
           (prismatic_too ? ", not revolute or prismatic" : ", not revolute"));
  }
  return j;
}

int JointByName(const Node& n, const server::Scene& s, bool revolute) {
  return JointNamed(n, n.String(), s, revolute);
}

optimizer::Attachment PointOn(const Node& n, const server::Scene& s, double unit) {
  n.OnlyKeys({"body", "point"});
  optimizer::Attachment a;
  const std::string body = n.At("body").String();
  a.body = s.BodyIndex(body);
  if (a.body < 0) n.At("body").Fail("no body named \"" + body + "\" in the scene");
  if (n.Has("point")) a.point = unit * n.At("point").Vector<3>();
  return a;
}

Eigen::Vector3d UnitVector(const Node& n) {
  const Eigen::Vector3d v = n.Vector<3>();
  if (!(v.norm() > 0.0)) n.Fail("must not be zero");
  return v.normalized();
}

void ParseObjective(const Node& n, double unit, RunSpec* run) {
  n.OnlyKeys({"sense", "terms"});
  const std::string sense = n.String("sense", "maximize");
  if (sense != "maximize" && sense != "minimize") {
    n.At("sense").Fail("must be \"maximize\" or \"minimize\", got \"" + sense + "\"");
  }
  run->maximize = sense == "maximize";
  const Node terms = n.At("terms");
  if (terms.Size() == 0) terms.Fail("must name at least one term");
  for (size_t i = 0; i < terms.Size(); ++i) {
    const Node t = terms.At(i);
    t.OnlyKeys({"measure", "weight", "end_effector", "joints", "target"});
    MeasureSpec m;
    m.measure = t.At("measure").String();
    m.weight = t.Number("weight", 1.0);
    if (m.weight == 0.0) t.At("weight").Fail("must not be zero");
    m.end_effector = PointOn(t.At("end_effector"), *run->scene, unit);
    if (m.measure == "grasp_distance") {
      m.target = unit * t.At("target").Vector<3>();
      // F = Σ w m is maximized or minimized: a distance must enter as a cost.
      if ((run->maximize ? -m.weight : m.weight) < 0.0) {
        t.At("weight").Fail(std::string("grasp_distance would reward moving away from the "
                                        "target; give it a ") +
                            (run->maximize ? "negative" : "positive") + " weight");
      }
    } else if (m.measure == "dexterity" || m.measure == "inverse_condition" ||
               m.measure == "force_transmission") {
      const Node joints = t.At("joints");
      if (joints.Size() == 0) joints.Fail("must name at least one revolute joint");
      std::set<int> seen;
      for (size_t k = 0; k < joints.Size(); ++k) {
        const int j = JointByName(joints.At(k), *run->scene, true);
        if (!seen.insert(j).second) joints.At(k).Fail("joint named twice");
        m.joints.push_back(j);
      }
    } else {
      t.At("measure").Fail("unknown measure \"" + m.measure +
                           "\" (dexterity, inverse_condition, force_transmission, "
                           "grasp_distance)");
    }
    run->terms.push_back(std::move(m));
  }
}

// The tracking seed of a point-on-surface term: the domain's centre (each case re-seeds it at
// its own start, Study::Solve).
Eigen::Vector2d SurfaceSeed(const server::Scene& s, int surface) {
  const nurbs::NurbsSurface& f = s.surfaces[static_cast<size_t>(surface)].surface;
  return {0.5 * (f.knots_u().domain_begin() + f.knots_u().domain_end()),
          0.5 * (f.knots_v().domain_begin() + f.knots_v().domain_end())};
}

void ParseConstraints(const Node& n, double unit, RunSpec* run) {
  const server::Scene& s = *run->scene;
  std::set<std::string> names;
  for (size_t i = 0; i < n.Size(); ++i) {
    const Node c = n.At(i);
    c.OnlyKeys({"name", "type", "at", "origin", "normal", "direction", "target", "surface", "rhs"});
    ConstraintSpec cs;
    cs.name = c.At("name").String();
    if (!names.insert(cs.name).second) c.At("name").Fail("duplicate constraint name");
    cs.type = c.At("type").String();
    const optimizer::Attachment at = PointOn(c.At("at"), s, unit);
    if (cs.type == "plane" || cs.type == "half_space") {
      const Eigen::Vector3d origin = unit * c.At("origin").Vector<3>();
      const Eigen::Vector3d normal = UnitVector(c.At("normal"));
      cs.inequality = cs.type == "half_space";
      cs.term = cs.inequality ? optimizer::HalfSpaceGoal(at, origin, normal, false)
                              : optimizer::PlaneGoal(at, origin, normal);
    } else if (cs.type == "point") {
      cs.term = optimizer::MakePositionGoal(at, unit * c.At("target").Vector<3>());
    } else if (cs.type == "line") {
      cs.term =
          optimizer::LineGoal(at, unit * c.At("origin").Vector<3>(), UnitVector(c.At("direction")));
    } else if (cs.type == "point_on_surface" || cs.type == "point_above_surface") {
      const std::string surface = c.At("surface").String();
      cs.surface = s.SurfaceIndex(surface);
      if (cs.surface < 0) c.At("surface").Fail("no surface named \"" + surface + "\"");
      const server::SceneSurface& ss = s.surfaces[static_cast<size_t>(cs.surface)];
      if (ss.body == at.body) c.At("at").Fail("the point is on the surface's own body");
      cs.inequality = cs.type == "point_above_surface";
      cs.term = optimizer::MakePointOnSurface(at, ss.body, &ss.surface, SurfaceSeed(s, cs.surface));
    } else {
      c.At("type").Fail("unknown constraint type \"" + cs.type +
                        "\" (plane, half_space, point, line, point_on_surface, "
                        "point_above_surface)");
    }
    // The right-hand side: r(q) = rhs (lengths in the run's unit).
    cs.inner = cs.term;
    cs.rhs = Eigen::VectorXd::Zero(cs.term->dim());
    if (c.Has("rhs")) {
      const Node rhs = c.At("rhs");
      if (rhs.j.is_number()) {
        if (cs.term->dim() != 1) {
          rhs.Fail("this constraint has " + std::to_string(cs.term->dim()) +
                   " rows: give an array of as many numbers");
        }
        cs.rhs[0] = unit * rhs.Number();
      } else {
        if (rhs.Size() != static_cast<size_t>(cs.term->dim())) {
          rhs.Fail("must have " + std::to_string(cs.term->dim()) + " numbers, got " +
                   std::to_string(rhs.Size()));
        }
        for (int k = 0; k < cs.term->dim(); ++k) {
          cs.rhs[k] = unit * rhs.At(static_cast<size_t>(k)).Number();
        }
      }
    }
    // Always through Shifted: its rhs is per-solve data, so a sweep moves it case by case.
    cs.term = optimizer::Shifted(cs.inner, cs.rhs);
    run->constraints.push_back(std::move(cs));
  }
}

void ParseBounds(const Node& n, RunSpec* run) {
  std::set<int> seen;
  for (size_t i = 0; i < n.Size(); ++i) {
    const Node b = n.At(i);
    b.OnlyKeys({"joint", "min_deg", "max_deg"});
    BoundSpec bs;
    bs.joint = JointByName(b.At("joint"), *run->scene, true);
    if (!seen.insert(bs.joint).second) b.At("joint").Fail("joint bounded twice");
    if (run->scene->joints[static_cast<size_t>(bs.joint)].limits) {
      b.At("joint").Fail("the scene already limits this joint (limits_deg)");
    }
    bs.lo = b.At("min_deg").Number() * kDeg;
    bs.hi = b.At("max_deg").Number() * kDeg;
    if (!(bs.lo < bs.hi)) b.Fail("empty or inverted bounds: min_deg must be below max_deg");
    if (bs.lo < -std::numbers::pi - 1e-12 || bs.hi > std::numbers::pi + 1e-12) {
      b.Fail("bounds must lie within [-180, 180] degrees");
    }
    run->bounds.push_back(bs);
  }
}

// A list of values: "values": [a, b, …] or "range": [first, last, count], times `scale`.
std::vector<double> ValuesOrRange(const Node& g, const char* values, const char* range,
                                  double scale) {
  if (g.Has(values) == g.Has(range)) {
    g.Fail(std::string("give either \"") + values + "\" or \"" + range + "\"");
  }
  std::vector<double> out;
  if (g.Has(values)) {
    const Node v = g.At(values);
    for (size_t k = 0; k < v.Size(); ++k) out.push_back(scale * v.At(k).Number());
  } else {
    const Node r = g.At(range);
    if (r.Size() != 3) r.Fail("must be [first, last, count]");
    const double lo = scale * r.At(0).Number(), hi = scale * r.At(1).Number();
    const Node count = r.At(2);
    if (!count.j.is_number_integer() || count.j.get<long long>() < 2 ||
        count.j.get<long long>() > 10000) {
      count.Fail("the count must be an integer in [2, 10000]");
    }
    const int m = static_cast<int>(count.j.get<long long>());
    if (!(lo < hi)) r.Fail("empty or inverted range: first must be below last");
    for (int k = 0; k < m; ++k) out.push_back(lo + (hi - lo) * k / (m - 1));
  }
  return out;
}

void ParseGrid(const Node& n, double unit, RunSpec* run) {
  for (size_t i = 0; i < n.Size(); ++i) {
    const Node g = n.At(i);
    g.OnlyKeys({"constraint", "row", "values", "range"});
    GridAxis axis;
    const std::string name = g.At("constraint").String();
    axis.constraint = -1;
    for (size_t k = 0; k < run->constraints.size(); ++k) {
      if (run->constraints[k].name == name) axis.constraint = static_cast<int>(k);
    }
    if (axis.constraint < 0) g.At("constraint").Fail("no constraint named \"" + name + "\"");
    const ConstraintSpec& c = run->constraints[static_cast<size_t>(axis.constraint)];
    axis.row = g.Integer("row", 0, 0, c.term->dim() - 1);
    for (const GridAxis& other : run->grid) {
      if (other.constraint == axis.constraint && other.row == axis.row) {
        g.Fail("this constraint row is already an axis");
      }
    }
    axis.values = ValuesOrRange(g, "values", "range", unit);
    if (axis.values.empty()) g.Fail("no values");
    run->grid.push_back(std::move(axis));
  }
  if (run->num_grid_points() > 1000000) n.Fail("more than 10^6 grid points");
}

void ParseDesignJoints(const Node& n, double unit, RunSpec* run) {
  const server::Scene& s = *run->scene;
  for (size_t i = 0; i < n.Size(); ++i) {
    const Node d = n.At(i);
    DesignJointSpec ds;
    ds.joint = JointNamed(d.At("joint"), d.At("joint").String(), s, true, true);
    const server::JointSpec& js = s.joints[static_cast<size_t>(ds.joint)];
    ds.prismatic = js.type == "prismatic";
    for (const DesignJointSpec& other : run->design_joints) {
      if (other.joint == ds.joint) d.At("joint").Fail("joint is a design parameter twice");
    }
    for (const BoundSpec& b : run->bounds) {
      if (b.joint == ds.joint) d.At("joint").Fail("joint is bounded as a motion (bounds) too");
    }
    if (js.limits) d.At("joint").Fail("the scene already limits this joint (limits_deg)");
    for (const MeasureSpec& m : run->terms) {
      for (int j : m.joints) {
        if (j == ds.joint) d.At("joint").Fail("a design joint cannot drive a measure's motion");
      }
    }
    if (ds.prismatic) {
      d.OnlyKeys({"joint", "min", "max"});
      ds.lo = unit * d.At("min").Number();
      ds.hi = unit * d.At("max").Number();
    } else {
      d.OnlyKeys({"joint", "min_deg", "max_deg"});
      ds.lo = d.At("min_deg").Number() * kDeg;
      ds.hi = d.At("max_deg").Number() * kDeg;
    }
    if (!(ds.lo < ds.hi)) d.Fail("empty or inverted bounds: the minimum must be below the maximum");
    run->design_joints.push_back(ds);
  }
}

void ParseStarts(const Node& n, double unit, RunSpec* run) {
  n.OnlyKeys({"list", "random", "seed", "joints"});
  const server::Scene& s = *run->scene;
  if (n.Has("list")) {
    const Node list = n.At("list");
    for (size_t i = 0; i < list.Size(); ++i) {
      const Node st = list.At(i);
      st.OnlyKeys({"joints_deg", "joints_m"});
      StartSpec start;
      if (st.Has("joints_deg")) {
        const Node angles = st.At("joints_deg");
        if (!angles.j.is_object()) angles.Fail("must be an object {\"joint name\": degrees}");
        for (const auto& [name, value] : angles.j.items()) {
          const Node a = angles.At(name);
          start.angles[JointNamed(a, name, s, true)] = a.Number() * kDeg;
        }
      }
      if (st.Has("joints_m")) {  // prismatic joints' displacements
        const Node lengths = st.At("joints_m");
        if (!lengths.j.is_object()) lengths.Fail("must be an object {\"joint name\": length}");
        for (const auto& [name, value] : lengths.j.items()) {
          const Node a = lengths.At(name);
          const int j = JointNamed(a, name, s, false);
          if (s.joints[static_cast<size_t>(j)].type != "prismatic") a.Fail("not a prismatic joint");
          start.angles[j] = unit * a.Number();
        }
      }
      run->starts.push_back(std::move(start));
    }
  }
  run->random_starts = n.Integer("random", 0, 0, 1000000);
  if (n.Has("seed")) {
    const Node sd = n.At("seed");
    if (!sd.j.is_number_unsigned()) sd.Fail("must be a non-negative integer");
    run->seed = sd.j.get<uint64_t>();
  }
  if (n.Has("joints")) {
    const Node joints = n.At("joints");
    for (size_t k = 0; k < joints.Size(); ++k) {
      run->random_joints.push_back(JointByName(joints.At(k), s, true));
    }
  } else {
    for (size_t j = 0; j < s.joints.size(); ++j) {
      bool design = false;
      for (const DesignJointSpec& d : run->design_joints) design |= d.joint == static_cast<int>(j);
      if (s.joints[j].type == "revolute" || design) {
        run->random_joints.push_back(static_cast<int>(j));
      }
    }
  }
  if (run->num_starts() == 0) n.Fail("no start: give \"list\" or \"random\" > 0");
}

// The configurations (configurations.h): parsed against the scene as written, then the scene
// is replaced by its replica and every joint index of the run moved to the replica's.
void ParseConfigurations(const Node& root, double unit, RunSpec* run) {
  const Node n = root.At("configurations");
  n.OnlyKeys({"joint", "values_deg", "range_deg", "values", "range", "tolerance"});
  auto c = std::make_unique<ConfigurationsSpec>();
  const server::Scene& base = *run->scene;
  c->joint = JointNamed(n.At("joint"), n.At("joint").String(), base, true, true);
  const server::JointSpec& cj = base.joints[static_cast<size_t>(c->joint)];
  c->prismatic = cj.type == "prismatic";
  if (c->prismatic) {
    if (n.Has("values_deg") || n.Has("range_deg")) {
      n.Fail("a prismatic joint's configurations are lengths: \"values\" or \"range\"");
    }
    c->values = ValuesOrRange(n, "values", "range", unit);
  } else {
    if (n.Has("values") || n.Has("range")) {
      n.Fail("a revolute joint's configurations are angles: \"values_deg\" or \"range_deg\"");
    }
    c->values = ValuesOrRange(n, "values_deg", "range_deg", kDeg);
    for (double v : c->values) {
      if (std::abs(v) > std::numbers::pi + 1e-12) n.Fail("angles must lie within [-180, 180]");
    }
  }
  if (c->values.empty() || c->values.size() > 1000) n.Fail("give 1 to 1000 configurations");
  if (!n.Has("tolerance")) {
    n.Fail(
        "give \"tolerance\": how far the smooth worst case may lie from the exact one, in "
        "the measure's units");
  }
  c->tolerance = n.Positive("tolerance", 0.0);
  // What the copies cannot carry yet, and what the configurations set themselves.
  if (root.Has("constraints")) {
    root.At("constraints")
        .Fail(
            "cannot be combined with \"configurations\" yet (each "
            "constraint would need a copy per configuration)");
  }
  for (size_t i = 0; i < run->terms.size(); ++i) {
    if (run->terms[i].measure == "grasp_distance") {
      root.At("objective")
          .At("terms")
          .At(i)
          .At("measure")
          .Fail(
              "grasp_distance cannot be combined with \"configurations\" (a worst case over "
              "configurations is of dexterity measures)");
    }
  }
  for (const DesignJointSpec& d : run->design_joints) {
    if (d.joint == c->joint) n.At("joint").Fail("a design joint cannot be the configuration joint");
    c->design_joints.push_back(d.joint);
  }
  for (const BoundSpec& b : run->bounds) {
    if (b.joint == c->joint) n.At("joint").Fail("is bounded too: the configurations set it");
  }
  for (size_t i = 0; i < run->starts.size(); ++i) {
    if (run->starts[i].angles.count(c->joint)) {
      root.At("starts").At("list").At(i).Fail("sets the configuration joint \"" + cj.name +
                                              "\": the configurations do");
    }
  }
  const auto random = std::find(run->random_joints.begin(), run->random_joints.end(), c->joint);
  if (random != run->random_joints.end()) {
    if (root.At("starts").Has("joints")) {
      root.At("starts").At("joints").Fail("names the configuration joint \"" + cj.name +
                                          "\": the configurations set it");
    }
    run->random_joints.erase(random);
  }

  c->base = std::move(run->scene);
  try {
    run->scene = Replicate(c.get());
  } catch (const std::invalid_argument& e) {
    n.Fail(e.what());
  }
  // Every joint index to the replica's: one per copy (a shared joint once).
  const int K = c->size();
  auto copies = [&](int j) {
    std::vector<int> out;
    for (int k = 0; k < K; ++k) {
      const int r = c->Joint(k, j);
      if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
    }
    return out;
  };
  std::vector<BoundSpec> bounds;
  for (const BoundSpec& b : run->bounds) {
    for (int r : copies(b.joint)) bounds.push_back({r, b.lo, b.hi});
  }
  run->bounds = bounds;
  for (DesignJointSpec& d : run->design_joints) d.joint = copies(d.joint).front();
  for (StartSpec& st : run->starts) {
    std::map<int, double> angles;
    for (const auto& [j, value] : st.angles) {
      for (int r : copies(j)) angles[r] = value;
    }
    st.angles = angles;
  }
  std::vector<int> random_joints;
  for (int j : run->random_joints) {
    for (int r : copies(j)) random_joints.push_back(r);
  }
  run->random_joints = random_joints;
  // Copy k's configuration joint at its value: an equality whose multiplier is dF*/dθ_k.
  for (int k = 0; k < K; ++k) {
    const server::JointSpec& js = run->scene->joints[static_cast<size_t>(c->Joint(k, c->joint))];
    ConstraintSpec cs;
    const double v = c->values[static_cast<size_t>(k)];
    char value[64];
    std::snprintf(value, sizeof value, c->prismatic ? "%.6g m" : "%.6g deg",
                  c->prismatic ? v : v / kDeg);
    cs.name = "configuration " + std::to_string(k + 1) + ": " + cj.name + " at " + value;
    cs.type = "configuration";
    cs.inner = optimizer::JointCoordinate(js.type, js.a, js.b);
    cs.rhs = Eigen::VectorXd::Constant(1, v);
    cs.term = optimizer::Shifted(cs.inner, cs.rhs);
    run->constraints.push_back(std::move(cs));
  }
  run->configurations = std::move(c);
}

}  // namespace

RunSpec ParseRun(const std::string& text, const std::string& where, const std::string& base_dir) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // (also a number overflowing a double)
    throw RunError(where + ": not valid JSON: " + e.what());
  }
  const Node root{j, where, "", Node::Style::kPointer};
  root.OnlyKeys({"comment", "scene", "length_unit", "objective", "constraints", "bounds", "design",
                 "grid", "starts", "configurations", "solver"});
  RunSpec run;
  run.path = where;
  const std::string scene = root.At("scene").String();
  run.scene_path = std::filesystem::path(scene).is_absolute()
                       ? scene
                       : (std::filesystem::path(base_dir) / scene).lexically_normal().string();
  try {
    run.scene = server::LoadScene(run.scene_path);
  } catch (const server::SceneError& e) {
    root.At("scene").Fail(std::string("the scene could not be loaded: ") + e.what());
  }
  const std::string unit_name = root.String("length_unit", "m");
  if (unit_name != "m" && unit_name != "mm") {
    root.At("length_unit").Fail("must be \"m\" or \"mm\", got \"" + unit_name + "\"");
  }
  const double unit = unit_name == "mm" ? 1e-3 : 1.0;
  ParseObjective(root.At("objective"), unit, &run);
  if (root.Has("constraints")) ParseConstraints(root.At("constraints"), unit, &run);
  if (root.Has("bounds")) ParseBounds(root.At("bounds"), &run);
  if (root.Has("design")) ParseDesignJoints(root.At("design"), unit, &run);
  if (root.Has("grid")) ParseGrid(root.At("grid"), unit, &run);
  ParseStarts(root.At("starts"), unit, &run);
  if (root.Has("configurations")) ParseConfigurations(root, unit, &run);
  if (root.Has("solver")) {
    const Node sv = root.At("solver");
    sv.OnlyKeys({"max_iterations", "relative_kkt_tolerance", "constraint_tolerance"});
    run.max_iterations = sv.Integer("max_iterations", run.max_iterations, 1, 1000000);
    run.relative_kkt_tolerance = sv.Positive("relative_kkt_tolerance", run.relative_kkt_tolerance);
    run.constraint_tolerance = sv.Positive("constraint_tolerance", run.constraint_tolerance);
  }
  return run;
}

RunSpec LoadRun(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw RunError(path + ": cannot open the run file");
  std::stringstream text;
  text << in.rdbuf();
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return ParseRun(text.str(), path, dir.empty() ? "." : dir);
}

}  // namespace tangent::design
