// `auv topic list|info|echo|hz|bw|pub`, modelled on `ros2 topic`, on either vendor.
#include <algorithm>
#include <cmath>
#include <deque>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "auv/config/yaml_scalars.h"
#include "auv/interfaces/backend.h"
#include "auv/interfaces/executor.h"
#include "auv/interfaces/graph.h"
#include "auv/interfaces/waitable.h"
#include "cli/cli_common.h"

namespace auv::bringup {
namespace {

using namespace std::chrono_literals;
using interfaces::Durability;
using interfaces::GraphInspector;
using interfaces::GraphSnapshot;
using interfaces::QosProfile;
using interfaces::Reliability;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: auv topic <command>\n"
    "  list [-t] [--wait s]                 topics seen on the domain (-t: with types)\n"
    "  info <topic> [-v] [--wait s]         publishers/subscribers (-v: node, host, vendor, QoS)\n"
    "  echo <topic> [--once] [--field f] [--timeout s] [--full] [--qos profile]\n"
    "  hz <topic> [--window n] [--duration s] [--timeout s]\n"
    "  bw <topic> [--window n] [--duration s] [--timeout s]\n"
    "  pub <topic> <type> '<yaml>' [--rate hz] [--once] [--times n] [--qos profile]\n"
    "Environment: AUV_DDS=cyclonedds|fastdds (vendor), AUV_DOMAIN_ID (domain, default 0).\n";

std::unique_ptr<GraphInspector> makeInspector() {
  return std::make_unique<GraphInspector>(interfaces::vendorFromEnvironment(),
                                          interfaces::domainFromEnvironment());
}

// Waits for `topic` to have a publisher and returns its type (one clear error otherwise).
std::string discoverType(const GraphInspector& inspector, const std::string& topic,
                         double timeout_s, GraphSnapshot* snapshot_out) {
  const auto has_writer = [&](const GraphSnapshot& s) {
    return !s.endpointsOn(topic, true).empty();
  };
  GraphSnapshot snapshot = inspector.waitFor(
      has_writer, std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000)));
  if (!has_writer(snapshot)) {
    throw CliError("no publisher on " + displayTopic(topic) + " within " +
                       std::to_string(static_cast<int>(timeout_s)) +
                       " s (check the topic name, AUV_DOMAIN_ID, and that the publisher runs)",
                   1);
  }
  std::set<std::string> types;
  for (const auto& e : snapshot.endpointsOn(topic, true)) types.insert(e.type);
  if (types.size() > 1) {
    std::string list;
    for (const auto& t : types) list += (list.empty() ? "" : ", ") + t;
    throw CliError("topic " + displayTopic(topic) + " has publishers of several types: " + list, 1);
  }
  if (snapshot_out != nullptr) *snapshot_out = snapshot;
  return *types.begin();
}

const msg::TypeSupport& requireType(const std::string& name) {
  const msg::TypeSupport* ts = msg::findType(name);
  if (ts == nullptr)
    throw CliError("unknown message type '" + name + "' (see `auv interface list`)");
  return *ts;
}

// A reader QoS that matches every publisher seen: best effort if any publisher is, and
// transient local only if all publishers keep history (so echo shows latched data).
QosProfile compatibleQos(const GraphSnapshot& snapshot, const std::string& topic) {
  QosProfile q = interfaces::commandQos();
  q.name = "echo";
  bool all_transient = true;
  for (const auto& e : snapshot.endpointsOn(topic, true)) {
    if (e.qos.reliability == Reliability::BEST_EFFORT) q.reliability = Reliability::BEST_EFFORT;
    if (e.qos.durability != Durability::TRANSIENT_LOCAL) all_transient = false;
  }
  if (all_transient && q.reliability == Reliability::RELIABLE)
    q.durability = Durability::TRANSIENT_LOCAL;
  return q;
}

