#include "auv/config/yaml_section.h"

#include <cerrno>
#include <cmath>
#include <limits>
#include <sstream>

#include "auv/config/spelling.h"

namespace auv::config {
namespace {

std::string describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a sequence";
  if (node.IsMap()) return "a map";
  return "nothing";
}

// Strict YAML 1.2 core-schema numbers: yaml-cpp would also accept e.g. "0x10" for double
// and "1e3" for int inconsistently, so parse the text ourselves.
bool parseDouble(const std::string& text, double& value) {
  if (text == ".inf" || text == "+.inf")
    return value = std::numeric_limits<double>::infinity(), true;
  if (text == "-.inf") return value = -std::numeric_limits<double>::infinity(), true;
  if (text == ".nan") return value = std::numeric_limits<double>::quiet_NaN(), true;
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end && *end == '\0' && text.find_first_of("xXpP") == std::string::npos;
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
  double parsed = 0;
  if (!parseDouble(node.Scalar(), parsed) || !std::isfinite(parsed)) {
    fail(key, "expected a finite number" + rangeText(min, max) + ", got " + describe(node));
  }
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
  const std::string& text = node.Scalar();
  char* end = nullptr;
  errno = 0;
  const long parsed = std::strtol(text.c_str(), &end, 10);
  std::string range;
  if (min && max)
    range = " in [" + std::to_string(*min) + ", " + std::to_string(*max) + "]";
  else if (min)
    range = " >= " + std::to_string(*min);
  else if (max)
    range = " <= " + std::to_string(*max);
  if (text.empty() || *end != '\0' || errno == ERANGE || parsed < std::numeric_limits<int>::min() ||
      parsed > std::numeric_limits<int>::max()) {
    fail(key, "expected an integer" + range + ", got " + describe(node));
  }
  if ((min && parsed < *min) || (max && parsed > *max)) {
    fail(key, "expected an integer" + range + ", got " + text);
  }
  value = static_cast<int>(parsed);
}

void YamlSection::read(const std::string& key, bool& value) const {
  if (!has(key)) return;
  const YAML::Node node = scalar(key, "true or false");
  const std::string& t = node.Scalar();
  if (t == "true" || t == "True" || t == "TRUE") {
    value = true;
  } else if (t == "false" || t == "False" || t == "FALSE") {
    value = false;
  } else {
    fail(key, "expected true or false, got " + describe(node));
  }
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
  for (double x : v) {
    if ((min && x < *min) || (max && x > *max)) {
      fail(key, "every element must be a number" + rangeText(min, max));
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
    double x = 0;
    if (!list[i].IsScalar() || !parseDouble(list[i].Scalar(), x) || !std::isfinite(x)) {
      fail(key, "element " + std::to_string(i) + " is not a finite number: " + describe(list[i]));
    }
    out.push_back(x);
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
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    bool found = false;
    std::string best;
    size_t best_distance = 3;  // suggest only close spellings
    for (const std::string& k : known) {
      if (k == key) found = true;
      const size_t d = editDistance(k, key);
      if (d < best_distance) best_distance = d, best = k;
    }
    if (found) continue;
    std::string message = "unknown setting";
    if (!best.empty()) message += " (did you mean '" + best + "'?)";
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    fail(key, message + "; known: " + list);
  }
}

YamlSection loadYamlFile(const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw ConfigError(file + ": cannot open the file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(file + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw ConfigError(file + ": expected a map of settings at the top level");
  return YamlSection(root, "", file);
}

}  // namespace auv::config
