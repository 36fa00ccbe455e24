#include "internal/polygon.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>

namespace strata::internal {
namespace {

using Vec2 = Eigen::Vector2d;

// The fan apex whose smallest triangle, measured along \p normal, is largest; that measure in
// \p score. O(n^2): small polygons only.
std::size_t best_fan_apex(const std::vector<Vec3>& v, const int* c, std::size_t n, const Vec3& normal,
                          double& score) {
  std::size_t best = 0;
  score = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    double s = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i + 1 < n; ++i)
      s = std::min(s, triangle_area_normal(v[c[k]], v[c[(k + i) % n]], v[c[(k + i + 1) % n]]).dot(normal));
    if (s > score) {
      score = s;
      best = k;
    }
  }
  return best;
}

// Ear clipping of a polygon projected to the plane of its normal (counter-clockwise there), the
// best-shaped ear first. Corners are positions 0..n-1 of the polygon, linked in a ring.
class EarClipper {
 public:
  EarClipper(const std::vector<Vec3>& v, const int* c, std::size_t n, const Vec3& normal)
      : c_(c), n_(static_cast<int>(n)), p_(n), prev_(n), next_(n), version_(n, 0), removed_(n, 0) {
    // An orthonormal basis (u, w) of the plane with u x w = normal / |normal|: the polygon's
    // signed area is positive in it.
    const Vec3 nn = normal.normalized();
    int k = 0;
    nn.cwiseAbs().minCoeff(&k);
    const Vec3 u = nn.cross(Vec3::Unit(k)).normalized(), w = nn.cross(u);
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int i = 0; i < n_; ++i) {
      const Vec3 d = v[c[i]] - v[c[0]];
      p_[i] = Vec2(d.dot(u), d.dot(w));
      lo = lo.cwiseMin(p_[i]);
      hi = hi.cwiseMax(p_[i]);
      prev_[i] = (i + n_ - 1) % n_;
      next_[i] = (i + 1) % n_;
    }
    const double extent = std::max((hi - lo).maxCoeff(), std::numeric_limits<double>::min());
    eps_ = 1e-14 * extent * extent;
    build_grid(lo, hi);
  }

  void run(Face* out) {
    for (int i = 0; i < n_; ++i) push(i);
    int left = n_, written = 0;
    while (left > 3) {
      const int i = -std::get<3>(queue_.top()), version = std::get<4>(queue_.top());
      queue_.pop();
      if (removed_[i] || version != version_[i]) continue;  // stale: re-pushed since
      const int a = prev_[i], b = next_[i];
      out[written++] = {c_[a], c_[i], c_[b]};
      removed_[i] = 1;
      next_[a] = b;
      prev_[b] = a;
      --left;
      ++version_[a];
      ++version_[b];
      push(a);
      push(b);
    }
    int i = 0;
    while (removed_[i]) ++i;
    out[written] = {c_[prev_[i]], c_[i], c_[next_[i]]};
  }

 private:
  // Twice the signed area of (a, b, q).
  double orient(const Vec2& a, const Vec2& b, const Vec2& q) const {
    return (b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x());
  }
  bool convex(int i) const { return orient(p_[prev_[i]], p_[i], p_[next_[i]]) > eps_; }

  // Whether no other corner lies in the closed triangle (prev, i, next): only corners that are not
  // convex can, in a simple polygon (and only they are in the grid).
  bool clear(int i) const {
    const int a = prev_[i], b = next_[i];
    const Vec2 &pa = p_[a], &pi = p_[i], &pb = p_[b];
    const Vec2 lo = pa.cwiseMin(pi).cwiseMin(pb), hi = pa.cwiseMax(pi).cwiseMax(pb);
    const auto [x0, y0] = cell(lo);
    const auto [x1, y1] = cell(hi);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        for (int t = cell_start_[y * cells_ + x]; t < cell_start_[y * cells_ + x + 1]; ++t) {
          const int q = cell_items_[t];
          if (q == a || q == i || q == b || removed_[q] || convex(q)) continue;
          const Vec2& pq = p_[q];
          if (orient(pa, pi, pq) >= -eps_ && orient(pi, pb, pq) >= -eps_ && orient(pb, pa, pq) >= -eps_)
            return false;
        }
    return true;
  }

  // Queues corner i: ears first (tier 2), the smallest first (by the octave of the longest side:
  // cut in rounds, a circle of many corners gets triangles that nest, where the largest-first
  // order or a fan makes each of them cross the whole polygon), the best-shaped first among
  // those (4 sqrt(3) area over the sum of the squared sides: 1 for an equilateral triangle);
  // then convex corners whose triangle holds another corner (tier 1), then the rest (tier 0),
  // which only a polygon that is not simple reaches, so that the clipping always ends with n - 2
  // triangles.
  void push(int i) {
    const Vec2 &pa = p_[prev_[i]], &pi = p_[i], &pb = p_[next_[i]];
    const double area2 = orient(pa, pi, pb);
    const double ab = (pi - pa).squaredNorm(), bc = (pb - pi).squaredNorm(), ca = (pa - pb).squaredNorm();
    const double sides = ab + bc + ca;
    const double quality = sides > 0 ? 2.0 * std::sqrt(3.0) * area2 / sides : 0.0;
    const int tier = area2 > eps_ ? (clear(i) ? 2 : 1) : 0;
    const int octave = tier == 2 ? std::ilogb(std::max({ab, bc, ca})) : 0;
    queue_.push({tier, -octave, quality, -i, version_[i]});
  }

  // A uniform grid over the corners that are not convex at the start (a corner only turns
  // convex as ears are cut next to it), about one per cell.
  void build_grid(const Vec2& lo, const Vec2& hi) {
    std::vector<int> items;
    for (int i = 0; i < n_; ++i)
      if (!convex(i)) items.push_back(i);
    cells_ = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(items.size()))));
    lo_ = lo;
    const Vec2 size = (hi - lo).cwiseMax(std::numeric_limits<double>::min());
    inv_cell_ = Vec2(cells_ / size.x(), cells_ / size.y());
    cell_start_.assign(static_cast<std::size_t>(cells_) * cells_ + 1, 0);
    auto index = [&](int i) {
      const auto [x, y] = cell(p_[i]);
      return y * cells_ + x;
    };
    for (int i : items) ++cell_start_[index(i) + 1];
    for (std::size_t k = 1; k < cell_start_.size(); ++k) cell_start_[k] += cell_start_[k - 1];
    cell_items_.resize(items.size());
    std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (int i : items) cell_items_[fill[index(i)]++] = i;
  }
  std::pair<int, int> cell(const Vec2& q) const {
    auto clamp = [&](double t) {  // NaN and infinities (from overflowing coordinates) too, without UB
      if (!(t >= 1.0)) return 0;
      return t < cells_ ? static_cast<int>(t) : cells_ - 1;
    };
    return {clamp((q.x() - lo_.x()) * inv_cell_.x()), clamp((q.y() - lo_.y()) * inv_cell_.y())};
  }

  const int* c_;
  int n_;
  std::vector<Vec2> p_;
  std::vector<int> prev_, next_, version_;
  std::vector<char> removed_;
  double eps_ = 0.0;
  int cells_ = 1;
  Vec2 lo_, inv_cell_;
  std::vector<int> cell_start_, cell_items_;
  // tier, -octave, quality, -corner, version
  std::priority_queue<std::tuple<int, int, double, int, int>> queue_;
};

}  // namespace

