#pragma once

// Messages from the browser to tangent-view (JSON text frames). Everything a browser sends is
// untrusted: a message that is not one of these, or has a field of the wrong type or size, is a
// ProtocolError naming what is wrong; the server answers it with {"type":"error"} and goes on.
//
//   {"type":"need", "hash":"<16 hex>"}              send me this mesh
//   {"type":"camera", "position":[x,y,z], "target":[x,y,z]}   the user moved the camera (metres)
//   {"type":"png", "utime":N, "data":"data:image/png;base64,..."}   an answer to "snapshot"
//   {"type":"play"} | {"type":"pause"} | {"type":"seek", "t":seconds}   replay controls

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace tangent::view {

class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ClientMessage {
  enum class Kind { kNeed, kCamera, kPng, kPlay, kPause, kSeek } kind = Kind::kNeed;
  std::string hash;
  Eigen::Vector3d camera_position = Eigen::Vector3d::Zero(),
                  camera_target = Eigen::Vector3d::Zero();
  int64_t utime = 0;
  std::string png;  ///< decoded PNG bytes
  double t = 0.0;   ///< seconds from the start of the log
};

/// Largest message accepted from a browser: a 4K PNG snapshot fits; anything larger is refused
/// by the WebSocket layer before it is parsed.
inline constexpr size_t kMaxClientMessageBytes = 32u << 20;

/// @throws ProtocolError naming the message type or field that is wrong.
ClientMessage ParseClientMessage(std::string_view text);

/// Standard base64 (RFC 4648, padding required). @throws ProtocolError on any other character or
/// a length that is not a multiple of 4.
std::string DecodeBase64(std::string_view text);

}  // namespace tangent::view
