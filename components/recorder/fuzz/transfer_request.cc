// Fuzz harness: requests from the vehicle-shore link as the recorder validates and serves them
// (components/transfer/README.md): a fetch_chunk request (file_path, offset, length) goes
// through RecorderComponent::onFetch's steps — the catalogue decides whether the path is a
// complete recording or sidecar, checkRelativePath names a malformed one, the ChunkReader
// reads the range in the catalogued state of the file, a digest kept on the catalogue's grid
// is served for it — and the ChunkReader alone takes the same path, offset and length (its own
// guard against paths that leave the root, symlinks included); a list_recordings request
// (camera_id) goes through onList's lookups. The recordings root is a fixture made once, with
// symlinks that lead out of it.
// Input: byte 0 even, a fetch: offset (8 bytes, little endian), length (4 bytes), then the
// path; byte 0 odd, a list: byte 1 bit 0 include_incomplete, then the camera id.
// A clear error is a ChunkError (what the component turns into a reply code). A served chunk
// that is longer than asked or capped, lies past the file's end, carries a digest that is not
// its bytes' or comes from outside the root aborts, as does any other exception or crash.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "../test/test_files.h"
#include "auv/msg/recorder.h"
#include "auv/recorder/catalogue.h"
#include "auv/transfer/chunk_reader.h"
#include "auv/transfer/sha256.h"

namespace {

namespace fs = std::filesystem;
using auv::recorder::Catalogue;
using auv::transfer::ChunkError;
using auv::transfer::Sha256;

constexpr uint32_t kMaxChunkBytes = 4096;  // the recorder's smallest cap: chunks on a fine grid

// A recordings root as the recorder serves it, and the component's catalogue and reader of it.
struct Fixture {
  auv::transfer::testing::TempDir dir{"fuzz_transfer_request"};
  fs::path root = dir.path() / "recordings";
  std::unique_ptr<Catalogue> catalogue;
  std::unique_ptr<auv::transfer::ChunkReader> reader;

