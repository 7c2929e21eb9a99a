// The message set must mean the same thing to both vendors' generators, and the YAML
// conversion used by the CLI must round-trip and reject bad input by naming the field.
#include <gtest/gtest.h>

#include <dds/dds.h>

#include <cstring>

#include "auv/msg/all.h"
#include "idlc_headers.h"

namespace auv::msg {
namespace {

struct IdlcType {
  const dds_topic_descriptor_t* descriptor;
  const char* name;
  bool keyed;
};

#define AUV_IDLC_TYPE(desc, name, keyed) {&desc, name, keyed},
const std::vector<IdlcType> kIdlcTypes = {
#include "idlc_descriptors.inc"
};

TEST(TypeSupportTest, IdlcAndFastddsgenAgreeOnEveryTypeNameAndKey) {
  ASSERT_EQ(kIdlcTypes.size(), allTypes().size());
  for (const IdlcType& idlc : kIdlcTypes) {
    EXPECT_STREQ(idlc.descriptor->m_typename, idlc.name);
    const TypeSupport* ts = findType(idlc.name);
    ASSERT_NE(ts, nullptr) << idlc.name;
    std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(ts->make_topic_data_type());
    EXPECT_EQ(tdt->getName(), std::string(idlc.name));
    EXPECT_EQ(tdt->m_isGetKeyDefined, idlc.keyed) << idlc.name;
    EXPECT_EQ(idlc.descriptor->m_nkeys > 0, idlc.keyed) << idlc.name;
  }
}

TEST(TypeSupportTest, FindTypeAcceptsScopedSlashAndShortNames) {
  const TypeSupport* a = findType("auv::msg::Odometry");
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(findType("auv/msg/Odometry"), a);
  EXPECT_EQ(findType("Odometry"), a);
  EXPECT_EQ(findType("NoSuchType"), nullptr);
}

TEST(TypeSupportTest, EveryTypeRoundTripsThroughYamlAndCdr) {
  for (const TypeSupport& ts : allTypes()) {
    auto sample = ts.create_sample();
    const YAML::Node yaml = ts.to_yaml(sample.get());
    auto back = ts.create_sample();
    ts.from_yaml(yaml, back.get());
    EXPECT_EQ(YAML::Dump(ts.to_yaml(back.get())), YAML::Dump(yaml)) << ts.name;

    std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(ts.make_topic_data_type());
    eprosima::fastrtps::rtps::SerializedPayload_t payload(
        tdt->getSerializedSizeProvider(back.get())());
    ASSERT_TRUE(tdt->serialize(back.get(), &payload)) << ts.name;
    auto decoded = ts.create_sample();
    ASSERT_TRUE(tdt->deserialize(&payload, decoded.get())) << ts.name;
    EXPECT_EQ(YAML::Dump(ts.to_yaml(decoded.get())), YAML::Dump(yaml)) << ts.name;
  }
}

TEST(TypeSupportTest, TruncatedOrCorruptPayloadsAreRejectedNotFatal) {
  for (const TypeSupport& ts : allTypes()) {
    std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(ts.make_topic_data_type());
    auto sample = ts.create_sample();
    eprosima::fastrtps::rtps::SerializedPayload_t payload(
        tdt->getSerializedSizeProvider(sample.get())());
    ASSERT_TRUE(tdt->serialize(sample.get(), &payload)) << ts.name;
    // Every truncation of a valid payload: never a crash; when bytes of the body are missing
    // the result is a failure, not a silently half-filled sample passed on as valid.
    for (uint32_t length = 0; length + 1 < payload.length; ++length) {
      eprosima::fastrtps::rtps::SerializedPayload_t cut(payload.length);
      std::memcpy(cut.data, payload.data, length);
      cut.length = length;
      auto out = ts.create_sample();
      const bool ok = tdt->deserialize(&cut, out.get());
      if (length < 4) EXPECT_FALSE(ok) << ts.name << " accepted " << length << " bytes";
    }
  }
  // A string length field that points far beyond the payload.
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> tdt(
      findType("String")->make_topic_data_type());
  String text;
  text.data("hello");
  eprosima::fastrtps::rtps::SerializedPayload_t payload(tdt->getSerializedSizeProvider(&text)());
  ASSERT_TRUE(tdt->serialize(&text, &payload));
  const uint32_t huge = 0x7fffff00;
  std::memcpy(payload.data + 4, &huge, 4);  // after the 4-byte encapsulation header
  String out;
  EXPECT_FALSE(tdt->deserialize(&payload, &out));
}

TEST(TypeSupportTest, YamlFillsNestedFieldsEnumsAndSequences) {
  Odometry odom;
  const YAML::Node yaml = YAML::Load(
      "{header: {frame_id: world, stamp: {sec: 12, nanosec: 5}},"
      " pose: {pose: {position: {x: 1.5, y: -2, z: 3}}}}");
  fromYaml(yaml, odom, "");
  EXPECT_EQ(odom.header().frame_id(), "world");
  EXPECT_EQ(odom.header().stamp().sec(), 12);
  EXPECT_DOUBLE_EQ(odom.pose().pose().position().y(), -2.0);
  EXPECT_EQ(toYaml(odom)["pose"]["pose"]["position"]["x"].as<double>(), 1.5);
}

TEST(TypeSupportTest, BadYamlNamesTheField) {
  Odometry odom;
  try {
    fromYaml(YAML::Load("{pose: {pose: {position: {x: abc}}}}"), odom, "");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pose.pose.position.x"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'abc'"), std::string::npos) << e.what();
  }
  try {
    fromYaml(YAML::Load("{pose: {psoe: 1}}"), odom, "");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown field 'pose.psoe'"), std::string::npos)
        << e.what();
  }
  Time t;
  EXPECT_THROW(fromYaml(YAML::Load("{nanosec: -1}"), t, ""), std::invalid_argument);
  EXPECT_THROW(fromYaml(YAML::Load("{sec: 99999999999}"), t, ""), std::invalid_argument);
}

