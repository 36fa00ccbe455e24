//! \file mesh_processing.h
//! Low-pass filtering and simplification of triangle meshes: the smooth, coarse versions of a
//! scan that serve as bases (a cage to fit, the intermediate bands of a layered model).
#pragma once

#include <vector>

#include "strata/mesh.h"

namespace strata {

//! Taubin's lambda|mu smoothing (lambda 0.5, mu -0.53, uniform weights), \p steps pairs of
//! passes: a low-pass filter that, unlike plain Laplacian smoothing, does not shrink the surface.
//! A boundary vertex averages its neighbours along boundary edges only (edges of one face), so
//! open boundaries are smoothed along themselves instead of pulled inwards (also where an inner
//! edge joins two boundary vertices: an ear's third edge, a fan over a polygon). No face collapses: a step
//! (its two passes) that would leave a face with less than 1% of its area in \p mesh keeps that face's
//! vertices where the step before left them (and so on for the faces around them), so that ears on a
//! boundary and the slivers of CAD meshes, which uniform weights flatten onto a line, keep an area, and a
//! small part that plain Taubin would shrink to a point stops at that area (neither collapsed nor grown).
//! Faces may turn over where the smoothing flattens a fold (10 of the camel's 19,536 at the 10 steps of a
//! band, 25 at 30; the decimation after it refuses collapses that flip a normal). Holding them too (their
//! vertices kept where a pass would turn them) left the man's finest band with 215 projections falling back
//! instead of under 1%, thirty-eighth session. Where no face comes near collapsing (the scans of
//! assets/scans at the default 10 steps of a cage fit or a band), the result is plain Taubin
//! smoothing.
//! Returns the smoothed positions (mesh's order).
//! \throw InvalidInput if steps < 0, a face index is out of range or a coordinate is not finite
//!        (one NaN spread over the mesh).
std::vector<Vec3> taubin_smooth(const TriMesh& mesh, int steps);

//! \p mesh with its coincident vertices joined: bitwise-equal positions (-0 as +0) become one
//! vertex, numbered in order of first use (as the STL readers weld corners); faces whose corners
//! then coincide are dropped. A scan whose parts share positions but not vertices (seams cut
//! into slabs, a triangle soup) becomes one surface.
//! \throw InvalidInput if a face index is out of range (as the other functions here; it was read
//!        out of bounds).
TriMesh weld_vertices(const TriMesh& mesh);

//! Quadric-error decimation (Garland and Heckbert, OpenMesh's decimater) of \p mesh to about
//! \p target_faces faces, refusing collapses that flip a face normal by more than 45 degrees or
//! create slivers (aspect ratio above 8). Unreferenced vertices are dropped and the rest renumbered.
//! A vertex where separate fans of faces meet (a non-manifold vertex) is split into one vertex per
//! fan first, so that no face is lost (OpenMesh holds only manifold vertices). The result keeps the
//! mesh's orientation.
//! A connected part (faces joined by a vertex, after that split) too small to keep 4 faces of the
//! target by its share of the faces (target_faces * its faces < 4 * all faces), as scan debris,
//! is decimated alone to 4 or 5 faces (a part of 5 or fewer is kept as it is; the largest part is
//! never small), and the other parts share the whole target: decimated with them, the small parts,
//! which cannot go below their few faces, took the rest's budget. Their faces come after the
//! rest's, and the result can then have more than \p target_faces faces. A collapse that the
//! checks above refuse can leave any part above its share.
//! \pre mesh is a valid triangle mesh (validate_mesh()); what would crash OpenMesh or give NaN
//!      vertices is checked.
//! \throw InvalidInput if target_faces < 4 or the mesh has fewer than 4 faces, a face index is
//!        out of range, a face repeats a
//!        vertex, a coordinate is not finite, or two faces run along an edge the same way (an
//!        edge of three faces or inconsistent orientation, which validate_mesh() refuses too).
//! \throw SolverError if the decimater cannot be initialized or leaves fewer than 4 faces.
TriMesh decimate_mesh(const TriMesh& mesh, int target_faces);

//! Flips faces of \p mesh so that each connected part (faces joined by edges of exactly two faces)
//! is consistently oriented: every such edge is traversed once each way. Of the part's two
//! consistent orientations the one that flips fewer faces is taken (a tie keeps the
//! lowest-numbered face's), so a part that is already consistent is left as it is, inside out or
//! not (the inner shell of a cavity faces inwards). A face is flipped by swapping its last two
//! corners. Faces with an index out of range or a repeated corner, and edges of one face or of
//! three or more, are left for validate_mesh() to report: they join nothing.
//! Returns the number of faces flipped (0 for a mesh already consistent).
//! \throw InvalidInput if a part is not orientable (a Moebius strip), naming an edge where its
//!        orientation cannot agree; the mesh is then unchanged.
int orient_faces(TriMesh& mesh);

}  // namespace strata
