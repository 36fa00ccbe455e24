#include "strata/mesh.h"

#include <cmath>
#include <set>
#include <sstream>
#include <utility>

#include "strata/exceptions.h"
#include "strata/json_check.h"

namespace strata {

void check_coordinates(const std::vector<Vec3>& points, const std::string& what) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    if (!p.allFinite())
      throw InvalidInput(what + " vertex " + std::to_string(i) + " has a non-finite coordinate");
    const double m = p.cwiseAbs().maxCoeff();
    if (m > kMaxCoordinate) {
      std::ostringstream s;
      s << what << " vertex " << i << " has a coordinate of magnitude " << m
        << ", beyond the engine's range (" << kMaxCoordinate << ")";
      throw InvalidInput(s.str());
    }
  }
}

void check_mesh_attributes(const MeshAttributes& attributes, const TriMesh& mesh, const std::string& what) {
  const MeshAttributes& a = attributes;
  auto per_vertex = [&](const auto& values, const char* name, const char* plural) {
    if (values.empty()) return;
    if (values.size() != mesh.vertices.size())
      throw InvalidInput(what + ": " + std::to_string(values.size()) + " vertex " + plural + " for " +
                         std::to_string(mesh.vertices.size()) + " vertices");
    for (std::size_t i = 0; i < values.size(); ++i)
      for (double x : values[i])
        if (!std::isfinite(x))
          throw InvalidInput(what + ": vertex " + std::to_string(i) + " has a non-finite " + name);
  };
  per_vertex(a.colors, "colour", "colours");
  per_vertex(a.texcoords, "texture coordinate", "texture coordinates");
  if (!a.colors_have_alpha)
    for (std::size_t i = 0; i < a.colors.size(); ++i)
      if (a.colors[i][3] != 1.0)
        throw InvalidInput(what + ": vertex " + std::to_string(i) + " has alpha " +
                           std::to_string(a.colors[i][3]) +
                           ", but the colours have no alpha channel (colors_have_alpha): it would be lost");
  if (!a.texcoords.empty() && !a.corner_uv_index.empty())
    throw InvalidInput(what + ": texture coordinates both per vertex and per face corner");
  for (std::size_t i = 0; i < a.corner_uv.size(); ++i)
    if (!std::isfinite(a.corner_uv[i][0]) || !std::isfinite(a.corner_uv[i][1]))
      throw InvalidInput(what + ": texture coordinate " + std::to_string(i) + " is not finite");
  // Per face: empty or one entry a face, each an index into a list of \p count, or -1 (none).
  auto per_face = [&](const std::vector<int>& index, std::size_t count, const char* name, const char* list) {
    if (!index.empty() && index.size() != mesh.faces.size())
      throw InvalidInput(what + ": " + std::to_string(index.size()) + " face " + name + "s for " +
                         std::to_string(mesh.faces.size()) + " faces");
    for (std::size_t f = 0; f < index.size(); ++f)
      if (index[f] < -1 || index[f] >= static_cast<long long>(count))
        throw InvalidInput(what + ": face " + std::to_string(f) + "'s " + name + " " +
                           std::to_string(index[f]) + " is out of range (" + std::to_string(count) + " " +
                           list + ")");
  };
  if (!a.corner_uv_index.empty() && a.corner_uv_index.size() != mesh.faces.size())
    throw InvalidInput(what + ": " + std::to_string(a.corner_uv_index.size()) +
                       " faces of texture coordinate indices for " + std::to_string(mesh.faces.size()) +
                       " faces");
  for (std::size_t f = 0; f < a.corner_uv_index.size(); ++f)
    for (int t : a.corner_uv_index[f])
      if (t < 0 || static_cast<std::size_t>(t) >= a.corner_uv.size())
        throw InvalidInput(what + ": face " + std::to_string(f) + "'s texture coordinate index " +
                           std::to_string(t) + " is out of range (" + std::to_string(a.corner_uv.size()) +
                           " texture coordinates)");
  per_face(a.face_materials, a.material_names.size(), "material", "materials");
  per_face(a.face_textures, a.texture_files.size(), "texture", "texture files");
  // Names go into OBJ lines (materials) or PLY comment lines (images), which the readers split at
  // whitespace and trim, and OBJ's cut at '#': what else they hold would not come back as it was.
  auto check_name = [&](const std::string& name, const std::string& which, bool obj) {
    bool ok = !name.empty() && name.front() != ' ' && name.back() != ' ' &&
              (!obj || name.find("  ") == std::string::npos);
    for (char c : name) ok = ok && !(obj && c == '#') && c != 0x7f && static_cast<unsigned char>(c) >= 0x20;
    if (!ok)
      throw InvalidInput(what + ": " + which + " '" + printable_key(name) + "' cannot be written to " +
                         (obj ? "OBJ as it is (empty, or with '#', a control character, or spaces other than "
                                "single ones between words)"
                              : "PLY as it is (empty, a control character, or spaces at an end)"));
  };
  if (!a.material_library.empty()) check_name(a.material_library, "material library", true);
  for (const std::string& n : a.material_names) check_name(n, "material name", true);
  for (const std::string& n : a.texture_files) check_name(n, "texture file", false);
  std::set<std::string> names;
  for (const CompanionFile& f : a.files) {
    const std::string problem = companion_name_problem(f.name);
    if (!problem.empty())
      throw InvalidInput(what + ": companion file '" + printable_key(f.name) + "': " + problem);
    if (!names.insert(f.name).second)
      throw InvalidInput(what + ": companion file '" + printable_key(f.name) + "' is given twice");
  }
}

