// `auv bag record` and `auv bag play` on real DDS (domains 14-19 and 28, test/README.md): every
// type of the message set, published by either vendor, is recorded with its schema and QoS, read
// back by @mcap/core and decoded by Foxglove's modules into the values published, and played
// back into typed readers of both vendors unchanged; play keeps the recorded order and
// spacing and scales it by --rate; filters; and the programs as a user runs them refuse bad
// arguments (exit 2, naming them) and play the intact part of a cut bag (exit 1).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "auv/bag/dds/player.h"
#include "auv/bag/dds/qos_metadata.h"
#include "auv/bag/dds/recorder.h"
#include "auv/interfaces/msg_time.h"
#include "auv/interfaces/serialized.h"
#include "auv/msg/all.h"
#include "bag_test_util.h"
#include "sample_filler.h"
#include "serialized_test_util.h"

namespace auv::bag {
namespace {

using namespace ::testing;
using namespace auv::bag::testing;
using namespace std::chrono_literals;
using interfaces::Vendor;
using nlohmann::json;

struct CommandRun {
  int exit_code = -1;
  std::string out;  // stdout and stderr
};

CommandRun runCommand(const std::string& command) {
  CommandRun run;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return run;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) run.out.append(buffer, n);
  const int status = ::pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

std::string shortName(const msg::TypeSupport& type) {
  return type.name.substr(type.name.rfind(':') + 1);
}

/// Waits until `done` or `timeout`.
template <class Done>
bool waitUntil(Done done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(20ms);
  }
  return true;
}

/// One sample of every type on "/bag/<vendor>/<Type>", transient local so that the recorder
/// gets it whenever it matches, from a participant of each vendor.
struct EveryType {
  struct Case {
    const msg::TypeSupport* type;
    std::string topic;
    std::shared_ptr<void> sample;
    std::unique_ptr<interfaces::DataWriter> writer;
  };
  std::vector<std::unique_ptr<interfaces::Participant>> senders;
  std::vector<Case> cases;

