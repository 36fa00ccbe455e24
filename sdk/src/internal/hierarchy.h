// Internal: the multigrid hierarchy of a detail mesh, built by decimation (paper, section 4.3).
#pragma once

#include <atomic>
#include <functional>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Nested levels of a triangle mesh built by half-edge collapses: every level's vertices are a
//! subset of the next finer level's, so coarse solutions carry over by injection.
struct Hierarchy {
  struct Level {
    std::vector<int> vertices;  //!< original vertex ids
    std::vector<Face> faces;    //!< original vertex ids
    //! Vertices that the prolongation from the next coarser level inserts, in insertion order
    //! (the reverse of their removal), each with the ring of neighbours it had when it was
    //! removed: ring_vertices[ring_offsets[k] .. ring_offsets[k+1]). Empty on the coarsest level.
    std::vector<int> inserted;
    std::vector<int> ring_offsets;
    std::vector<int> ring_vertices;
  };
  std::vector<Level> levels;  //!< coarsest first; the last level is the input mesh
};

struct HierarchyOptions {
  int max_levels = 10;
  int coarsest_vertices = 200;
  double ratio = 0.25;
  //! Optional: read every 1024 edges taken from the queue (collapsed or not); once true, build_hierarchy()
  //! throws Cancelled.
  const std::atomic<bool>* cancel = nullptr;
  //! Optional: the fraction of the input's vertices removed so far, every 65536 edges taken from the queue
  //! and at each level's end (about 1 - ratio after the first level, which takes most of the time).
  std::function<void(double)> progress;
};

//! Decimates (positions, faces) by shortest-edge-first half-edge collapses that keep the mesh
//! manifold, boundaries in place and face normals from flipping; equally long edges in a fixed
//! pseudo-random order. Each level keeps about `ratio` of the finer level's vertices; it stops at
//! max_levels, below coarsest_vertices, or when the collapses stall. Deterministic.
//! Any faces with indices in range are accepted: a face with a repeated corner, or one that uses
//! a directed edge an earlier face uses, stays on the finest level only; a vertex where several
//! fans of faces meet is kept on every level. Linear memory, flat arrays (no OpenMesh).
//! \throw Cancelled once options.cancel reads true (nothing is kept).
Hierarchy build_hierarchy(const std::vector<Vec3>& positions, const std::vector<Face>& faces,
                          const HierarchyOptions& options);

}  // namespace strata::internal
