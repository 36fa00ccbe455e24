#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <utility>

#include "internal/intersection_update.h"
#include "strata/exceptions.h"
#include "strata/intersections.h"
#include "test_meshes.h"

namespace strata {
namespace {

using Pair = std::pair<int, int>;
using Tri = std::array<Vec3, 3>;
using test::icosphere;

// Two unconnected triangles (vertices 0-2 and 3-5).
TriMesh two_triangles(const Tri& a, const Tri& b) {
  TriMesh m;
  m.vertices = {a[0], a[1], a[2], b[0], b[1], b[2]};
  m.faces = {{0, 1, 2}, {3, 4, 5}};
  return m;
}

constexpr double kPi = 3.14159265358979323846;

const Tri kBase = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};  // in the plane z = 0

IntersectionResult find(const TriMesh& m, bool parallel = true, std::size_t max_pairs = 0) {
  IntersectionOptions o;
  o.collect_pairs = true;
  o.parallel = parallel;
  o.max_pairs = max_pairs;
  return find_self_intersections(m.vertices, m.faces, o);
}

std::size_t count(const TriMesh& m) {
  return find_self_intersections(m.vertices, m.faces).num_pairs;
}

// The O(n^2) reference: every pair of faces sharing no vertex index, through the same exact predicate.
std::vector<Pair> brute_force_pairs(const TriMesh& m) {
  std::vector<Pair> pairs;
  auto tri = [&](const Face& f) { return Tri{m.vertices[f[0]], m.vertices[f[1]], m.vertices[f[2]]}; };
  for (int i = 0; i < m.num_faces(); ++i)
    for (int j = i + 1; j < m.num_faces(); ++j) {
      const Face& f = m.faces[i];
      const Face& g = m.faces[j];
      bool adjacent = false;
      for (int a : f) adjacent = adjacent || a == g[0] || a == g[1] || a == g[2];
      if (!adjacent && triangles_intersect(tri(f), tri(g))) pairs.emplace_back(i, j);
    }
  return pairs;
}

// Latitude-longitude sphere with 2 * slices * (stacks - 1) triangles (fans at the poles).
TriMesh uv_sphere(int slices, int stacks) {
  TriMesh m;
  m.vertices.emplace_back(0, 0, 1);
  for (int i = 1; i < stacks; ++i) {
    const double theta = kPi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2.0 * kPi * j / slices;
      m.vertices.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
    }
  }
  m.vertices.emplace_back(0, 0, -1);
  const int south = m.num_vertices() - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * slices + (j % slices); };
  for (int j = 0; j < slices; ++j) m.faces.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      m.faces.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.faces.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < slices; ++j) m.faces.push_back({south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
  return m;
}

TriMesh concatenate(const TriMesh& a, const TriMesh& b) {
  TriMesh m = a;
  const int offset = a.num_vertices();
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Face f : b.faces) m.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  return m;
}

TriMesh translated(TriMesh m, const Vec3& d) {
  for (Vec3& p : m.vertices) p += d;
  return m;
}

// Small triangles scattered in the unit cube, each with its own vertices.
TriMesh small_triangle_soup(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> pos(0.0, 1.0), off(-0.15, 0.15);
  TriMesh m;
  for (int i = 0; i < n; ++i) {
    const Vec3 c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) m.vertices.push_back(c + Vec3(off(rng), off(rng), off(rng)));
    m.faces.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  return m;
}

// Large triangles over a shared pool of vertices: dense intersections and many adjacent pairs.
TriMesh shared_vertex_soup(int n, int pool, std::mt19937& rng) {
  std::uniform_real_distribution<double> pos(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, pool - 1);
  TriMesh m;
  for (int i = 0; i < pool; ++i) m.vertices.emplace_back(pos(rng), pos(rng), pos(rng));
  while (m.num_faces() < n) {
    const Face f = {pick(rng), pick(rng), pick(rng)};
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) m.faces.push_back(f);
  }
  return m;
}

// Vertices on an integer lattice: exact touching, coplanar overlaps, collinear (degenerate) faces
// and coincident unwelded vertices all occur often, which is where inexact tests go wrong. Each
// face spans at most `size` lattice steps inside a cube of `extent` steps.
TriMesh lattice_soup(int n, int extent, int size, std::mt19937& rng) {
  std::uniform_int_distribution<int> corner(0, extent - size), step(0, size), coin(0, 3);
  TriMesh m;
  for (int i = 0; i < n; ++i) {
    const Vec3 c(corner(rng), corner(rng), corner(rng));
    Face f;
    for (int k = 0; k < 3; ++k) {
      // Now and then reuse a recent vertex, so that adjacency also occurs.
      if (m.num_vertices() > 0 && coin(rng) == 0) {
        f[k] =
            std::uniform_int_distribution<int>(std::max(0, m.num_vertices() - 6), m.num_vertices() - 1)(rng);
      } else {
        m.vertices.push_back(c + Vec3(step(rng), step(rng), step(rng)));
        f[k] = m.num_vertices() - 1;
      }
    }
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) m.faces.push_back(f);
  }
  return m;
}

void expect_matches_brute_force(const TriMesh& m) {
  const std::vector<Pair> expected = brute_force_pairs(m);
  for (bool parallel : {false, true}) {
    const IntersectionResult r = find(m, parallel);
    EXPECT_EQ(r.num_pairs, expected.size()) << "parallel=" << parallel;
    EXPECT_EQ(r.pairs, expected) << "parallel=" << parallel;
    EXPECT_FALSE(r.truncated);
  }
}

// ---------------------------------------------------------------------------------------------
// Two-triangle cases

TEST(IntersectPair, CrossingTrianglesCountOne) {
  const TriMesh m = two_triangles(kBase, {Vec3(0.25, 0.25, -1), Vec3(0.25, 0.25, 1), Vec3(2, 2, 0)});
  const IntersectionResult r = find(m);
  EXPECT_EQ(r.num_pairs, 1u);
  EXPECT_EQ(r.pairs, (std::vector<Pair>{{0, 1}}));
  EXPECT_EQ(r.faces, (std::vector<int>{0, 1}));
  EXPECT_EQ(count(m), 1u);  // without collect_pairs: count only
  EXPECT_TRUE(find_self_intersections(m.vertices, m.faces).pairs.empty());
}