  /// Without a domain (-1): the same cases, published nowhere (values to compare with).
  explicit EveryType(int domain) {
    for (Vendor vendor : {Vendor::CYCLONEDDS, Vendor::FASTDDS}) {
      if (domain >= 0) senders.push_back(interfaces::createParticipant(vendor, {domain, "sender"}));
      for (const msg::TypeSupport& type : msg::allTypes()) {
        Case c{&type, "/bag/" + interfaces::toString(vendor) + "/" + shortName(type),
               interfaces::test::SampleFiller(type).sample(), nullptr};
        if (domain >= 0) {
          c.writer = senders.back()->createWriter(c.topic, type, interfaces::latchedStateQos());
          c.writer->write(c.sample.get());
        }
        cases.push_back(std::move(c));
      }
    }
  }
  std::string yamlOf(const Case& c) const { return YAML::Dump(c.type->to_yaml(c.sample.get())); }
};

RecorderOptions recorderOptions(const fs::path& output, int domain) {
  RecorderOptions options;
  options.output = output.string();
  options.domain_id = domain;
  options.vendor = "cyclonedds";
  return options;
}

TEST(RecordPlay, EveryTypeOfEitherVendorIsRecordedWithItsSchemaAndQos) {
  const int domain = 14;
  TempDir dir("record_every_type");
  const fs::path bag = dir.path() / "every_type.mcap";
  EveryType every(domain);
  {
    Recorder recorder(recorderOptions(bag, domain));
    recorder.start();
    ASSERT_TRUE(waitUntil(
        [&] {
          const auto stats = recorder.stats();
          size_t with_sample = 0;
          for (const auto& topic : stats.topics) with_sample += topic.messages > 0;
          return with_sample == every.cases.size();
        },
        30s))
        << recorder.recordedTopics() << " of " << every.cases.size() << " topics";
    recorder.stop();
    for (const auto& topic : recorder.stats().topics) EXPECT_EQ(topic.lost, 0u) << topic.topic;
  }
  EXPECT_FALSE(fs::exists(bag.string() + ".part"));

  McapReader reader;
  reader.open(bag);
  EXPECT_TRUE(reader.indexed());
  EXPECT_TRUE(reader.verify());
  std::map<std::string, const Channel*> channels;
  for (const auto& [id, channel] : reader.channels()) channels[channel.topic] = &channel;
  for (const auto& c : every.cases) {
    SCOPED_TRACE(c.topic);
    ASSERT_TRUE(channels.count(c.topic));
    const Channel& channel = *channels[c.topic];
    const Schema& schema = reader.schemas().at(channel.schema_id);
    EXPECT_EQ(schema.name, c.type->name);
    EXPECT_EQ(schema.encoding, "omgidl");
    EXPECT_EQ(std::string(schema.data.begin(), schema.data.end()), c.type->omg_idl);
    EXPECT_EQ(channel.message_encoding, "cdr");
    const auto qos = qosFromMetadata(channel.metadata, interfaces::commandQos());
    EXPECT_EQ(qos.reliability, interfaces::Reliability::RELIABLE);
    EXPECT_EQ(qos.durability, interfaces::Durability::TRANSIENT_LOCAL);
  }
  // The bytes are the sample's CDR as published.
  ReadFilter filter;
  for (const auto& message : reader.readMessages(filter)) {
    for (const auto& c : every.cases) {
      if (c.topic != message.channel->topic) continue;
      auto decoded = c.type->create_sample();
      ASSERT_TRUE(interfaces::test::decodeInto(*c.type, message.message.data, decoded.get()))
          << c.topic;
      EXPECT_EQ(YAML::Dump(c.type->to_yaml(decoded.get())), every.yamlOf(c)) << c.topic;
    }
  }

  // What others wrote reads it: @mcap/core (CRCs, indexes) and Foxglove's OMG IDL decoder
  // with the schema in the file give the values published.
  if (std::system("node --version > /dev/null 2>&1") != 0 ||
      !fs::exists(fs::path(AUV_BAG_JS_DIR) / "node_modules/@foxglove/omgidl-serialization")) {
    GTEST_SKIP() << "node or js/node_modules missing: scripts/install-deps.sh installs them";
  }
  const CommandRun decoded = runCommand("node '" + std::string(AUV_BAG_JS_SCRIPTS) +
                                        "/mcap_decode.mjs' '" + bag.string() + "'");
  ASSERT_EQ(decoded.exit_code, 0) << decoded.out;
  const json result = json::parse(decoded.out);
  for (const auto& c : every.cases) {
    SCOPED_TRACE(c.topic);
    const json& channel = result["channels"][c.topic];
    ASSERT_EQ(channel["messages"].size(), 1u);
    auto sample = c.type->create_sample();
    c.type->from_yaml(YAML::Load(channel["messages"][0].get<std::string>()), sample.get());
    EXPECT_EQ(YAML::Dump(c.type->to_yaml(sample.get())), every.yamlOf(c));
  }
}

TEST(RecordPlay, PlayedSamplesReachTypedReadersOfBothVendorsUnchanged) {
  const int domain = 15;
  TempDir dir("play_every_type");
  const fs::path bag = dir.path() / "every_type.mcap";
  {
    EveryType every(domain);
    Recorder recorder(recorderOptions(bag, domain));
    recorder.start();
    ASSERT_TRUE(
        waitUntil([&] { return recorder.stats().writer.messages == every.cases.size(); }, 30s));
    recorder.stop();
  }  // the senders are gone: what arrives now comes from the bag

  // Typed readers of the other vendor than each sample's writer; transient local, as recorded.
  const EveryType expected(-1);
  std::vector<std::unique_ptr<interfaces::Participant>> listeners;
  for (Vendor vendor : {Vendor::FASTDDS, Vendor::CYCLONEDDS})
    listeners.push_back(interfaces::createParticipant(vendor, {domain, "listener"}));
  struct Received {
    std::mutex mutex;
    std::string yaml;
  };
  std::vector<std::unique_ptr<Received>> received;
  std::vector<std::unique_ptr<interfaces::DataReader>> readers;
  for (size_t i = 0; i < expected.cases.size(); ++i) {
    const auto& c = expected.cases[i];
    received.push_back(std::make_unique<Received>());
    Received* into = received.back().get();
    const auto* type = c.type;
    auto& listener = *listeners[i < expected.cases.size() / 2 ? 0 : 1];
    readers.push_back(listener.createReader(
        c.topic, *type, interfaces::latchedStateQos(), [into, type](interfaces::DataReader& r) {
          auto sample = type->create_sample();
          while (r.take(sample.get(), nullptr)) {
            std::lock_guard<std::mutex> lock(into->mutex);
            into->yaml = YAML::Dump(type->to_yaml(sample.get()));
          }
        }));
  }
  PlayerOptions options;
  options.input = bag.string();
  options.domain_id = domain;
  options.vendor = "fastdds";
  options.delay_s = 0.5;
  Player player(options);
  EXPECT_TRUE(player.skipped().empty());
  std::atomic<bool> stop{false};
  const PlayStats stats = player.play(stop);
  EXPECT_EQ(stats.messages, expected.cases.size());
  EXPECT_EQ(stats.refused, 0u);
  for (size_t i = 0; i < expected.cases.size(); ++i) {
    SCOPED_TRACE(expected.cases[i].topic);
    EXPECT_TRUE(waitUntil(
        [&] {
          std::lock_guard<std::mutex> lock(received[i]->mutex);
          return !received[i]->yaml.empty();
        },
        10s));
    std::lock_guard<std::mutex> lock(received[i]->mutex);
    EXPECT_EQ(received[i]->yaml, expected.yamlOf(expected.cases[i]));
  }
}

/// Records `count` String samples "0", "1", ... on /bag/timing every `period`.
fs::path recordSequence(const fs::path& dir, int domain, int count,
                        std::chrono::milliseconds period) {
  const fs::path bag = dir / "timing.mcap";
  auto sender = interfaces::createParticipant(Vendor::CYCLONEDDS, {domain, "sender"});
  const auto& type = interfaces::typeSupportByName("String");
  auto writer = sender->createWriter("/bag/timing", type, interfaces::commandQos());
  Recorder recorder(recorderOptions(bag, domain));
  recorder.start();
  EXPECT_TRUE(waitUntil([&] { return writer->matchedReaders() > 0; }, 10s));
  for (int i = 0; i < count; ++i) {
    msg::String text;
    text.data(std::to_string(i));
    writer->write(&text);
    std::this_thread::sleep_for(period);
  }
  EXPECT_TRUE(writer->waitForAcknowledgments(5.0));
  recorder.stop();
  return bag;
}

TEST(RecordPlay, PlayKeepsOrderAndSpacingScaledByRate) {
  const int domain = 16;
  TempDir dir("timing");
  const fs::path bag = recordSequence(dir.path(), domain, 20, 50ms);

  auto listener = interfaces::createParticipant(Vendor::FASTDDS, {domain, "listener"});
  std::mutex mutex;
  std::vector<std::pair<std::string, std::chrono::steady_clock::time_point>> arrivals;
  auto reader = listener->createReader("/bag/timing", interfaces::typeSupportByName("String"),
                                       interfaces::commandQos(), [&](interfaces::DataReader& r) {
                                         msg::String text;
                                         while (r.take(&text, nullptr)) {
                                           std::lock_guard<std::mutex> lock(mutex);
                                           arrivals.emplace_back(text.data(),
                                                                 std::chrono::steady_clock::now());
                                         }
                                       });
  const auto span_at = [&](double rate) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      arrivals.clear();
    }
    PlayerOptions options;
    options.input = bag.string();
    options.domain_id = domain;
    options.rate = rate;
    options.delay_s = 0.5;
    std::atomic<bool> stop{false};
    Player(options).play(stop);
    waitUntil(
        [&] {
          std::lock_guard<std::mutex> lock(mutex);
          return arrivals.size() >= 20;
        },
        5s);
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_EQ(arrivals.size(), 20u);
    for (size_t i = 0; i < arrivals.size(); ++i) EXPECT_EQ(arrivals[i].first, std::to_string(i));
    return arrivals.empty()
               ? 0.0
               : std::chrono::duration<double>(arrivals.back().second - arrivals.front().second)
                     .count();
  };
  // Recorded over 19 periods of 50 ms (0.95 s): at rate 1 about that, at rate 4 a quarter. The
  // bounds only tell the rates apart; they do not time the machine.
  const double normal = span_at(1.0);
  const double fast = span_at(4.0);
  EXPECT_GT(normal, 0.6);
  EXPECT_LT(fast, normal / 2);
}

