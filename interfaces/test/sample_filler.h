#pragma once
// Samples with a non-default value in every field, for tests that must cover every type of
// the message set (serialized_test.cc, foxglove_decode_test.cc).

#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "auv/msg/type_support.h"

namespace auv::interfaces::test {

// A YAML document as a plain tree, so a filler can change one leaf and put it back.
struct Value {
  enum Kind { SCALAR, MAP, SEQUENCE } kind = SCALAR;
  std::string scalar;
  std::vector<std::pair<std::string, Value>> map;
  std::vector<Value> sequence;
};

inline Value fromNode(const YAML::Node& node) {
  Value v;
  if (node.IsMap()) {
    v.kind = Value::MAP;
    for (const auto& entry : node) v.map.emplace_back(entry.first.Scalar(), fromNode(entry.second));
  } else if (node.IsSequence()) {
    v.kind = Value::SEQUENCE;
    for (const auto& element : node) v.sequence.push_back(fromNode(element));
  } else {
    v.scalar = node.Scalar();
  }
  return v;
}

inline YAML::Node toNode(const Value& v) {
  if (v.kind == Value::MAP) {
    YAML::Node node(YAML::NodeType::Map);
    for (const auto& [key, value] : v.map) node[key] = toNode(value);
    return node;
  }
  if (v.kind == Value::SEQUENCE) {
    YAML::Node node(YAML::NodeType::Sequence);
    for (const Value& element : v.sequence) node.push_back(toNode(element));
    return node;
  }
  return YAML::Node(v.scalar);
}

// Builds a sample of `type` with a non-default value in every field, nested structs and
// sequence elements included, through the type's own from_yaml: each leaf gets the first
// candidate the type accepts (so a float gets a fraction, an int64 a value beyond 32 bits, a
// uint64 one beyond 63 bits, an enum its last enumerator), each empty sequence two or three
// elements.
class SampleFiller {
 public:
  explicit SampleFiller(const msg::TypeSupport& type) : type_(type) {
    const auto sample = type.create_sample();
    root_ = fromNode(type.to_yaml(sample.get()));
    for (bool grew = true; grew;) {
      grew = fill(root_, "");
      root_ = fromNode(type_.to_yaml(sample_().get()));  // new struct elements get their fields
    }
  }
  std::shared_ptr<void> sample() { return sample_(); }

 private:
  std::shared_ptr<void> sample_() {
    auto sample = type_.create_sample();
    type_.from_yaml(toNode(root_), sample.get());
    return sample;
  }
  std::string error() {
    try {
      sample_();
      return "";
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
  }
  bool accepts() { return error().empty(); }

  // True when it added struct elements to a sequence (their fields come next round).
  bool fill(Value& v, const std::string& path) {
    if (filled_.count(path)) return false;
    bool grew = false;
    if (v.kind == Value::MAP) {
      for (auto& [key, value] : v.map) grew = fill(value, path + "." + key) || grew;
    } else if (v.kind == Value::SEQUENCE && v.sequence.empty()) {
      grew = fillSequence(v, path);
    } else if (v.kind == Value::SEQUENCE) {
      for (size_t i = 0; i < v.sequence.size(); ++i)
        grew = fill(v.sequence[i], path + "[" + std::to_string(i) + "]") || grew;
    } else {
      fillScalar(v, path);
    }
    return grew;
  }

  std::vector<std::string> numbers() {
    const int k = ++counter_;
    return {std::to_string(k) + ".1",                     // float, double
            std::to_string(-(7123456789012LL + k)),       // int64
            std::to_string(-(k + 7)),                     // int16, int32
            std::to_string(12345678901234567890ULL - k),  // uint64
            std::to_string(k % 250 + 1)};                 // octet, uint16, uint32
  }

  // The enumerators, as the error for an unknown one lists them.
  std::vector<std::string> enumerators(Value& v) {
    const std::string old = v.scalar;
    v.scalar = "?";
    const std::string what = error();
    v.scalar = old;
    const size_t begin = what.find("one of [");
    const size_t end = what.find(']', begin);
    std::vector<std::string> names;
    if (begin == std::string::npos || end == std::string::npos) return names;
    std::string list = what.substr(begin + 8, end - begin - 8) + ", ";
    for (size_t at; (at = list.find(", ")) != std::string::npos; list.erase(0, at + 2))
      names.push_back(list.substr(0, at));
    return names;
  }

  void fillScalar(Value& v, const std::string& path) {
    filled_.insert(path);
    std::vector<std::string> candidates;
    if (v.scalar == "false")
      candidates = {"true"};
    else if (v.scalar.empty())
      candidates = {"text " + std::to_string(++counter_) + " \xc3\xbc"};  // UTF-8 too
    else if (v.scalar == "0")
      candidates = numbers();
    else if (const auto names = enumerators(v); !names.empty())
      candidates = {names.back()};
    for (const std::string& candidate : candidates) {
      const std::string old = v.scalar;
      v.scalar = candidate;
      if (accepts()) return;
      v.scalar = old;
    }
    ADD_FAILURE() << type_.name << path << ": no value accepted";
  }

  bool fillSequence(Value& v, const std::string& path) {
    const auto list = [](std::vector<std::string> scalars) {
      Value seq;
      seq.kind = Value::SEQUENCE;
      for (auto& s : scalars) seq.sequence.push_back(Value{Value::SCALAR, s, {}, {}});
      return seq;
    };
    Value structs;
    structs.kind = Value::SEQUENCE;
    structs.sequence.resize(2, Value{Value::MAP, "", {}, {}});
    std::vector<Value> candidates = {structs, list({"word a", "word b \xc3\xbc"}),
                                     list({"true", "false", "true"})};
    const std::vector<std::vector<std::string>> three = {numbers(), numbers(), numbers()};
    for (size_t i = 0; i < three.front().size(); ++i)
      candidates.push_back(list({three[0][i], three[1][i], three[2][i]}));
    // A sequence of an enum: its enumerators, as the error for an unknown one lists them.
    const Value before = v;
    v = list({"?"});
    const std::vector<std::string> names = enumerators(v.sequence.front());
    v = before;
    if (!names.empty()) candidates.push_back(list({names.back(), names.front()}));
    for (size_t i = 0; i < candidates.size(); ++i) {
      Value old = v;
      v = candidates[i];
      if (accepts()) {
        if (i != 0) filled_.insert(path);
        return i == 0;
      }
      v = old;
    }
    ADD_FAILURE() << type_.name << path << ": no sequence accepted";
    return false;
  }

  const msg::TypeSupport& type_;
  Value root_;
  std::set<std::string> filled_;  // paths of leaves and sequences given their value
  int counter_ = 0;
};

}  // namespace auv::interfaces::test
