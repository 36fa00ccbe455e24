//! \file metrics.h
//! Quality measures of a reconstruction: prism volume errors and the change of the total volume
//! between base and detail. Self-intersections are counted by intersections.h.
#pragma once

#include <vector>

#include "strata/encoding.h"

namespace strata {

//! Prism volumes of a detail over a base, against the encoding's targets.
struct VolumeMetrics {
  double max_relative_error = 0.0;   //!< max_j |V_j - V*_j| / mean_j |V*_j|
  double rms_relative_error = 0.0;   //!< RMS_j |V_j - V*_j| / mean_j |V*_j|
  double mean_abs_target = 0.0;      //!< mean_j |V*_j|
  double total_target = 0.0;         //!< sum_j V*_j: the volume between base and detail at encoding
  double total_volume = 0.0;         //!< sum_j V_j
  double total_volume_change = 0.0;  //!< (total_volume - total_target) / |total_target|
};

//! Measures the prisms spanned by \p detail_positions over the base points in \p frames.
//! Where every target is 0 (amplitude 0), the relative errors are 0 if every volume is 0 and
//! infinite otherwise; total_volume_change is 0 if total_target is 0.
//! \throw InvalidInput if positions or frames do not have one entry per detail vertex, if one of
//! them or the amplitude is not finite, or as check_encoding().
//! With \p amplitude, the targets are amplitude times V*_j (a layered model's band amplitude).
VolumeMetrics volume_metrics(const DetailEncoding& encoding, const BaseFrames& frames,
                             const std::vector<Vec3>& detail_positions, double amplitude = 1.0);

//! The signed volume of every prism, in face order.
//! \throw InvalidInput if the two point arrays differ in size or a face index is out of range.
std::vector<double> prism_volumes(const std::vector<Face>& faces, const std::vector<Vec3>& detail_positions,
                                  const std::vector<Vec3>& base_points);

}  // namespace strata
