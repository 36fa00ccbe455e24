// taubin_smooth(): plain Taubin smoothing against a reference where no face comes near collapse,
// and no face collapsed where uniform weights would flatten one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "strata/mesh.h"
#include "strata/mesh_processing.h"

using namespace strata;

namespace {

double area(const std::vector<Vec3>& x, const Face& f) {
  return 0.5 * (x[f[1]] - x[f[0]]).cross(x[f[2]] - x[f[0]]).norm();
}

// The smallest ratio of a face's area in \p x to its area in the mesh.
double min_area_ratio(const TriMesh& m, const std::vector<Vec3>& x) {
  double r = 1e300;
  for (const Face& f : m.faces) r = std::min(r, area(x, f) / area(m.vertices, f));
  return r;
}

// Taubin's lambda|mu passes as the header states them, written out plainly: uniform weights, a
// boundary vertex averaging its boundary neighbours only. *lowest: min_area_ratio() over the
// passes.
std::vector<Vec3> reference_taubin(const TriMesh& m, int steps, double* lowest = nullptr) {
  const int nv = m.num_vertices();
  std::vector<std::set<int>> nb(nv);
  std::map<std::pair<int, int>, int> edge_faces;
  for (const Face& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      nb[a].insert(b);
      nb[b].insert(a);
      ++edge_faces[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<char> boundary(nv, 0);
  for (const auto& [e, n] : edge_faces)
    if (n == 1) boundary[e.first] = boundary[e.second] = 1;
  std::vector<Vec3> x = m.vertices, next(nv);
  auto pass = [&](double factor) {
    for (int v = 0; v < nv; ++v) {
      Vec3 sum = Vec3::Zero();
      int n = 0;
      for (int w : nb[v])
        if (!boundary[v] || boundary[w]) sum += x[w], ++n;
      next[v] = n > 0 ? Vec3(x[v] + factor * (sum / n - x[v])) : x[v];
    }
    x.swap(next);
    if (lowest) *lowest = std::min(*lowest, min_area_ratio(m, x));
  };
  if (lowest) *lowest = 1.0;
  for (int s = 0; s < steps; ++s) {
    pass(0.5);
    pass(-0.53);
  }
  return x;
}

// Two rows of n + 1 vertices, a unit apart, cut into 2n triangles: every vertex is on the
// boundary, and uniform boundary smoothing flattens the strip onto a line.
TriMesh strip(int n) {
  TriMesh m;
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i, row, 0.0);
  for (int i = 0; i < n; ++i) {
    m.faces.push_back({i, i + 1, n + 2 + i});
    m.faces.push_back({i, n + 2 + i, n + 1 + i});
  }
  return m;
}

}  // namespace

TEST(TaubinSmooth, IsPlainTaubinWhereNoFaceNearsCollapse) {
  // A noisy sphere: 642 vertices, its noise 2% of the radius.
  TriMesh m;
  const int rings = 20, segments = 40;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-0.02, 0.02);
  m.vertices.emplace_back(0, 0, 1);
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double t = M_PI * r / rings, p = 2 * M_PI * s / segments, rad = 1 + noise(rng);
      m.vertices.emplace_back(rad * std::sin(t) * std::cos(p), rad * std::sin(t) * std::sin(p),
                              rad * std::cos(t));
    }
  m.vertices.emplace_back(0, 0, -1);
  const int south = m.num_vertices() - 1;
  auto at = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) {
    m.faces.push_back({0, at(1, s), at(1, s + 1)});
    m.faces.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
    for (int r = 1; r < rings - 1; ++r) {
      m.faces.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.faces.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  }
  for (int steps : {0, 1, 10, 30}) {
    double lowest = 0.0;
    const std::vector<Vec3> x = taubin_smooth(m, steps), ref = reference_taubin(m, steps, &lowest);
    ASSERT_GT(lowest, 0.05) << steps << " steps: the reference nears a collapse";
    ASSERT_EQ(x.size(), ref.size());
    double d = 0.0;
    for (std::size_t v = 0; v < x.size(); ++v) d = std::max(d, (x[v] - ref[v]).norm());
    EXPECT_LE(d, 1e-12) << steps << " steps";
  }
}

TEST(TaubinSmooth, NoFaceOfAStripCollapses) {
  const TriMesh m = strip(4);
  // Plain Taubin flattens the strip (this is what the floor is for) ...
  ASSERT_LT(min_area_ratio(m, reference_taubin(m, 100)), 1e-6);
  // ... taubin_smooth() keeps every face at 1% of its area at least.
  for (int steps : {30, 100, 300}) {
    const std::vector<Vec3> x = taubin_smooth(m, steps);
    EXPECT_GE(min_area_ratio(m, x), 0.01) << steps << " steps";
    // Held, not frozen: the strip's ends are still rounded off.
    double moved = 0.0;
    for (int v = 0; v < m.num_vertices(); ++v) moved = std::max(moved, (x[v] - m.vertices[v]).norm());
    EXPECT_GT(moved, 0.2) << steps << " steps";
  }
  // Above the floor at every pass (the first 5 steps), it is plain Taubin.
  double lowest = 0.0;
  const std::vector<Vec3> ref = reference_taubin(m, 5, &lowest), x = taubin_smooth(m, 5);
  ASSERT_GT(lowest, 0.01);
  for (int v = 0; v < m.num_vertices(); ++v) EXPECT_LE((x[v] - ref[v]).norm(), 1e-12) << "vertex " << v;
}
