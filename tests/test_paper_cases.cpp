// Tests of the Fig. 6 case generator (tools/cases): mesh validity, the normal-displacement
// property of the detail, the analytic bend and the resolution targeting.
#include <gtest/gtest.h>

#include <Eigen/Geometry>  // cross(), used by strata/mesh.h
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <vector>

#include "paper_cases.h"
#include "strata/exceptions.h"

namespace strata::cases {
namespace {

constexpr double kPi = 3.14159265358979323846;
const DetailKind kAllKinds[] = {DetailKind::Bumps, DetailKind::Rings, DetailKind::Cuboid};

CylinderCaseOptions options_for(DetailKind kind) {
  CylinderCaseOptions o;
  o.detail = kind;
  return o;
}

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

// Structural checks shared by every generated mesh: an open tube (annulus) whose only boundary is
// the two rings at z = 0 and z = length. Sorting keys instead of hashing keeps 1M-face meshes fast.
// `unbent` (if given) holds the positions before the bend, whose z values tell the ends apart.
void expect_valid_tube(const TriMesh& m, double length, const char* what,
                       const std::vector<Vec3>* unbent = nullptr) {
  SCOPED_TRACE(what);
  const std::vector<Vec3>& ends = unbent ? *unbent : m.vertices;
  ASSERT_EQ(ends.size(), m.vertices.size());
  ASSERT_GT(m.num_faces(), 0);
  const int nv = m.num_vertices();
  const double scale = bbox_diagonal(m.vertices);
  std::vector<char> used(nv, 0);
  std::vector<std::uint64_t> directed, undirected;
  directed.reserve(3 * m.faces.size());
  undirected.reserve(3 * m.faces.size());
  int bad_index = 0, tiny = 0;
  for (const Face& f : m.faces) {
    bool in_range = true;
    for (int c = 0; c < 3; ++c) in_range = in_range && f[c] >= 0 && f[c] < nv;
    if (!in_range) {
      ++bad_index;
      continue;
    }
    const Vec3& a = m.vertices[f[0]];
    const Vec3& b = m.vertices[f[1]];
    const Vec3& c = m.vertices[f[2]];
    if (!(triangle_area_normal(a, b, c).norm() > 1e-10 * scale * scale)) ++tiny;
    for (int k = 0; k < 3; ++k) {
      const int u = f[k], v = f[(k + 1) % 3];
      used[u] = 1;
      directed.push_back(edge_key(u, v));
      undirected.push_back(edge_key(std::min(u, v), std::max(u, v)));
    }
  }
  ASSERT_EQ(bad_index, 0) << "face indices out of range";
  EXPECT_EQ(tiny, 0) << "zero-area faces";
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "vertices used by no face";

  std::sort(directed.begin(), directed.end());
  EXPECT_EQ(std::adjacent_find(directed.begin(), directed.end()), directed.end())
      << "a directed edge is used twice: inconsistent orientation or duplicate face";

  std::sort(undirected.begin(), undirected.end());
  int non_manifold = 0, boundary = 0, boundary_off_ends = 0;
  std::size_t edges = 0;
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i;
    while (j < undirected.size() && undirected[j] == undirected[i]) ++j;
    ++edges;
    if (j - i > 2) ++non_manifold;
    if (j - i == 1) {
      ++boundary;
      const double za = ends[undirected[i] >> 32].z();
      const double zb = ends[undirected[i] & 0xffffffffu].z();
      const bool at_end = (za == 0.0 && zb == 0.0) || (za == length && zb == length);
      if (!at_end) ++boundary_off_ends;
    }
    i = j;
  }
  EXPECT_EQ(non_manifold, 0) << "edges shared by more than two faces";
  EXPECT_GT(boundary, 0);
  EXPECT_EQ(boundary_off_ends, 0) << "boundary edges away from the tube's two ends";
  // Euler characteristic of an annulus.
  EXPECT_EQ(static_cast<long>(nv) - static_cast<long>(edges) + m.num_faces(), 0);

