// taubin_smooth(): plain Taubin smoothing against a reference where no face comes near collapse,
// and no face collapsed where uniform weights would flatten one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "strata/cage_fit.h"
#include "strata/exceptions.h"
#include "strata/layers/model.h"
#include "strata/mesh.h"
#include "strata/mesh_io.h"
#include "strata/mesh_processing.h"
#include "test_files.h"
#include "test_meshes.h"

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
// boundary vertex averaging its neighbours along boundary edges only. *lowest: min_area_ratio() over the
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
  auto boundary_edge = [&](int a, int b) { return edge_faces.at({std::min(a, b), std::max(a, b)}) == 1; };
  std::vector<Vec3> x = m.vertices, next(nv);
  auto pass = [&](double factor) {
    for (int v = 0; v < nv; ++v) {
      Vec3 sum = Vec3::Zero();
      int n = 0;
      for (int w : nb[v])
        if (!boundary[v] || boundary_edge(v, w)) sum += x[w], ++n;
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
// boundary. strip(1), a square of two triangles, is a boundary 4-cycle, which Taubin's passes
// shrink to a point (its lowest frequency is above their pass band).
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

// Coincident vertices become one, numbered in order of first use (-0 as +0); a face whose
// corners join is dropped.
TEST(WeldVertices, JoinsEqualPositionsInOrderOfFirstUse) {
  TriMesh m;
  m.vertices = {Vec3(0, 0, 0),    Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0),
                Vec3(-0.0, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 0)};
  m.faces = {{0, 1, 2}, {3, 5, 4}, {3, 5, 6}};
  const TriMesh w = weld_vertices(m);
  EXPECT_EQ(w.vertices, (std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)}));
  EXPECT_EQ(w.faces, (std::vector<Face>{{0, 1, 2}, {1, 3, 2}}));
  // A face index out of range is refused by name (it was read out of bounds; a review).
  for (const int bad : {7, -1}) {
    TriMesh b = m;
    b.faces[1][2] = bad;
    try {
      weld_vertices(b);
      FAIL() << "no exception for index " << bad;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("weld_vertices: face 1"), std::string::npos) << e.what();
    }
  }
}

