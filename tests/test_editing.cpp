// The editing operator (paper, section 5): selections, blended transforms, the region
// decomposition, exact edits and drags, and edit scripts.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <string>

#include "paper_cases.h"
#include "strata/edit_script.h"
#include "strata/editing.h"
#include "strata/exceptions.h"
#include "strata/intersections.h"
#include "test_meshes.h"

using namespace strata;
using strata::test::max_distance;

namespace {

// The paper's bumpy cylinder (detail only): an open tube along z from 0 to 6, radius about 1.35.
TriMesh bumpy_cylinder(int triangles) {
  cases::CylinderCaseOptions o;
  o.detail = cases::DetailKind::Bumps;
  o.target_detail_triangles = triangles;
  return cases::make_cylinder_case(o).detail;
}

// A smooth open cylinder of radius 1 along z from 0 to 6.
TriMesh smooth_cylinder() {
  return cases::make_cylinder_case({}).base;
}

std::vector<char> above(const TriMesh& m, double z) {
  return select_vertices(m.vertices, Selection::halfspace(Vec3(0, 0, z), Vec3::UnitZ()));
}

// A 90-degree bend of everything above z = 2 towards +x, the handle above z = 3.5.
struct Bend {
  std::vector<char> region, handle;
  EditTransform transform;
};
Bend elbow(const TriMesh& m, double degrees = 90.0) {
  return {above(m, 2.0), above(m, 3.5), EditTransform::rotation(Vec3::UnitY(), degrees, Vec3(1.2, 0, 2.5))};
}

// A flat grid in the plane z = 0 over [0,1]^2, with ripples of amplitude h and wavelength 0.1
// in the disc of radius 0.3 about the centre.
TriMesh rippled_grid(int k, double h) {
  TriMesh m;
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= k; ++i) {
      const double x = double(i) / k, y = double(j) / k;
      const double r2 = (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5);
      m.vertices.emplace_back(x, y, r2 < 0.09 ? h * std::sin(20 * M_PI * x) * std::sin(20 * M_PI * y) : 0.0);
    }
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const int a = j * (k + 1) + i, b = a + 1, c = a + k + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  return m;
}

}  // namespace

TEST(Selection, EvaluatesEachKindOnPositions) {
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, -1)};
  EXPECT_EQ(select_vertices(x, Selection::sphere(Vec3::Zero(), 1.0)), (std::vector<char>{1, 1, 0, 1}));
  EXPECT_EQ(select_vertices(x, Selection::halfspace(Vec3(0, 1, 0), Vec3(0, 1, 0))),
            (std::vector<char>{0, 0, 1, 0}));
  EXPECT_EQ(select_vertices(x, Selection::box(Vec3(-0.5, -0.5, -2), Vec3(1, 0.5, 0))),
            (std::vector<char>{1, 1, 0, 1}));
  EXPECT_EQ(select_vertices(x, Selection::vertices({2, 0})), (std::vector<char>{1, 0, 1, 0}));
}

TEST(Selection, RejectsMalformedSelections) {
  const std::vector<Vec3> x = {Vec3(0, 0, 0)};
  EXPECT_THROW(select_vertices(x, Selection::sphere(Vec3::Zero(), -1.0)), InvalidInput);
  EXPECT_THROW(select_vertices(x, Selection::sphere(Vec3(NAN, 0, 0), 1.0)), InvalidInput);
  EXPECT_THROW(select_vertices(x, Selection::halfspace(Vec3::Zero(), Vec3::Zero())), InvalidInput);
  EXPECT_THROW(select_vertices(x, Selection::box(Vec3(1, 0, 0), Vec3(0, 1, 1))), InvalidInput);
  EXPECT_THROW(select_vertices(x, Selection::vertices({1})), InvalidInput);
  EXPECT_THROW(select_vertices(x, Selection::vertices({-1})), InvalidInput);
}

// Radii and centres whose squares overflow (a review, thirty-eighth session: a sphere of radius
// 1e200 about 1e300 selected every vertex near the origin, inf <= inf).
TEST(Selection, HugeSpheresSelectByTheirDistance) {
  const std::vector<Vec3> x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1e300, 0, 0), Vec3(-1e300, 0, 0)};
  EXPECT_EQ(select_vertices(x, Selection::sphere(Vec3(1e300, 0, 0), 1e200)), (std::vector<char>{0, 0, 1, 0}));
  EXPECT_EQ(select_vertices(x, Selection::sphere(Vec3(1e160, 0, 0), 1e155)), (std::vector<char>{0, 0, 0, 0}));
  EXPECT_EQ(select_vertices(x, Selection::sphere(Vec3::Zero(), 1e200)), (std::vector<char>{1, 1, 0, 0}));
  EXPECT_EQ(select_vertices(x, Selection::sphere(Vec3::Zero(), 1.5e300)), (std::vector<char>{1, 1, 1, 1}));
}

