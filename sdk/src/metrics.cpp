#include "strata/metrics.h"

#include <cmath>
#include <limits>
#include <string>

#include "strata/exceptions.h"
#include "strata/prism.h"

namespace strata {

std::vector<double> prism_volumes(const std::vector<Face>& faces, const std::vector<Vec3>& p,
                                  const std::vector<Vec3>& q) {
  if (p.size() != q.size())
    throw InvalidInput("prism_volumes: " + std::to_string(p.size()) + " detail positions and " +
                       std::to_string(q.size()) + " base points");
  check_face_indices(p.size(), faces, "prism_volumes");
  std::vector<double> v(faces.size());
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const Face& f = faces[j];
    v[j] = prism_volume(p[f[0]], p[f[1]], p[f[2]], q[f[0]], q[f[1]], q[f[2]]);
  }
  return v;
}

VolumeMetrics volume_metrics(const DetailEncoding& e, const BaseFrames& frames, const std::vector<Vec3>& p,
                             double amplitude) {
  check_encoding(e);
  const std::size_t n = static_cast<std::size_t>(e.num_detail_vertices());
  if (p.size() != n || frames.points.size() != n)
    throw InvalidInput("volume_metrics: expected " + std::to_string(n) +
                       " detail positions and base points, got " + std::to_string(p.size()) + " and " +
                       std::to_string(frames.points.size()));
  // A NaN volume would pass std::max() unseen: the max error came out 0 for NaN positions.
  if (!std::isfinite(amplitude)) throw InvalidInput("volume_metrics: the amplitude is not finite");
  for (std::size_t i = 0; i < n; ++i) {
    if (!p[i].allFinite())
      throw InvalidInput("volume_metrics: detail position " + std::to_string(i) + " is not finite");
    if (!frames.points[i].allFinite())
      throw InvalidInput("volume_metrics: base point " + std::to_string(i) + " is not finite");
  }
  const std::vector<double> v = prism_volumes(e.detail_faces, p, frames.points);
  VolumeMetrics m;
  double sq = 0.0, mx = 0.0, abs_sum = 0.0;
  for (std::size_t j = 0; j < v.size(); ++j) {
    const double target = amplitude * e.target_volumes[j];
    const double err = std::abs(v[j] - target);
    mx = std::max(mx, err);
    sq += err * err;
    abs_sum += std::abs(target);
    m.total_target += target;
    m.total_volume += v[j];
  }
  if (!v.empty()) {
    m.mean_abs_target = abs_sum / v.size();
    if (m.mean_abs_target > 0) {
      m.max_relative_error = mx / m.mean_abs_target;
      m.rms_relative_error = std::sqrt(sq / v.size()) / m.mean_abs_target;
    } else if (mx > 0) {  // volumes where every target is 0 (a muted band): no relative error fits
      m.max_relative_error = m.rms_relative_error = std::numeric_limits<double>::infinity();
    }
  }
  if (m.total_target != 0.0)
    m.total_volume_change = (m.total_volume - m.total_target) / std::abs(m.total_target);
  return m;
}

}  // namespace strata
