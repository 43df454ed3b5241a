#include "nurbs/json_io.h"

#include "nurbs/primitives.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace tangent::nurbs {

namespace {

using nlohmann::json;

// A location inside the document for messages: "<where>: /a/b/3".
struct Loc {
  std::string where;
  std::string pointer;
  Loc operator/(const std::string& key) const { return {where, pointer + "/" + key}; }
  Loc operator/(size_t index) const { return {where, pointer + "/" + std::to_string(index)}; }
  [[noreturn]] void Fail(const std::string& what) const {
    std::string prefix = where.empty() ? "" : where + ": ";
    throw ParseError(prefix + (pointer.empty() ? "/" : pointer) + ": " + what);
  }
};

std::string TypeName(const json& j) { return j.type_name(); }

const json& Field(const json& obj, const Loc& loc, const std::string& key) {
  if (!obj.is_object()) loc.Fail("expected an object, found " + TypeName(obj));
  const auto it = obj.find(key);
  if (it == obj.end()) (loc / key).Fail("missing required field \"" + key + "\"");
  return *it;
}

double Number(const json& j, const Loc& loc) {
  if (!j.is_number()) loc.Fail("expected a number, found " + TypeName(j));
  const double x = j.get<double>();
  if (!std::isfinite(x)) loc.Fail("number is not finite");
  return x;
}

int Integer(const json& j, const Loc& loc) {
  if (!j.is_number_integer()) loc.Fail("expected an integer, found " + TypeName(j));
  return j.get<int>();
}

const json& Array(const json& j, const Loc& loc) {
  if (!j.is_array()) loc.Fail("expected an array, found " + TypeName(j));
  return j;
}

int Degree(const json& obj, const Loc& loc, const std::string& key) {
  const int p = Integer(Field(obj, loc, key), loc / key);
  if (p < 1 || p > kMaxDegree) {
    (loc / key).Fail("unsupported degree " + std::to_string(p) + " (supported: 1.." +
                     std::to_string(kMaxDegree) + ")");
  }
  return p;
}

KnotVector Knots(const json& obj, const Loc& loc, const std::string& key, int degree) {
  const Loc at = loc / key;
  const json& arr = Array(Field(obj, loc, key), at);
  std::vector<double> k;
  for (size_t i = 0; i < arr.size(); ++i) k.push_back(Number(arr[i], at / i));
  try {
    return KnotVector(degree, std::move(k));
  } catch (const std::invalid_argument& e) {
    // KnotVector names the knot index; prefix the field's location.
    std::string msg = e.what();
    const std::string head = "knot vector: ";
    if (msg.rfind(head, 0) == 0) msg = msg.substr(head.size());
    at.Fail(msg);
  }
}

double UnitScale(const json& obj, const Loc& loc) {
  const auto it = obj.find("units");
  if (it == obj.end()) return 1.0;
  if (!it->is_string()) (loc / "units").Fail("expected a string, found " + TypeName(*it));
  const std::string u = it->get<std::string>();
  if (u == "m") return 1.0;
  if (u == "mm") return 1e-3;
  if (u == "cm") return 1e-2;
  if (u == "in") return 0.0254;
  (loc / "units").Fail("unknown unit \"" + u + "\" (expected m, cm, mm or in)");
}

template <int Dim>
Eigen::Matrix<double, Dim, 1> Point(const json& j, const Loc& loc, double scale) {
  const json& arr = Array(j, loc);
  if (arr.size() != static_cast<size_t>(Dim)) {
    loc.Fail("expected " + std::to_string(Dim) + " coordinates, found " +
             std::to_string(arr.size()));
  }
  Eigen::Matrix<double, Dim, 1> x;
  for (int d = 0; d < Dim; ++d)
    x[d] = scale * Number(arr[static_cast<size_t>(d)], loc / static_cast<size_t>(d));
  return x;
}

double Weight(const json& j, const Loc& loc) {
  const double w = Number(j, loc);
  if (!(w > 0.0)) {
    std::ostringstream os;
    os << "weight " << w << " must be positive";
    loc.Fail(os.str());
  }
  return w;
}

void CheckType(const json& j, const Loc& loc, const std::string& expected) {
  const json& type = Field(j, loc, "type");
  if (!type.is_string() || type.get<std::string>() != expected) {
    (loc / "type").Fail("expected \"" + expected + "\", found " + type.dump());
  }
}

json Json17(double x) { return json(x); }  // nlohmann writes doubles round-trip exactly.

json ParseText(const std::string& text, const std::string& where) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    // Syntax errors (parse_error) and numbers beyond double range (out_of_range 406).
    throw ParseError((where.empty() ? "" : where + ": ") + "invalid JSON: " + e.what());
  }
}

}  // namespace

