#pragma once

#include <memory>
#include <string>

#include "auv/interfaces/backend.h"

namespace auv::interfaces {

/// Publishes messages of type T on one topic. Created by Node::createPublisher.
template <class T>
class Publisher {
 public:
  Publisher(std::string topic, QosProfile qos, std::unique_ptr<DataWriter> writer)
      : topic_(std::move(topic)), qos_(std::move(qos)), writer_(std::move(writer)) {}
  /// Sends one message; throws std::runtime_error naming the topic on failure.
  void publish(const T& message) { writer_->write(&message); }
  /// Subscriptions currently matched, of both vendors.
  int matchedSubscriptions() const { return writer_->matchedReaders(); }
  /// Waits until matched reliable subscriptions acknowledged everything; false on timeout.
  bool waitForAcknowledgments(double timeout_s) { return writer_->waitForAcknowledgments(timeout_s); }
  const std::string& topic() const { return topic_; }
  const QosProfile& qos() const { return qos_; }
  Guid guid() const { return writer_->guid(); }

 private:
  std::string topic_;
  QosProfile qos_;
  std::unique_ptr<DataWriter> writer_;
};

}  // namespace auv::interfaces
