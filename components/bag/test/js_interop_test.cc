// Our files read by what others wrote, and theirs by us: @mcap/core (Foxglove's TypeScript
// MCAP library, pinned in js/, js/README.md) reads what McapWriter writes with its indexed
// reader (summary, chunk indexes, CRCs) and its stream reader, through test/js/mcap_check.mjs;
// McapReader reads what @mcap/core's McapWriter writes (test/js/mcap_write.mjs). Skipped
// without node or js/node_modules (scripts/install-deps.sh installs both).
#include <gtest/gtest.h>
#include <stdio.h>
#include <sys/wait.h>

#include <array>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "auv/bag/mcap_reader.h"
#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;
using nlohmann::json;

const fs::path kJsDir = AUV_BAG_JS_DIR;
const fs::path kScripts = AUV_BAG_JS_SCRIPTS;

/// Why the node checks cannot run here, or "".
std::string missingNode() {
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    return "node is not installed (scripts/install-deps.sh installs it)";
  }
  if (!fs::exists(kJsDir / "node_modules" / "@mcap" / "core")) {
    return (kJsDir / "node_modules").string() +
           " has no @mcap/core (scripts/install-deps.sh runs npm ci there)";
  }
  return "";
}

/// Runs `command`, returning its standard output; fails the test on a non-zero exit.
std::string run(const std::string& command) {
  FILE* pipe = ::popen(command.c_str(), "r");
  EXPECT_NE(pipe, nullptr) << command;
  if (!pipe) return "";
  std::string out;
  std::array<char, 65536> buffer;
  size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command << "\n" << out;
  return out;
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

std::vector<uint8_t> unhex(const std::string& text) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i + 1 < text.size(); i += 2) {
    out.push_back(static_cast<uint8_t>(std::stoi(text.substr(i, 2), nullptr, 16)));
  }
  return out;
}

/// Messages of the script's JSON as Written, topics through its channel list.
std::vector<Written> messagesOf(const json& messages, const json& channels) {
  std::map<int, std::string> topics;
  for (const json& c : channels) topics[c["id"].get<int>()] = c["topic"].get<std::string>();
  std::vector<Written> out;
  for (const json& m : messages) {
    out.push_back(Written{topics[m["channelId"].get<int>()], m["sequence"].get<uint32_t>(),
                          std::stoull(m["logTime"].get<std::string>()),
                          std::stoull(m["publishTime"].get<std::string>()),
                          unhex(m["data"].get<std::string>())});
  }
  return out;
}

class NodeReads : public ::testing::TestWithParam<std::string> {};

TEST_P(NodeReads, WhatWeWrite) {
  const std::string missing = missingNode();
  if (!missing.empty()) GTEST_SKIP() << missing;
  TempDir dir("node_reads");
  const fs::path path = dir.path() / ("ours_" + GetParam() + ".mcap");
  const std::vector<Written> messages = someMessages(240, 3, 300, 31);
  McapWriterOptions options;
  options.compression = GetParam();
  options.chunk_size = 4096;
  writeBag(path, messages, options);
  McapReader ours;
  ours.open(path);

  const uint64_t start = messages[50].log_time;
  const uint64_t end = messages[150].log_time;
  const std::string output =
      run("node " + quoted(kScripts / "mcap_check.mjs") + " " + quoted(path) +
          " --topic /topic_1 --start " + std::to_string(start) + " --end " + std::to_string(end));
  const json result = json::parse(output);
  ASSERT_FALSE(result.contains("error")) << result["error"];

  const json& indexed = result["indexed"];
  EXPECT_EQ(indexed["header"]["library"], "auv-inspect");
  ASSERT_EQ(indexed["schemas"].size(), 1u);
  EXPECT_EQ(indexed["schemas"][0]["name"], "auv_msgs::msg::Blob");
  EXPECT_EQ(indexed["schemas"][0]["encoding"], "omgidl");
  EXPECT_EQ(indexed["schemas"][0]["data"], ours.schemas().at(1).data);
  ASSERT_EQ(indexed["channels"].size(), 3u);
  for (const json& channel : indexed["channels"]) {
    EXPECT_EQ(channel["messageEncoding"], "cdr");
    EXPECT_EQ(channel["metadata"]["offered_qos_profiles"], "reliable, keep last 10");
  }
  EXPECT_EQ(indexed["chunkCount"], ours.chunkIndexes().size());
  EXPECT_EQ(indexed["statistics"]["messageCount"], "240");
  EXPECT_EQ(indexed["statistics"]["chunkCount"], ours.chunkIndexes().size());
  EXPECT_EQ(indexed["statistics"]["channelMessageCounts"]["2"], "80");
  EXPECT_EQ(indexed["statistics"]["messageStartTime"], std::to_string(messages.front().log_time));
  EXPECT_EQ(indexed["summaryOffsetOpcodes"], json::parse("[3, 4, 8, 11, 13]"));
  EXPECT_NE(indexed["dataSectionCrc"]["stored"], 0);
  EXPECT_EQ(indexed["dataSectionCrc"]["stored"], indexed["dataSectionCrc"]["computed"]);
  ASSERT_EQ(indexed["metadata"].size(), 1u);
  EXPECT_EQ(indexed["metadata"][0]["metadata"]["vehicle"], "sparus");
  EXPECT_EQ(messagesOf(indexed["messages"], indexed["channels"]), inTimeOrder(messages));
  std::vector<Written> filtered;
  for (const Written& w : messages) {
    if (w.topic == "/topic_1" && w.log_time >= start && w.log_time <= end) filtered.push_back(w);
  }
  EXPECT_EQ(messagesOf(indexed["filtered"], indexed["channels"]), filtered);

  const json& stream = result["stream"];
  EXPECT_TRUE(stream["done"].get<bool>());
  EXPECT_EQ(messagesOf(stream["messages"], stream["channels"]), messages);  // file order
  EXPECT_EQ(stream["recordCounts"]["DataEnd"], 1);
  EXPECT_EQ(stream["recordCounts"]["Footer"], 1);
  EXPECT_EQ(stream["recordCounts"]["ChunkIndex"], ours.chunkIndexes().size());
  EXPECT_GE(stream["recordCounts"]["MessageIndex"], ours.chunkIndexes().size());
}

