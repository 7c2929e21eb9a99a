#pragma once
// Request/reply on two plain topics, `<name>/request` and `<name>/reply`, with the
// correlation id (RequestHeader: client GUID + sequence number) inside our own IDL types,
// because vendor RPC does not interoperate between Fast DDS and Cyclone DDS
// (rmw_cyclonedds issue 184). Request types have `header`; reply types have `header` and
// `status` (auv::msg::ReplyStatus).

#include <chrono>
#include <cstring>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "auv/interfaces/backend.h"
#include "auv/interfaces/waitable.h"
#include "auv/msg/all.h"

namespace auv::interfaces {

/// Thrown by a service handler to answer with a specific code instead of INTERNAL_ERROR.
class ServiceError : public std::runtime_error {
 public:
  ServiceError(msg::ReplyCode code, const std::string& text) : runtime_error(text), code_(code) {}
  msg::ReplyCode code() const { return code_; }

 private:
  msg::ReplyCode code_;
};

/// Serves requests on the executor that spins its node. The handler fills the reply's
/// payload; the header is copied and the status set to OK unless the handler throws
/// (ServiceError: its code; std::invalid_argument: INVALID_ARGUMENT; else INTERNAL_ERROR).
template <class Req, class Rep>
class Service : public Waitable {
 public:
  using Handler = std::function<void(const Req& request, Rep& reply)>;

  Service(std::string name, Handler handler)
      : name_(std::move(name)), handler_(std::move(handler)) {}
  void attach(std::unique_ptr<DataReader> requests, std::unique_ptr<DataWriter> replies) {
    requests_ = std::move(requests);
    replies_ = std::move(replies);
  }
  void markReady() { ready_ = true; }

  bool execute() override {
    if (!ready_.exchange(false)) return false;
    Req request;
    SampleInfo info;
    while (requests_->take(&request, &info)) {
      // Clients resend until answered: answer a repeat from the cache, never run it twice.
      auto& last = last_reply_[request.header().client_guid()];
      if (request.header().sequence_number() <= last.first) {
        if (request.header().sequence_number() == last.first && last.second) {
          sendReply(*last.second);
        }
        continue;
      }
      // Built in place and kept by pointer: a reply can be a multi-MiB file chunk
      // (bulk_transfer), and copying it into the cache cost a full pass over its bytes.
      auto shared_reply = std::make_shared<Rep>();
      Rep& reply = *shared_reply;
      reply.header(request.header());
      reply.status().code(msg::REPLY_CODE_OK);
      try {
        handler_(request, reply);
      } catch (const ServiceError& e) {
        reply.status().code(e.code());
        reply.status().error_text(e.what());
      } catch (const std::invalid_argument& e) {
        reply.status().code(msg::REPLY_CODE_INVALID_ARGUMENT);
        reply.status().error_text(e.what());
      } catch (const std::exception& e) {
        reply.status().code(msg::REPLY_CODE_INTERNAL_ERROR);
        reply.status().error_text(e.what());
      }
      last = {request.header().sequence_number(), std::move(shared_reply)};
      ++served_;  // before the reply leaves, so a client that got it sees the count
      sendReply(reply);
    }
    return true;
  }
  const std::string& name() const { return name_; }
  uint64_t served() const { return served_; }
  /// Replies the middleware refused (e.g. a reliable writer blocked past its max_blocking_time
  /// by a client that stopped reading); the client's resend gets the cached reply.
  uint64_t failedReplies() const { return failed_replies_; }

 private:
  void sendReply(const Rep& reply) {
    // A reply that cannot be written must not take the server down: clients resend until
    // answered, and a repeat is answered from the cache.
    try {
      replies_->write(&reply);
    } catch (const std::exception&) {
      ++failed_replies_;
    }
  }