// The schemas themselves are decoded by Foxglove's reader in interfaces/test/serialized_test.cc;
// this checks what makes them self-contained and readable by it.
TEST(TypeSupportTest, EverySchemaDeclaresWhatItUsesBeforeTheType) {
  for (const TypeSupport& ts : allTypes()) {
    const std::string idl = ts.omg_idl;
    const std::string short_name = ts.name.substr(ts.name.rfind(':') + 1);
    const size_t root = idl.find("struct " + short_name + " {");
    ASSERT_NE(root, std::string::npos) << ts.name << ":\n" << idl;
    EXPECT_EQ(idl.find("struct ", root + 1), std::string::npos) << ts.name << ": root not last";
    EXPECT_EQ(idl.find("module auv {\nmodule msg {"), idl.find("module")) << ts.name;
    for (const char* absent :
         {"#include", "#ifndef", "#define", "= 0x", " _header;", "struct _String"})
      EXPECT_EQ(idl.find(absent), std::string::npos) << ts.name << " holds " << absent;
  }
  const std::string odometry = findType("Odometry")->omg_idl;
  const size_t time = odometry.find("struct Time {");
  const size_t header = odometry.find("struct Header {");
  ASSERT_NE(time, std::string::npos);
  ASSERT_NE(header, std::string::npos);
  EXPECT_LT(time, header);
  EXPECT_LT(header, odometry.find("struct Odometry {"));
  EXPECT_NE(odometry.find("  Header header;"), std::string::npos);
  EXPECT_NE(odometry.find("ODOMETRY_SOURCE_GROUND_TRUTH   = 64;"), std::string::npos);
  EXPECT_NE(odometry.find("// m, distance to the seabed"), std::string::npos);  // comments kept
  // Each declaration once, even when two members use it.
  const std::string update = findType("OctomapUpdate")->omg_idl;
  EXPECT_EQ(update.find("struct Point {"), update.rfind("struct Point {"));
}

}  // namespace
}  // namespace auv::msg