  // No two vertices at the same place.
  std::vector<Vec3> sorted = m.vertices;
  std::sort(sorted.begin(), sorted.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "duplicate vertex positions";
}

TEST(PaperCasesMesh, EveryMeshIsAValidOrientedTube) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCaseOptions o = options_for(kind);
    const CylinderCase c = make_cylinder_case(o);
    expect_valid_tube(c.detail, o.length, "detail");
    expect_valid_tube(c.base, o.length, "base");
    // The bent tail's end is no longer at z = length: tell the ends apart by S's z values.
    expect_valid_tube(c.edited_base, o.length, "edited base", &c.base.vertices);
    EXPECT_EQ(c.edited_base.faces, c.base.faces);
  }
}

TEST(PaperCasesMesh, EditedBaseIsTheBentBase) {
  const CylinderCaseOptions o;
  const CylinderCase c = make_cylinder_case(o);
  ASSERT_EQ(c.edited_base.faces, c.base.faces);
  ASSERT_EQ(c.edited_base.num_vertices(), c.base.num_vertices());
  for (int i = 0; i < c.base.num_vertices(); ++i)
    EXPECT_EQ(c.edited_base.vertices[i], bend_point(c.base.vertices[i], o)) << "vertex " << i;
  // No zero-area faces after the bend either, and the faces keep their orientation (below).
  const double scale = bbox_diagonal(c.edited_base.vertices);
  for (const Face& f : c.edited_base.faces) {
    const Vec3 n = triangle_area_normal(c.edited_base.vertices[f[0]], c.edited_base.vertices[f[1]],
                                        c.edited_base.vertices[f[2]]);
    EXPECT_GT(n.norm(), 1e-10 * scale * scale);
  }
}

TEST(PaperCasesDefaults, SizesNamesAndFoldingBend) {
  const CylinderCaseOptions defaults;
  EXPECT_DOUBLE_EQ(defaults.effective_bend_end(), 2.0 + 1.2 * kPi / 2.0);
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCase c = make_cylinder_case(options_for(kind));
    // The documented base size: 48 around, 54 rings.
    EXPECT_EQ(c.base.num_vertices(), 48 * 54);
    EXPECT_EQ(c.base.num_faces(), 2 * 48 * 53);
    EXPECT_EQ(c.detail.num_vertices() % 96, 0);  // 96 detail vertices around
    EXPECT_NE(c.detail.num_vertices(), c.base.num_vertices());
    EXPECT_DOUBLE_EQ(c.inner_bend_radius, 0.2);
    // The point of the case: the inner side of the bend is tighter than the detail is high.
    EXPECT_LT(c.inner_bend_radius, c.max_detail_height);
    double max_h = 0.0;
    for (const Vec3& p : c.detail.vertices) max_h = std::max(max_h, std::hypot(p.x(), p.y()) - 1.0);
    EXPECT_DOUBLE_EQ(c.max_detail_height, max_h);
    std::printf("[ sizes    ] %-15s detail %6d vertices %6d faces, base %d vertices %d faces, max h %.4f\n",
                c.name.c_str(), c.detail.num_vertices(), c.detail.num_faces(), c.base.num_vertices(),
                c.base.num_faces(), c.max_detail_height);
  }
  EXPECT_EQ(make_cylinder_case(options_for(DetailKind::Bumps)).name, "cylinder-bumps");
  EXPECT_EQ(make_cylinder_case(options_for(DetailKind::Rings)).name, "cylinder-rings");
  EXPECT_EQ(make_cylinder_case(options_for(DetailKind::Cuboid)).name, "cuboid");
  // The cuboid's corners are vertices: its largest offset is the corner's.
  EXPECT_NEAR(make_cylinder_case(options_for(DetailKind::Cuboid)).max_detail_height,
              1.35 * std::sqrt(2.0) - 1.0, 1e-12);
}

TEST(PaperCasesDefaults, DetailKindNamesRoundTrip) {
  for (DetailKind kind : kAllKinds) EXPECT_EQ(parse_detail_kind(to_string(kind)), kind);
  EXPECT_FALSE(parse_detail_kind("Bumps").has_value());
  EXPECT_FALSE(parse_detail_kind("").has_value());
}

