#define ASIO_STANDALONE
#include "view/web_server.h"

#include <chrono>
#include <csignal>
#include <fstream>
#include <map>
#include <sstream>

#include <asio.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace tangent::view {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;

std::string ContentType(const std::string& path) {
  auto ends = [&](const std::string& e) {
    return path.size() >= e.size() && path.compare(path.size() - e.size(), e.size(), e) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".json")) return "application/json";
  return "application/octet-stream";
}

}  // namespace

struct WebServer::Impl {
  std::string web_root;
  Handlers handlers;
  asio::io_context io;
  WsServer ws;
  asio::signal_set signals{io, SIGINT, SIGTERM};
  std::map<Hdl, ClientId, std::owner_less<Hdl>> ids;
  std::map<ClientId, Hdl> hdls;
  ClientId next_id = 1;
  std::vector<std::unique_ptr<asio::steady_timer>> timers;

  void OnHttp(Hdl h) {
    auto con = ws.get_con_from_hdl(h);
    std::string path = con->get_resource();
    path = path.substr(0, path.find('?'));
    std::string file;
    if (path == "/" || path == "/index.html") {
      file = web_root + "/index.html";
    } else if (path == "/view.js") {
      file = web_root + "/view.js";
    } else if (path.rfind("/three/", 0) == 0 && path.find("..") == std::string::npos) {
      file = web_root + "/node_modules" + path;
    }
    std::ifstream in(file, std::ios::binary);
    if (file.empty() || !in) {
      con->set_status(websocketpp::http::status_code::not_found);
      std::string body = "not found: " + path;
      if (path.rfind("/three/", 0) == 0)
        body += " (three.js comes from npm: scripts/install-web.sh)";
      con->set_body(body);
      return;
    }
    std::ostringstream body;
    body << in.rdbuf();
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", ContentType(file));
    con->append_header("Cache-Control", "no-cache");
    con->set_body(body.str());
  }

  void Forget(Hdl h) {
    const auto it = ids.find(h);
    if (it == ids.end()) return;
    const ClientId id = it->second;
    hdls.erase(id);
    ids.erase(it);
    if (handlers.close) handlers.close(id);
  }

  void Repeat(asio::steady_timer* t, std::chrono::microseconds period, std::function<void()> fn) {
    t->expires_after(period);
    t->async_wait([this, t, period, fn = std::move(fn)](const asio::error_code& e) {
      if (e) return;
      fn();
      Repeat(t, period, fn);
    });
  }
};

WebServer::WebServer(std::string web_root, size_t max_message_bytes, Handlers handlers)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.web_root = std::move(web_root);
  s.handlers = std::move(handlers);
  s.ws.clear_access_channels(websocketpp::log::alevel::all);
  s.ws.clear_error_channels(websocketpp::log::elevel::all);
  s.ws.init_asio(&s.io);
  s.ws.set_reuse_addr(true);
  s.ws.set_max_message_size(max_message_bytes);
  s.ws.set_http_handler([&s](Hdl h) { s.OnHttp(h); });
  s.ws.set_open_handler([&s](Hdl h) {
    const ClientId id = s.next_id++;
    s.ids[h] = id;
    s.hdls[id] = h;
    if (s.handlers.open) s.handlers.open(id);
  });
  s.ws.set_close_handler([&s](Hdl h) { s.Forget(h); });
  s.ws.set_fail_handler([&s](Hdl h) { s.Forget(h); });
  s.ws.set_message_handler([&s](Hdl h, WsServer::message_ptr m) {
    const auto it = s.ids.find(h);
    if (it != s.ids.end() && s.handlers.message) s.handlers.message(it->second, m->get_payload());
  });
}

WebServer::~WebServer() = default;

int WebServer::Listen(const std::string& bind, int port, std::string* error) {
  asio::error_code ec;
  const asio::ip::address address = asio::ip::make_address(bind, ec);
  if (ec) {
    *error = "\"" + bind + "\" is not an IP address";
    return -1;
  }
  impl_->ws.listen(asio::ip::tcp::endpoint(address, static_cast<unsigned short>(port)), ec);
  if (!ec) impl_->ws.start_accept(ec);
  if (ec) {
    *error = "cannot listen on " + bind + ":" + std::to_string(port) + ": " + ec.message();
    return -1;
  }
  return impl_->ws.get_local_endpoint(ec).port();
}

void WebServer::Send(ClientId client, const std::string& text) {
  const auto it = impl_->hdls.find(client);
  if (it == impl_->hdls.end()) return;
  websocketpp::lib::error_code ec;
  impl_->ws.send(it->second, text, websocketpp::frame::opcode::text, ec);
}

size_t WebServer::Buffered(ClientId client) const {
  const auto it = impl_->hdls.find(client);
  if (it == impl_->hdls.end()) return 0;
  websocketpp::lib::error_code ec;
  const auto con = impl_->ws.get_con_from_hdl(it->second, ec);
  return ec ? 0 : con->get_buffered_amount();
}

void WebServer::Every(double seconds, std::function<void()> fn) {
  impl_->timers.push_back(std::make_unique<asio::steady_timer>(impl_->io));
  impl_->Repeat(impl_->timers.back().get(),
                std::chrono::microseconds(static_cast<int64_t>(seconds * 1e6)), std::move(fn));
}

void WebServer::After(double seconds, std::function<void()> fn) {
  impl_->timers.push_back(std::make_unique<asio::steady_timer>(impl_->io));
  asio::steady_timer* t = impl_->timers.back().get();
  t->expires_after(std::chrono::microseconds(static_cast<int64_t>(seconds * 1e6)));
  t->async_wait([fn = std::move(fn)](const asio::error_code& e) {
    if (!e) fn();
  });
}

void WebServer::OnStopSignal(std::function<void()> fn) {
  impl_->signals.async_wait([fn = std::move(fn)](const asio::error_code& e, int) {
    if (!e) fn();
  });
}

void WebServer::Run() { impl_->io.run(); }

void WebServer::Stop() {
  Impl& s = *impl_;
  websocketpp::lib::error_code ec;
  s.ws.stop_listening(ec);
  for (const auto& [id, h] : s.hdls) s.ws.close(h, websocketpp::close::status::going_away, "", ec);
  for (auto& t : s.timers) t->cancel();
  asio::error_code aec;
  s.signals.cancel(aec);
  s.io.stop();
}

}  // namespace tangent::view
