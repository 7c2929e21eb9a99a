#include "auv/foxglove_bridge/websocket_server.h"

#ifndef ASIO_STANDALONE
#define ASIO_STANDALONE  // websocketpp on Debian's standalone asio (libasio-dev)
#endif
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <chrono>
#include <stdexcept>

namespace auv::foxglove_bridge {
namespace {

using Server = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string percentDecoded(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '%' && i + 2 < text.size() && hexValue(text[i + 1]) >= 0 &&
        hexValue(text[i + 2]) >= 0) {
      out += static_cast<char>(hexValue(text[i + 1]) * 16 + hexValue(text[i + 2]));
      i += 2;
    } else {
      out += text[i] == '+' ? ' ' : text[i];
    }
  }
  return out;
}

// Equal strings in time that depends on the lengths only.
bool sameSecret(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  return diff == 0;
}

}  // namespace

bool resourceHasToken(const std::string& resource, const std::string& token) {
  const size_t query = resource.find('?');
  if (query == std::string::npos) return false;
  bool found = false;
  size_t start = query + 1;
  while (start <= resource.size()) {
    size_t end = resource.find('&', start);
    if (end == std::string::npos) end = resource.size();
    const std::string pair = resource.substr(start, end - start);
    if (pair.rfind("token=", 0) == 0)
      found = sameSecret(percentDecoded(pair.substr(6)), token) || found;
    start = end + 1;
  }
  return found;
}

struct WebSocketServer::Impl {
  Server server;
  std::thread thread;
  BridgeCore* core = nullptr;
  std::mutex mutex;  // the maps below
  std::map<ClientId, Handle> handles;
  std::map<Handle, ClientId, std::owner_less<Handle>> ids;
  ClientId next_id = 1;

  Server::connection_ptr connection(ClientId client, ClientId* found = nullptr) {
    Handle handle;
    {
      std::lock_guard<std::mutex> lock(mutex);
      const auto it = handles.find(client);
      if (it == handles.end()) return nullptr;
      handle = it->second;
      if (found) *found = it->first;
    }
    websocketpp::lib::error_code ec;
    auto con = server.get_con_from_hdl(handle, ec);
    return ec ? nullptr : con;
  }
};

WebSocketServer::WebSocketServer(ServerOptions options)
    : impl_(std::make_unique<Impl>()), options_(std::move(options)) {
  Server& s = impl_->server;
  // websocketpp would print every connection and error on stdout/stderr: the bridge reports.
  s.clear_access_channels(websocketpp::log::alevel::all);
  s.clear_error_channels(websocketpp::log::elevel::all);
  s.init_asio();
  s.set_reuse_addr(true);
  s.set_max_message_size(options_.max_client_message);
  websocketpp::lib::error_code ec;
  asio::error_code address_error;
  const auto address = asio::ip::make_address(options_.address, address_error);
  if (address_error)
    throw std::runtime_error("address '" + options_.address +
                             "': not an IP address: " + address_error.message());
  s.listen(asio::ip::tcp::endpoint(address, options_.port), ec);
  if (ec)
    throw std::runtime_error("cannot listen on " + options_.address + ":" +
                             std::to_string(options_.port) + ": " + ec.message());
  asio::error_code endpoint_error;
  port_ = s.get_local_endpoint(endpoint_error).port();
}

WebSocketServer::~WebSocketServer() { stop(); }

