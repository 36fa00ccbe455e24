// The tests' reference for internal::build_hierarchy(): the same decimation on OpenMesh's
// TriMesh (is_collapse_ok, collapse), which the SDK used until it moved to flat arrays for speed.
// The SDK's version must give the same levels.
#pragma once

#include <vector>

#include "internal/hierarchy.h"

namespace strata::testing {

internal::Hierarchy reference_hierarchy(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                        const internal::HierarchyOptions& o);

}  // namespace strata::testing