TEST(IntersectPair, DisjointTrianglesCountZero) {
  Tri above = kBase;
  for (Vec3& p : above) p.z() += 0.5;
  EXPECT_EQ(count(two_triangles(kBase, above)), 0u);
  // Coplanar but apart.
  Tri beside = kBase;
  for (Vec3& p : beside) p.x() += 1.5;
  EXPECT_EQ(count(two_triangles(kBase, beside)), 0u);
  // Boxes overlap, triangles do not: b passes over the hypotenuse of the base triangle.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.6, 0.6, -1), Vec3(0.6, 0.6, 1), Vec3(1, 1, 0)})), 0u);
}

TEST(IntersectPair, TouchingAtAPointCounts) {
  // A vertex of b lies exactly inside the base triangle; the rest of b is above it.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.25, 0.25, 0), Vec3(0.25, 0.25, 1), Vec3(1, 1, 1)})), 1u);
  // Vertex on vertex, at coincident positions but distinct (unwelded) indices.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(1, 0, 0), Vec3(2, 0, 1), Vec3(2, 1, 1)})), 1u);
  // Vertex of b exactly on an edge of the base triangle.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.5, 0.5, 0), Vec3(1, 1, 1), Vec3(1, 1, -1)})), 1u);
}

TEST(IntersectPair, TouchingAlongAnEdgeCounts) {
  // b stands on the base triangle's edge (0,0,0)-(1,0,0), with its own copies of those vertices.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 0, 1)})), 1u);
  // b's edge lies inside the base triangle.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.1, 0.1, 0), Vec3(0.4, 0.1, 0), Vec3(0.2, 0.2, 1)})), 1u);
}

TEST(IntersectPair, CoplanarOverlapCounts) {
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.2, 0.2, 0), Vec3(1.2, 0.2, 0), Vec3(0.2, 1.2, 0)})), 1u);
  // One inside the other.
  EXPECT_EQ(count(two_triangles(kBase, {Vec3(0.1, 0.1, 0), Vec3(0.3, 0.1, 0), Vec3(0.1, 0.3, 0)})), 1u);
}

TEST(IntersectPair, AdjacentFacesAreNeverCounted) {
  TriMesh m;
  // Sharing an edge, folded by 90 degrees.
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.5, 0, 1)};
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  EXPECT_EQ(count(m), 0u);
  // Sharing an edge and folded flat onto each other (coplanar overlap): excluded too.
  m.vertices[3] = Vec3(0.3, 0.3, 0);
  EXPECT_EQ(count(m), 0u);
  // Sharing one vertex only.
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(-1, 0, 0), Vec3(0, -1, 0)};
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(count(m), 0u);
}

TEST(IntersectPair, FoldAroundASharedVertexIsIgnoredByDesign) {
  // b shares vertex 0 with the base triangle and cuts through it: a real intersection that the
  // predicate sees but the count excludes, as documented (only non-adjacent pairs are counted).
  TriMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.4, 0.4, -1), Vec3(0.4, 0.4, 1)};
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_TRUE(triangles_intersect(kBase, {m.vertices[0], m.vertices[3], m.vertices[4]}));
  EXPECT_EQ(count(m), 0u);
}

TEST(IntersectPair, DegenerateFacesAreSkipped) {
  TriMesh m = two_triangles(kBase, {Vec3(0.25, 0.25, -1), Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, 0)});
  EXPECT_EQ(count(m), 0u);  // collinear: zero area, though it pierces the base triangle
  m.faces[1] = {3, 3, 4};   // repeated vertex
  EXPECT_EQ(count(m), 0u);
  EXPECT_FALSE(triangles_intersect(kBase, {Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0)}));
}

TEST(IntersectPair, EmptyAndSingleFace) {
  EXPECT_EQ(count(TriMesh{}), 0u);
  TriMesh one;
  one.vertices = {kBase[0], kBase[1], kBase[2]};
  one.faces = {{0, 1, 2}};
  const IntersectionResult r = find(one);
  EXPECT_EQ(r.num_pairs, 0u);
  EXPECT_EQ(r.num_faces, 1u);
}

TEST(IntersectPair, InvalidInputThrows) {
  TriMesh m = two_triangles(kBase, kBase);
  m.faces[1][2] = 6;
  EXPECT_THROW(find_self_intersections(m.vertices, m.faces), InvalidInput);
  m.faces[1][2] = -1;
  EXPECT_THROW(find_self_intersections(m.vertices, m.faces), InvalidInput);
  m.faces[1][2] = 5;
  m.vertices[4].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(find_self_intersections(m.vertices, m.faces), InvalidInput);
  m.vertices[4].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(find_self_intersections(m.vertices, m.faces), InvalidInput);
  EXPECT_THROW(triangles_intersect(kBase, {m.vertices[3], m.vertices[4], m.vertices[5]}), InvalidInput);
  // An unused vertex may be anything.
  m.faces.pop_back();
  EXPECT_EQ(count(m), 0u);
}

TEST(IntersectPair, HugeCoordinatesStayExact) {
  // Beyond the float range: the outward-rounded boxes must still not prune the touching pair.
  const double s = 1e300;
  Tri a = kBase, b = {Vec3(0.25, 0.25, 0), Vec3(0.25, 0.25, 1), Vec3(1, 1, 1)};
  for (Vec3& p : a) p *= s;
  for (Vec3& p : b) p *= s;
  EXPECT_EQ(count(two_triangles(a, b)), 1u);
  for (Vec3& p : b) p.z() += 1e290;
  EXPECT_EQ(count(two_triangles(a, b)), 0u);
}

