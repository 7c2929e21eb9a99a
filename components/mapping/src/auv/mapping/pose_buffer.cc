#include "auv/mapping/pose_buffer.h"

#include <algorithm>
#include <stdexcept>

namespace auv::mapping {

std::string toString(PoseLookupStatus status) {
  switch (status) {
    case PoseLookupStatus::OK:
      return "ok";
    case PoseLookupStatus::EMPTY:
      return "no odometry yet";
    case PoseLookupStatus::BEFORE_START:
      return "stamp older than the pose buffer";
    case PoseLookupStatus::AFTER_END:
      return "stamp newer than the latest odometry";
    case PoseLookupStatus::GAP_TOO_LONG:
      return "odometry gap around the stamp too long";
  }
  return "unknown";
}

const config::OptionTable<PoseBuffer::Options>& PoseBuffer::Options::table() {
  using config::Range;
  using O = Options;
  static const config::OptionTable<O> kTable = {
      {"pose_buffer_length", &O::capacity, "odometry poses kept for interpolation", "poses",
       Range::closed(2, 1e6)},
      {"pose_max_gap", &O::max_gap_s, "largest odometry gap bridged by interpolation", "s",
       Range::aboveUpTo(0.0, 60.0)},
      {"pose_max_extrapolation", &O::max_extrapolation_s,
       "how far past the newest odometry a beam still gets that pose", "s",
       Range::closed(0.0, 10.0)},
  };
  return kTable;
}

void PoseBuffer::Options::check() const { config::checkOptions(*this, table(), "PoseBuffer: "); }

PoseBuffer::PoseBuffer(const Options& options) : options_(options) { options_.check(); }

void PoseBuffer::add(const StampedPose& pose) {
  StampedPose normalized = pose;
  normalized.orientation.normalize();
  const auto later = std::lower_bound(
      poses_.begin(), poses_.end(), pose.stamp_ns,
      [](const StampedPose& kept, int64_t stamp) { return kept.stamp_ns < stamp; });
  if (later != poses_.end() && later->stamp_ns == pose.stamp_ns) {
    *later = normalized;
  } else {
    poses_.insert(later, normalized);
  }
  while (poses_.size() > options_.capacity) poses_.pop_front();
}

StampedPose interpolate(const StampedPose& a, const StampedPose& b, int64_t stamp_ns) {
  if (b.stamp_ns == a.stamp_ns) return a;
  const double t =
      static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
  StampedPose result;
  result.stamp_ns = stamp_ns;
  result.position = a.position + t * (b.position - a.position);
  result.orientation = a.orientation.slerp(t, b.orientation);  // takes the shorter arc
  return result;
}

std::optional<StampedPose> PoseBuffer::lookUp(int64_t stamp_ns, PoseLookupStatus* status) const {
  auto report = [status](PoseLookupStatus s) {
    if (status) *status = s;
  };
  if (poses_.empty()) {
    report(PoseLookupStatus::EMPTY);
    return std::nullopt;
  }
  if (stamp_ns < poses_.front().stamp_ns) {
    report(PoseLookupStatus::BEFORE_START);
    return std::nullopt;
  }
  if (stamp_ns >= poses_.back().stamp_ns) {
    const double ahead_s = 1e-9 * static_cast<double>(stamp_ns - poses_.back().stamp_ns);
    if (ahead_s > options_.max_extrapolation_s) {
      report(PoseLookupStatus::AFTER_END);
      return std::nullopt;
    }
    report(PoseLookupStatus::OK);
    StampedPose held = poses_.back();
    held.stamp_ns = stamp_ns;
    return held;
  }
  const auto after = std::upper_bound(
      poses_.begin(), poses_.end(), stamp_ns,
      [](int64_t stamp, const StampedPose& kept) { return stamp < kept.stamp_ns; });
  const StampedPose& b = *after;
  const StampedPose& a = *(after - 1);
  if (1e-9 * static_cast<double>(b.stamp_ns - a.stamp_ns) > options_.max_gap_s) {
    report(PoseLookupStatus::GAP_TOO_LONG);
    return std::nullopt;
  }
  report(PoseLookupStatus::OK);
  return interpolate(a, b, stamp_ns);
}

}  // namespace auv::mapping
