#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "internal/closest_point.h"
#include "internal/parts.h"
#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/metrics.h"
#include "strata/subdiv.h"
#include "test_files.h"
#include "test_meshes.h"

using namespace strata;

namespace {

// A small bumps case: its detail is an exact normal displacement of the analytic cylinder.
const cases::CylinderCase& small_case() {
  static const cases::CylinderCase c = [] {
    cases::CylinderCaseOptions o;
    o.target_detail_triangles = 3000;
    return cases::make_cylinder_case(o);
  }();
  return c;
}

// Unit normal of the base's interpolated (Phong) normal field at a base point.
Vec3 interpolated_normal(const TriMesh& base, const BasePoint& bp) {
  const std::vector<Vec3> vn = vertex_normals(base.vertices, base.faces);
  const Face& f = base.faces[bp.face];
  return (bp.bary[0] * vn[f[0]] + bp.bary[1] * vn[f[1]] + bp.bary[2] * vn[f[2]]).normalized();
}

}  // namespace

TEST(Encoding, DisplacementsAreParallelToInterpolatedNormals) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  EXPECT_EQ(e.report.num_fallback, 0);
  EXPECT_EQ(e.report.num_projected, c.detail.num_vertices());
  const std::vector<Vec3> vn = vertex_normals(c.base.vertices, c.base.faces);
  for (int i = 0; i < c.detail.num_vertices(); i += 7) {
    const BasePoint& bp = e.base_points[i];
    ASSERT_GE(bp.face, 0);
    EXPECT_NEAR(bp.bary.sum(), 1.0, 1e-12);
    EXPECT_GE(bp.bary.minCoeff(), 0.0);
    const Face& f = c.base.faces[bp.face];
    const Vec3 q = bp.bary[0] * c.base.vertices[f[0]] + bp.bary[1] * c.base.vertices[f[1]] +
                   bp.bary[2] * c.base.vertices[f[2]];
    const Vec3 d = c.detail.vertices[i] - q;
    const Vec3 n = interpolated_normal(c.base, bp);
    // p - q parallel to n(q): the cross product vanishes relative to |d|.
    EXPECT_LE(d.cross(n).norm(), 1e-8 * d.norm()) << "vertex " << i;
    EXPECT_NEAR(d.dot(n), e.normal_offsets[i], 1e-10);
    EXPECT_GT(e.normal_offsets[i], 0.0);  // the detail lies outside the cylinder
    EXPECT_TRUE(e.tangential_offsets[i].isZero());
  }
}

TEST(Encoding, TargetsAreThePrismVolumesOverTheOriginalBase) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  const VolumeMetrics m = volume_metrics(e, fr, c.detail.vertices);
  EXPECT_EQ(m.max_relative_error, 0.0);
  EXPECT_GT(m.total_target, 0.0);
  // The layer between a cylinder of radius R and the detail (offsets in [0.175, 0.525]) over
  // length 6 has a volume between the two bounding shells.
  const double R = 1.0, L = 6.0;
  EXPECT_GT(m.total_target, M_PI * L * ((R + 0.175) * (R + 0.175) - R * R) * 0.95);
  EXPECT_LT(m.total_target, M_PI * L * ((R + 0.525) * (R + 0.525) - R * R));
  // Exactly: the volume of the closed layer by the divergence theorem, without prism_volume().
  // Its surface is the detail's triangles, the base points' triangles reversed, and at the
  // tube's two open ends each boundary edge's side quad (q_i, q_j, p_j, p_i), split at its
  // centroid as a prism splits it (the inner quads, shared by two prisms, cancel).
  const std::vector<Vec3>& p = c.detail.vertices;
  std::vector<Vec3> q(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const BasePoint& bp = e.base_points[i];
    const Face& f = c.base.faces[bp.face];
    q[i] = bp.bary[0] * c.base.vertices[f[0]] + bp.bary[1] * c.base.vertices[f[1]] +
           bp.bary[2] * c.base.vertices[f[2]];
  }
  auto det = [](const Vec3& a, const Vec3& b, const Vec3& d) { return a.dot(b.cross(d)); };
  std::set<std::pair<int, int>> directed;
  for (const Face& f : c.detail.faces)
    for (int k = 0; k < 3; ++k) directed.emplace(f[k], f[(k + 1) % 3]);
  double six_volume = 0.0;
  int boundary_edges = 0;
  for (const Face& f : c.detail.faces) {
    six_volume += det(p[f[0]], p[f[1]], p[f[2]]) - det(q[f[0]], q[f[1]], q[f[2]]);
    for (int k = 0; k < 3; ++k) {
      const int i = f[k], j = f[(k + 1) % 3];
      if (directed.count({j, i})) continue;  // an inner edge
      ++boundary_edges;
      const Vec3 quad[4] = {q[i], q[j], p[j], p[i]};
      const Vec3 centroid = (quad[0] + quad[1] + quad[2] + quad[3]) / 4.0;
      for (int t = 0; t < 4; ++t) six_volume += det(quad[t], quad[(t + 1) % 4], centroid);
    }
  }
  EXPECT_GT(boundary_edges, 0);  // the tube's two rims
  EXPECT_NEAR(m.total_target, six_volume / 6.0, 1e-12 * m.total_target);
}