TEST(TaubinSmooth, NoFaceOfAStripCollapses) {
  const TriMesh m = strip(1);
  // Plain Taubin collapses the square (this is what the floor is for) ...
  ASSERT_LT(min_area_ratio(m, reference_taubin(m, 100)), 1e-6);
  // ... taubin_smooth() keeps every face at 1% of its area at least.
  for (int steps : {30, 100, 300}) {
    const std::vector<Vec3> x = taubin_smooth(m, steps);
    EXPECT_GE(min_area_ratio(m, x), 0.01) << steps << " steps";
    // Held, not frozen: the strip's ends are still rounded off.
    double moved = 0.0;
    for (int v = 0; v < m.num_vertices(); ++v) moved = std::max(moved, (x[v] - m.vertices[v]).norm());
    EXPECT_GT(moved, 0.2) << steps << " steps";
    // Nor grown: with the floor per pass, the expanding passes went on where the shrinking ones
    // were held, and the square was 231 across after 100 steps (a review).
    EXPECT_LE(bbox_diagonal(x), bbox_diagonal(m.vertices)) << steps << " steps";
  }
  // Its faces' own scales: beside an unreferenced vertex at 1e100 or a triangle at 1e170 (the
  // mesh's extent), the square's areas in the mesh's scale underflowed to 0 and the floor never
  // fired (it was smoothed to a point).
  for (const double far : {1e100, 1e170}) {
    TriMesh with = m;
    with.vertices.push_back(Vec3(far, 0, 0));
    const std::vector<Vec3> lone = taubin_smooth(with, 100);
    EXPECT_GE(min_area_ratio(m, {lone.begin(), lone.begin() + m.num_vertices()}), 0.01) << far;
    with.vertices.push_back(Vec3(far, 1e155, 0));
    with.vertices.push_back(Vec3(far, 0, 1e155));
    with.faces.push_back({m.num_vertices(), m.num_vertices() + 1, m.num_vertices() + 2});
    const std::vector<Vec3> part = taubin_smooth(with, 100);
    EXPECT_GE(min_area_ratio(m, {part.begin(), part.begin() + m.num_vertices()}), 0.01) << far;
  }
  // Scaled by a power of two, the same (exactly, scaled): the floor held at 2^+-530 too, where
  // the areas' cross products overflowed to inf or underflowed to 0 and it never fired.
  const std::vector<Vec3> unit = taubin_smooth(m, 100);
  for (int e : {530, -530}) {
    TriMesh scaled = m;
    for (Vec3& v : scaled.vertices) v *= std::ldexp(1.0, e);
    const std::vector<Vec3> xs = taubin_smooth(scaled, 100);
    for (int v = 0; v < m.num_vertices(); ++v)
      EXPECT_EQ(xs[v], Vec3(std::ldexp(1.0, e) * unit[v])) << "2^" << e << ", vertex " << v;
  }
  // Near the largest doubles the neighbour sums overflowed (a 100-face sphere of radius 4.5e307
  // came out all inf and NaN; a review): scaled by 2^1022 a sphere is smoothed as at radius 1,
  // scaled, exactly.
  const TriMesh sphere = test::icosphere(2);
  const std::vector<Vec3> small = taubin_smooth(sphere, 3);
  TriMesh huge = sphere;
  for (Vec3& v : huge.vertices) v *= std::ldexp(1.0, 1022);
  const std::vector<Vec3> big = taubin_smooth(huge, 3);
  for (int v = 0; v < sphere.num_vertices(); ++v)
    ASSERT_EQ(big[v], Vec3(std::ldexp(1.0, 1022) * small[v])) << "vertex " << v;
  // Above the floor at every pass (the first 5 steps), it is plain Taubin.
  double lowest = 0.0;
  const std::vector<Vec3> ref = reference_taubin(m, 5, &lowest), x = taubin_smooth(m, 5);
  ASSERT_GT(lowest, 0.01);
  for (int v = 0; v < m.num_vertices(); ++v) EXPECT_LE((x[v] - ref[v]).norm(), 1e-12) << "vertex " << v;
}

// A boundary vertex follows its boundary edges only: a fan over a 16-gon, whose chords join
// vertex 0 to every other vertex (all on the boundary), keeps the polygon round (vertex 0 was
// pulled to radius 0.21 of 1 in 10 steps, the far vertex to 0.49).
TEST(TaubinSmooth, ChordsBetweenBoundaryVerticesDoNotPullTheRimIn) {
  TriMesh m;
  const int n = 16;
  for (int i = 0; i < n; ++i)
    m.vertices.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), 0.0);
  for (int i = 1; i + 1 < n; ++i) m.faces.push_back({0, i, i + 1});
  const std::vector<Vec3> x = taubin_smooth(m, 10), ref = reference_taubin(m, 10);
  for (int v = 0; v < n; ++v) {
    EXPECT_GT(x[v].norm(), 0.9) << "vertex " << v;
    EXPECT_LE((x[v] - ref[v]).norm(), 1e-12) << "vertex " << v;
  }
}

// A sphere with a random third of its faces flipped: orient_faces() flips them back (the side
// that flips fewer faces), and the mesh passes validation again. A part already consistent is
// left alone, inside out (all faces flipped) or the inward inner shell of a cavity.
TEST(OrientFaces, APartTakesTheSideThatFlipsFewerFaces) {
  const TriMesh sphere = test::icosphere(3);
  TriMesh m = sphere;
  std::mt19937 rng(3);
  int shuffled = 0;
  for (Face& f : m.faces)
    if (rng() % 3 == 0) std::swap(f[1], f[2]), ++shuffled;
  ASSERT_LT(2 * shuffled, m.num_faces());
  EXPECT_THROW(validate_mesh(m, "shuffled"), InvalidInput);
  EXPECT_EQ(orient_faces(m), shuffled);
  EXPECT_EQ(m.faces, sphere.faces);
  // The same with face 0 among the flipped ones: the majority, not face 0, decides.
  TriMesh first = sphere;
  for (int f = 0; f < first.num_faces(); f += 4) std::swap(first.faces[f][1], first.faces[f][2]);
  EXPECT_EQ(orient_faces(first), (first.num_faces() + 3) / 4);
  EXPECT_EQ(first.faces, sphere.faces);
  TriMesh inside_out = sphere;
  for (Face& f : inside_out.faces) std::swap(f[1], f[2]);
  const std::vector<Face> kept = inside_out.faces;
  EXPECT_EQ(orient_faces(inside_out), 0);
  EXPECT_EQ(inside_out.faces, kept);
  // A solid with a cavity: the outer shell outwards, the inner one inwards; valid, and unchanged.
  TriMesh cavity = test::icosphere(2, 2.0);
  const TriMesh inner = test::icosphere(2, 1.0);
  const int offset = cavity.num_vertices();
  for (const Vec3& p : inner.vertices) cavity.vertices.push_back(p);
  for (Face f : inner.faces) cavity.faces.push_back({f[0] + offset, f[2] + offset, f[1] + offset});
  validate_mesh(cavity, "cavity");
  const std::vector<Face> before = cavity.faces;
  EXPECT_EQ(orient_faces(cavity), 0);
  EXPECT_EQ(cavity.faces, before);
}

