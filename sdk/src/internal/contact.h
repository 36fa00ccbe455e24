// Internal: which of a reconstruction's new intersecting triangle pairs are a contact that the
// edit made (two parts of the base brought together: a limb bent into the body) rather than a
// fold of the detail. Not part of the public API.
//
// Why: the solver's retries, fold repair and fallback schedule exist for folds, which another
// schedule or local smoothing can undo. A contact is in the edited base itself: no schedule
// undoes it, and each retry is a whole clean-start solve spent for nothing (a layered model's
// bend into the body ran six solves per band).
#pragma once

#include <cstdint>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! The detail's graph as the contact test reads it: faces over vertices [0, n), each vertex's
//! (face * 3 + corner) entries in CSR form, and each vertex's base point on the edited base. The
//! arrays must outlive the test and stay unchanged.
struct BaseGraph {
  const std::vector<Face>* faces = nullptr;
  const std::vector<int>* vf_offsets = nullptr;
  const std::vector<int>* vf = nullptr;
  const std::vector<Vec3>* base_points = nullptr;
};

//! Whether a pair of detail faces is a contact: the shortest path between the two faces' base
//! points along the detail's edges (each edge as long as the distance between its ends' base
//! points, i.e. along the edited base) is longer than `ratio` times their straight distance plus
//! the longer of the two faces' base edges. A fold's triangles lie over one stretch of base, where
//! the path is about as long as the straight line (a graph path over a triangulation overestimates
//! a geodesic by less than 1.5); across a contact it runs around through the base. An A* search
//! (the straight distance to the other face as its estimate) stops at that bound, so a fold costs
//! about its path's vertices and a contact the ellipse within the bound. Answers are remembered
//! per pair (the base points are fixed while a reconstruction checks its results). The searches
//! share a budget of vertex visits, `visits_per_vertex` times the vertex count: a result with
//! millions of new pairs (a solve gone wrong) costs a few passes over the mesh, not millions of
//! searches. Once it is spent every further pair counts as a fold, the answer that leaves the
//! solver's retries as they were (deterministic: the pairs come sorted).
class ContactTest {
 public:
  //! \pre the graph's arrays are consistent; ratio >= 1.
  ContactTest(const BaseGraph& graph, double ratio, double visits_per_vertex = 20.0);
  //! \pre a and b are face indices, a != b.
  bool operator()(int a, int b);

 private:
  bool within(int a, int b, double bound);
  BaseGraph g_;
  double ratio_;
  double visits_left_;        // the searches' budget (vertices taken off the heap)
  std::vector<double> dist_;  // per vertex: the path length found so far (infinite: none)
  std::vector<int> touched_;  // the vertices whose dist_ a search set
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>> heap_;
  std::unordered_map<std::uint64_t, bool> known_;
};

}  // namespace strata::internal