TEST(Encoding, DetailOnTheBaseHasZeroOffsetsAndVolumes) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.base, c.base);
  for (double f : e.normal_offsets) EXPECT_NEAR(f, 0.0, 1e-12);
  for (double v : e.target_volumes) EXPECT_NEAR(v, 0.0, 1e-12);
}

TEST(Encoding, FallbackToClosestPointIsCountedAndLossless) {
  // A detail point far off to the side of a single base triangle has no normal projection:
  // it falls back to the closest point, keeps its tangential offset, and the vectors rebuild it.
  TriMesh base;
  base.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  base.faces = {Face{0, 1, 2}};
  TriMesh detail;
  detail.vertices = {Vec3(0.1, 0.1, 0.5), Vec3(0.6, 0.1, 0.5), Vec3(3.0, 3.0, 0.2)};
  detail.faces = {Face{0, 1, 2}};
  const DetailEncoding e = encode_detail(detail, base);
  EXPECT_EQ(e.report.num_projected, 2);
  EXPECT_EQ(e.report.num_fallback, 1);
  EXPECT_GT(e.report.max_tangential_offset, 1.0);
  const std::vector<Vec3> p = reconstruct_vectors(e, base.vertices);
  for (int i = 0; i < 3; ++i) EXPECT_LE((p[i] - detail.vertices[i]).norm(), 1e-12);
}

// The same encoding at any scale: the tolerances were partly absolute (1.0 and 1e-12 world
// units), so at 1e-9 a fallback's tangential offset was zeroed and the vectors lost the vertex.
TEST(Encoding, ScaledByAPowerOfTwoTheEncodingIsTheSame) {
  TriMesh base;
  base.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0.3)};
  base.faces = {Face{0, 1, 2}, Face{1, 3, 2}};
  TriMesh detail;
  detail.vertices = {Vec3(0.1, 0.1, 0.5), Vec3(0.6, 0.1, 0.5), Vec3(3.0, 3.0, 0.2), Vec3(0.7, 0.7, 0.6)};
  detail.faces = {Face{0, 1, 3}, Face{1, 2, 3}};
  const DetailEncoding unit = encode_detail(detail, base);
  ASSERT_EQ(unit.report.num_fallback, 1);
  for (int e : {-30, -60, 30, 60}) {  // about 1e-9, 1e-18, 1e9, 1e18
    const double s = std::ldexp(1.0, e);
    TriMesh b = base, d = detail;
    for (Vec3& x : b.vertices) x *= s;
    for (Vec3& x : d.vertices) x *= s;
    const DetailEncoding enc = encode_detail(d, b);
    EXPECT_EQ(enc.report.num_projected, unit.report.num_projected) << "2^" << e;
    EXPECT_EQ(enc.report.num_fallback, unit.report.num_fallback) << "2^" << e;
    EXPECT_EQ(enc.report.num_ambiguous, unit.report.num_ambiguous) << "2^" << e;
    for (int i = 0; i < d.num_vertices(); ++i) {
      EXPECT_EQ(enc.base_points[i].face, unit.base_points[i].face) << "2^" << e << ", vertex " << i;
      EXPECT_EQ(enc.tangential_offsets[i].isZero(0), unit.tangential_offsets[i].isZero(0))
          << "2^" << e << ", vertex " << i;
    }
    const std::vector<Vec3> p = reconstruct_vectors(enc, b.vertices);
    for (int i = 0; i < d.num_vertices(); ++i)
      EXPECT_LE((p[i] - d.vertices[i]).norm(), 1e-12 * s) << "2^" << e;
  }
}

TEST(Encoding, VectorsOverTheOriginalBaseReturnTheDetail) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const std::vector<Vec3> p = reconstruct_vectors(e, c.base.vertices);
  double worst = 0.0;
  for (int i = 0; i < c.detail.num_vertices(); ++i)
    worst = std::max(worst, (p[i] - c.detail.vertices[i]).norm());
  EXPECT_LE(worst, 1e-12);
}