// Tiny coordinates, where the pre-filter's projections underflow: a touching pair at 2^-270
// (integer coordinates scaled, so the scaled pair touches exactly) was "proved" apart, while
// triangles_intersect() found it (found by a review, 2026-11-30).
TEST(IntersectPair, TinyCoordinatesStayExact) {
  const Tri a0 = {Vec3(-36, -54, 58), Vec3(25, -30, 1), Vec3(-9, -6, -54)};
  const Tri b0 = {Vec3(-5.5, -42, 29.5), Vec3(41, -50, -18), Vec3(39, -59, 17)};
  ASSERT_TRUE(triangles_intersect(a0, b0));
  for (int e : {-270, -275, -360, -400}) {
    Tri a = a0, b = b0;
    for (Vec3& p : a) p *= std::ldexp(1.0, e);
    for (Vec3& p : b) p *= std::ldexp(1.0, e);
    EXPECT_TRUE(triangles_intersect(a, b)) << e;
    EXPECT_EQ(count(two_triangles(a, b)), 1u) << e;
  }
}

// ---------------------------------------------------------------------------------------------
// Closed meshes and reference tests

TEST(IntersectSphere, ClosedSpheresHaveNoIntersections) {
  const TriMesh ico = icosphere(4);
  ASSERT_EQ(ico.num_faces(), 5120);
  EXPECT_EQ(count(ico), 0u);
  const TriMesh uv = uv_sphere(64, 33);
  ASSERT_EQ(uv.num_faces(), 2 * 64 * 32);
  EXPECT_EQ(count(uv), 0u);
}

TEST(IntersectSphere, OverlappingCopiesMatchBruteForce) {
  const TriMesh a = icosphere(3);
  const TriMesh m = concatenate(a, translated(a, Vec3(0.7, 0.1, 0.05)));
  const std::vector<Pair> expected = brute_force_pairs(m);
  ASSERT_GT(expected.size(), 0u);
  for (bool parallel : {false, true}) {
    const IntersectionResult r = find(m, parallel);
    EXPECT_GT(r.num_pairs, 0u);
    EXPECT_EQ(r.num_pairs, expected.size());
    EXPECT_EQ(r.pairs, expected);
    // Every pair joins the two copies, and all faces of the pairs are listed.
    for (const Pair& p : r.pairs) {
      EXPECT_LT(p.first, a.num_faces());
      EXPECT_GE(p.second, a.num_faces());
      EXPECT_TRUE(std::binary_search(r.faces.begin(), r.faces.end(), p.first));
      EXPECT_TRUE(std::binary_search(r.faces.begin(), r.faces.end(), p.second));
    }
    EXPECT_TRUE(std::is_sorted(r.faces.begin(), r.faces.end()));
    EXPECT_EQ(std::adjacent_find(r.faces.begin(), r.faces.end()), r.faces.end());
  }
}

// A fan around one vertex (a CAD cylinder's cap) with triangles through it and through its hub:
// the search skips the subtrees whose triangles all share a vertex, and finds what brute force
// finds, the pairs at the hub included.
TEST(IntersectFan, AFanAroundOneVertexMatchesBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int k = 1200;
  TriMesh m;
  m.vertices.push_back(Vec3(0, 0, 0));
  for (int i = 0; i < k; ++i) {
    const double a = 2 * M_PI * i / k;
    m.vertices.push_back(Vec3(std::cos(a), std::sin(a), 0.02 * u(rng)));
    m.faces.push_back({0, 1 + i, 1 + (i + 1) % k});
  }
  for (int t = 0; t < 12; ++t) {  // vertical triangles across the fan, some through the hub
    const Vec3 c = t % 3 == 0 ? Vec3::Zero() : Vec3(0.6 * u(rng), 0.6 * u(rng), 0.0);
    const Vec3 d(u(rng), u(rng), 0.0);
    const int b = static_cast<int>(m.vertices.size());
    m.vertices.insert(m.vertices.end(),
                      {c - 0.2 * d + Vec3(0, 0, -0.3), c + 0.2 * d + Vec3(0, 0, -0.3), c + Vec3(0, 0, 0.4)});
    m.faces.push_back({b, b + 1, b + 2});
  }
  const std::vector<Pair> expected = brute_force_pairs(m);
  ASSERT_GT(expected.size(), 12u);
  for (bool parallel : {false, true}) EXPECT_EQ(find(m, parallel).pairs, expected);
}

// One stray face far from a scan (a scanner's outlier) keeps the others' search as tight as
// without it: the float boxes are relative to the faces' median. Relative to the box centre,
// midway to the stray face, every box of the sphere below was a float step (0.06) wide and the
// search made millions of exact tests where it makes thousands.
TEST(IntersectSphere, AStrayFarFaceKeepsTheSearchTight) {
  TriMesh ico = concatenate(icosphere(5), translated(icosphere(5), Vec3(0.7, 0.1, 0.05)));
  for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(-3e6, 1e6, 2e6)}) {
    SCOPED_TRACE("offset " + std::to_string(offset.x()));
    const TriMesh m = translated(ico, offset);
    TriMesh stray = m;
    const int v = static_cast<int>(stray.vertices.size());
    for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)})
      stray.vertices.push_back(p + Vec3(2e6, 0, 0) - offset);
    stray.faces.push_back({v, v + 1, v + 2});
    for (bool parallel : {false, true}) {
      const IntersectionResult without = find(m, parallel), with = find(stray, parallel);
      ASSERT_GT(without.num_pairs, 0u);
      EXPECT_EQ(with.pairs, without.pairs);
      EXPECT_LE(with.num_tests, without.num_tests + 100) << without.num_tests;
      EXPECT_LT(without.num_tests, 100u * without.num_pairs);
    }
  }
}