// Whole turns are dropped before the angle is taken in radians: 1e308 degrees overflowed to a
// NaN matrix, and a huge angle in radians lost its digits.
TEST(EditTransform, HugeAnglesAreTakenModuloATurn) {
  const Vec3 axis(0, 0, 1), pivot(1, 2, 3);
  for (double degrees : {1e308, -1e308, 1e20}) {
    const EditTransform t = EditTransform::rotation(axis, degrees, pivot);
    ASSERT_TRUE(t.linear.allFinite()) << degrees;
    EXPECT_LT((t.linear * t.linear.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((t.linear - EditTransform::rotation(axis, std::fmod(degrees, 360.0), pivot).linear)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-15);
  }
  EXPECT_EQ(EditTransform::rotation(axis, 360.0 * 1e10 + 90.0, pivot).linear,
            EditTransform::rotation(axis, 90.0, pivot).linear);
}

TEST(EditTransform, BlendScalesTheRotationAngleAndTheTranslation) {
  const Vec3 pivot(1, 2, 3), t(0.5, -1, 2);
  const EditTransform T = EditTransform::rotation(Vec3(0, 0, 2), 90.0, pivot, t);
  const Vec3 x(2, 2, 3);
  EXPECT_LT((T.apply_blended(x, 0.0) - x).norm(), 1e-15);
  EXPECT_LT((T.apply_blended(x, 1.0) - T.apply(x)).norm(), 1e-12);
  EXPECT_LT((T.apply(x) - (pivot + Vec3(0, 1, 0) + t)).norm(), 1e-12);
  // Half the blend: 45 degrees about the pivot, half the translation; the distance to the
  // pivot's axis is kept (a rotation, not a linear mix of positions that would shorten it).
  const Vec3 half = T.apply_blended(x, 0.5) - 0.5 * t;
  EXPECT_LT((half - (pivot + Vec3(std::sqrt(0.5), std::sqrt(0.5), 0))).norm(), 1e-12);
}

// A turn past 180 degrees is blended along its own way: the linear part alone gives only the
// short way (270 degrees at weight 0.5 turned -45; a drag through 180 degrees flipped the bend;
// found by a review, 2026-11-30). By rotation(), by a script, scaled, and as partial().
TEST(EditTransform, BlendFollowsATurnPast180Degrees) {
  const Vec3 pivot(1, 2, 3), x(2, 2, 3);
  auto turned = [&](double degrees) {
    const double a = degrees * M_PI / 180.0;
    return Vec3(pivot + Vec3(std::cos(a), std::sin(a), 0));
  };
  for (double degrees : {190.0, 270.0, 359.0, -270.0}) {
    const EditTransform T = EditTransform::rotation(Vec3(0, 0, 1), degrees, pivot);
    EXPECT_LT((T.apply_blended(x, 0.5) - turned(degrees / 2)).norm(), 1e-12) << degrees;
    EXPECT_LT((T.partial(0.5).apply(x) - turned(degrees / 2)).norm(), 1e-12) << degrees;
    EXPECT_LT((T.partial(0.25).partial(2.0).apply(x) - turned(degrees / 2)).norm(), 1e-12) << degrees;
    EXPECT_LT((T.partial(1.0).apply(x) - T.apply(x)).norm(), 0.0 + 1e-15) << degrees;
    const std::string script = R"({"region": {"vertices": [0]}, "handle": {"vertices": [0]},
        "transform": {"rotate": {"axis": [0, 0, 3], "degrees": )" +
                               std::to_string(degrees) + R"(, "pivot": [1, 2, 3]}, "scale": 2}})";
    const EditTransform parsed = parse_edit_script(script, "s.json").edits.at(0).transform;
    const Vec3 half = parsed.apply_blended(x, 0.5);  // scaled by 1.5 from the pivot
    EXPECT_LT((half - (pivot + 1.5 * (turned(degrees / 2) - pivot))).norm(), 1e-12) << degrees;
  }
  // A linear part that is not the recorded rotation (changed after): the short way, as before.
  EditTransform T = EditTransform::rotation(Vec3(0, 0, 1), 270.0, pivot);
  T.linear = EditTransform::rotation(Vec3(1, 0, 0), 30.0, pivot).linear;
  const Eigen::AngleAxisd half(M_PI / 12, Vec3(1, 0, 0));
  EXPECT_LT((T.apply_blended(x, 0.5) - (pivot + half * (x - pivot))).norm(), 1e-12);
}

TEST(EditTransform, BlendInterpolatesAStretchFromTheIdentity) {
  EditTransform T;
  T.linear = Eigen::Vector3d(2.0, 1.0, 1.0).asDiagonal();
  const Vec3 x(1, 1, 1);
  EXPECT_LT((T.apply_blended(x, 0.5) - Vec3(1.5, 1, 1)).norm(), 1e-12);
}

TEST(RegionEditor, RejectsBadSelections) {
  const TriMesh m = bumpy_cylinder(2000);
  const std::vector<char> none(m.num_vertices(), 0), all(m.num_vertices(), 1);
  const std::vector<char> region = above(m, 2.0), handle = above(m, 4.0);
  EXPECT_THROW(RegionEditor(m, none, handle), InvalidInput);                     // empty region
  EXPECT_THROW(RegionEditor(m, region, none), InvalidInput);                     // empty handle
  EXPECT_THROW(RegionEditor(m, region, above(m, -1.0)), InvalidInput);           // handle = region
  EXPECT_THROW(RegionEditor(m, all, handle), InvalidInput);                      // nothing fixed
  EXPECT_THROW(RegionEditor(m, std::vector<char>(3, 1), handle), InvalidInput);  // size mismatch
  // A region that does not reach the handle: its handle flags select no region vertex.
  EXPECT_THROW(RegionEditor(m, region,
                            select_vertices(m.vertices, Selection::halfspace(Vec3(0, 0, 1), -Vec3::UnitZ()))),
               InvalidInput);
  RegionEditor ok(m, region, handle);
  EXPECT_THROW(ok.update_drag(EditTransform{}), InvalidInput);  // no drag begun
  EditTransform flip;
  flip.linear = Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal();
  EXPECT_THROW(ok.apply(flip), InvalidInput);  // a reflection cannot be blended
  // Coordinates beyond the engine's range.
  TriMesh far = m;
  far.vertices[0].x() = 1e25;
  EXPECT_THROW(RegionEditor(far, region, handle), InvalidInput);
  // The mesh precondition, checked (an out-of-range face index crashed the adjacency), and a
  // NaN named as the editor's mesh (it was "edited mesh").
  TriMesh bad_index = m;
  bad_index.faces[7][1] = m.num_vertices();
  EXPECT_THROW(RegionEditor(bad_index, region, handle), InvalidInput);
  // A zero-area face is not refused (a layered model's band muted to its base has them, and its
  // region is edited): only what the editor indexes with is checked.
  TriMesh flat = m;
  const Face& sliver = flat.faces[0];
  flat.vertices[sliver[2]] = 0.5 * (flat.vertices[sliver[0]] + flat.vertices[sliver[1]]);
  EXPECT_NO_THROW(RegionEditor(flat, region, handle));
  TriMesh nan = m;
  nan.vertices[0].y() = std::nan("");
  try {
    RegionEditor(nan, region, handle);
    ADD_FAILURE() << "a NaN vertex accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("region editor's mesh"), std::string::npos) << e.what();
  }
}

// A tiny normal is a direction like any other (1e-170 underflowed norm() and was refused as
// zero), and a kind cast from outside the enum is refused (it selected nothing).
TEST(Selection, TinyNormalsSelectAndBadKindsAreRefused) {
  const TriMesh m = bumpy_cylinder(2000);
  const std::vector<char> unit =
      select_vertices(m.vertices, Selection::halfspace(Vec3(0, 0, 2), Vec3::UnitZ()));
  const std::vector<char> tiny =
      select_vertices(m.vertices, Selection::halfspace(Vec3(0, 0, 2), Vec3(0, 1e-300, 1e-170)));
  EXPECT_EQ(tiny, unit);
  EXPECT_GT(std::count(unit.begin(), unit.end(), 1), 0);
  EXPECT_THROW(select_vertices(m.vertices, Selection::halfspace(Vec3(0, 0, 2), Vec3::Zero())), InvalidInput);
  Selection bad = Selection::sphere(Vec3::Zero(), 1.0);
  bad.kind = static_cast<Selection::Kind>(7);
  EXPECT_THROW(select_vertices(m.vertices, bad), InvalidInput);
  const EditScript sc = parse_edit_script(
      R"({"region": {"halfspace": {"point": [0, 0, 2], "normal": [0, 0, 1e-170]}}, "handle": {"vertices": [0]}, "transform": {}})",
      "tiny.json");
  EXPECT_EQ(select_vertices(m.vertices, sc.edits[0].region), unit);
}

// Options out of range: NaN or negative smoothing was taken as the default, negative solved rings
// changed the result, and a tiny wavelength was a SolverError of the fairing.
TEST(RegionEditor, OptionsOutOfRangeAreRejected) {
  const TriMesh m = bumpy_cylinder(2000);
  const std::vector<char> region = above(m, 2.0), handle = above(m, 4.0);
  std::vector<std::pair<EditOptions, const char*>> bad;
  EditOptions o;
  o.smoothing_wavelength = std::nan("");
  bad.emplace_back(o, "smoothing_wavelength");
  o = {};
  o.smoothing_wavelength = -1;
  bad.emplace_back(o, "smoothing_wavelength");
  o = {};
  o.smoothing_fraction = 0;
  bad.emplace_back(o, "smoothing_fraction");
  o = {};
  o.smoothing_fraction = std::nan("");
  bad.emplace_back(o, "smoothing_fraction");
  o = {};
  o.handle_solved_rings = -1;
  bad.emplace_back(o, "handle_solved_rings");
  o = {};
  o.drag_end_cycles = 0;
  bad.emplace_back(o, "drag_end_cycles");
  o = {};
  o.smoothing_wavelength = 1e-300;
  bad.emplace_back(o, "too small");
  // The solver's and the drag's options, at construction (they failed at the first apply() or
  // update_drag()); an infinite length floor made the solve diverge, blaming the edit.
  o = {};
  o.reconstruct.threads = -1;
  bad.emplace_back(o, "reconstruction option threads = -1");
  o = {};
  o.reconstruct.min_length_fraction = INFINITY;
  bad.emplace_back(o, "reconstruction option min_length_fraction = inf");
  o = {};
  o.drag.tolerance = -1;
  bad.emplace_back(o, "warm-start option tolerance = -1");
  for (const auto& [options, name] : bad) {
    try {
      RegionEditor(m, region, handle, options);
      ADD_FAILURE() << name << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// The open rim's fairing past the region's size: only the pull holds the rim's vertices (they
// have no fairing rows), and as the wavelength grew it let the rim flare (a review, thirty-eighth
// session: the tube's end region moved 0.52 / 4.94 / 632 from the input at smoothing 1 / 3 / 100,
// a closed region 0.24 / 0.28 / 0.29). Now the base stays as near the input as at the region's
// own size, and a wavelength whose weights overflow with the positions is refused as too small.
TEST(RegionEditor, ARimInTheRegionStaysPutAtLongWavelengths) {
  const TriMesh m = bumpy_cylinder(2000);
  const std::vector<char> region = above(m, 3.0), handle = above(m, 5.0);
  auto base_offset = [&](double fraction) {
    EditOptions o;
    o.smoothing_fraction = fraction;
    const RegionEditor ed(m, region, handle, o);
    return max_distance(ed.base(), m.vertices);
  };
  const double at_size = base_offset(1.0);
  EXPECT_GT(at_size, 0.1);  // the bumps (height 0.35 about a radius of 1.35) go into the detail
  for (double fraction : {3.0, 100.0, 1e6}) {
    const double d = base_offset(fraction);
    EXPECT_LT(d, 1.5 * at_size) << "smoothing_fraction " << fraction << " (at 1: " << at_size << ")";
  }
  TriMesh huge = m;
  for (Vec3& p : huge.vertices) p *= 1e10;
  EditOptions o;
  o.smoothing_wavelength = 1e-70;
  try {
    RegionEditor(huge, region, handle, o);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("too small"), std::string::npos) << e.what();
  }
}

// A blend weight that is not a number is refused, not turned into NaN coordinates.
TEST(EditTransform, ANonFiniteBlendWeightIsRejected) {
  const EditTransform t = EditTransform::rotation(Vec3::UnitZ(), 30.0, Vec3::Zero());
  EXPECT_THROW(t.apply_blended(Vec3(1, 0, 0), std::nan("")), InvalidInput);
  EXPECT_THROW(blend_transform({Vec3(1, 0, 0), Vec3(0, 1, 0)}, {0.5, std::nan("")}, t), InvalidInput);
  EXPECT_TRUE(t.apply_blended(Vec3(1, 0, 0), 0.5)
                  .isApprox(EditTransform::rotation(Vec3::UnitZ(), 15.0, Vec3::Zero()).apply(Vec3(1, 0, 0))));
}

// Open edges (rims) have no Laplacian rows in the decomposition's systems; without the fairing's
// pull the blend field was then undetermined, and region edits of meshes with holes failed (CGAL's
// elephant-with-holes, holes, ALSTOM_TEST4 and double-torus-3-holes: "system is singular at
// vertex" or "could not be factorized"). The blend field now takes the rim's rows in that case.
// A strip of two rows of vertices, every one on a rim: 0 outside the region, 1 on the handle,
// rising along the strip between, and the handle moved by the edit's translation.
TEST(RegionEditor, AStripWithEveryVertexOnARimGetsABlendField) {
  TriMesh m;
  const int n = 30;
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(0.1 * i, 0.1 * row, 0.0);
  for (int i = 0; i < n; ++i) {
    m.faces.push_back({i, i + 1, n + 2 + i});
    m.faces.push_back({i, n + 2 + i, n + 1 + i});
  }
  const std::vector<char> region =
      select_vertices(m.vertices, Selection::halfspace(Vec3(0.75, 0, 0), Vec3::UnitX()));
  const std::vector<char> handle =
      select_vertices(m.vertices, Selection::halfspace(Vec3(2.25, 0, 0), Vec3::UnitX()));
  const RegionEditor ed(m, region, handle);
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i <= n; ++i) {
      const int v = row * (n + 1) + i;
      const double s = ed.blend()[v];
      if (!region[v]) {
        EXPECT_EQ(s, 0.0) << "vertex " << v;
      }
      if (handle[v]) {
        EXPECT_EQ(s, 1.0) << "vertex " << v;
      }
      EXPECT_GT(s, -0.01) << "vertex " << v;
      EXPECT_LT(s, 1.01) << "vertex " << v;
      if (i > 0) {
        EXPECT_GE(s, ed.blend()[v - 1] - 1e-9) << "vertex " << v;
      }
    }
  EXPECT_GT(ed.blend()[15], 0.2);  // between, not a step
  EXPECT_LT(ed.blend()[15], 0.8);
  const Vec3 t(0.0, 0.0, 0.3);
  const EditResult r = ed.apply(EditTransform::rotation(Vec3::UnitX(), 0.0, Vec3::Zero(), t));
  for (int v = 0; v < m.num_vertices(); ++v) {
    ASSERT_TRUE(r.positions[v].allFinite());
    if (!region[v]) {
      EXPECT_EQ(r.positions[v], m.vertices[v]);
    }
    if (handle[v]) {
      EXPECT_LT((r.positions[v] - (m.vertices[v] + t)).norm(), 1e-3) << "vertex " << v;
    }
  }
}

// A part of the region that touches neither the handle nor the rest of the mesh has no blend to
// follow (CGAL's boeing, bones and b9_mesh failed with "a connected part of the region touches
// neither the fixed rest of the mesh nor the handle"): it is left out and stays where it is, and
// the rest of the region is edited as without it (to within the solver's tolerance). A region that is then
// all handle is refused.
TEST(RegionEditor, APartConnectedToNeitherTheHandleNorTheRestIsLeftOut) {
  const TriMesh tube = bumpy_cylinder(2000);
  TriMesh m = tube;
  // A loose square of two triangles inside the region (z = 3), away from the handle (z >= 4).
  const int base = m.num_vertices();
  for (const Vec3& p : {Vec3(0.1, 0.1, 3), Vec3(0.3, 0.1, 3), Vec3(0.3, 0.3, 3), Vec3(0.1, 0.3, 3)})
    m.vertices.push_back(p);
  m.faces.push_back({base, base + 1, base + 2});
  m.faces.push_back({base, base + 2, base + 3});
  const RegionEditor ed(m, above(m, 2.0), above(m, 4.0));
  EXPECT_EQ(ed.left_out_vertices(), 4);
  const RegionEditor alone(tube, above(tube, 2.0), above(tube, 4.0));
  EXPECT_EQ(alone.left_out_vertices(), 0);
  EXPECT_EQ(ed.region_vertices(), alone.region_vertices());
  const EditTransform t = EditTransform::rotation(Vec3::UnitY(), 30.0, Vec3(0, 0, 3));
  const EditResult r = ed.apply(t), r_alone = alone.apply(t);
  for (int v = base; v < base + 4; ++v) EXPECT_EQ(r.positions[v], m.vertices[v]) << v;
  // Not to the bit: the square is part of the solver's intersection context.
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LT(
      max_distance(std::vector<Vec3>(r.positions.begin(), r.positions.begin() + base), r_alone.positions),
      1e-3);
  // The loose square and the handle only: nothing is left to blend.
  std::vector<char> region = above(m, 4.0), handle = region;
  for (int v = base; v < base + 4; ++v) region[v] = 1;
  try {
    const RegionEditor none(m, region, handle);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("the handle is the whole region once the 4 vertices"),
              std::string::npos)
        << e.what();
  }
}

// A rim strip that one interior row alone ties to the rest: a boundary triangle of a jittered grid
// fanned from an interior vertex through two new rim vertices (one row, two unknowns). Without the
// rim's rows the system is singular, but CHOLMOD often factorizes it at a rounding-level pivot: a
// review found blends of -8.7e5 to 1.8e6 in 16 of 200 such grids, and a translation by 1 flung a
// vertex 2,200 away. Every blend now stays near [0, 1] and the edit near its translation.
TEST(RegionEditor, ANearlySingularBlendSystemTakesTheRimsRows) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15), along(0.2, 0.45);
  const int n = 12, cell = 5;
  for (int trial = 0; trial < 200; ++trial) {
    TriMesh m;
    auto id = [&](int x, int y) { return y * (n + 1) + x; };
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x)
        m.vertices.emplace_back(x + (y ? jitter(rng) : 0), y + jitter(rng), 0.3 * jitter(rng));
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (y == 0 && x == cell) continue;
        m.faces.push_back({id(x, y), id(x + 1, y), id(x, y + 1)});
        m.faces.push_back({id(x + 1, y), id(x + 1, y + 1), id(x, y + 1)});
      }
    const Vec3 a = m.vertices[id(cell, 0)], b = m.vertices[id(cell + 1, 0)];
    const double t1 = along(rng), t2 = 0.5 + along(rng);
    const int r1 = m.num_vertices();
    m.vertices.push_back(a + t1 * (b - a) + Vec3(0, 0, 0.1 * jitter(rng)));
    const int r2 = m.num_vertices();
    m.vertices.push_back(a + t2 * (b - a) + Vec3(0, 0, 0.1 * jitter(rng)));
    const int k = id(cell, 1);
    m.faces.push_back({id(cell, 0), r1, k});
    m.faces.push_back({r1, r2, k});
    m.faces.push_back({r2, id(cell + 1, 0), k});
    m.faces.push_back({id(cell + 1, 0), id(cell + 1, 1), k});
    std::vector<char> region(m.num_vertices()), handle(m.num_vertices());
    for (int v = 0; v < m.num_vertices(); ++v) {
      region[v] = m.vertices[v].x() < 9.5;
      handle[v] = m.vertices[v].x() < 1.5;
    }
    const RegionEditor ed(m, region, handle);
    const auto [lo, hi] = std::minmax_element(ed.blend().begin(), ed.blend().end());
    ASSERT_GE(*lo, -0.5) << "trial " << trial;
    ASSERT_LE(*hi, 1.5) << "trial " << trial;
    EditTransform t;
    t.translation = Vec3(0, 0, 1);
    const EditResult r = ed.apply(t);
    for (int v = 0; v < m.num_vertices(); ++v)
      ASSERT_LT(std::abs(r.positions[v].z() - m.vertices[v].z()), 1.6)
          << "trial " << trial << ", vertex " << v;
  }
}

