// Internal: the prism volume and its gradient for two prisms at once. Not part of the public API.
#pragma once

#include "strata/prism.h"

namespace strata::internal {

//! The corners of two prisms: p[k][c] and q[k][c] are corner c's top and base points of prism k.
struct PrismPair {
  const Vec3* p[2][3];
  const Vec3* q[2][3];
};

//! prism_volume_gradient() of both prisms: the same operations in the same order, bit for bit,
//! with the two prisms in the two lanes of a vector (SSE2 on x86-64, NEON on aarch64). The
//! solver's passes over the prisms take them in pairs: the scalar function's three-component
//! arithmetic left the vector unit half empty.
void prism_volume_gradient_pair(const PrismPair& corners, PrismVolumeGradient out[2]);

//! prism_volume() of both prisms, bit for bit, as prism_volume_gradient_pair() does.
void prism_volume_pair(const PrismPair& corners, double out[2]);

}  // namespace strata::internal
