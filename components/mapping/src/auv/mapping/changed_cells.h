#pragma once
// The cells MapBuilder changed since its last diff, each with its newest log-odds: a flat
// open-addressing table on the packed key. std::unordered_map allocated a node per cell and
// freed them all at every diff: a fifth of the mapping component's time (mapping_bench).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <octomap/OcTreeKey.h>

namespace auv::mapping::detail {

class ChangedCells {
 public:
  /// Notes (or overwrites) the log-odds of `key`.
  void set(const octomap::OcTreeKey& key, float log_odds) {
    if (2 * (size_ + 1) > slots_.size()) grow();  // load factor <= 1/2
    const uint64_t packed = pack(key);
    for (std::size_t i = slotOf(packed);; i = (i + 1) & (slots_.size() - 1)) {
      Slot& slot = slots_[i];
      if (slot.packed == packed) {
        slot.log_odds = log_odds;
        return;
      }
      if (slot.packed == 0) {
        slot = {packed, log_odds};
        ++size_;
        return;
      }
    }
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Calls f(key, log_odds) for every cell, in no particular order.
  template <class F>
  void forEach(F&& f) const {
    for (const Slot& slot : slots_) {
      if (slot.packed != 0) f(unpack(slot.packed), slot.log_odds);
    }
  }
  /// Forgets every cell; keeps the table unless it is far larger than the last use needed.
  void clear() {
    if (slots_.size() > kMinSlots && 8 * size_ < slots_.size()) {
      reset(capacityFor(size_));
    } else {
      std::fill(slots_.begin(), slots_.end(), Slot{});
    }
    size_ = 0;
  }

 private:
  struct Slot {
    uint64_t packed = 0;  // 0: empty (a used slot has bit 48 set)
    float log_odds = 0.0f;
  };
  static constexpr std::size_t kMinSlots = 1024;

  static uint64_t pack(const octomap::OcTreeKey& key) {
    return (uint64_t{1} << 48) | (uint64_t{key[2]} << 32) | (uint64_t{key[1]} << 16) | key[0];
  }
  static octomap::OcTreeKey unpack(uint64_t packed) {
    return octomap::OcTreeKey(static_cast<octomap::key_type>(packed & 0xFFFF),
                              static_cast<octomap::key_type>((packed >> 16) & 0xFFFF),
                              static_cast<octomap::key_type>((packed >> 32) & 0xFFFF));
  }
  std::size_t slotOf(uint64_t packed) const {  // Fibonacci hashing: the high bits mix well
    return static_cast<std::size_t>((packed * 0x9E3779B97F4A7C15ull) >> (64 - bits_));
  }
  static std::size_t capacityFor(std::size_t cells) {
    std::size_t capacity = kMinSlots;
    while (capacity < 2 * cells) capacity *= 2;
    return capacity;
  }
  // Empty table of `capacity` (a power of two) slots.
  void reset(std::size_t capacity) {
    std::vector<Slot>(capacity).swap(slots_);
    bits_ = 0;
    while ((std::size_t{1} << bits_) < capacity) ++bits_;
  }
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    reset(old.empty() ? kMinSlots : 2 * old.size());
    size_ = 0;
    for (const Slot& slot : old) {
      if (slot.packed != 0) set(unpack(slot.packed), slot.log_odds);
    }
  }

  std::vector<Slot> slots_;
  unsigned bits_ = 0;  // log2(slots_.size())
  std::size_t size_ = 0;
};

}  // namespace auv::mapping::detail
