//! \file intersections.h
//! Self-intersection detection on a flat triangle mesh: counts the pairs of non-adjacent triangles
//! that intersect, decided by exact predicates and pruned by a bounding-volume hierarchy.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "strata/mesh.h"

namespace strata {

//! Options of find_self_intersections().
struct IntersectionOptions {
  //! Collect the intersecting pairs themselves (not just count them).
  bool collect_pairs = false;
  //! Stop counting after this many pairs (0 = no limit). Keeps a badly broken mesh from costing O(n^2).
  std::size_t max_pairs = 0;
  //! Stop after this many exact triangle-pair tests (0 = no limit): the pairs whose boxes overlap
  //! and that share no vertex. Long thin triangles whose boxes mostly overlap cost O(n^2) tests
  //! even where none intersect (a 20k-face sheet of parallel sheared triangles: 2e8 tests, 9.5 s,
  //! 0 pairs); a scan's compact triangles cost under one test a face. The threads add their tests
  //! to the shared count in batches of at least 4096, so a search may run a batch a thread past it;
  //! a search whose tests exceed it counts as cut short even if it finished.
  std::size_t max_tests = 0;
  //! Run on the TBB thread pool; false runs on the calling thread only. The result is the same
  //! either way, except, in a search cut short (max_pairs, max_tests), which pairs are kept and
  //! how many tests were made; whether it is cut short does not depend on the threads.
  bool parallel = true;
  //! Optional: a flag another thread may set to stop the search (read at every node of the
  //! hierarchy the search visits); once it reads true, find_self_intersections() (or
  //! find_intersections_between()) throws Cancelled.
  const std::atomic<bool>* cancel = nullptr;
};

//! What find_self_intersections() found.
struct IntersectionResult {
  //! Number of intersecting pairs of non-adjacent triangles (at most max_pairs if that was set).
  std::size_t num_pairs = 0;
  //! The pairs (i, j) of face indices, i < j, sorted; only if collect_pairs (then pairs.size() == num_pairs).
  //! From find_intersections_between(): (index in the first list, index in the second), sorted.
  std::vector<std::pair<int, int>> pairs;
  //! The sorted distinct faces occurring in `pairs` (find_intersections_between(): those of the
  //! first list); only if collect_pairs.
  std::vector<int> faces;
  //! True iff the search was cut short: the mesh has more than max_pairs intersecting pairs, or
  //! its search needs more than max_tests tests (out_of_tests). num_pairs is then only a lower
  //! bound, and which pairs were kept is unspecified.
  bool truncated = false;
  //! True iff the search stopped because it ran out of max_tests.
  bool out_of_tests = false;
  //! Exact triangle-pair tests made (see IntersectionOptions::max_tests).
  std::size_t num_tests = 0;
  //! Number of faces of the mesh searched.
  std::size_t num_faces = 0;
  //! 64-bit fingerprint of the face list (indices and order), so that count_new_intersections()
  //! can check that two results refer to the same connectivity.
  std::uint64_t connectivity_hash = 0;
};

//! Counts the pairs of triangles that share no vertex and intersect, as closed sets (touching at a
//! point or along an edge counts as intersecting; so does coplanar overlap).
//!
//! The triangle-pair test is exact (CGAL's filtered predicates on the double coordinates, no
//! tolerance); a bounding-volume hierarchy over the faces prunes the candidate pairs, so a mesh
//! with few intersections and compact triangles costs O(n log n) (long thin triangles whose boxes
//! mostly overlap cost O(n^2) tests: see IntersectionOptions::max_tests).
//!
//! Adjacency is by vertex index: two faces sharing one vertex or an edge are never counted, even
//! when they do cross (a sharp fold around a shared vertex is a real self-intersection that this
//! function misses by design: like the paper, it counts non-adjacent pairs only). Conversely, faces
//! that meet at coincident but distinct (unwelded) vertices do touch and are counted.
//! Degenerate faces (zero area, decided exactly: collinear or repeated vertices) are skipped.
//!
//! Costs about 75 bytes per face of working memory at its peak; safe to call concurrently.
//!
//! \pre Every face index is in [0, vertices.size()); every vertex used by a face has finite coordinates.
//! \throw InvalidInput if a face index is out of range, a used vertex has a non-finite coordinate,
//!        or there are more faces than fit in an int; Cancelled once options.cancel reads true.
IntersectionResult find_self_intersections(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                           const IntersectionOptions& options = {});

//! Counts the pairs (a, b) of a face a of \p faces_a and a face b of \p faces_b, both over \p vertices,
//! whose triangles share no vertex and intersect: the pairs between two parts of a mesh (a region
//! and the rest of its mesh), without those within either part. The same rules, exact test,
//! hierarchy, limits, threads and cancel as find_self_intersections(): adjacency by vertex index
//! (the two lists may share vertices, and a pair sharing one is never counted), degenerate faces
//! skipped, a face listed in both lists tested against itself never (it shares its vertices).
//!
//! The result's pairs are (index in faces_a, index in faces_b), sorted; its `faces` are the
//! distinct faces of \p faces_a occurring in them; num_faces is the two lists' sizes together, and
//! connectivity_hash a fingerprint of both lists, so count_new_intersections() compares two
//! results between the same lists.
//!
//! \pre Every face index is in [0, vertices.size()); every vertex used by a face has finite coordinates.
//! \throw InvalidInput if a face index is out of range, a used vertex has a non-finite coordinate,
//!        or a list has more faces than fit in an int; Cancelled once options.cancel reads true.
IntersectionResult find_intersections_between(const std::vector<Vec3>& vertices,
                                              const std::vector<Face>& faces_a,
                                              const std::vector<Face>& faces_b,
                                              const IntersectionOptions& options = {});

//! Search limits for callers that must finish on any mesh: at most 10 million pairs (80 MB when
//! collected) and 50 million + 200 per face exact tests (a few seconds on one core, where the
//! paper's meshes and the scans take under 10 tests a face). The Strata tools, the viewer and the
//! solver's fold check use them; a result cut short says so (IntersectionResult::truncated).
IntersectionOptions bounded_intersection_options(std::size_t num_faces);

//! Number of pairs present in \p after but not in \p before: the "new" intersections caused by an
//! edit of the vertex positions.
//! \pre Both results list all their pairs (computed with collect_pairs, or with no pairs at all:
//!      pairs.size() == num_pairs), neither is truncated, and both come from the same face list.
//! \throw InvalidInput if a result does not list its pairs, is truncated, or the two results have
//!        different connectivity (face count or fingerprint differ).
std::size_t count_new_intersections(const IntersectionResult& before, const IntersectionResult& after);

//! As count_new_intersections(), but for results a search limit may have cut short: exact when
//! neither was; when only \p after was, the pairs of its list that \p before lacks (a lower bound);
//! 0 when \p before was (its list is incomplete, so no pair is known to be new).
//! \pre Both list their pairs and come from the same face list.
//! \throw InvalidInput as count_new_intersections() except for truncation.
std::size_t count_new_intersections_at_least(const IntersectionResult& before,
                                             const IntersectionResult& after);

//! Whether the closed triangles \p a and \p b intersect (touching counts), decided exactly with
//! the same predicate find_self_intersections() uses. No adjacency rule here: triangles sharing a
//! vertex position do intersect. False if either triangle is degenerate (zero area, decided exactly).
//! \throw InvalidInput if a coordinate is not finite.
bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);

}  // namespace strata
