// Service bookkeeping without a middleware: the endpoints are in-memory queues, so a reply
// writer can be made to fail on purpose (a DDS writer does when a reliable reader stops
// acknowledging). Request/reply over real DDS is in interop_test.cc.
#include "auv/interfaces/service.h"

#include <gtest/gtest.h>

#include <deque>

namespace auv::interfaces {
namespace {

class QueueReader : public DataReader {
 public:
  std::deque<msg::TriggerRequest> samples;
  bool take(void* sample, SampleInfo*) override {
    if (samples.empty()) return false;
    *static_cast<msg::TriggerRequest*>(sample) = samples.front();
    samples.pop_front();
    return true;
  }
  int matchedWriters() const override { return 1; }
  Guid guid() const override { return {}; }
};

class FlakyWriter : public DataWriter {
 public:
  int failures_left = 0;
  std::vector<msg::TriggerReply> written;
  void write(const void* sample) override {
    if (failures_left > 0) {
      --failures_left;
      throw std::runtime_error("write timed out");
    }
    written.push_back(*static_cast<const msg::TriggerReply*>(sample));
  }
  int matchedReaders() const override { return 1; }
  bool waitForAcknowledgments(double) override { return true; }
  Guid guid() const override { return {}; }
};

msg::TriggerRequest request(uint64_t sequence) {
  msg::TriggerRequest r;
  r.header().client_guid()[0] = 7;
  r.header().sequence_number(sequence);
  return r;
}

TEST(ServiceTest, AReplyThatCannotBeWrittenIsCountedAndResentFromTheCache) {
  int handled = 0;
  Service<msg::TriggerRequest, msg::TriggerReply> service(
      "test", [&](const msg::TriggerRequest&, msg::TriggerReply& reply) {
        ++handled;
        reply.message("done " + std::to_string(handled));
      });
  auto reader = std::make_unique<QueueReader>();
  auto writer = std::make_unique<FlakyWriter>();
  QueueReader* requests = reader.get();
  FlakyWriter* replies = writer.get();
  service.attach(std::move(reader), std::move(writer));

  replies->failures_left = 1;
  requests->samples.push_back(request(1));
  ASSERT_NO_THROW(service.execute());
  EXPECT_EQ(service.failedReplies(), 1u);
  EXPECT_TRUE(replies->written.empty());

  // The client resends: answered from the cache, the handler does not run twice.
  service.markReady();
  requests->samples.push_back(request(1));
  service.execute();
  ASSERT_EQ(replies->written.size(), 1u);
  EXPECT_EQ(replies->written[0].message(), "done 1");
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(service.served(), 1u);
}

}  // namespace
}  // namespace auv::interfaces