NurbsSurface SurfaceFromJson(const json& j, const std::string& where) {
  const Loc loc{where, ""};
  CheckType(j, loc, "nurbs_surface");
  const double scale = UnitScale(j, loc);
  const int p = Degree(j, loc, "degree_u");
  const int q = Degree(j, loc, "degree_v");
  KnotVector ku = Knots(j, loc, "knots_u", p);
  KnotVector kv = Knots(j, loc, "knots_v", q);
  const int nu = ku.num_basis(), nv = kv.num_basis();
  const Loc cl = loc / "control_points";
  const json& rows = Array(Field(j, loc, "control_points"), cl);
  if (rows.size() != static_cast<size_t>(nu)) {
    cl.Fail("expected " + std::to_string(nu) + " rows (knots_u has " + std::to_string(ku.size()) +
            " knots of degree " + std::to_string(p) + "), found " + std::to_string(rows.size()));
  }
  std::vector<Eigen::Vector3d> pts;
  for (size_t i = 0; i < rows.size(); ++i) {
    const json& row = Array(rows[i], cl / i);
    if (row.size() != static_cast<size_t>(nv)) {
      (cl / i).Fail("expected " + std::to_string(nv) + " control points (knots_v has " +
                    std::to_string(kv.size()) + " knots of degree " + std::to_string(q) +
                    "), found " + std::to_string(row.size()));
    }
    for (size_t jj = 0; jj < row.size(); ++jj) pts.push_back(Point<3>(row[jj], cl / i / jj, scale));
  }
  std::vector<double> w;
  if (j.contains("weights")) {
    const Loc wl = loc / "weights";
    const json& wrows = Array(j["weights"], wl);
    if (wrows.size() != static_cast<size_t>(nu)) {
      wl.Fail("expected " + std::to_string(nu) + " rows, found " + std::to_string(wrows.size()));
    }
    for (size_t i = 0; i < wrows.size(); ++i) {
      const json& row = Array(wrows[i], wl / i);
      if (row.size() != static_cast<size_t>(nv)) {
        (wl / i).Fail("expected " + std::to_string(nv) + " weights, found " +
                      std::to_string(row.size()));
      }
      for (size_t jj = 0; jj < row.size(); ++jj) w.push_back(Weight(row[jj], wl / i / jj));
    }
  }
  // The net's own checks (finite, weights and coordinates within range so evaluation cannot
  // overflow) name the control point; they are this document's error.
  try {
    return NurbsSurface(std::move(ku), std::move(kv), pts, w);
  } catch (const std::invalid_argument& e) {
    cl.Fail(e.what());
  }
}

template <int Dim>
NurbsCurve<Dim> CurveAt(const json& j, const Loc& loc);

template <int Dim>
NurbsCurve<Dim> CurveFromJson(const json& j, const std::string& where) {
  return CurveAt<Dim>(j, Loc{where, ""});
}

template <int Dim>
NurbsCurve<Dim> CurveAt(const json& j, const Loc& loc) {
  CheckType(j, loc, "nurbs_curve");
  const int dim = Integer(Field(j, loc, "dimension"), loc / "dimension");
  if (dim != Dim) {
    (loc / "dimension")
        .Fail("expected a " + std::to_string(Dim) + "-D curve, found dimension " +
              std::to_string(dim));
  }
  const double scale = UnitScale(j, loc);
  const int p = Degree(j, loc, "degree");
  KnotVector k = Knots(j, loc, "knots", p);
  const Loc cl = loc / "control_points";
  const json& arr = Array(Field(j, loc, "control_points"), cl);
  if (arr.size() != static_cast<size_t>(k.num_basis())) {
    cl.Fail("expected " + std::to_string(k.num_basis()) + " control points (" +
            std::to_string(k.size()) + " knots of degree " + std::to_string(p) + "), found " +
            std::to_string(arr.size()));
  }
  std::vector<Eigen::Matrix<double, Dim, 1>> pts;
  for (size_t i = 0; i < arr.size(); ++i) pts.push_back(Point<Dim>(arr[i], cl / i, scale));
  std::vector<double> w;
  if (j.contains("weights")) {
    const Loc wl = loc / "weights";
    const json& warr = Array(j["weights"], wl);
    if (warr.size() != arr.size()) {
      wl.Fail("expected " + std::to_string(arr.size()) + " weights, found " +
              std::to_string(warr.size()));
    }
    for (size_t i = 0; i < warr.size(); ++i) w.push_back(Weight(warr[i], wl / i));
  }
  try {
    return NurbsCurve<Dim>(std::move(k), pts, w);
  } catch (const std::invalid_argument& e) {  // the net's range checks, as for surfaces
    cl.Fail(e.what());
  }
}

