// Internal: triangulation of one polygon of a mesh file. Not part of the public API.
#pragma once

#include <cstddef>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Splits the polygon with corners \p c[0..n) (indices into \p v, n >= 3) into n - 2 triangles
//! written to \p out[0..n-2), each oriented as the polygon (its Newell normal).
//!
//! A polygon of at most 32 corners that some corner sees whole (convex, or star-shaped) gets the
//! fan from the corner whose smallest triangle is largest, so that slivers are avoided where a fan
//! allows it: the triangles every earlier version read. Any other polygon is cut by ear clipping in
//! the plane of its Newell normal, the best-shaped ear first: a U-shaped face of a CAD export gets
//! triangles that cover it without overlaps, and a hole's cap of many corners no apex of thousands
//! of slivers (which, besides their shape, made an intersection count over them quadratic).
//!
//! A polygon that is not simple in that plane (it crosses itself, or is degenerate: all corners
//! on a line) still gets n - 2 triangles, which the mesh validation may then reject (zero area).
//!
//! \p mesh_diagonal: the diagonal of the bounding box of the mesh the polygon belongs to (0 if
//! unknown). Ear clipping then avoids, where the polygon allows, triangles of doubled area at most
//! 2e-14 mesh_diagonal^2, which the mesh validation calls zero area.
void triangulate_polygon(const std::vector<Vec3>& v, const int* c, std::size_t n, double mesh_extent,
                         Face* out);

}  // namespace strata::internal