  Fixture() {
    using auv::recorder::testing::writeRecording;
    using auv::transfer::testing::randomBytes;
    using auv::transfer::testing::writeFile;
    writeRecording(root, "down", 1, 10000, 12, 1);  // two whole chunks and a short one
    writeRecording(root, "down", 2, kMaxChunkBytes, 3, 2);
    writeRecording(root, "forward", 1, 100, 1, 3);
    writeFile(root / "forward" / "forward_0002.incomplete.mp4", randomBytes(3000, 4));
    writeFile(root / "forward" / "notes.txt", "not a recording");
    // What must never be served: a file beside the root, reached through symlinks inside it.
    writeFile(dir.path() / "outside" / "secret.mp4", "not the vehicle's to give");
    fs::create_directory_symlink("../outside", root / "linked_camera");
    fs::create_symlink("../../outside/secret.mp4", root / "forward" / "forward_0003.mp4");
    catalogue = std::make_unique<Catalogue>(
        auv::recorder::CatalogueOptions{root, {".mp4"}, kMaxChunkBytes});
    catalogue->scan();
    reader = std::make_unique<auv::transfer::ChunkReader>(root, kMaxChunkBytes);
  }
};

Fixture& fixture() {
  static Fixture made;
  return made;
}

void expect(bool ok, const std::string& what) {
  if (ok) return;
  std::fprintf(stderr, "transfer_request: %s\n", what.c_str());
  std::abort();
}

// What any served chunk must be: at most what was asked and the cap, inside the file.
void checkChunk(const auv::transfer::Chunk& chunk, uint64_t offset, uint32_t length) {
  expect(chunk.data.size() <= length && chunk.data.size() <= kMaxChunkBytes,
         std::to_string(chunk.data.size()) + " bytes served for " + std::to_string(length));
  expect(offset <= chunk.total_size && chunk.data.size() <= chunk.total_size - offset,
         "a chunk past the end of its file");
}

// RecorderComponent::onFetch without DDS (the component is the catalogue and the reader).
void fetchChunk(Fixture& f, const auv::msg::FileChunkRequest& request) {
  const std::string& path = request.file_path();
  try {
    const auto served = f.catalogue->servedFile(path);
    if (!served) {
      auv::transfer::checkRelativePath(path);  // INVALID_ARGUMENT for a malformed path
      f.catalogue->changedProblem(path);       // REJECTED if it changed, else NOT_FOUND
      return;
    }
    if (served->relative_path != path) return;  // NOT_FOUND: not a complete file
    const auto chunk = f.reader->read(path, request.offset(), request.length(), served->stamp);
    checkChunk(chunk, request.offset(), request.length());
    const std::optional<std::string> kept =
        f.catalogue->chunkDigest(path, served->stamp, request.offset(), chunk.data.size());
    if (kept) {
      expect(*kept == Sha256::of(chunk.data.data(), chunk.data.size()),
             "the kept digest of '" + path + "' at " + std::to_string(request.offset()) +
                 " is not the digest of the bytes served");
    }
  } catch (const ChunkError&) {
  }
  // The reader on its own: whatever the catalogue says, nothing outside the root is read.
  try {
    const auto chunk = f.reader->read(path, request.offset(), request.length());
    checkChunk(chunk, request.offset(), request.length());
    const std::string resolved = f.reader->resolve(path).string();
    const std::string inside = fs::canonical(f.root).string() + "/";
    expect(resolved.compare(0, inside.size(), inside) == 0,
           "'" + path + "' was read from " + resolved + ", outside the root");
  } catch (const ChunkError&) {
  }
}

// RecorderComponent::onList's lookups.
void listRecordings(Fixture& f, const auv::msg::RecordingCatalogueRequest& request) {
  if (!request.camera_id().empty() && !f.catalogue->hasCamera(request.camera_id())) return;
  for (const auto& recording :
       f.catalogue->list(request.camera_id(), request.include_incomplete())) {
    expect(request.camera_id().empty() || recording.camera_id == request.camera_id(),
           "listed another camera's recording");
  }
}

uint64_t littleEndian(const uint8_t* bytes, size_t count) {
  uint64_t value = 0;
  for (size_t i = count; i-- > 0;) value = (value << 8) | bytes[i];
  return value;
}

// The harness's encoding of a request (the inverse of LLVMFuzzerTestOneInput's decoding).
std::string encode(const auv::msg::FileChunkRequest& request) {
  std::string bytes(1, '\0');
  for (int i = 0; i < 8; ++i) bytes += static_cast<char>((request.offset() >> (8 * i)) & 0xFF);
  for (int i = 0; i < 4; ++i) bytes += static_cast<char>((request.length() >> (8 * i)) & 0xFF);
  return bytes + request.file_path();
}

std::string encode(const auv::msg::RecordingCatalogueRequest& request) {
  return std::string(1, '\1') + static_cast<char>(request.include_incomplete() ? 1 : 0) +
         request.camera_id();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  Fixture& f = fixture();
  if (data[0] % 2 == 0) {
    uint8_t fields[12] = {};  // offset and length; missing bytes are 0
    const size_t given = std::min<size_t>(size - 1, sizeof(fields));
    std::copy(data + 1, data + 1 + given, fields);
    auv::msg::FileChunkRequest request;
    request.offset(littleEndian(fields, 8));
    request.length(static_cast<uint32_t>(littleEndian(fields + 8, 4)));
    request.file_path(
        std::string(reinterpret_cast<const char*>(data + 1 + given), size - 1 - given));
    fetchChunk(f, request);
  } else {
    auv::msg::RecordingCatalogueRequest request;
    request.include_incomplete(size > 1 && (data[1] & 1) != 0);
    if (size > 2) request.camera_id(std::string(reinterpret_cast<const char*>(data + 2), size - 2));
    listRecordings(f, request);
  }
  return 0;
}

/// What a shore's pull asks for: each catalogued file (recording and sidecar) in chunks on the
/// grid, one off the grid, its end; the catalogue per camera and whole.
std::vector<std::string> auvFuzzSeeds() {
  Fixture& f = fixture();
  std::vector<std::string> seeds;
  for (const auto& recording : f.catalogue->list("", true)) {
    for (const std::string& path : {recording.file_path, recording.sidecar_file}) {
      if (path.empty()) continue;
      for (uint64_t offset :
           {uint64_t{0}, uint64_t{kMaxChunkBytes}, 2 * uint64_t{kMaxChunkBytes}, uint64_t{100}}) {
        auv::msg::FileChunkRequest request;
        request.file_path(path);
        request.offset(offset);
        request.length(kMaxChunkBytes);
        seeds.push_back(encode(request));
      }
    }
    auv::msg::RecordingCatalogueRequest list;
    list.camera_id(recording.camera_id);
    seeds.push_back(encode(list));
  }
  auv::msg::RecordingCatalogueRequest all;
  all.include_incomplete(true);
  seeds.push_back(encode(all));
  return seeds;
}