namespace {

// One curve of a trimming loop: a 2-D NURBS curve, a polyline or a circle (parameter units).
NurbsCurve2d TrimCurve(const json& j, const Loc& loc) {
  const json& type = Field(j, loc, "type");
  const std::string t = type.is_string() ? type.get<std::string>() : "";
  if (t == "nurbs_curve") return CurveAt<2>(j, loc);
  if (t == "polyline") {
    const Loc pl = loc / "points";
    const json& arr = Array(Field(j, loc, "points"), pl);
    if (arr.size() < 2)
      pl.Fail("a polyline needs at least 2 points, found " + std::to_string(arr.size()));
    std::vector<Eigen::Vector2d> pts;
    for (size_t i = 0; i < arr.size(); ++i) {
      pts.push_back(Point<2>(arr[i], pl / i, 1.0));
      if (i > 0 && pts[i] == pts[i - 1]) (pl / i).Fail("repeats the previous point");
    }
    try {
      return MakePolyline2d(pts);
    } catch (const std::invalid_argument& e) {  // the net's range checks
      pl.Fail(e.what());
    }
  }
  if (t == "circle") {
    const Eigen::Vector2d c = Point<2>(Field(j, loc, "center"), loc / "center", 1.0);
    const double r = Number(Field(j, loc, "radius"), loc / "radius");
    if (!(r > 0.0)) (loc / "radius").Fail("must be positive");
    bool clockwise = false;
    if (j.contains("clockwise")) {
      if (!j["clockwise"].is_boolean()) (loc / "clockwise").Fail("expected true or false");
      clockwise = j["clockwise"].get<bool>();
    }
    try {
      return MakeCircle2d(c, r, clockwise);
    } catch (const std::invalid_argument& e) {  // the net's range checks
      loc.Fail(e.what());
    }
  }
  (loc / "type").Fail("expected \"nurbs_curve\", \"polyline\" or \"circle\", found " + type.dump());
}

TrimLoop TrimLoopAt(const json& j, const Loc& loc) {
  const json& arr = Array(j, loc);
  if (arr.empty()) loc.Fail("a loop needs at least one curve");
  TrimLoop loop;
  for (size_t i = 0; i < arr.size(); ++i) {
    try {
      loop.curves.push_back(TrimCurve(arr[i], loc / i));
    } catch (const std::invalid_argument& e) {  // (a curve's own checks: knots, weights)
      (loc / i).Fail(e.what());
    }
  }
  return loop;
}

}  // namespace

TrimmedDomain TrimFromJson(const json& j, const NurbsSurface& surface, const std::string& where,
                           std::vector<std::string>* warnings) {
  const Loc loc{where, ""};
  if (!j.is_object()) loc.Fail("expected an object, found " + TypeName(j));
  for (const auto& [key, value] : j.items()) {
    if (key != "outer" && key != "holes" && key != "band" && key != "comment") {
      (loc / key).Fail("unknown field (known: outer, holes, band, comment)");
    }
  }
  std::optional<TrimLoop> outer;
  if (j.contains("outer")) outer = TrimLoopAt(j["outer"], loc / "outer");
  std::vector<TrimLoop> holes;
  if (j.contains("holes")) {
    const json& arr = Array(j["holes"], loc / "holes");
    for (size_t i = 0; i < arr.size(); ++i) holes.push_back(TrimLoopAt(arr[i], loc / "holes" / i));
  }
  if (!outer && holes.empty()) loc.Fail("no loop: give \"outer\" or \"holes\"");
  TrimOptions options;
  if (j.contains("band")) {
    options.band = Number(j["band"], loc / "band");
    if (!(options.band > 0.0 && options.band < 0.1)) (loc / "band").Fail("must be in (0, 0.1)");
  }
  const Eigen::Vector2d lo(surface.knots_u().domain_begin(), surface.knots_v().domain_begin());
  const Eigen::Vector2d hi(surface.knots_u().domain_end(), surface.knots_v().domain_end());
  try {
    return TrimmedDomain(lo, hi, std::move(outer), std::move(holes), options, warnings);
  } catch (const TrimError& e) {
    std::string msg = e.what();
    if (msg.rfind("trim: ", 0) == 0) msg = msg.substr(6);
    // The loop the message names, as a pointer: "hole k" is /holes/k, the outer loop /outer.
    Loc at = loc;
    const size_t hole = msg.find("hole ");
    const size_t outer_at = msg.find("outer loop");
    if (hole != std::string::npos && (outer_at == std::string::npos || hole < outer_at)) {
      at = loc / "holes" / static_cast<size_t>(std::stoul(msg.substr(hole + 5)));
    } else if (outer_at != std::string::npos) {
      at = loc / "outer";
    }
    at.Fail(msg);
  }
}