// A bag without a recorded clock (a real dive) played for nodes with use_sim_time: the player
// publishes the bag's time on `clock`, advancing at `rate` through the bag's span and held at
// its end; a bag with its own clock is refused (two clocks would fight).
TEST(RecordPlay, ClockOptionPublishesTheBagsTimeAtTheRate) {
  const int domain = 28;
  TempDir dir("clock");
  const fs::path bag = recordSequence(dir.path(), domain, 20, 50ms);
  McapReader reader;
  reader.open(bag);
  const uint64_t start = reader.statistics().message_start_time,
                 end = reader.statistics().message_end_time;
  ASSERT_GT(end, start + 500000000ULL);

  auto listener = interfaces::createParticipant(Vendor::FASTDDS, {domain, "listener"});
  std::mutex mutex;
  std::vector<int64_t> times;
  auto clock_reader =
      listener->createReader("clock", msg::makeTypeSupport<msg::Clock>(), interfaces::clockQos(),
                             [&](interfaces::DataReader& r) {
                               msg::Clock clock;
                               while (r.take(&clock, nullptr)) {
                                 std::lock_guard<std::mutex> lock(mutex);
                                 times.push_back(interfaces::toNanoseconds(clock.sim_time()));
                               }
                             });
  PlayerOptions options;
  options.input = bag.string();
  options.domain_id = domain;
  options.rate = 2.0;
  options.delay_s = 1.0;
  options.clock_hz = 100;
  std::atomic<bool> stop{false};
  Player player(options);
  player.play(stop);
  // The last time published is the bag's end (best effort: wait for it to arrive).
  waitUntil(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return !times.empty() && static_cast<uint64_t>(times.back()) >= end;
      },
      5s);
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GT(times.size(), 10u);
  for (size_t i = 1; i < times.size(); ++i) ASSERT_GE(times[i], times[i - 1]) << i;
  EXPECT_GE(static_cast<uint64_t>(times.front()), start);
  EXPECT_LE(static_cast<uint64_t>(times.back()), end);
  EXPECT_EQ(static_cast<uint64_t>(times.back()), end);
  // ... reached by steps through the bag (every 10 ms of wall time, 20 ms of bag time at rate 2;
  // 10 or more however loaded the machine), not in one jump.
  const size_t inside = std::count_if(times.begin(), times.end(), [&](int64_t t) {
    return static_cast<uint64_t>(t) > start && static_cast<uint64_t>(t) < end;
  });
  EXPECT_GE(inside, 10u);

  // The bag records its own clock: refused, naming the option.
  {
    auto sender = interfaces::createParticipant(Vendor::CYCLONEDDS, {domain, "sim"});
    auto writer =
        sender->createWriter("clock", msg::makeTypeSupport<msg::Clock>(), interfaces::clockQos());
    auto text_writer = sender->createWriter("/bag/timing", interfaces::typeSupportByName("String"),
                                            interfaces::commandQos());
    Recorder recorder(recorderOptions(dir.path() / "with_clock.mcap", domain));
    recorder.start();
    EXPECT_TRUE(waitUntil(
        [&] { return writer->matchedReaders() > 0 && text_writer->matchedReaders() > 0; }, 10s));
    msg::Clock clock;
    writer->write(&clock);
    msg::String text;
    text_writer->write(&text);
    std::this_thread::sleep_for(300ms);
    recorder.stop();
  }
  options.input = (dir.path() / "with_clock.mcap").string();
  try {
    Player refused(options);
    ADD_FAILURE() << "a bag with a recorded clock was accepted with clock_hz";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("clock_hz"), std::string::npos) << e.what();
  }
  options.topics = {"/bag/timing"};  // the recorded clock left out: accepted
  EXPECT_NO_THROW(Player{options});
}

