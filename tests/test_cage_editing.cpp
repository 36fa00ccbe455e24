// The editing operator over a subdivision base (issue 4, item 5): selections on cage vertices,
// the handle's transform blended over the cage, the detail rebuilt over the limit surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "paper_cases.h"
#include "strata/cage_editing.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "test_meshes.h"

using namespace strata;

namespace {

struct EditCase {
  cases::CylinderCase c;
  PolyMesh cage;
  std::vector<char> region, handle;
};

// The bumpy cylinder over its cage; the region is the cage's upper part, the handle its top ring.
EditCase edit_case() {
  cases::CylinderCaseOptions o;
  o.detail = cases::DetailKind::Bumps;
  o.target_detail_triangles = 4000;
  EditCase s{cases::make_cylinder_case(o), cases::make_cylinder_cage(o), {}, {}};
  double top = -1e300;
  for (const Vec3& v : s.cage.vertices) top = std::max(top, v.z());
  for (const Vec3& v : s.cage.vertices) {
    s.region.push_back(v.z() > 0.45 * top);
    s.handle.push_back(v.z() > 0.99 * top);
  }
  return s;
}

}  // namespace

TEST(CageEditor, BlendsOverTheCageAndKeepsUnaffectedVerticesExactly) {
  const EditCase s = edit_case();
  CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle);
  const Vec3 pivot(0, 0, 0.6 * s.cage.vertices.back().z());
  const EditTransform t = EditTransform::rotation(Vec3(0, 1, 0), 60.0, pivot);
  const std::vector<Vec3> cage = ed.edited_cage(t);
  for (int v = 0; v < s.cage.num_vertices(); ++v) {
    const double b = ed.blend()[v];
    EXPECT_GE(b, -1e-9);
    EXPECT_LE(b, 1.0 + 1e-9);
    if (!s.region[v]) {
      EXPECT_EQ(cage[v], s.cage.vertices[v]);
    }
    if (s.handle[v]) {
      EXPECT_LE((cage[v] - t.apply(s.cage.vertices[v])).norm(), 1e-12);
    }
  }
  const EditResult r = ed.apply(t);
  EXPECT_EQ(r.base_positions, cage);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
  // Vertices whose base points do not depend on the region stay bit for bit; some do move.
  int kept = 0, moved = 0;
  const DetailEncoding& e = ed.encoding();
  EXPECT_LT(ed.region_faces(), s.c.detail.num_faces());
  for (int i = 0; i < s.c.detail.num_vertices(); ++i) {
    if (r.positions[i] == s.c.detail.vertices[i])
      ++kept;
    else
      ++moved;
  }
  EXPECT_GT(kept, 0);
  EXPECT_GT(moved, 0);
  EXPECT_EQ(e.detail_faces.size(), static_cast<std::size_t>(ed.region_faces()));
  // The handle's detail moved with it: the topmost point went at least half the way its rigid
  // rotation would take it (the limit near the top also depends on the blended second ring).
  const int far_vertex =
      static_cast<int>(std::max_element(s.c.detail.vertices.begin(), s.c.detail.vertices.end(),
                                        [](const Vec3& a, const Vec3& b) { return a.z() < b.z(); }) -
                       s.c.detail.vertices.begin());
  const Vec3& top_point = s.c.detail.vertices[far_vertex];
  EXPECT_GE((r.positions[far_vertex] - top_point).norm(), 0.5 * (t.apply(top_point) - top_point).norm());
}

// The rest of the mesh in the fold check (VolumeReconstructor::set_intersection_context(), set by
// the editor): the tube's upper part turned 180 degrees down into its lower part, which stays.
// Without contact_ratio every context triangle is kept, and the solver's count of new pairs is
// the whole mesh's: the moved part's own and those with the part that stayed (pairs within that
// part are never new). It has pairs of both kinds.
TEST(CageEditor, TheSolverCountsThePairsWithTheRestOfTheMesh) {
  const EditCase s = edit_case();
  CageEditOptions o;
  o.reconstruct.contact_ratio = 0.0;
  o.reconstruct.fallback_schedule = false;
  o.reconstruct.fold_repair_rounds = 0;
  const CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle, o);
  const Vec3 pivot(0, 0, 0.6 * s.cage.vertices.back().z());
  const EditResult r = ed.apply(EditTransform::rotation(Vec3(0, 1, 0), 180.0, pivot));
  std::vector<char> moved(s.c.detail.vertices.size(), 0);
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = r.positions[i] != s.c.detail.vertices[i];
  const auto [own, with_rest] =
      test::new_pairs_by_part(s.c.detail.vertices, r.positions, s.c.detail.faces, moved);
  EXPECT_GT(own, 0);
  EXPECT_GT(with_rest, 0);
  EXPECT_EQ(r.stats.new_intersecting_pairs, own + with_rest);
}