INSTANTIATE_TEST_SUITE_P(Compressions, NodeReads, ::testing::Values("none", "zstd", "lz4"));

class WeRead : public ::testing::TestWithParam<std::string> {};

TEST_P(WeRead, WhatNodeWrites) {
  const std::string missing = missingNode();
  if (!missing.empty()) GTEST_SKIP() << missing;
  TempDir dir("we_read");
  const fs::path path = dir.path() / ("theirs_" + GetParam() + ".mcap");
  const json written = json::parse(
      run("node " + quoted(kScripts / "mcap_write.mjs") + " " + quoted(path) + " " + GetParam()));
  std::vector<Written> expected;
  for (const json& m : written["messages"]) {
    expected.push_back(Written{
        m["topic"], m["sequence"].get<uint32_t>(), std::stoull(m["logTime"].get<std::string>()),
        std::stoull(m["publishTime"].get<std::string>()), unhex(m["data"].get<std::string>())});
  }
  ASSERT_EQ(expected.size(), 300u);

  McapReader reader;
  reader.open(path);
  EXPECT_TRUE(reader.damage().empty()) << damageText(reader);
  // Without chunks nothing is indexed: such a file is read in order, which is no damage.
  EXPECT_EQ(reader.indexed(), GetParam() != "unchunked");
  EXPECT_EQ(reader.header().library, "mcap_write.mjs");
  ASSERT_EQ(reader.channels().size(), 3u);
  EXPECT_EQ(reader.statistics().message_count, 300u);
  EXPECT_EQ(asWritten(reader.readMessages()), inTimeOrder(expected));
  ReadFilter late;
  late.topics = {"/late"};
  std::vector<Written> only_late;
  for (const Written& w : inTimeOrder(expected)) {
    if (w.topic == "/late") only_late.push_back(w);
  }
  const std::vector<BagMessage> read_late = reader.readMessages(late);
  EXPECT_EQ(asWritten(read_late), only_late);
  ASSERT_FALSE(read_late.empty());
  EXPECT_EQ(read_late[0].channel->metadata.at("offered_qos_profiles"), "best_effort");
  ASSERT_NE(read_late[0].schema, nullptr);
  EXPECT_EQ(read_late[0].schema->name, "test_msgs::msg::Ping");
  ASSERT_EQ(reader.metadata().size(), 1u);
  EXPECT_EQ(reader.metadata()[0].metadata.at("writer"), "@mcap/core");
  EXPECT_TRUE(reader.verify()) << damageText(reader);
}

INSTANTIATE_TEST_SUITE_P(Modes, WeRead, ::testing::Values("chunked-lz4", "chunked", "unchunked"));

}  // namespace
}  // namespace auv::bag
