#pragma once
// Durable state of a process across its restarts within one launch (docs/reliability.md). A
// state file is replaced whole or not at all (written beside it, flushed to disk, renamed over
// it), and records the launch it belongs to: a process started by a new launch must not take
// the previous launch's map or mission progress for its own.

#include <filesystem>
#include <string>
#include <string_view>

namespace auv::config {

/// The launch this process belongs to: AUV_LAUNCH_ID, which `auv launch` gives its processes
/// (the same across their restarts; exported by the user to resume a launch after a reboot).
/// Empty outside a launch: nothing is resumed then.
std::string launchId();

/// Replaces `path` with `data`: written to `<path>.tmp`, flushed to disk, renamed over `path`,
/// the folder flushed (creates the folder). A crash at any point leaves the old or the new
/// content, never a part. Throws std::runtime_error naming the file and the system's reason.
void writeFileAtomically(const std::filesystem::path& path, std::string_view data);

}  // namespace auv::config
