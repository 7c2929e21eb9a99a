#include "ws_client.h"

#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

#include <thread>

namespace auv::foxglove_bridge::test {

using Client = websocketpp::client<websocketpp::config::asio_client>;

struct WsClient::Impl {
  Client client;
  websocketpp::connection_hdl handle;
  std::thread thread;
};

WsClient::WsClient(const std::string& uri, const std::string& subprotocol)
    : impl_(std::make_unique<Impl>()) {
  Client& c = impl_->client;
  c.clear_access_channels(websocketpp::log::alevel::all);
  c.clear_error_channels(websocketpp::log::elevel::all);
  c.init_asio();
  c.set_max_message_size(256 << 20);
  const auto notify = [this] {
    std::lock_guard<std::mutex> lock(mutex_);
    changed_.notify_all();
  };
  c.set_open_handler([this, notify](websocketpp::connection_hdl) {
    open_ = true;
    notify();
  });
  c.set_fail_handler([this, notify](websocketpp::connection_hdl h) {
    http_status_ = impl_->client.get_con_from_hdl(h)->get_response_code();
    failed_ = true;
    notify();
  });
  c.set_close_handler([this, notify](websocketpp::connection_hdl) {
    closed_ = true;
    notify();
  });
  c.set_message_handler([this](websocketpp::connection_hdl, Client::message_ptr m) {
    if (delay_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_));
    const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
    std::lock_guard<std::mutex> lock(mutex_);
    if (m->get_opcode() == websocketpp::frame::opcode::text) {
      texts_.push_back(nlohmann::json::parse(m->get_payload(), nullptr, false));
    } else {
      const std::string& p = m->get_payload();
      frames_.emplace_back(p.begin(), p.end());
      frame_times_.push_back(now);
    }
    changed_.notify_all();
  });
  websocketpp::lib::error_code ec;
  auto con = c.get_connection(uri, ec);
  if (ec) {
    failed_ = true;
    return;
  }
  if (!subprotocol.empty()) con->add_subprotocol(subprotocol);
  impl_->handle = con->get_handle();
  c.connect(con);
  impl_->thread = std::thread([this] { impl_->client.run(); });
}

WsClient::~WsClient() {
  websocketpp::lib::error_code ec;
  if (open_ && !closed_)
    impl_->client.close(impl_->handle, websocketpp::close::status::normal, "", ec);
  delay_ = 0;
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  impl_->client.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool WsClient::waitOpen(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return changed_.wait_for(lock, timeout, [this] { return open_ || failed_; }) && open_;
}

void WsClient::sendText(const std::string& text) {
  websocketpp::lib::error_code ec;
  impl_->client.send(impl_->handle, text, websocketpp::frame::opcode::text, ec);
}

void WsClient::sendBinary(const std::vector<uint8_t>& bytes) {
  websocketpp::lib::error_code ec;
  impl_->client.send(impl_->handle, bytes.data(), bytes.size(), websocketpp::frame::opcode::binary,
                     ec);
}

bool WsClient::waitFor(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (pred()) return true;
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_for(lock, std::chrono::milliseconds(20));
  }
  return pred();
}

std::vector<nlohmann::json> WsClient::texts(const std::string& op) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<nlohmann::json> out;
  for (const auto& t : texts_)
    if (op.empty() || (t.is_object() && t.value("op", "") == op)) out.push_back(t);
  return out;
}

std::vector<std::vector<uint8_t>> WsClient::frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_;
}

std::vector<int64_t> WsClient::frameTimes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frame_times_;
}

int64_t WsClient::channel(const std::string& topic) const {
  int64_t id = -1;
  for (const auto& m : texts()) {
    if (m.value("op", "") == "advertise")
      for (const auto& c : m["channels"])
        if (c["topic"] == topic) id = c["id"];
    if (m.value("op", "") == "unadvertise")
      for (const auto& c : m["channelIds"])
        if (c == id) id = -1;
  }
  return id;
}

void WsClient::subscribe(uint32_t subscription, uint32_t channel) {
  sendText(nlohmann::json{{"op", "subscribe"},
                          {"subscriptions", {{{"id", subscription}, {"channelId", channel}}}}}
               .dump());
}

}  // namespace auv::foxglove_bridge::test
