#pragma once

// The HTTP and WebSocket server of tangent-view, with its event loop (timers, SIGINT/SIGTERM),
// behind an interface free of websocketpp and asio. websocketpp 0.8.2 (Debian 12) only compiles as
// C++17, so it lives in this one translation unit built as C++17; everything else stays C++20.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace tangent::view {

class WebServer {
 public:
  using ClientId = uint64_t;
  struct Handlers {
    std::function<void(ClientId)> open, close;
    std::function<void(ClientId, const std::string&)> message;
  };

  /// Serves GET / (index.html), /view.js and /three/... (web_root/node_modules/three/...) over
  /// HTTP, and WebSocket connections on the same port. Text messages larger than
  /// `max_message_bytes` close the connection (the WebSocket "message too big" status).
  WebServer(std::string web_root, size_t max_message_bytes, Handlers handlers);
  ~WebServer();

  /// @return the port listened on (a free one when `port` is 0), or −1 with *error set.
  int Listen(const std::string& bind, int port, std::string* error);
  /// Queues a text message; a closed or unknown client is ignored.
  void Send(ClientId client, const std::string& text);
  /// Bytes queued for the client and not yet written to its socket.
  size_t Buffered(ClientId client) const;
  /// Calls fn every `seconds` until Stop.
  void Every(double seconds, std::function<void()> fn);
  /// Calls fn once after `seconds`.
  void After(double seconds, std::function<void()> fn);
  /// Calls fn on SIGINT or SIGTERM.
  void OnStopSignal(std::function<void()> fn);
  /// Runs the loop until Stop.
  void Run();
  /// Closes every connection, stops listening and ends Run.
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tangent::view
