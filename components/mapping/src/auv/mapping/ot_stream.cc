#include "auv/mapping/ot_stream.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace auv::mapping::ot_stream {
namespace {

// AbstractOcTree::write's header, formatted by a default std::ostream as there.
std::string header(const std::string& type, std::size_t size, double resolution) {
  std::ostringstream s;
  s << "# Octomap OcTree file"
    << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
  s << "id " << type << std::endl;
  s << "size " << size << std::endl;
  s << "res " << resolution << std::endl;
  s << "data" << std::endl;
  return s.str();
}

void appendNode(float log_odds, uint8_t children, std::string& out) {
  char bytes[sizeof(float) + 1];
  std::memcpy(bytes, &log_odds, sizeof(float));
  bytes[sizeof(float)] = static_cast<char>(children);
  out.append(bytes, sizeof(bytes));
}

void appendSubtree(const octomap::OcTree& tree, const octomap::OcTreeNode* node, std::string& out) {
  uint8_t children = 0;
  for (unsigned i = 0; i < 8; ++i) {
    if (tree.nodeChildExists(node, i)) children |= static_cast<uint8_t>(1u << i);
  }
  appendNode(node->getLogOdds(), children, out);
  for (unsigned i = 0; i < 8; ++i) {
    if (children & (1u << i)) appendSubtree(tree, tree.getNodeChild(node, i), out);
  }
}

// Pre-order records of the node holding cells [begin, end) at `depth`; returns its log-odds
// (leaf: the cell's; inner: the largest below, written once the children are known).
float appendCells(const Cell* begin, const Cell* end, unsigned depth, unsigned tree_depth,
                  std::string& out) {
  const std::size_t at = out.size();
  if (depth == tree_depth) {
    appendNode(begin->log_odds, 0, out);
    return begin->log_odds;
  }
  appendNode(0.0f, 0, out);  // patched below
  const unsigned shift = 3 * (tree_depth - 1 - depth);
  uint8_t children = 0;
  float largest = -std::numeric_limits<float>::max();  // as OcTreeNode::getMaxChildLogOdds
  for (const Cell* first = begin; first != end;) {
    const unsigned child = (first->code >> shift) & 7u;
    const Cell* last = first;
    while (last != end && ((last->code >> shift) & 7u) == child) ++last;
    children |= static_cast<uint8_t>(1u << child);
    const float value = appendCells(first, last, depth + 1, tree_depth, out);
    if (value > largest) largest = value;
    first = last;
  }
  std::memcpy(&out[at], &largest, sizeof(float));
  out[at + sizeof(float)] = static_cast<char>(children);
  return largest;
}

}  // namespace

namespace {

// Sorts by code: LSD radix sort, 8 bits per pass, skipping digits all cells share (cells are
// clustered in space, so most high digits are). Several times faster than std::sort here.
void sortByCode(std::vector<Cell>& cells, unsigned code_bits) {
  std::vector<Cell> scratch(cells.size());
  for (unsigned shift = 0; shift < code_bits; shift += 8) {
    std::size_t count[256] = {};
    for (const Cell& cell : cells) ++count[(cell.code >> shift) & 0xFF];
    if (count[(cells.front().code >> shift) & 0xFF] == cells.size()) continue;
    std::size_t start = 0;
    for (std::size_t& c : count) start += std::exchange(c, start);  // counts -> offsets
    for (const Cell& cell : cells) scratch[count[(cell.code >> shift) & 0xFF]++] = cell;
    cells.swap(scratch);
  }
}

// Bit b of a 16-bit value to bit 3b.
uint64_t spread(uint64_t v) {
  v = (v | (v << 16)) & 0x0000FF0000FFull;
  v = (v | (v << 8)) & 0x00F00F00F00Full;
  v = (v | (v << 4)) & 0x0C30C30C30C3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}

}  // namespace

uint64_t cellCode(const octomap::OcTreeKey& key) {
  // Per bit from the top: the child index x | y << 1 | z << 2 (octomap::computeChildIdx).
  return spread(key[0]) | (spread(key[1]) << 1) | (spread(key[2]) << 2);
}

std::string writeTree(const octomap::OcTree& tree) {
  std::string out = header(tree.getTreeType(), tree.size(), tree.getResolution());
  out.reserve(out.size() + 5 * tree.size());
  if (tree.getRoot() != nullptr) appendSubtree(tree, tree.getRoot(), out);
  return out;
}

std::string writeCells(std::vector<Cell>& cells, double resolution, unsigned tree_depth) {
  if (!cells.empty()) sortByCode(cells, 3 * tree_depth);
  // Nodes: the root, then per cell the levels below where it leaves the previous cell's path.
  std::size_t nodes = cells.empty() ? 0 : 1 + tree_depth;
  for (std::size_t i = 1; i < cells.size(); ++i) {
    // Levels below the root shared with the previous cell: its equal leading 3-bit groups.
    const int equal_bits =
        __builtin_clzll(cells[i].code ^ cells[i - 1].code) - static_cast<int>(64 - 3 * tree_depth);
    nodes += tree_depth - static_cast<unsigned>(equal_bits) / 3;
  }
  std::string out = header("OcTree", nodes, resolution);
  out.reserve(out.size() + 5 * nodes);
  if (!cells.empty()) appendCells(cells.data(), cells.data() + cells.size(), 0, tree_depth, out);
  return out;
}