// Two clusters far apart (two scans in one georeferenced frame): whichever the median falls in,
// the other is far from it, and its faces must keep tight boxes too. The pairs are each
// cluster's own, and the search makes each cluster's tests (at 2e7 with float boxes relative to
// the median: 23.9M exact tests instead of 13.5k).
TEST(IntersectSphere, TwoClustersFarApartKeepTheSearchTight) {
  const TriMesh cluster = concatenate(icosphere(4), translated(icosphere(4), Vec3(0.7, 0.1, 0.05)));
  const IntersectionResult one = find(cluster, false);
  ASSERT_GT(one.num_pairs, 0u);
  const int nf = cluster.num_faces();
  for (double far : {2e4, 2e7, 2e10}) {
    SCOPED_TRACE("far " + std::to_string(far));
    const TriMesh m = concatenate(cluster, translated(cluster, Vec3(far, -0.5 * far, 0.3 * far)));
    std::vector<Pair> expected = one.pairs;
    for (const Pair& p : one.pairs) expected.emplace_back(p.first + nf, p.second + nf);
    for (bool parallel : {false, true}) {
      const IntersectionResult r = find(m, parallel);
      EXPECT_EQ(r.pairs, expected);
      EXPECT_LE(r.num_tests, 2 * one.num_tests + 100);
    }
    // Between the clusters' first spheres and their second ones: the same pairs, as many tests.
    std::vector<Face> a, b;
    for (int f = 0; f < m.num_faces(); ++f) (f % nf < nf / 2 ? a : b).push_back(m.faces[f]);
    IntersectionOptions o;
    o.collect_pairs = true;
    const IntersectionResult r = find_intersections_between(m.vertices, a, b, o);
    EXPECT_EQ(r.num_pairs, expected.size());
    EXPECT_LE(r.num_tests, 2 * one.num_tests + 100);
  }
}

TEST(IntersectReference, RandomSoupsMatchBruteForce) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    expect_matches_brute_force(small_triangle_soup(600, rng));
    expect_matches_brute_force(shared_vertex_soup(300, 120, rng));
    expect_matches_brute_force(lattice_soup(400, 3, 3, rng));   // dense
    expect_matches_brute_force(lattice_soup(800, 12, 2, rng));  // sparse, so the hierarchy prunes
  }
}

// The floating-point pre-filter (a separating axis with a rounding bound) before the exact
// predicates: unwelded coplanar triangles in a tilted plane far from the origin, as a scan's flat
// regions are, touching exactly along their edges (counted) or shrunk about their centroids so that
// gaps of a few units in the last place open (not counted), and sheets lifted off the plane by
// such gaps. The search must agree with the exact brute force pair for pair.
TEST(IntersectReference, NearlyTouchingCoplanarTrianglesMatchBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const Vec3 o = Vec3(uni(rng), uni(rng), uni(rng)) * std::pow(10.0, 3 * trial);
    const Vec3 u = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
    const Vec3 v = u.cross(Vec3(uni(rng), uni(rng), uni(rng))).normalized();
    const Vec3 n = u.cross(v);
    const double scale = std::max(1.0, o.norm());
    const double ulp = std::numeric_limits<double>::epsilon() * scale;
    auto at = [&](double x, double y) { return Vec3(o + 0.01 * scale * (x * u + y * v)); };
    TriMesh m;
    auto add = [&](const Tri& t) {
      const int b = m.num_vertices();
      for (const Vec3& p : t) m.vertices.push_back(p);
      m.faces.push_back({b, b + 1, b + 2});
    };
    std::uniform_int_distribution<int> pick(0, 3);
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j)
        for (int half = 0; half < 2; ++half) {
          Tri t = half == 0 ? Tri{at(i, j), at(i + 1, j), at(i + 1, j + 1)}
                            : Tri{at(i, j), at(i + 1, j + 1), at(i, j + 1)};
          const Vec3 c = (t[0] + t[1] + t[2]) / 3.0;
          switch (pick(rng)) {
            case 0:  // as it is: touches its neighbours exactly (the same rounded vertices)
              break;
            case 1:  // shrunk by a few ulps: gaps at the rounding scale
              for (Vec3& p : t) p = c + (1.0 - 4.0 * std::numeric_limits<double>::epsilon()) * (p - c);
              break;
            case 2:  // lifted off the plane by a few ulps
              for (Vec3& p : t) p += 3.0 * ulp * n;
              break;
            default:  // grown slightly: overlaps its neighbours in the plane
              for (Vec3& p : t) p = c + (1.0 + 1e-9) * (p - c);
              break;
          }
          add(t);
        }
    expect_matches_brute_force(m);
  }
}

TEST(IntersectReference, FaceOrderDoesNotMatter) {
  std::mt19937 rng(7);
  TriMesh m = small_triangle_soup(500, rng);
  const std::size_t n = find(m).num_pairs;
  std::shuffle(m.faces.begin(), m.faces.end(), rng);
  EXPECT_EQ(find(m).num_pairs, n);
}

// ---------------------------------------------------------------------------------------------
// Limits and new intersections

TEST(IntersectLimit, MaxPairsStopsTheSearch) {
  const TriMesh a = icosphere(2);
  const TriMesh m = concatenate(a, translated(a, Vec3(0.5, 0.0, 0.0)));
  const std::vector<Pair> all = brute_force_pairs(m);
  ASSERT_GT(all.size(), 10u);
  for (bool parallel : {false, true}) {
    const IntersectionResult cut = find(m, parallel, 10);
    EXPECT_EQ(cut.num_pairs, 10u);
    EXPECT_TRUE(cut.truncated);
    ASSERT_EQ(cut.pairs.size(), 10u);
    for (const Pair& p : cut.pairs) EXPECT_TRUE(std::binary_search(all.begin(), all.end(), p));

    const IntersectionResult exact = find(m, parallel, all.size());  // exactly at the limit: complete
    EXPECT_EQ(exact.num_pairs, all.size());
    EXPECT_FALSE(exact.truncated);
    EXPECT_EQ(exact.pairs, all);
  }
}

// A strip of n parallel sheared triangle pairs in the plane z = 0: every triangle spans about n
// units in x, so nearly all boxes overlap, but the triangles are disjoint (0 pairs, O(n^2) tests).
TriMesh sheared_strip(int n) {
  TriMesh m;
  for (int i = 0; i <= n; ++i) {
    m.vertices.emplace_back(i, 0.0, 0.0);
    m.vertices.emplace_back(i + n, n, 0.0);
  }
  for (int i = 0; i < n; ++i) {
    m.faces.push_back({2 * i, 2 * i + 2, 2 * i + 3});
    m.faces.push_back({2 * i, 2 * i + 3, 2 * i + 1});
  }
  return m;
}

