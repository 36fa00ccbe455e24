// dihedral_change(): exact angles on hinges, nearest-rank percentiles, invariance under similarity
// transforms, which edges are measured, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "strata/exceptions.h"
#include "strata/metrics.h"
#include "test_meshes.h"

using namespace strata;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A hinge: faces (a, b, c) and (b, a, d) over the edge a b along x, flat at rest; folded, d turns
// by \p degrees about that edge.
struct Hinge {
  std::vector<Vec3> rest, folded;
  std::vector<Face> faces;
};

Hinge hinge(double degrees, const Vec3& offset = Vec3::Zero()) {
  const double t = degrees * kPi / 180.0;
  Hinge h;
  h.rest = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1, 0), Vec3(0.3, -1, 0)};
  h.folded = h.rest;
  h.folded[3] = Vec3(0.3, -std::cos(t), -std::sin(t));
  for (Vec3& p : h.rest) p += offset;
  for (Vec3& p : h.folded) p += offset;
  h.faces = {Face{0, 1, 2}, Face{1, 0, 3}};
  return h;
}

// Appends \p h's faces and points to (faces, rest, folded), its vertex ids shifted past them.
void append(const Hinge& h, std::vector<Face>& faces, std::vector<Vec3>& rest, std::vector<Vec3>& folded) {
  const int base = static_cast<int>(rest.size());
  for (const Face& f : h.faces) faces.push_back(Face{f[0] + base, f[1] + base, f[2] + base});
  rest.insert(rest.end(), h.rest.begin(), h.rest.end());
  folded.insert(folded.end(), h.folded.begin(), h.folded.end());
}

}  // namespace

TEST(Metrics, AHingeFoldedByThetaChangesItsDihedralAngleByTheta) {
  for (double theta : {1e-3, 30.0, 90.0, 150.0, 179.0}) {
    const Hinge h = hinge(theta);
    const DihedralChange d = dihedral_change(h.faces, h.rest, h.folded);
    ASSERT_EQ(d.edges, 1u) << theta;  // the shared edge; the four boundary edges are not measured
    EXPECT_NEAR(d.max_degrees, theta, 1e-9 * std::max(1.0, theta)) << theta;
    EXPECT_EQ(d.median_degrees, d.max_degrees);
    EXPECT_EQ(d.p90_degrees, d.max_degrees);
    EXPECT_EQ(d.p99_degrees, d.max_degrees);
    EXPECT_EQ(d.mean_degrees, d.max_degrees);
    // From folded back to flat: the same change.
    EXPECT_NEAR(dihedral_change(h.faces, h.folded, h.rest).max_degrees, theta, 1e-9 * std::max(1.0, theta));
  }
}

TEST(Metrics, DihedralChangePercentilesAreNearestRanks) {
  // Ten separate hinges folded by 10, 20, .., 100 degrees.
  std::vector<Face> faces;
  std::vector<Vec3> rest, folded;
  for (int k = 1; k <= 10; ++k) append(hinge(10.0 * k, Vec3(3.0 * k, 0, 0)), faces, rest, folded);
  const DihedralChange d = dihedral_change(faces, rest, folded);
  ASSERT_EQ(d.edges, 10u);
  EXPECT_NEAR(d.median_degrees, 50.0, 1e-9);  // rank ceil(0.5 * 10) = 5
  EXPECT_NEAR(d.p90_degrees, 90.0, 1e-9);     // rank 9
  EXPECT_NEAR(d.p99_degrees, 100.0, 1e-9);    // rank ceil(9.9) = 10
  EXPECT_NEAR(d.max_degrees, 100.0, 1e-9);
  EXPECT_NEAR(d.mean_degrees, 55.0, 1e-9);
}

TEST(Metrics, DihedralChangeIsInvariantUnderRotationTranslationAndScale) {
  const TriMesh sphere = test::icosphere(3);
  // Some bends: every vertex pushed out by a smooth function of its position.
  std::vector<Vec3> bumpy = sphere.vertices;
  for (Vec3& p : bumpy) p *= 1.0 + 0.2 * std::sin(5 * p.x()) * std::cos(3 * p.y());
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vec3> moved = bumpy;
  for (Vec3& p : moved) p = 2.5 * (rot * p) + Vec3(10, -4, 7);
  const DihedralChange d = dihedral_change(sphere.faces, bumpy, moved);
  EXPECT_EQ(d.edges, 3 * sphere.faces.size() / 2);  // closed: every edge has two faces
  EXPECT_LT(d.max_degrees, 1e-9);
  // And the bumps themselves are seen against the sphere.
  const DihedralChange b = dihedral_change(sphere.faces, sphere.vertices, bumpy);
  EXPECT_GT(b.max_degrees, 1.0);
  EXPECT_GT(b.p90_degrees, b.median_degrees);
}

TEST(Metrics, DihedralChangeSkipsBoundaryNonManifoldAndDegenerateEdges) {
  const std::vector<Vec3> one = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_EQ(dihedral_change({Face{0, 1, 2}}, one, one).edges, 0u);
  // Three faces on the edge 0 1: not measured.
  const std::vector<Vec3> fan = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1, 0), Vec3(0.5, -1, 0),
                                 Vec3(0.5, 0, 1)};
  const std::vector<Face> three = {Face{0, 1, 2}, Face{1, 0, 3}, Face{0, 1, 4}};
  EXPECT_EQ(dihedral_change(three, fan, fan).edges, 0u);
  // A hinge whose second face has zero area in the folded shape: its edge is not measured.
  Hinge h = hinge(45.0);
  h.folded[3] = Vec3(0.3, 0, 0);  // on the edge a b
  EXPECT_EQ(dihedral_change(h.faces, h.rest, h.folded).edges, 0u);
  const DihedralChange none = dihedral_change({}, {}, {});
  EXPECT_EQ(none.edges, 0u);
  EXPECT_EQ(none.max_degrees, 0.0);
}

TEST(Metrics, DihedralChangeRejectsBadInput) {
  const Hinge h = hinge(30.0);
  std::vector<Vec3> short_points = h.folded;
  short_points.pop_back();
  EXPECT_THROW(dihedral_change(h.faces, h.rest, short_points), InvalidInput);
  EXPECT_THROW(dihedral_change({Face{0, 1, 7}}, h.rest, h.folded), InvalidInput);
  std::vector<Vec3> nan_points = h.folded;
  nan_points[2].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    dihedral_change(h.faces, h.rest, nan_points);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("point 2 is not finite"), std::string::npos) << e.what();
  }
}
