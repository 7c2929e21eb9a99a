// The YAML 1.2 core-schema scalar rule of every reader, and the loading every reader shares
// (see yaml_scalars.h).

#include "auv/config/yaml_scalars.h"

#include <cctype>
#include <charconv>
#include <limits>
#include <sstream>
#include <system_error>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <yaml-cpp/anchor.h>
#include <yaml-cpp/eventhandler.h>

namespace auv::config {

std::optional<bool> parseBool(const std::string& text) {
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  return std::nullopt;
}

std::optional<int64_t> parseInteger(const std::string& text) {
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  if (text.empty()) return std::nullopt;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  bool negative = false;
  if (*begin == '+' || *begin == '-') {
    negative = *begin == '-';
    ++begin;
  }
  int base = 10;
  if (end - begin > 2 && begin[0] == '0' && (begin[1] == 'x' || begin[1] == 'o')) {
    base = begin[1] == 'x' ? 16 : 8;
    if (negative || text[0] == '+') return std::nullopt;  // YAML 1.2: unsigned hex and octal
    begin += 2;
  }
  if (begin == end) return std::nullopt;
  // from_chars accepts a leading '-' only; parse the magnitude as unsigned to reach INT64_MIN.
  uint64_t magnitude = 0;
  const auto result = std::from_chars(begin, end, magnitude, base);
  if (result.ec != std::errc() || result.ptr != end) return std::nullopt;
  if (negative) {
    if (magnitude > static_cast<uint64_t>(kMax) + 1) return std::nullopt;
    return static_cast<int64_t>(0 - magnitude);
  }
  if (magnitude > static_cast<uint64_t>(kMax)) return std::nullopt;
  return static_cast<int64_t>(magnitude);
}

std::optional<double> parseNumber(const std::string& text) {
  if (text == ".inf" || text == ".Inf" || text == ".INF" || text == "+.inf" || text == "+.Inf" ||
      text == "+.INF") {
    return std::numeric_limits<double>::infinity();
  }
  if (text == "-.inf" || text == "-.Inf" || text == "-.INF") {
    return -std::numeric_limits<double>::infinity();
  }
  if (text == ".nan" || text == ".NaN" || text == ".NAN") {
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (const auto integer = parseInteger(text)) return static_cast<double>(*integer);
  // YAML 1.2 core float: [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?
  size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  size_t digits = 0;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i, ++digits;
  if (i < text.size() && text[i] == '.') {
    ++i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i, ++digits;
  }
  if (digits == 0) return std::nullopt;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    size_t exponent_digits = 0;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
      ++i;
      ++exponent_digits;
    }
    if (exponent_digits == 0) return std::nullopt;
  }
  if (i != text.size()) return std::nullopt;
  // from_chars rejects a leading '+'; the grammar above already validated the text.
  const char* begin = text.data() + (text[0] == '+' ? 1 : 0);
  double value = 0.0;
  const auto result = std::from_chars(begin, text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size()) return std::nullopt;
  return value;
}

bool isPlainScalar(const YAML::Node& node) { return node.IsScalar() && node.Tag() == "?"; }

std::string nodeText(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "null";
    case YAML::NodeType::Scalar:
      return isPlainScalar(node) ? node.Scalar() : "\"" + node.Scalar() + "\"";
    case YAML::NodeType::Sequence: {
      std::string text = "[";
      for (size_t i = 0; i < node.size(); ++i) {
        if (i > 0) text += ", ";
        text += nodeText(node[i]);
      }
      return text + "]";
    }
    case YAML::NodeType::Map:
      return "{...}";
    case YAML::NodeType::Undefined:
      break;
  }
  return "?";
}

std::string describeNode(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null (empty value)";
  if (node.IsMap()) return "a map";
  if (node.IsScalar() && !isPlainScalar(node)) return nodeText(node) + " (a quoted string)";
  return "'" + nodeText(node) + "'";
}

std::string markText(const YAML::Mark& mark) {
  if (mark.is_null() || mark.line < 0) return "";
  return ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

namespace {

/// Follows the parser's events of one document: which collections are open (an alias of one of
/// them would make it contain itself) and how many nodes each anchor and the aliases stand for.
class AliasCheck : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t anchor) override { leaf(anchor); }
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t anchor,
                const std::string&) override {
    leaf(anchor);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    if (open_anchors_.count(anchor) > 0) {
      throw YAML::ParserException(
          mark, "an alias inside the node it refers to (that node would contain itself)");
    }
    const std::size_t nodes = nodes_[anchor];
    aliased_ += nodes;
    if (aliased_ > kMaxAliasedNodes) {
      throw YAML::ParserException(mark, "the aliases stand for more than " +
                                            std::to_string(kMaxAliasedNodes) + " nodes in all");
    }
    add(nodes);
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(anchor);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Open {
    YAML::anchor_t anchor;
    std::size_t nodes;  // the collection and everything in it so far, aliases expanded
  };

  void leaf(YAML::anchor_t anchor) {
    if (anchor != YAML::NullAnchor) nodes_[anchor] = 1;
    add(1);
  }
  void add(std::size_t nodes) {
    if (!open_.empty()) open_.back().nodes += nodes;
  }
  void open(YAML::anchor_t anchor) {
    open_.push_back({anchor, 1});
    if (anchor != YAML::NullAnchor) open_anchors_.insert(anchor);
  }
  void close() {
    const Open done = open_.back();
    open_.pop_back();
    if (done.anchor != YAML::NullAnchor) {
      open_anchors_.erase(done.anchor);
      nodes_[done.anchor] = done.nodes;
    }
    add(done.nodes);
  }

  std::vector<Open> open_;
  std::unordered_set<YAML::anchor_t> open_anchors_;
  std::unordered_map<YAML::anchor_t, std::size_t> nodes_;  // of every closed anchor
  std::size_t aliased_ = 0;
};

}  // namespace

YAML::Node loadYaml(const std::string& text) {
  {
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    AliasCheck check;
    parser.HandleNextDocument(check);
  }
  return YAML::Load(text);
}

}  // namespace auv::config