// A subscription to a topic whose type is known only at run time.
class GenericReader {
 public:
  GenericReader(const msg::TypeSupport& type, const std::string& topic, const QosProfile& qos)
      : type_(type),
        waker_(std::make_shared<interfaces::Waker>()),
        participant_(
            interfaces::createParticipant(interfaces::vendorFromEnvironment(),
                                          {interfaces::domainFromEnvironment(), "_auv_cli"})),
        topic_data_type_(type.make_topic_data_type()) {
    std::weak_ptr<interfaces::Waker> waker = waker_;
    reader_ = participant_->createReader(topic, type, qos, [waker](interfaces::DataReader&) {
      if (auto w = waker.lock()) w->notify();
    });
  }
  /// Waits up to `timeout` for a sample; fills `sample` and its serialized size.
  bool next(std::shared_ptr<void>& sample, uint32_t* size, Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      sample = type_.create_sample();
      if (reader_->take(sample.get(), nullptr)) {
        if (size) *size = topic_data_type_->getSerializedSizeProvider(sample.get())();
        return true;
      }
      if (interfaces::Executor::signalled() || Clock::now() >= deadline) return false;
      waker_->waitUntil(std::min(deadline, Clock::now() + std::chrono::milliseconds(100)));
    }
  }

 private:
  const msg::TypeSupport& type_;
  std::shared_ptr<interfaces::Waker> waker_;
  std::unique_ptr<interfaces::Participant> participant_;
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> topic_data_type_;
  std::unique_ptr<interfaces::DataReader> reader_;
};

// Replaces long byte arrays and sequences by a short note, unless --full.
YAML::Node truncate(const YAML::Node& node, size_t limit) {
  if (node.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& kv : node) out[kv.first] = truncate(kv.second, limit);
    return out;
  }
  if (node.IsSequence() && node.size() > limit) {
    return YAML::Node("<" + std::to_string(node.size()) + " elements, --full to show>");
  }
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& e : node) out.push_back(truncate(e, limit));
    return out;
  }
  return node;
}

// Follows "pose.pose.position" or "ranges[3]" into a message.
YAML::Node selectField(const YAML::Node& root, const std::string& path) {
  YAML::Node node = YAML::Clone(root);
  std::stringstream in(path);
  std::string part;
  while (std::getline(in, part, '.')) {
    std::string name = part;
    std::optional<size_t> index;
    if (auto bracket = part.find('['); bracket != std::string::npos) {
      name = part.substr(0, bracket);
      index = std::stoul(part.substr(bracket + 1));
    }
    if (!name.empty()) {
      if (!node.IsMap() || !node[name]) throw CliError("message has no field '" + path + "'");
      node = node[name];
    }
    if (index) {
      if (!node.IsSequence() || *index >= node.size())
        throw CliError("field '" + path + "': index out of range");
      node = node[*index];
    }
  }
  return node;
}

int listTopics(const Args& args) {
  auto inspector = makeInspector();
  const double wait = args.number("--wait", 2.0);
  const GraphSnapshot snapshot =
      inspector->waitFor([](const GraphSnapshot&) { return false; },
                         std::chrono::milliseconds(static_cast<int64_t>(wait * 1000)));
  for (const auto& [topic, types] : snapshot.topicTypes()) {
    std::cout << topic;
    if (args.flag("-t")) {
      std::string list;
      for (const auto& t : types) list += (list.empty() ? "" : ", ") + t;
      std::cout << " [" << list << "]";
    }
    std::cout << "\n";
  }
  return 0;
}

