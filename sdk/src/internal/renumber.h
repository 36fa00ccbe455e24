// Internal: a renumbering of an encoding's detail vertices and faces for memory locality, used by
// the reconstructor when the caller's numbering scatters neighbours over the arrays (scans written
// by tools that hash or shuffle their vertices). Not part of the public API.
#pragma once

#include <vector>

#include "strata/encoding.h"

namespace strata::internal {

//! A permutation of the detail vertices; empty() when the caller's numbering is kept.
struct Renumbering {
  std::vector<int> old_of_new;  //!< new index -> the caller's
  std::vector<int> new_of_old;  //!< the caller's index -> new
  bool empty() const { return old_of_new.empty(); }
};

//! Edges of \p faces (each face's three, so interior edges twice) whose end points' indices differ by
//! more than \p window, as a fraction of all of them (0 for no faces).
double scattered_edge_fraction(const std::vector<Face>& faces, int window);

//! A vertex order along a Morton (Z-order) curve of \p points' positions, ties by index, if the
//! numbering is scattered: at least kMinVertices vertices, and more than kMaxScatteredFraction of
//! the face edges join vertices more than kWindow indices apart. Empty otherwise.
//! \pre every face index is in range.
Renumbering locality_renumbering(const std::vector<Vec3>& points, const std::vector<Face>& faces);

//! Below this many vertices the arrays stay in the caches whatever the numbering.
constexpr int kMinVertices = 16384;
//! Neighbours within this many indices share the caches' working set (an estimate, not measured:
//! about 100 bytes of solver state a vertex, 400 KB, the size of a core's L2 cache).
constexpr int kWindow = 4096;
//! A row-major grid has none beyond the window; the real scans of assets/scans have 0-83%.
constexpr double kMaxScatteredFraction = 0.1;

//! \p e with its detail vertices renumbered by \p r (every per-vertex array, the faces' corners and
//! the regularization graph's rows and neighbours; each row keeps its neighbours' order, each face
//! its corners' order) and its faces ordered by their smallest new corner index (then the other
//! corners), with their target volumes; \p face_order (if not null) receives each new face's index
//! in \p e. \pre check_encoding(e) passed; r is a permutation of its vertices.
DetailEncoding renumber(const DetailEncoding& e, const Renumbering& r,
                        std::vector<int>* face_order = nullptr);

//! The encoding that renumber() made \p o from, exactly: \p o's vertices, faces and regularization
//! rows back in the caller's order, with their names. \pre o = renumber(e, r, &face_order).
DetailEncoding restore(const DetailEncoding& o, const Renumbering& r, const std::vector<int>& face_order);

//! \p v (one entry per vertex in the caller's numbering) in the new numbering; \p v as is if its
//! size is not the vertex count (the callee's size check then reports it).
template <class T>
std::vector<T> to_new(const Renumbering& r, const std::vector<T>& v) {
  if (r.empty() || v.size() != r.old_of_new.size()) return v;
  std::vector<T> out(v.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = v[static_cast<std::size_t>(r.old_of_new[i])];
  return out;
}

//! \p v (one entry per vertex in the new numbering) in the caller's numbering.
template <class T>
std::vector<T> to_old(const Renumbering& r, const std::vector<T>& v) {
  if (r.empty() || v.size() != r.old_of_new.size()) return v;
  std::vector<T> out(v.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[static_cast<std::size_t>(r.old_of_new[i])] = v[i];
  return out;
}

inline BaseFrames to_new(const Renumbering& r, const BaseFrames& f) {
  return {to_new(r, f.points), to_new(r, f.normals), to_new(r, f.tangents)};
}
inline BaseFrames to_old(const Renumbering& r, const BaseFrames& f) {
  return {to_old(r, f.points), to_old(r, f.normals), to_old(r, f.tangents)};
}

}  // namespace strata::internal