TEST(Encoding, VectorsFollowARigidMotionOfTheBase) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 t(0.5, -2.0, 3.0);
  std::vector<Vec3> moved;
  for (const Vec3& x : c.base.vertices) moved.push_back(R * x + t);
  const std::vector<Vec3> p = reconstruct_vectors(e, moved);
  for (int i = 0; i < c.detail.num_vertices(); i += 5)
    EXPECT_LE((p[i] - (R * c.detail.vertices[i] + t)).norm(), 1e-10);
}

TEST(Encoding, RejectsBadInput) {
  const auto& c = small_case();
  TriMesh empty;
  EXPECT_THROW(encode_detail(empty, c.base), InvalidInput);
  EXPECT_THROW(encode_detail(c.detail, empty), InvalidInput);
  TriMesh nan_detail = c.detail;
  nan_detail.vertices[3][1] = std::nan("");
  EXPECT_THROW(encode_detail(nan_detail, c.base), InvalidInput);
  TriMesh bad_index = c.detail;
  bad_index.faces[0][2] = c.detail.num_vertices() + 5;
  EXPECT_THROW(encode_detail(bad_index, c.base), InvalidInput);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  std::vector<Vec3> short_base(c.base.vertices.begin(), c.base.vertices.end() - 1);
  EXPECT_THROW(evaluate_base_frames(e, short_base), InvalidInput);
  std::vector<Vec3> nan_base = c.base.vertices;
  nan_base[0][0] = INFINITY;
  EXPECT_THROW(reconstruct_vectors(e, nan_base), InvalidInput);
  // Beyond the engine's range (kMaxCoordinate): a detail vertex 1e80 from the base crashed the
  // encoding, one 1e28 away overflowed the solver. The message names the vertex and its magnitude.
  TriMesh far_detail = c.detail;
  far_detail.vertices[2] *= 1e80;
  try {
    encode_detail(far_detail, c.base);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& ex) {
    EXPECT_NE(std::string(ex.what()).find("detail mesh vertex 2 has a coordinate of magnitude"),
              std::string::npos)
        << ex.what();
  }
  // Base points whose barycentric coordinates are not a point's on the face (a file's 1e308).
  std::vector<BasePoint> off(c.detail.vertices.size(), BasePoint{0, Vec3(1, 0, 0)});
  EXPECT_NO_THROW(encode_detail_at(c.detail, c.base, off));
  off[1].bary = Vec3(1e308, 0, 0);
  EXPECT_THROW(encode_detail_at(c.detail, c.base, off), InvalidInput);
  off[1].bary = Vec3(0.5, 0.6, 0.0);
  EXPECT_THROW(encode_detail_at(c.detail, c.base, off), InvalidInput);
  std::vector<Vec3> far_base = c.base.vertices;
  far_base[1] *= 1e25;
  EXPECT_THROW(evaluate_base_frames(e, far_base), InvalidInput);
  // A base face with two equal corners, in either corner order: named, not a crash (its closest
  // point was 0/0, and the encoding indexed face -1 when the corners came first).
  for (const Face f : {Face{0, 1, 2}, Face{2, 0, 1}}) {
    const TriMesh degenerate{{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)}, {f}};
    TriMesh detail{{Vec3(0.2, 0.3, 0.5), Vec3(0.3, 0.3, 0.5), Vec3(0.2, 0.4, 0.5)}, {{0, 1, 2}}};
    EXPECT_TRUE(
        test::throws_with<InvalidInput>([&] { encode_detail(detail, degenerate); }, {"has no normal"}))
        << f[0] << f[1] << f[2];
  }
}

// The closest point on a triangle against the closest of its sides, on triangles degenerate and
// thin to rounding: two equal corners gave a NaN point, and slivers (relative height 1e-14) a
// point farther than a side's (found by a review, 2026-11-30).
TEST(ClosestPoint, DegenerateAndSliverTrianglesGiveTheClosestSidePoint) {
  auto on_segment = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 d = b - a;
    const double len = d.squaredNorm();
    return len == 0 ? a : Vec3(a + std::clamp((p - a).dot(d) / len, 0.0, 1.0) * d);
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto random = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  int worse = 0;
  for (int it = 0; it < 20000; ++it) {
    const Vec3 a = random(), b = random(), p = 2.0 * random();
    const double height = std::pow(10.0, -(it % 17));
    const Vec3 c = it % 5 == 0 ? a : Vec3(a + (b - a) * 1.5 * u(rng) + height * random());
    Vec3 bary;
    const Vec3 x = internal::closest_point_on_triangle(p, a, b, c, bary);
    ASSERT_TRUE(x.allFinite() && bary.allFinite()) << it;
    EXPECT_NEAR(bary.sum(), 1.0, 1e-12);
    EXPECT_LT((bary[0] * a + bary[1] * b + bary[2] * c - x).norm(), 1e-12);
    const double sides = std::min({(on_segment(p, a, b) - p).norm(), (on_segment(p, b, c) - p).norm(),
                                   (on_segment(p, c, a) - p).norm()});
    worse += (x - p).norm() > sides * (1 + 1e-9) + 1e-12;
  }
  EXPECT_EQ(worse, 0);
}

