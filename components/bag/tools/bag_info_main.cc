// `auv bag info <file.mcap> [--verify]` (run by `auv` as auv-bag-info): what a bag holds —
// channels, counts, times, chunks — and where a damaged one breaks. Exit 0 for an intact bag,
// 1 when damage was found (what is intact is still listed), 2 for bad arguments or a file that
// is missing or not MCAP (config/errors.h's rule).
#include <cstdio>
#include <exception>
#include <string>

#include "auv/bag/bag_error.h"
#include "auv/bag/bag_info.h"
#include "auv/config/errors.h"

namespace {

constexpr const char* kUsage =
    "usage: auv bag info <file.mcap> [--verify]\n"
    "  --verify  also read every chunk and check its CRC and the data section's (reads the\n"
    "            whole file; without it only the summary is read, or the records when the\n"
    "            summary is missing or damaged)\n";

}  // namespace

int main(int argc, char** argv) {
  std::string file;
  bool verify = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (arg == "--verify") {
      verify = true;
    } else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "auv bag info: unknown option '%s'\n%s", arg.c_str(), kUsage);
      return 2;
    } else if (file.empty()) {
      file = arg;
    } else {
      std::fprintf(stderr, "auv bag info: one file at a time ('%s' and '%s')\n", file.c_str(),
                   arg.c_str());
      return 2;
    }
  }
  if (file.empty()) {
    std::fprintf(stderr, "auv bag info: no file given\n%s", kUsage);
    return 2;
  }
  try {
    const auv::bag::Summary summary = auv::bag::info(file, verify);
    std::fputs(auv::bag::formatInfo(summary).c_str(), stdout);
    return summary.damage.empty() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auv bag info: %s\n", e.what());
    return auv::config::exitCodeFor(e);
  }
}