// The identity gives the mesh back bit for bit with no solve (the base at rest). A tiny edit (the
// cage's handle moved by 1e-9 of the diagonal, beyond rounding) runs the solve from the clean
// start and comes back close: vectors exactly so, volumes within the round trip.
TEST(CageEditor, IdentityAndTinyEditsGiveBackTheMesh) {
  const EditCase s = edit_case();
  const double diag = bbox_diagonal(s.c.detail.vertices);
  for (auto method : {EditOptions::Method::Volumes, EditOptions::Method::Vectors}) {
    CageEditOptions o;
    o.method = method;
    CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle, o);
    const EditResult id = ed.apply(EditTransform{});
    EXPECT_EQ(id.positions, s.c.detail.vertices);
    EXPECT_EQ(id.stats.volume_sweeps, 0);
    // A drag back to the start too (its at-rest test read the reconstructor's single-precision
    // frames, 4e-8 off: it solved, and ended 3.8e-8 off the mesh).
    ed.begin_drag();
    ed.update_drag(EditTransform::rotation(Vec3(0, 1, 0), 20.0, Vec3::Zero()));
    ed.update_drag(EditTransform{});
    EXPECT_EQ(ed.end_drag().positions, s.c.detail.vertices);
    EditTransform tiny;
    tiny.translation = Vec3(0.0, 0.0, 1e-9 * diag);
    const EditResult r = ed.apply(tiny);
    double worst = 0.0;
    for (int i = 0; i < s.c.detail.num_vertices(); ++i)
      worst = std::max(worst, (r.positions[i] - s.c.detail.vertices[i]).norm());
    // Vectors follow the base. Volumes restart from the clean configuration p' = q' and reach
    // prisms of the right volumes, but the regularization does not single out the original
    // positions (measured: 8e-3 of the diagonal at most).
    if (method == EditOptions::Method::Vectors) {
      EXPECT_LE(worst, 1e-6 * diag);
    } else {
      EXPECT_GT(r.stats.volume_sweeps, 0) << "the detail was not solved";
      EXPECT_GT(worst, 0.0);
      EXPECT_LE(worst, 1.5e-2 * diag);
      EXPECT_LE(r.volume.max_relative_error, 1e-3);
    }
  }
}

TEST(CageEditor, DragEndsWithTheExactSolve) {
  const EditCase s = edit_case();
  CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle);
  const Vec3 pivot(0, 0, 0.6 * s.cage.vertices.back().z());
  EXPECT_THROW(ed.update_drag(EditTransform{}), InvalidInput);
  ed.begin_drag();
  std::vector<Vec3> last;
  for (double a : {15.0, 30.0, 45.0}) last = ed.update_drag(EditTransform::rotation(Vec3(0, 1, 0), a, pivot));
  ASSERT_EQ(last.size(), s.c.detail.vertices.size());
  const EditResult end = ed.end_drag();
  EXPECT_FALSE(ed.dragging());
  EXPECT_FALSE(end.drag_end_fallback);  // from the drag's state, converged without new pairs
  EXPECT_TRUE(end.stats.converged);
  EXPECT_EQ(end.stats.new_intersecting_pairs, 0);
  EXPECT_LE(end.volume.max_relative_error, 1e-4);
  // The preview followed the drag: it is closer to the exact result than the unedited mesh is.
  double preview = 0.0, unedited = 0.0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    preview += (last[i] - end.positions[i]).squaredNorm();
    unedited += (s.c.detail.vertices[i] - end.positions[i]).squaredNorm();
  }
  EXPECT_LT(preview, 0.25 * unedited);
  // DragEnd::CleanStart ends exactly where apply() of the same transform does.
  CageEditOptions co;
  co.drag_end = EditOptions::DragEnd::CleanStart;
  CageEditor ce(s.c.detail, SubdivSurface(s.cage), s.region, s.handle, co);
  ce.begin_drag();
  for (double a : {15.0, 30.0, 45.0}) ce.update_drag(EditTransform::rotation(Vec3(0, 1, 0), a, pivot));
  const EditResult clean_end = ce.end_drag();
  EXPECT_FALSE(clean_end.drag_end_fallback);
  EXPECT_EQ(clean_end.positions, ce.apply(EditTransform::rotation(Vec3(0, 1, 0), 45.0, pivot)).positions);
}

