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
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "auv/interfaces/serialized.h"
#include "serialized_test_util.h"

namespace auv::interfaces {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

const fs::path kRepository = AUV_SOURCE_ROOT;
const fs::path kScript = kRepository / "interfaces/test/js/decode_cdr.mjs";

// A YAML document as a plain tree, so a filler can change one leaf and put it back.
struct Value {
  enum Kind { SCALAR, MAP, SEQUENCE } kind = SCALAR;
  std::string scalar;
  std::vector<std::pair<std::string, Value>> map;
  std::vector<Value> sequence;
};

Value fromNode(const YAML::Node& node) {
  Value v;
  if (node.IsMap()) {
    v.kind = Value::MAP;
    for (const auto& entry : node) v.map.emplace_back(entry.first.Scalar(), fromNode(entry.second));
  } else if (node.IsSequence()) {
    v.kind = Value::SEQUENCE;
    for (const auto& element : node) v.sequence.push_back(fromNode(element));
  } else {
    v.scalar = node.Scalar();
  }
  return v;
}

YAML::Node toNode(const Value& v) {
  if (v.kind == Value::MAP) {
    YAML::Node node(YAML::NodeType::Map);
    for (const auto& [key, value] : v.map) node[key] = toNode(value);
    return node;
  }
  if (v.kind == Value::SEQUENCE) {
    YAML::Node node(YAML::NodeType::Sequence);
    for (const Value& element : v.sequence) node.push_back(toNode(element));
    return node;
  }
  return YAML::Node(v.scalar);
}

// Builds a sample of `type` with a non-default value in every field, nested structs and
// sequence elements included, through the type's own from_yaml: each leaf gets the first
// candidate the type accepts (so a float gets a fraction, an int64 a value beyond 32 bits, a
// uint64 one beyond 63 bits, an enum its last enumerator), each empty sequence two or three
// elements.
class SampleFiller {
 public:
  explicit SampleFiller(const msg::TypeSupport& type) : type_(type) {
    const auto sample = type.create_sample();
    root_ = fromNode(type.to_yaml(sample.get()));
    for (bool grew = true; grew;) {
      grew = fill(root_, "");
      root_ = fromNode(type_.to_yaml(sample_().get()));  // new struct elements get their fields
    }
  }
  std::shared_ptr<void> sample() { return sample_(); }

 private:
  std::shared_ptr<void> sample_() {
    auto sample = type_.create_sample();
    type_.from_yaml(toNode(root_), sample.get());
    return sample;
  }
  std::string error() {
    try {
      sample_();
      return "";
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
  }
  bool accepts() { return error().empty(); }

  // True when it added struct elements to a sequence (their fields come next round).
  bool fill(Value& v, const std::string& path) {
    if (filled_.count(path)) return false;
    bool grew = false;
    if (v.kind == Value::MAP) {
      for (auto& [key, value] : v.map) grew = fill(value, path + "." + key) || grew;
    } else if (v.kind == Value::SEQUENCE && v.sequence.empty()) {
      grew = fillSequence(v, path);
    } else if (v.kind == Value::SEQUENCE) {
      for (size_t i = 0; i < v.sequence.size(); ++i)
        grew = fill(v.sequence[i], path + "[" + std::to_string(i) + "]") || grew;
    } else {
      fillScalar(v, path);
    }
    return grew;
  }

  std::vector<std::string> numbers() {
    const int k = ++counter_;
    return {std::to_string(k) + ".1",                     // float, double
            std::to_string(-(7123456789012LL + k)),       // int64
            std::to_string(-(k + 7)),                     // int16, int32
            std::to_string(12345678901234567890ULL - k),  // uint64
            std::to_string(k % 250 + 1)};                 // octet, uint16, uint32
  }

  // The enumerators, as the error for an unknown one lists them.
  std::vector<std::string> enumerators(Value& v) {
    const std::string old = v.scalar;
    v.scalar = "?";
    const std::string what = error();
    v.scalar = old;
    const size_t begin = what.find("one of [");
    const size_t end = what.find(']', begin);
    std::vector<std::string> names;
    if (begin == std::string::npos || end == std::string::npos) return names;
    std::string list = what.substr(begin + 8, end - begin - 8) + ", ";
    for (size_t at; (at = list.find(", ")) != std::string::npos; list.erase(0, at + 2))
      names.push_back(list.substr(0, at));
    return names;
  }

  void fillScalar(Value& v, const std::string& path) {
    filled_.insert(path);
    std::vector<std::string> candidates;
    if (v.scalar == "false")
      candidates = {"true"};
    else if (v.scalar.empty())
      candidates = {"text " + std::to_string(++counter_) + " \xc3\xbc"};  // UTF-8 too
    else if (v.scalar == "0")
      candidates = numbers();
    else if (const auto names = enumerators(v); !names.empty())
      candidates = {names.back()};
    for (const std::string& candidate : candidates) {
      const std::string old = v.scalar;
      v.scalar = candidate;
      if (accepts()) return;
      v.scalar = old;
    }
    ADD_FAILURE() << type_.name << path << ": no value accepted";
  }

  bool fillSequence(Value& v, const std::string& path) {
    const auto list = [](std::vector<std::string> scalars) {
      Value seq;
      seq.kind = Value::SEQUENCE;
      for (auto& s : scalars) seq.sequence.push_back(Value{Value::SCALAR, s, {}, {}});
      return seq;
    };
    Value structs;
    structs.kind = Value::SEQUENCE;
    structs.sequence.resize(2, Value{Value::MAP, "", {}, {}});
    std::vector<Value> candidates = {structs, list({"word a", "word b \xc3\xbc"}),
                                     list({"true", "false", "true"})};
    const std::vector<std::vector<std::string>> three = {numbers(), numbers(), numbers()};
    for (size_t i = 0; i < three.front().size(); ++i)
      candidates.push_back(list({three[0][i], three[1][i], three[2][i]}));
    // A sequence of an enum: its enumerators, as the error for an unknown one lists them.
    const Value before = v;
    v = list({"?"});
    const std::vector<std::string> names = enumerators(v.sequence.front());
    v = before;
    if (!names.empty()) candidates.push_back(list({names.back(), names.front()}));
    for (size_t i = 0; i < candidates.size(); ++i) {
      Value old = v;
      v = candidates[i];
      if (accepts()) {
        if (i != 0) filled_.insert(path);
        return i == 0;
      }
      v = old;
    }
    ADD_FAILURE() << type_.name << path << ": no sequence accepted";
    return false;
  }

  const msg::TypeSupport& type_;
  Value root_;
  std::set<std::string> filled_;  // paths of leaves and sequences given their value
  int counter_ = 0;
};

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
