// Internal: a self-intersection search redone only around the faces that moved. Not part of the
// public API.
#pragma once

#include <vector>

#include "strata/intersections.h"

namespace strata::internal {

//! find_self_intersections(vertices, faces, options), given \p before: that search's result over
//! the same faces at positions that differ from \p vertices only at vertices of the faces
//! \p changed (face indices, any order, repeats allowed). Pairs without a changed face are
//! \p before's; those with one are searched among the faces whose boxes share a cell of a grid
//! with a changed face's box, a superset of the faces that can meet them. The pairs are the same
//! as a whole search's, exactly; num_tests counts this search's tests only.
//!
//! Falls back to the whole search where that is no dearer or the shortcut cannot hold: \p before
//! cut short or not listing its pairs, from another face list, over a quarter of the faces
//! changed or over half of them near a changed one, or the local search cut short.
//! Why: the solver's fold repair moves a few thousand vertices a round and checks the result; at
//! 1M prisms each whole search took 0.8 s (one thread), a round's repair itself less.
//! \pre options.collect_pairs.
//! \throw as find_self_intersections().
IntersectionResult update_self_intersections(const std::vector<Vec3>& vertices,
                                             const std::vector<Face>& faces, const IntersectionResult& before,
                                             const std::vector<int>& changed,
                                             const IntersectionOptions& options);

}  // namespace strata::internal