// Vehicle state is offered with a 0.5 s deadline and its readers request it: a player that
// offered none would match no such reader (the first mission bag replayed fed no odometry).
TEST(RecordPlay, ReadersThatRequestADeadlineGetThePlayedState) {
  const int domain = 18;
  TempDir dir("deadline");
  const fs::path bag = dir.path() / "state.mcap";
  const auto& type = interfaces::typeSupportByName("Odometry");
  {
    auto sender = interfaces::createParticipant(Vendor::CYCLONEDDS, {domain, "sender"});
    auto writer = sender->createWriter("/bag/state", type, interfaces::stateQos());
    Recorder recorder(recorderOptions(bag, domain));
    recorder.start();
    ASSERT_TRUE(waitUntil([&] { return writer->matchedReaders() > 0; }, 10s));
    msg::Odometry odometry;
    for (int i = 0; i < 10; ++i) {
      odometry.altitude(i);
      writer->write(&odometry);
      std::this_thread::sleep_for(20ms);
    }
    ASSERT_TRUE(writer->waitForAcknowledgments(5.0));
    recorder.stop();
  }
  McapReader reader;
  reader.open(bag);
  ASSERT_EQ(reader.channels().size(), 1u);
  const auto qos = qosFromMetadata(reader.channels().begin()->second.metadata, {});
  EXPECT_DOUBLE_EQ(qos.deadline_s, interfaces::stateQos().deadline_s);

  auto listener = interfaces::createParticipant(Vendor::FASTDDS, {domain, "listener"});
  std::atomic<int> received{0};
  auto subscription = listener->createReader("/bag/state", type, interfaces::stateQos(),
                                             [&](interfaces::DataReader& r) {
                                               msg::Odometry sample;
                                               while (r.take(&sample, nullptr)) ++received;
                                             });
  PlayerOptions options;
  options.input = bag.string();
  options.domain_id = domain;
  options.delay_s = 1.0;
  std::atomic<bool> stop{false};
  Player(options).play(stop);
  EXPECT_TRUE(waitUntil([&] { return received > 0; }, 5s));
}