  std::string name_;
  Handler handler_;
  std::unique_ptr<DataWriter> replies_;
  std::atomic<bool> ready_{true};
  std::atomic<uint64_t> failed_replies_{0};
  std::atomic<uint64_t> served_{0};
  // Per client: the last sequence number answered and its reply, for repeats.
  std::map<std::array<uint8_t, 16>, std::pair<uint64_t, std::shared_ptr<const Rep>>> last_reply_;
  std::unique_ptr<DataReader> requests_;  // last: destroyed first, before what its callback uses
};

/// Outcome of a Client call that got no reply.
enum class CallStatus { OK, TIMEOUT, NO_SERVICE };

/// Calls a service. Replies are matched in the middleware thread, so a call may block even
/// inside a callback of the same executor without deadlock. Discovery is asymmetric (the
/// client may see the service before the service sees the client), so call() resends an
/// unanswered request every `kResendPeriod`; the service answers repeats from its cache.
template <class Req, class Rep>
class Client {
 public:
  explicit Client(std::string name) : name_(std::move(name)) {}
  static constexpr auto kResendPeriod = std::chrono::milliseconds(500);

  void attach(std::unique_ptr<DataWriter> requests, std::unique_ptr<DataReader> replies) {
    requests_ = std::move(requests);
    replies_ = std::move(replies);
    const Guid guid = requests_->guid();
    std::memcpy(client_id_.data(), guid.data(), 16);
    attached_ = true;
  }

  /// True once a service is matched in both directions (requests and replies).
  bool serviceReady() const {
    return requests_->matchedReaders() > 0 && replies_->matchedWriters() > 0;
  }
  /// Waits until serviceReady() or `timeout`.
  bool waitForService(std::chrono::milliseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!serviceReady()) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return true;
  }

  /// Sends `request` (its header is filled in) and returns the future reply.
  std::future<Rep> callAsync(Req request) {
    uint64_t sequence = 0;
    return send(std::move(request), &sequence);
  }

  /// Sends `request` and waits for its reply up to `timeout`, resending it every
  /// `resend_period` until answered. NO_SERVICE when no service was matched within the
  /// timeout, TIMEOUT when it was but did not answer.
  CallStatus call(const Req& request, Rep* reply, std::chrono::milliseconds timeout,
                  std::chrono::milliseconds resend_period = kResendPeriod) {
    const auto start = std::chrono::steady_clock::now();
    if (!waitForService(timeout)) return CallStatus::NO_SERVICE;
    auto remaining = timeout - std::chrono::duration_cast<std::chrono::milliseconds>(
                                   std::chrono::steady_clock::now() - start);
    uint64_t sequence = 0;
    Req sent = request;
    std::future<Rep> future = send(sent, &sequence);
    const auto deadline = std::chrono::steady_clock::now() + remaining;
    while (future.wait_until(std::min(deadline, std::chrono::steady_clock::now() +
                                                    resend_period)) != std::future_status::ready) {
      if (std::chrono::steady_clock::now() >= deadline) {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_.erase(sequence);
        return CallStatus::TIMEOUT;
      }
      sent.header().client_guid(client_id_);
      sent.header().sequence_number(sequence);
      requests_->write(&sent);
    }
    *reply = future.get();
    return CallStatus::OK;
  }

  /// Called from the middleware thread when replies arrive: keeps ours, drops others'.
  void onReplies(DataReader& replies) {
    if (!attached_) return;
    Rep reply;
    SampleInfo info;
    while (replies.take(&reply, &info)) {
      if (reply.header().client_guid() != client_id_) continue;
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = pending_.find(reply.header().sequence_number());
      if (it == pending_.end()) continue;      // late reply to a call that timed out
      it->second.set_value(std::move(reply));  // no copy of a large reply
      pending_.erase(it);
    }
  }
  const std::string& name() const { return name_; }

 private:
  std::future<Rep> send(Req request, uint64_t* sequence) {
    std::future<Rep> future;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      *sequence = ++sequence_;
      request.header().client_guid(client_id_);
      request.header().sequence_number(*sequence);
      future = pending_[*sequence].get_future();
    }
    requests_->write(&request);
    return future;
  }

  std::string name_;
  std::unique_ptr<DataWriter> requests_;
  std::atomic<bool> attached_{false};
  std::array<uint8_t, 16> client_id_{};
  std::mutex mutex_;
  uint64_t sequence_ = 0;
  std::map<uint64_t, std::promise<Rep>> pending_;
  std::unique_ptr<DataReader> replies_;  // last: destroyed first, before what its callback uses
};

}  // namespace auv::interfaces
