// `auv bag info` as a user runs it (the auv-bag-info program): the summary on stdout and exit 0
// for a whole bag; the intact part, where it breaks, and exit 1 for a cut one; exit 2 naming
// the file or the argument for a missing file, a file that is not MCAP, or bad arguments.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <cstdio>
#include <fstream>
#include <string>

#include "bag_test_util.h"

namespace auv::bag {
namespace {

using namespace testing;

struct CommandRun {
  int exit_code = -1;
  std::string out;  // stdout and stderr
};

CommandRun runInfo(const std::string& args) {
  CommandRun run;
  const std::string command = std::string(AUV_BAG_INFO_EXE) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return run;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) run.out.append(buffer, n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

TEST(BagInfoCommand, PrintsAWholeBagAndNamesWhereACutOneBreaks) {
  TempDir dir("info_command");
  const fs::path path = dir.path() / "run.mcap";
  McapWriterOptions options;
  options.chunk_size = 16 * 1024;
  writeBag(path, someMessages(600, 3, 500, 2, 1795773600ULL * 1000000000ULL, 1000000), options);

  const CommandRun whole = runInfo(path.string() + " --verify");
  EXPECT_EQ(whole.exit_code, 0) << whole.out;
  EXPECT_NE(whole.out.find("600"), std::string::npos) << whole.out;

  const fs::path cut = dir.path() / "cut.mcap";
  fs::copy_file(path, cut);
  fs::resize_file(cut, fs::file_size(path) * 2 / 3);
  const CommandRun broken = runInfo(cut.string());
  EXPECT_EQ(broken.exit_code, 1) << broken.out;
  EXPECT_NE(broken.out.find("truncated at byte"), std::string::npos) << broken.out;
  EXPECT_NE(broken.out.find("a linear scan"), std::string::npos) << broken.out;
}

TEST(BagInfoCommand, RefusesWhatItCannotReadNamingIt) {
  TempDir dir("info_command_bad");
  const fs::path missing = dir.path() / "nowhere.mcap";
  const CommandRun none = runInfo(missing.string());
  EXPECT_EQ(none.exit_code, 2) << none.out;
  EXPECT_NE(none.out.find("nowhere.mcap"), std::string::npos) << none.out;

  const fs::path text = dir.path() / "notes.mcap";
  std::ofstream(text) << "not a bag at all, just some words in a file\n";
  const CommandRun not_mcap = runInfo(text.string());
  EXPECT_EQ(not_mcap.exit_code, 2) << not_mcap.out;
  EXPECT_NE(not_mcap.out.find("notes.mcap"), std::string::npos) << not_mcap.out;

  EXPECT_EQ(runInfo("").exit_code, 2);
  const CommandRun unknown = runInfo(text.string() + " --fast");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.out.find("--fast"), std::string::npos) << unknown.out;
}

}  // namespace
}  // namespace auv::bag