TEST(RecordPlay, TopicFiltersRecordAndPlayOnlyWhatWasAsked) {
  const int domain = 17;
  TempDir dir("filters");
  auto sender = interfaces::createParticipant(Vendor::FASTDDS, {domain, "sender"});
  const auto& type = interfaces::typeSupportByName("String");
  std::vector<std::unique_ptr<interfaces::DataWriter>> writers;
  for (const char* topic : {"/bag/a", "/bag/b", "/bag/c"})
    writers.push_back(sender->createWriter(topic, type, interfaces::latchedStateQos()));
  msg::String text;
  text.data("x");
  for (auto& writer : writers) writer->write(&text);

  RecorderOptions options = recorderOptions(dir.path() / "ab.mcap", domain);
  options.topics = {"/bag/a", "bag/b"};  // either spelling
  options.exclude = {"/bag/b"};
  Recorder recorder(options);
  recorder.start();
  ASSERT_TRUE(waitUntil([&] { return recorder.stats().writer.messages >= 1; }, 20s));
  std::this_thread::sleep_for(1s);  // what else would arrive
  recorder.stop();
  const auto stats = recorder.stats();
  ASSERT_EQ(stats.topics.size(), 1u);
  EXPECT_EQ(stats.topics[0].topic, "/bag/a");

  PlayerOptions play;
  play.input = options.output;
  play.qos_overrides = {"/bag/a=bulk_transfer"};
  EXPECT_EQ(Player(play).playing().size(), 1u);
  EXPECT_THAT(Player(play).playing()[0], HasSubstr("keep_all"));
  play.qos_overrides = {"/bag/a=fastest"};
  EXPECT_THROW(Player{play}, std::invalid_argument);
  play.qos_overrides = {"/bag/b=bulk_transfer"};  // not in the bag
  EXPECT_THROW(Player{play}, std::invalid_argument);
  play.qos_overrides.clear();
  play.topics = {"/bag/c"};
  try {
    Player player(play);
    ADD_FAILURE() << "a topic the bag does not have was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("/bag/c"));
  }
}