// An open part: the few faces against the rest are flipped, whichever face comes first (face 0
// among them); a second part, consistent, is left alone; a face with a repeated corner or an
// index out of range joins nothing and is left for the validation.
TEST(OrientFaces, OpenPartsFollowTheirMajority) {
  TriMesh m = strip(6);
  const std::vector<Face> faces = m.faces;
  TriMesh other = strip(3);
  const int offset = m.num_vertices();
  for (Vec3 p : other.vertices) m.vertices.push_back(p + Vec3(0, 0, 5));
  for (Face f : other.faces) {
    for (int& v : f) v += offset;
    std::swap(f[1], f[2]);  // the second strip all the other way: consistent, left so
    m.faces.push_back(f);
  }
  std::swap(m.faces[0][1], m.faces[0][2]);  // two faces of the first strip against the rest
  std::swap(m.faces[7][1], m.faces[7][2]);
  m.faces.push_back({0, 0, 1});
  m.faces.push_back({0, 1, 1000});
  const TriMesh before = m;
  EXPECT_EQ(orient_faces(m), 2);
  for (int f = 0; f < 12; ++f) EXPECT_EQ(m.faces[f], faces[f]) << f;
  for (int f = 12; f < m.num_faces(); ++f) EXPECT_EQ(m.faces[f], before.faces[f]) << f;
}

