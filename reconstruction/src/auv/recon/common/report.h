#pragma once
// <survey>/report.json: one section per stage (what it did: counts, timings, its options),
// each stage replacing only its own section.
//
//   {"format": "auv-recon-report 1",
//    "stages": {"keyframes": {...}, "sfm": {"images_registered": 312, "seconds": 84.1, ...}}}

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace auv::recon {

/// Replaces `stage`'s section of the report (read, modify, write through a temporary name,
/// under a lock so that two stages finishing together keep both sections). A report that is
/// not valid JSON is kept as `report.json.unreadable` and a new one is started.
void updateReport(const std::filesystem::path& report, const std::string& stage,
                  const nlohmann::json& section);

/// The whole report; an empty object when there is none yet. Throws on invalid JSON.
nlohmann::json readReport(const std::filesystem::path& report);

/// `stage`'s section as written, or an empty object when there is none, it is not an object, or
/// the report is unreadable (updateReport sets that aside). For stages that keep the entries of
/// earlier runs (cameras not redone) beside this run's.
nlohmann::json readReportSection(const std::filesystem::path& report, const std::string& stage);

}  // namespace auv::recon
