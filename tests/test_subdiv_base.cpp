// The core engine over a subdivision limit surface (issue 4): the paper's cylinder bends with a
// Catmull-Clark cage as the base, bent by moving its control points.
#include <gtest/gtest.h>

#include <cmath>

#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/intersections.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"
#include "strata/subdiv.h"

using namespace strata;

namespace {

struct CageCase {
  cases::CylinderCase c;
  PolyMesh cage;
  std::vector<Vec3> bent;  // the cage's control points, bent
};

CageCase make_cage_case(cases::DetailKind kind, int triangles) {
  cases::CylinderCaseOptions o;
  o.detail = kind;
  o.target_detail_triangles = triangles;
  CageCase k{cases::make_cylinder_case(o), cases::make_cylinder_cage(o), {}};
  for (const Vec3& v : k.cage.vertices) k.bent.push_back(cases::bend_point(v, o));
  return k;
}

}  // namespace

TEST(SubdivBase, CylinderCageLimitIsTheBaseCylinder) {
  const PolyMesh cage = cases::make_cylinder_cage();
  const SubdivSurface s(cage);
  EXPECT_EQ(s.scheme(), SubdivScheme::CatmullClark);
  double worst = 0.0;
  for (int f = 0; f < s.num_ptex_faces(); ++f)
    for (double u : {0.0, 0.5})
      for (double v : {0.0, 0.5, 1.0}) {
        const Vec3 p = s.evaluate({f, u, v}).position;
        worst = std::max(worst, std::abs(std::hypot(p.x(), p.y()) - 1.0));
        EXPECT_GE(p.z(), -1e-12);
        EXPECT_LE(p.z(), 6.0 + 1e-12);
      }
  EXPECT_LE(worst, 0.01);  // a 16-gon's limit is round to within 1%
}

TEST(SubdivBase, EncodingProjectsOntoTheLimitAndRoundTrips) {
  const CageCase k = make_cage_case(cases::DetailKind::Bumps, 4000);
  const SubdivSurface s(k.cage);
  const DetailEncoding e = encode_detail(k.c.detail, s);
  ASSERT_TRUE(e.over_limit_surface());
  EXPECT_EQ(e.report.num_projected + e.report.num_fallback, k.c.detail.num_vertices());
  EXPECT_LE(e.report.num_fallback, k.c.detail.num_vertices() / 1000);
  // Over the unedited cage, vectors give the detail back, up to the tangential residue that the
  // projection's orthogonality tolerance (1e-9) leaves and the encoding rounds to zero.
  const BaseFrames fr = evaluate_base_frames(e, k.cage.vertices);
  const std::vector<Vec3> back = reconstruct_vectors(e, fr);
  double worst = 0.0;
  for (int i = 0; i < k.c.detail.num_vertices(); ++i)
    worst = std::max(worst, (back[i] - k.c.detail.vertices[i]).norm());
  EXPECT_LE(worst, 1e-9);
  // The foot points are orthogonal projections: the detail offset is along the limit normal.
  for (int i = 0; i < k.c.detail.num_vertices(); i += 17)
    EXPECT_LE(std::abs(e.tangential_offsets[i].norm()), 1e-12);
  // Frames from a kept surface equal frames from control points.
  SubdivSurface edited(k.cage);
  edited.set_control_points(k.bent);
  const BaseFrames a = evaluate_base_frames(e, edited), b = evaluate_base_frames(e, k.bent);
  for (int i = 0; i < k.c.detail.num_vertices(); i += 7) {
    EXPECT_LE((a.points[i] - b.points[i]).norm(), 1e-14);
    EXPECT_LE((a.normals[i] - b.normals[i]).norm(), 1e-14);
  }
  EXPECT_THROW(evaluate_base_frames(e, std::vector<Vec3>(3, Vec3::Zero())), InvalidInput);
}

// The same acceptance as over a triangle base: volumes keep every prism's volume and make no new
// intersections where displacement vectors fold.
class SubdivBend : public ::testing::TestWithParam<cases::DetailKind> {};

TEST_P(SubdivBend, VolumesAvoidTheFoldsThatVectorsMake) {
  const CageCase k = make_cage_case(GetParam(), 8000);
  const SubdivSurface s(k.cage);
  const DetailEncoding e = encode_detail(k.c.detail, s);
  const VolumeReconstructor rec(e);
  const ReconstructResult r = rec.reconstruct(k.bent);
  const BaseFrames fr = evaluate_base_frames(e, k.bent);
  const std::vector<Vec3> vec = reconstruct_vectors(e, fr);
  const VolumeMetrics mv = volume_metrics(e, fr, r.positions), mvec = volume_metrics(e, fr, vec);
  IntersectionOptions io;
  io.collect_pairs = true;
  const auto in = find_self_intersections(k.c.detail.vertices, k.c.detail.faces, io);
  const auto out = find_self_intersections(r.positions, k.c.detail.faces, io);
  const auto outv = find_self_intersections(vec, k.c.detail.faces, io);
  EXPECT_EQ(in.num_pairs, 0u);
  EXPECT_EQ(count_new_intersections(in, out), 0u);
  EXPECT_GT(count_new_intersections(in, outv), 0u);
  EXPECT_LE(mv.max_relative_error, 1e-3);
  EXPECT_LE(mv.rms_relative_error, 1e-4);
  EXPECT_LE(std::abs(mv.total_volume_change), 1e-3);
  EXPECT_GT(mvec.max_relative_error, 1e-2);
}

INSTANTIATE_TEST_SUITE_P(Fig6OverACage, SubdivBend,
                         ::testing::Values(cases::DetailKind::Bumps, cases::DetailKind::Cuboid),
                         [](const auto& info) { return std::string(cases::to_string(info.param)); });
