// The files a mesh file names (material libraries, their images, PLY texture images): read from
// beside one mesh, written beside another (mesh_io.h).
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

#include "strata/atomic_file.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/mesh_io.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

// The directory a mesh file's relative names start from ("" for the current one, so that the
// notes name "scan.mtl", not "./scan.mtl").
fs::path directory_of(const std::string& mesh_path) {
  return fs::path(mesh_path).parent_path();
}

// \p name with "." components and "dir/.." pairs resolved (lexically: no file system access),
// '/' between components; a name companion_name_problem() refuses is returned as it is.
std::string normal_name(const std::string& name) {
  if (!companion_name_problem(name).empty()) return name;
  return fs::path(name).lexically_normal().generic_string();
}

bool is_number(const std::string& token) {
  char* end = nullptr;
  std::strtod(token.c_str(), &end);
  return !token.empty() && end == token.c_str() + token.size();
}

// The image file names of an MTL library's texture statements (map_Kd and the others named in
// mesh_io.h), each the rest of its line after the statement's options.
std::vector<std::string> mtl_image_names(const std::string& text) {
  std::vector<std::string> names;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    line = line.substr(0, line.find('#'));
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    // Tokens with where each starts, so that the name keeps its inner spaces.
    std::vector<std::pair<std::string, std::size_t>> tokens;
    for (std::size_t i = 0; i < line.size();) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      const std::size_t start = i;
      while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i > start) tokens.emplace_back(line.substr(start, i - start), start);
    }
    if (tokens.empty()) continue;
    std::string key = tokens[0].first;
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    if (key.rfind("map_", 0) != 0 && key != "bump" && key != "disp" && key != "decal" && key != "refl" &&
        key != "norm")
      continue;
    std::size_t t = 1;
    while (t < tokens.size() && tokens[t].first.size() > 1 && tokens[t].first[0] == '-' &&
           !is_number(tokens[t].first)) {
      const std::string& option = tokens[t++].first;
      // The MTL options with words for arguments; the others (-o, -s, -t, -mm, -bm, -boost,
      // -texres and any unknown one) take numbers.
      static const std::set<std::string> one_word = {"-blendu", "-blendv",  "-cc",
                                                     "-clamp",  "-imfchan", "-type"};
      if (one_word.count(option)) {
        ++t;
      } else {
        while (t + 1 < tokens.size() && is_number(tokens[t].first)) ++t;  // the name may be a number
      }
    }
    if (t < tokens.size()) names.push_back(line.substr(tokens[t].second));
  }
  return names;
}

// Gathers the files of one mesh: each name once, in the order first named.
class CompanionReader {
 public:
  explicit CompanionReader(const std::string& mesh_path) : dir_(directory_of(mesh_path)) {}

  // Reads \p name (relative to the mesh's directory) if it can travel and is there; \p named_by
  // says what names it, for the notes. Returns the file's index in files(), or -1.
  int add(const std::string& given, const std::string& named_by, const std::string& what) {
    const std::string name = normal_name(given);
    const std::string problem = companion_name_problem(name);
    if (!problem.empty()) {
      notes_.push_back(named_by + ": " + what + " '" + printable_key(given) +
                       "' is not carried along: " + problem);
      return -1;
    }
    if (!seen_.insert(name).second) return -1;
    const fs::path path = dir_ / name;
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      notes_.push_back(named_by + ": " + what + " '" + printable_key(given) + "' is not there (" +
                       path.string() + "); it is not carried along");
      return -1;
    }
    files_.push_back({name, read_file_bytes(path.string())});
    return static_cast<int>(files_.size()) - 1;
  }

  std::vector<CompanionFile>& files() { return files_; }
  std::vector<std::string>& notes() { return notes_; }

 private:
  fs::path dir_;
  std::set<std::string> seen_;
  std::vector<CompanionFile> files_;
  std::vector<std::string> notes_;
};

}  // namespace

std::vector<std::string> read_companion_files(MeshAttributes& attributes, const std::string& mesh_path) {
  CompanionReader reader(mesh_path);
  std::istringstream libraries(attributes.material_library);
  std::string library;
  while (libraries >> library) {
    const int i = reader.add(library, mesh_path, "material library");
    if (i < 0) continue;
    // The library's images, relative to its own directory (where Blender and MeshLab look).
    const CompanionFile lib = reader.files()[i];  // a copy: add() grows the list
    const std::string named_by = (directory_of(mesh_path) / lib.name).string();
    for (const std::string& image : mtl_image_names(lib.bytes))
      reader.add((fs::path(lib.name).parent_path() / image).generic_string(), named_by, "texture image");
  }
  for (const std::string& image : attributes.texture_files) reader.add(image, mesh_path, "texture image");
  attributes.files = std::move(reader.files());
  return std::move(reader.notes());
}

std::vector<std::string> write_companion_files(const MeshAttributes& attributes,
                                               const std::string& mesh_path) {
  std::vector<std::string> notes;
  const fs::path dir = directory_of(mesh_path);
  // What the written mesh names: an OBJ its material libraries and their images, a PLY its images.
  std::string ext = fs::path(mesh_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  std::set<std::string> named;
  if (ext == ".obj") {
    std::istringstream libraries(attributes.material_library);
    std::string library;
    while (libraries >> library) {
      const std::string lib = normal_name(library);
      named.insert(lib);
      for (const CompanionFile& f : attributes.files)
        if (f.name == lib)
          for (const std::string& image : mtl_image_names(f.bytes))
            named.insert(normal_name((fs::path(lib).parent_path() / image).generic_string()));
    }
  } else if (ext == ".ply") {
    for (const std::string& image : attributes.texture_files) named.insert(normal_name(image));
  }
  for (const CompanionFile& f : attributes.files) {
    const std::string problem = companion_name_problem(f.name);
    if (!problem.empty())
      throw InvalidInput(mesh_path + ": companion file '" + printable_key(f.name) + "': " + problem);
    if (!named.count(f.name)) continue;
    const fs::path path = dir / f.name;
    std::error_code ec;
    if (fs::exists(path, ec)) {
      if (read_file_bytes(path.string()) != f.bytes)
        notes.push_back(path.string() + " is already there and differs from the scan's file of that name; " +
                        "it was left as it is, and " + mesh_path + " now names it");
      continue;
    }
    ec.clear();
    if (!path.parent_path().empty()) fs::create_directories(path.parent_path(), ec);
    if (ec) throw IoError(path.parent_path().string() + ": cannot create the directory: " + ec.message());
    write_text_file_atomically(path.string(), f.bytes);
  }
  return notes;
}

}  // namespace strata