void printEndpoint(const GraphSnapshot& snapshot, const interfaces::EndpointInfo& e) {
  const interfaces::ParticipantInfo* p = snapshot.participant(e.participant);
  std::cout << "Node name: " << (p && !p->node_name.empty() ? p->node_name : "_unknown") << "\n"
            << "Host: " << (p && !p->host.empty() ? p->host : "?")
            << (p && p->pid ? "  pid " + std::to_string(p->pid) : "") << "\n"
            << "Vendor: " << (p ? p->vendor : interfaces::vendorNameFromGuid(e.guid)) << "\n"
            << "Topic type: " << e.type << "\n"
            << "Endpoint type: " << (e.is_writer ? "PUBLISHER" : "SUBSCRIPTION") << "\n"
            << "GID: " << interfaces::toString(e.guid) << "\n"
            << "QoS profile:\n"
            << "  Reliability: "
            << (e.qos.reliability == Reliability::RELIABLE ? "RELIABLE" : "BEST_EFFORT") << "\n"
            << "  Durability: "
            << (e.qos.durability == Durability::TRANSIENT_LOCAL ? "TRANSIENT_LOCAL" : "VOLATILE")
            << "\n"
            << "  History: ";
  if (!e.history_known)
    std::cout << "? (not announced by this vendor)\n";
  else if (e.qos.history == interfaces::History::KEEP_LAST)
    std::cout << "KEEP_LAST (" << e.qos.depth << ")\n";
  else
    std::cout << "KEEP_ALL\n";
  std::cout << "  Deadline: "
            << (e.qos.deadline_s > 0 ? std::to_string(e.qos.deadline_s) + " s" : "Infinite") << "\n"
            << "  Liveliness lease: "
            << (e.qos.liveliness_lease_s > 0 ? std::to_string(e.qos.liveliness_lease_s) + " s"
                                             : "Infinite")
            << "\n\n";
}

int topicInfo(const Args& args) {
  const std::string topic = args.at(1, "topic name");
  interfaces::toDdsTopicName(topic);  // validates
  auto inspector = makeInspector();
  const auto wait =
      std::chrono::milliseconds(static_cast<int64_t>(args.number("--wait", 5.0) * 1000));
  GraphSnapshot snapshot =
      inspector->waitFor([&](const GraphSnapshot& s) { return s.hasTopic(topic); }, wait);
  if (!snapshot.hasTopic(topic))
    throw CliError("unknown topic " + displayTopic(topic) + " (no endpoint seen within " +
                       std::to_string(wait.count() / 1000.0).substr(0, 3) + " s)",
                   1);
  // Endpoints of other participants keep arriving for a moment (a Fast DDS endpoint can
  // take ~1 s to reach a Cyclone inspector): wait until the count is stable for 1.5 s.
  const auto deadline = Clock::now() + wait;
  size_t count = 0;
  auto stable_since = Clock::now();
  while (Clock::now() < deadline && Clock::now() - stable_since < 1500ms) {
    snapshot = inspector->waitFor([](const GraphSnapshot&) { return false; }, 100ms);
    const size_t now =
        snapshot.endpointsOn(topic, true).size() + snapshot.endpointsOn(topic, false).size();
    if (now != count) {
      count = now;
      stable_since = Clock::now();
    }
  }
  const auto writers = snapshot.endpointsOn(topic, true);
  const auto readers = snapshot.endpointsOn(topic, false);
  if (writers.empty() && readers.empty())
    throw CliError("topic " + displayTopic(topic) + " disappeared (its endpoints were deleted)", 1);
  std::set<std::string> types;
  for (const auto& e : writers) types.insert(e.type);
  for (const auto& e : readers) types.insert(e.type);
  std::string list;
  for (const auto& t : types) list += (list.empty() ? "" : ", ") + t;
  std::cout << "Type: " << list << "\n\nPublisher count: " << writers.size() << "\n\n";
  if (args.flag("-v"))
    for (const auto& e : writers) printEndpoint(snapshot, e);
  std::cout << "Subscription count: " << readers.size() << "\n\n";
  if (args.flag("-v"))
    for (const auto& e : readers) printEndpoint(snapshot, e);
  return 0;
}

