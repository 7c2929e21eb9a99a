#pragma once
// Plays an MCAP bag back onto DDS, as `auv bag play` does: one serialized writer per channel,
// with the type its schema names and the QoS its metadata keeps (qos_metadata.h), each
// message published unchanged at its recorded log time, scaled by `rate`. Nodes with
// use_sim_time follow the recorded `clock` topic as it plays, or the player's own (clock_hz). A
// damaged bag plays what is intact (the reader's linear scan) and says where it breaks.
// components/bag/README.md, "Playing".

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "auv/bag/mcap_reader.h"
#include "auv/config/option_table.h"
#include "auv/interfaces/backend.h"

namespace auv::bag {

struct PlayerOptions {
  std::string input;                ///< the .mcap file
  std::vector<std::string> topics;  ///< topics to play ("/a/b" or "a/b"); empty: all
  double rate = 1.0;                ///< playback speed: 2 = twice as fast as recorded
  bool loop = false;                ///< start again at the end, until stopped
  double delay_s = 1.0;             ///< wait after creating the writers (discovery) before playing
  /// Wait (up to delay_s) until every writer has a matched reader instead of the whole
  /// delay_s: for a replay into readers that exist already (discovery across vendors on a busy
  /// machine can take seconds, and a volatile reader misses what came before it matched).
  bool wait_for_readers = false;
  double start_offset_s = 0.0;  ///< skip this much of the bag's beginning
  std::string vendor;           ///< cyclonedds or fastdds; empty: AUV_DDS (cyclonedds)
  int domain_id = -1;           ///< -1: AUV_DOMAIN_ID (0)
  /// "topic=profile": offer a named profile (qos.h) instead of the recorded QoS, e.g.
  /// "/sonar/beam=bulk_transfer" to feed a reader set to the same profile without loss.
  std::vector<std::string> qos_overrides;
  /// Publish `clock` (msg::Clock) at this rate (Hz of wall time) with the bag's time as it
  /// plays — for nodes with use_sim_time on a bag without a recorded clock (a real dive); 0:
  /// off. Refused when the bag's own `clock` is played too.
  double clock_hz = 0.0;

  static const config::OptionTable<PlayerOptions>& table();
  /// Throws std::invalid_argument naming the field and the value.
  void check() const;
};

struct PlayStats {
  uint64_t messages = 0;  ///< published, over all loops
  std::map<std::string, uint64_t> per_topic;
  /// Messages the middleware refused (a keyed type whose key does not decode): counted, and
  /// play goes on.
  uint64_t refused = 0;
  int loops = 0;  ///< complete passes through the bag
  double wall_s = 0;
  bool stopped = false;  ///< ended by the stop flag, not by the bag's end
};

class Player {
 public:
  /// Checks the options and opens the bag: BagError NOT_FOUND / NOT_MCAP naming the file;
  /// std::invalid_argument naming a topic of the filter the bag does not have, or one whose
  /// channel cannot be played (not CDR, a type this build does not know, a schema that is not
  /// this build's). Channels that cannot be played and were not asked for are skipped
  /// (skipped()).
  explicit Player(PlayerOptions options);
  ~Player();
  Player(const Player&) = delete;
  Player& operator=(const Player&) = delete;

  /// Where the bag is damaged (played up to and after each break where the reader can).
  const std::vector<Damage>& damage() const { return reader_.damage(); }
  /// "topic: why" for each channel left out.
  const std::vector<std::string>& skipped() const { return skipped_; }
  /// Topics that will be played, with their QoS summary.
  std::vector<std::string> playing() const;

  /// Joins the domain, waits delay_s, publishes until the bag ends (or, with loop, until
  /// `stop`), then waits up to 5 s for reliable readers to acknowledge. Returns early when
  /// `stop` becomes true.
  PlayStats play(const std::atomic<bool>& stop);

 private:
  struct Output;
  PlayerOptions options_;
  McapReader reader_;
  std::map<uint16_t, std::unique_ptr<Output>> outputs_;  // by channel id
  std::vector<std::string> skipped_;
};

}  // namespace auv::bag