json ToJson(const TrimmedDomain& trim) {
  json j = json::object();
  auto loop = [](const TrimLoop& l) {
    json curves = json::array();
    for (const NurbsCurve2d& c : l.curves) curves.push_back(ToJson(c));
    return curves;
  };
  const std::vector<TrimLoop>& loops = trim.loops();
  size_t first_hole = 0;
  if (trim.has_outer()) {
    j["outer"] = loop(loops[0]);
    first_hole = 1;
  }
  json holes = json::array();
  for (size_t i = first_hole; i < loops.size(); ++i) holes.push_back(loop(loops[i]));
  if (!holes.empty()) j["holes"] = holes;
  return j;
}

NurbsSurface ParseSurface(const std::string& text, const std::string& where) {
  return SurfaceFromJson(ParseText(text, where), where);
}

template <int Dim>
NurbsCurve<Dim> ParseCurve(const std::string& text, const std::string& where) {
  return CurveFromJson<Dim>(ParseText(text, where), where);
}

nlohmann::json LoadDocument(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ParseError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseText(ss.str(), path);
}

NurbsSurface LoadSurface(const std::string& path) {
  return SurfaceFromJson(LoadDocument(path), path);
}

json ToJson(const NurbsSurface& s) {
  json j;
  j["type"] = "nurbs_surface";
  j["degree_u"] = s.degree_u();
  j["degree_v"] = s.degree_v();
  j["knots_u"] = s.knots_u().knots();
  j["knots_v"] = s.knots_v().knots();
  json pts = json::array(), ws = json::array();
  for (int i = 0; i < s.num_u(); ++i) {
    json row = json::array(), wrow = json::array();
    for (int jj = 0; jj < s.num_v(); ++jj) {
      const Eigen::Vector3d x = s.point(i, jj);
      row.push_back({Json17(x.x()), Json17(x.y()), Json17(x.z())});
      wrow.push_back(s.weight(i, jj));
    }
    pts.push_back(row);
    ws.push_back(wrow);
  }
  j["control_points"] = pts;
  if (s.IsRational()) j["weights"] = ws;
  return j;
}

template <int Dim>
json ToJson(const NurbsCurve<Dim>& c) {
  json j;
  j["type"] = "nurbs_curve";
  j["dimension"] = Dim;
  j["degree"] = c.degree();
  j["knots"] = c.knots().knots();
  json pts = json::array(), ws = json::array();
  bool rational = false;
  for (int i = 0; i < c.num_points(); ++i) {
    json x = json::array();
    for (int d = 0; d < Dim; ++d) x.push_back(c.point(i)[d]);
    pts.push_back(x);
    ws.push_back(c.weight(i));
    rational = rational || c.weight(i) != c.weight(0);
  }
  j["control_points"] = pts;
  if (rational) j["weights"] = ws;
  return j;
}

template NurbsCurve<2> CurveFromJson<2>(const json&, const std::string&);
template NurbsCurve<3> CurveFromJson<3>(const json&, const std::string&);
template NurbsCurve<2> ParseCurve<2>(const std::string&, const std::string&);
template NurbsCurve<3> ParseCurve<3>(const std::string&, const std::string&);
template json ToJson(const NurbsCurve<2>&);
template json ToJson(const NurbsCurve<3>&);

}  // namespace tangent::nurbs
