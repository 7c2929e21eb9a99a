#pragma once
// A Node is one component's presence on DDS: its own participant (so `auv node list` shows
// it), its parameters, logger and clock, and the publishers, subscriptions, timers and
// services it creates. Like an rclcpp node, its callbacks run when an Executor spins it.

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "auv/interfaces/backend.h"
#include "auv/interfaces/clock.h"
#include "auv/interfaces/logging.h"
#include "auv/interfaces/parameters.h"
#include "auv/interfaces/publisher.h"
#include "auv/interfaces/service.h"
#include "auv/interfaces/subscription.h"
#include "auv/interfaces/timer.h"
#include "auv/interfaces/waitable.h"
#include "auv/msg/all.h"

namespace auv::interfaces {

struct NodeOptions {
  std::optional<Vendor> vendor;           ///< Default: AUV_DDS (cyclonedds).
  std::optional<int> domain_id;           ///< Default: AUV_DOMAIN_ID (0).
  std::vector<std::string> params_files;  ///< YAML parameter files, loaded in order.
  std::vector<std::string> overrides;     ///< "name:=value" assignments (command line).
};

/// Options for a node on `vendor` and `domain_id` with "name:=value" overrides: the usual case
/// in component tests (each on its own domain) and benchmarks.
inline NodeOptions nodeOptions(Vendor vendor, int domain_id,
                               std::vector<std::string> overrides = {}) {
  NodeOptions options;
  options.vendor = vendor;
  options.domain_id = domain_id;
  options.overrides = std::move(overrides);
  return options;
}

class Node {
 public:
  /// Creates the participant and reads the node's built-in parameters: `use_sim_time`
  /// (bool, follow the `clock` topic) and `log_level`. Throws ParameterError or
  /// std::runtime_error with the offending parameter, file or vendor.
  explicit Node(const std::string& name, const NodeOptions& options = {});
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return name_; }
  Vendor vendor() const { return participant_->vendor(); }
  int domainId() const { return domain_id_; }
  Parameters& parameters() { return *parameters_; }
  const Logger& logger() const { return logger_; }
  const Clock& clock() const { return *clock_; }
  Participant& participant() { return *participant_; }

  /// Publisher of T on `topic` with the `qos` profile (overridable by the string parameter
  /// `qos.<topic>`, e.g. `qos.nav/odometry: sensor_data`).
  template <class T>
  std::shared_ptr<Publisher<T>> createPublisher(const std::string& topic, const QosProfile& qos);

  /// Subscription of T. By default `callback` runs on the executor spinning this node, one
  /// callback at a time with the node's other callbacks.
  ///
  /// With `options.callback_thread = CallbackThread::MIDDLEWARE` it runs instead in the DDS
  /// vendor's thread that delivers the data, with no executor involved (the node need not be
  /// spun at all): for latency-critical relays that do their own locking. Threading contract
  /// of such a callback:
  ///  * it runs concurrently with this node's executor callbacks and with other middleware
  ///    callbacks, on threads the vendor owns; for a publisher in the same process it may run
  ///    inside that publisher's publish() call, on the publishing thread. Calls for one
  ///    subscription never overlap (both vendors serialize listener calls per reader).
  ///  * it must be thread-safe: guard any state it shares with other callbacks yourself.
  ///  * it must not block (no waiting on locks held for long, no sleeps, no blocking service
  ///    calls): while it runs, that vendor thread delivers nothing else.
  ///  * it must never destroy its own subscription (deleting a reader waits for its running
  ///    callbacks: a deadlock). Destroy it from another thread; once the destructor returns
  ///    no callback runs any more.
  template <class T>
  std::shared_ptr<Subscription<T>> createSubscription(const std::string& topic,
                                                      const QosProfile& qos,
                                                      std::function<void(const T&)> callback,
                                                      const SubscriptionOptions& options = {});
  template <class T>
  std::shared_ptr<Subscription<T>> createSubscription(const std::string& topic,
                                                      const QosProfile& qos,
                                                      typename Subscription<T>::Callback callback,
                                                      const SubscriptionOptions& options = {});

  /// Timer on the node's clock; the first call is one period from now.
  std::shared_ptr<Timer> createTimer(double period_s, std::function<void()> callback);

  /// Service on `<name>/request` and `<name>/reply`.
  template <class Req, class Rep>
  std::shared_ptr<Service<Req, Rep>> createService(const std::string& name,
                                                   typename Service<Req, Rep>::Handler handler,
                                                   const QosProfile& qos = commandQos());
  template <class Req, class Rep>
  std::shared_ptr<Client<Req, Rep>> createClient(const std::string& name,
                                                 const QosProfile& qos = commandQos());

  /// Runs every ready callback of this node once; returns true if any ran. Called by the one
  /// executor spinning this node, from its thread.
  bool executeReady();
  /// Steady-clock nanoseconds until the earliest timer is due (nullopt: no system timer).
  std::optional<int64_t> nanosecondsUntilNextTimer() const;
  /// Woken whenever this node has work; an Executor forwards it to its own.
  const std::shared_ptr<Waker>& waker() const { return waker_; }

 private:
  QosProfile resolveQos(const std::string& topic, const QosProfile& qos);
  template <class T>
  static const msg::TypeSupport& typeSupport();
  void addWaitable(const std::shared_ptr<Waitable>& waitable);

