// The solver's renumbering for locality (internal/renumber.h, ReconstructOptions::
// renumber_for_locality): when a detail's numbering scatters neighbours, the reconstructor solves
// in a Morton order of its own, and every call still takes and returns arrays in the caller's
// numbering: each answer is the renumbered encoding's own, renamed back, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "internal/renumber.h"
#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/reconstruction.h"

using namespace strata;

namespace {

cases::CylinderCase bumps_case() {
  cases::CylinderCaseOptions o;
  o.detail = cases::DetailKind::Bumps;
  o.target_detail_triangles = 40000;
  o.jitter = 0.4;
  return cases::make_cylinder_case(o);
}

// Each face as its sorted corners (in the caller's numbering) with its target volume.
std::vector<std::tuple<int, int, int, double>> face_set(const DetailEncoding& e,
                                                        const std::vector<int>* old_of_new) {
  std::vector<std::tuple<int, int, int, double>> s;
  for (std::size_t j = 0; j < e.detail_faces.size(); ++j) {
    std::array<int, 3> c;
    for (int k = 0; k < 3; ++k)
      c[k] = old_of_new ? (*old_of_new)[e.detail_faces[j][k]] : e.detail_faces[j][k];
    std::sort(c.begin(), c.end());
    s.emplace_back(c[0], c[1], c[2], e.target_volumes[j]);
  }
  std::sort(s.begin(), s.end());
  return s;
}

}  // namespace

TEST(Renumber, AScatteredNumberingIsRenumberedAndAGridKept) {
  const cases::CylinderCase c = bumps_case();
  ASSERT_GE(c.detail.num_vertices(), internal::kMinVertices);
  // The generated grid's neighbours are close in the numbering: kept.
  EXPECT_LT(internal::scattered_edge_fraction(c.detail.faces, internal::kWindow), 0.01);
  EXPECT_TRUE(internal::locality_renumbering(c.detail.vertices, c.detail.faces).empty());
  const TriMesh s = cases::shuffled_numbering(c.detail, 7);
  EXPECT_GT(internal::scattered_edge_fraction(s.faces, internal::kWindow), 0.5);
  const DetailEncoding e = encode_detail(s, c.base);
  const internal::Renumbering r = internal::locality_renumbering(e.detail_rest, e.detail_faces);
  ASSERT_FALSE(r.empty());
  // A permutation, whose inverse is new_of_old.
  const int n = e.num_detail_vertices();
  ASSERT_EQ(static_cast<int>(r.old_of_new.size()), n);
  std::vector<int> seen(n, 0);
  for (int i = 0; i < n; ++i) {
    ASSERT_GE(r.old_of_new[i], 0);
    ASSERT_LT(r.old_of_new[i], n);
    ++seen[r.old_of_new[i]];
    EXPECT_EQ(r.new_of_old[r.old_of_new[i]], i);
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n);

  // The same encoding under new names: every per-vertex value, the faces with their targets, and
  // each vertex's regularization neighbours with their weights.
  const DetailEncoding o = internal::renumber(e, r);
  EXPECT_NO_THROW(check_encoding(o));
  EXPECT_LE(internal::scattered_edge_fraction(o.detail_faces, internal::kWindow),
            internal::kMaxScatteredFraction);
  EXPECT_TRUE(internal::locality_renumbering(o.detail_rest, o.detail_faces).empty());  // not again
  for (int i = 0; i < n; ++i) {
    const int v = r.old_of_new[i];
    ASSERT_EQ(o.detail_rest[i], e.detail_rest[v]);
    ASSERT_EQ(o.base_points[i].face, e.base_points[v].face);
    ASSERT_EQ(o.base_points[i].bary, e.base_points[v].bary);
    ASSERT_EQ(o.normal_offsets[i], e.normal_offsets[v]);
    ASSERT_EQ(o.tangential_offsets[i], e.tangential_offsets[v]);
    ASSERT_EQ(o.base_rest_points[i], e.base_rest_points[v]);
    ASSERT_EQ(o.base_rest_normals[i], e.base_rest_normals[v]);
    ASSERT_EQ(o.base_rest_tangents[i], e.base_rest_tangents[v]);
    std::vector<std::pair<int, double>> a, b;
    for (int t = o.weight_offsets[i]; t < o.weight_offsets[i + 1]; ++t)
      a.emplace_back(r.old_of_new[o.weight_neighbors[t]], o.weights[t]);
    for (int t = e.weight_offsets[v]; t < e.weight_offsets[v + 1]; ++t)
      b.emplace_back(e.weight_neighbors[t], e.weights[t]);
    ASSERT_EQ(a, b) << "vertex " << v;
  }
  EXPECT_EQ(face_set(o, &r.old_of_new), face_set(e, nullptr));
  // restore() gives the caller's encoding back exactly (what VolumeReconstructor::encoding() returns).
  std::vector<int> face_order;
  const DetailEncoding back = internal::restore(internal::renumber(e, r, &face_order), r, face_order);
  EXPECT_EQ(back.detail_faces, e.detail_faces);
  EXPECT_EQ(back.target_volumes, e.target_volumes);
  EXPECT_EQ(back.detail_rest, e.detail_rest);
  EXPECT_EQ(back.base_rest_points, e.base_rest_points);
  EXPECT_EQ(back.normal_offsets, e.normal_offsets);
  EXPECT_EQ(back.tangential_offsets, e.tangential_offsets);
  EXPECT_EQ(back.base_rest_normals, e.base_rest_normals);
  EXPECT_EQ(back.base_rest_tangents, e.base_rest_tangents);
  EXPECT_EQ(back.weight_offsets, e.weight_offsets);
  EXPECT_EQ(back.weight_neighbors, e.weight_neighbors);
  EXPECT_EQ(back.weights, e.weights);
  EXPECT_EQ(back.pinned, e.pinned);
  EXPECT_EQ(back.base_faces, e.base_faces);
  ASSERT_EQ(back.base_points.size(), e.base_points.size());
  for (std::size_t v = 0; v < e.base_points.size(); ++v) {
    ASSERT_EQ(back.base_points[v].face, e.base_points[v].face);
    ASSERT_EQ(back.base_points[v].bary, e.base_points[v].bary);
  }
  // The faces go by their smallest corner.
  for (std::size_t j = 1; j < o.detail_faces.size(); ++j) {
    const Face& f = o.detail_faces[j - 1];
    const Face& g = o.detail_faces[j];
    ASSERT_LE(std::min({f[0], f[1], f[2]}), std::min({g[0], g[1], g[2]}));
  }
}

