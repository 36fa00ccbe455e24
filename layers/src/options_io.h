// Internal to layers: the model options as a .strata file stores them (model_io.cpp).
#pragma once

#include "strata/layers/model.h"

namespace strata::layers::internal {

//! Writes \p options as write_model() does and reads them back as read_model() does.
//! \throw InvalidInput "the model's options: <the reader's problem>" for options that a file
//!        could not hold (an infinite tolerance is written as null; a count above 2^30 is
//!        refused), so that check_model_options() accepts only what reads back.
void check_options_round_trip(const ModelOptions& options);

}  // namespace strata::layers::internal