// Every function that takes an encoding checks that its arrays fit before indexing with them (an
// encoding made or altered by hand read past its arrays under ASan): the message names the array.
TEST(Encoding, FunctionsTakingAnEncodingRejectAnInconsistentOne) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  EXPECT_NO_THROW(check_encoding(e));
  const BaseFrames frames = evaluate_base_frames(e, c.edited_base.vertices);
  const std::vector<Vec3> x = reconstruct_vectors(e, frames);
  std::vector<int> kept;
  // evaluate_base_frames() reads the base points and faces only (the encoders call it before the
  // rest is filled in): it refuses what breaks those.
  auto all_refuse = [&](const DetailEncoding& broken, const std::string& name, bool base_part) {
    auto expect = [&](auto&& call, const char* what) {
      try {
        call();
        ADD_FAILURE() << what << " accepted an encoding with a broken " << name;
      } catch (const InvalidInput& ex) {
        EXPECT_NE(std::string(ex.what()).find(name), std::string::npos) << what << ": " << ex.what();
      }
    };
    expect([&] { check_encoding(broken); }, "check_encoding");
    if (base_part)
      expect([&] { evaluate_base_frames(broken, c.edited_base.vertices); }, "evaluate_base_frames");
    expect([&] { reconstruct_vectors(broken, frames); }, "reconstruct_vectors");
    expect([&] { volume_metrics(broken, frames, x); }, "volume_metrics");
    expect([&] { restrict_encoding(broken, {0, 1, 2}, kept); }, "restrict_encoding");
  };
  // Arrays shrunk to their size (pop_back() alone leaves the capacity that ASan does not flag).
  auto shrunk = [](auto& v) {
    v.pop_back();
    v.shrink_to_fit();
  };
  DetailEncoding broken = e;
  shrunk(broken.base_points);
  all_refuse(broken, "base points", true);
  broken = e;
  shrunk(broken.target_volumes);
  all_refuse(broken, "target volumes", false);
  broken = e;
  shrunk(broken.normal_offsets);
  all_refuse(broken, "normal offsets", false);
  broken = e;
  broken.pinned.assign(5, 0);
  all_refuse(broken, "pinned flags", false);
  broken = e;
  broken.base_faces[3][2] = -1;
  all_refuse(broken, "base face index", true);
  broken = e;
  broken.base_points[4].face = static_cast<int>(e.base_faces.size());
  all_refuse(broken, "missing base face", true);
  broken = e;
  broken.detail_faces[8][0] = e.num_detail_vertices();
  all_refuse(broken, "detail face index", false);
  // Frames of another size, and prism volumes over indices beyond the points.
  BaseFrames short_frames = frames;
  shrunk(short_frames.tangents);
  EXPECT_THROW(reconstruct_vectors(e, short_frames), InvalidInput);
  std::vector<Face> faces = e.detail_faces;
  faces[2][1] = static_cast<int>(x.size());
  EXPECT_THROW(prism_volumes(faces, x, frames.points), InvalidInput);
  std::vector<Vec3> short_points(frames.points.begin(), frames.points.end() - 1);
  EXPECT_THROW(prism_volumes(e.detail_faces, x, short_points), InvalidInput);
}

// An edited base collapsed to a point has no normals: the frames were NaN (and the vectors' result
// with them), where the reconstruction said only "base frame 0 is not finite".
TEST(Encoding, ADegenerateEditedBaseIsNamed) {
  const auto& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  // Collapsed to a point: below the engine's range. Onto a line: every face without a normal.
  const std::vector<Vec3> point(c.base.vertices.size(), Vec3(1, 2, 3));
  std::vector<Vec3> line;
  for (std::size_t i = 0; i < c.base.vertices.size(); ++i) line.push_back(Vec3(1e-3 * i, 2, 3));
  using Case = std::pair<const std::vector<Vec3>*, std::vector<std::string>>;
  for (const auto& [collapsed, expected] :
       {Case{&point, {"edited base has an extent (bounding box diagonal) of 0"}},
        Case{&line, {"base face", "has no normal"}}})
    for (int k = 0; k < 2; ++k) {
      try {
        if (k == 0)
          evaluate_base_frames(e, *collapsed);
        else
          reconstruct_vectors(e, *collapsed);
        ADD_FAILURE() << "a collapsed base gave frames";
      } catch (const InvalidInput& ex) {
        for (const std::string& part : expected)
          EXPECT_NE(std::string(ex.what()).find(part), std::string::npos) << ex.what();
      }
    }
}