  std::string name_;
  int domain_id_ = 0;
  std::unique_ptr<Parameters> parameters_;
  Logger logger_;
  std::unique_ptr<Clock> clock_;
  std::unique_ptr<Participant> participant_;
  std::shared_ptr<Waker> waker_;
  mutable std::mutex mutex_;
  std::vector<std::weak_ptr<Waitable>> waitables_;
  std::vector<std::shared_ptr<Waitable>> execute_scratch_;  // executeReady() only (one thread)
  std::unique_ptr<DataWriter> log_writer_;                  // LogEntry on `log`
  // Last, so it is destroyed first: its callback uses the members above.
  std::unique_ptr<DataReader> clock_reader_;  // simulation time, taken in the DDS thread
};

// ---------------------------------------------------------------------------------------
// Template definitions.

template <class T>
const msg::TypeSupport& Node::typeSupport() {
  static const msg::TypeSupport support = msg::makeTypeSupport<T>();
  return support;
}

template <class T>
std::shared_ptr<Publisher<T>> Node::createPublisher(const std::string& topic,
                                                    const QosProfile& qos) {
  const QosProfile resolved = resolveQos(topic, qos);
  return std::make_shared<Publisher<T>>(
      topic, resolved, participant_->createWriter(topic, typeSupport<T>(), resolved));
}

template <class T>
std::shared_ptr<Subscription<T>> Node::createSubscription(
    const std::string& topic, const QosProfile& qos, typename Subscription<T>::Callback callback,
    const SubscriptionOptions& options) {
  const QosProfile resolved = resolveQos(topic, qos);
  auto subscription = std::make_shared<Subscription<T>>(topic, resolved, std::move(callback),
                                                        options.callback_thread);
  // Raw pointer, not a shared_ptr: the subscription owns the reader, whose deletion waits for
  // running callbacks; a callback holding a reference could end up deleting its own reader.
  Subscription<T>* raw = subscription.get();
  DataCallback on_data;
  if (options.callback_thread == CallbackThread::MIDDLEWARE) {
    on_data = [raw](DataReader& reader) { raw->onData(reader); };
  } else {
    std::shared_ptr<Waker> waker = waker_;
    on_data = [raw, waker](DataReader&) {
      if (raw->markReady()) waker->notify();  // a burst costs one wake-up, not one per sample
    };
  }
  subscription->attach(
      participant_->createReader(topic, typeSupport<T>(), resolved, std::move(on_data)));
  // A middleware-thread subscription has nothing for the executor to do.
  if (options.callback_thread == CallbackThread::EXECUTOR) {
    addWaitable(subscription);
    // It starts ready (history may be waiting), so arrivals skip the wake-up until it has
    // run once: have the executor run it now.
    waker_->notify();
  }
  return subscription;
}

template <class T>
std::shared_ptr<Subscription<T>> Node::createSubscription(const std::string& topic,
                                                          const QosProfile& qos,
                                                          std::function<void(const T&)> callback,
                                                          const SubscriptionOptions& options) {
  return createSubscription<T>(
      topic, qos,
      typename Subscription<T>::Callback(
          [cb = std::move(callback)](const T& message, const SampleInfo&) { cb(message); }),
      options);
}

/// The QoS of a service's reply writer and a client's request writer: keep-all becomes
/// keep-last as deep as the profile's sample limit. A keep-all writer blocks, then fails, once
/// its history is full of samples a reader has not acknowledged yet: a client gone but still
/// matched (Fast DDS 2.9 writers keep vanished Cyclone clients for a while), or requests sent
/// faster than acknowledgements come back (a Fast DDS client pulling 256 KiB chunks at
/// ~250 MB/s from a Cyclone service); then every caller waits. A request or reply lost that
/// way is repeated by the client.
inline QosProfile serviceWriterQos(QosProfile qos) {
  if (qos.history == History::KEEP_ALL) {
    qos.history = History::KEEP_LAST;
    qos.depth = qos.max_samples > 0 ? qos.max_samples : 256;
  }
  return qos;
}

template <class Req, class Rep>
std::shared_ptr<Service<Req, Rep>> Node::createService(const std::string& name,
                                                       typename Service<Req, Rep>::Handler handler,
                                                       const QosProfile& qos) {
  auto service = std::make_shared<Service<Req, Rep>>(name, std::move(handler));
  Service<Req, Rep>* raw = service.get();  // owns the reader: see createSubscription
  std::shared_ptr<Waker> waker = waker_;
  auto requests = participant_->createReader(name + "/request", typeSupport<Req>(), qos,
                                             [raw, waker](DataReader&) {
                                               raw->markReady();
                                               waker->notify();
                                             });
  service->attach(
      std::move(requests),
      participant_->createWriter(name + "/reply", typeSupport<Rep>(), serviceWriterQos(qos)));
  addWaitable(service);
  return service;
}

template <class Req, class Rep>
std::shared_ptr<Client<Req, Rep>> Node::createClient(const std::string& name,
                                                     const QosProfile& qos) {
  auto client = std::make_shared<Client<Req, Rep>>(name);
  Client<Req, Rep>* raw = client.get();  // owns the reader: see createSubscription
  auto replies = participant_->createReader(name + "/reply", typeSupport<Rep>(), qos,
                                            [raw](DataReader& reader) { raw->onReplies(reader); });
  client->attach(
      participant_->createWriter(name + "/request", typeSupport<Req>(), serviceWriterQos(qos)),
      std::move(replies));
  return client;
}

}  // namespace auv::interfaces