// Triangles that share no edge (every other face of a tube): every vertex lies on open edges. The
// editor refused them (CHOLMOD had been handed empty columns and crashed); with the rim's rows the
// blend field is defined, and the edit leaves the rest of the mesh where it was.
TEST(RegionEditor, TrianglesThatShareNoEdgeAreEdited) {
  const TriMesh m = bumpy_cylinder(2000);
  TriMesh apart;
  apart.vertices = m.vertices;
  for (std::size_t f = 0; f < m.faces.size(); f += 2) apart.faces.push_back(m.faces[f]);
  const std::vector<char> region = above(apart, 2.0), handle = above(apart, 4.0);
  const RegionEditor ed(apart, region, handle);
  const EditResult r = ed.apply(EditTransform::rotation(Vec3::UnitY(), 10.0, Vec3(0, 0, 3)));
  for (int v = 0; v < apart.num_vertices(); ++v) {
    ASSERT_TRUE(r.positions[v].allFinite());
    if (!region[v]) {
      EXPECT_EQ(r.positions[v], apart.vertices[v]);
    }
    EXPECT_GT(ed.blend()[v], -0.05);
    EXPECT_LT(ed.blend()[v], 1.05);
  }
}

// The decomposition is a low-pass filter: short ripples go to the detail, the plane they sit on
// stays in the base. The blend field is 0 outside the region, 1 on the handle, between elsewhere.
TEST(RegionEditor, DecompositionFiltersRipplesOutOfThePlane) {
  const double amplitude = 0.01;
  const TriMesh m = rippled_grid(80, amplitude);
  const std::vector<char> region = select_vertices(m.vertices, Selection::sphere(Vec3(0.5, 0.5, 0), 0.4));
  const std::vector<char> handle = select_vertices(m.vertices, Selection::sphere(Vec3(0.5, 0.5, 0), 0.05));
  const RegionEditor ed(m, region, handle);
  double max_z = 0.0, max_input_z = 0.0;
  for (int i = 0; i < m.num_vertices(); ++i) {
    max_input_z = std::max(max_input_z, std::abs(m.vertices[i].z()));
    if (!region[i]) {
      EXPECT_EQ(ed.base()[i], m.vertices[i]);
      EXPECT_EQ(ed.blend()[i], 0.0);
      continue;
    }
    max_z = std::max(max_z, std::abs(ed.base()[i].z()));
    EXPECT_LT((ed.base()[i] - m.vertices[i]).head<2>().norm(), 0.3 * amplitude);  // little drift in the plane
    EXPECT_GT(ed.blend()[i], -0.05);
    EXPECT_LT(ed.blend()[i], 1.05);
    if (handle[i]) {
      EXPECT_EQ(ed.blend()[i], 1.0);
    }
  }
  EXPECT_GT(max_input_z, 0.9 * amplitude);
  EXPECT_LT(max_z, 0.1 * amplitude);  // at least 90% of the ripples filtered out
  EXPECT_EQ(ed.encoding().report.num_fallback, 0);
}

