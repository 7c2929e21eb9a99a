// The main of a fuzz harness built without libFuzzer (auv_add_fuzzer in auv_conventions.cmake):
// runs LLVMFuzzerTestOneInput once on every input, so the seeds and the inputs that once
// crashed a parser are regression tests in every build, with any compiler.
//
//   fuzz_<name>_replay [FILE|DIR]...      every file (directories: their files, sorted)
//   fuzz_<name>_replay --write-seeds DIR  writes the harness's own seeds (auvFuzzSeeds) into DIR
//
// A harness may define auvFuzzSeeds(): inputs it makes itself (e.g. the CDR bytes of every
// message type), replayed first. Fails when there was nothing to replay (a test that cannot
// fail otherwise), or when a named path does not exist; a crash of the harness is the failure
// the replay is for.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);
__attribute__((weak)) std::vector<std::string> auvFuzzSeeds();

namespace {

std::string readFile(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

void run(const std::string& input) {
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(input.data()), input.size());
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  const std::vector<std::string> seeds = auvFuzzSeeds ? auvFuzzSeeds() : std::vector<std::string>{};
  if (argc == 3 && std::string(argv[1]) == "--write-seeds") {
    fs::create_directories(argv[2]);
    for (std::size_t i = 0; i < seeds.size(); ++i) {
      std::ofstream(fs::path(argv[2]) / ("seed_" + std::to_string(i)), std::ios::binary)
          << seeds[i];
    }
    std::printf("wrote %zu seeds into %s\n", seeds.size(), argv[2]);
    return 0;
  }
  std::size_t replayed = 0;
  for (const std::string& seed : seeds) {
    run(seed);
    ++replayed;
  }
  for (int i = 1; i < argc; ++i) {
    const fs::path path(argv[i]);
    std::error_code error;
    if (fs::is_directory(path, error)) {
      std::vector<fs::path> files;
      for (const auto& entry : fs::recursive_directory_iterator(path)) {
        if (entry.is_regular_file()) files.push_back(entry.path());
      }
      std::sort(files.begin(), files.end());
      for (const fs::path& file : files) {
        run(readFile(file));
        ++replayed;
      }
    } else if (fs::is_regular_file(path, error)) {
      run(readFile(path));
      ++replayed;
    } else if (path.parent_path().filename() != "regressions") {
      // A package without regressions yet names its (absent) regressions folder: not an error.
      std::fprintf(stderr, "fuzz replay: no such file or directory: %s\n", argv[i]);
      return 2;
    }
  }
  std::printf("replayed %zu inputs\n", replayed);
  if (replayed == 0) {
    std::fprintf(stderr, "fuzz replay: nothing to replay (no seeds, files or regressions)\n");
    return 1;
  }
  return 0;
}
