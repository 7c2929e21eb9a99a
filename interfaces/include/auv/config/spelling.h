#pragma once
// Typo distance and the one "did you mean ...?" rule of parameter, YAML, launch and CLI errors.

#include <cstddef>
#include <string>
#include <vector>

namespace auv::config {

/// Optimal string alignment distance: Levenshtein plus adjacent transpositions, so
/// "rnage" is one edit from "range".
size_t editDistance(const std::string& a, const std::string& b);

/// How far a word may be from a known name to be suggested: max(2, length / 3) edits, so short
/// names get near misses only and long ones allow a few slips.
size_t suggestionDistance(const std::string& word);

/// The candidate closest to `word` within `max_distance` edits (the first of equals), or "".
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates,
                         size_t max_distance);
/// The same within suggestionDistance(word).
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace auv::config
