// The repository stands alone (docs/contributing.md, "The repository stands alone"): no file
// sends a reader to design notes kept outside the repository, and every relative Markdown link
// points to a file that exists. Walks the source tree given as AUV_SOURCE_DIR, skipping build
// outputs (build/, install/, log/, build-*/, auv_runs/, bench_results/), node_modules/ and .git.
//
// The names of the outside notes are assembled at run time below, so that this file does not
// contain the references it looks for.

#include <gtest/gtest.h>

#include <cctype>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// The repository root, without a trailing separator ("<src>/test/.." normalises to "<src>/").
fs::path repositoryRoot() {
  fs::path root = fs::path(AUV_SOURCE_DIR).lexically_normal();
  return root.has_filename() ? root : root.parent_path();
}

const fs::path kRoot = repositoryRoot();

/// Directories never searched: build outputs, version control, and the npm packages
/// `npm ci` installs in js/ (other people's files, whose READMEs link to files npm leaves out).
bool skippedDirectory(const fs::path& dir) {
  const std::string name = dir.filename().string();
  return name == ".git" || name == "build" || name == "install" || name == "log" ||
         name.rfind("build-", 0) == 0 || name == "auv_runs" || name == "bench_results" ||
         name == "__pycache__" || name == "node_modules";
}

struct TextFile {
  fs::path path;         ///< Absolute.
  std::string relative;  ///< Relative to the repository root, '/'-separated.
  std::vector<std::string> lines;
};

