#include "auv/config/mesh_file_check.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <streambuf>
#include <vector>

namespace auv::config {
namespace {

namespace fs = std::filesystem;

// Open3D 0.16 reads PLY with rply and trusts the file: it allocates the header's vertex count
// before reading, rply visits every instance of an element even one without properties, a list
// of lists makes rply call past its table of readers, and every face is triangulated with its
// corners read from the vertices unchecked. plyProblem() walks the file as rply does and says
// what would crash, exhaust the memory or not end there; "" when Open3D may read it (or fail
// by itself). `faces`: check the faces too (the mesh reader; the cloud reader skips them).
namespace ply_check {

constexpr double kMaxCorners = 255;  // a uchar count; ear clipping costs up to corners^3

enum class Storage { kAscii, kLittleEndian, kBigEndian };

struct Property {
  std::string name;
  int type = 0;  // 0..7: int8 uint8 int16 uint16 int32 uint32 float32 float64; of the count
  bool list = false;
  int item_type = 0;
};

struct Element {
  std::string name;
  long count = 0;
  std::vector<Property> properties;
};

constexpr int kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};

/// 0..7 as above (rply's aliases char..double included), -1 for anything else ("list" too).
int typeOf(const std::string& word) {
  static const char* const names[] = {"int8",    "uint8",   "int16", "uint16", "int32", "uint32",
                                      "float32", "float64", "char",  "uchar",  "short", "ushort",
                                      "int",     "uint",    "float", "double"};
  for (int i = 0; i < 16; ++i) {
    if (word == names[i]) return i % 8;
  }
  return -1;
}

bool isBlank(int c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

/// rply's ply_read_word: blanks skipped, the word ends at a blank or NUL (consumed).
bool readWord(std::streambuf& in, std::string& word) {
  int c = in.sbumpc();
  while (c != EOF && isBlank(c)) c = in.sbumpc();
  word.clear();
  while (c != EOF && !isBlank(c) && c != '\0') {
    word += static_cast<char>(c);
    c = in.sbumpc();
  }
  return !word.empty() && word.size() < 256;
}

/// rply's ply_read_line (comment, obj_info): the rest of the line, '\n' consumed.
std::string skipLine(std::streambuf& in) {
  size_t length = 0;
  for (int c = in.sbumpc(); c != '\n'; c = in.sbumpc(), ++length) {
    if (c == EOF) return "the header ends in a comment";
    if (c == '\0') return "a NUL byte in the header";
  }
  return length < 1024 ? "" : "a header line over 1023 bytes";
}

/// The header as rply reads it; a problem where rply would refuse it (or read it otherwise).
std::string readHeader(std::streambuf& in, Storage& storage, std::vector<Element>& elements) {
  char magic[5] = {};
  in.sgetn(magic, 5);
  if (magic[0] != 'p' || magic[1] != 'l' || magic[2] != 'y' ||
      !std::isspace(static_cast<unsigned char>(magic[3]))) {
    return "not a PLY file (no 'ply' first line)";
  }
  const bool crlf = magic[3] == '\r' && magic[4] == '\n';
  in.pubseekpos(3, std::ios::in);
  std::string word, version;
  if (!readWord(in, word) || word != "format" || !readWord(in, word) || !readWord(in, version) ||
      version != "1.0") {
    return "no 'format <ascii|binary_little_endian|binary_big_endian> 1.0' line";
  }
  if (word == "ascii") {
    storage = Storage::kAscii;
  } else if (word == "binary_little_endian") {
    storage = Storage::kLittleEndian;
  } else if (word == "binary_big_endian") {
    storage = Storage::kBigEndian;
  } else {
    return "unknown format '" + word + "'";
  }
  if (!readWord(in, word)) return "the header ends before end_header";
  while (word != "end_header") {
    if (word == "comment" || word == "obj_info") {
      if (std::string problem = skipLine(in); !problem.empty()) return problem;
    } else if (word == "element") {
      Element element;
      if (!readWord(in, element.name) || !readWord(in, word) ||
          std::sscanf(word.c_str(), "%ld", &element.count) != 1) {
        return "an element without a name or count";
      }
      elements.push_back(element);
    } else if (word == "property" && !elements.empty()) {
      Property property;
      if (!readWord(in, word)) return "a property without a type";
      property.list = word == "list";
      std::string item;
      if (property.list && (!readWord(in, word) || !readWord(in, item))) {
        return "a list property without its types";
      }
      property.type = typeOf(word);
      property.item_type = property.list ? typeOf(item) : 0;
      if (!readWord(in, property.name)) return "a property without a name";
      if (property.type < 0 || property.item_type < 0) {
        return "property '" + property.name + "' of an unknown type (a list of lists?)";
      }
      elements.back().properties.push_back(property);
    } else {
      return "unexpected '" + word + "' in the header";
    }
    if (!readWord(in, word)) return "the header ends before end_header";
  }
  if (crlf) in.sbumpc();
  return "";
}

/// A value of type T from its little-endian bytes.
template <class T>
double load(const unsigned char* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof value);
  return static_cast<double>(value);
}

/// One value as rply reads it; false where rply stops (end of file, not a number).
bool readValue(std::streambuf& in, Storage storage, int type, double& value) {
  if (storage == Storage::kAscii) {
    std::string word;
    if (!readWord(in, word)) return false;
    char* end = nullptr;
    value = type >= 6 ? std::strtod(word.c_str(), &end)
                      : static_cast<double>(std::strtol(word.c_str(), &end, 10));
    return *end == '\0';
  }
  unsigned char bytes[8];
  const int size = kSizes[type];
  if (in.sgetn(reinterpret_cast<char*>(bytes), size) != size) return false;
  if (storage == Storage::kBigEndian) std::reverse(bytes, bytes + size);  // x86/ARM: little
  switch (type) {
    case 0:
      value = load<int8_t>(bytes);
      break;
    case 1:
      value = load<uint8_t>(bytes);
      break;
    case 2:
      value = load<int16_t>(bytes);
      break;
    case 3:
      value = load<uint16_t>(bytes);
      break;
    case 4:
      value = load<int32_t>(bytes);
      break;
    case 5:
      value = load<uint32_t>(bytes);
      break;
    case 6:
      value = load<float>(bytes);
      break;
    default:
      value = load<double>(bytes);
      break;
  }
  return true;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string plyProblem(const std::string& path, bool faces) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return "";  // Open3D says so
  std::streambuf& in = *file.rdbuf();
  Storage storage = Storage::kAscii;
  std::vector<Element> elements;
  if (std::string problem = readHeader(in, storage, elements); !problem.empty()) return problem;

  // Every instance takes at least a byte per scalar (binary: its size) or a word and a blank.
  const std::streamoff data = in.pubseekoff(0, std::ios::cur, std::ios::in);
  const std::streamoff bytes = in.pubseekoff(0, std::ios::end, std::ios::in) - data;
  in.pubseekpos(data, std::ios::in);
  double needed = 0;
  for (const Element& e : elements) {
    if (e.count <= 0) continue;
    if (e.properties.empty()) {
      return "element '" + e.name + "' has " + std::to_string(e.count) +
             " instances but no property";
    }
    double instance = 0;
    for (const Property& p : e.properties)
      instance += storage == Storage::kAscii ? 2 : kSizes[p.type];
    needed += static_cast<double>(e.count) * instance;
    if (needed > static_cast<double>(bytes) + 1) {
      return "the header declares " + std::to_string(e.count) + " '" + e.name +
             "' elements, more than the " + std::to_string(bytes) +
             " bytes after it hold (truncated or damaged)";
    }
  }
  if (!faces) return "";

  // The faces Open3D triangulates: property vertex_indices (or vertex_index) of element face,
  // corners into element vertex (with an x: else Open3D reads nothing).
  const auto named = [](const auto& items, const std::string& name) {
    return std::find_if(items.begin(), items.end(), [&](const auto& i) { return i.name == name; });
  };
  const auto vertex = named(elements, "vertex");
  const auto face = named(elements, "face");
  if (vertex == elements.end() || named(vertex->properties, "x") == vertex->properties.end() ||
      face == elements.end() || face->count <= 0) {
    return "";
  }
  const int vertices = static_cast<int>(vertex->count);  // as Open3D takes it
  if (vertices <= 0) return "";
  std::vector<bool> corners(face->properties.size(), false);
  for (const char* name : {"vertex_indices", "vertex_index"}) {
    const auto p = named(face->properties, name);
    if (p == face->properties.end()) continue;
    if (!p->list) return "face property '" + p->name + "' is not a list";
    corners[static_cast<size_t>(p - face->properties.begin())] = true;
  }
  for (auto e = elements.begin(); e <= face; ++e) {
    const bool fixed = std::none_of(e->properties.begin(), e->properties.end(),
                                    [](const Property& p) { return p.list; });
    if (e != face && storage != Storage::kAscii && fixed) {  // skip it whole
      std::streamoff stride = 0;
      for (const Property& p : e->properties) stride += kSizes[p.type];
      in.pubseekoff(std::max(e->count, 0L) * stride, std::ios::cur, std::ios::in);
      continue;
    }
    for (long i = 0; i < e->count; ++i) {
      for (size_t k = 0; k < e->properties.size(); ++k) {
        const Property& p = e->properties[k];
        double value = 0;
        if (!p.list && storage == Storage::kAscii) {  // a word: what rply makes of it is not read
          std::string word;
          if (!readWord(in, word)) return "";  // rply stops here too
          continue;
        }
        if (!readValue(in, storage, p.type, value)) return "";
        if (!p.list) continue;
        if (e == face && corners[k] && !(value >= 3 && value < kMaxCorners + 1)) {
          return "face " + std::to_string(i) + " has " + number(value) +
                 " corners (3 to 255 are read)";
        }
        const double length = value >= 1 ? std::min(value, 1e18) : 0;
        for (long n = 0; n < static_cast<long>(length); ++n) {
          if (!readValue(in, storage, p.item_type, value)) return "";
          if (e == face && corners[k] && !(value >= 0 && value < vertices)) {
            return "face " + std::to_string(i) + " refers to vertex " + number(value) + " of " +
                   std::to_string(vertices);
          }
        }
      }
    }
  }
  return "";
}

}  // namespace ply_check

// Open3D reads OBJ through ASSIMP (5.2.5 in Debian 12). Its material-library reader uses the
// current material without checking that there is one: a texture map (map_Kd, bump, ...) or an
// anisotropy before the first newmtl crashes it. It keeps a face of one or two corners as a
// triangle, whose third corner Open3D then reads past the face (a crash when the mesh has
// texture coordinates), and a corner of four indices sends it past the line. objProblem() reads
// the face statements as ASSIMP does and the material libraries it may read for `path` (those
// its mtllib lines name, and <path without "obj">mtl, its fallback); "" when none is such.
namespace obj_check {

bool isLineEnd(char c) { return c == '\n' || c == '\r' || c == '\0' || c == '\f'; }

/// The bytes of a regular file (a device could be endless); false when there is none.
bool readRegularFile(const std::string& path, std::string& text) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;
  std::ifstream in(path, std::ios::binary);
  text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return static_cast<bool>(in) || in.eof();
}

std::string mtlProblem(const std::string& text) {
  const auto starts = [&](const char* bytes, size_t n) {
    return text.compare(0, n, bytes, n) == 0;
  };
  if (starts("\xFE\xFF", 2) || starts("\xFF\xFE", 2)) return "UTF-16 or UTF-32 text";
  size_t line = starts("\xEF\xBB\xBF", 3) ? 3 : 0;  // ASSIMP drops a UTF-8 byte order mark
  while (line < text.size()) {
    size_t end = line;
    while (end < text.size() && !isLineEnd(text[end])) ++end;
    size_t first = line;
    while (first < end && (text[first] == ' ' || text[first] == '\t')) ++first;
    if (first < end && text[first] != '#') {
      if ((text[first] == 'n' || text[first] == 'N') && first + 1 < end && text[first + 1] == 'e') {
        return "";  // newmtl: a current material from here on
      }
      size_t word = first;
      while (word < end && text[word] != ' ' && text[word] != '\t') ++word;
      return "'" + text.substr(first, std::min<size_t>(word - first, 32)) +
             "' before the first newmtl";
    }
    line = end + 1;
  }
  return "";
}

/// The corners ASSIMP's getFace keeps of the face statement `line`; -1 when it fails the import
/// (an index 0), -2 when a corner has more than three indices. `jump`: it has normals and no
/// texture coordinates (a corner's second index is then a normal's).
int assimpCorners(const std::string& line, bool jump) {
  size_t i = 0;
  while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;  // "f"
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
  int corners = 0, part = 0;
  while (i < line.size()) {
    size_t step = 1;
    if (line[i] == '/') {
      ++part;
    } else if (line[i] == ' ' || line[i] == '\t') {
      part = 0;
    } else {
      const int value = static_cast<int>(std::strtol(line.c_str() + i, nullptr, 10));  // atoi
      if (value < 0) ++step;
      for (int rest = value; (rest /= 10) != 0;) ++step;
      if (part == 1 && jump) part = 2;
      if (value == 0) return -1;
      if (part > 2) return -2;
      if (part == 0) ++corners;
    }
    i += step;
  }
  return corners;
}

std::string objProblem(const std::string& path) {
  std::string obj;
  if (!readRegularFile(path, obj)) return "";
  const size_t slash = path.find_last_of("\\/");
  const std::string folder = slash == std::string::npos ? "" : path.substr(0, slash);
  std::vector<std::string> libraries;
  if (path.size() >= 3) libraries.push_back(path.substr(0, path.size() - 3) + "mtl");
  // Lines as ASSIMP's IOStreamBuffer cuts them: a '\' before the line end joins the line with
  // the one after the next '\n', whose first byte is kept whatever it is.
  std::string line;
  bool texture_coordinates = false, normals = false;
  for (size_t i = 0; i < obj.size(); ++i) {
    const size_t start = i;
    line.clear();
    while (i < obj.size()) {
      if (obj[i] == '\\' && i + 1 < obj.size() && isLineEnd(obj[i + 1])) {
        i = std::min(obj.find('\n', i + 1), obj.size()) + 1;
        if (i >= obj.size()) break;
      } else if (isLineEnd(obj[i])) {
        break;
      }
      line += obj[i++];
    }
    for (size_t at = line.find("mtllib"); at != std::string::npos;
         at = line.find("mtllib", at + 6)) {
      size_t begin = at + 6;
      while (begin < line.size() && (line[begin] == ' ' || line[begin] == '\t')) ++begin;
      size_t end = begin;
      while (end < line.size() && !isLineEnd(line[end])) ++end;
      if (end == begin) continue;
      const std::string name = line.substr(begin, end - begin);
      libraries.push_back(folder.empty() ? name : folder + "/" + name);
    }
    if (line.compare(0, 2, "vt") == 0) texture_coordinates = true;
    if (line.compare(0, 2, "vn") == 0) normals = true;
    if (line.empty() || line[0] != 'f') continue;
    const int corners = assimpCorners(line, !texture_coordinates && normals);
    if (corners == -1) break;  // ASSIMP refuses the file here
    const auto where = [&] {   // counted only for the message: the lines are many
      return "line " +
             std::to_string(1 + std::count(obj.begin(),
                                           obj.begin() + static_cast<std::ptrdiff_t>(start),
                                           '\n')) +
             ": ";
    };
    if (corners == -2 || assimpCorners(line, false) == -2 || assimpCorners(line, true) == -2) {
      return where() + "a face corner of more than 3 indices";
    }
    if (corners == 1 || corners == 2) {
      return where() + "a face of " + std::to_string(corners) + " corners";
    }
  }
  for (const std::string& library : libraries) {
    std::string text;
    if (!readRegularFile(library, text)) continue;
    if (const std::string problem = mtlProblem(text); !problem.empty()) {
      return "material library " + library + ": " + problem;
    }
  }
  return "";
}

}  // namespace obj_check

}  // namespace

std::string plyFileProblem(const std::string& path, bool check_faces) {
  return ply_check::plyProblem(path, check_faces);
}

std::string objFileProblem(const std::string& path) { return obj_check::objProblem(path); }

}  // namespace auv::config
