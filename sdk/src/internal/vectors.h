// Internal: the displacement vectors' placement without the public function's checks, for callers
// that checked the encoding and the frames once (the reconstructor, per reconstruction and drag
// step). Not part of the public API.
#pragma once

#include <vector>

#include "strata/encoding.h"

namespace strata::internal {

//! reconstruct_vectors(encoding, frames, amplitude) without check_encoding() and the frames' size
//! check. \pre check_encoding(encoding) passed; frames has one entry per detail vertex.
std::vector<Vec3> vectors_unchecked(const DetailEncoding& encoding, const BaseFrames& frames,
                                    double amplitude);

}  // namespace strata::internal