// Detail vertices whose limit stencils reach handle cage vertices only move rigidly with the
// handle: they are placed exactly (not solved), and the rings around the blended part are solved.
TEST(CageEditor, RigidHandleDetailMovesExactlyWithTheHandle) {
  EditCase s = edit_case();
  double top = -1e300;
  for (const Vec3& v : s.cage.vertices) top = std::max(top, v.z());
  for (std::size_t v = 0; v < s.cage.vertices.size(); ++v) s.handle[v] = s.cage.vertices[v].z() > 0.75 * top;
  const Vec3 pivot(0, 0, 0.6 * top);
  const EditTransform t = EditTransform::rotation(Vec3(0, 1, 0), 60.0, pivot);
  const double diag = bbox_diagonal(s.c.detail.vertices);
  std::size_t pinned_with_rings = 0, pinned_without = 0;
  for (int rings : {3, -1}) {
    CageEditOptions o;
    o.handle_solved_rings = rings;
    CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle, o);
    const EditResult r = ed.apply(t);
    EXPECT_LE(r.volume.max_relative_error, 1e-3) << rings;
    EXPECT_LE(r.volume.rms_relative_error, 1e-4) << rings;
    // Pinned vertices whose frames move are exactly the rigid motion of the rest detail.
    const DetailEncoding& e = ed.encoding();
    std::size_t& pinned = rings < 0 ? pinned_without : pinned_with_rings;
    const std::vector<Vec3> rest_frames = evaluate_base_frames(e, SubdivSurface(s.cage)).points;
    const std::vector<Vec3> edited_frames =
        evaluate_base_frames(e, SubdivSurface(PolyMesh{ed.edited_cage(t), s.cage.faces})).points;
    int moving_pinned = 0;
    for (std::size_t k = 0; k < e.pinned.size(); ++k) {
      if (!e.pinned[k]) continue;
      ++pinned;
      if ((rest_frames[k] - edited_frames[k]).norm() == 0.0) continue;  // outside the region's reach
      ++moving_pinned;
      const Vec3& rest = e.detail_rest[k];
      const Vec3 expected = t.apply(rest);
      // The pinned vertex is one of the mesh's: find it by its rest position in the result.
      double best = 1e300;
      for (int i = 0; i < s.c.detail.num_vertices(); ++i)
        if (s.c.detail.vertices[i] == rest) best = std::min(best, (r.positions[i] - expected).norm());
      // Exact up to the reconstruction's base frames, whose stencil weights are stored in float
      // (LimitPointSet): measured 1e-9 of the diagonal.
      EXPECT_LE(best, 1e-7 * diag) << "pinned vertex " << k;
      if (moving_pinned > 50) break;  // a sample is enough
    }
    if (rings >= 0) {
      EXPECT_GT(moving_pinned, 0);
    }
  }
  // Without the rigid pinning only vertices whose frames cannot change are pinned.
  EXPECT_GT(pinned_with_rings, pinned_without);
  // A scaled handle: not rigid, so the handle is solved too (with it pinned the solve stopped at
  // a max error of 1.48, unconverged).
  EditTransform scaled = t;
  scaled.linear *= 1.5;
  CageEditor ed(s.c.detail, SubdivSurface(s.cage), s.region, s.handle);
  const EditResult r = ed.apply(scaled);
  EXPECT_TRUE(r.stats.converged);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
}