// Encoding options out of range (the ranges a .strata file's are read with): NaN ratios made every
// projection fall back to the closest point without a word.
TEST(Encoding, OptionsOutOfRangeAreRejected) {
  const auto& c = small_case();
  const double nan = std::nan("");
  std::vector<std::pair<EncodeOptions, const char*>> bad;
  EncodeOptions o;
  o.search_rings = -1;
  bad.emplace_back(o, "search_rings");
  o = {};
  o.barycentric_tolerance = nan;
  bad.emplace_back(o, "barycentric_tolerance");
  o = {};
  o.max_distance_ratio = nan;
  bad.emplace_back(o, "max_distance_ratio");
  o = {};
  o.max_distance_ratio = 0.5;
  bad.emplace_back(o, "max_distance_ratio");
  for (const auto& [options, name] : bad) {
    try {
      encode_detail(c.detail, c.base, options);
      ADD_FAILURE() << name << " accepted";
    } catch (const InvalidInput& ex) {
      EXPECT_NE(std::string(ex.what()).find(name), std::string::npos) << ex.what();
    }
  }
}

// The projections run on TBB's threads: one thread and three give the same base points, offsets,
// targets and counts (several chunks of projections, so the counts are summed across threads).
TEST(Encoding, TheSameForAnyThreadCount) {
  cases::CylinderCaseOptions o;
  o.target_detail_triangles = 8000;
  o.detail = cases::DetailKind::Cuboid;
  const cases::CylinderCase c = cases::make_cylinder_case(o);
  ASSERT_GT(c.detail.num_vertices(), 3 * 1024);
  auto encode_on = [&](int threads) {
    tbb::task_arena arena(threads);
    return arena.execute([&] { return encode_detail(c.detail, c.base); });
  };
  const DetailEncoding one = encode_on(1), three = encode_on(3);
  ASSERT_EQ(one.base_points.size(), three.base_points.size());
  for (std::size_t i = 0; i < one.base_points.size(); ++i) {
    ASSERT_EQ(one.base_points[i].face, three.base_points[i].face) << "vertex " << i;
    ASSERT_EQ(one.base_points[i].bary, three.base_points[i].bary) << "vertex " << i;
    ASSERT_EQ(one.normal_offsets[i], three.normal_offsets[i]) << "vertex " << i;
  }
  EXPECT_EQ(one.target_volumes, three.target_volumes);
  EXPECT_EQ(one.report.num_projected, three.report.num_projected);
  EXPECT_EQ(one.report.num_fallback, three.report.num_fallback);
  EXPECT_EQ(one.report.num_ambiguous, three.report.num_ambiguous);
  EXPECT_EQ(one.report.num_projected + one.report.num_fallback, c.detail.num_vertices());
}

// The paper's details are normal displacements of the cylinder, outside it: every vertex has one
// normal projection and no other. Where a base face's normal offset collapses (at the cylinder's
// axis, the focal line of its curvature) every point's cubic has a root whose barycentric
// coordinates are rounding noise; such roots were counted as projections (3-29 "ambiguous"
// vertices at 20k prisms), and at 100k one won as the nearest, a base point 0.03 off the normal
// projection (the rings: 35 ambiguous, max tangential offset 0.030).
TEST(Encoding, ANormalDisplacementHasOneProjectionPerVertex) {
  struct Size {
    cases::DetailKind kind;
    int triangles;
  };
  for (const Size& s : {Size{cases::DetailKind::Bumps, 20000}, Size{cases::DetailKind::Rings, 20000},
                        Size{cases::DetailKind::Cuboid, 20000}, Size{cases::DetailKind::Rings, 100000}}) {
    cases::CylinderCaseOptions o;
    o.detail = s.kind;
    o.target_detail_triangles = s.triangles;
    o.jitter = 0.4;
    const cases::CylinderCase c = cases::make_cylinder_case(o);
    const DetailEncoding e = encode_detail(c.detail, c.base);
    EXPECT_EQ(e.report.num_projected, c.detail.num_vertices()) << c.name << " " << s.triangles;
    EXPECT_EQ(e.report.num_ambiguous, 0) << c.name << " " << s.triangles;
    EXPECT_EQ(e.report.max_tangential_offset, 0.0) << c.name << " " << s.triangles;
  }
}

