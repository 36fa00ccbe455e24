// Internal: the edge graph of a polygonal control cage (cage fitting, cage editing).
#pragma once

#include <Eigen/SparseCore>

#include "strata/subdiv.h"

namespace strata::internal {

//! The uniform Laplacian of the cage's edge graph as a sparse matrix: row v is c_v minus the mean
//! of v's neighbours (an empty row for an isolated vertex). With \p boundary_along_itself, a
//! vertex on an open boundary (an edge of one face) averages its boundary neighbours only, so the
//! boundary is smoothed along itself instead of being pulled into the surface.
Eigen::SparseMatrix<double> cage_laplacian(const PolyMesh& cage, bool boundary_along_itself);

}  // namespace strata::internal