TEST(CageEditor, RejectsBadSelections) {
  const EditCase s = edit_case();
  const std::vector<char> none(s.cage.num_vertices(), 0);
  EXPECT_THROW(CageEditor(s.c.detail, SubdivSurface(s.cage), none, s.handle), InvalidInput);
  EXPECT_THROW(CageEditor(s.c.detail, SubdivSurface(s.cage), s.region, none), InvalidInput);
  EXPECT_THROW(CageEditor(s.c.detail, SubdivSurface(s.cage), s.region, s.region), InvalidInput);
  EXPECT_THROW(CageEditor(s.c.detail, SubdivSurface(s.cage), std::vector<char>(3, 1), s.handle),
               InvalidInput);
  // The whole cage as the region is well posed (unlike a mesh's): the field is 1 everywhere, a
  // rigid move of the model.
  const std::vector<char> all(s.cage.num_vertices(), 1);
  for (double v : cage_blend_field(s.cage, all, s.handle)) EXPECT_NEAR(v, 1.0, 1e-9);
  // A cage vertex in no face inside the region (its row of the field's system was empty, and
  // the edit failed as a factorization) keeps s = 0; the others get the field without it.
  PolyMesh stray = s.cage;
  stray.vertices.push_back(Vec3(9, 9, 9));
  std::vector<char> region = s.region, handle = s.handle;
  region.push_back(1);
  handle.push_back(0);
  const std::vector<double> with = cage_blend_field(stray, region, handle),
                            without = cage_blend_field(s.cage, s.region, s.handle);
  ASSERT_EQ(with.size(), without.size() + 1);
  EXPECT_EQ(with.back(), 0.0);
  for (std::size_t v = 0; v < without.size(); ++v) EXPECT_NEAR(with[v], without[v], 1e-12) << v;
  // A cage face index out of range (the Laplacian's assembly wrote past its arrays), and solved
  // rings beyond any mesh (INT_MAX overflowed the ring search's bound).
  PolyMesh bad = s.cage;
  bad.faces[2][1] = s.cage.num_vertices() + 1000;
  EXPECT_THROW(cage_blend_field(bad, s.region, s.handle), InvalidInput);
  bad.faces[2][1] = -5;
  EXPECT_THROW(cage_blend_field(bad, s.region, s.handle), InvalidInput);
  CageEditOptions rings;
  rings.handle_solved_rings = std::numeric_limits<int>::max();
  EXPECT_THROW(CageEditor(s.c.detail, SubdivSurface(s.cage), s.region, s.handle, rings), InvalidInput);
}

// The region's vertices are encoded over their own part's base, at the points the whole mesh's
// projection gives them: the submesh of a region over the sphere is one part, and projected alone
// it put 50 sphere vertices on the tetrahedra's cages (a review). The region takes tetrahedron
// cages too, so that vertices of both kinds are checked.
TEST(CageEditor, ScanDebrisIsNotTheRegionsBase) {
  const test::DebrisScene s = test::debris_scene(test::icosphere(1, 0.9));
  const PolyMesh cage = test::triangle_cage(s.base);
  SubdivOptions loop;
  loop.scheme = SubdivScheme::Loop;
  const SubdivSurface surface(cage, {}, loop);
  std::vector<char> region(cage.num_vertices(), 0), handle(cage.num_vertices(), 0);
  const int sphere_cage_vertices = test::icosphere(1).num_vertices();
  for (int v = 0; v < cage.num_vertices(); ++v) {
    region[v] = cage.vertices[v].z() > 0.0;
    handle[v] = v < sphere_cage_vertices && cage.vertices[v].z() > 0.6;
  }
  const CageEditor editor(s.detail, SubdivSurface(cage, {}, loop), region, handle);
  const DetailEncoding& e = editor.encoding();
  const Projection whole = project_mesh_to_limit(surface, s.detail);
  int sphere = 0, debris = 0;
  for (std::size_t k = 0; k < e.detail_rest.size(); ++k) {
    // The detail vertex at region vertex k's position (the scene's vertices are distinct).
    const auto at = std::find(s.detail.vertices.begin(), s.detail.vertices.end(), e.detail_rest[k]);
    ASSERT_NE(at, s.detail.vertices.end()) << "region vertex " << k;
    const int i = static_cast<int>(at - s.detail.vertices.begin());
    const int part = i < s.sphere_vertices ? -1 : (i - s.sphere_vertices) / 4;
    const LimitPoint& p = e.limit_points[k];
    (part < 0 ? sphere : debris) += 1;
    ASSERT_EQ(p.face < s.base_sphere_faces ? -1 : (p.face - s.base_sphere_faces) / 4, part)
        << "region vertex " << k;
    ASSERT_EQ(p.face, whole.points[i].face) << "region vertex " << k;
    ASSERT_EQ(p.u, whole.points[i].u) << "region vertex " << k;
    ASSERT_EQ(p.v, whole.points[i].v) << "region vertex " << k;
  }
  EXPECT_GT(sphere, 100);
  EXPECT_GT(debris, 0);
}
