// Internal: flat compressed adjacency of an indexed triangle mesh. Not part of the public API.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Vertex -> incident faces (with the vertex's corner in the face) and vertex -> neighbours,
//! both in compressed sparse row form.
struct Adjacency {
  std::vector<int> face_offsets;      //!< size nv+1
  std::vector<int> faces;             //!< incident face ids
  std::vector<std::uint8_t> corners;  //!< corner (0..2) of the vertex in that face
  std::vector<int> neighbor_offsets;  //!< size nv+1
  std::vector<int> neighbors;         //!< distinct neighbour vertices, sorted

  int num_vertices() const { return static_cast<int>(face_offsets.size()) - 1; }
};

//! Where the per-vertex loops below run: on the calling thread, or on TBB's threads of the
//! caller's task arena (the encoding's; the solver's set-up keeps to its own thread count). The
//! results are the same bit for bit.
enum class Threads { Serial, Caller };

Adjacency build_adjacency(int num_vertices, const std::vector<Face>& faces,
                          Threads threads = Threads::Serial);

//! Throws InvalidInput "WHAT: face F has vertex index V out of range (N vertices)" for the first
//! index of \p faces outside [0, num_vertices): what build_adjacency() and the per-vertex arrays
//! need (a mesh's other defects, e.g. zero-area faces, are the callers' to judge).
void check_face_indices(const std::vector<Face>& faces, int num_vertices, const std::string& what);

//! Face -> the faces sharing an edge with it (up to 3, -1 where the edge is a boundary; on an edge
//! of more than two faces, one of the others).
std::vector<std::array<int, 3>> face_neighbors(int num_vertices, const std::vector<Face>& faces);

//! Edge distance of each vertex from the nearest seed (seeds[i] != 0), capped at cap: vertices
//! farther than cap - 1 edges (or unreachable) get cap.
std::vector<int> ring_distance(const Adjacency& adj, const std::vector<char>& seeds, int cap);

//! One flag per vertex: whether it is \p free and its connected part of free vertices (through the
//! graph's rows: vertex v's neighbours are neighbors[offsets[v] .. offsets[v + 1])) touches no
//! vertex that is not: in a problem held at the other vertices its values are undetermined.
std::vector<char> floating_parts(const int* offsets, const int* neighbors, const std::vector<char>& free);

//! One flag per vertex: whether it lies on a boundary edge (an edge of one face only).
std::vector<char> boundary_vertices(int num_vertices, const std::vector<Face>& faces);

//! Cotangent weights (cot alpha + cot beta) / 2 of each vertex's neighbours, clamped to be
//! non-negative. Aligned with Adjacency::neighbors.
std::vector<double> clamped_cotan_weights(const std::vector<Vec3>& positions, const std::vector<Face>& faces,
                                          const Adjacency& adj, Threads threads = Threads::Serial);

//! Cotangent weights of each vertex's neighbours on the mesh (positions, faces), clamped to be
//! non-negative and normalized to sum to 1 per vertex (uniform where all clamp to zero). Aligned
//! with Adjacency::neighbors.
std::vector<double> normalized_cotan_weights(const std::vector<Vec3>& positions,
                                             const std::vector<Face>& faces, const Adjacency& adj,
                                             Threads threads = Threads::Serial);

}  // namespace strata::internal
