//! \file metrics.h
//! Quality measures of a reconstruction: prism volume errors, the change of the total volume
//! between base and detail, and how much the detail's bends between neighbouring triangles changed
//! (its smoothness). Self-intersections are counted by intersections.h.
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

//! How much a surface's bends between neighbouring triangles changed from a reference shape (a
//! reconstruction against the rest detail): per edge of exactly two faces, |theta - theta_ref|,
//! theta the angle between the two faces' normals (0: coplanar, 180 degrees: folded flat), in
//! degrees. Volumes and intersection counts do not see a detail that the solver left crumpled at
//! the scale of its triangles (rough steps that still keep every prism's volume); this does. Where
//! the base bends smoothly, the detail's bends change little (displacement vectors on the paper's
//! scan-like 100k bumps bend: median 0, 90th percentile 2.5 degrees; at 1M 0.8).
struct DihedralChange {
  std::size_t edges = 0;        //!< edges measured: two faces, both non-degenerate in both shapes
  double mean_degrees = 0.0;    //!< 0 when no edge is measured, as every field below
  double median_degrees = 0.0;  //!< percentiles by nearest rank: the value at rank ceil(p * edges)
  double p90_degrees = 0.0;
  double p99_degrees = 0.0;
  double max_degrees = 0.0;
};

//! The change of the dihedral angles of \p faces from \p reference to \p positions (see
//! DihedralChange). Edges of one face (boundary) or of three or more (non-manifold), and edges next
//! to a face of zero area in either shape, are not measured. Invariant under rigid motions and
//! uniform scaling of either shape. O(F log F).
//! \throw InvalidInput if the two point arrays differ in size, a face index is out of range, or a
//! point of a face is not finite.
DihedralChange dihedral_change(const std::vector<Face>& faces, const std::vector<Vec3>& reference,
                               const std::vector<Vec3>& positions);

}  // namespace strata