void triangulate_polygon(const std::vector<Vec3>& v, const int* c, std::size_t n, Face* out) {
  // Newell: twice the area vector, from the corners relative to the first (the same sum): from
  // their absolute positions, a 3 cm face at 1e7 lost its area to rounding (a flipped fan).
  Vec3 normal = Vec3::Zero();
  const Vec3 o = v[c[0]];
  for (std::size_t i = 1; i + 1 < n; ++i) normal += (v[c[i]] - o).cross(v[c[i + 1]] - o);
  // Scaled to a largest component of 1, so that its square neither overflows nor underflows.
  const double largest = normal.cwiseAbs().maxCoeff();
  const bool flat = !(largest > 0) || !std::isfinite(largest);  // or overflowing, or NaN
  if (!flat) normal /= largest;
  std::size_t apex = 0;
  if (n <= 32 || flat) {
    double score = 0.0;
    if (n <= 32) apex = best_fan_apex(v, c, n, normal, score);
    // A fan whose every triangle faces the normal with some area (relative to the polygon's).
    // (score / |normal| is a triangle's doubled area along the normal, largest * |normal| the
    // polygon's.)
    if (flat || score > 1e-10 * largest * normal.squaredNorm()) {
      for (std::size_t i = 1; i + 1 < n; ++i)
        out[i - 1] = {c[apex], c[(apex + i) % n], c[(apex + i + 1) % n]};
      return;
    }
  }
  EarClipper(v, c, n, normal).run(out);
}

}  // namespace strata::internal