void WebSocketServer::start(BridgeCore& core) {
  Impl& impl = *impl_;
  impl.core = &core;
  Server& s = impl.server;
  s.set_validate_handler([this, &impl](Handle handle) {
    auto con = impl.server.get_con_from_hdl(handle);
    bool subprotocol = false;
    for (const std::string& p : con->get_requested_subprotocols())
      subprotocol = subprotocol || p == kSubprotocol;
    if (!subprotocol) {
      ++refused_;
      con->set_status(websocketpp::http::status_code::bad_request,
                      std::string("this server speaks the subprotocol ") + kSubprotocol);
      return false;
    }
    if (!options_.token.empty() && !resourceHasToken(con->get_resource(), options_.token)) {
      ++refused_;
      con->set_status(websocketpp::http::status_code::unauthorized,
                      "an access token is required: ws://host:port/?token=...");
      return false;
    }
    con->select_subprotocol(kSubprotocol);
    return true;
  });
  s.set_open_handler([&impl](Handle handle) {
    ClientId id;
    {
      std::lock_guard<std::mutex> lock(impl.mutex);
      id = impl.next_id++;
      impl.handles[id] = handle;
      impl.ids[handle] = id;
    }
    impl.core->clientConnected(id);
  });
  const auto closed = [&impl](Handle handle) {
    ClientId id = 0;
    {
      std::lock_guard<std::mutex> lock(impl.mutex);
      const auto it = impl.ids.find(handle);
      if (it == impl.ids.end()) return;
      id = it->second;
      impl.handles.erase(id);
      impl.ids.erase(it);
    }
    impl.core->clientDisconnected(id);
  };
  s.set_close_handler(closed);
  s.set_fail_handler(closed);
  s.set_message_handler([&impl](Handle handle, Server::message_ptr message) {
    ClientId id = 0;
    {
      std::lock_guard<std::mutex> lock(impl.mutex);
      const auto it = impl.ids.find(handle);
      if (it == impl.ids.end()) return;
      id = it->second;
    }
    const std::string& payload = message->get_payload();
    if (message->get_opcode() == websocketpp::frame::opcode::text) {
      impl.core->textMessage(id, payload);
    } else {
      impl.core->binaryMessage(id, reinterpret_cast<const uint8_t*>(payload.data()),
                               payload.size());
    }
  });
  websocketpp::lib::error_code ec;
  s.start_accept(ec);
  if (ec) throw std::runtime_error("cannot accept connections: " + ec.message());
  impl.thread = std::thread([&impl] {
    // A handler's exception must not end the server thread: log-free retry of run().
    while (true) {
      try {
        impl.server.run();
        break;
      } catch (const std::exception&) {
        continue;
      }
    }
  });
}

void WebSocketServer::stop() {
  Impl& impl = *impl_;
  if (!impl.thread.joinable()) return;
  asio::post(impl.server.get_io_service(), [&impl] {
    websocketpp::lib::error_code ec;
    impl.server.stop_listening(ec);
    std::vector<Handle> open;
    {
      std::lock_guard<std::mutex> lock(impl.mutex);
      for (const auto& entry : impl.handles) open.push_back(entry.second);
    }
    for (const Handle& handle : open)
      impl.server.close(handle, websocketpp::close::status::going_away, "bridge stopping", ec);
  });
  // Give the closing handshakes a moment, then stop whatever is left.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(impl.mutex);
      if (impl.handles.empty()) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  impl.server.stop();
  impl.thread.join();
}

void WebSocketServer::sendText(ClientId client, const std::string& text) {
  auto con = impl_->connection(client);
  if (!con) return;  // gone meanwhile
  websocketpp::lib::error_code ec;
  con->send(text, websocketpp::frame::opcode::text);
}

void WebSocketServer::sendBinary(ClientId client, std::vector<uint8_t> frame, bool droppable) {
  auto con = impl_->connection(client);
  if (!con) return;
  const size_t queued = con->get_buffered_amount();
  if (droppable && queued + frame.size() > options_.send_buffer_limit) {
    ++dropped_;
    return;
  }
  if (queued + frame.size() > kReliableLimitFactor * options_.send_buffer_limit) {
    ++overflow_disconnects_;
    websocketpp::lib::error_code ec;
    con->close(websocketpp::close::status::policy_violation,
               "send buffer limit exceeded: the client does not keep up", ec);
    return;
  }
  con->send(frame.data(), frame.size(), websocketpp::frame::opcode::binary);
}

}  // namespace auv::foxglove_bridge
