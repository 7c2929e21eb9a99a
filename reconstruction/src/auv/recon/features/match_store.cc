#include "auv/recon/features/match_store.h"

#include <cstring>

#include "auv/recon/common/staged_output.h"
#include "auv/recon/features/binary_io.h"

namespace fs = std::filesystem;

namespace auv::recon::features {
namespace {

constexpr char kMagic[8] = {'A', 'U', 'V', 'M', 'A', 'T', 'C', 'H'};
constexpr uint32_t kVersion = 1;

}  // namespace

std::string geometryKindName(GeometryKind kind) {
  switch (kind) {
    case GeometryKind::ESSENTIAL:
      return "essential";
    case GeometryKind::FUNDAMENTAL:
      return "fundamental";
    case GeometryKind::HOMOGRAPHY:
      return "homography";
  }
  return "unknown";
}

std::string pairSourceName(PairSource source) {
  switch (source) {
    case PairSource::EXHAUSTIVE:
      return "exhaustive";
    case PairSource::SEQUENTIAL:
      return "sequential";
    case PairSource::CROSS_CAMERA:
      return "cross_camera";
    case PairSource::LOOP:
      return "loop";
  }
  return "unknown";
}

fs::path verifiedPairsFile(const fs::path& features_folder) {
  return features_folder / "matches" / "pairs.bin";
}

void writeVerifiedPairs(const fs::path& pairs_bin, const std::vector<VerifiedPair>& pairs) {
  internal::ByteWriter out;
  out.putBytes(kMagic, sizeof(kMagic));
  out.put<uint32_t>(kVersion);
  out.put<uint32_t>(static_cast<uint32_t>(pairs.size()));
  for (const VerifiedPair& p : pairs) {
    out.putString16(p.image1);
    out.putString16(p.image2);
    out.put<uint8_t>(static_cast<uint8_t>(p.kind));
    out.put<uint8_t>(static_cast<uint8_t>(p.source));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out.put<double>(p.model(r, c));
    }
    out.put<double>(p.log10_nfa);
    out.put<double>(p.threshold_px);
    out.put<uint32_t>(p.putative);
    out.put<uint32_t>(p.homography_inliers);
    out.put<uint32_t>(static_cast<uint32_t>(p.inliers.size()));
    for (const MatchIndices& m : p.inliers) {
      out.put<uint32_t>(m.first);
      out.put<uint32_t>(m.second);
    }
  }
  writeFileAtomically(pairs_bin, out.bytes());
}

std::vector<VerifiedPair> readVerifiedPairs(const fs::path& pairs_bin) {
  const std::string bytes = internal::readWholeFile(pairs_bin.string());
  internal::ByteReader in(bytes, pairs_bin.string());
  char magic[8];
  in.getBytes(magic, sizeof(magic));
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    throw std::runtime_error(pairs_bin.string() + ": not a pairs file (bad magic)");
  }
  const uint32_t version = in.get<uint32_t>();
  if (version != kVersion) {
    throw std::runtime_error(pairs_bin.string() + ": version " + std::to_string(version) +
                             " (this build reads " + std::to_string(kVersion) + ")");
  }
  const uint32_t count = in.get<uint32_t>();
  std::vector<VerifiedPair> pairs;
  pairs.reserve(std::min<uint32_t>(count, 1u << 20));
  for (uint32_t i = 0; i < count; ++i) {
    VerifiedPair p;
    p.image1 = in.getString16();
    p.image2 = in.getString16();
    const uint8_t kind = in.get<uint8_t>(), source = in.get<uint8_t>();
    if (kind > 2 || source > 3) {
      throw std::runtime_error(pairs_bin.string() + ": pair " + std::to_string(i) +
                               ": bad geometry kind or source (corrupt file)");
    }
    p.kind = static_cast<GeometryKind>(kind);
    p.source = static_cast<PairSource>(source);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p.model(r, c) = in.get<double>();
    }
    p.log10_nfa = in.get<double>();
    p.threshold_px = in.get<double>();
    p.putative = in.get<uint32_t>();
    p.homography_inliers = in.get<uint32_t>();
    const uint32_t n = in.get<uint32_t>();
    if (static_cast<uint64_t>(n) * 8 > in.remaining()) {
      throw std::runtime_error(pairs_bin.string() + ": pair " + std::to_string(i) + " (" +
                               p.image1 + ", " + p.image2 + "): truncated");
    }
    p.inliers.resize(n);
    for (MatchIndices& m : p.inliers) {
      m.first = in.get<uint32_t>();
      m.second = in.get<uint32_t>();
    }
    pairs.push_back(std::move(p));
  }
  if (in.remaining() != 0) {
    throw std::runtime_error(pairs_bin.string() + ": " + std::to_string(in.remaining()) +
                             " bytes after the last pair (corrupt file)");
  }
  return pairs;
}

}  // namespace auv::recon::features
