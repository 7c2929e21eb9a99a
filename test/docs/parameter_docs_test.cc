// The parameter tables of the component READMEs against `auv run <component> --help`: every
// declared parameter is documented, and a documented unit, range and default are the
// declared ones — the docs cannot drift from the code (one declaration per parameter,
// auv/config/option_table.h). Built-in parameters (use_sim_time, log_level, qos.*) are
// documented once, in the top-level README.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct DocRow {
  int line = 0;
  std::map<std::string, std::string> cells;  // column name (lower case) -> cell text
};

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t") - begin + 1);
}

std::string stripQuotes(std::string text) {
  text = trim(text);
  while (text.size() >= 2 && ((text.front() == '`' && text.back() == '`') ||
                              (text.front() == '"' && text.back() == '"'))) {
    text = trim(text.substr(1, text.size() - 2));
  }
  return text;
}

std::vector<std::string> cellsOf(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool in_code = false;
  for (size_t i = 1; i < line.size(); ++i) {  // after the leading '|'
    const char c = line[i];
    if (c == '`') in_code = !in_code;
    if (c == '|' && !in_code) {
      cells.push_back(trim(cell));
      cell.clear();
    } else {
      cell += c;
    }
  }
  return cells;
}

/// The first table after the "## Parameters" heading of `readme`.
std::vector<DocRow> parameterTable(const std::string& readme) {
  std::ifstream in(readme);
  EXPECT_TRUE(in) << readme;
  std::string line;
  int number = 0;
  bool in_section = false;
  std::vector<std::string> header;
  std::vector<DocRow> rows;
  while (std::getline(in, line)) {
    ++number;
    if (line.rfind("## ", 0) == 0) {
      if (in_section && !header.empty()) break;
      in_section = line == "## Parameters";
      continue;
    }
    if (!in_section) continue;
    if (line.rfind("|", 0) != 0) {
      if (!header.empty()) break;  // the table ended
      continue;
    }
    const std::vector<std::string> cells = cellsOf(line);
    if (header.empty()) {
      for (const std::string& c : cells) {
        std::string name;
        for (char ch : c) name += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        header.push_back(name);
      }
      continue;
    }
    if (line.rfind("|---", 0) == 0 || line.rfind("| ---", 0) == 0) continue;
    DocRow row;
    row.line = number;
    for (size_t i = 0; i < cells.size() && i < header.size(); ++i) row.cells[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  ::pclose(pipe);
  return out;
}

std::optional<double> number(const std::string& text) {
  const std::string t = stripQuotes(text);
  if (t.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(t.c_str(), &end);
  if (end == t.c_str() || *end != '\0') return std::nullopt;
  return value;
}

bool isBuiltIn(const std::string& name) {
  return name == "use_sim_time" || name == "log_level" || name.rfind("qos.", 0) == 0;
}

std::string formatNumber(double value) {
  std::ostringstream out;
  out.precision(12);  // 16777216, not 1.67772e+07
  out << value;
  return out.str();
}

/// What a declared parameter accepts, as a README writes it: "[a, b]", "(a, b]", "> a",
/// "<= b" for numbers (an integer's ends are always inclusive), "one of a, b" for strings with
/// choices, "" for anything else.
std::string declaredRange(const YAML::Node& p) {
  const bool low_open = p["min_exclusive"] && p["min_exclusive"].as<bool>();
  const bool high_open = p["max_exclusive"] && p["max_exclusive"].as<bool>();
  if (p["min"] && p["max"]) {
    return (low_open ? "(" : "[") + formatNumber(p["min"].as<double>()) + ", " +
           formatNumber(p["max"].as<double>()) + (high_open ? ")" : "]");
  }
  if (p["min"]) return (low_open ? "> " : ">= ") + formatNumber(p["min"].as<double>());
  if (p["max"]) return (high_open ? "< " : "<= ") + formatNumber(p["max"].as<double>());
  if (p["choices"]) {
    std::string text = "one of ";
    for (size_t i = 0; i < p["choices"].size(); ++i) {
      text += (i ? ", " : "") + p["choices"][i].as<std::string>();
    }
    return text;
  }
  return "";
}

/// The same of a documented range, with its numbers read as numbers ("1e6" == 1000000) and
/// code quotes dropped ("one of `a`, `b`").
std::string documentedRange(const std::string& cell) {
  std::string t;
  for (char c : trim(cell)) {
    if (c != '`') t += c;
  }
  for (const char* op : {">=", "<=", ">", "<"}) {
    if (t.rfind(op, 0) != 0) continue;
    const auto value = number(t.substr(std::string(op).size()));
    return value ? std::string(op) + " " + formatNumber(*value) : t;
  }
  if (t.size() < 5 || (t.front() != '[' && t.front() != '(')) return t;
  const size_t comma = t.find(',');
  if (comma == std::string::npos) return t;
  const auto low = number(t.substr(1, comma - 1));
  const auto high = number(t.substr(comma + 1, t.size() - comma - 2));
  if (!low || !high) return t;
  return t.front() + formatNumber(*low) + ", " + formatNumber(*high) + t.back();
}

void checkComponent(const std::string& component, const std::string& readme_path) {
  SCOPED_TRACE(component + ": " + readme_path);
  // In a folder of its own: configuring the simulator writes a run folder (auv_runs/...).
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() /
      ("auv_parameter_docs_" + component + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const std::string help = run("cd '" + folder.string() + "' && " + AUV_EXECUTABLE + " run " +
                               component + " --help 2>/dev/null");
  std::filesystem::remove_all(folder);
  const YAML::Node declared = YAML::Load(help);
  ASSERT_TRUE(declared.IsMap()) << help;
  const std::vector<DocRow> rows = parameterTable(readme_path);
  ASSERT_FALSE(rows.empty()) << "no table under '## Parameters'";
  std::map<std::string, int> documented;
  for (const DocRow& row : rows) {
    const std::string where = readme_path + ":" + std::to_string(row.line);
    const std::string name =
        stripQuotes(row.cells.count("name") ? row.cells.at("name") : row.cells.at("parameter"));
    documented[name] = row.line;
    const YAML::Node p = declared[name];
    if (!p) {
      ADD_FAILURE() << where << ": '" << name << "' is not a parameter of " << component;
      continue;
    }
    const std::string unit = p["unit"] ? p["unit"].as<std::string>() : "";
    if (row.cells.count("unit")) {
      EXPECT_EQ(stripQuotes(row.cells.at("unit")), unit) << where << ": unit of " << name;
    }
    if (row.cells.count("range")) {
      EXPECT_EQ(documentedRange(row.cells.at("range")), declaredRange(p))
          << where << ": range of " << name;
    }
    if (row.cells.count("default") && p["value"].IsScalar()) {
      const std::string doc = stripQuotes(row.cells.at("default"));
      const auto doc_number = number(doc);
      const auto value_number = number(p["value"].Scalar());
      if (doc_number && value_number) {
        EXPECT_DOUBLE_EQ(*doc_number, *value_number) << where << ": default of " << name;
      } else if (doc.empty() || doc.front() != '(') {  // "(required)", "(the user's cache)"
        EXPECT_EQ(doc, p["value"].Scalar()) << where << ": default of " << name;
      }
    }
  }
  for (const auto& entry : declared) {
    const std::string name = entry.first.as<std::string>();
    if (!isBuiltIn(name) && !documented.count(name)) {
      ADD_FAILURE() << readme_path << ": parameter '" << name << "' of " << component
                    << " is not in the table under '## Parameters'";
    }
  }
}

TEST(ParameterDocs, MappingReadmeMatchesHelp) {
  checkComponent("mapping", std::string(AUV_SOURCE_DIR) + "/components/mapping/README.md");
}

TEST(ParameterDocs, RecorderReadmeMatchesHelp) {
  checkComponent("recorder", std::string(AUV_SOURCE_DIR) + "/components/recorder/README.md");
}

TEST(ParameterDocs, ControllerReadmeMatchesHelp) {
  checkComponent("controller", std::string(AUV_SOURCE_DIR) + "/components/control/README.md");
}

TEST(ParameterDocs, PlanningReadmeMatchesHelp) {
  checkComponent("planning", std::string(AUV_SOURCE_DIR) + "/components/planning/README.md");
}

TEST(ParameterDocs, MissionReadmeMatchesHelp) {
  checkComponent("mission", std::string(AUV_SOURCE_DIR) + "/components/mission/README.md");
}

TEST(ParameterDocs, SimulatorReadmeMatchesHelp) {
  checkComponent("simulator", std::string(AUV_SOURCE_DIR) + "/components/simulator/README.md");
}

TEST(ParameterDocs, FoxgloveBridgeReadmeMatchesHelp) {
  checkComponent("foxglove_bridge",
                 std::string(AUV_SOURCE_DIR) + "/components/foxglove_bridge/README.md");
}

// The checker itself: a range or a parameter that differs is found.
TEST(ParameterDocs, RangesAreComparedAsNumbers) {
  EXPECT_EQ(documentedRange("[2, 1e6]"), "[2, 1000000]");
  EXPECT_EQ(documentedRange("[4096, 16777216]"), "[4096, 16777216]");
  EXPECT_EQ(documentedRange(">= 0.0"), ">= 0");
  EXPECT_EQ(documentedRange("one of `stop`, `hold_depth`"), "one of stop, hold_depth");
  EXPECT_EQ(declaredRange(YAML::Load("{min: 0, min_exclusive: true}")), "> 0");
  EXPECT_EQ(declaredRange(YAML::Load("{max: 3}")), "<= 3");
  EXPECT_EQ(declaredRange(YAML::Load("{choices: [stop, hold_depth]}")), "one of stop, hold_depth");
  EXPECT_EQ(declaredRange(YAML::Load("{type: bool}")), "");
  EXPECT_EQ(documentedRange("(0.5, 1)"), "(0.5, 1)");
  EXPECT_EQ(documentedRange("(0, prob_miss]"), "(0, prob_miss]");  // not numbers: as written
  const YAML::Node open =
      YAML::Load("{min: 0.5, min_exclusive: true, max: 1, max_exclusive: true}");
  EXPECT_EQ(declaredRange(open), "(0.5, 1)");
  EXPECT_NE(documentedRange("[0.501, 0.999]"), declaredRange(open));
}

}  // namespace
