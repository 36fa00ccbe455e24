// The multigrid hierarchy by decimation (internal::build_hierarchy, paper section 4.3): its
// levels must be nested, manifold and of the input's topology, and the prolongation's insertion
// records must be complete, on regular and scan-like triangulations.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <utility>

#include "internal/hierarchy.h"
#include "paper_cases.h"

namespace strata {
namespace {

using internal::Hierarchy;

// Edges (as vertex pairs, lower id first) and the number of faces on each; fails on a directed
// edge used twice (inconsistent orientation) or a degenerate face.
std::map<std::pair<int, int>, int> edge_faces(const std::vector<Face>& faces) {
  std::map<std::pair<int, int>, int> count;
  std::set<std::pair<int, int>> directed;
  for (const Face& f : faces) {
    EXPECT_TRUE(f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
    for (int c = 0; c < 3; ++c) {
      const int a = f[c], b = f[(c + 1) % 3];
      EXPECT_TRUE(directed.emplace(a, b).second) << "directed edge " << a << "-" << b << " twice";
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  }
  return count;
}

std::set<int> boundary_vertices(const std::map<std::pair<int, int>, int>& edges) {
  std::set<int> out;
  for (const auto& [e, n] : edges)
    if (n == 1) out.insert(e.first), out.insert(e.second);
  return out;
}

void check_hierarchy(const TriMesh& mesh, const internal::HierarchyOptions& o) {
  const Hierarchy h = internal::build_hierarchy(mesh.vertices, mesh.faces, o);
  ASSERT_GE(h.levels.size(), 3u);
  ASSERT_LE(static_cast<int>(h.levels.size()), o.max_levels);
  // The finest level is the input, unchanged.
  const Hierarchy::Level& finest = h.levels.back();
  ASSERT_EQ(finest.vertices.size(), mesh.vertices.size());
  for (std::size_t i = 0; i < finest.vertices.size(); ++i) ASSERT_EQ(finest.vertices[i], static_cast<int>(i));
  EXPECT_EQ(finest.faces, mesh.faces);
  EXPECT_TRUE(h.levels.front().inserted.empty());

  const auto input_edges = edge_faces(mesh.faces);
  const std::set<int> input_boundary = boundary_vertices(input_edges);
  const long long euler = static_cast<long long>(mesh.vertices.size()) -
                          static_cast<long long>(input_edges.size()) +
                          static_cast<long long>(mesh.faces.size());
  for (std::size_t l = 0; l < h.levels.size(); ++l) {
    SCOPED_TRACE("level " + std::to_string(l));
    const Hierarchy::Level& L = h.levels[l];
    const std::set<int> verts(L.vertices.begin(), L.vertices.end());
    ASSERT_EQ(verts.size(), L.vertices.size());
    // Manifold (at most two faces an edge), consistently oriented, and of the input's topology.
    const auto edges = edge_faces(L.faces);
    for (const auto& [e, n] : edges) {
      EXPECT_LE(n, 2);
      EXPECT_TRUE(verts.count(e.first) && verts.count(e.second));
    }
    std::set<int> used;
    for (const Face& f : L.faces) used.insert(f.begin(), f.end());
    EXPECT_EQ(used, verts) << "every level vertex is in a face";
    EXPECT_EQ(static_cast<long long>(verts.size()) - static_cast<long long>(edges.size()) +
                  static_cast<long long>(L.faces.size()),
              euler);
    // The boundary stays in place: its vertices are the input's.
    for (int v : boundary_vertices(edges)) EXPECT_TRUE(input_boundary.count(v)) << v;
    if (l == 0) continue;
    // Nested: the coarser level's vertices, then the inserted ones, make this level's; each
    // inserted vertex's ring is made of vertices present when it is inserted.
    const Hierarchy::Level& C = h.levels[l - 1];
    EXPECT_LE(static_cast<double>(C.vertices.size()),
              (o.ratio + 0.05) * static_cast<double>(L.vertices.size()));
    std::set<int> present(C.vertices.begin(), C.vertices.end());
    ASSERT_EQ(L.ring_offsets.size(), L.inserted.size() + 1);
    ASSERT_EQ(L.ring_offsets.back(), static_cast<int>(L.ring_vertices.size()));
    for (std::size_t k = 0; k < L.inserted.size(); ++k) {
      const int v = L.inserted[k];
      EXPECT_TRUE(verts.count(v));
      EXPECT_GE(L.ring_offsets[k + 1] - L.ring_offsets[k], 2) << "vertex " << v;
      for (int t = L.ring_offsets[k]; t < L.ring_offsets[k + 1]; ++t)
        EXPECT_TRUE(present.count(L.ring_vertices[t])) << "vertex " << v << "'s ring";
      EXPECT_TRUE(present.insert(v).second) << "vertex " << v << " inserted twice";
    }
    EXPECT_EQ(present, verts);
  }
  // Deterministic: a second build gives the same hierarchy (nothing depends on addresses or on
  // uninitialized state; whether the ties' order is the intended one is not checked here).
  const Hierarchy again = internal::build_hierarchy(mesh.vertices, mesh.faces, o);
  ASSERT_EQ(again.levels.size(), h.levels.size());
  for (std::size_t l = 0; l < h.levels.size(); ++l) {
    EXPECT_EQ(again.levels[l].vertices, h.levels[l].vertices);
    EXPECT_EQ(again.levels[l].faces, h.levels[l].faces);
    EXPECT_EQ(again.levels[l].inserted, h.levels[l].inserted);
    EXPECT_EQ(again.levels[l].ring_vertices, h.levels[l].ring_vertices);
  }
}

TriMesh tube(double jitter, int triangles) {
  cases::CylinderCaseOptions o;
  o.detail = cases::DetailKind::Bumps;
  o.target_detail_triangles = triangles;
  o.jitter = jitter;
  return cases::make_cylinder_case(o).detail;
}

TEST(Hierarchy, RegularTubeLevelsAreNestedManifoldAndOfTheInputsTopology) {
  internal::HierarchyOptions o;
  o.coarsest_vertices = 100;
  check_hierarchy(tube(0.0, 12000), o);
}

TEST(Hierarchy, ScanLikeTubeLevelsAreNestedManifoldAndOfTheInputsTopology) {
  internal::HierarchyOptions o;
  o.coarsest_vertices = 100;
  check_hierarchy(tube(0.4, 12000), o);
}

// A closed surface (no boundary): the Euler characteristic 2 is kept down to the coarsest level.
TEST(Hierarchy, ClosedSurfaceKeepsItsTopology) {
  // Cap the tube's two boundary loops with a fan each, around a new centre vertex.
  TriMesh m = tube(0.0, 4000);
  const auto edges = edge_faces(m.faces);
  std::map<int, int> next;  // boundary vertex -> the next one along its loop, against the faces
  for (const Face& f : m.faces)
    for (int c = 0; c < 3; ++c) {
      const int a = f[c], b = f[(c + 1) % 3];
      if (edges.at({std::min(a, b), std::max(a, b)}) == 1) next[b] = a;  // the reversed edge
    }
  std::set<int> done;
  for (const auto& [start, unused] : next) {
    if (done.count(start)) continue;
    std::vector<int> loop;
    for (int v = start; !done.count(v); v = next.at(v)) done.insert(v), loop.push_back(v);
    Vec3 centre = Vec3::Zero();
    for (int v : loop) centre += m.vertices[v];
    m.vertices.push_back(centre / static_cast<double>(loop.size()));
    const int c = static_cast<int>(m.vertices.size()) - 1;
    for (int v : loop) m.faces.push_back(Face{v, next.at(v), c});
  }
  const auto closed = edge_faces(m.faces);
  ASSERT_TRUE(boundary_vertices(closed).empty());
  ASSERT_EQ(static_cast<long long>(m.vertices.size()) - static_cast<long long>(closed.size()) +
                static_cast<long long>(m.faces.size()),
            2);  // a sphere
  internal::HierarchyOptions o;
  o.coarsest_vertices = 50;
  check_hierarchy(m, o);
}

}  // namespace
}  // namespace strata
