// The schemas and bytes a recorder or bridge hands on, checked with what Foxglove itself
// runs: for every type of the message set, a sample with non-default values in every field
// travels from a typed writer to a serialized reader of the other vendor, and Foxglove's
// @foxglove/omgidl-parser + omgidl-serialization (pinned in js/, driven by
// test/js/decode_cdr.mjs) decode the received bytes with TypeSupport::omg_idl into exactly
// the values sent. Skipped without node or js/node_modules (scripts/install-deps.sh).
// Domain 57 (test/README.md).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "auv/interfaces/serialized.h"
#include "sample_filler.h"
#include "serialized_test_util.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using test::fromNode;
using test::SampleFiller;
using test::Value;

const fs::path kRepository = AUV_SOURCE_ROOT;
const fs::path kScript = kRepository / "interfaces/test/js/decode_cdr.mjs";

// Runs decode_cdr.mjs on one sample; returns its stdout, or fails.
std::string decodeWithFoxglove(const std::string& schema_name, const std::string& idl,
                               const std::vector<uint8_t>& cdr, const fs::path& scratch) {
  const fs::path idl_file = scratch / "schema.idl";
  const fs::path cdr_file = scratch / "sample.cdr";
  std::ofstream(idl_file) << idl;
  std::ofstream(cdr_file, std::ios::binary)
      .write(reinterpret_cast<const char*>(cdr.data()), static_cast<std::streamsize>(cdr.size()));
  const std::string command = "node '" + kScript.string() + "' '" + schema_name + "' '" +
                              idl_file.string() + "' '" + cdr_file.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  std::string output;
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) output.append(buffer, n);
  const int status = ::pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << schema_name << ": " << output;
  return output;
}

class FoxgloveDecodeTest : public testing::Test {
 protected:
  void SetUp() override {
    if (std::system("node --version > /dev/null 2>&1") != 0)
      GTEST_SKIP() << "node not found: scripts/install-deps.sh installs it";
    if (!fs::exists(kRepository / "js/node_modules/@foxglove/omgidl-serialization"))
      GTEST_SKIP() << (kRepository / "js/node_modules").string()
                   << " is missing: scripts/install-deps.sh runs npm ci there";
  }
};

TEST_F(FoxgloveDecodeTest, EveryTypeDecodesFromItsSchemaIntoTheValuesSent) {
  const int domain = 57;
  const fs::path scratch = fs::temp_directory_path() / ("auv_foxglove_" + std::to_string(getpid()));
  fs::create_directories(scratch);
  // Across vendors both ways: the bytes cross the network (alignment padding included).
  for (const test::VendorPair& pair : {test::kPairs[2], test::kPairs[3]}) {
    SCOPED_TRACE(test::pairName(pair));
    auto sender = createParticipant(pair.writer, {domain, "sender"});
    auto recorder = createParticipant(pair.reader, {domain, "recorder"});
    struct Case {
      const msg::TypeSupport* type;
      std::shared_ptr<void> sample;
      std::unique_ptr<DataWriter> writer;
      std::unique_ptr<test::Collector> received;
      std::unique_ptr<SerializedReader> reader;
    };
    std::vector<Case> cases;
    for (const msg::TypeSupport& type : msg::allTypes()) {
      const std::string topic =
          "foxglove/" + test::pairName(pair) + "/" + type.name.substr(type.name.rfind(':') + 1);
      Case c{&type, SampleFiller(type).sample(), nullptr, std::make_unique<test::Collector>(),
             nullptr};
      // Transient local: written once, it reaches the reader whenever they match.
      c.writer = sender->createWriter(topic, type, latchedStateQos());
      c.writer->write(c.sample.get());
      c.reader =
          recorder->createSerializedReader(topic, type, latchedStateQos(), c.received->callback());
      cases.push_back(std::move(c));
    }
    for (Case& c : cases) {
      SCOPED_TRACE(c.type->name);
      ASSERT_TRUE(c.received->waitFor(1, 20s));
      const std::vector<uint8_t> cdr = c.received->samples().front().cdr;
      const std::string json = decodeWithFoxglove(c.type->name, c.type->omg_idl, cdr, scratch);
      auto decoded = c.type->create_sample();
      try {
        c.type->from_yaml(YAML::Load(json), decoded.get());
      } catch (const std::exception& e) {
        ADD_FAILURE() << "Foxglove's decode does not fit the type: " << e.what() << "\n" << json;
        continue;
      }
      EXPECT_EQ(YAML::Dump(c.type->to_yaml(decoded.get())),
                YAML::Dump(c.type->to_yaml(c.sample.get())))
          << json;
      EXPECT_EQ(test::cdrOf(*c.type, decoded.get()), test::cdrOf(*c.type, c.sample.get()));
    }
  }
  fs::remove_all(scratch);
}

TEST_F(FoxgloveDecodeTest, FillerLeavesNoFieldAtItsDefault) {
  // The check above only means something if the samples are far from default: every leaf
  // of a filled Odometry differs from the default's.
  const msg::TypeSupport& type = typeSupportByName("Odometry");
  const auto filled = SampleFiller(type).sample();
  const auto blank = type.create_sample();
  const Value a = fromNode(type.to_yaml(filled.get()));
  const Value b = fromNode(type.to_yaml(blank.get()));
  std::function<void(const Value&, const Value&, const std::string&)> differ =
      [&](const Value& x, const Value& y, const std::string& path) {
        if (x.kind == Value::MAP) {
          for (size_t i = 0; i < x.map.size(); ++i)
            differ(x.map[i].second, y.map[i].second, path + "." + x.map[i].first);
        } else if (x.kind == Value::SEQUENCE) {
          if (y.sequence.size() != x.sequence.size()) return;  // a filled sequence
          for (size_t i = 0; i < x.sequence.size(); ++i)
            differ(x.sequence[i], y.sequence[i], path + "[" + std::to_string(i) + "]");
        } else {
          EXPECT_NE(x.scalar, y.scalar) << path;
        }
      };
  differ(a, b, "");
  const YAML::Node yaml = type.to_yaml(filled.get());
  EXPECT_GT(yaml["header"]["stamp"]["nanosec"].as<uint64_t>(), 0u);
  EXPECT_LT(yaml["header"]["stamp"]["sec"].as<int64_t>(), 0);
}

}  // namespace
}  // namespace auv::interfaces