namespace {

struct Header {
  std::string id;
  std::size_t size = 0;
  double resolution = 0.0;
};

// The header after the first line, as AbstractOcTree::readHeader reads it: keywords up to
// "data", '#' comments; the stream is left at the node data. `what` names the format.
Header readHeader(std::istream& stream, const char* what) {
  Header header;
  std::string token;
  while (stream >> token && token != "data") {
    if (token == "id") {
      stream >> header.id;
    } else if (token == "size") {
      stream >> header.size;
    } else if (token == "res") {
      stream >> header.resolution;
    } else {
      std::getline(stream, token);  // a comment or a keyword OctoMap would skip
    }
  }
  std::getline(stream, token);  // the rest of the "data" line
  if (!stream || header.id != "OcTree" || !(header.resolution > 0.0)) {
    throw std::runtime_error(std::string("not an OcTree ") + what + " stream (id '" + header.id +
                             "', resolution " + std::to_string(header.resolution) + ")");
  }
  return header;
}

}  // namespace

std::unique_ptr<octomap::OcTree> readTree(std::istream& stream) {
  std::string line;
  if (!std::getline(stream, line) || line.rfind("# Octomap OcTree file", 0) != 0) {
    throw std::runtime_error("not an OctoMap .ot stream");
  }
  const Header header = readHeader(stream, ".ot");
  const std::size_t size = header.size;
  const double resolution = header.resolution;
  // OctoMap trusts the node data: it reads past the end of a short stream with child bits it
  // never read, and recurses as deep as the child bits say (a fuzzed stream overflowed the
  // stack). So the data is checked whole first.
  std::string data{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  const std::string problem = otDataProblem(data, size);
  if (!problem.empty()) throw std::runtime_error("OcTree .ot stream: " + problem);
  auto tree = std::make_unique<octomap::OcTree>(resolution);
  std::istringstream nodes(std::move(data));
  if (size > 0) tree->readData(nodes);
  if (!nodes || tree->size() != size) {
    throw std::runtime_error("OcTree .ot stream ends early (" + std::to_string(tree->size()) +
                             " of " + std::to_string(size) + " nodes)");
  }
  return tree;
}

namespace {

// Walks pre-order node data without recursion: `node_bytes` per node, `children(offset)` the
// number of children of the node at `offset` (or -1: not a node). A node at `tree_depth` has
// none; the walk must use the data up to its last byte.
template <class Children>
std::string nodeDataProblem(const std::string& data, std::size_t node_bytes, unsigned tree_depth,
                            std::size_t* nodes_read, Children children) {
  struct Level {
    unsigned depth;
    unsigned pending;  // nodes still to read at this depth under the same parent
  };
  std::vector<Level> stack{{0, 1}};
  std::size_t offset = 0;
  std::size_t nodes = 0;
  while (!stack.empty()) {
    if (stack.back().pending == 0) {
      stack.pop_back();
      continue;
    }
    --stack.back().pending;
    const unsigned depth = stack.back().depth;
    if (data.size() - offset < node_bytes) {
      return "ends early (" + std::to_string(data.size()) + " bytes hold " + std::to_string(nodes) +
             " whole nodes of the tree the data starts)";
    }
    const int count = children(offset);
    offset += node_bytes;
    ++nodes;
    if (count < 0) return "node " + std::to_string(nodes) + " has an invalid child code";
    if (count == 0) continue;
    if (depth >= tree_depth) {
      return "node " + std::to_string(nodes) + " at depth " + std::to_string(depth) +
             " has children (the tree is " + std::to_string(tree_depth) + " deep)";
    }
    stack.push_back({depth + 1, static_cast<unsigned>(count)});
  }
  *nodes_read = nodes;
  return "";
}

}  // namespace

std::string otDataProblem(const std::string& data, std::size_t size, unsigned tree_depth) {
  if (size == 0) return "";
  std::size_t nodes = 0;
  std::string problem =
      nodeDataProblem(data, sizeof(float) + 1, tree_depth, &nodes, [&](std::size_t offset) {
        const auto bits = static_cast<unsigned char>(data[offset + sizeof(float)]);
        int count = 0;
        for (int i = 0; i < 8; ++i) count += (bits >> i) & 1;
        return count;
      });
  if (problem.empty() && nodes != size) {
    problem = "the header says " + std::to_string(size) + " nodes, the data holds " +
              std::to_string(nodes);
  }
  return problem;
}

std::string btDataProblem(const std::string& data, unsigned tree_depth) {
  // Each node: two bytes of 2-bit child codes (00 none, 01 occupied leaf, 10 free leaf, 11
  // inner node, whose own two bytes follow in pre-order).
  std::size_t nodes = 0;
  return nodeDataProblem(data, 2, tree_depth - 1, &nodes, [&](std::size_t offset) {
    int inner = 0;
    for (std::size_t byte = 0; byte < 2; ++byte) {
      const auto bits = static_cast<unsigned char>(data[offset + byte]);
      for (int child = 0; child < 4; ++child) inner += ((bits >> (2 * child)) & 3) == 3;
    }
    return inner;
  });
}

void readBinaryTree(std::istream& stream, octomap::OcTree& tree) {
  std::string line;
  if (!std::getline(stream, line) || line.rfind("# Octomap OcTree binary file", 0) != 0) {
    throw std::runtime_error("not an OctoMap binary (.bt) stream");
  }
  const Header header = readHeader(stream, ".bt");
  // OctoMap is handed exactly the node data checked (readBinaryData), as in readTree.
  std::string data{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  if (header.size > 0) {
    const std::string problem = btDataProblem(data);
    if (!problem.empty()) throw std::runtime_error("OctoMap binary (.bt) stream: " + problem);
  }
  tree.clear();
  tree.setResolution(header.resolution);
  std::istringstream nodes(std::move(data));
  if (header.size > 0) tree.readBinaryData(nodes);
  if (tree.size() != header.size) {
    throw std::runtime_error("OctoMap binary (.bt) stream holds " + std::to_string(tree.size()) +
                             " nodes, its header says " + std::to_string(header.size));
  }
}

}  // namespace auv::mapping::ot_stream
