// The files a mesh file names (material libraries, their images, PLY texture images): read from
// beside one mesh, written beside another (mesh_io.h).
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <functional>
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
// '/' between components: the form of CompanionFile::name.
std::string normal_name(const fs::path& name) {
  return name.lexically_normal().generic_string();
}

std::string lower_extension(const std::string& mesh_path) {
  std::string ext = fs::path(mesh_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool is_number(const std::string& token) {
  char* end = nullptr;
  std::strtod(token.c_str(), &end);
  return !token.empty() && end == token.c_str() + token.size();
}

// An MTL library's texture statements (map_Kd and the others named in mesh_io.h) and its newmtl
// lines: (keyword in lower case, the rest of the line after the statement's options).
std::vector<std::pair<std::string, std::string>> mtl_statements(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> statements;
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
    if (key == "newmtl" && tokens.size() > 1) statements.emplace_back(key, line.substr(tokens[1].second));
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
    if (t < tokens.size()) statements.emplace_back(key, line.substr(tokens[t].second));
  }
  return statements;
}

// The image file names of an MTL library's texture statements.
std::vector<std::string> mtl_image_names(const std::string& text) {
  std::vector<std::string> names;
  for (const auto& [key, name] : mtl_statements(text))
    if (key != "newmtl") names.push_back(name);
  return names;
}

// Whether \p name has a ".." after a directory ("sub/../x.png"): lexically that is "x.png", but
// the file system resolves it only where "sub" exists, which beside an output it need not.
bool has_inner_dotdot(const std::string& name) {
  bool seen_directory = false;
  std::istringstream parts(name);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (part == ".." && seen_directory) return true;
    if (!part.empty() && part != "." && part != "..") seen_directory = true;
  }
  return false;
}

// Whether \p path, followed through symbolic links, lies inside \p dir.
bool inside(const fs::path& path, const fs::path& dir) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  if (ec) return false;
  const fs::path d = fs::weakly_canonical(dir.empty() ? fs::path(".") : dir, ec);
  if (ec) return false;
  const std::string ps = p.generic_string(), ds = d.generic_string();
  return ps.size() > ds.size() && ps.compare(0, ds.size(), ds) == 0 &&
         (ds.back() == '/' || ps[ds.size()] == '/');
}

// Gathers the files of one mesh: each name once, in the order first named.
class CompanionReader {
 public:
  explicit CompanionReader(const std::string& mesh_path) : dir_(directory_of(mesh_path)) {}

