#include "strata/cage_io.h"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "internal/read_file.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/mesh_io.h"

namespace strata {
namespace {

using json = nlohmann::json;

[[noreturn]] void fail(const std::string& name, const std::string& where, const std::string& what) {
  throw InvalidInput(name + ": " + where + ": " + what);
}

void only_keys(const std::string& name, const std::string& where, const json& j,
               std::initializer_list<const char*> keys) {
  if (!j.is_object()) fail(name, where, "expected an object");
  for (const auto& [k, v] : j.items()) {
    bool known = false;
    for (const char* a : keys) known = known || k == a;
    if (!known) fail(name, where, "unknown key \"" + printable_key(k) + "\"");
  }
}

int vertex(const std::string& name, const std::string& where, const json& j) {
  if (!j.is_number_integer() || j.get<long long>() < 0 || j.get<long long>() > 2147483647LL)
    fail(name, where, "expected a vertex index (a non-negative integer)");
  return j.get<int>();
}

double sharpness(const std::string& name, const std::string& where, const json& j) {
  if (!j.contains("sharpness")) return 10.0;
  const json& s = j["sharpness"];
  if (!s.is_number() || !std::isfinite(s.get<double>()) || s.get<double>() < 0)
    fail(name, where + ".sharpness", "expected a finite number >= 0");
  return s.get<double>();
}

const json& list(const std::string& name, const json& j, const char* key) {
  static const json empty = json::array();
  if (!j.contains(key)) return empty;
  if (!j[key].is_array()) fail(name, key, "expected a list");
  return j[key];
}

}  // namespace

SubdivTags parse_subdiv_tags(const std::string& text, const std::string& name) {
  // The JSON parser stops at a NUL byte and took what came before (a tags file with one was read).
  if (text.find('\0') != std::string::npos)
    throw InvalidInput(name + ": not valid JSON: it holds a NUL byte");
  // A key twice (the parser kept the last value silently: two "corners" lists gave the second),
  // and depth and width, as for edit scripts.
  const std::string problem = json_structure_problem(text);
  if (!problem.empty()) throw InvalidInput(name + ": " + problem);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw InvalidInput(name + ": not valid JSON: " + json_error_text(e.what()));
  }
  only_keys(name, "top level", j, {"creases", "corners"});
  SubdivTags tags;
  const json& creases = list(name, j, "creases");
  for (std::size_t k = 0; k < creases.size(); ++k) {
    const std::string where = "creases[" + std::to_string(k) + "]";
    const json& c = creases[k];
    only_keys(name, where, c, {"edge", "sharpness"});
    if (!c.contains("edge") || !c["edge"].is_array() || c["edge"].size() != 2)
      fail(name, where + ".edge", "expected two vertex indices");
    tags.creases.push_back({vertex(name, where + ".edge", c["edge"][0]),
                            vertex(name, where + ".edge", c["edge"][1]), sharpness(name, where, c)});
  }
  const json& corners = list(name, j, "corners");
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const std::string where = "corners[" + std::to_string(k) + "]";
    const json& c = corners[k];
    only_keys(name, where, c, {"vertex", "sharpness"});
    if (!c.contains("vertex")) fail(name, where, "missing \"vertex\"");
    tags.corners.push_back({vertex(name, where + ".vertex", c["vertex"]), sharpness(name, where, c)});
  }
  return tags;
}

SubdivTags read_subdiv_tags(const std::string& path) {
  return parse_subdiv_tags(internal::read_whole_file(path), path);
}

// STL keeps neither the vertex numbering that tags name (its vertices are merged in the order
// of their first use) nor double coordinates: a tetrahedron's cage came back renumbered and
// 0.1 as 0.10000000149011612 (a review, thirty-eighth session).
void check_cage_format(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".stl")
    throw IoError(path +
                  ": a cage is not kept in STL (it loses the vertex numbering that tags name, "
                  "and rounds the points to floats); use .obj, .off or .ply");
}

PolyMesh read_cage(const std::string& path) {
  check_cage_format(path);
  PolyMesh cage;
  cage.vertices = read_mesh(path, &cage.faces).vertices;
  check_coordinates(cage.vertices, path + ":");  // named here, not by the edit that uses the cage
  return cage;
}

void write_cage(const PolyMesh& cage, const std::string& path) {
  // What read_cage() refuses is not written (a cage of 1e300 was, and could not be read back).
  check_cage_format(path);
  check_coordinates(cage.vertices, path + ":");
  write_polygon_mesh(cage.vertices, cage.faces, path);
}

}  // namespace strata