TEST(RecordPlay, ChannelsThisBuildCannotPlayAreSkippedOrNamed) {
  TempDir dir("foreign");
  const fs::path bag = dir.path() / "foreign.mcap";
  {
    McapWriter writer;
    writer.open(bag);
    const uint16_t ours = writer.addSchema("auv::msg::String", "omgidl",
                                           interfaces::typeSupportByName("String").omg_idl);
    const uint16_t theirs = writer.addSchema("other::Thing", "omgidl", "struct Thing { long x; };");
    const uint16_t json_channel = writer.addChannel(ours, "/as_json", "json");
    const uint16_t foreign = writer.addChannel(theirs, "/foreign", "cdr");
    const uint16_t good = writer.addChannel(ours, "/good", "cdr");
    const std::vector<uint8_t> cdr = {0, 1, 0, 0, 2, 0, 0, 0, 'x', 0};
    for (uint16_t channel : {json_channel, foreign, good}) writer.write(channel, 1, 1, 1, cdr);
    writer.close();
  }
  PlayerOptions options;
  options.input = bag.string();
  Player player(options);
  ASSERT_EQ(player.skipped().size(), 2u);
  EXPECT_THAT(player.skipped()[0], HasSubstr("not cdr"));
  EXPECT_THAT(player.skipped()[1], HasSubstr("other::Thing"));
  ASSERT_EQ(player.playing().size(), 1u);
  EXPECT_THAT(player.playing()[0], StartsWith("/good"));
  options.topics = {"/foreign"};
  EXPECT_THROW(Player{options}, std::invalid_argument);
}

TEST(RecordPlayCommands, RefuseBadArgumentsNamingThem) {
  TempDir dir("commands");
  const std::string record = AUV_BAG_RECORD_EXE;
  const std::string play = AUV_BAG_PLAY_EXE;
  auto run = runCommand(record + " -o " + (dir.path() / "x.mcap").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("no topics given"));
  run = runCommand(record + " -a --compression gzip -o " + (dir.path() / "x.mcap").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("compression"));
  run = runCommand(record + " -a --duration soon");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("--duration: expected a number, got 'soon'"));
  std::ofstream(dir.path() / "taken.mcap") << "precious";
  run = runCommand(record + " -a --domain 18 -o " + (dir.path() / "taken.mcap").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("taken.mcap"));
  std::ifstream kept(dir.path() / "taken.mcap");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(kept), {}), "precious");
  run = runCommand(play + " " + (dir.path() / "missing.mcap").string());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("missing.mcap"));
  run = runCommand(play + " " + (dir.path() / "taken.mcap").string());
  EXPECT_EQ(run.exit_code, 2);
  run = runCommand(play + " x.mcap --rate 0");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.out, HasSubstr("rate"));
}

TEST(RecordPlayCommands, ACutBagPlaysItsIntactPartAndSaysWhereItBreaks) {
  const int domain = 19;
  TempDir dir("cut");
  // A recording of 200 samples in small chunks, cut in its middle.
  const fs::path bag = dir.path() / "cut.mcap";
  {
    auto sender = interfaces::createParticipant(Vendor::CYCLONEDDS, {domain, "sender"});
    const auto& type = interfaces::typeSupportByName("String");
    auto writer = sender->createWriter("/bag/cut", type, interfaces::commandQos());
    RecorderOptions options = recorderOptions(bag, domain);
    options.chunk_size = 1024;
    Recorder recorder(options);
    recorder.start();
    ASSERT_TRUE(waitUntil([&] { return writer->matchedReaders() > 0; }, 10s));
    for (int i = 0; i < 200; ++i) {
      msg::String text;
      text.data("sample " + std::to_string(i) + std::string(40, '.'));
      writer->write(&text);
    }
    ASSERT_TRUE(writer->waitForAcknowledgments(5.0));
    recorder.stop();
  }
  const auto size = fs::file_size(bag);
  fs::resize_file(bag, size / 2);
  const auto run = runCommand(std::string(AUV_BAG_PLAY_EXE) + " --delay 0 --rate 100 --domain " +
                              std::to_string(domain) + " " + bag.string());
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_THAT(run.out, HasSubstr("damaged: "));
  EXPECT_THAT(run.out, HasSubstr("truncated at byte " + std::to_string(size / 2)));
  EXPECT_THAT(run.out, ContainsRegex("played [1-9][0-9]* messages"));
}

}  // namespace
}  // namespace auv::bag
