// libFuzzer target: the NURBS JSON reader (nurbs/json_io.h) on arbitrary text: a surface
// document (with its trim, when it has one) or a curve. What loads must evaluate: the fast,
// reference and per-span paths at a few points, finite, and every trimmed point classified.
// Errors must be ParseError or TrimError naming the document, the JSON pointer and the problem.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "nurbs/json_io.h"
#include "nurbs/trim.h"

namespace {

void Exercise(const tangent::nurbs::NurbsSurface& s, const nlohmann::json& doc) {
  for (double u : {0.0, 0.37, 1.0}) {
    for (double v : {0.0, 0.61, 1.0}) (void)s.Evaluate(u, v);  // clamped to the domain
  }
  if (!doc.is_object() || !doc.contains("trim")) return;
  const tangent::nurbs::TrimmedDomain trim = tangent::nurbs::TrimFromJson(doc["trim"], s, "fuzz");
  for (double u : {0.1, 0.5, 0.9}) {
    const Eigen::Vector2d uv(u, 1.0 - u);
    (void)trim.Contains(uv);
    const auto c = trim.Nearest(uv);
    if (!std::isfinite(c.signed_distance)) std::abort();  // a validated trim has a nearest point
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const nlohmann::json doc = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    const bool curve = doc.is_object() && doc.contains("type") && doc["type"] == "nurbs_curve";
    if (curve) {
      // A curve document is 2-D or 3-D; the other reading must fail with a ParseError.
      try {
        (void)tangent::nurbs::ParseCurve<3>(text, "fuzz");
      } catch (const tangent::nurbs::ParseError&) {
      }
      (void)tangent::nurbs::ParseCurve<2>(text, "fuzz");
    } else {
      Exercise(tangent::nurbs::ParseSurface(text, "fuzz"), doc);
    }
  } catch (const tangent::nurbs::ParseError&) {
  } catch (const tangent::nurbs::TrimError&) {
  }
  return 0;
}
