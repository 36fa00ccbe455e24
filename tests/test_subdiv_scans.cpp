// Projection of real scans (CGAL's demo data, tools/fetch_scans.sh) onto the Loop limit surface of
// a decimated copy: the foot points must be found for at least 99.9% of the vertices (issue 4).
// DISABLED, known open defect (2026-11-22): the hierarchy's collapses leave camel and bear nearly
// undecimated (19536 and 27648 cage faces), and over the unfitted decimated cages 841 of 17495
// (man) and 194 of 26002 (armadillo) vertices fall back. Needs the cage fitting of issue 4
// (OpenMesh's quadric decimater, then a least-squares fit of the limit to the smoothed scan).
#include <gtest/gtest.h>

#include <fstream>

#include "internal/hierarchy.h"
#include "strata/mesh_io.h"
#include "strata/subdiv.h"

using namespace strata;

namespace {

// A Loop cage: the scan decimated to about 1% of its faces (at least a few hundred).
PolyMesh decimated_cage(const TriMesh& m) {
  internal::HierarchyOptions o;
  o.max_levels = 2;
  o.ratio = 0.01;
  o.coarsest_vertices = 150;
  const internal::Hierarchy h = internal::build_hierarchy(m.vertices, m.faces, o);
  const auto& L = h.levels.front();
  std::vector<int> local(m.vertices.size(), -1);
  PolyMesh cage;
  for (int v : L.vertices) {
    local[v] = cage.num_vertices();
    cage.vertices.push_back(m.vertices[v]);
  }
  for (const Face& f : L.faces) cage.faces.push_back({local[f[0]], local[f[1]], local[f[2]]});
  return cage;
}

class ScanProjection : public ::testing::TestWithParam<const char*> {};

}  // namespace

TEST_P(ScanProjection, DISABLED_FootPointsOnTheLimitOfADecimatedCage) {
  const std::string scan = std::string(STRATA_ASSETS_DIR) + "/scans/" + GetParam() + ".off";
  ASSERT_TRUE(std::ifstream(scan).good()) << scan << " is missing: run tools/setup.sh (tools/fetch_scans.sh)";
  const TriMesh m = read_mesh(scan);
  const PolyMesh cage = decimated_cage(m);
  ASSERT_GE(cage.num_faces(), 200);
  ASSERT_LE(cage.num_faces(), m.num_faces() / 20);
  const SubdivSurface s(cage);
  ASSERT_EQ(s.scheme(), SubdivScheme::Loop);
  const Projection pr = project_to_limit(s, m.vertices);
  RecordProperty("cage_faces", cage.num_faces());
  RecordProperty("fallback", pr.num_fallback);
  EXPECT_GE(pr.num_converged, static_cast<int>(std::ceil(0.999 * m.num_vertices())))
      << pr.num_fallback << " of " << m.num_vertices() << " fell back";
  // Converged foot points are orthogonal projections.
  for (int i = 0; i < m.num_vertices(); i += 13) {
    if (!pr.converged[i]) continue;
    const LimitSample x = s.evaluate(pr.points[i]);
    const Vec3 d = m.vertices[i] - x.position;
    if (d.norm() < 1e-9) continue;
    EXPECT_LE(std::abs(d.normalized().dot(x.du.normalized())), 1e-3);
    EXPECT_LE(std::abs(d.normalized().dot(x.dv.normalized())), 1e-3);
  }
}

INSTANTIATE_TEST_SUITE_P(RealScans, ScanProjection, ::testing::Values("camel", "man", "armadillo", "bear"));