namespace {

using test::DebrisScene;

// Which base part face j of the scene's base is on: -1 the sphere's, else its tetrahedron's.
int debris_part(const DebrisScene& s, int j) {
  return j < s.base_sphere_faces ? -1 : (j - s.base_sphere_faces) / 4;
}
int debris_part_of_vertex(const DebrisScene& s, int i) {
  return i < s.sphere_vertices ? -1 : (i - s.sphere_vertices) / 4;
}

// The faces of \p m whose centroids \p keep, with their vertices, renumbered.
template <class Keep>
TriMesh faces_where(const TriMesh& m, Keep keep) {
  TriMesh out;
  std::vector<int> id(m.vertices.size(), -1);
  for (const Face& f : m.faces) {
    if (!keep((m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) / 3.0)) continue;
    Face g;
    for (int c = 0; c < 3; ++c) {
      if (id[f[c]] < 0) {
        id[f[c]] = out.num_vertices();
        out.vertices.push_back(m.vertices[f[c]]);
      }
      g[c] = id[f[c]];
    }
    out.faces.push_back(g);
  }
  return out;
}

}  // namespace

// Each detail vertex takes its base point on its own part's base: the sphere's on the sphere's,
// each tetrahedron's on its own. Encoded alone, the sphere puts vertices on the tetrahedra's
// bases (the setting is one where it matters), and its part of the whole encoding is the sphere
// encoded alone over the base sphere alone, bit for bit.
TEST(Encoding, ScanDebrisAndTheSurfaceEachKeepTheirOwnBase) {
  const DebrisScene s = test::debris_scene(test::icosphere(2, 0.9));
  const DetailEncoding e = encode_detail(s.detail, s.base);
  for (int i = 0; i < s.detail.num_vertices(); ++i)
    ASSERT_EQ(debris_part(s, e.base_points[i].face), debris_part_of_vertex(s, i)) << "vertex " << i;
  const TriMesh sphere = test::icosphere(3);
  int on_debris = 0;
  for (const BasePoint& bp : encode_detail(sphere, s.base).base_points)
    on_debris += debris_part(s, bp.face) >= 0;
  EXPECT_GT(on_debris, 0);
  const DetailEncoding alone = encode_detail(sphere, test::icosphere(2, 0.9));
  for (int i = 0; i < s.sphere_vertices; ++i) {
    ASSERT_EQ(e.base_points[i].face, alone.base_points[i].face) << "vertex " << i;
    ASSERT_EQ(e.base_points[i].bary, alone.base_points[i].bary) << "vertex " << i;
  }
}

// The same over a limit surface: a Loop cage of the 0.9 sphere with a tetrahedron cage at each
// piece of debris (the limit points' ptex faces are the cage's triangles).
TEST(Encoding, ScanDebrisAndTheSurfaceEachKeepTheirOwnBaseOverALimitSurface) {
  const DebrisScene s = test::debris_scene(test::icosphere(1, 0.9));
  SubdivOptions loop;
  loop.scheme = SubdivScheme::Loop;
  const SubdivSurface surface(test::triangle_cage(s.base), {}, loop);
  const DetailEncoding e = encode_detail(s.detail, surface);
  EXPECT_EQ(e.report.num_fallback, 0);
  for (int i = 0; i < s.detail.num_vertices(); ++i)
    ASSERT_EQ(debris_part(s, e.limit_points[i].face), debris_part_of_vertex(s, i)) << "vertex " << i;
  int on_debris = 0;
  for (const LimitPoint& p : project_to_limit(surface, test::icosphere(3).vertices).points)
    on_debris += debris_part(s, p.face) >= 0;
  EXPECT_GT(on_debris, 0);
  // project_mesh_to_limit() of one part is project_to_limit().
  const TriMesh sphere = test::icosphere(3);
  const Projection whole = project_mesh_to_limit(surface, sphere),
                   points = project_to_limit(surface, sphere.vertices);
  for (int i = 0; i < sphere.num_vertices(); ++i) {
    ASSERT_EQ(whole.points[i].face, points.points[i].face) << "vertex " << i;
    ASSERT_EQ(whole.points[i].u, points.points[i].u) << "vertex " << i;
    ASSERT_EQ(whole.points[i].v, points.points[i].v) << "vertex " << i;
  }
}