// Two combs that cross everywhere: n strips along x in the plane z = 0, and n triangles standing
// across them, each crossing the middle half of the strips (about n^2 pairs).
TriMesh crossing_combs(int n) {
  TriMesh m;
  for (int i = 0; i <= n; ++i) {
    m.vertices.emplace_back(0.0, i, 0.0);
    m.vertices.emplace_back(n, i, 0.0);
  }
  for (int i = 0; i < n; ++i) {
    m.faces.push_back({2 * i, 2 * i + 1, 2 * i + 3});
    m.faces.push_back({2 * i, 2 * i + 3, 2 * i + 2});
  }
  for (int j = 0; j < n; ++j) {
    const int k = m.num_vertices();
    m.vertices.emplace_back(j + 0.5, -1.0, -1.0);
    m.vertices.emplace_back(j + 0.5, n + 1.0, -1.0);
    m.vertices.emplace_back(j + 0.6, 0.5 * n, 1.0);
    m.faces.push_back({k, k + 1, k + 2});
  }
  return m;
}

// IntersectionOptions::max_tests: a search that runs out of exact tests stops, says so, and its
// count is a lower bound; with room to spare it is exact. bounded_intersection_options() leaves
// the paper's meshes exact (a few tests a face) and stops the quadratic cases within its budget.
TEST(IntersectLimit, MaxTestsStopsTheSearch) {
  const TriMesh strip = sheared_strip(400);
  const IntersectionResult all = find(strip);
  EXPECT_EQ(all.num_pairs, 0u);
  EXPECT_FALSE(all.truncated);
  EXPECT_GT(all.num_tests, 100000u);  // nearly every pair of the 800 faces' boxes overlaps
  const TriMesh combs = crossing_combs(100);
  const IntersectionResult exact = find(combs);
  ASSERT_GT(exact.num_pairs, 5000u);
  ASSERT_GT(exact.num_tests, 2u * 4096u);  // room for a search cut short after a batch
  // A strip of 24k faces forks the search across threads; whether it is cut short does not
  // depend on them.
  const TriMesh big = sheared_strip(12000);
  for (bool parallel : {false, true}) {
    IntersectionOptions o;
    o.parallel = parallel;
    o.max_tests = 1000000;
    const IntersectionResult r = find_self_intersections(big.vertices, big.faces, o);
    EXPECT_TRUE(r.truncated && r.out_of_tests);
    EXPECT_GE(r.num_tests, o.max_tests);
    EXPECT_LT(r.num_tests, o.max_tests + 4096 * (parallel ? 64 : 1));
  }
  for (bool parallel : {false, true}) {
    IntersectionOptions o;
    o.collect_pairs = true;
    o.parallel = parallel;
    o.max_tests = 20000;
    const IntersectionResult cut = find_self_intersections(strip.vertices, strip.faces, o);
    EXPECT_TRUE(cut.truncated);
    EXPECT_TRUE(cut.out_of_tests);
    EXPECT_EQ(cut.num_pairs, 0u);
    // Batches of 4096 a thread: the search stops within a batch per thread of the limit.
    EXPECT_GE(cut.num_tests, o.max_tests);
    EXPECT_LT(cut.num_tests, o.max_tests + 4096 * (parallel ? 64 : 1));
    // A limit the whole search stays within leaves it exact; one it exceeds by less than a batch
    // still cuts it short (counted after the search), on any number of threads.
    o.max_tests = all.num_tests;
    EXPECT_FALSE(find_self_intersections(strip.vertices, strip.faces, o).truncated);
    o.max_tests = all.num_tests - 1;
    EXPECT_TRUE(find_self_intersections(strip.vertices, strip.faces, o).truncated);
    EXPECT_LT(cut.num_tests, all.num_tests);
    // Cut short among intersecting pairs, the pairs found are real ones.
    o.max_tests = 1;
    const IntersectionResult some = find_self_intersections(combs.vertices, combs.faces, o);
    ASSERT_TRUE(some.truncated);
    ASSERT_GT(some.num_pairs, 0u);  // the first batch of tests finds some
    EXPECT_LE(some.num_pairs, exact.num_pairs);
    EXPECT_EQ(some.pairs.size(), some.num_pairs);
    for (const Pair& p : some.pairs)
      EXPECT_TRUE(std::binary_search(exact.pairs.begin(), exact.pairs.end(), p));
  }
  const TriMesh a = icosphere(4);
  const TriMesh spheres = concatenate(a, translated(a, Vec3(0.5, 0.0, 0.0)));
  IntersectionOptions bounded = bounded_intersection_options(spheres.faces.size());
  bounded.collect_pairs = true;
  const IntersectionResult b = find_self_intersections(spheres.vertices, spheres.faces, bounded);
  EXPECT_FALSE(b.truncated);
  EXPECT_EQ(b.pairs, find(spheres).pairs);
  EXPECT_LT(b.num_tests, spheres.faces.size());
  // The limits the header documents: 50 million + 200 per face tests, 10 million pairs.
  EXPECT_EQ(bounded_intersection_options(0).max_tests, 50000000u);
  EXPECT_EQ(bounded_intersection_options(1000).max_tests, 50200000u);
  EXPECT_EQ(bounded_intersection_options(1000).max_pairs, 10000000u);
}

// count_new_intersections_at_least(): exact for complete results; for an "after" cut short, the
// listed pairs that "before" lacks (at most the exact count); 0 for a "before" cut short.
TEST(IntersectNew, AtLeastIsALowerBound) {
  const TriMesh a = icosphere(2);
  const TriMesh rest = concatenate(a, translated(a, Vec3(3.0, 0.0, 0.0)));  // apart: no pairs
  const TriMesh moved = concatenate(a, translated(a, Vec3(0.5, 0.0, 0.0)));
  const IntersectionResult before = find(rest), after = find(moved);
  ASSERT_EQ(before.num_pairs, 0u);
  ASSERT_GT(after.num_pairs, 20u);
  EXPECT_EQ(count_new_intersections_at_least(before, after), count_new_intersections(before, after));
  const IntersectionResult cut = find(moved, true, 20);
  ASSERT_TRUE(cut.truncated);
  EXPECT_THROW(count_new_intersections(before, cut), InvalidInput);
  EXPECT_EQ(count_new_intersections_at_least(before, cut), 20u);
  EXPECT_EQ(count_new_intersections_at_least(cut, after), 0u);
  EXPECT_EQ(count_new_intersections_at_least(after, after), 0u);
  // A "before" with pairs: only the listed pairs it lacks count, at most the exact number.
  const TriMesh more = concatenate(a, translated(a, Vec3(0.3, 0.0, 0.0)));
  const IntersectionResult more_all = find(more), more_cut = find(more, true, 30);
  ASSERT_TRUE(more_cut.truncated);
  const std::size_t exact = count_new_intersections(after, more_all);
  ASSERT_GT(exact, 0u);
  ASSERT_LT(exact, more_all.num_pairs);  // some pairs are in both
  std::size_t listed_new = 0;
  for (const Pair& p : more_cut.pairs)
    listed_new += !std::binary_search(after.pairs.begin(), after.pairs.end(), p);
  EXPECT_EQ(count_new_intersections_at_least(after, more_cut), listed_new);
  EXPECT_LE(listed_new, exact);
  EXPECT_EQ(count_new_intersections_at_least(after, more_all), exact);
}

