#include "auv/recon/common/report.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "auv/recon/common/staged_output.h"

namespace fs = std::filesystem;

namespace auv::recon {

namespace {
constexpr const char* kFormat = "auv-recon-report 1";

/// flock() on `<report>.lock` for the lifetime of the object.
class ReportLock {
 public:
  explicit ReportLock(const fs::path& report) {
    const fs::path lock = report.string() + ".lock";
    fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error(lock.string() + ": cannot open: " + std::strerror(errno));
    ::flock(fd_, LOCK_EX);
  }
  ~ReportLock() { ::close(fd_); }
  ReportLock(const ReportLock&) = delete;
  ReportLock& operator=(const ReportLock&) = delete;

 private:
  int fd_ = -1;
};
}  // namespace

nlohmann::json readReport(const fs::path& report) {
  std::ifstream in(report);
  if (!in) return nlohmann::json::object();
  std::stringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(report.string() + ": not valid JSON: " + e.what());
  }
}

nlohmann::json readReportSection(const fs::path& report, const std::string& stage) {
  try {
    const nlohmann::json whole = readReport(report);
    if (whole.contains("stages") && whole["stages"].is_object() &&
        whole["stages"].contains(stage) && whole["stages"][stage].is_object()) {
      return whole["stages"][stage];
    }
  } catch (const std::exception&) {
    // An unreadable report is set aside by updateReport.
  }
  return nlohmann::json::object();
}

void updateReport(const fs::path& report, const std::string& stage, const nlohmann::json& section) {
  fs::create_directories(report.parent_path().empty() ? fs::path(".") : report.parent_path());
  ReportLock lock(report);
  nlohmann::json whole;
  try {
    whole = readReport(report);
  } catch (const std::runtime_error&) {
    std::error_code ignored;
    fs::rename(report, report.string() + ".unreadable", ignored);
    whole = nlohmann::json::object();
  }
  if (!whole.is_object()) whole = nlohmann::json::object();
  whole["format"] = kFormat;
  if (!whole.contains("stages") || !whole["stages"].is_object()) {
    whole["stages"] = nlohmann::json::object();
  }
  whole["stages"][stage] = section;
  writeFileAtomically(report, whole.dump(2) + "\n");
}

}  // namespace auv::recon