// Each part goes to the part of the other mesh its samples lie nearest to; parts are joined at
// equal positions (an unwelded seam), and one part on either side restricts nothing.
TEST(PartMatch, BasePartsGoToTheDetailPartTheyLieOn) {
  const DebrisScene s = test::debris_scene(test::icosphere(2, 0.9));
  const internal::PartMatch m = internal::match_parts(s.detail, s.base.vertices, s.base.faces);
  ASSERT_EQ(m.groups.size(), 13u);
  // Each detail vertex's base is its own part's: the sphere's the base sphere's faces, tetrahedron
  // t's the faces of the base tetrahedron t (a review: with the sizes alone checked, a shift of
  // every tetrahedron onto its neighbour's base passed).
  for (int i = 0; i < s.detail.num_vertices(); ++i) {
    std::vector<int> want;
    const int t = debris_part_of_vertex(s, i);
    if (t < 0)
      for (int j = 0; j < s.base_sphere_faces; ++j) want.push_back(j);
    else
      for (int j = 0; j < 4; ++j) want.push_back(s.base_sphere_faces + 4 * t + j);
    ASSERT_EQ(m.faces(m.group(i)), want) << "detail vertex " << i;
  }
  // An unwelded copy of a vertex's position joins its faces' parts.
  TriMesh seam;
  seam.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  seam.faces = {{0, 1, 2}, {3, 5, 4}};
  EXPECT_EQ(internal::connected_parts(seam.vertices, seam.faces, false).count, 2);
  EXPECT_EQ(internal::connected_parts(seam.vertices, seam.faces, true).count, 1);
  EXPECT_TRUE(internal::match_parts(seam, s.base.vertices, s.base.faces).empty());
  EXPECT_TRUE(internal::match_parts(s.detail, seam.vertices, seam.faces).empty());
  // A base of one part restricts nothing.
  const TriMesh sphere_base = test::icosphere(2, 0.9);
  EXPECT_TRUE(internal::match_parts(s.detail, sphere_base.vertices, sphere_base.faces).empty());
}

// A base part that no detail part lies on (a tetrahedron of the base alone, 0.5 below a sphere
// whose two caps are the detail's parts) is matched to the nearer cap; it must not become that
// cap's whole base (a review: all 421 vertices of the lower cap were encoded over it, with normal
// offsets up to 1.14). Each cap's base is also the part it lies on.
TEST(Encoding, ABasePartUnderNoDetailPartIsNoPartsWholeBase) {
  const TriMesh fine = test::icosphere(4);
  TriMesh detail = faces_where(fine, [](const Vec3& c) { return c.z() > -0.5; });
  test::append_mesh(detail, faces_where(fine, [](const Vec3& c) { return c.z() < -0.7; }));
  TriMesh base = test::icosphere(2);
  const int sphere_faces = base.num_faces();
  test::append_tetrahedron(base, Vec3(0, 0, -1.6), 0.2);
  const DetailEncoding e = encode_detail(detail, base);
  // The base points of the caps encoded over the sphere without the tetrahedron (the same points;
  // on an edge or a corner through either face, as the trees differ).
  const DetailEncoding without = encode_detail(detail, test::icosphere(2));
  for (int i = 0; i < detail.num_vertices(); ++i) {
    ASSERT_LT(e.base_points[i].face, sphere_faces) << "vertex " << i;
    ASSERT_LT((e.base_rest_points[i] - without.base_rest_points[i]).norm(), 1e-12) << "vertex " << i;
  }
}

// A mesh with a face index out of range is refused by name, not read out of bounds.
TEST(Encoding, ProjectMeshToLimitRefusesAnOutOfRangeIndex) {
  SubdivOptions loop;
  loop.scheme = SubdivScheme::Loop;
  const SubdivSurface surface(test::triangle_cage(test::icosphere(1)), {}, loop);
  TriMesh m = test::icosphere(1);
  for (const int bad : {50000000, -1}) {
    m.faces[3][2] = bad;
    try {
      project_mesh_to_limit(surface, m);
      FAIL() << "no exception for index " << bad;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("project_mesh_to_limit: face 3"), std::string::npos) << e.what();
    }
  }
}

