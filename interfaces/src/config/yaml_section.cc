#include "auv/config/yaml_section.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "auv/config/spelling.h"
#include "auv/config/yaml_scalars.h"

namespace auv::config {
namespace {

std::string describe(const YAML::Node& node) { return describeNode(node); }

/// The number of a plain scalar by the one rule (yaml_scalars.h), or nullopt.
std::optional<double> plainNumber(const YAML::Node& node) {
  if (!isPlainScalar(node)) return std::nullopt;
  return parseNumber(node.Scalar());
}

std::string rangeText(std::optional<double> min, std::optional<double> max) {
  std::ostringstream out;
  if (min && max)
    out << " in [" << *min << ", " << *max << "]";
  else if (min)
    out << " >= " << *min;
  else if (max)
    out << " <= " << *max;
  return out.str();
}

}  // namespace

YamlSection::YamlSection(YAML::Node node, std::string path, std::string file)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw ConfigError(file_ + ": " + (path_.empty() ? "the file" : path_) +
                      ": expected a map of settings, got " + describe(node_));
  }
}

bool YamlSection::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

std::string YamlSection::where(const std::string& key) const {
  return file_ + ": " + (path_.empty() ? key : path_ + "." + key);
}

void YamlSection::fail(const std::string& key, const std::string& what) const {
  throw ConfigError(where(key) + ": " + what);
}

YamlSection YamlSection::child(const std::string& key) const {
  const std::string path = path_.empty() ? key : path_ + "." + key;
  if (!has(key)) return YamlSection(YAML::Node(), path, file_);
  return YamlSection(node_[key], path, file_);
}

std::vector<YamlSection> YamlSection::childList(const std::string& key) const {
  std::vector<YamlSection> out;
  if (!has(key)) return out;
  const YAML::Node list = node_[key];
  if (!list.IsSequence()) fail(key, "expected a list, got " + describe(list));
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path =
        (path_.empty() ? key : path_ + "." + key) + "[" + std::to_string(i) + "]";
    if (!list[i].IsMap()) {
      throw ConfigError(file_ + ": " + path + ": expected a map, got " + describe(list[i]));
    }
    out.emplace_back(list[i], path, file_);
  }
  return out;
}

YAML::Node YamlSection::scalar(const std::string& key, const char* expected) const {
  const YAML::Node value = node_[key];
  if (!value.IsScalar())
    fail(key, std::string("expected ") + expected + ", got " + describe(value));
  return value;
}

void YamlSection::read(const std::string& key, double& value, std::optional<double> min,
                       std::optional<double> max) const {
  if (!has(key)) return;
  const YAML::Node node = scalar(key, "a number");
  const std::optional<double> number = plainNumber(node);
  if (!number || !std::isfinite(*number)) {
    fail(key, "expected a finite number" + rangeText(min, max) + ", got " + describe(node));
  }
  const double parsed = *number;
  if ((min && parsed < *min) || (max && parsed > *max)) {
    fail(key, "expected a number" + rangeText(min, max) + ", got " + node.Scalar());
  }
  value = parsed;
}

void YamlSection::read(const std::string& key, float& value, std::optional<double> min,
                       std::optional<double> max) const {
  double v = value;
  read(key, v, min, max);
  value = static_cast<float>(v);
}

void YamlSection::read(const std::string& key, int& value, std::optional<int> min,
                       std::optional<int> max) const {
  if (!has(key)) return;
  const YAML::Node node = scalar(key, "an integer");
  const std::optional<int64_t> parsed =
      isPlainScalar(node) ? parseInteger(node.Scalar()) : std::nullopt;
  std::string range;
  if (min && max)
    range = " in [" + std::to_string(*min) + ", " + std::to_string(*max) + "]";
  else if (min)
    range = " >= " + std::to_string(*min);
  else if (max)
    range = " <= " + std::to_string(*max);
  const int64_t number = parsed.value_or(0);
  if (!parsed || number < std::numeric_limits<int>::min() ||
      number > std::numeric_limits<int>::max()) {
    fail(key, "expected an integer" + range + ", got " + describe(node));
  }
  if ((min && number < *min) || (max && number > *max)) {
    fail(key, "expected an integer" + range + ", got " + node.Scalar());
  }
  value = static_cast<int>(number);
}

