#include "strata/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
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

namespace {

// Unit normals of every face of \p p (zero for a face of zero area).
std::vector<Vec3> unit_normals(const std::vector<Face>& faces, const std::vector<Vec3>& p) {
  std::vector<Vec3> n(faces.size());
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const Face& f = faces[j];
    const Vec3 c = triangle_area_normal(p[f[0]], p[f[1]], p[f[2]]);
    const double len = c.norm();
    n[j] = len > 0 && std::isfinite(len) ? Vec3(c / len) : Vec3(Vec3::Zero());
  }
  return n;
}

// The angle between two unit normals, in degrees: atan2 of |a x b| and a . b, accurate near 0
// and 180 degrees where acos is not.
double angle_degrees(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * (180.0 / 3.14159265358979323846);
}

}  // namespace

DihedralChange dihedral_change(const std::vector<Face>& faces, const std::vector<Vec3>& reference,
                               const std::vector<Vec3>& positions) {
  if (reference.size() != positions.size())
    throw InvalidInput("dihedral_change: " + std::to_string(reference.size()) + " reference points and " +
                       std::to_string(positions.size()) + " positions");
  check_face_indices(positions.size(), faces, "dihedral_change");
  for (const Face& f : faces)
    for (int v : f)
      if (!reference[v].allFinite() || !positions[v].allFinite())
        throw InvalidInput("dihedral_change: point " + std::to_string(v) + " is not finite");
  const std::vector<Vec3> n0 = unit_normals(faces, reference), n1 = unit_normals(faces, positions);
  // Each face's edges keyed by their two vertices, sorted, so that an edge's faces are adjacent
  // (internal::face_neighbors() would not tell an edge of three faces from one of two).
  struct Side {
    std::uint64_t key;
    int face;
  };
  std::vector<Side> sides;
  sides.reserve(3 * faces.size());
  for (std::size_t j = 0; j < faces.size(); ++j)
    for (int e = 0; e < 3; ++e) {
      const auto a = static_cast<std::uint32_t>(faces[j][e]),
                 b = static_cast<std::uint32_t>(faces[j][(e + 1) % 3]);
      sides.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), static_cast<int>(j)});
    }
  std::sort(sides.begin(), sides.end(),
            [](const Side& x, const Side& y) { return x.key != y.key ? x.key < y.key : x.face < y.face; });
  std::vector<double> change;
  for (std::size_t b = 0, e; b < sides.size(); b = e) {
    for (e = b + 1; e < sides.size() && sides[e].key == sides[b].key;) ++e;
    if (e - b != 2) continue;  // a boundary or non-manifold edge
    const int f = sides[b].face, g = sides[b + 1].face;
    if (n0[f].isZero() || n0[g].isZero() || n1[f].isZero() || n1[g].isZero()) continue;
    change.push_back(std::abs(angle_degrees(n1[f], n1[g]) - angle_degrees(n0[f], n0[g])));
  }
  DihedralChange d;
  d.edges = change.size();
  if (change.empty()) return d;
  double sum = 0.0;
  for (double c : change) sum += c;
  d.mean_degrees = sum / static_cast<double>(change.size());
  auto rank = [&](double p) {  // nearest rank: the ceil(p * n)-th smallest
    const auto k = static_cast<std::size_t>(std::ceil(p * static_cast<double>(change.size())));
    const std::size_t i = std::min(change.size() - 1, k > 0 ? k - 1 : 0);
    std::nth_element(change.begin(), change.begin() + static_cast<std::ptrdiff_t>(i), change.end());
    return change[i];
  };
  d.median_degrees = rank(0.5);
  d.p90_degrees = rank(0.9);
  d.p99_degrees = rank(0.99);
  d.max_degrees = *std::max_element(change.begin(), change.end());
  return d;
}

}  // namespace strata
