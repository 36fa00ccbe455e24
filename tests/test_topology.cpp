// The flat adjacency and the cotangent weights (internal/topology.h) against plain references:
// the neighbours as a set per vertex, the weights as a scatter over the faces in order (the
// definition: each corner's half cotangent added to its opposite edge, in both directions). The
// per-vertex gathers, serial or on threads, must give them bit for bit, on a scattered
// numbering, at a non-manifold edge (three faces: the order of its sum matters) and next to a
// zero-area face (no weight).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "internal/topology.h"
#include "paper_cases.h"

using namespace strata;
using internal::Threads;

namespace {

std::vector<double> scatter_reference(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                      const internal::Adjacency& adj, bool normalize) {
  std::map<std::pair<int, int>, double> sum;
  for (const Face& f : faces)
    for (int o = 0; o < 3; ++o) {
      const int a = f[(o + 1) % 3], b = f[(o + 2) % 3];
      const Vec3 ea = x[a] - x[f[o]], eb = x[b] - x[f[o]];
      const double s = ea.cross(eb).norm();
      if (!(s > 0.0)) continue;
      const double cot = 0.5 * ea.dot(eb) / s;
      sum[{a, b}] += cot;
      sum[{b, a}] += cot;
    }
  std::vector<double> w;
  for (int v = 0; v < adj.num_vertices(); ++v) {
    const int b = adj.neighbor_offsets[v], e = adj.neighbor_offsets[v + 1];
    double total = 0.0;
    for (int k = b; k < e; ++k) {
      w.push_back(std::max(sum[{v, adj.neighbors[k]}], 0.0));
      total += w.back();
    }
    if (normalize)
      for (int k = b; k < e; ++k) w[k] = total > 0.0 ? w[k] / total : 1.0 / (e - b);
  }
  return w;
}

// A scan-like cylinder numbered at random, with a non-manifold fan and a zero-area face.
TriMesh awkward_mesh() {
  cases::CylinderCaseOptions o;
  o.target_detail_triangles = 30000;  // above the threaded loops' threshold of vertices
  o.jitter = 0.4;
  TriMesh m = cases::shuffled_numbering(cases::make_cylinder_case(o).detail, 3);
  const Face f0 = m.faces[0];
  const Vec3 p = m.vertices[f0[0]], q = m.vertices[f0[1]];
  // A fan of twelve more faces on the edge (p, q), their apexes at different heights and sides,
  // so that the edge's weight is a sum of thirteen unlike terms, whose order shows in its bits.
  for (int k = 0; k < 12; ++k) {
    const int apex = m.num_vertices();
    const Vec3 e = q - p, side = e.cross(Vec3(0.3, 0.5, 0.8)).normalized() * e.norm();
    const Vec3 up = e.cross(side).normalized() * e.norm();
    // From 0.6 to 37 edge lengths away (the apex's cotangent grows about as the distance): a sum
    // of unlike terms whose rounding depends on its order (summed in reverse, it fails the test).
    const double away = 0.6 * std::pow(10.0, k / 6.0);
    m.vertices.push_back(p + (0.2 + 0.05 * k) * e + away * (k % 3 ? side : up));
    m.faces.push_back(k % 2 ? Face{f0[0], f0[1], apex} : Face{f0[1], f0[0], apex});
  }
  // A zero-area face: a duplicate of the last apex.
  const int n = m.num_vertices();
  m.vertices.push_back(m.vertices[n - 1]);
  m.faces.push_back({f0[0], n, n - 1});
  return m;
}

TEST(Topology, AdjacencyListsEachVertexsNeighboursOnceSorted) {
  const TriMesh m = awkward_mesh();
  const internal::Adjacency a = internal::build_adjacency(m.num_vertices(), m.faces);
  std::vector<std::set<int>> ref(m.num_vertices());
  for (const Face& f : m.faces)
    for (int c = 0; c < 3; ++c) {
      ref[f[c]].insert(f[(c + 1) % 3]);
      ref[f[c]].insert(f[(c + 2) % 3]);
    }
  ASSERT_EQ(a.num_vertices(), m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) {
    const std::vector<int> got(a.neighbors.begin() + a.neighbor_offsets[v],
                               a.neighbors.begin() + a.neighbor_offsets[v + 1]);
    ASSERT_EQ(got, std::vector<int>(ref[v].begin(), ref[v].end())) << "vertex " << v;
    for (int k = a.face_offsets[v]; k < a.face_offsets[v + 1]; ++k) {
      ASSERT_EQ(m.faces[a.faces[k]][a.corners[k]], v);
      if (k > a.face_offsets[v]) {
        ASSERT_LT(a.faces[k - 1], a.faces[k]);  // faces ascending
      }
    }
  }
  tbb::task_arena two(2);
  two.execute([&] {
    const internal::Adjacency b = internal::build_adjacency(m.num_vertices(), m.faces, Threads::Caller);
    EXPECT_EQ(b.face_offsets, a.face_offsets);
    EXPECT_EQ(b.faces, a.faces);
    EXPECT_EQ(b.corners, a.corners);
    EXPECT_EQ(b.neighbor_offsets, a.neighbor_offsets);
    EXPECT_EQ(b.neighbors, a.neighbors);
  });
}

TEST(Topology, CotanWeightsAreTheFaceScatterBitForBit) {
  const TriMesh m = awkward_mesh();
  const internal::Adjacency a = internal::build_adjacency(m.num_vertices(), m.faces);
  const std::vector<double> clamped = scatter_reference(m.vertices, m.faces, a, false);
  const std::vector<double> normalized = scatter_reference(m.vertices, m.faces, a, true);
  EXPECT_EQ(internal::clamped_cotan_weights(m.vertices, m.faces, a), clamped);
  EXPECT_EQ(internal::normalized_cotan_weights(m.vertices, m.faces, a), normalized);
  tbb::task_arena two(2);
  two.execute([&] {
    EXPECT_EQ(internal::clamped_cotan_weights(m.vertices, m.faces, a, Threads::Caller), clamped);
    EXPECT_EQ(internal::normalized_cotan_weights(m.vertices, m.faces, a, Threads::Caller), normalized);
  });
  // The weights are real ones: positive on most edges, and each vertex's sum to 1.
  const auto positive = std::count_if(clamped.begin(), clamped.end(), [](double w) { return w > 0; });
  EXPECT_GT(positive, 0.9 * static_cast<double>(clamped.size()));
  for (int v = 0; v < a.num_vertices(); ++v) {
    double s = 0.0;
    for (int k = a.neighbor_offsets[v]; k < a.neighbor_offsets[v + 1]; ++k) s += normalized[k];
    EXPECT_NEAR(s, 1.0, 1e-12) << "vertex " << v;
  }
}

}  // namespace