// Over a base of the detail's own connectivity (a smoothed copy: the region editors', `strata
// deform`'s) each part's base is its own faces, even where the smoothing brought a piece of debris
// nearer to another part than to its own (here onto the base sphere).
TEST(PartMatch, OverTheDetailsOwnConnectivityEachPartIsItsOwnBase) {
  TriMesh detail = test::icosphere(2);
  const int sphere_faces = detail.num_faces();
  test::append_tetrahedron(detail, Vec3(0, 0, 1.04), 0.04);
  TriMesh base = detail;
  for (int v = 0; v < test::icosphere(2).num_vertices(); ++v) base.vertices[v] *= 0.9;
  for (std::size_t v = test::icosphere(2).vertices.size(); v < base.vertices.size(); ++v)
    base.vertices[v] += Vec3(0, 0, -0.14);
  const internal::PartMatch m = internal::match_parts(detail, base.vertices, base.faces);
  ASSERT_EQ(m.groups.size(), 2u);
  EXPECT_EQ(m.faces(m.group(0)).size(), static_cast<std::size_t>(sphere_faces));
  EXPECT_EQ(m.faces(m.group(detail.num_vertices() - 1)),
            (std::vector<int>{sphere_faces, sphere_faces + 1, sphere_faces + 2, sphere_faces + 3}));
  // The same geometry under another connectivity (the faces' corners rotated) is matched by
  // distance: the tetrahedron, on the base sphere, is the sphere's base too.
  for (Face& f : base.faces) f = {f[1], f[2], f[0]};
  const internal::PartMatch d = internal::match_parts(detail, base.vertices, base.faces);
  EXPECT_GT(d.faces(d.group(0)).size(), static_cast<std::size_t>(sphere_faces));
}

// GroupedTrees against its reference, every part's tree searched in ascending order (the nearest
// point, the lower part's on a tie): a sphere's group holds hundreds of base parts (base-only
// debris against it, searched through the tree of the parts' boxes), and mirrored pairs of pieces
// make exact ties between parts for the queries on their mirror plane. Searching every part in
// turn made the group's queries cost its parts' count each (a review: 20.7 s for 10k vertices over
// 50,000 pieces of debris).
TEST(PartMatch, GroupedTreesFindTheNearestPartsPointAsASearchOfEveryPart) {
  TriMesh detail = test::icosphere(2);
  test::append_tetrahedron(detail, Vec3(4, 0, 0), 0.2);
  TriMesh base = test::icosphere(2, 0.9);
  test::append_tetrahedron(base, Vec3(4, 0, 0), 0.1);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 150; ++k) {
    const Vec3 d = Vec3(u(rng), u(rng), 0.3 * u(rng)).normalized();
    test::append_tetrahedron(base, 0.95 * d, 0.03);
    // Its mirror image in z = 0 (corners negated in z, faces turned to keep them outward).
    const int b = base.num_vertices();
    for (int c = 0; c < 4; ++c)
      base.vertices.push_back(base.vertices[b - 4 + c].cwiseProduct(Vec3(1, 1, -1)));
    for (int j = 0; j < 4; ++j) {
      const Face& f = base.faces[base.faces.size() - 4];
      base.faces.push_back({f[0] + 4, f[2] + 4, f[1] + 4});
    }
  }
  const internal::PartMatch m = internal::match_parts(detail, base.vertices, base.faces);
  ASSERT_FALSE(m.empty());
  const int sphere_group = m.group(0);
  ASSERT_GT(m.groups[sphere_group].size(), 200u);  // through the parts' box tree
  const internal::GroupedTrees trees(base.vertices, base.faces, m);
  std::vector<internal::TriangleTree> part_trees;
  for (const std::vector<int>& faces : m.part_faces)
    part_trees.emplace_back(base.vertices, base.faces, faces);
  int ties = 0;
  for (int g = 0; g < static_cast<int>(m.groups.size()); ++g)
    for (int q = 0; q < 3000; ++q) {
      Vec3 p(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
      if (q % 2 == 0) p.z() = 0.0;  // as near to a piece as to its mirror image
      internal::TriangleTree::Hit want;
      want.distance_sq = std::numeric_limits<double>::infinity();
      bool tie = false;
      for (int b : m.groups[g]) {
        const internal::TriangleTree::Hit h = part_trees[b].closest(p);
        tie = tie || h.distance_sq == want.distance_sq;
        if (h.distance_sq < want.distance_sq) {
          want = h;
          tie = false;
        }
      }
      ties += tie;
      const internal::TriangleTree::Hit got = trees.closest(g, p);
      ASSERT_EQ(got.face, want.face) << "group " << g << " query " << q;
      ASSERT_EQ(got.distance_sq, want.distance_sq) << "group " << g << " query " << q;
      ASSERT_EQ(got.point, want.point) << "group " << g << " query " << q;
    }
  EXPECT_GT(ties, 10);  // the tie rule is exercised
}