// An edit that barely moves the base (the handle translated by 1e-9 of the diagonal: beyond the
// rounding that counts as at rest, so the detail is solved from the clean start) gives the mesh
// back: exactly outside the region, and within 0.5% of the bounding-box diagonal inside it, the
// volumes converged and without new intersecting pairs. Over resolutions from 1k to 16k
// triangles (measured 2026-11-28: 0.03-0.13% of the diagonal, no retries). At 4000 triangles
// this folded one patch until the fold repair and retries of the later sessions (a vertex moved
// 19% of the diagonal, 88 new pairs), so the sweep keeps the resolutions around it.
class TinyEdit : public testing::TestWithParam<int> {};

TEST_P(TinyEdit, GivesTheMeshBack) {
  const int triangles = GetParam();
  const TriMesh m = bumpy_cylinder(triangles);
  const Bend b = elbow(m);
  const double diag = bbox_diagonal(m.vertices);
  for (auto method : {EditOptions::Method::Vectors, EditOptions::Method::Volumes}) {
    EditOptions o;
    o.method = method;
    const RegionEditor ed(m, b.region, b.handle, o);
    EditTransform tiny;
    tiny.translation = Vec3(0.0, 0.0, 1e-9 * diag);
    const EditResult r = ed.apply(tiny);
    if (method == EditOptions::Method::Volumes) {
      EXPECT_GT(r.stats.volume_sweeps, 0) << "the detail was not solved";
      EXPECT_TRUE(r.stats.converged);
      EXPECT_EQ(r.stats.new_intersecting_pairs, 0);
      EXPECT_LE(r.volume.max_relative_error, 1e-3);
    }
    double d = 0.0;
    for (int i = 0; i < m.num_vertices(); ++i) {
      if (!b.region[i]) {
        EXPECT_EQ(r.positions[i], m.vertices[i]);
      }
      d = std::max(d, (r.positions[i] - m.vertices[i]).norm());
    }
    EXPECT_LT(d, (method == EditOptions::Method::Vectors ? 1e-8 : 5e-3) * diag);
  }
}

