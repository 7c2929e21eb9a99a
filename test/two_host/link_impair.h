// The decision core of `auv_link_impair` (link_impair.cc, README.md): for each packet an iptables
// NFQUEUE rule hands over, drop it or hold it for a while, and release held packets in the order
// of their times. No netfilter here and no clock: times are passed in (microseconds on any
// monotonic clock), so the core is tested without root (link_impair_test.cc).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace auv::link_impair {

struct Options {
  int queue = 0;                   // --queue: NFQUEUE number, 0..65535
  double loss = 0.0;               // --loss: probability of a drop, [0, 1]
  double delay_ms = 0.0;           // --delay: hold time, ms
  double jitter_ms = 0.0;          // --jitter: hold time varies uniformly by +- this, ms
  double reorder = 0.0;            // --reorder: probability of an extra hold, [0, 1]
  double reorder_delay_ms = 10.0;  // --reorder-delay: the extra hold, ms
  uint32_t seed = 1;               // --seed
  bool seed_given = false;         // otherwise the tool picks one and prints it
  size_t capacity = 4096;          // --capacity: packets held at most; more pass at once
  double stats_every_s = 0.0;      // --stats-every: print the counters every S s (0: never)
  bool help = false;               // --help
};

/// Parses the arguments after the program name into `options`. Returns "" or an error message
/// that names the option ("--loss: expected a probability in [0, 1], got '1.5'").
std::string parseOptions(const std::vector<std::string>& args, Options* options);

/// The --help text.
std::string usage();

struct Counters {
  uint64_t seen = 0;       // packets handed over by the queue
  uint64_t dropped = 0;    // NF_DROP
  uint64_t delayed = 0;    // held for a while before NF_ACCEPT
  uint64_t reordered = 0;  // released ahead of a packet that arrived before them
  uint64_t held_back = 0;  // given the extra --reorder-delay
  uint64_t overflow = 0;   // would have been held, but --capacity packets already were: passed
};

/// One line: "seen N dropped N delayed N reordered N held_back N overflow N held N".
std::string formatCounters(const Counters& counters, size_t held);

enum class Verdict { kDrop, kAccept, kHold };

struct Decision {
  Verdict verdict = Verdict::kAccept;
  int64_t release_us = 0;  // when to accept it (kHold), else the arrival time
};

/// Decides the fate of each packet with a std::mt19937 seeded with Options::seed. Every packet
/// takes exactly three numbers from it (loss, jitter, reorder), so the k-th packet's fate depends
/// only on the seed and k, whatever happened to the packets before it.
class Impairer {
 public:
  explicit Impairer(const Options& options);

  /// A packet arrives at `now_us`. Call takeDue(now_us) first, so that packets whose time has
  /// come are not counted as overtaken.
  Decision arrive(uint32_t id, int64_t now_us);

  /// Appends the ids of held packets with release time <= now_us, in release order (ties in
  /// arrival order), and forgets them; their release times to `release_us` if given.
  void takeDue(int64_t now_us, std::vector<uint32_t>* ids,
               std::vector<int64_t>* release_us = nullptr);

  /// Appends every held packet's id in release order and forgets them (shutdown).
  void takeAll(std::vector<uint32_t>* ids);

  /// The earliest release time of a held packet, if any.
  std::optional<int64_t> nextRelease() const;

  size_t held() const { return held_.size(); }
  const Counters& counters() const { return counters_; }

 private:
  struct Held {
    int64_t release_us;
    uint64_t sequence;  // arrival order, breaks ties
    uint32_t id;
    bool operator<(const Held& other) const {
      return release_us != other.release_us ? release_us < other.release_us
                                            : sequence < other.sequence;
    }
  };
  double uniform();  // in (0, 1), from one 32-bit draw: the same on every standard library

  Options options_;
  std::mt19937 random_;
  std::set<Held> held_;
  uint64_t sequence_ = 0;
  Counters counters_;
};

}  // namespace auv::link_impair