void YamlSection::read(const std::string& key, bool& value) const {
  if (!has(key)) return;
  const YAML::Node node = scalar(key, "a boolean (true or false)");
  const std::optional<bool> parsed = isPlainScalar(node) ? parseBool(node.Scalar()) : std::nullopt;
  if (!parsed) fail(key, "expected a boolean (true or false), got " + describe(node));
  value = *parsed;
}

void YamlSection::read(const std::string& key, std::string& value) const {
  if (!has(key)) return;
  value = scalar(key, "a string").Scalar();
}

void YamlSection::read(const std::string& key, Eigen::Vector3d& value, std::optional<double> min,
                       std::optional<double> max) const {
  std::vector<double> v;
  read(key, v);
  if (!has(key)) return;
  if (v.size() != 3) {
    fail(key, "expected 3 numbers [a, b, c], got " + std::to_string(v.size()));
  }
  for (size_t i = 0; i < v.size(); ++i) {
    if ((min && v[i] < *min) || (max && v[i] > *max)) {
      fail(key + "[" + std::to_string(i) + "]",
           "expected a number" + rangeText(min, max) + ", got " + nodeText(node_[key][i]));
    }
  }
  value = Eigen::Vector3d(v[0], v[1], v[2]);
}

void YamlSection::read(const std::string& key, std::vector<double>& value) const {
  if (!has(key)) return;
  const YAML::Node list = node_[key];
  if (!list.IsSequence()) fail(key, "expected a list of numbers, got " + describe(list));
  std::vector<double> out;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::optional<double> x = plainNumber(list[i]);
    if (!x || !std::isfinite(*x)) {
      fail(key + "[" + std::to_string(i) + "]",
           "expected a finite number, got " + describe(list[i]));
    }
    out.push_back(*x);
  }
  value = std::move(out);
}

void YamlSection::readDegrees(const std::string& key, double& radians,
                              std::optional<double> min_deg, std::optional<double> max_deg) const {
  if (!has(key)) return;
  double degrees = radians * 180.0 / M_PI;
  read(key, degrees, min_deg, max_deg);
  radians = degrees * M_PI / 180.0;
}

void requireOption(bool ok, const std::string& field, const std::string& what, double value) {
  if (ok) return;
  std::ostringstream message;
  message << field << ": expected " << what << ", got " << value;
  throw ConfigError(message.str());
}

void YamlSection::rejectUnknownKeys(const std::vector<std::string>& known) const {
  if (!node_.IsMap()) return;
  std::vector<std::string> seen;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) {
      throw ConfigError(file_ + markText(entry.first.Mark()) + ": " +
                        (path_.empty() ? "the file" : path_) + ": keys must be plain names, got " +
                        describe(entry.first));
    }
    const std::string& key = entry.first.Scalar();
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) fail(key, "duplicate key");
    seen.push_back(key);
    if (std::find(known.begin(), known.end(), key) == known.end()) unknownKey(key, known);
  }
}

void YamlSection::unknownKey(const std::string& key, const std::vector<std::string>& known) const {
  std::string message = "unknown setting";
  const std::string best = closestMatch(key, known);
  if (!best.empty()) message += " (did you mean '" + best + "'?)";
  std::string list;
  for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
  fail(key, message + "; known: " + list);
}

namespace {

YamlSection rootSection(const YAML::Node& root, const std::string& source, bool allow_empty) {
  if (allow_empty && (!root.IsDefined() || root.IsNull()))
    return YamlSection(YAML::Node(), "", source);
  if (!root.IsMap()) {
    throw ConfigError(source + markText(root.Mark()) +
                      ": expected a map of settings at the top level, got " + describe(root));
  }
  return YamlSection(root, "", source);
}

}  // namespace

YamlSection loadYamlText(const std::string& text, const std::string& source, bool allow_empty) {
  YAML::Node root;
  try {
    root = loadYaml(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + markText(e.mark) + ": malformed YAML: " + e.msg);
  }
  return rootSection(root, source, allow_empty);
}

YamlSection loadYamlFile(const std::string& file, bool allow_empty) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  YAML::Node root;
  try {
    root = loadYaml(text.str());
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + markText(e.mark) + ": malformed YAML: " + e.msg);
  }
  return rootSection(root, file, allow_empty);
}

}  // namespace auv::config
