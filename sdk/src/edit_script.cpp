#include "strata/edit_script.h"

#include <Eigen/Geometry>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "internal/blended_map.h"
#include "internal/read_file.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"

namespace strata {
namespace {

using json = nlohmann::json;

// Parsing context: the file name and the JSON path of the value being read, for messages.
struct Ctx {
  const std::string& name;
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InvalidInput(name + ": " + where + ": " + what);
  }
};

void check_keys(const Ctx& c, const std::string& where, const json& j, const std::set<std::string>& allowed) {
  if (!j.is_object()) c.fail(where, "expected an object");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!allowed.count(it.key())) c.fail(where, "unknown key \"" + printable_key(it.key()) + "\"");
}

const json& required(const Ctx& c, const std::string& where, const json& j, const char* key) {
  if (!j.contains(key)) c.fail(where, std::string("missing \"") + key + "\"");
  return j.at(key);
}

double number(const Ctx& c, const std::string& where, const json& j) {
  if (!j.is_number()) c.fail(where, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) c.fail(where, "not a finite number");
  // Positions, pivots and translations beyond the engine's range overflowed the solves into
  // messages that did not name the script.
  if (std::abs(v) > kMaxCoordinate) {
    std::ostringstream s;
    s << v << " is beyond the engine's range (" << kMaxCoordinate << ")";
    c.fail(where, s.str());
  }
  return v;
}

Vec3 vec3(const Ctx& c, const std::string& where, const json& j) {
  if (!j.is_array() || j.size() != 3) c.fail(where, "expected three numbers [x, y, z]");
  return Vec3(number(c, where + "[0]", j[0]), number(c, where + "[1]", j[1]), number(c, where + "[2]", j[2]));
}

Selection selection(const Ctx& c, const std::string& where, const json& j) {
  check_keys(c, where, j, {"sphere", "halfspace", "box", "vertices"});
  if (j.size() != 1) c.fail(where, "expected exactly one of sphere, halfspace, box, vertices");
  const auto it = j.begin();
  const std::string w = where + "." + it.key();
  const json& v = it.value();
  if (it.key() == "sphere") {
    check_keys(c, w, v, {"center", "radius"});
    const double r = number(c, w + ".radius", required(c, w, v, "radius"));
    if (r < 0) c.fail(w + ".radius", "must not be negative");
    return Selection::sphere(vec3(c, w + ".center", required(c, w, v, "center")), r);
  }
  if (it.key() == "halfspace") {
    check_keys(c, w, v, {"point", "normal"});
    const Vec3 n = vec3(c, w + ".normal", required(c, w, v, "normal"));
    if (!(n.cwiseAbs().maxCoeff() > 0))
      c.fail(w + ".normal", "must not be zero");  // norm() underflows at 1e-170
    return Selection::halfspace(vec3(c, w + ".point", required(c, w, v, "point")), n);
  }
  if (it.key() == "box") {
    check_keys(c, w, v, {"min", "max"});
    const Vec3 lo = vec3(c, w + ".min", required(c, w, v, "min"));
    const Vec3 hi = vec3(c, w + ".max", required(c, w, v, "max"));
    if ((lo.array() > hi.array()).any()) c.fail(w, "min exceeds max");
    return Selection::box(lo, hi);
  }
  if (!v.is_array()) c.fail(w, "expected a list of vertex indices");
  std::vector<int> idx;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::string at = w + "[" + std::to_string(k) + "]";
    // The parser keeps non-negative integers unsigned: those above INT_MAX are out of range, the
    // signed ones are negative.
    if (!v[k].is_number_integer() || !v[k].is_number_unsigned())
      c.fail(at, "expected a non-negative vertex index");
    const unsigned long long index = v[k].get<unsigned long long>();
    if (index > 2147483647ULL)
      c.fail(at, "vertex index " + std::to_string(index) + " is out of range (at most 2147483647)");
    idx.push_back(static_cast<int>(index));
  }
  return Selection::vertices(std::move(idx));
}

