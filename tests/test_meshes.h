// Meshes shared by several test suites.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "strata/intersections.h"
#include "strata/mesh.h"
#include "strata/reconstruction.h"
#include "strata/subdiv.h"

namespace strata::test {

// The multigrid preset's polish as it was before its smoothness term (2026-12-03): the tests
// whose folds, retries or local ends were measured on it (with the term those cases no longer
// fold, or their polish no longer reaches a local end).
inline ReconstructOptions without_polish_smoothness(ReconstructOptions o) {
  o.multigrid.polish_smoothness = 0.0;
  o.multigrid.polish_smoothness_decay = 1.0;
  return o;
}

// The multigrid preset as it was before the rest Laplacian (rest offsets, the coarsest level as
// the others, 3 final cycles, no polish smoothness): the tests whose folds or local ends were
// measured on it.
inline ReconstructOptions rest_offset_multigrid_preset() {
  ReconstructOptions o = without_polish_smoothness(multigrid_reconstruct_options());
  o.tangential_regularization = TangentialRegularization::RestOffset;
  o.coarsest_regularization_iterations = 0;
  o.coarsest_max_cycles = 0;
  o.final_max_cycles = 3;
  return o;
}

//! The largest distance between corresponding points of \p a and \p b (same sizes).
inline double max_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d;
}

//! The intersecting pairs of \p faces at \p now that are not at \p rest, counted by how many of
//! their two faces have a vertex that \p part flags: {both, one} (pairs with neither are not
//! counted). An edit's new pairs within its solved part, and between it and the rest.
inline std::pair<long long, long long> new_pairs_by_part(const std::vector<Vec3>& rest,
                                                         const std::vector<Vec3>& now,
                                                         const std::vector<Face>& faces,
                                                         const std::vector<char>& part) {
  IntersectionOptions io;
  io.collect_pairs = true;
  const IntersectionResult before = find_self_intersections(rest, faces, io);
  const IntersectionResult after = find_self_intersections(now, faces, io);
  auto in_part = [&](int j) { return part[faces[j][0]] || part[faces[j][1]] || part[faces[j][2]]; };
  long long both = 0, one = 0;
  for (const auto& pair : after.pairs) {
    if (std::binary_search(before.pairs.begin(), before.pairs.end(), pair)) continue;
    const int k = in_part(pair.first) + in_part(pair.second);
    both += k == 2;
    one += k == 1;
  }
  return {both, one};
}

//! A sphere: the icosahedron subdivided \p levels times (20 * 4^levels faces), its vertices
//! projected onto the sphere of \p radius about \p centre. Outward-oriented.
inline TriMesh icosphere(int levels, double radius = 1.0, const Vec3& centre = Vec3::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : m.vertices) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      const auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return midpoints[key] = m.num_vertices() - 1;
    };
    std::vector<Face> faces;
    for (const Face& f : m.faces) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      faces.insert(faces.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    m.faces = std::move(faces);
  }
  for (Vec3& p : m.vertices) p = centre + radius * p;
  return m;
}

//! Appends \p part to \p m as a separate part (its vertices after m's).
inline void append_mesh(TriMesh& m, const TriMesh& part) {
  const int offset = m.num_vertices();
  m.vertices.insert(m.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (const Face& f : part.faces) m.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
}

//! Appends a regular tetrahedron of edge \p size centred at \p c, outward-oriented.
inline void append_tetrahedron(TriMesh& m, const Vec3& c, double size) {
  const double h = size / (2 * std::sqrt(2.0));
  TriMesh t;
  for (const Vec3& s : {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)})
    t.vertices.push_back(c + h * s);
  t.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  append_mesh(m, t);
}

//! Scan debris: the unit sphere (icosphere(3)) with a tetrahedron of edge 0.04 4% off its surface
//! over each of its 12 icosahedron vertices, over a base (\p base_sphere, e.g. a sphere of
//! radius 0.9) with a tetrahedron of edge 0.02 at each. A sphere vertex under a tetrahedron is
//! about 0.1 from a 0.9 base and about 0.035 from the tetrahedron's. Both meshes have the
//! sphere's vertices and faces first, then each tetrahedron's 4.
struct DebrisScene {
  TriMesh detail, base;
  int sphere_vertices = 0, base_sphere_faces = 0;
};

inline DebrisScene debris_scene(const TriMesh& base_sphere) {
  DebrisScene s;
  s.detail = icosphere(3);
  s.base = base_sphere;
  s.sphere_vertices = s.detail.num_vertices();
  s.base_sphere_faces = s.base.num_faces();
  for (const Vec3& d : icosphere(0).vertices) {
    append_tetrahedron(s.detail, 1.04 * d, 0.04);
    append_tetrahedron(s.base, 1.04 * d, 0.02);
  }
  return s;
}

//! \p m's triangles as a cage (for a Loop surface).
inline PolyMesh triangle_cage(const TriMesh& m) {
  PolyMesh c;
  c.vertices = m.vertices;
  for (const Face& f : m.faces) c.faces.push_back({f[0], f[1], f[2]});
  return c;
}

}  // namespace strata::test
