// Internal: triangulation of one polygon of a mesh file. Not part of the public API.
#pragma once

#include <cstddef>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! The mesh validation's zero area: a triangle's doubled area at most this times the squared
//! diagonal of the bounding box of the mesh's face vertices.
constexpr double kZeroAreaRelative = 2e-14;

//! Splits the polygon with corners \p c[0..n) (indices into \p v, n >= 3) into n - 2 triangles
//! written to \p out[0..n-2), each oriented as the polygon (its Newell normal).
//!
//! First, a polygon of 5 or more corners whose sides cross by more than rounding gets false (a
//! fan is written): any triangulation covers twice where it winds twice. The sweep that finds the
//! crossing gives up past 64 n + 100,000 candidate pairs and lets the polygon through. (A quad
//! that crosses itself has no fan of positive triangles, and fails below.)
//!
//! A polygon of at most 32 corners with a fan whose every triangle faces the normal with over
//! 1e-10 of the polygon's area (a convex or star-shaped one) gets the fan from the corner whose
//! smallest triangle is largest, so that slivers are avoided where a fan allows it: the triangles
//! earlier versions read, but where two corners tie. So does a polygon whose normal is zero (all
//! corners on a line: its triangles have zero area, which the mesh validation reports; or lobes
//! of opposite orientation, as a bow tie: then false is returned). Any other
//! polygon is cut by ear clipping in the plane of its Newell normal, the smallest ear first (so
//! that a circle of many corners gets triangles that nest, where a fan or the best-shaped-first
//! order makes each cross the whole polygon, and an intersection count over them quadratic), the
//! best-shaped first among those: a U-shaped face of a CAD export gets triangles that cover it
//! without overlaps.
//!
//! \p mesh_diagonal: the diagonal of the bounding box of the mesh's face vertices (0 if unknown).
//! Ear clipping cuts last the ears of doubled area at most kZeroAreaRelative mesh_diagonal^2,
//! which the mesh validation calls zero area.
//!
//! If the clipping finds no ear at some point (the polygon crosses itself, or corners within
//! rounding of a line through other corners trap it), a polygon of at most 256 corners whose sides
//! do not cross gets the triangulation whose smallest triangle is largest, by an exact O(n^3)
//! search; a triangle within rounding of zero area there is left to the mesh validation.
//!
//! Returns false if the triangles overlap: the clipping was trapped and the exact search did not
//! apply or found only triangles that face away, or the normal is zero with corners off a line.
//! The n - 2 triangles are written either way.
bool triangulate_polygon(const std::vector<Vec3>& v, const int* c, std::size_t n, double mesh_diagonal,
                         Face* out);

}  // namespace strata::internal
