// LowLevelController's safety manoeuvres (controller.h): the conditions, what the vehicle does
// about them depending on the water above it, and the breadcrumb trail it backs away along.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "auv/control/controller.h"

namespace auv::control {
namespace {

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string metres(double value) {
  std::ostringstream out;
  out.precision(1);
  out << std::fixed << value << " m";
  return out.str();
}

}  // namespace

void LowLevelController::recordBreadcrumb(const Eigen::Vector3d& position) {
  if (options_.breadcrumb_length <= 0) return;
  if (!trail_.empty() && (position - trail_.back()).norm() < options_.breadcrumb_spacing) return;
  trail_.push_back(position);
  const auto keep =
      static_cast<size_t>(std::ceil(options_.breadcrumb_length / options_.breadcrumb_spacing)) + 1;
  while (trail_.size() > keep) trail_.pop_front();
}

double LowLevelController::overheadClearance(const Eigen::Vector3d& position) const {
  const double infinity = std::numeric_limits<double>::infinity();
  if (!overhead_probe_) return infinity;
  const double clearance = overhead_probe_(position);
  // A broken answer is no reason to drive into what may be rock: NaN counts as rock right above.
  if (std::isnan(clearance)) return 0.0;
  // Rock at or above the surface is no rock in the way.
  return clearance >= position.z() ? infinity : std::max(clearance, 0.0);
}

void LowLevelController::updateSafety(double now) {
  SafetyReason reason = SafetyReason::NONE;
  std::string text;
  if (!navigation_ || now - navigation_time_ > options_.navigation_timeout) {
    const double since = now - (navigation_ ? navigation_time_ : *first_update_);
    if (since > options_.navigation_timeout) {
      reason = SafetyReason::NAVIGATION_LOST;
      text = (navigation_ ? "no navigation for " : "no valid navigation received in ") +
             number(since) + " s (navigation_timeout " + number(options_.navigation_timeout) +
             " s)";
    }
  }
  if (reason == SafetyReason::NONE && navigation_) {
    const double depth = navigation_->position.z();
    const double altitude = navigation_->altitude;
    if (depth > options_.max_depth) {
      reason = SafetyReason::MAX_DEPTH;
      text = "depth " + number(depth) + " m > max_depth " + number(options_.max_depth) + " m";
    } else if (altitude >= 0 && altitude < options_.min_altitude) {
      reason = SafetyReason::MIN_ALTITUDE;
      text = "altitude " + number(altitude) + " m < min_altitude " + number(options_.min_altitude) +
             " m";
    }
  }

  if (reason != SafetyReason::NONE) {
    condition_seen_ = now;
    if (!status_.safety_maneuver) manoeuvre_depth_.reset();
    status_.safety_maneuver = true;
    status_.state = ControllerState::SAFETY_MANEUVER;
    status_.safety_reason = reason;
    condition_text_ = text;
    status_.reached = false;
    status_.distance_to_target = -1.0;
    return;
  }
  if (status_.safety_maneuver && now - *condition_seen_ >= options_.safety_clear_time) {
    // Over: drop the interrupted command, the mission handler decides what comes next.
    status_.safety_maneuver = false;
    status_.safety_reason = SafetyReason::NONE;
    status_.safety_text.clear();
    status_.safety_action.clear();
    condition_text_.clear();
    manoeuvre_depth_.reset();
    status_.state = ControllerState::IDLE;
    const uint64_t id = command_.command_id;
    command_ = ControlCommand();
    resetIntegrals(true);
    if (navigation_ && !std::isinf(overheadClearance(navigation_->position))) {
      // Under rock, thrusters off would let the buoyancy lift the vehicle into it: hold here
      // (the status still says which command was interrupted).
      command_.command_id = id;
      command_.mode = ControlMode::HOLD;
      status_.state = ControllerState::HOLDING;
      startHolding(navigation_->position, options_.default_tolerance, navigation_->yaw);
    }
  }
}

ThrusterCommand LowLevelController::safetyManoeuvre(double dt) {
  resetIntegrals(false);
  const double clearance = navigation_ ? overheadClearance(navigation_->position)
                                       : std::numeric_limits<double>::infinity();
  if (std::isinf(clearance)) {
    status_.safety_action = "ascending";
    status_.safety_text = condition_text_ + "; ascending";
    manoeuvre_depth_.reset();
    return {0.0, 0.0, -1.0};  // horizontal off, full up: open water above, the surface is safe
  }
  const std::string rock = "rock " + metres(clearance) + " above";
  const ControllerNavigation& nav = *navigation_;
  if (!manoeuvre_depth_) manoeuvre_depth_ = nav.position.z();
  switch (status_.safety_reason) {
    case SafetyReason::NAVIGATION_LOST:
      // No position to follow the trail with and no fresh depth to regulate on: balance the
      // buoyancy, nothing else.
      status_.safety_action = "holding";
      status_.safety_text = condition_text_ + "; holding: " + rock + ", no navigation";
      return {0.0, 0.0, options_.model.commandForThrust(options_.model.net_buoyancy)};
    case SafetyReason::MAX_DEPTH: {
      // A little above max_depth, but never closer than overhead_margin to the rock.
      const double rock_depth = nav.position.z() - clearance;
      const double target =
          std::min(nav.position.z(),
                   std::max(options_.max_depth - 1.0, rock_depth + options_.overhead_margin));
      status_.safety_action = "rising";
      status_.safety_text = condition_text_ + "; rising to " + metres(target) + ": " + rock;
      ThrusterCommand out = regulate({nav.yaw, target, 0.0}, dt);
      out.port = out.starboard = 0.0;
      return out;
    }
    default: {
      Targets targets{nav.yaw, *manoeuvre_depth_, 0.0};
      if (retreatTargets(targets)) {
        status_.safety_action = "backing away";
        status_.safety_text = condition_text_ + "; backing away: " + rock;
      } else {
        status_.safety_action = "holding";
        status_.safety_text = condition_text_ + "; holding: " + rock + ", no trail left";
      }
      return regulate(targets, dt);
    }
  }
}

bool LowLevelController::retreatTargets(Targets& targets) {
  const ControllerNavigation& nav = *navigation_;
  // Breadcrumbs within half a spacing are passed: the next one back is the target.
  const double reach = 0.5 * options_.breadcrumb_spacing;
  while (!trail_.empty() && (trail_.back() - nav.position).head<2>().norm() < reach) {
    trail_.pop_back();
  }
  if (trail_.empty()) return false;
  const Eigen::Vector2d offset = (trail_.back() - nav.position).head<2>();
  // Reversing: the stern points at the breadcrumb, so the heading is the one it came with.
  targets.yaw = wrapAngle(std::atan2(offset.y(), offset.x()) + M_PI);
  targets.surge_speed = -options_.retreat_speed * underwayFraction(targets.yaw - nav.yaw);
  return true;
}

}  // namespace auv::control