// encode_detail() projects a scattered numbering's vertices along a Morton curve (for the caches):
// each vertex still gets the base point the grid's numbering gives it, and the same counts.
TEST(Renumber, AScatteredDetailEncodesToTheSameBasePoints) {
  const cases::CylinderCase c = bumps_case();
  const TriMesh s = cases::shuffled_numbering(c.detail, 5);
  ASSERT_FALSE(internal::locality_renumbering(s.vertices, s.faces).empty());  // the path under test
  const DetailEncoding grid = encode_detail(c.detail, c.base);
  const DetailEncoding shuffled = encode_detail(s, c.base);
  // The grid's vertex at each shuffled vertex's position (positions are distinct).
  std::vector<std::pair<std::array<double, 3>, int>> by_position;
  for (int i = 0; i < c.detail.num_vertices(); ++i) {
    const Vec3& p = c.detail.vertices[i];
    by_position.push_back({{p.x(), p.y(), p.z()}, i});
  }
  std::sort(by_position.begin(), by_position.end());
  ASSERT_EQ(s.num_vertices(), c.detail.num_vertices());
  for (int i = 0; i < s.num_vertices(); ++i) {
    const Vec3& p = s.vertices[i];
    const auto it = std::lower_bound(by_position.begin(), by_position.end(),
                                     std::make_pair(std::array<double, 3>{p.x(), p.y(), p.z()}, -1));
    ASSERT_TRUE(it != by_position.end() && it->first == (std::array<double, 3>{p.x(), p.y(), p.z()}));
    const BasePoint &a = shuffled.base_points[i], &b = grid.base_points[it->second];
    ASSERT_EQ(a.face, b.face) << "vertex " << i;
    ASSERT_EQ(a.bary, b.bary) << "vertex " << i;
  }
  EXPECT_EQ(shuffled.report.num_projected, grid.report.num_projected);
  EXPECT_EQ(shuffled.report.num_fallback, grid.report.num_fallback);
  EXPECT_EQ(shuffled.report.num_ambiguous, grid.report.num_ambiguous);
}