// IntersectionOptions::cancel: set, the call throws Cancelled, on one thread and on many;
// cleared, the same options give the full result. (A flag set before the call is caught before
// the hierarchy's build; the polls inside the search, which a flag set midway reaches, have no
// deterministic test: their latency is measured in the engine log, twelfth session.)
TEST(IntersectCancel, ASetFlagStopsTheSearch) {
  const TriMesh a = icosphere(4);
  const TriMesh m = concatenate(a, translated(a, Vec3(0.5, 0.0, 0.0)));
  for (bool parallel : {false, true}) {
    std::atomic<bool> stop{true};
    IntersectionOptions o;
    o.parallel = parallel;
    o.collect_pairs = true;
    o.cancel = &stop;
    EXPECT_THROW(find_self_intersections(m.vertices, m.faces, o), Cancelled);
    stop = false;
    const IntersectionResult r = find_self_intersections(m.vertices, m.faces, o);
    o.cancel = nullptr;
    EXPECT_EQ(r.pairs, find_self_intersections(m.vertices, m.faces, o).pairs);
    EXPECT_GT(r.num_pairs, 0u);
  }
}

TEST(IntersectNew, CountsPairsCreatedByAnEdit) {
  // Face 0 is the base triangle, face 1 crosses it, faces 2 and 3 are away from everything.
  TriMesh m;
  m.vertices = {kBase[0],      kBase[1],      kBase[2],      Vec3(0.25, 0.25, -1), Vec3(0.25, 0.25, 1),
                Vec3(2, 2, 0), Vec3(5, 0, 0), Vec3(6, 0, 0), Vec3(5, 1, 0),        Vec3(5, 0, 3),
                Vec3(6, 0, 3), Vec3(5, 1, 3)};
  m.faces = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}};
  const IntersectionResult before = find(m);
  ASSERT_EQ(before.pairs, (std::vector<Pair>{{0, 1}}));
  EXPECT_EQ(count_new_intersections(before, before), 0u);

  // The edit moves face 2 through the base triangle (in the plane y = 0.6, left of face 1) and
  // face 3 across face 2 above the base: pairs (0,2) and (2,3) are new, (0,1) stays.
  TriMesh edited = m;
  edited.vertices[6] = Vec3(0.1, 0.6, -1);
  edited.vertices[7] = Vec3(0.1, 0.6, 1);
  edited.vertices[8] = Vec3(-1, 0.6, 0);
  edited.vertices[9] = Vec3(-0.5, 0, 0.5);
  edited.vertices[10] = Vec3(-0.5, 1.2, 0.5);
  edited.vertices[11] = Vec3(-0.3, 0.6, 0.5);
  const IntersectionResult after = find(edited);
  ASSERT_EQ(after.pairs, (std::vector<Pair>{{0, 1}, {0, 2}, {2, 3}}));
  EXPECT_EQ(count_new_intersections(before, after), 2u);
  EXPECT_EQ(count_new_intersections(after, before), 0u);  // undoing it only removes pairs

  // Also moving face 1 away removes (0,1): still two new ones, and undoing that edit adds (0,1) back.
  for (int v : {3, 4, 5}) edited.vertices[v].x() += 10;
  const IntersectionResult moved = find(edited);
  ASSERT_EQ(moved.pairs, (std::vector<Pair>{{0, 2}, {2, 3}}));
  EXPECT_EQ(count_new_intersections(before, moved), 2u);
  EXPECT_EQ(count_new_intersections(moved, before), 1u);
}

