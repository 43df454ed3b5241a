#pragma once

// A JSON value with where it came from, for parsers whose errors name the file and the item:
// "scenes/x.json: bodies[1].mass: must be positive, got -2" (dotted paths, scene files) or
// "runs/x.json: /objective/joints/2: unknown joint \"elbw\"" (JSON pointers, run files).
// Header only; each parser picks its error type.

#include <cmath>
#include <set>
#include <sstream>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace tangent {

template <class Error>
struct JsonNode {
  enum class Style { kDotted, kPointer };
  const nlohmann::json& j;
  std::string where;  ///< the file (or another source name)
  std::string path;   ///< the item inside it, in `style`
  Style style = Style::kDotted;

  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(where + ": " + (path.empty() ? "" : path + ": ") + what);
  }
  bool Has(const std::string& key) const { return j.is_object() && j.contains(key); }
  JsonNode At(const std::string& key) const {
    if (!j.is_object()) Fail("must be an object");
    if (!j.contains(key)) Fail("missing \"" + key + "\"");
    return {j.at(key), where, Child(key), style};
  }
  JsonNode At(size_t i) const { return {j.at(i), where, Child(i), style}; }
  size_t Size() const {
    if (!j.is_array()) Fail("must be an array");
    return j.size();
  }
  /// Rejects keys not in `known` (a misspelt option must not be silently ignored).
  void OnlyKeys(const std::set<std::string>& known) const {
    if (!j.is_object()) Fail("must be an object");
    for (const auto& [key, value] : j.items()) {
      if (known.count(key)) continue;
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      At(key).Fail("unknown field \"" + key + "\" (known: " + list + ")");
    }
  }
  double Number() const {
    if (!j.is_number()) Fail("must be a number");
    const double x = j.get<double>();
    if (!std::isfinite(x)) Fail("must be finite");
    return x;
  }
  double Number(const std::string& key, double fallback) const {
    return Has(key) ? At(key).Number() : fallback;
  }
  double Positive(const std::string& key, double fallback) const {
    const double x = Number(key, fallback);
    if (!(x > 0.0)) At(key).Fail("must be positive, got " + Format(x));
    return x;
  }
  int Integer(const std::string& key, int fallback, int lo, int hi) const {
    if (!Has(key)) return fallback;
    const JsonNode n = At(key);
    if (!n.j.is_number_integer()) n.Fail("must be an integer");
    const auto x = n.j.template get<long long>();
    if (x < lo || x > hi) {
      n.Fail("must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
             std::to_string(x));
    }
    return static_cast<int>(x);
  }
  std::string String() const {
    if (!j.is_string()) Fail("must be a string");
    return j.template get<std::string>();
  }
  std::string String(const std::string& key, const std::string& fallback) const {
    return Has(key) ? At(key).String() : fallback;
  }
  bool Bool(const std::string& key, bool fallback) const {
    if (!Has(key)) return fallback;
    const JsonNode n = At(key);
    if (!n.j.is_boolean()) n.Fail("must be true or false");
    return n.j.template get<bool>();
  }
  template <int N>
  Eigen::Matrix<double, N, 1> Vector() const {
    if (!j.is_array() || static_cast<int>(j.size()) != N) {
      Fail("must be an array of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v[i] = At(static_cast<size_t>(i)).Number();
    return v;
  }
  static std::string Format(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  }

 private:
  std::string Child(const std::string& key) const {
    if (style == Style::kPointer) return path + "/" + Escaped(key);
    return path.empty() ? key : path + "." + key;
  }
  std::string Child(size_t i) const {
    return style == Style::kPointer ? path + "/" + std::to_string(i)
                                    : path + "[" + std::to_string(i) + "]";
  }
  // RFC 6901: "~" as "~0", "/" as "~1".
  static std::string Escaped(const std::string& key) {
    std::string out;
    for (char c : key) {
      if (c == '~') {
        out += "~0";
      } else if (c == '/') {
        out += "~1";
      } else {
        out += c;
      }
    }
    return out;
  }
};

}  // namespace tangent