TEST(PaperCasesDetail, VerticesAreNormalDisplacementsOfTheAnalyticCylinder) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCaseOptions o = options_for(kind);
    const CylinderCase c = make_cylinder_case(o);
    double min_h = 1e300, max_h = 0.0;
    int mismatched = 0;
    for (const Vec3& p : c.detail.vertices) {
      const double theta = std::atan2(p.y(), p.x());
      const double r = std::hypot(p.x(), p.y());
      const double h = detail_offset(o, theta, p.z());
      // p = q + h n(q) with q = R (cos theta, sin theta, z) and n(q) = (cos theta, sin theta, 0).
      const Vec3 q(o.radius * std::cos(theta), o.radius * std::sin(theta), p.z());
      const Vec3 n(std::cos(theta), std::sin(theta), 0.0);
      if (std::abs(r - o.radius - h) > 1e-12 || (q + h * n - p).norm() > 1e-12) ++mismatched;
      min_h = std::min(min_h, h);
      max_h = std::max(max_h, h);
      EXPECT_GE(p.z(), 0.0);
      EXPECT_LE(p.z(), o.length);
    }
    EXPECT_EQ(mismatched, 0);
    EXPECT_GT(min_h, 0.0);
    if (kind == DetailKind::Cuboid) {
      // The middles of the sides are vertices (24 segments per side), where the offset is smallest.
      EXPECT_NEAR(min_h, o.detail_height, 1e-12);
    } else {
      EXPECT_GE(min_h, 0.5 * o.detail_height - 1e-12);
      EXPECT_LE(max_h, 1.5 * o.detail_height + 1e-12);
      EXPECT_GT(max_h - min_h, 0.5 * o.detail_height);  // the pattern is really there
    }
  }
}

TEST(PaperCasesDetail, OffsetIsAlwaysPositiveAndHasTheDocumentedMean) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCaseOptions o = options_for(kind);
    double sum = 0.0, min_h = 1e300;
    const int n = 720, m = 600;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < n; ++j) {
        const double h = detail_offset(o, 2.0 * kPi * j / n, o.length * i / m);
        sum += h;
        min_h = std::min(min_h, h);
      }
    EXPECT_GT(min_h, 0.0);
    if (kind != DetailKind::Cuboid) {
      EXPECT_NEAR(sum / (n * m), o.detail_height, 1e-9);
    }
  }
}

TEST(PaperCasesDetail, CuboidSidesAreFlatWithSharpCorners) {
  const CylinderCaseOptions o = options_for(DetailKind::Cuboid);
  const CylinderCase c = make_cylinder_case(o);
  const double a = o.radius + o.detail_height;
  int corners = 0;
  for (const Vec3& p : c.detail.vertices) {
    // Every vertex lies exactly on one of the four side planes.
    EXPECT_TRUE(std::abs(p.x()) == a || std::abs(p.y()) == a) << p.transpose();
    if (std::abs(p.x()) == a && std::abs(p.y()) == a) ++corners;
  }
  const int rings = c.detail.num_vertices() / 96;
  EXPECT_EQ(corners, 4 * rings);
  // Every face is flat on one side: its three vertices share the constant coordinate.
  for (const Face& f : c.detail.faces) {
    const Vec3& p0 = c.detail.vertices[f[0]];
    const Vec3& p1 = c.detail.vertices[f[1]];
    const Vec3& p2 = c.detail.vertices[f[2]];
    const bool same_x = p0.x() == p1.x() && p1.x() == p2.x() && std::abs(p0.x()) == a;
    const bool same_y = p0.y() == p1.y() && p1.y() == p2.y() && std::abs(p0.y()) == a;
    EXPECT_TRUE(same_x || same_y);
  }
}

// Ray/triangle intersection (Moeller-Trumbore) with a small tolerance on the barycentrics, so rays
// through shared edges or along the tube's end rings still hit.
bool ray_hits(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c, double* t) {
  const Vec3 e1 = b - a, e2 = c - a, pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) < 1e-300) return false;
  const Vec3 tv = o - a;
  const double u = tv.dot(pv) / det;
  const Vec3 qv = tv.cross(e1);
  const double v = d.dot(qv) / det;
  const double eps = 1e-9;
  if (u < -eps || v < -eps || u + v > 1.0 + eps) return false;
  *t = e2.dot(qv) / det;
  return true;
}

