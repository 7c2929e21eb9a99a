#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <sstream>

#include "link_impair.h"

namespace auv::link_impair {
namespace {

constexpr double kMaxMilliseconds = 3600.0 * 1000.0;  // one hour: far beyond any useful hold

bool parseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(parsed)) return false;
  *value = parsed;
  return true;
}

bool parseUnsigned(const std::string& text, unsigned long long max, unsigned long long* value) {
  if (text.empty() || text[0] < '0' || text[0] > '9') return false;  // no sign, no space
  char* end = nullptr;
  errno = 0;
  const unsigned long long parsed = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size() || parsed > max) return false;
  *value = parsed;
  return true;
}

std::string got(const std::string& option, const std::string& expected, const std::string& text) {
  return option + ": expected " + expected + ", got '" + text + "'";
}

int64_t microseconds(double milliseconds) { return std::llround(milliseconds * 1000.0); }

}  // namespace

std::string usage() {
  return "usage: auv_link_impair --queue N [--loss P] [--delay MS] [--jitter MS] [--reorder P]\n"
         "                       [--reorder-delay MS] [--seed N] [--capacity N] "
         "[--stats-every S]\n"
         "Takes the packets an iptables NFQUEUE rule (--queue-num N --queue-bypass) hands over\n"
         "and drops each with probability --loss, else holds it --delay MS +- a uniform\n"
         "--jitter MS (at least 0) plus, with probability --reorder, --reorder-delay MS more,\n"
         "then accepts it. Held packets beyond --capacity are accepted at once. Counters go to\n"
         "stdout on SIGINT/SIGTERM, at exit and every --stats-every S. See\n"
         "test/two_host/README.md.\n"
         "  --queue N           NFQUEUE number, 0..65535 (required)\n"
         "  --loss P            drop probability, 0..1 [0]\n"
         "  --delay MS          hold time in ms [0]\n"
         "  --jitter MS         hold time varies uniformly by +- MS [0]\n"
         "  --reorder P         probability of an extra hold, 0..1 [0]\n"
         "  --reorder-delay MS  the extra hold in ms [10]\n"
         "  --seed N            seed of the std::mt19937, 0..4294967295 [random, printed]\n"
         "  --capacity N        packets held at most, 1..1000000 [4096]\n"
         "  --stats-every S     print the counters every S seconds, 0 = never [0]\n";
}

std::string parseOptions(const std::vector<std::string>& args, Options* options) {
  bool queue_given = false;
  for (size_t i = 0; i < args.size(); ++i) {
    std::string option = args[i];
    std::string value;
    bool has_value = false;
    const size_t equals = option.find('=');
    if (option.rfind("--", 0) == 0 && equals != std::string::npos) {
      value = option.substr(equals + 1);
      option = option.substr(0, equals);
      has_value = true;
    }
    if (option == "--help" || option == "-h") {
      options->help = true;
      continue;
    }
    static const std::set<std::string> kKnown = {"--queue",  "--loss",     "--delay",
                                                 "--jitter", "--reorder",  "--reorder-delay",
                                                 "--seed",   "--capacity", "--stats-every"};
    if (kKnown.count(option) == 0) return "unknown option '" + option + "' (see --help)";
    if (!has_value) {
      if (i + 1 >= args.size()) return option + ": missing value";
      value = args[++i];
    }
    double number = 0.0;
    unsigned long long integer = 0;
    if (option == "--queue") {
      if (!parseUnsigned(value, 65535, &integer)) {
        return got(option, "a queue number in 0..65535", value);
      }
      options->queue = static_cast<int>(integer);
      queue_given = true;
    } else if (option == "--loss" || option == "--reorder") {
      if (!parseDouble(value, &number) || number < 0.0 || number > 1.0) {
        return got(option, "a probability in [0, 1]", value);
      }
      (option == "--loss" ? options->loss : options->reorder) = number;
    } else if (option == "--delay" || option == "--jitter" || option == "--reorder-delay") {
      if (!parseDouble(value, &number) || number < 0.0 || number > kMaxMilliseconds) {
        return got(option, "milliseconds in [0, 3600000]", value);
      }
      (option == "--delay"    ? options->delay_ms
       : option == "--jitter" ? options->jitter_ms
                              : options->reorder_delay_ms) = number;
    } else if (option == "--seed") {
      if (!parseUnsigned(value, 4294967295ULL, &integer)) {
        return got(option, "an integer in 0..4294967295", value);
      }
      options->seed = static_cast<uint32_t>(integer);
      options->seed_given = true;
    } else if (option == "--capacity") {
      if (!parseUnsigned(value, 1000000, &integer) || integer == 0) {
        return got(option, "a number of packets in 1..1000000", value);
      }
      options->capacity = static_cast<size_t>(integer);
    } else {  // --stats-every
      if (!parseDouble(value, &number) || number < 0.0 || number > 86400.0) {
        return got(option, "seconds in [0, 86400]", value);
      }
      options->stats_every_s = number;
    }
  }
  if (!queue_given && !options->help) return "--queue: missing (the NFQUEUE number of the rule)";
  return "";
}

