#pragma once
// Typo distance, for "did you mean ...?" hints in parameter, launch and CLI errors.

#include <cstddef>
#include <string>

namespace auv::config {

/// Optimal string alignment distance: Levenshtein plus adjacent transpositions, so
/// "rnage" is one edit from "range".
size_t editDistance(const std::string& a, const std::string& b);

}  // namespace auv::config