TEST(PaperCasesDetail, ProjectionAlongTheNormalHitsTheTriangulatedBaseNearTheAnalyticPoint) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCaseOptions o = options_for(kind);
    const CylinderCase c = make_cylinder_case(o);
    // Bucket base faces by z so each ray tests a few rings only.
    const double cell = 0.25;
    std::map<int, std::vector<int>> buckets;
    for (int f = 0; f < c.base.num_faces(); ++f) {
      double lo = 1e300, hi = -1e300;
      for (int k = 0; k < 3; ++k) {
        lo = std::min(lo, c.base.vertices[c.base.faces[f][k]].z());
        hi = std::max(hi, c.base.vertices[c.base.faces[f][k]].z());
      }
      for (int b = static_cast<int>(std::floor(lo / cell)) - 1;
           b <= static_cast<int>(std::floor(hi / cell)) + 1; ++b)
        buckets[b].push_back(f);
    }
    // The triangulated base lies inside the analytic cylinder, at most a sagitta below it.
    const double sagitta = o.radius * (1.0 - std::cos(kPi / o.base_segments));
    int missed = 0;
    double worst = 0.0;
    for (const Vec3& p : c.detail.vertices) {
      const double theta = std::atan2(p.y(), p.x());
      const double h = std::hypot(p.x(), p.y()) - o.radius;
      const Vec3 n(std::cos(theta), std::sin(theta), 0.0);
      const Vec3 q = p - h * n;
      double best = -1.0;
      for (int f : buckets[static_cast<int>(std::floor(p.z() / cell))]) {
        double t;
        const Face& fc = c.base.faces[f];
        if (ray_hits(p, -n, c.base.vertices[fc[0]], c.base.vertices[fc[1]], c.base.vertices[fc[2]], &t) &&
            t > 0 && (best < 0 || t < best))
          best = t;
      }
      if (best < 0) {
        ++missed;
        continue;
      }
      // The hit is on the same ray, between q and the sagitta below it.
      EXPECT_GE(best, h - 1e-12);
      worst = std::max(worst, (p - best * n - q).norm());
    }
    EXPECT_EQ(missed, 0);
    EXPECT_LE(worst, sagitta + 1e-12);
  }
}

TEST(PaperCasesOrientation, FaceNormalsPointAwayFromTheAxis) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    const CylinderCaseOptions o = options_for(kind);
    const CylinderCase c = make_cylinder_case(o);
    for (const TriMesh* m : {&c.detail, &c.base}) {
      int inward = 0;
      for (const Face& f : m->faces) {
        const Vec3 &a = m->vertices[f[0]], &b = m->vertices[f[1]], &d = m->vertices[f[2]];
        const Vec3 centroid = (a + b + d) / 3.0;
        const Vec3 radial(centroid.x(), centroid.y(), 0.0);
        const Vec3 n = triangle_area_normal(a, b, d).normalized();
        if (!(n.dot(radial.normalized()) > 0.5)) ++inward;
      }
      EXPECT_EQ(inward, 0) << (m == &c.detail ? "detail" : "base");
    }
    // S': away from the bent axis, whose point at height z is bend_point((0, 0, z)).
    int inward = 0;
    for (const Face& f : c.edited_base.faces) {
      const Vec3 centroid = (c.base.vertices[f[0]] + c.base.vertices[f[1]] + c.base.vertices[f[2]]) / 3.0;
      const Vec3 radial = bend_point(centroid, o) - bend_point(Vec3(0.0, 0.0, centroid.z()), o);
      const Vec3 n = triangle_area_normal(c.edited_base.vertices[f[0]], c.edited_base.vertices[f[1]],
                                          c.edited_base.vertices[f[2]])
                         .normalized();
      if (!(n.dot(radial.normalized()) > 0.5)) ++inward;
    }
    EXPECT_EQ(inward, 0) << "edited base";
  }
}