int topicEcho(const Args& args) {
  const std::string topic = args.at(1, "topic name");
  interfaces::toDdsTopicName(topic);
  const double timeout = args.number("--timeout", 5.0);
  GraphSnapshot snapshot;
  std::string type_name;
  {
    auto inspector = makeInspector();
    type_name = discoverType(*inspector, topic, timeout, &snapshot);
  }
  const msg::TypeSupport& type = requireType(type_name);
  QosProfile qos = compatibleQos(snapshot, topic);
  if (auto name = args.option("--qos")) qos = interfaces::qosProfileByName(*name);
  GenericReader reader(type, topic, qos);
  interfaces::Executor::installSignalHandlers();
  const auto field = args.option("--field");
  bool first = true;
  for (;;) {
    std::shared_ptr<void> sample;
    const auto wait =
        first ? std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout))
              : Clock::duration(std::chrono::hours(24 * 365));
    if (!reader.next(sample, nullptr, wait)) {
      if (interfaces::Executor::signalled()) return 0;
      throw CliError("no message on " + displayTopic(topic) + " within " +
                         std::to_string(static_cast<int>(timeout)) + " s",
                     1);
    }
    first = false;
    YAML::Node node = type.to_yaml(sample.get());
    if (field) node = selectField(node, *field);
    if (!args.flag("--full")) node = truncate(node, 64);
    if (node.IsScalar()) {  // a single field: print it as is, handy in scripts
      std::cout << node.Scalar() << std::endl;
    } else {
      YAML::Emitter out;
      out << node;
      std::cout << out.c_str() << "\n---" << std::endl;
    }
    if (args.flag("--once")) return 0;
  }
}

// Shared by hz and bw: receives for --duration (or until Ctrl-C) and reports each second.
int topicRate(const Args& args, bool bandwidth) {
  const std::string topic = args.at(1, "topic name");
  interfaces::toDdsTopicName(topic);
  const double timeout = args.number("--timeout", 5.0);
  const double duration = args.number("--duration", 0.0);
  const size_t window = static_cast<size_t>(args.number("--window", 10000));
  GraphSnapshot snapshot;
  std::string type_name;
  {
    auto inspector = makeInspector();
    type_name = discoverType(*inspector, topic, timeout, &snapshot);
  }
  GenericReader reader(requireType(type_name), topic, compatibleQos(snapshot, topic));
  interfaces::Executor::installSignalHandlers();
  std::deque<std::pair<Clock::time_point, uint32_t>> samples;
  const auto start = Clock::now();
  auto next_report = start + 1s;
  bool any = false;
  while (!interfaces::Executor::signalled()) {
    if (duration > 0 && Clock::now() - start >= std::chrono::duration<double>(duration)) break;
    std::shared_ptr<void> sample;
    uint32_t size = 0;
    if (reader.next(sample, &size, 100ms)) {
      any = true;
      samples.emplace_back(Clock::now(), size);
      while (samples.size() > window) samples.pop_front();
    }
    if (!any && Clock::now() - start > std::chrono::duration<double>(timeout))
      throw CliError("no message on " + displayTopic(topic) + " within " +
                         std::to_string(static_cast<int>(timeout)) + " s",
                     1);
    if (Clock::now() < next_report || samples.size() < 2) continue;
    next_report += 1s;
    const double span =
        std::chrono::duration<double>(samples.back().first - samples.front().first).count();
    std::vector<double> gaps;
    double bytes = 0;
    uint32_t min_size = UINT32_MAX, max_size = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
      bytes += samples[i].second;
      min_size = std::min(min_size, samples[i].second);
      max_size = std::max(max_size, samples[i].second);
      if (i > 0)
        gaps.push_back(
            std::chrono::duration<double>(samples[i].first - samples[i - 1].first).count());
    }
    std::cout << std::fixed;
    if (bandwidth) {
      std::cout << std::setprecision(2) << "average: " << bytes / span / 1024.0 << " KiB/s\n"
                << "\tmean: " << bytes / samples.size() / 1024.0
                << " KiB min: " << min_size / 1024.0 << " KiB max: " << max_size / 1024.0
                << " KiB window: " << samples.size() << std::endl;
    } else {
      double mean = 0, sq = 0;
      for (double g : gaps) mean += g;
      mean /= gaps.size();
      for (double g : gaps) sq += (g - mean) * (g - mean);
      std::cout << std::setprecision(3) << "average rate: " << 1.0 / mean << "\n"
                << "\tmin: " << *std::min_element(gaps.begin(), gaps.end())
                << "s max: " << *std::max_element(gaps.begin(), gaps.end())
                << "s std dev: " << std::setprecision(5) << std::sqrt(sq / gaps.size())
                << "s window: " << samples.size() << std::endl;
    }
  }
  return 0;
}