TEST(Renumber, EveryCallAnswersInTheCallersNumbering) {
  const cases::CylinderCase c = bumps_case();
  const TriMesh s = cases::shuffled_numbering(c.detail, 11);
  DetailEncoding e = encode_detail(s, c.base);
  // Pinned vertices (a region edit's outside), with positions of their own: the displacement
  // vectors' over the bent base, a little moved (null pinned_positions is the vectors' own).
  const int n = e.num_detail_vertices();
  const std::vector<Vec3>& bent = c.edited_base.vertices;
  std::vector<Vec3> pinned_at = reconstruct_vectors(e, evaluate_base_frames(e, bent));
  e.pinned.assign(n, 0);
  for (int v = 0; v < n; ++v) {
    if (s.vertices[v].z() < 0.6) e.pinned[v] = 1, pinned_at[v] += Vec3(0, 0, 1e-5);
  }
  const auto pinned = std::count(e.pinned.begin(), e.pinned.end(), 1);
  ASSERT_GT(pinned, n / 20);
  ASSERT_LT(pinned, n / 2);
  const internal::Renumbering r = internal::locality_renumbering(e.detail_rest, e.detail_faces);
  ASSERT_FALSE(r.empty());
  ReconstructOptions o = multigrid_reconstruct_options();
  const VolumeReconstructor a(e, o);  // renumbers
  o.renumber_for_locality = false;
  const VolumeReconstructor b(internal::renumber(e, r), o);  // solves in that numbering as given
  EXPECT_EQ(a.encoding().detail_faces, e.detail_faces);
  EXPECT_EQ(a.encoding().weight_neighbors, e.weight_neighbors);
  EXPECT_EQ(a.encoding().pinned, e.pinned);
  EXPECT_EQ(a.level_vertex_counts(), b.level_vertex_counts());
  const auto back = [&](const ReconstructResult& res) { return internal::to_old(r, res.positions); };

  ReconstructRequest req;
  req.pinned_positions = &pinned_at;
  const std::vector<Vec3> pinned_new = internal::to_new(r, pinned_at);
  ReconstructRequest req_new;
  req_new.pinned_positions = &pinned_new;
  const ReconstructResult ra = a.reconstruct(bent, req);
  EXPECT_TRUE(ra.stats.renumbered);
  EXPECT_TRUE(ra.stats.converged);
  EXPECT_LE(ra.stats.max_relative_error, 1e-3);
  EXPECT_EQ(ra.positions, back(b.reconstruct(bent, req_new)));
  for (int v = 0; v < n; ++v) {
    if (e.pinned[v]) {
      ASSERT_EQ(ra.positions[v], pinned_at[v]) << v;
    }
  }
  // The frames: those the caller evaluates, and those the reconstructor hands out.
  const BaseFrames fr = evaluate_base_frames(e, bent);
  const BaseFrames fa = a.base_frames(bent);
  EXPECT_EQ(fa.points, fr.points);
  EXPECT_EQ(fa.normals, fr.normals);
  EXPECT_EQ(fa.tangents, fr.tangents);
  EXPECT_EQ(a.reconstruct(fr, req).positions, ra.positions);

  // A warm start from the detail at rest.
  WarmStartOptions warm;
  warm.coarse_levels_only = true;
  EXPECT_EQ(a.reconstruct_from(bent, s.vertices, warm, req).positions,
            back(b.reconstruct_from(bent, internal::to_new(r, s.vertices), warm, req_new)));
  EXPECT_EQ(
      a.reconstruct_from(fr, s.vertices, warm, req).positions,
      back(b.reconstruct_from(internal::to_new(r, fr), internal::to_new(r, s.vertices), warm, req_new)));

  // A drag in two steps, by the base's vertices and by frames.
  const std::vector<Vec3>& rest = c.base.vertices;
  std::vector<Vec3> half(rest.size());
  for (std::size_t v = 0; v < rest.size(); ++v) half[v] = 0.5 * (rest[v] + bent[v]);
  DragState da, db;
  da.reset(evaluate_base_frames(e, rest), s.vertices);
  db.reset(internal::to_new(r, evaluate_base_frames(e, rest)), internal::to_new(r, s.vertices));
  EXPECT_EQ(a.drag_step(half, da, warm, req).positions, back(b.drag_step(half, db, warm, req_new)));
  EXPECT_EQ(a.drag_step(fr, da, warm, req).positions,
            back(b.drag_step(internal::to_new(r, fr), db, warm, req_new)));
  // The state belongs to the reconstructor that took its first step.
  EXPECT_THROW(b.drag_step(half, da, warm, req_new), InvalidInput);
  // A first step refused (an amplitude out of range) leaves the state in the caller's numbering:
  // another reconstructor's first step then renumbers it as a fresh state's. The refused step used
  // to mark it as in the solver's order, owned by nobody, and the renumbering one took it as is.
  {
    ReconstructRequest huge = req_new;
    huge.amplitude = 1e301;
    DragState refused, fresh;
    refused.reset(evaluate_base_frames(e, rest), s.vertices);
    fresh.reset(evaluate_base_frames(e, rest), s.vertices);
    EXPECT_THROW(b.drag_step(half, refused, warm, huge), InvalidInput);
    EXPECT_EQ(a.drag_step(half, refused, warm, req).positions, a.drag_step(half, fresh, warm, req).positions);
  }

  // Errors name vertices by the caller's numbers.
  int k = 0;  // a pinned vertex the renumbering moved
  while (!(e.pinned[k] && r.new_of_old[k] != k)) ++k;
  const auto message = [](auto&& call) {
    try {
      call();
    } catch (const InvalidInput& err) {
      return std::string(err.what());
    }
    return std::string("no error");
  };
  BaseFrames bad_frames = fr;
  bad_frames.normals[k] = Vec3(std::nan(""), 0, 0);
  EXPECT_NE(message([&] { a.reconstruct(bad_frames); }).find("base frame " + std::to_string(k) + " "),
            std::string::npos);
  std::vector<Vec3> bad_start = s.vertices;
  bad_start[k] = Vec3(0, std::nan(""), 0);
  EXPECT_NE(
      message([&] { a.reconstruct_from(bent, bad_start, warm); }).find("vertex " + std::to_string(k) + " "),
      std::string::npos);
  std::vector<Vec3> bad_pinned = pinned_at;
  bad_pinned[k] = Vec3(0, 0, std::nan(""));
  ReconstructRequest bad_req;
  bad_req.pinned_positions = &bad_pinned;
  EXPECT_NE(message([&] { a.reconstruct(bent, bad_req); }).find("pinned position " + std::to_string(k) + " "),
            std::string::npos);
  // An edited base collapsed around a vertex (no normals there): the message is the one the
  // caller's own evaluation gives, naming the caller's first vertex over such a face (found by a
  // review, 2026-11-28: it named the solver's).
  std::vector<Vec3> collapsed = c.base.vertices;
  std::vector<char> ring(collapsed.size(), 0);
  ring[0] = 1;
  for (int round = 0; round < 3; ++round) {
    std::vector<char> next = ring;
    for (const Face& f : c.base.faces)
      if (ring[f[0]] || ring[f[1]] || ring[f[2]]) next[f[0]] = next[f[1]] = next[f[2]] = 1;
    ring.swap(next);
  }
  for (std::size_t v = 0; v < collapsed.size(); ++v)
    if (ring[v]) collapsed[v] = c.base.vertices[0];
  const std::string expected = message([&] { evaluate_base_frames(e, collapsed); });
  ASSERT_NE(expected.find("no normal"), std::string::npos) << expected;
  EXPECT_EQ(message([&] { a.reconstruct(collapsed); }), expected);
  EXPECT_EQ(message([&] { a.base_frames(collapsed); }), expected);
  EXPECT_EQ(message([&] { a.drag_step(collapsed, da, warm); }), expected);
}