TEST(PaperCasesBend, StraightPartBeforeTheBendIsUnchanged) {
  const CylinderCaseOptions o;
  const CylinderCase c = make_cylinder_case(o);
  int before = 0;
  for (int i = 0; i < c.base.num_vertices(); ++i)
    if (c.base.vertices[i].z() <= o.bend_start) {
      ++before;
      EXPECT_EQ(c.edited_base.vertices[i], c.base.vertices[i]);
    }
  EXPECT_GT(before, 0);
  EXPECT_EQ(bend_point(Vec3(-7.0, 3.0, o.bend_start), o), Vec3(-7.0, 3.0, o.bend_start));
}

TEST(PaperCasesBend, PartBeyondTheBendIsRigidlyMoved) {
  const CylinderCaseOptions o;
  const CylinderCase c = make_cylinder_case(o);
  const double end = o.effective_bend_end();
  std::vector<int> beyond;
  for (int i = 0; i < c.base.num_vertices(); ++i)
    if (c.base.vertices[i].z() >= end) beyond.push_back(i);
  ASSERT_GT(beyond.size(), 100u);
  // Pairwise distances among a spread-out sample are preserved...
  std::vector<int> sample;
  for (std::size_t k = 0; k < beyond.size(); k += beyond.size() / 150) sample.push_back(beyond[k]);
  const auto& P = c.base.vertices;
  const auto& Q = c.edited_base.vertices;
  double worst = 0.0;
  for (int i : sample)
    for (int j : sample) worst = std::max(worst, std::abs((Q[i] - Q[j]).norm() - (P[i] - P[j]).norm()));
  EXPECT_LT(worst, 1e-12);
  // ...and so is handedness (a rotation, not a reflection).
  const int a = sample[0], b = sample[sample.size() / 3], d = sample[2 * sample.size() / 3],
            e = sample.back();
  const double before = (P[b] - P[a]).cross(P[d] - P[a]).dot(P[e] - P[a]);
  const double after = (Q[b] - Q[a]).cross(Q[d] - Q[a]).dot(Q[e] - Q[a]);
  EXPECT_NEAR(after, before, 1e-12 * std::abs(before) + 1e-12);
  // The end of the axis after a 90-degree bend towards +x: the arc's end, then straight along +x.
  const Vec3 axis_end = bend_point(Vec3(0.0, 0.0, o.length), o);
  EXPECT_NEAR((axis_end - Vec3(o.bend_radius + (o.length - end), 0.0, o.bend_start + o.bend_radius)).norm(),
              0.0, 1e-12);
}

TEST(PaperCasesBend, AxisKeepsItsLengthAndTheBendIsSmooth) {
  const CylinderCaseOptions o;
  const int n = 6000;
  double total = 0.0, worst_step = 0.0;
  Vec3 prev = bend_point(Vec3(0.0, 0.0, 0.0), o);
  for (int i = 1; i <= n; ++i) {
    const double dz = o.length / n;
    const Vec3 cur = bend_point(Vec3(0.0, 0.0, o.length * i / n), o);
    total += (cur - prev).norm();
    worst_step = std::max(worst_step, std::abs((cur - prev).norm() - dz) / dz);
    prev = cur;
  }
  EXPECT_NEAR(total, o.length, 1e-6);
  EXPECT_LT(worst_step, 1e-6);  // chords of a 1.2-radius arc, 0.001 long
  // C1 across both ends of the bend: the tangent of the axis is continuous.
  const double eps = 1e-6;
  for (double z : {o.bend_start, o.effective_bend_end()}) {
    const Vec3 left = (bend_point(Vec3(0, 0, z), o) - bend_point(Vec3(0, 0, z - eps), o)) / eps;
    const Vec3 right = (bend_point(Vec3(0, 0, z + eps), o) - bend_point(Vec3(0, 0, z), o)) / eps;
    EXPECT_NEAR((left - right).norm(), 0.0, 1e-5) << "at z = " << z;
    EXPECT_NEAR(right.norm(), 1.0, 1e-6);
  }
  // The tangent turns by the bend angle: from +z to +x.
  const double end = o.effective_bend_end();
  const Vec3 t = (bend_point(Vec3(0, 0, end + 1.0), o) - bend_point(Vec3(0, 0, end), o));
  EXPECT_NEAR((t - Vec3(1.0, 0.0, 0.0)).norm(), 0.0, 1e-12);
}

