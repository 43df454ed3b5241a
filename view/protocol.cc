#include "view/protocol.h"

#include <cmath>

#include <nlohmann/json.hpp>

namespace tangent::view {
namespace {

using nlohmann::json;

const json& Field(const json& j, const char* type, const char* name) {
  const auto it = j.find(name);
  if (it == j.end()) {
    throw ProtocolError(std::string("\"") + type + "\" message: missing field \"" + name + "\"");
  }
  return *it;
}

Eigen::Vector3d Point(const json& j, const char* type, const char* name) {
  const json& f = Field(j, type, name);
  if (!f.is_array() || f.size() != 3) {
    throw ProtocolError(std::string("\"") + type + "\" message: \"" + name +
                        "\" must be an array of 3 numbers");
  }
  Eigen::Vector3d x;
  for (int i = 0; i < 3; ++i) {
    const json& e = f[static_cast<size_t>(i)];
    if (!e.is_number() || !std::isfinite(e.get<double>())) {
      throw ProtocolError(std::string("\"") + type + "\" message: \"" + name + "\"[" +
                          std::to_string(i) + "] must be a finite number");
    }
    x[i] = e.get<double>();
  }
  return x;
}

int Sextet(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

}  // namespace

std::string DecodeBase64(std::string_view text) {
  if (text.size() % 4 != 0) {
    throw ProtocolError("base64: length " + std::to_string(text.size()) +
                        " is not a multiple of 4");
  }
  std::string out;
  out.reserve(text.size() / 4 * 3);
  for (size_t i = 0; i < text.size(); i += 4) {
    const bool last = i + 4 == text.size();
    int s[4];
    int pad = 0;
    for (int k = 0; k < 4; ++k) {
      const char c = text[i + static_cast<size_t>(k)];
      if (c == '=' && last && k >= 2) {
        s[k] = 0;
        ++pad;
        continue;
      }
      s[k] = pad > 0 ? -1 : Sextet(c);
      if (s[k] < 0) {
        throw ProtocolError("base64: invalid character at offset " +
                            std::to_string(i + static_cast<size_t>(k)));
      }
    }
    const uint32_t v = (static_cast<uint32_t>(s[0]) << 18) | (static_cast<uint32_t>(s[1]) << 12) |
                       (static_cast<uint32_t>(s[2]) << 6) | static_cast<uint32_t>(s[3]);
    out.push_back(static_cast<char>((v >> 16) & 0xff));
    if (pad < 2) out.push_back(static_cast<char>((v >> 8) & 0xff));
    if (pad < 1) out.push_back(static_cast<char>(v & 0xff));
  }
  return out;
}

ClientMessage ParseClientMessage(std::string_view text) {
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw ProtocolError("message is not JSON");
  if (!j.is_object()) throw ProtocolError("message is not a JSON object");
  const auto type_it = j.find("type");
  if (type_it == j.end() || !type_it->is_string()) {
    throw ProtocolError("message has no string field \"type\"");
  }
  const std::string type = type_it->get<std::string>();
  ClientMessage m;
  if (type == "need") {
    m.kind = ClientMessage::Kind::kNeed;
    const json& h = Field(j, "need", "hash");
    if (!h.is_string() || h.get<std::string>().size() != 16) {
      throw ProtocolError("\"need\" message: \"hash\" must be a string of 16 hex digits");
    }
    m.hash = h.get<std::string>();
  } else if (type == "camera") {
    m.kind = ClientMessage::Kind::kCamera;
    m.camera_position = Point(j, "camera", "position");
    m.camera_target = Point(j, "camera", "target");
    if ((m.camera_position - m.camera_target).norm() == 0.0) {
      throw ProtocolError("\"camera\" message: position and target coincide");
    }
  } else if (type == "png") {
    m.kind = ClientMessage::Kind::kPng;
    const json& u = Field(j, "png", "utime");
    if (!u.is_number_integer())
      throw ProtocolError("\"png\" message: \"utime\" must be an integer");
    m.utime = u.get<int64_t>();
    const json& d = Field(j, "png", "data");
    static constexpr std::string_view kPrefix = "data:image/png;base64,";
    if (!d.is_string() || d.get_ref<const std::string&>().rfind(kPrefix, 0) != 0) {
      throw ProtocolError("\"png\" message: \"data\" must be a data:image/png;base64 URL");
    }
    m.png = DecodeBase64(std::string_view(d.get_ref<const std::string&>()).substr(kPrefix.size()));
    static constexpr std::string_view kSignature = "\x89PNG\r\n\x1a\n";
    if (m.png.rfind(kSignature, 0) != 0) {
      throw ProtocolError("\"png\" message: the data is not a PNG (no PNG signature)");
    }
  } else if (type == "play") {
    m.kind = ClientMessage::Kind::kPlay;
  } else if (type == "pause") {
    m.kind = ClientMessage::Kind::kPause;
  } else if (type == "seek") {
    m.kind = ClientMessage::Kind::kSeek;
    const json& t = Field(j, "seek", "t");
    if (!t.is_number() || !std::isfinite(t.get<double>())) {
      throw ProtocolError("\"seek\" message: \"t\" must be a finite number of seconds");
    }
    m.t = t.get<double>();
  } else {
    throw ProtocolError("unknown message type \"" + type + "\"");
  }
  return m;
}

}  // namespace tangent::view