// A Moebius strip cannot be oriented: an error naming an edge, the mesh unchanged.
TEST(OrientFaces, AMoebiusStripIsRefused) {
  TriMesh m;
  const int n = 12;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    for (int side : {-1, 1}) {
      const double w = 0.3 * side;
      m.vertices.emplace_back((1 + w * std::cos(t / 2)) * std::cos(t),
                              (1 + w * std::cos(t / 2)) * std::sin(t), w * std::sin(t / 2));
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i, b = 2 * i + 1;
    // The last quad joins the first with its sides swapped: the half twist.
    const int c = i + 1 < n ? 2 * (i + 1) : 1, d = i + 1 < n ? 2 * (i + 1) + 1 : 0;
    m.faces.push_back({a, c, d});
    m.faces.push_back({a, d, b});
  }
  const TriMesh before = m;
  try {
    orient_faces(m);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("is not orientable (a Moebius strip)"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(m.faces, before.faces);
}

// Two tetrahedra touching at vertex 3 only: every edge has two faces, but the faces around
// vertex 3 form two fans, which OpenMesh cannot hold (its add_face dropped a face of them, with
// only a line on stderr, and a cage fit went on with the rest).
namespace {
TriMesh bowtie() {
  TriMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {0, 0, 2}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {3, 5, 4}, {3, 4, 6}, {3, 6, 5}, {4, 5, 6}};
  return m;
}
}  // namespace

// A vertex where two sheets touch (common in scans): OpenMesh's add_face refused the second
// sheet's faces there, with a line on stderr, and the decimation ran on what was left (a bowtie's
// fitted cage had 5 faces and a hole). The vertex is split, one copy per fan: every face is kept.
TEST(DecimateMesh, ANonManifoldVertexIsSplitAndNoFaceIsLost) {
  // Edges of one face only.
  auto open_edges = [](const auto& faces) {
    std::map<std::pair<int, int>, int> count;
    for (const auto& f : faces)
      for (std::size_t c = 0; c < f.size(); ++c) {
        const int a = f[c], b = f[(c + 1) % f.size()];
        ++count[{std::min(a, b), std::max(a, b)}];
      }
    int open = 0;
    for (const auto& [edge, n] : count) open += n == 1;
    return open;
  };
  const TriMesh m = bowtie();
  EXPECT_NO_THROW(validate_mesh(m, "bowtie"));  // the core has no use for manifold vertices
  ::testing::internal::CaptureStderr();
  const TriMesh d = decimate_mesh(m, 8);
  EXPECT_EQ(d.num_faces(), 8);
  EXPECT_EQ(d.num_vertices(), 8);  // vertex 3 twice
  EXPECT_NO_THROW(validate_mesh(d, "decimated"));
  EXPECT_EQ(open_edges(d.faces), 0);
  // The cage fitted to it and a model built on it: closed, both tetrahedra there.
  CageFitOptions cage;
  cage.faces = 4;
  const CageFit fit = fit_cage(m, cage);
  EXPECT_GE(fit.cage.num_faces(), 8);
  EXPECT_EQ(open_edges(fit.cage.faces), 0);
  layers::BuildOptions build;
  build.bands = 2;
  build.cage = cage;
  const layers::LayeredModel model = layers::LayeredModel::build(m, build);
  EXPECT_GE(model.band(0).cage.num_faces(), 8);
  EXPECT_EQ(open_edges(model.band(0).cage.faces), 0);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

// Scan debris: a sphere of 1,280 faces with 40 tetrahedra beside it, decimated to 200 faces.
// Decimated together, the tetrahedra (which cannot go below their 4 faces) kept 160 of the 200 and
// the sphere got the other 40; each small part is now decimated alone, and the sphere gets the
// whole target. A part that does get a share decimates with the largest as before.
TEST(DecimateMesh, SmallPartsDoNotTakeTheRestsFaces) {
  TriMesh m = test::icosphere(3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int debris = 40;
  for (int t = 0; t < debris; ++t) {
    const Vec3 c = 1.5 * Vec3(u(rng), u(rng), u(rng)).normalized();
    test::append_tetrahedron(m, c, 0.01);
  }
  const TriMesh d = decimate_mesh(m, 200);
  EXPECT_NO_THROW(validate_mesh(d, "decimated"));
  // Faces on the sphere (corners within 0.2 of the unit sphere) and on the tetrahedra (1.5 away).
  int on_sphere = 0, on_debris = 0;
  for (const Face& f : d.faces) {
    const double r = (d.vertices[f[0]] + d.vertices[f[1]] + d.vertices[f[2]]).norm() / 3;
    on_sphere += std::abs(r - 1.0) < 0.2;
    on_debris += std::abs(r - 1.5) < 0.05;
  }
  EXPECT_EQ(on_sphere + on_debris, d.num_faces());
  EXPECT_EQ(on_debris, 4 * debris);
  EXPECT_GE(on_sphere, 196);
  EXPECT_LE(on_sphere, 200);
  // The sphere's faces first, then the tetrahedra's, each as it was: the same corners in the same
  // order (a review: a check of the distance alone passed with every tetrahedron turned inside out).
  const int input_sphere_faces = test::icosphere(3).num_faces();
  for (int j = 0; j < 4 * debris; ++j)
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(d.vertices[d.faces[on_sphere + j][c]], m.vertices[m.faces[input_sphere_faces + j][c]])
          << "tetrahedron face " << j << " corner " << c;
  // A second sphere of a quarter of the faces (half the radius) gets a share: the two decimate
  // together, as before.
  TriMesh two = test::icosphere(3);
  test::append_mesh(two, test::icosphere(2, 0.5, Vec3(3, 0, 0)));
  const TriMesh both = decimate_mesh(two, 200);
  EXPECT_LE(both.num_faces(), 200);
  EXPECT_GE(both.num_faces(), 196);
}

namespace {
// Appends a fan of \p n faces about \p c (radius 0.01, in a plane through c), an open part.
void append_fan(TriMesh& m, const Vec3& c, int n) {
  const int b = m.num_vertices();
  m.vertices.push_back(c);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    m.vertices.push_back(c + 0.01 * Vec3(std::cos(a), std::sin(a), 0.0));
  }
  for (int k = 0; k < n; ++k) m.faces.push_back({b, b + 1 + k, b + 1 + (k + 1) % n});
}

// An n x n grid of squares, two faces each, at height z (2 n^2 faces).
TriMesh grid(int n, double z) {
  TriMesh m;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.vertices.push_back(Vec3(i, j, z));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.push_back({a, c, d});
      m.faces.push_back({a, d, b});
    }
  return m;
}
}  // namespace

// Small open parts (a review, thirty-ninth session): decimated to 4, an open part of 5 faces lost
// two in one collapse and ended with 3. One of 5 faces or fewer is now kept whole, and a larger one
// decimated to 4 or 5. And a part whose share of the target is exactly 4 faces is not small (the
// share was taken in floating point, 3.9999999999999996 for 98 of 196 faces at a target of 8).
TEST(DecimateMesh, SmallOpenPartsKeepFourFacesAndAShareOfFourIsNotSmall) {
  TriMesh m = test::icosphere(3);
  const std::vector<int> fans = {5, 7, 12};
  std::vector<Vec3> centres;
  for (std::size_t k = 0; k < fans.size(); ++k) {
    centres.push_back(Vec3(1.5 + 0.5 * static_cast<double>(k), 0, 0));
    append_fan(m, centres.back(), fans[k]);
  }
  const TriMesh d = decimate_mesh(m, 200);
  EXPECT_NO_THROW(validate_mesh(d, "decimated"));
  std::vector<int> faces_of_fan(fans.size(), 0);
  for (const Face& f : d.faces)
    for (std::size_t k = 0; k < fans.size(); ++k)
      if ((d.vertices[f[0]] - centres[k]).norm() < 0.02) {
        ++faces_of_fan[k];
        // Oriented as the fan was (its faces turn counterclockwise about +z).
        EXPECT_GT((d.vertices[f[1]] - d.vertices[f[0]]).cross(d.vertices[f[2]] - d.vertices[f[0]]).z(), 0.0)
            << fans[k] << " faces";
      }
  EXPECT_EQ(faces_of_fan[0], 5);  // kept whole
  for (std::size_t k = 1; k < fans.size(); ++k) {
    EXPECT_GE(faces_of_fan[k], 4) << fans[k] << " faces";
    EXPECT_LE(faces_of_fan[k], 5) << fans[k] << " faces";
  }
  // Two grids of 98 faces each, target 8: each part's share is 4 faces, so they decimate together.
  TriMesh two = grid(7, 0.0);
  test::append_mesh(two, grid(7, 10.0));
  const TriMesh both = decimate_mesh(two, 8);
  EXPECT_LE(both.num_faces(), 8);  // 11 with the second grid alone (7 + 4)
}

// What validate_mesh() refuses too (decimate_mesh() has it as a precondition) is refused, not
// left to OpenMesh's add_face to drop.
TEST(DecimateMesh, AnEdgeTwoFacesRunAlongAlikeIsRefused) {
  TriMesh m = bowtie();
  m.vertices.resize(4);
  m.faces.resize(4);
  std::swap(m.faces[3][1], m.faces[3][2]);  // face 3 against the others
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(test::throws_with<InvalidInput>([&] { decimate_mesh(m, 4); },
                                              {"decimate_mesh: faces ", "the same way"}));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  // Its manifold half decimates as before.
  const TriMesh tetra = [] {
    TriMesh t = bowtie();
    t.vertices.resize(4);
    t.faces.resize(4);
    return t;
  }();
  EXPECT_EQ(decimate_mesh(tetra, 4).num_faces(), 4);
  // Fewer than 4 faces: the input's fault (a SolverError said the decimation left too few).
  TriMesh three = tetra;
  three.faces.resize(3);
  EXPECT_TRUE(test::throws_with<InvalidInput>([&] { decimate_mesh(three, 4); }, {"the mesh has 3 faces"}));
}