INSTANTIATE_TEST_SUITE_P(RegionEditor, TinyEdit,
                         testing::Values(1000, 2000, 3000, 4000, 5000, 6000, 8000, 16000),
                         [](const testing::TestParamInfo<int>& i) {
                           return std::to_string(i.param) + "_triangles";
                         });

// back_at_rest(): rounding, not motion. A point moved by 1e-12 of the scale or by 45 units in the
// last place of its coordinates is at rest; twice that is not; NaN never is.
TEST(RegionEditor, BackAtRestIsWithinRoundingOnly) {
  const Vec3 rest(0.3, -0.2, 0.1);
  EXPECT_TRUE(back_at_rest(rest, rest, 1.0));
  EXPECT_TRUE(back_at_rest(rest + Vec3(0.9e-12, 0, 0), rest, 1.0));
  EXPECT_FALSE(back_at_rest(rest + Vec3(2e-12, 0, 0), rest, 1.0));
  const Vec3 far(1e6, -2e6, 1e6);  // 1e-14 of 2e6: 2e-8
  EXPECT_TRUE(back_at_rest(far + Vec3(0, 1.5e-8, 0), far, 1.0));
  EXPECT_FALSE(back_at_rest(far + Vec3(0, 3e-8, 0), far, 1.0));
  EXPECT_FALSE(back_at_rest(Vec3(std::nan(""), 0, 0), rest, 1.0));
}

