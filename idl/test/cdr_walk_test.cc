// Every payload is walked (MessageTraits<T>::walkCdr) before fastddsgen's code decodes it: the
// walk must read exactly what the decoder reads, and a sample whose sequences claim more
// elements than the bytes hold must be refused before the decoder sizes a vector for them.
#include <gtest/gtest.h>

#include <cstring>

#include "auv/msg/all.h"

namespace auv::msg {
namespace {

using eprosima::fastrtps::rtps::SerializedPayload_t;

SerializedPayload_t serialize(eprosima::fastdds::dds::TopicDataType& tdt, void* sample) {
  SerializedPayload_t payload(tdt.getSerializedSizeProvider(sample)());
  EXPECT_TRUE(tdt.serialize(sample, &payload)) << tdt.getName();
  return payload;
}

TEST(CdrWalkTest, FilledSamplesOfEveryTypeRoundTripAndNoTruncationPasses) {
  for (const TypeSupport& ts : allTypes()) {
    SCOPED_TRACE(ts.name);
    std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(ts.make_topic_data_type());
    const auto sample = filledSample(ts);
    const SerializedPayload_t payload = serialize(*tdt, sample.get());
    auto decoded = ts.create_sample();
    SerializedPayload_t copy(payload.length);
    copy.length = payload.length;
    std::memcpy(copy.data, payload.data, payload.length);
    ASSERT_TRUE(tdt->deserialize(&copy, decoded.get()));
    EXPECT_EQ(YAML::Dump(ts.to_yaml(decoded.get())), YAML::Dump(ts.to_yaml(sample.get())));
    // The payload ends with the last member's bytes: every shorter one lacks some.
    for (uint32_t length = 0; length < payload.length; ++length) {
      copy.length = length;
      auto out = ts.create_sample();
      EXPECT_FALSE(tdt->deserialize(&copy, out.get())) << length << " of " << payload.length;
    }
  }
}

/// A StartMissionRequest of `queries` whose length field then claims `claimed` queries.
SerializedPayload_t missionClaiming(size_t queries, uint32_t claimed) {
  GuardedPubSubType<StartMissionRequest> tdt;
  StartMissionRequest request;
  request.mission_id("m");
  // `queries` is the last member: without queries, its length is the payload's last 4 bytes.
  const uint32_t length_at = serialize(tdt, &request).length - 4;
  request.queries().resize(queries);
  SerializedPayload_t payload = serialize(tdt, &request);
  uint32_t written;
  std::memcpy(&written, payload.data + length_at, 4);
  EXPECT_EQ(written, queries);
  std::memcpy(payload.data + length_at, &claimed, 4);
  return payload;
}

TEST(CdrWalkTest, ASequenceClaimingMoreElementsThanItsBytesIsRefusedBeforeDecoding) {
  GuardedPubSubType<StartMissionRequest> tdt;
  SerializedPayload_t honest = missionClaiming(3, 3);
  StartMissionRequest decoded;
  ASSERT_TRUE(tdt.deserialize(&honest, &decoded));
  EXPECT_EQ(decoded.queries().size(), 3u);

  // Three whole queries, a length of a thousand: fastcdr accepts the length (it is below the
  // bytes left) and would size the vector (~560 bytes a query: a million cost ~560 MB) before
  // finding the end.
  SerializedPayload_t lying = missionClaiming(3, 1000);
  StartMissionRequest out;
  out.mission_id("untouched");
  EXPECT_FALSE(tdt.deserialize(&lying, &out));
  EXPECT_EQ(out.mission_id(), "untouched");  // the decoder never ran
  EXPECT_TRUE(out.queries().empty());
  EXPECT_FALSE(holdsWholeSample<StartMissionRequest>(lying));
  EXPECT_TRUE(holdsWholeSample<StartMissionRequest>(honest));
}

TEST(CdrWalkTest, PrimitiveSequencesAreSkippedButStillBoundedByTheirBytes) {
  GuardedPubSubType<OctomapUpdate> tdt;
  OctomapUpdate map;
  map.data().assign(1000, 7);
  SerializedPayload_t payload = serialize(tdt, &map);
  OctomapUpdate out;
  ASSERT_TRUE(tdt.deserialize(&payload, &out));
  EXPECT_EQ(out.data().size(), 1000u);
  payload.length -= 1;  // the last data byte is gone
  EXPECT_FALSE(holdsWholeSample<OctomapUpdate>(payload));
}

}  // namespace
}  // namespace auv::msg