TEST(PaperCasesBend, InnerAndOuterSidesFollowArcsAroundTheBendCentre) {
  const CylinderCaseOptions o;
  const Vec3 centre(o.bend_radius, 0.0, o.bend_start);
  const double end = o.effective_bend_end();
  for (int i = 0; i <= 50; ++i) {
    const double z = o.bend_start + (end - o.bend_start) * i / 50;
    for (double y : {-0.5, 0.0, 0.5}) {
      const Vec3 inner = bend_point(Vec3(o.radius, y, z), o);
      const Vec3 outer = bend_point(Vec3(-o.radius, y, z), o);
      EXPECT_NEAR(inner.y(), y, 1e-15);
      EXPECT_NEAR((inner - Vec3(centre.x(), y, centre.z())).norm(), o.bend_radius - o.radius, 1e-12);
      EXPECT_NEAR((outer - Vec3(centre.x(), y, centre.z())).norm(), o.bend_radius + o.radius, 1e-12);
    }
  }
}

TEST(PaperCasesBend, BaseEdgeLengths) {
  const CylinderCaseOptions o;
  const CylinderCase c = make_cylinder_case(o);
  const double start = o.bend_start, end = o.effective_bend_end(), br = o.bend_radius;
  const auto& P = c.base.vertices;
  const auto& Q = c.edited_base.vertices;
  int straight = 0, bent = 0;
  for (const Face& f : c.base.faces)
    for (int k = 0; k < 3; ++k) {
      const int u = f[k], v = f[(k + 1) % 3];
      const double before = (P[u] - P[v]).norm(), after = (Q[u] - Q[v]).norm();
      const double zlo = std::min(P[u].z(), P[v].z()), zhi = std::max(P[u].z(), P[v].z());
      if (zhi <= start || zlo >= end) {
        ++straight;
        EXPECT_NEAR(after, before, 1e-12);  // exact in the straight parts
      } else {
        ++bent;
        // Inside the bend lengths along z scale by (br - x) / br and across them by 1.
        const double s_u = (br - P[u].x()) / br, s_v = (br - P[v].x()) / br;
        const double lo = std::min({1.0, s_u, s_v}), hi = std::max({1.0, s_u, s_v});
        EXPECT_GE(after / before, 0.99 * lo);
        EXPECT_LE(after / before, 1.01 * hi);
      }
    }
  EXPECT_GT(straight, 0);
  EXPECT_GT(bent, 0);
  // On the neutral plane x = 0 (theta = 90 and 270 degrees, on the unshifted rings) distances
  // along z become chords of the axis arc: within a fraction of a percent for neighbours.
  std::map<int, std::vector<int>> columns;  // sign of y -> vertices, by increasing z
  for (int i = 0; i < c.base.num_vertices(); ++i)
    if (std::abs(P[i].x()) < 1e-12) columns[P[i].y() > 0 ? 1 : -1].push_back(i);
  ASSERT_EQ(columns.size(), 2u);
  for (const auto& [key, ids] : columns) {
    ASSERT_GT(ids.size(), 10u);
    for (std::size_t k = 1; k < ids.size(); ++k) {
      const int u = ids[k - 1], v = ids[k];
      const double dz = std::abs(P[v].z() - P[u].z());
      const double after = (Q[u] - Q[v]).norm();
      EXPECT_NEAR(after, dz, 0.01 * dz);
      if (P[u].z() >= start && P[v].z() <= end) {
        EXPECT_NEAR(after, 2.0 * br * std::sin(dz / (2.0 * br)), 1e-12);
      }
    }
  }
}