/// Every text file of the tree (files larger than 4 MiB or with a NUL byte are skipped).
std::vector<TextFile> textFiles() {
  std::vector<TextFile> files;
  std::error_code error;
  fs::recursive_directory_iterator it(kRoot, fs::directory_options::skip_permission_denied, error);
  for (; !error && it != fs::recursive_directory_iterator(); it.increment(error)) {
    const fs::directory_entry& entry = *it;
    if (entry.is_directory() && !entry.is_symlink()) {
      if (skippedDirectory(entry.path())) it.disable_recursion_pending();
      continue;
    }
    if (!entry.is_regular_file() || entry.file_size() > (4u << 20)) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string content((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
    if (content.find('\0') != std::string::npos) continue;
    TextFile file;
    file.path = entry.path();
    file.relative = entry.path().lexically_relative(kRoot).generic_string();
    std::istringstream lines(content);
    for (std::string line; std::getline(lines, line);) file.lines.push_back(line);
    files.push_back(std::move(file));
  }
  EXPECT_FALSE(error) << "walking " << kRoot << ": " << error.message();
  return files;
}

/// The references to notes outside the repository found in `line` (empty: none). A path into
/// the shared folder is allowed only for its data and tools, which tests, benchmarks and
/// scripts use when present and skip cleanly without.
std::vector<std::string> outsideReferences(const std::string& line) {
  static const std::vector<std::string> kNames = {
      std::string("PAPER") + ".md",  std::string("DESIGN") + ".md",
      std::string("STYLE") + ".md",  std::string("LIBRARY") + "_NOTES",
      std::string("DDS") + "_NOTES",
  };
  static const std::string kShared = std::string("../") + "shared/";
  static const std::vector<std::string> kAllowedShared = {"data", "tools"};
  std::vector<std::string> found;
  for (const std::string& name : kNames) {
    if (line.find(name) != std::string::npos) found.push_back(name);
  }
  for (std::size_t at = line.find(kShared); at != std::string::npos;
       at = line.find(kShared, at + 1)) {
    const std::string rest = line.substr(at + kShared.size());
    bool allowed = false;
    for (const std::string& ok : kAllowedShared) {
      allowed = allowed || (rest.compare(0, ok.size(), ok) == 0 &&
                            (rest.size() == ok.size() ||
                             !std::isalnum(static_cast<unsigned char>(rest[ok.size()]))));
    }
    if (!allowed) found.push_back(kShared + rest.substr(0, rest.find_first_of(" \t)`'\",;")));
  }
  return found;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The link targets of one Markdown line outside code: inline links `[text](target "title")`
/// and reference definitions `[label]: target`. Inline code spans are ignored.
std::vector<std::string> markdownTargets(const std::string& raw) {
  static const std::regex kCode("`[^`]*`");
  static const std::regex kInline(R"(\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\))");
  static const std::regex kDefinition(R"(^\s{0,3}\[[^\]]+\]:\s*<?([^\s>]+)>?)");
  const std::string line = std::regex_replace(raw, kCode, "");
  std::vector<std::string> targets;
  for (std::sregex_iterator m(line.begin(), line.end(), kInline), end; m != end; ++m) {
    targets.push_back((*m)[1].str());
  }
  std::smatch definition;
  if (std::regex_search(line, definition, kDefinition)) targets.push_back(definition[1].str());
  return targets;
}

/// The file a relative link target names, or an empty path for links not checked (URLs with
/// a scheme such as http: or mailto:, anchors within the same page).
fs::path linkedFile(const fs::path& markdown, std::string target) {
  static const std::regex kScheme("^[A-Za-z][A-Za-z0-9+.-]*:");
  if (target.empty() || target[0] == '#' || std::regex_search(target, kScheme)) return {};
  target = target.substr(0, target.find_first_of("#?"));
  for (std::size_t at; (at = target.find("%20")) != std::string::npos;) {
    target.replace(at, 3, " ");
  }
  if (target.empty()) return {};
  if (target[0] == '/') return (kRoot / target.substr(1)).lexically_normal();
  return (markdown.parent_path() / target).lexically_normal();
}

TEST(RepositoryStandsAloneTest, FindsTheRepository) {
  ASSERT_TRUE(fs::is_regular_file(kRoot / "README.md")) << kRoot;
  bool found_docs = false;
  for (const TextFile& file : textFiles()) {
    found_docs = found_docs || file.relative == "docs/paper.md";
  }
  EXPECT_TRUE(found_docs) << "docs/paper.md not found under " << kRoot;
}

TEST(RepositoryStandsAloneTest, CheckerFlagsOutsideNotesAndAllowsSharedDataAndTools) {
  const std::string shared = std::string("../") + "shared/";
  EXPECT_EQ(outsideReferences("see " + shared + "DE" + "SIGN.md section 6").size(), 2u);
  EXPECT_EQ(outsideReferences("(PAPER"
                              ".md 2.3)")
                .size(),
            1u);
  EXPECT_EQ(outsideReferences("see LIBRARY"
                              "_NOTES")
                .size(),
            1u);
  EXPECT_EQ(outsideReferences("see " + shared + "notes/x").size(), 1u);
  EXPECT_EQ(outsideReferences("see " + shared + "database").size(), 1u);
  EXPECT_TRUE(outsideReferences("data=\"$repo/" + shared + "data/sceaux_castle\"").empty());
  EXPECT_TRUE(outsideReferences("[ -x " + shared + "tools/no-external-traffic ]").empty());
  EXPECT_TRUE(outsideReferences("docs/paper.md §2.3, docs/design.md §6").empty());
}

TEST(RepositoryStandsAloneTest, CheckerFindsMarkdownLinkTargets) {
  EXPECT_EQ(markdownTargets("see [a](docs/a.md) and [b](../b.md#x \"t\")"),
            (std::vector<std::string>{"docs/a.md", "../b.md#x"}));
  EXPECT_TRUE(markdownTargets("`[a](not/a/link.md)` only code").empty());
  EXPECT_EQ(markdownTargets("[ref]: other.md"), (std::vector<std::string>{"other.md"}));
  const fs::path page = kRoot / "docs" / "page.md";
  EXPECT_TRUE(linkedFile(page, "https://example.org/a.md").empty());
  EXPECT_TRUE(linkedFile(page, "#section").empty());
  EXPECT_EQ(linkedFile(page, "../README.md#status"), (kRoot / "README.md").lexically_normal());
}

TEST(RepositoryStandsAloneTest, NoReferencesToNotesOutsideTheRepository) {
  std::size_t files = 0;
  for (const TextFile& file : textFiles()) {
    ++files;
    for (std::size_t i = 0; i < file.lines.size(); ++i) {
      for (const std::string& reference : outsideReferences(file.lines[i])) {
        ADD_FAILURE() << file.relative << ":" << i + 1 << ": refers to '" << reference
                      << "', which is not in the repository; cite docs/ instead "
                         "(docs/contributing.md): "
                      << file.lines[i].substr(0, 160);
      }
    }
  }
  EXPECT_GT(files, 100u) << "too few files under " << kRoot;
}

TEST(RepositoryStandsAloneTest, RelativeMarkdownLinksPointToExistingFiles) {
  std::size_t links = 0;
  for (const TextFile& file : textFiles()) {
    if (!endsWith(file.relative, ".md")) continue;
    std::string fence;  // the open code fence ("```" or "~~~"), empty outside one
    for (std::size_t i = 0; i < file.lines.size(); ++i) {
      const std::string& line = file.lines[i];
      const std::size_t start = line.find_first_not_of(" \t");
      if (start != std::string::npos) {
        const std::string marker = line.substr(start, 3);
        if (marker == "```" || marker == "~~~") {
          if (fence.empty()) {
            fence = marker;
          } else if (marker == fence) {
            fence.clear();
          }
          continue;
        }
      }
      if (!fence.empty()) continue;
      for (const std::string& target : markdownTargets(line)) {
        const fs::path linked = linkedFile(file.path, target);
        if (linked.empty()) continue;
        ++links;
        EXPECT_TRUE(fs::exists(linked)) << file.relative << ":" << i + 1 << ": link to '" << target
                                        << "', which does not exist";
      }
    }
  }
  EXPECT_GT(links, 10u) << "too few relative links found under " << kRoot;
}

}  // namespace