// The identity, and a drag that comes back to its start, give the mesh back bit for bit with no
// solve: the base is at rest, and so is the detail (a solve from the clean start would land up to
// the round trip's 0.5% away, and a layered model's finer bands would follow it).
TEST(RegionEditor, IdentityEditAndADragBackGiveTheMeshBackExactly) {
  const TriMesh m = bumpy_cylinder(8000);
  const Bend b = elbow(m);
  for (auto method : {EditOptions::Method::Vectors, EditOptions::Method::Volumes}) {
    EditOptions o;
    o.method = method;
    RegionEditor ed(m, b.region, b.handle, o);
    const EditResult r = ed.apply(EditTransform{});
    EXPECT_EQ(r.positions, m.vertices);
    EXPECT_EQ(r.stats.volume_sweeps, 0);
    EXPECT_LT(r.volume.max_relative_error, 1e-12);
    if (method == EditOptions::Method::Volumes) {
      EXPECT_TRUE(r.stats.converged);
    }
    ed.begin_drag();
    ed.update_drag(b.transform);
    ed.update_drag(EditTransform{});
    EXPECT_EQ(ed.end_drag().positions, m.vertices);
  }
}

// The acceptance's cylinder: bent by 90 degrees with the editing operator, each ring of the
// smooth cylinder keeps its radius within 10%, and the handle's axis turns by 90 degrees.
TEST(RegionEditor, BentCylinderKeepsItsCrossSection) {
  const TriMesh m = smooth_cylinder();
  const Bend b = elbow(m);
  const RegionEditor ed(m, b.region, b.handle);
  const EditResult r = ed.apply(b.transform);
  std::map<long, std::vector<int>> rings;
  for (int i = 0; i < m.num_vertices(); ++i) rings[std::lround(m.vertices[i].z() * 1000)].push_back(i);
  int checked = 0;
  double min_radius = 1e300, max_radius = 0.0;
  for (const auto& [key, ids] : rings) {
    if (ids.size() < 8) continue;
    Vec3 c = Vec3::Zero();
    for (int i : ids) c += r.positions[i];
    c /= ids.size();
    for (int i : ids) {
      const double radius = (r.positions[i] - c).norm();
      ASSERT_GT(radius, 0.9) << "ring z = " << key / 1000.0;
      ASSERT_LT(radius, 1.1) << "ring z = " << key / 1000.0;
      min_radius = std::min(min_radius, radius);
      max_radius = std::max(max_radius, radius);
    }
    ++checked;
  }
  EXPECT_GT(checked, 40);
  // The measured extremes (unit rest radius), for the record.
  RecordProperty("min_radius", std::to_string(min_radius));
  RecordProperty("max_radius", std::to_string(max_radius));
  // The top ring's axis direction: the normal of its best plane turned from +z to +x.
  const std::vector<int>& top = rings.rbegin()->second;
  Vec3 c = Vec3::Zero();
  for (int i : top) c += r.positions[i];
  c /= top.size();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : top) cov += (r.positions[i] - c) * (r.positions[i] - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  EXPECT_GT(std::abs(es.eigenvectors().col(0).x()), 0.99);
  EXPECT_EQ(0u, find_self_intersections(r.positions, m.faces).num_pairs);
}

// A bend of the bumpy cylinder: volumes keep the region's prisms and add no intersection; the
// pinned rest of the mesh does not move.
TEST(RegionEditor, VolumesKeepTheRegionsPrisms) {
  const TriMesh m = bumpy_cylinder(8000);
  const Bend b = elbow(m);
  const RegionEditor ed(m, b.region, b.handle);
  const EditResult r = ed.apply(b.transform);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
  EXPECT_LE(std::abs(r.volume.total_volume_change), 1e-3);
  EXPECT_EQ(0u, find_self_intersections(r.positions, m.faces).num_pairs);
  for (int i = 0; i < m.num_vertices(); ++i)
    if (!b.region[i]) {
      ASSERT_EQ(r.positions[i], m.vertices[i]);
    }
  // The vectors' volumes are far off on the same edit (what volumes fix).
  EditOptions vo;
  vo.method = EditOptions::Method::Vectors;
  EXPECT_GT(RegionEditor(m, b.region, b.handle, vo).apply(b.transform).volume.max_relative_error, 1.0);
}