  // Reads \p given, a name relative to \p base (a directory relative to the mesh's), if it can
  // travel and is there; \p named_by says what names it, for the notes. Returns the file's index
  // in files(), or -1.
  int add(const fs::path& base, const std::string& given, const std::string& named_by,
          const std::string& what) {
    auto note = [&](const std::string& why) {
      notes_.push_back(named_by + ": " + what + " '" + printable_key(given) +
                       "' is not carried along: " + why);
      return -1;
    };
    if (has_inner_dotdot(given)) return note("it goes into a directory and out again ('dir/..')");
    const std::string name = normal_name(base / given);
    const std::string problem = companion_name_problem(name);
    if (!problem.empty()) return note(problem);
    if (!seen_.insert(name).second) return -1;
    const fs::path path = dir_ / name;
    std::error_code ec;
    if (!fs::exists(path, ec)) return note("it is not there (" + path.string() + ")");
    if (!inside(path, dir_)) return note("it leads out of the mesh file's directory (a symbolic link)");
    try {
      files_.push_back({name, read_file_bytes(path.string())});
    } catch (const IoError& e) {
      return note(e.what());
    }
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

// The material libraries that an OBJ's mtllib names: the whole value if \p is_there says a file
// of that name is (Blender writes "mtllib my scan.mtl" for "my scan.obj"), else its words.
std::vector<std::string> library_names(const std::string& material_library,
                                       const std::function<bool(const std::string&)>& is_there) {
  if (material_library.empty()) return {};
  if (is_there(material_library)) return {material_library};
  std::vector<std::string> names;
  std::istringstream words(material_library);
  for (std::string word; words >> word;) names.push_back(word);
  return names;
}

// The index in attributes.files of the file called \p name (in normal form), or -1.
int file_index(const MeshAttributes& attributes, const fs::path& name) {
  const std::string normal = normal_name(name);
  for (std::size_t i = 0; i < attributes.files.size(); ++i)
    if (attributes.files[i].name == normal) return static_cast<int>(i);
  return -1;
}

// The indices in attributes.files of the material libraries that material_library names.
std::vector<int> libraries_among(const MeshAttributes& attributes) {
  std::vector<int> found;
  for (const std::string& name : library_names(
           attributes.material_library, [&](const std::string& n) { return file_index(attributes, n) >= 0; }))
    if (file_index(attributes, name) >= 0) found.push_back(file_index(attributes, name));
  return found;
}

// The names of attributes.files that a mesh file at \p mesh_path names: an OBJ its libraries and
// their images, a PLY its images.
std::set<std::string> names_in(const MeshAttributes& attributes, const std::string& mesh_path) {
  const std::string ext = lower_extension(mesh_path);
  std::set<std::string> named;
  if (ext == ".obj") {
    for (int i : libraries_among(attributes)) {
      const CompanionFile& lib = attributes.files[i];
      named.insert(lib.name);
      for (const std::string& image : mtl_image_names(lib.bytes()))
        named.insert(normal_name(fs::path(lib.name).parent_path() / image));
    }
  } else if (ext == ".ply") {
    for (const std::string& image : attributes.texture_files) named.insert(normal_name(image));
  }
  return named;
}

}  // namespace

std::vector<std::string> read_companion_files(MeshAttributes& attributes, const std::string& mesh_path) {
  CompanionReader reader(mesh_path);
  const auto is_there = [&](const std::string& name) {
    std::error_code ec;
    return fs::exists(directory_of(mesh_path) / name, ec);
  };
  for (const std::string& library : library_names(attributes.material_library, is_there)) {
    const int i = reader.add("", library, mesh_path, "material library");
    if (i < 0) continue;
    // The library's images, relative to its own directory (where Blender and MeshLab look).
    const CompanionFile lib = reader.files()[i];  // a copy: add() grows the list
    const std::string named_by = (directory_of(mesh_path) / lib.name).string();
    for (const std::string& image : mtl_image_names(lib.bytes()))
      reader.add(fs::path(lib.name).parent_path(), image, named_by, "texture image");
  }
  for (const std::string& image : attributes.texture_files) reader.add("", image, mesh_path, "texture image");
  attributes.files = std::move(reader.files());
  return std::move(reader.notes());
}

std::vector<std::string> write_companion_files(const MeshAttributes& attributes, const std::string& mesh_path,
                                               const CompanionWriter& write) {
  std::vector<std::string> notes;
  const fs::path dir = directory_of(mesh_path);
  const std::set<std::string> named = names_in(attributes, mesh_path);
  for (const CompanionFile& f : attributes.files) {
    const std::string problem = companion_name_problem(f.name);
    if (!problem.empty())
      throw InvalidInput(mesh_path + ": companion file '" + printable_key(f.name) + "': " + problem);
    if (!named.count(f.name)) continue;
    const fs::path path = dir / f.name;
    std::error_code ec;
    const fs::file_status link = fs::symlink_status(path, ec);
    if (fs::exists(link)) {
      // Never replaced: a file there may be the user's own. Compared only where it can be read.
      const fs::file_status target = fs::status(path, ec);
      std::string why;
      if (!fs::is_regular_file(target)) {
        why =
            fs::is_symlink(link) && !fs::exists(target) ? "a symbolic link to nothing" : "not a regular file";
      } else {
        try {
          if (fs::file_size(path, ec) != f.bytes().size() || read_file_bytes(path.string()) != f.bytes())
            why = "a file that differs from the scan's of that name";
        } catch (const IoError& e) {
          why = std::string("a file that cannot be read: ") + e.what();
        }
      }
      if (!why.empty())
        notes.push_back(path.string() + " is already there (" + why + "); it was left as it is, and " +
                        mesh_path + " names it");
      continue;
    }
    // As the reader refuses it: a directory of the name that is a symbolic link out of the mesh's
    // directory (the file was written through it).
    const std::string outside = path.string() + " is not written: it leads out of the directory of " +
                                mesh_path + " (a symbolic link)";
    if (!inside(path, dir)) {
      notes.push_back(outside);
      continue;
    }
    ec.clear();
    if (!path.parent_path().empty()) fs::create_directories(path.parent_path(), ec);
    if (ec) {  // something else is where the directory would go: left as it is too
      notes.push_back(path.string() + " is not written: cannot create the directory " +
                      path.parent_path().string() + " (" + ec.message() + ")");
      continue;
    }
    if (!inside(path, dir)) {  // a link made meanwhile
      notes.push_back(outside);
      continue;
    }
    if (write)
      write(path.string(), f.bytes());
    else
      write_text_file_atomically(path.string(), f.bytes());
  }
  // A library that is neither among the files (written, or a note said why not) nor beside it.
  if (lower_extension(mesh_path) == ".obj") {
    const auto is_there = [&](const std::string& name) {
      std::error_code ec;
      return file_index(attributes, name) >= 0 || fs::exists(dir / name, ec);
    };
    for (const std::string& library : library_names(attributes.material_library, is_there))
      if (!is_there(library))
        notes.push_back(mesh_path + " refers to the material library '" + library +
                        "', which is not in its directory: copy it (and its textures) there");
  }
  return notes;
}

std::vector<int> face_texture_files(const MeshAttributes& attributes) {
  std::vector<int> image_of_texture;  // per texture_files entry
  for (const std::string& name : attributes.texture_files)
    image_of_texture.push_back(file_index(attributes, name));
  std::vector<int> image_of_material(attributes.material_names.size(), -1);
  if (!attributes.face_materials.empty()) {
    // Each material's map_Kd, from the first library that defines the material.
    std::vector<char> defined(attributes.material_names.size(), 0);
    for (int lib : libraries_among(attributes)) {
      const fs::path lib_dir = fs::path(attributes.files[lib].name).parent_path();
      int current = -1;
      for (const auto& [key, name] : mtl_statements(attributes.files[lib].bytes())) {
        if (key == "newmtl") {
          const auto it = std::find(attributes.material_names.begin(), attributes.material_names.end(), name);
          current = it == attributes.material_names.end() || defined[it - attributes.material_names.begin()]
                        ? -1
                        : static_cast<int>(it - attributes.material_names.begin());
          if (current >= 0) defined[current] = 1;
        } else if (key == "map_kd" && current >= 0) {
          image_of_material[current] = file_index(attributes, lib_dir / name);
        }
      }
    }
  }
  std::vector<int> result;
  bool any = false;
  const std::size_t nf = std::max(attributes.face_materials.size(), attributes.face_textures.size());
  for (std::size_t f = 0; f < nf; ++f) {
    int image = -1;
    if (f < attributes.face_textures.size() && attributes.face_textures[f] >= 0 &&
        attributes.face_textures[f] < static_cast<int>(image_of_texture.size()))
      image = image_of_texture[attributes.face_textures[f]];
    if (image < 0 && f < attributes.face_materials.size() && attributes.face_materials[f] >= 0 &&
        attributes.face_materials[f] < static_cast<int>(image_of_material.size()))
      image = image_of_material[attributes.face_materials[f]];
    result.push_back(image);
    any = any || image >= 0;
  }
  if (!any) result.clear();
  return result;
}

MeshAttributes attributes_for_format(const MeshAttributes& attributes, const std::string& mesh_path,
                                     std::vector<std::string>* notes) {
  MeshAttributes a = attributes;
  const std::string ext = lower_extension(mesh_path);
  const bool materials = !a.material_library.empty() || !a.face_materials.empty();
  auto note = [&](const std::string& image, const std::string& why) {
    if (notes)
      notes->push_back(mesh_path + ": texture image '" + printable_key(image) + "' " + why +
                       "; its faces are written without a texture");
  };
  if (ext == ".obj" && !materials && !a.texture_files.empty()) {
    // A PLY's images as an OBJ names them: a library of one material per image. Every material
    // is defined, an image MTL cannot name too (without map_Kd), so that no reader misses one.
    std::string text = "# Materials for " + fs::path(mesh_path).filename().string() +
                       ": one per texture image (written by Strata)\n";
    std::vector<char> named(a.texture_files.size(), 0);
    for (std::size_t i = 0; i < a.texture_files.size(); ++i) {
      std::string image = a.texture_files[i];
      text += "\nnewmtl material_" + std::to_string(i) + "\nKd 1 1 1\n";
      // MTL has no quoting: '#' starts a comment, and a leading '-' an option ("./-x.png" is not).
      if (image.empty() || image.find('#') != std::string::npos) {
        note(image, "cannot be named in a material library (MTL has no quoting for '#')");
        continue;
      }
      if (image.front() == '-') image = "./" + image;
      named[i] = 1;
      text += "map_Kd " + image + "\n";
    }
    // The library's name: the mesh's stem with what an OBJ line or a companion name cannot hold
    // ('#', spaces, control characters, a leading '.') as '_', and "_1", "_2", .. appended while
    // the name is another of the files, or a file beside the mesh with other bytes (a library
    // from an earlier run with the same bytes is the same library).
    std::string stem = fs::path(mesh_path).stem().string();
    for (char& c : stem)
      if (c == '#' || c == ' ' || c == 0x7f || static_cast<unsigned char>(c) < 0x20) c = '_';
    stem.erase(0, stem.find_first_not_of('.'));
    if (stem.empty()) stem = "materials";
    auto taken = [&](const std::string& name) {
      if (file_index(a, name) >= 0) return true;
      const fs::path path = directory_of(mesh_path) / name;
      std::error_code ec;
      if (!fs::exists(fs::symlink_status(path, ec))) return false;
      try {
        return !fs::is_regular_file(path, ec) || fs::file_size(path, ec) != text.size() ||
               read_file_bytes(path.string()) != text;
      } catch (const IoError&) {
        return true;
      }
    };
    std::string library = stem + ".mtl";
    for (std::size_t k = 1; taken(library); ++k) library = stem + "_" + std::to_string(k) + ".mtl";
    a.material_library = library;
    for (std::size_t i = 0; i < a.texture_files.size(); ++i)
      a.material_names.push_back("material_" + std::to_string(i));
    a.face_materials.assign(a.face_textures.size(), -1);
    for (std::size_t f = 0; f < a.face_textures.size(); ++f) {
      const int t = a.face_textures[f];
      if (t >= 0 && t < static_cast<int>(named.size()) && named[t]) a.face_materials[f] = t;
    }
    a.files.emplace_back(library, std::move(text));
    a.texture_files.clear();
    a.face_textures.clear();
  } else if (ext == ".ply" && materials && a.texture_files.empty() && a.face_textures.empty()) {
    // An OBJ's materials' diffuse images as a PLY names them (TextureFile, texnumber), in the
    // order the faces first use them. The materials stay, for attributes_not_stored().
    const std::vector<int> image_of_face = face_texture_files(a);
    std::vector<int> texture_of_file(a.files.size(), -1);
    std::vector<char> noted(a.files.size(), 0);
    for (int file : image_of_face) {
      if (file < 0 || texture_of_file[file] >= 0 || noted[file]) continue;
      const std::string& name = a.files[file].name;
      // A PLY comment line is trimmed when read (check_mesh_attributes() refuses such a name).
      if (name.front() == ' ' || name.back() == ' ') {
        noted[file] = 1;
        note(name, "cannot be named in a PLY (a space at an end of the name)");
        continue;
      }
      texture_of_file[file] = static_cast<int>(a.texture_files.size());
      a.texture_files.push_back(name);
    }
    if (!a.texture_files.empty())
      for (int file : image_of_face) a.face_textures.push_back(file < 0 ? -1 : texture_of_file[file]);
  }
  return a;
}

}  // namespace strata