// internal::update_self_intersections(): after local edits (a patch of vertices pushed through
// the other sphere, or pulled back), the pairs of a search only around the moved faces equal a
// whole search's, edit after edit, each update starting from the last; and it searches less.
TEST(IntersectUpdate, LocalEditsGiveTheWholeSearchsPairs) {
  const TriMesh a = icosphere(4);
  TriMesh m = concatenate(a, translated(a, Vec3(1.3, 0.2, 0.1)));
  IntersectionOptions o;
  o.collect_pairs = true;
  o.parallel = false;
  IntersectionResult last = find_self_intersections(m.vertices, m.faces, o);
  ASSERT_GT(last.num_pairs, 0u);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(m.vertices.size()) - 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int local_searches = 0;
  for (int edit = 0; edit < 24; ++edit) {
    // The vertices within a radius of a random one, moved by a smooth bump (the bigger edits
    // move over a quarter of the faces: the whole search then runs).
    const Vec3 centre = m.vertices[pick(rng)];
    const double radius = edit % 6 == 5 ? 1.2 : 0.15 + 0.05 * (edit % 4);
    const Vec3 push(0.4 * u(rng), 0.4 * u(rng), 0.4 * u(rng));
    std::vector<char> moved(m.vertices.size(), 0);
    for (std::size_t v = 0; v < m.vertices.size(); ++v) {
      const double d = (m.vertices[v] - centre).norm() / radius;
      if (d < 1) m.vertices[v] += (1 - d * d) * push, moved[v] = 1;
    }
    std::vector<int> changed;
    for (int f = 0; f < m.num_faces(); ++f)
      if (moved[m.faces[f][0]] || moved[m.faces[f][1]] || moved[m.faces[f][2]]) changed.push_back(f);
    const IntersectionResult whole = find_self_intersections(m.vertices, m.faces, o);
    const IntersectionResult update =
        strata::internal::update_self_intersections(m.vertices, m.faces, last, changed, o);
    SCOPED_TRACE("edit " + std::to_string(edit) + ", " + std::to_string(changed.size()) + " faces moved");
    ASSERT_EQ(update.pairs, whole.pairs);
    EXPECT_EQ(update.num_pairs, whole.num_pairs);
    EXPECT_EQ(update.faces, whole.faces);
    EXPECT_FALSE(update.truncated);
    EXPECT_EQ(count_new_intersections(last, update), count_new_intersections(last, whole));
    if (4 * changed.size() <= static_cast<std::size_t>(m.num_faces()) && update.num_tests < whole.num_tests)
      ++local_searches;
    last = update;
  }
  EXPECT_GE(local_searches, 12);
  // Nothing moved: the pairs as they were, without a search.
  const IntersectionResult same =
      strata::internal::update_self_intersections(m.vertices, m.faces, last, {}, o);
  EXPECT_EQ(same.pairs, last.pairs);
  EXPECT_EQ(same.num_tests, 0u);
  // A result of another face list is not taken: the whole search runs.
  TriMesh fewer = m;
  fewer.faces.pop_back();
  const IntersectionResult other =
      strata::internal::update_self_intersections(fewer.vertices, fewer.faces, last, {}, o);
  EXPECT_EQ(other.pairs, find_self_intersections(fewer.vertices, fewer.faces, o).pairs);
  EXPECT_THROW(strata::internal::update_self_intersections(m.vertices, m.faces, last, {m.num_faces()}, o),
               InvalidInput);
}

TEST(IntersectNew, RejectsIncomparableResults) {
  const TriMesh a = icosphere(1);
  const TriMesh m = concatenate(a, translated(a, Vec3(0.5, 0, 0)));
  const IntersectionResult r = find(m);
  ASSERT_GT(r.num_pairs, 2u);

  // Counted but not collected.
  const IntersectionResult counted = find_self_intersections(m.vertices, m.faces);
  EXPECT_THROW(count_new_intersections(r, counted), InvalidInput);
  EXPECT_THROW(count_new_intersections(counted, r), InvalidInput);
  // Truncated.
  EXPECT_THROW(count_new_intersections(r, find(m, true, 2)), InvalidInput);
  // Different connectivity: another face list of the same size, and another size.
  TriMesh other = m;
  std::swap(other.faces[0][1], other.faces[0][2]);
  EXPECT_THROW(count_new_intersections(r, find(other)), InvalidInput);
  EXPECT_THROW(count_new_intersections(r, find(a)), InvalidInput);
  // A hand-made result with unsorted pairs is accepted.
  IntersectionResult hand = r;
  std::reverse(hand.pairs.begin(), hand.pairs.end());
  EXPECT_EQ(count_new_intersections(hand, r), 0u);
  hand.pairs.pop_back();
  hand.num_pairs = hand.pairs.size();
  EXPECT_EQ(count_new_intersections(hand, r), 1u);
}

// ---------------------------------------------------------------------------------------------
// find_intersections_between(): the pairs between two face lists over one vertex array

// The O(n m) reference: every pair (a, b) sharing no vertex index, through the same exact predicate.
std::vector<Pair> brute_force_between(const std::vector<Vec3>& v, const std::vector<Face>& a,
                                      const std::vector<Face>& b) {
  std::vector<Pair> pairs;
  auto tri = [&](const Face& f) { return Tri{v[f[0]], v[f[1]], v[f[2]]}; };
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      bool adjacent = false;
      for (int x : a[i]) adjacent = adjacent || x == b[j][0] || x == b[j][1] || x == b[j][2];
      if (!adjacent && triangles_intersect(tri(a[i]), tri(b[j])))
        pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
    }
  return pairs;
}

IntersectionResult between(const std::vector<Vec3>& v, const std::vector<Face>& a, const std::vector<Face>& b,
                           bool parallel = true, std::size_t max_pairs = 0) {
  IntersectionOptions o;
  o.collect_pairs = true;
  o.parallel = parallel;
  o.max_pairs = max_pairs;
  return find_intersections_between(v, a, b, o);
}

// A soup's faces dealt at random into two lists, a few of them into both.
void split_faces(const TriMesh& m, std::mt19937& rng, std::vector<Face>& a, std::vector<Face>& b) {
  std::uniform_int_distribution<int> deal(0, 9);
  for (const Face& f : m.faces) {
    const int d = deal(rng);
    if (d < 5 || d == 9) a.push_back(f);
    if (d >= 5) b.push_back(f);
  }
}

// Against the brute force on soups (shared vertices, exact touching, coplanar and degenerate
// faces), with one thread and with several, and with the lists swapped (the pairs swap too).
TEST(IntersectBetween, RandomSoupsMatchBruteForce) {
  std::mt19937 rng(11);
  const TriMesh soups[] = {small_triangle_soup(600, rng), shared_vertex_soup(300, 120, rng),
                           lattice_soup(400, 3, 3, rng), lattice_soup(800, 12, 2, rng)};
  for (const TriMesh& m : soups) {
    std::vector<Face> a, b;
    split_faces(m, rng, a, b);
    const std::vector<Pair> expected = brute_force_between(m.vertices, a, b);
    ASSERT_FALSE(expected.empty());
    for (bool parallel : {false, true}) {
      const IntersectionResult r = between(m.vertices, a, b, parallel);
      EXPECT_EQ(r.pairs, expected) << "parallel=" << parallel;
      EXPECT_EQ(r.num_pairs, expected.size());
      EXPECT_FALSE(r.truncated);
      EXPECT_EQ(r.num_faces, a.size() + b.size());
      std::vector<int> faces;
      for (const Pair& p : expected) faces.push_back(p.first);
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
      EXPECT_EQ(r.faces, faces);
      std::vector<Pair> swapped;
      for (const Pair& p : between(m.vertices, b, a, parallel).pairs) swapped.emplace_back(p.second, p.first);
      std::sort(swapped.begin(), swapped.end());
      EXPECT_EQ(swapped, expected);
    }
  }
}

