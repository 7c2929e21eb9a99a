// filledSample: a sample with every string and sequence non-empty, learnt from the type's own
// YAML conversion (no per-type code to keep in step with the IDL).
#include <variant>
#include <vector>

#include "auv/msg/type_support.h"

namespace auv::msg {
namespace {

// A path into a sample's YAML tree: map keys and sequence indices.
using YamlPath = std::vector<std::variant<std::string, size_t>>;

YAML::Node at(YAML::Node root, const YamlPath& path) {
  YAML::Node node = root;
  for (const auto& step : path) {
    YAML::Node next = std::holds_alternative<std::string>(step) ? node[std::get<std::string>(step)]
                                                                : node[std::get<size_t>(step)];
    node.reset(next);
  }
  return node;
}

// Empty strings (scalars "") and empty sequences of `node`, found from the type's to_yaml.
void emptyLeaves(const YAML::Node& node, YamlPath& path, std::vector<YamlPath>& found) {
  if (node.IsMap()) {
    for (const auto& entry : node) {
      path.push_back(entry.first.Scalar());
      emptyLeaves(entry.second, path, found);
      path.pop_back();
    }
  } else if (node.IsSequence()) {
    if (node.size() == 0) found.push_back(path);
    for (size_t i = 0; i < node.size(); ++i) {
      path.push_back(i);
      emptyLeaves(node[i], path, found);
      path.pop_back();
    }
  } else if (node.IsScalar() && node.Scalar().empty()) {
    found.push_back(path);
  }
}

}  // namespace

std::shared_ptr<void> filledSample(const TypeSupport& type) {
  auto sample = type.create_sample();
  for (int round = 0; round < 3; ++round) {  // new struct elements bring empty fields of their own
    const YAML::Node current = type.to_yaml(sample.get());
    YamlPath path;
    std::vector<YamlPath> leaves;
    emptyLeaves(current, path, leaves);
    if (leaves.empty()) break;
    for (const YamlPath& leaf : leaves) {
      for (const char* candidate : {"text", "3", "true", "{}"}) {
        const YAML::Node trial = type.to_yaml(sample.get());
        YAML::Node node = at(trial, leaf);
        if (node.IsSequence()) {
          node.push_back(YAML::Load(candidate));
        } else {
          node = candidate;
        }
        auto grown = type.create_sample();
        try {
          type.from_yaml(trial, grown.get());
        } catch (const std::invalid_argument&) {
          continue;
        }
        sample = grown;
        break;
      }
    }
  }
  return sample;
}

}  // namespace auv::msg