TEST(PaperCasesBend, ZeroDegreesIsTheIdentity) {
  CylinderCaseOptions o;
  o.bend_degrees = 0.0;
  EXPECT_EQ(o.effective_bend_end(), o.bend_start);
  for (double z : {0.0, 1.0, 2.0, 2.5, 5.0})
    EXPECT_NEAR((bend_point(Vec3(0.3, -0.7, z), o) - Vec3(0.3, -0.7, z)).norm(), 0.0, 1e-15);
}

TEST(PaperCasesOptions, OutOfRangeOptionsThrow) {
  auto throws = [](auto change) {
    CylinderCaseOptions o;
    change(o);
    EXPECT_THROW(make_cylinder_case(o), InvalidInput);
  };
  throws([](CylinderCaseOptions& o) { o.radius = 0.0; });
  throws([](CylinderCaseOptions& o) { o.length = -1.0; });
  throws([](CylinderCaseOptions& o) { o.base_segments = 2; });
  throws([](CylinderCaseOptions& o) { o.detail_segments = 2; });
  throws([](CylinderCaseOptions& o) { o.detail_height = 0.0; });
  throws([](CylinderCaseOptions& o) { o.detail_height = std::nan(""); });
  throws([](CylinderCaseOptions& o) { o.bend_degrees = -10.0; });
  throws([](CylinderCaseOptions& o) { o.bend_degrees = 400.0; });
  throws([](CylinderCaseOptions& o) { o.bend_radius = 1.0; });  // = radius: S' would fold
  throws([](CylinderCaseOptions& o) { o.bend_end = 4.5; });     // not the arc length
  throws([](CylinderCaseOptions& o) { o.target_detail_triangles = -5; });
  throws([](CylinderCaseOptions& o) { o.jitter = -0.1; });
  throws([](CylinderCaseOptions& o) { o.jitter = 0.5; });
  throws([](CylinderCaseOptions& o) { o.jitter = std::nan(""); });
  CylinderCaseOptions flat;
  flat.bend_radius = 0.0;
  EXPECT_THROW(bend_point(Vec3::Zero(), flat), InvalidInput);
  // A bend_end that matches the derived one is accepted.
  CylinderCaseOptions o;
  o.bend_end = o.effective_bend_end();
  EXPECT_NO_THROW(make_cylinder_case(o));
}

TEST(PaperCasesOptions, CuboidSegmentsRoundToMultiplesOfFour) {
  CylinderCaseOptions o = options_for(DetailKind::Cuboid);
  for (int n : {3, 4, 50, 97}) {
    o.detail_segments = n;
    const CylinderCase c = make_cylinder_case(o);
    const int expected = std::max(4, static_cast<int>(std::lround(n / 4.0)) * 4);
    EXPECT_EQ(c.detail.num_vertices() % expected, 0) << n;
    expect_valid_tube(c.detail, o.length, "detail");
  }
}

TEST(PaperCasesOptions, OtherParametersStillGiveValidCases) {
  for (DetailKind kind : kAllKinds) {
    CylinderCaseOptions o = options_for(kind);
    o.radius = 0.5;
    o.length = 3.0;
    o.base_segments = 5;
    o.detail_segments = 7;
    o.detail_height = 0.1;
    o.bend_degrees = 180.0;
    o.bend_radius = 2.0;
    o.bend_start = 0.5;
    SCOPED_TRACE(to_string(kind));
    const CylinderCase c = make_cylinder_case(o);
    expect_valid_tube(c.detail, o.length, "detail");
    expect_valid_tube(c.base, o.length, "base");
    EXPECT_DOUBLE_EQ(c.inner_bend_radius, 1.5);
    for (const Vec3& p : c.detail.vertices) EXPECT_GT(std::hypot(p.x(), p.y()) - o.radius, 0.0);
  }
}

TEST(PaperCasesTarget, DetailTriangleCountFollowsTheTarget) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    for (int target : {1000, 10000, 100000}) {
      CylinderCaseOptions o = options_for(kind);
      o.target_detail_triangles = target;
      const CylinderCase c = make_cylinder_case(o);
      EXPECT_NEAR(c.detail.num_faces(), target, 0.2 * target) << target;
      if (target == 100000) expect_valid_tube(c.detail, o.length, "detail");
      std::printf("[ target   ] %-15s asked %7d got %7d\n", c.name.c_str(), target, c.detail.num_faces());
    }
  }
}