// A map that is not rigid (a scale, allowed by edit scripts): the handle's inner vertices are not
// placed by the vector rule, which keeps volumes only under a rigid map (a scale of 1.5 left the
// solve at a max error of 3.27, unconverged; found by a review, 2026-11-30). Exact and drag ends.
TEST(RegionEditor, AScaledHandleIsSolvedToo) {
  const TriMesh m = bumpy_cylinder(8000);
  const Bend b = elbow(m);
  EditTransform t = b.transform;
  t.linear *= 1.5;
  ASSERT_FALSE(t.is_rigid());
  RegionEditor ed(m, b.region, b.handle);
  const EditResult r = ed.apply(t);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
  ed.begin_drag();
  for (double f : {0.5, 1.0}) {
    EditTransform step = b.transform;
    step.linear *= 1.0 + 0.5 * f;
    ed.update_drag(step);
  }
  const EditResult d = ed.end_drag();
  EXPECT_TRUE(d.stats.converged);
  EXPECT_LE(d.volume.max_relative_error, 1e-3);
  // A rigid map keeps pinning the handle: its result is unchanged by the second solver.
  const RegionEditor fresh(m, b.region, b.handle);
  EXPECT_EQ(ed.apply(b.transform).positions, fresh.apply(b.transform).positions);
}

// The interactive mode: steps from 0 to 90 degrees warm-started from each other, then the exact
// solve, which meets the same bounds as the edit from the clean start. By default it runs from the
// drag's per-level state (checked for new pairs); with DragEnd::CleanStart it is apply() itself,
// and it falls back to apply() when the solver counts no pairs to check against.
TEST(RegionEditor, DragEndsAtTheExactSolution) {
  const TriMesh m = bumpy_cylinder(8000);
  const Bend b = elbow(m);
  auto drag = [&](RegionEditor& ed) {
    ed.begin_drag();
    EXPECT_TRUE(ed.dragging());
    std::vector<Vec3> last;
    for (int k = 1; k <= 10; ++k) {
      last = ed.update_drag(EditTransform::rotation(Vec3::UnitY(), 9.0 * k, b.transform.pivot));
      EXPECT_EQ(last.size(), m.vertices.size());
      for (const Vec3& v : last) EXPECT_TRUE(v.allFinite());
    }
    return last;
  };
  const EditTransform end_transform = EditTransform::rotation(Vec3::UnitY(), 90.0, b.transform.pivot);
  RegionEditor ed(m, b.region, b.handle);
  const std::vector<Vec3> preview = drag(ed);
  const EditResult r = ed.end_drag();
  EXPECT_FALSE(ed.dragging());
  EXPECT_FALSE(r.drag_end_fallback);  // the warm solve converged without new pairs
  EXPECT_TRUE(r.stats.converged);
  EXPECT_EQ(r.stats.new_intersecting_pairs, 0);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
  EXPECT_EQ(0u, find_self_intersections(r.positions, m.faces).num_pairs);
  EXPECT_THROW(ed.end_drag(), InvalidInput);
  for (int i = 0; i < m.num_vertices(); ++i)
    if (!b.region[i]) {
      ASSERT_EQ(r.positions[i], m.vertices[i]);
    }
  // It ends nearer the last preview than apply()'s clean start does.
  const EditResult clean = ed.apply(end_transform);
  EXPECT_LT(max_distance(preview, r.positions), max_distance(preview, clean.positions));

  EditOptions co;
  co.drag_end = EditOptions::DragEnd::CleanStart;
  RegionEditor ce(m, b.region, b.handle, co);
  drag(ce);
  const EditResult cr = ce.end_drag();
  EXPECT_FALSE(cr.drag_end_fallback);
  EXPECT_EQ(cr.positions, clean.positions);

  EditOptions blind;
  blind.reconstruct.retry_on_new_intersections = false;  // no pair count: nothing to check with
  RegionEditor be(m, b.region, b.handle, blind);
  drag(be);
  const EditResult br = be.end_drag();
  EXPECT_TRUE(br.drag_end_fallback);
  EXPECT_EQ(br.positions, be.apply(end_transform).positions);
}

// A cancelled or failed end_drag() keeps the drag (it was ended before the solve and lost); the
// editor's CageEditor twin shares the code path.
TEST(RegionEditor, AnEndDragThatThrowsLeavesTheDragOn) {
  const TriMesh m = bumpy_cylinder(2000);
  const Bend b = elbow(m);
  std::atomic<bool> cancel{false};
  EditOptions o;
  o.reconstruct.cancel = &cancel;
  RegionEditor ed(m, b.region, b.handle, o);
  ed.begin_drag();
  ed.update_drag(b.transform);
  cancel = true;
  EXPECT_THROW(ed.end_drag(), Cancelled);
  EXPECT_TRUE(ed.dragging());
  cancel = false;
  const EditResult r = ed.end_drag();
  EXPECT_FALSE(ed.dragging());
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
}

// handle_solved_rings 0 pins the most of the handle (it pinned none: the rigid-frame test's
// depth was capped at rings + 1 = 1, below the 2 it asks for).
TEST(RegionEditor, FewerSolvedHandleRingsPinMoreOfTheHandle) {
  const TriMesh m = bumpy_cylinder(8000);
  const Bend b = elbow(m);
  auto pinned_in_handle = [&](int rings) {
    EditOptions o;
    o.handle_solved_rings = rings;
    const RegionEditor ed(m, b.region, b.handle, o);
    const std::vector<int>& sub = ed.region_submesh_vertices();
    int n = 0;
    for (std::size_t k = 0; k < sub.size(); ++k) n += b.handle[sub[k]] && ed.encoding().pinned[k];
    return n;
  };
  const int p0 = pinned_in_handle(0), p1 = pinned_in_handle(1), p3 = pinned_in_handle(3);
  EXPECT_GT(p3, 0);
  EXPECT_GT(p0, p1);
  EXPECT_GE(p1, p3);
}

