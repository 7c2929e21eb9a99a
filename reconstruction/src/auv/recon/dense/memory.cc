#include "auv/recon/dense/memory.h"

#include <fstream>
#include <string>

namespace auv::recon::dense {

namespace {
size_t statusField(const std::string& name) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(name + ":", 0) == 0) {
      return std::stoull(line.substr(name.size() + 1)) * 1024;  // "VmHWM:  1234 kB"
    }
  }
  return 0;
}
}  // namespace

size_t peakMemoryBytes() { return statusField("VmHWM"); }
size_t currentMemoryBytes() { return statusField("VmRSS"); }

bool resetPeakMemory() {
  std::ofstream out("/proc/self/clear_refs");
  if (!out) return false;
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

}  // namespace auv::recon::dense