// A mesh's pairs are those within each part and those between the parts: the self search of two
// overlapping spheres split into its two spheres' faces.
TEST(IntersectBetween, SelfPairsAreThePartsPairsAndThoseBetween) {
  const TriMesh s = icosphere(3);
  const TriMesh m = concatenate(s, translated(s, Vec3(0.6, 0.1, 0.0)));
  const std::vector<Face> a(m.faces.begin(), m.faces.begin() + s.num_faces());
  const std::vector<Face> b(m.faces.begin() + s.num_faces(), m.faces.end());
  const IntersectionResult whole = find(m);
  const IntersectionResult cross = between(m.vertices, a, b);
  ASSERT_GT(cross.num_pairs, 100u);
  EXPECT_EQ(find_self_intersections(m.vertices, a).num_pairs, 0u);
  std::vector<Pair> mapped;
  for (const Pair& p : cross.pairs) mapped.emplace_back(p.first, p.second + s.num_faces());
  EXPECT_EQ(mapped, whole.pairs);
  // Far apart: nothing between them, and no test made.
  const TriMesh apart = concatenate(s, translated(s, Vec3(5.0, 0.0, 0.0)));
  const std::vector<Face> c(apart.faces.begin() + s.num_faces(), apart.faces.end());
  const IntersectionResult none = between(apart.vertices, a, c);
  EXPECT_EQ(none.num_pairs, 0u);
  EXPECT_EQ(none.num_tests, 0u);
}

TEST(IntersectBetween, LimitsCancelAndBadInput) {
  const TriMesh s = icosphere(2);
  const TriMesh m = concatenate(s, translated(s, Vec3(0.5, 0.0, 0.0)));
  const std::vector<Face> a(m.faces.begin(), m.faces.begin() + s.num_faces());
  const std::vector<Face> b(m.faces.begin() + s.num_faces(), m.faces.end());
  const std::vector<Pair> all = brute_force_between(m.vertices, a, b);
  ASSERT_GT(all.size(), 10u);
  for (bool parallel : {false, true}) {
    const IntersectionResult cut = between(m.vertices, a, b, parallel, 10);
    EXPECT_TRUE(cut.truncated);
    ASSERT_EQ(cut.pairs.size(), 10u);
    for (const Pair& p : cut.pairs) EXPECT_TRUE(std::binary_search(all.begin(), all.end(), p));
    EXPECT_FALSE(between(m.vertices, a, b, parallel, all.size()).truncated);

    // Two halves of a sheared strip: nearly every pair of boxes overlaps, no triangle meets another.
    const TriMesh strip = sheared_strip(2000);
    const std::vector<Face> lo(strip.faces.begin(), strip.faces.begin() + 2000);
    const std::vector<Face> hi(strip.faces.begin() + 2000, strip.faces.end());
    IntersectionOptions o;
    o.parallel = parallel;
    o.max_tests = 100000;
    const IntersectionResult r = find_intersections_between(strip.vertices, lo, hi, o);
    EXPECT_TRUE(r.truncated && r.out_of_tests);
    EXPECT_GE(r.num_tests, o.max_tests);

    std::atomic<bool> stop{true};
    o = IntersectionOptions();
    o.parallel = parallel;
    o.cancel = &stop;
    EXPECT_THROW(find_intersections_between(m.vertices, a, b, o), Cancelled);
    stop = false;
    EXPECT_EQ(find_intersections_between(m.vertices, a, b, o).num_pairs, all.size());
  }
  // Empty lists: nothing to pair.
  EXPECT_EQ(between(m.vertices, {}, b).num_pairs, 0u);
  EXPECT_EQ(between(m.vertices, a, {}).num_pairs, 0u);
  // Out of range indices and non-finite coordinates, in either list, name the list.
  std::vector<Face> bad = b;
  bad.back()[2] = m.num_vertices();
  try {
    between(m.vertices, a, bad);
    ADD_FAILURE() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("second face list"), std::string::npos) << e.what();
  }
  std::vector<Vec3> nan = m.vertices;
  nan[a[0][0]].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(between(nan, a, b), InvalidInput);
  // Results between the same lists compare; one within a list does not.
  TriMesh moved = m;
  for (int i = s.num_vertices(); i < moved.num_vertices(); ++i) moved.vertices[i].x() += 0.4;
  const IntersectionResult before = between(m.vertices, a, b);
  const IntersectionResult after = between(moved.vertices, a, b);
  std::size_t fresh = 0;
  for (const Pair& p : after.pairs) fresh += !std::binary_search(before.pairs.begin(), before.pairs.end(), p);
  EXPECT_EQ(count_new_intersections(before, after), fresh);
  EXPECT_THROW(count_new_intersections(before, find(m)), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// Measurements (printed, never asserted on time)

double seconds_for(const TriMesh& m, bool parallel, std::size_t& pairs) {
  IntersectionOptions o;
  o.parallel = parallel;
  double best = std::numeric_limits<double>::infinity();
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    pairs = find_self_intersections(m.vertices, m.faces, o).num_pairs;
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

void measure(const char* name, const TriMesh& m) {
  std::size_t serial_pairs = 0, parallel_pairs = 0;
  const double serial = seconds_for(m, false, serial_pairs);
  const double parallel = seconds_for(m, true, parallel_pairs);
  std::printf(
      "[ MEASURE  ] %s, %d triangles: %.3f s single thread, %.3f s TBB parallel (best of 3), %zu pairs\n",
      name, m.num_faces(), serial, parallel, parallel_pairs);
  EXPECT_EQ(serial_pairs, parallel_pairs);
}

TEST(IntersectBenchmark, Sphere100k) {
  const TriMesh m = uv_sphere(250, 201);
  ASSERT_EQ(m.num_faces(), 100000);
  measure("UV sphere", m);
  std::size_t pairs = 0;
  seconds_for(m, true, pairs);
  EXPECT_EQ(pairs, 0u);
  const TriMesh ico = icosphere(6);
  measure("icosphere level 6", ico);
}

}  // namespace
}  // namespace strata
