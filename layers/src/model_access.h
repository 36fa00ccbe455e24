// Internal to layers: what the file reader may do that the public API does not offer.
#pragma once

#include "strata/layers/model.h"

namespace strata::layers::internal {

struct ModelAccess {
  //! LayeredModel::assemble() for bands whose encodings encode_detail_at() made from their base
  //! points over their bases at rest (as read_model() does): their derived values are those by
  //! construction, so they are not computed a second time (0.20 -> 0.35 s for a 52k-face model).
  static LayeredModel assemble_derived(std::vector<Band> bands, ModelOptions options,
                                       std::vector<std::string> history) {
    return LayeredModel::assemble_parts(std::move(bands), std::move(options), std::move(history), false);
  }
};

}  // namespace strata::layers::internal