std::string companion_name_problem(const std::string& name) {
  if (name.empty()) return "the name is empty";
  for (char c : name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "the name holds a control character";
  if (name.front() == '/') return "the name is absolute";
  std::istringstream parts(name);
  std::string part;
  bool first = true;
  while (std::getline(parts, part, '/')) {
    if (part == "..") return first ? "the name leads above the mesh file's directory" : "the name holds '..'";
    if (part.empty() || part == ".") return "the name is not in normal form (an empty or '.' component)";
    if (part.front() == '.') return "the name has a hidden component ('" + part + "')";
    first = false;
  }
  if (name.back() == '/') return "the name ends in '/' (a directory)";
  return "";
}

void check_face_indices(std::size_t num_vertices, const std::vector<Face>& faces, const std::string& what) {
  const long long n = static_cast<long long>(num_vertices);
  for (std::size_t j = 0; j < faces.size(); ++j)
    for (int v : faces[j])
      if (v < 0 || v >= n)
        throw InvalidInput(what + ": face " + std::to_string(j) + " has vertex index " + std::to_string(v) +
                           ", out of range (" + std::to_string(num_vertices) + " vertices)");
}

namespace {
// |v|, with v scaled by a power of two (exact) first, so that its squares neither underflow nor
// overflow: the same bits as v.norm() wherever that does neither.
double scaled_norm(const Vec3& v) {
  const double m = v.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m)) return v.norm();
  int e = 0;
  std::frexp(m, &e);
  // Each component by ldexp(): 2^-e itself overflows for a subnormal m (e below -1022).
  const Vec3 unit(std::ldexp(v.x(), -e), std::ldexp(v.y(), -e), std::ldexp(v.z(), -e));
  return std::ldexp(unit.norm(), e);
}

// The bounding box (lo, hi) of the vertices \p faces use. \pre !faces.empty()
std::pair<Vec3, Vec3> face_box(const std::vector<Vec3>& vertices, const std::vector<Face>& faces) {
  Vec3 lo = vertices[faces[0][0]], hi = lo;
  for (const Face& f : faces)
    for (int v : f) {
      lo = lo.cwiseMin(vertices[v]);
      hi = hi.cwiseMax(vertices[v]);
    }
  return {lo, hi};
}
}  // namespace

double bbox_diagonal(const std::vector<Vec3>& points) {
  if (points.empty()) return 0.0;
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return scaled_norm(hi - lo);
}

void check_extent(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                  const std::string& what) {
  if (faces.empty()) return;
  check_face_indices(vertices.size(), faces, what);
  const auto [lo, hi] = face_box(vertices, faces);
  const double extent = scaled_norm(hi - lo);
  if (extent >= kMinExtent) return;
  std::ostringstream s;
  s << what << " has an extent (bounding box diagonal) of " << extent << ", below the engine's range ("
    << kMinExtent << "): its prism volumes, cubic in it, would underflow";
  throw InvalidInput(s.str());
}

Vec3 bbox_centre(const std::vector<Vec3>& vertices, const std::vector<Face>& faces) {
  if (faces.empty()) return Vec3::Zero();
  check_face_indices(vertices.size(), faces, "bbox_centre");
  const auto [lo, hi] = face_box(vertices, faces);
  return lo / 2.0 + hi / 2.0;  // halves first: no overflow
}

Vec3 coordinate_median(const std::vector<Vec3>& points) {
  if (points.empty()) return Vec3::Zero();
  std::vector<double> x(points.size());
  Vec3 m;
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < points.size(); ++i) x[i] = points[i][k];
    const auto mid = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
    std::nth_element(x.begin(), mid, x.end());
    m[k] = *mid;
  }
  return m;
}

bool back_at_rest(const Vec3& p, const Vec3& rest, double scale) {
  return (p - rest).norm() <= 1e-12 * scale + 1e-14 * rest.cwiseAbs().maxCoeff();
}

std::vector<Vec3> vertex_normals(const std::vector<Vec3>& vertices, const std::vector<Face>& faces) {
  check_face_indices(vertices.size(), faces, "vertex_normals");
  std::vector<Vec3> normals(vertices.size(), Vec3::Zero());
  for (const Face& f : faces) {
    const Vec3 n = triangle_area_normal(vertices[f[0]], vertices[f[1]], vertices[f[2]]);
    const double len = n.norm();
    if (!(len > 0.0)) continue;
    for (int c = 0; c < 3; ++c) {
      const Vec3 e1 = vertices[f[(c + 1) % 3]] - vertices[f[c]];
      const Vec3 e2 = vertices[f[(c + 2) % 3]] - vertices[f[c]];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      normals[f[c]] += angle * (n / len);
    }
  }
  for (Vec3& n : normals) {
    const double len = n.norm();
    n = len > 0.0 ? Vec3(n / len) : Vec3::Zero();
  }
  return normals;
}

double signed_volume(const TriMesh& mesh) {
  check_face_indices(mesh.vertices.size(), mesh.faces, "signed_volume");
  double v = 0.0;
  for (const Face& f : mesh.faces)
    v += mesh.vertices[f[0]].dot(mesh.vertices[f[1]].cross(mesh.vertices[f[2]]));
  return v / 6.0;
}

}  // namespace strata