TEST(EditScript, ParsesTheDocumentedForms) {
  const std::string one = R"({"region": {"sphere": {"center": [0.0, 0.4, 0.1], "radius": 0.3}},
    "handle": {"sphere": {"center": [0.0, 0.7, 0.1], "radius": 0.12}},
    "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 60, "pivot": [0.0, 0.45, 0.1]},
                  "translate": [0, 0, 1]}})";
  const EditScript s = parse_edit_script(one, "one.json");
  ASSERT_EQ(s.edits.size(), 1u);
  EXPECT_EQ(s.edits[0].region.kind, Selection::Kind::Sphere);
  EXPECT_DOUBLE_EQ(s.edits[0].region.radius, 0.3);
  const EditTransform& t = s.edits[0].transform;
  EXPECT_LT((t.pivot - Vec3(0, 0.45, 0.1)).norm(), 1e-15);
  EXPECT_LT((t.translation - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_NEAR(Eigen::AngleAxisd(t.linear).angle(), M_PI / 3, 1e-12);

  const std::string list = R"({"edits": [
    {"region": {"halfspace": {"point": [0, 0, 1], "normal": [0, 0, 1]}}, "handle": {"box": {"min": [-1, -1, 4], "max": [1, 1, 9]}},
     "transform": {"scale": 2, "pivot": [0, 0, 1]}},
    {"region": {"vertices": [1, 2, 3]}, "handle": {"vertices": [3]},
     "transform": {"matrix": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "translate": [1, 2, 3]}}]})";
  const EditScript l = parse_edit_script(list, "list.json");
  ASSERT_EQ(l.edits.size(), 2u);
  EXPECT_EQ(l.edits[0].handle.kind, Selection::Kind::Box);
  EXPECT_DOUBLE_EQ(l.edits[0].transform.linear(2, 2), 2.0);
  EXPECT_EQ(l.edits[1].region.indices, (std::vector<int>{1, 2, 3}));
  EXPECT_DOUBLE_EQ(l.edits[1].transform.linear(0, 1), 0.5);
}

// Scales within the script's limits are maps the editors take: a uniform 1e-5 was refused as
// "singular or a reflection (determinant 0.000000)" by an absolute threshold on the determinant.
TEST(EditScript, TinyAndHugeScalesWithinTheLimitsReachTheEditors) {
  const TriMesh m = bumpy_cylinder(2000);
  const Bend b = elbow(m);
  const RegionEditor ed(m, b.region, b.handle);
  for (const char* scale : {"1e-6", "1e-5", "[1e-6, 1e6, 1]", "1e6"}) {
    const std::string text = std::string(R"({"region": {"vertices": [0]}, "handle": {"vertices": [0]}, )") +
                             R"("transform": {"scale": )" + scale + R"(, "pivot": [0, 0, 2]}})";
    const EditScript sc = parse_edit_script(text, "scale.json");
    ASSERT_EQ(sc.edits.size(), 1u);
    std::vector<Vec3> base;
    ASSERT_NO_THROW(base = ed.edited_base(sc.edits[0].transform)) << scale;
    for (const Vec3& v : base) ASSERT_TRUE(v.allFinite()) << scale;
  }
  EditTransform flat;
  flat.linear = Eigen::Vector3d(1.0, 1.0, 1e-16).asDiagonal();
  try {
    (void)ed.edited_base(flat);
    ADD_FAILURE() << "a singular map accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("is singular (determinant 1e-16"), std::string::npos) << e.what();
  }
}

TEST(EditScript, RejectsMalformedScriptsNamingTheFileAndThePlace) {
  const std::string sel =
      R"("region": {"sphere": {"center": [0, 0, 0], "radius": 1}}, "handle": {"vertices": [0]})";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"{", "not valid JSON: parse error at line 1, column 2"},
      {"[]", "empty"},
      {"42", "expected an edit object"},
      {R"({"handle": {"vertices": [0]}, "transform": {}})", "missing \"region\""},
      {"{" + sel + R"(, "transform": {"rotate": {"axis": [0, 0, 0], "degrees": 10}}})", "must not be zero"},
      {"{" + sel + R"(, "transform": {"rotate": {"axis": [0, 0, 1]}}})", "missing \"degrees\""},
      {"{" + sel + R"(, "transform": {"translate": [1, 2]}})", "three numbers"},
      {"{" + sel + R"(, "transform": {"scale": -1}})", "positive"},
      {"{" + sel + R"(, "transform": {"matrix": [[-1, 0, 0], [0, 1, 0], [0, 0, 1]]}})",
       "positive determinant"},
      {"{" + sel + R"(, "transform": {"rotat": {}}})", "unknown key \"rotat\""},
      {R"({"region": {"sphere": {"center": [0, 0, 0], "radius": -2}}, "handle": {"vertices": [0]}, "transform": {}})",
       "must not be negative"},
      {R"({"region": {"sphere": {"center": [0, 0], "radius": 2}}, "handle": {"vertices": [0]}, "transform": {}})",
       "edit.region.sphere.center"},
      {R"({"region": {"vertices": [0, -3]}, "handle": {"vertices": [0]}, "transform": {}})", "vertex index"},
      {R"({"region": {"vertices": [0, 99999999999]}, "handle": {"vertices": [0]}, "transform": {}})",
       "edit.region.vertices[1]: vertex index 99999999999 is out of range (at most 2147483647)"},
      {R"({"region": {"sphere": {}, "box": {}}, "handle": {"vertices": [0]}, "transform": {}})",
       "exactly one"},
      // Found by a fuzzing pass: a raw library message, and overflows blamed on other things.
      {"{" + sel + R"(, "transform": {"rotate": {"axis": [0, 0, 1], "degrees": 1e999}}})",
       "not valid JSON: number overflow parsing '1e999'"},
      {"{" + sel + R"(, "transform": {"translate": [1e300, 0, 0]}})",
       "edit.transform.translate[0]: 1e+300 is beyond the engine's range"},
      {"{" + sel + R"(, "transform": {"scale": 1e-300}})", "within 1e-6 to 1e6"},
      // Each part within its limits, the product singular to rounding.
      {"{" + sel +
           R"(, "transform": {"scale": [1, 1e6, 1e-6], "matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1e-9]]}})",
       "edit.transform: the linear part (rotate * matrix * scale) is singular"},
      {std::string("{}\0", 3), "it holds a NUL byte"},
  };
  for (const auto& [text, expected] : bad) {
    try {
      parse_edit_script(text, "bad.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("bad.json: ", 0), 0u) << msg;
      EXPECT_NE(msg.find(expected), std::string::npos) << msg << "\n(expected: " << expected << ")";
      // The parser's own exception class is not shown (a fuzzing pass, thirty-first session).
      EXPECT_EQ(msg.find("json.exception"), std::string::npos) << msg;
    }
  }
  EXPECT_THROW(read_edit_script("/nonexistent/edit.json"), IoError);
}
