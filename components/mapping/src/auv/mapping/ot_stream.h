#pragma once
// Writes OctoMap `.ot` streams (AbstractOcTree::write: text header, then every node in
// pre-order as its float log-odds and a byte of child bits) without going through an
// std::ostream per node, and without building a tree for a set of cells. The output is byte
// for byte what AbstractOcTree::write produces (map_builder_test checks it); it only exists
// because the component writes one per map update and OctoMap's writer costs ~5x more.
// Reads them back without AbstractOcTree::read, which Debian's liboctomap builds with debug
// output: two lines on stderr per map update read, thousands in a mission's log.

#include <cstdint>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include <octomap/OcTree.h>

namespace auv::mapping::ot_stream {

/// A finest-depth cell and its log-odds; `code` interleaves the key's bits so that sorting by
/// code gives OctoMap's depth-first child order (see cellCode).
struct Cell {
  uint64_t code;
  float log_odds;
};

/// Octree order of `key`: per depth from the root, the child index (x | y << 1 | z << 2).
uint64_t cellCode(const octomap::OcTreeKey& key);

/// What tree.write(stream) writes (an empty tree: the header only).
std::string writeTree(const octomap::OcTree& tree);

/// What AbstractOcTree::write writes for an OcTree of `resolution` holding exactly `cells` at
/// the finest depth (`tree_depth` = 16 for OcTree), each inner node at the largest log-odds
/// below it (updateInnerOccupancy), nothing pruned. Sorts `cells` by code; codes must be
/// unique.
std::string writeCells(std::vector<Cell>& cells, double resolution, unsigned tree_depth = 16);

/// The OcTree of an `.ot` stream (what AbstractOcTree::read returns for one), read silently.
/// Throws std::runtime_error when the stream is not an OcTree `.ot` stream or ends early.
std::unique_ptr<octomap::OcTree> readTree(std::istream& stream);

/// Reads a `.bt` stream into `tree` (as OcTree::readBinary: the file's resolution, occupied
/// cells at `tree`'s clamping bound), its node data checked first and handed to OctoMap; throws
/// std::runtime_error when it is not one, ends early or nests deeper than the tree.
void readBinaryTree(std::istream& stream, octomap::OcTree& tree);

/// Why `data`, the node data of an `.ot` stream (after its "data" line), is not `size` nodes
/// of an OcTree `tree_depth` deep; "" when it is. OctoMap's readers check neither: they read
/// past the end and recurse as deep as the child bits say.
std::string otDataProblem(const std::string& data, std::size_t size, unsigned tree_depth = 16);
/// The same for the node data of a `.bt` stream.
std::string btDataProblem(const std::string& data, unsigned tree_depth = 16);

}  // namespace auv::mapping::ot_stream