EditTransform transform(const Ctx& c, const std::string& where, const json& j) {
  check_keys(c, where, j, {"rotate", "scale", "matrix", "translate", "pivot"});
  EditTransform t;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity(), M = Eigen::Matrix3d::Identity(),
                  S = Eigen::Matrix3d::Identity();
  if (j.contains("pivot")) t.pivot = vec3(c, where + ".pivot", j["pivot"]);
  if (j.contains("rotate")) {
    const std::string w = where + ".rotate";
    const json& r = j["rotate"];
    check_keys(c, w, r, {"axis", "degrees", "pivot"});
    const Vec3 axis = vec3(c, w + ".axis", required(c, w, r, "axis"));
    const double largest = axis.cwiseAbs().maxCoeff();  // scaled first, as EditTransform::rotation()
    if (!(largest > 0)) c.fail(w + ".axis", "must not be zero");
    const double deg = number(c, w + ".degrees", required(c, w, r, "degrees"));
    if (r.contains("pivot")) {
      if (j.contains("pivot")) c.fail(w + ".pivot", "give the pivot once (here or in the transform)");
      t.pivot = vec3(c, w + ".pivot", r["pivot"]);
    }
    // Modulo a turn first, as EditTransform::rotation() (exact; 1e20 degrees in radians is not).
    R = Eigen::AngleAxisd(std::fmod(deg, 360.0) * M_PI / 180.0, (axis / largest).normalized())
            .toRotationMatrix();
    t.rotation_axis = (axis / largest).normalized();
    t.rotation_degrees = deg;
  }
  if (j.contains("scale")) {
    const json& s = j["scale"];
    const std::string w = where + ".scale";
    const Vec3 f = s.is_array() ? vec3(c, w, s) : Vec3::Constant(number(c, w, s));
    if (!(f.minCoeff() > 0)) c.fail(w, "scale factors must be positive");
    // A factor of 1e-300 made the map singular (reported as a determinant of 0.000000).
    if (f.minCoeff() < 1e-6 || f.maxCoeff() > 1e6) c.fail(w, "scale factors must be within 1e-6 to 1e6");
    S = f.asDiagonal();
  }
  if (j.contains("matrix")) {
    const json& m = j["matrix"];
    const std::string w = where + ".matrix";
    if (!m.is_array() || m.size() != 3) c.fail(w, "expected three rows of three numbers");
    for (int r = 0; r < 3; ++r) M.row(r) = vec3(c, w + "[" + std::to_string(r) + "]", m[r]).transpose();
    const std::string problem = internal::linear_map_problem(M);
    if (!problem.empty())
      c.fail(w, "must have a positive determinant (no reflection, not singular): it " + problem);
  }
  if (j.contains("translate")) t.translation = vec3(c, where + ".translate", j["translate"]);
  t.linear = R * M * S;
  // Each part may pass and their product still be singular to rounding (a matrix and a scale at
  // opposite extremes).
  const std::string problem = internal::linear_map_problem(t.linear);
  if (!problem.empty()) c.fail(where, "the linear part (rotate * matrix * scale) " + problem);
  return t;
}

EditStep step(const Ctx& c, const std::string& where, const json& j) {
  check_keys(c, where, j, {"region", "handle", "transform"});
  EditStep e;
  e.region = selection(c, where + ".region", required(c, where, j, "region"));
  e.handle = selection(c, where + ".handle", required(c, where, j, "handle"));
  e.transform = transform(c, where + ".transform", required(c, where, j, "transform"));
  return e;
}

}  // namespace

EditScript parse_edit_script(const std::string& text, const std::string& name) {
  const Ctx c{name};
  // The JSON parser stops at a NUL byte and took what came before.
  if (text.find('\0') != std::string::npos)
    throw InvalidInput(name + ": not valid JSON: it holds a NUL byte");
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw InvalidInput(name + ": not valid JSON: " + json_error_text(e.what()));
  }
  // A key given twice in one object: JSON keeps the later value silently (a second "region"
  // won); and the depth and width limits of Strata's JSON. Checked after the parse, so that a
  // file that is not JSON at all is called that (the parse builds a deep value without recursion).
  if (const std::string problem = json_structure_problem(text); !problem.empty())
    throw InvalidInput(name + ": " + problem);
  EditScript script;
  const json* list = &j;
  std::string where = "edits";
  if (j.is_object() && j.contains("edits")) {
    check_keys(c, "top level", j, {"edits"});
    list = &j["edits"];
  } else if (j.is_object()) {
    script.edits.push_back(step(c, "edit", j));
    return script;
  }
  if (!list->is_array()) c.fail(where, "expected an edit object or a list of edits");
  if (list->empty()) c.fail(where, "the list of edits is empty");
  for (std::size_t k = 0; k < list->size(); ++k)
    script.edits.push_back(step(c, where + "[" + std::to_string(k) + "]", (*list)[k]));
  return script;
}

EditScript read_edit_script(const std::string& path) {
  return parse_edit_script(internal::read_whole_file(path), path);
}

}  // namespace strata