int topicPub(const Args& args) {
  const std::string topic = args.at(1, "topic name");
  interfaces::toDdsTopicName(topic);
  const msg::TypeSupport& type = requireType(args.at(2, "message type"));
  const std::string text = args.positional().size() > 3 ? args.positional()[3] : "{}";
  auto sample = type.create_sample();
  try {
    type.from_yaml(config::loadYaml(text), sample.get());
  } catch (const YAML::Exception& e) {
    throw CliError("malformed YAML message '" + text + "': " + e.msg);
  } catch (const std::invalid_argument& e) {
    throw CliError(std::string("bad message for ") + type.name + ": " + e.what());
  }
  QosProfile qos = interfaces::commandQos();
  if (auto name = args.option("--qos")) qos = interfaces::qosProfileByName(*name);
  const double rate = args.number("--rate", 1.0);
  if (!(rate > 0)) throw CliError("option --rate: expected a rate > 0 Hz");
  const bool once = args.flag("--once");
  const long times = once ? 1 : static_cast<long>(args.number("--times", 0));
  auto participant = interfaces::createParticipant(
      interfaces::vendorFromEnvironment(), {interfaces::domainFromEnvironment(), "_auv_cli_pub"});
  auto writer = participant->createWriter(topic, type, qos);
  interfaces::Executor::installSignalHandlers();
  // Like `ros2 topic pub --once`: give subscribers a moment to match before the first sample.
  const auto match_deadline =
      Clock::now() + std::chrono::duration<double>(args.number("--wait-matching", 2.0));
  while (writer->matchedReaders() == 0 && Clock::now() < match_deadline &&
         !interfaces::Executor::signalled())
    std::this_thread::sleep_for(20ms);
  // Discovery is asymmetric: this writer may see a reader before that reader sees this
  // writer, and a volatile reader that matches late treats earlier samples as history it is
  // not owed (it acknowledges them unread). A short settle time avoids losing the first ones.
  if (writer->matchedReaders() > 0) std::this_thread::sleep_for(500ms);
  YAML::Emitter echo;
  echo << type.to_yaml(sample.get());
  std::cout << "publisher: beginning loop\n";
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  auto next = Clock::now();
  for (long n = 1; !interfaces::Executor::signalled(); ++n) {
    writer->write(sample.get());
    std::cout << "publishing #" << n << ": " << echo.c_str() << "\n" << std::flush;
    if (times > 0 && n >= times) break;
    next += period;
    std::this_thread::sleep_until(next);
  }
  // Reliable: stay until subscribers acknowledged (a subscriber of the other vendor may
  // still be completing discovery of this writer when the samples go out).
  if (qos.reliability == Reliability::RELIABLE && !writer->waitForAcknowledgments(5.0))
    std::cerr << "auv topic: warning: not every subscriber acknowledged within 5 s\n";
  return 0;
}

}  // namespace

int topicMain(const std::vector<std::string>& argv) {
  const Args args(argv, {"-t", "-v", "--once", "--full"},
                  {"--wait", "--field", "--timeout", "--qos", "--window", "--duration", "--rate",
                   "--times", "--wait-matching"});
  if (args.positional().empty() || args.helpRequested()) {
    std::cout << kUsage;
    return args.helpRequested() ? 0 : 2;
  }
  const std::string& command = args.positional()[0];
  if (command == "list") return listTopics(args);
  if (command == "info") return topicInfo(args);
  if (command == "echo") return topicEcho(args);
  if (command == "hz") return topicRate(args, false);
  if (command == "bw") return topicRate(args, true);
  if (command == "pub") return topicPub(args);
  throw CliError("unknown command 'topic " + command + "'\n" + kUsage);
}

}  // namespace auv::bringup