std::string formatCounters(const Counters& c, size_t held) {
  std::ostringstream line;
  line << "seen " << c.seen << " dropped " << c.dropped << " delayed " << c.delayed << " reordered "
       << c.reordered << " held_back " << c.held_back << " overflow " << c.overflow << " held "
       << held;
  return line.str();
}

Impairer::Impairer(const Options& options) : options_(options), random_(options.seed) {}

double Impairer::uniform() { return (static_cast<double>(random_()) + 0.5) / 4294967296.0; }

Decision Impairer::arrive(uint32_t id, int64_t now_us) {
  // Three draws per packet, always, so the k-th packet's fate depends only on seed and k.
  const double loss_draw = uniform();
  const double jitter_draw = uniform();
  const double reorder_draw = uniform();
  ++counters_.seen;
  const uint64_t sequence = sequence_++;
  if (loss_draw < options_.loss) {
    ++counters_.dropped;
    return {Verdict::kDrop, now_us};
  }
  double hold_ms = options_.delay_ms + (2.0 * jitter_draw - 1.0) * options_.jitter_ms;
  if (hold_ms < 0.0) hold_ms = 0.0;
  const bool held_back = reorder_draw < options_.reorder;
  if (held_back) hold_ms += options_.reorder_delay_ms;
  const int64_t release_us = now_us + microseconds(hold_ms);
  // Ahead of an earlier packet: released before the latest release among those held (all of
  // which arrived earlier; ties keep arrival order).
  const bool overtakes = !held_.empty() && release_us < std::prev(held_.end())->release_us;
  if (release_us <= now_us) {
    if (overtakes) ++counters_.reordered;
    return {Verdict::kAccept, now_us};
  }
  if (held_.size() >= options_.capacity) {
    ++counters_.overflow;  // never block the link: pass it now
    if (!held_.empty() && now_us < std::prev(held_.end())->release_us) ++counters_.reordered;
    return {Verdict::kAccept, now_us};
  }
  if (held_back) ++counters_.held_back;
  ++counters_.delayed;
  if (overtakes) ++counters_.reordered;
  held_.insert({release_us, sequence, id});
  return {Verdict::kHold, release_us};
}

void Impairer::takeDue(int64_t now_us, std::vector<uint32_t>* ids,
                       std::vector<int64_t>* release_us) {
  while (!held_.empty() && held_.begin()->release_us <= now_us) {
    ids->push_back(held_.begin()->id);
    if (release_us != nullptr) release_us->push_back(held_.begin()->release_us);
    held_.erase(held_.begin());
  }
}

void Impairer::takeAll(std::vector<uint32_t>* ids) {
  for (const Held& h : held_) ids->push_back(h.id);
  held_.clear();
}

std::optional<int64_t> Impairer::nextRelease() const {
  if (held_.empty()) return std::nullopt;
  return held_.begin()->release_us;
}

}  // namespace auv::link_impair