TEST(PaperCasesTarget, OneMillionPrisms) {
  // Generating the 1M-triangle detail takes a small fraction of a second (printed below).
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    CylinderCaseOptions o = options_for(kind);
    o.target_detail_triangles = 1000000;
    const auto t0 = std::chrono::steady_clock::now();
    const CylinderCase c = make_cylinder_case(o);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_NEAR(c.detail.num_faces(), 1000000, 200000);
    std::printf("[ target   ] %-15s asked 1000000 got %7d in %.3f s\n", c.name.c_str(), c.detail.num_faces(),
                seconds);
  }
}

// The scan-like variant (jitter): the same surfaces, an irregular Delaunay triangulation. It stays a
// valid oriented tube on the analytic detail surface with the same counts, its valences vary as a
// scan's (no global checkerboard of up and down triangles), the cuboid keeps its flat sides and
// sharp corners, and it is the same every time.
TEST(PaperCasesJitter, IrregularValidDeterministicTubesOnTheSameSurfaces) {
  for (DetailKind kind : kAllKinds) {
    SCOPED_TRACE(to_string(kind));
    CylinderCaseOptions o = options_for(kind);
    const CylinderCase regular = make_cylinder_case(o);
    o.jitter = 0.4;
    const CylinderCase c = make_cylinder_case(o);
    expect_valid_tube(c.detail, o.length, "jittered detail");
    EXPECT_EQ(c.detail.num_vertices(), regular.detail.num_vertices());
    EXPECT_EQ(c.detail.num_faces(), regular.detail.num_faces());
    EXPECT_EQ(c.base.vertices, regular.base.vertices);
    EXPECT_EQ(c.edited_base.vertices, regular.edited_base.vertices);
    const CylinderCase again = make_cylinder_case(o);
    EXPECT_EQ(again.detail.vertices, c.detail.vertices);
    EXPECT_EQ(again.detail.faces, c.detail.faces);

    std::vector<int> valence(c.detail.num_vertices(), 0);
    for (const Face& f : c.detail.faces)
      for (int v : f) ++valence[v];
    int interior = 0, odd = 0, moved = 0;
    for (int v = 0; v < c.detail.num_vertices(); ++v) {
      const double z = c.detail.vertices[v].z();
      if (z == 0.0 || z == o.length) continue;
      ++interior;
      odd += valence[v] % 2;
      moved += (c.detail.vertices[v] - regular.detail.vertices[v]).norm() > 1e-9;
    }
    EXPECT_GT(odd, interior / 4) << "odd valences (a regular grid has none inside)";
    EXPECT_GT(moved, interior * 9 / 10);
    for (const Vec3& p : c.detail.vertices) {
      if (kind == DetailKind::Cuboid) {
        const double a = o.radius + o.detail_height;
        EXPECT_TRUE(std::abs(p.x()) == a || std::abs(p.y()) == a) << p.transpose();
      } else {
        const double h = detail_offset(o, std::atan2(p.y(), p.x()), p.z());
        EXPECT_NEAR(std::hypot(p.x(), p.y()), o.radius + h, 1e-12);
      }
    }
    if (kind == DetailKind::Cuboid) {
      // The corner columns stay, and every face lies flat on one side.
      const double a = o.radius + o.detail_height;
      int corners = 0;
      for (const Vec3& p : c.detail.vertices) corners += std::abs(p.x()) == a && std::abs(p.y()) == a;
      EXPECT_EQ(corners, 4 * (c.detail.num_vertices() / 96));
      for (const Face& f : c.detail.faces) {
        const Vec3 &p0 = c.detail.vertices[f[0]], &p1 = c.detail.vertices[f[1]],
                   &p2 = c.detail.vertices[f[2]];
        EXPECT_TRUE((p0.x() == p1.x() && p1.x() == p2.x() && std::abs(p0.x()) == a) ||
                    (p0.y() == p1.y() && p1.y() == p2.y() && std::abs(p0.y()) == a));
      }
    }
  }
}

}  // namespace
}  // namespace strata::cases
