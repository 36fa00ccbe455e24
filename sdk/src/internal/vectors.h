// Internal: the displacement vectors' placement without the public function's checks, for callers
// that checked the encoding and the frames once (the reconstructor, per reconstruction and drag
// step). Not part of the public API.
#pragma once

#include <string>
#include <vector>

#include "strata/encoding.h"

namespace strata::internal {

//! Detail vertex \p i placed by its displacement vector over \p frames.
//! \pre check_encoding(encoding) passed; i is a detail vertex with a frame.
inline Vec3 vector_position(const DetailEncoding& e, const BaseFrames& fr, double amplitude, int i) {
  const Vec3& n = fr.normals[i];
  const Vec3& t = fr.tangents[i];
  const Eigen::Vector2d& o = e.tangential_offsets[i];
  return fr.points[i] + amplitude * (e.normal_offsets[i] * n + o[0] * t + o[1] * n.cross(t));
}

//! reconstruct_vectors(encoding, frames, amplitude) without check_encoding() and the frames' size
//! check. \pre check_encoding(encoding) passed; frames has one entry per detail vertex.
std::vector<Vec3> vectors_unchecked(const DetailEncoding& encoding, const BaseFrames& frames,
                                    double amplitude);

//! Throws InvalidInput("<what> base frame i: ...") at the first frame whose normal or tangent is
//! not of unit length, or whose two are not orthogonal, each within 1e-6 (BaseFrames' contract:
//! the displacements are laid out in that frame, and a normal of length 2 doubled them unseen).
//! \pre every entry is finite.
void check_frame_axes(const BaseFrames& frames, const std::string& what);

}  // namespace strata::internal
