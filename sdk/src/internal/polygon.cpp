#include "internal/polygon.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <queue>
#include <tuple>

namespace strata::internal {
namespace {

using Vec2 = Eigen::Vector2d;

// Polygons the ear clipping could not cut whose corners are at most this many get the exact
// search (max_min_area_triangulation(), O(n^3)): 2.7 million steps at most.
constexpr std::size_t kExactMaxCorners = 256;

// The polygon's corners relative to its first, in units of 2^exponent, the power of two just above
// its largest coordinate: exact (barring subnormals), and neither the differences, their cross
// products nor their squares overflow or underflow at 1e+-300, nor lose a small face far from the
// origin (a 3 cm face at 1e7) to rounding. Into \p w; false (w empty) if a coordinate is not
// finite.
bool local_corners(const std::vector<Vec3>& v, const int* c, std::size_t n, std::vector<Vec3>& w,
                   int& exponent) {
  w.clear();
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!v[c[i]].allFinite()) return false;
    largest = std::max(largest, v[c[i]].cwiseAbs().maxCoeff());
  }
  std::frexp(largest, &exponent);
  w.resize(n);
  if (std::abs(exponent) < 1000) {  // 2^-exponent is a double: a product, not a call per coordinate
    const double scale = std::ldexp(1.0, -exponent);
    for (std::size_t i = 0; i < n; ++i) w[i] = v[c[i]] * scale - v[c[0]] * scale;
  } else {
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        w[i][k] = std::ldexp(v[c[i]][k], -exponent) - std::ldexp(v[c[0]][k], -exponent);
  }
  return true;
}

// The fan apex whose smallest triangle, measured along \p normal, is largest; that measure in
// \p score. O(n^2): small polygons only.
std::size_t best_fan_apex(const std::vector<Vec3>& w, const Vec3& normal, double& score) {
  const std::size_t n = w.size();
  std::size_t best = 0;
  score = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    double s = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i + 1 < n; ++i)
      s = std::min(s, triangle_area_normal(w[k], w[(k + i) % n], w[(k + i + 1) % n]).dot(normal));
    if (s > score) {
      score = s;
      best = k;
    }
  }
  return best;
}

// Twice the signed area of (a, b, q).
double orient(const Vec2& a, const Vec2& b, const Vec2& q) {
  return (b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x());
}

// The corners \p w in an orthonormal basis (u, t) of the plane of \p normal (not zero) with
// u x t = normal / |normal|, so that the polygon's signed area is positive there; into \p p.
// Returns the doubled area within rounding of zero there: 1e-14 of the squared extent.
double plane_coordinates(const std::vector<Vec3>& w, const Vec3& normal, std::vector<Vec2>& p) {
  const Vec3 nn = normal.normalized();
  int k = 0;
  nn.cwiseAbs().minCoeff(&k);
  const Vec3 u = nn.cross(Vec3::Unit(k)).normalized(), t = nn.cross(u);
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  p.resize(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) {
    p[i] = Vec2(w[i].dot(u), w[i].dot(t));
    lo = lo.cwiseMin(p[i]);
    hi = hi.cwiseMax(p[i]);
  }
  const double extent = std::max((hi - lo).maxCoeff(), std::numeric_limits<double>::min());
  return 1e-14 * extent * extent;
}

// Whether two of the polygon's sides cross by more than rounding: each one's ends on either side of
// the other's line, in the plane of \p normal (not zero), by more than 1e-14 of the squared
// extent (sides that meet within rounding touch). A polygon that crosses itself has no
// triangulation without overlaps: any of positive triangles covers twice where it winds twice.
// O(n log n) plus the pairs of sides whose intervals along one axis overlap; past 64 n + 100,000
// such pairs (spokes that all span the centre) the answer is false, unknown, so that the test
// never costs more than a bounded multiple of reading the polygon.
bool sides_cross(const std::vector<Vec3>& w, const Vec3& normal) {
  const std::size_t n = w.size();
  Vec3 lo = w[0], hi = w[0];
  for (const Vec3& x : w) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double extent = (hi - lo).maxCoeff(), eps = 1e-14 * extent * extent * normal.norm();
  auto orient = [&normal](const Vec3& a, const Vec3& b, const Vec3& q) {
    return (b - a).cross(q - a).dot(normal);
  };
  auto opposite = [eps](double x, double y) { return (x > eps && y < -eps) || (x < -eps && y > eps); };
  // Sweep and prune along the coordinate axis that lies most in the plane: only sides whose
  // intervals there overlap can cross (all pairs took 0.84 ms for a 256-corner star, 12 times its
  // triangulation).
  int axis = 0;
  normal.cwiseAbs().minCoeff(&axis);
  thread_local std::vector<std::pair<double, int>> order;
  order.clear();
  for (std::size_t i = 0; i < n; ++i)
    order.emplace_back(std::min(w[i][axis], w[(i + 1) % n][axis]), static_cast<int>(i));
  std::sort(order.begin(), order.end());
  long long budget = 64 * static_cast<long long>(n) + 100000;
  for (std::size_t p = 0; p < n; ++p) {
    const int i = order[p].second;
    const Vec3 &a = w[i], &b = w[(i + 1) % n];
    const double end = std::max(a[axis], b[axis]);
    for (std::size_t q = p + 1; q < n && order[q].first <= end; ++q) {
      if (--budget < 0) return false;
      const int j = order[q].second;
      const int gap = std::abs(i - j);
      if (gap <= 1 || gap == static_cast<int>(n) - 1) continue;  // sides sharing a corner
      const Vec3 &c = w[j], &d = w[(j + 1) % n];
      if (opposite(orient(a, b, c), orient(a, b, d)) && opposite(orient(c, d, a), orient(c, d, b)))
        return true;
    }
  }
  return false;
}

// The triangulation of the polygon \p p (counter-clockwise) whose smallest triangle is largest,
// by dynamic programming over its chains (i..j cut by a triangle (i, k, j)): O(n^3) time, O(n^2)
// memory. For a polygon whose sides do not cross, any triangulation of positive triangles covers
// it once (their winding numbers sum to the polygon's, 1 inside and 0 outside), whatever the
// diagonals: so no visibility test is needed, and the rounding that traps the ear clipping
// (corners within 1e-14 of a line through others) does not. Writes \p out and returns true if
// the smallest doubled area exceeds -\p eps: a triangle within rounding of zero area is left to
// the mesh validation, which names it (the polygon has a part of zero width).
bool max_min_area_triangulation(const std::vector<Vec2>& p, double eps, std::array<int, 3>* out) {
  const int n = static_cast<int>(p.size());
  std::vector<double> best(static_cast<std::size_t>(n) * n, std::numeric_limits<double>::infinity());
  std::vector<int> apex(static_cast<std::size_t>(n) * n, -1);
  auto at = [n](int i, int j) { return static_cast<std::size_t>(i) * n + j; };
  for (int len = 2; len < n; ++len)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      double b = -std::numeric_limits<double>::infinity();
      for (int k = i + 1; k < j; ++k) {
        const double s = std::min({orient(p[i], p[k], p[j]), best[at(i, k)], best[at(k, j)]});
        if (s > b) {
          b = s;
          apex[at(i, j)] = k;
        }
      }
      best[at(i, j)] = b;
    }
  if (!(best[at(0, n - 1)] > -eps)) return false;
  int written = 0;
  std::vector<std::pair<int, int>> chains{{0, n - 1}};  // still to cut
  while (!chains.empty()) {
    const auto [i, j] = chains.back();
    chains.pop_back();
    if (j - i < 2) continue;
    const int k = apex[at(i, j)];
    out[written++] = {i, k, j};
    chains.push_back({i, k});
    chains.push_back({k, j});
  }
  return written == n - 2;
}

// A static k-d tree over some of the corners, from which corners are removed: the clipper's
// candidates for blocking an ear. Subtrees without live corners are skipped, so a query costs about
// the live corners near its box, however the corners cluster (a uniform grid over a comb's base or
// a zigzag in a large square scanned thousands of dead or distant entries per ear).
class CornerTree {
 public:
  CornerTree(const std::vector<Vec2>& p, std::vector<int> items) : p_(p), order_(std::move(items)) {
    pos_.assign(p.size(), -1);
    dead_.assign(p.size(), 0);
    if (!order_.empty()) {
      nodes_.resize(1);
      build(0, 0, static_cast<int>(order_.size()));
    }
    for (int k = 0; k < static_cast<int>(order_.size()); ++k) pos_[order_[k]] = k;
  }

  //! Takes corner \p i out (a no-op if it is not in the tree or already out).
  void remove(int i) {
    if (pos_[i] < 0 || dead_[i]) return;
    dead_[i] = 1;
    for (int k = 0;;) {
      Node& nd = nodes_[k];
      --nd.alive;
      if (nd.left < 0) break;
      k = pos_[i] < nodes_[nd.left].end ? nd.left : nd.left + 1;
    }
  }

  //! Whether \p hit(i) holds for a live corner i in the box [lo, hi]; subtrees whose box
  //! \p outside(lo, hi) rules out are skipped.
  template <class Outside, class Hit>
  bool any(const Vec2& lo, const Vec2& hi, Outside&& outside, Hit&& hit) const {
    if (nodes_.empty()) return false;
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& nd = nodes_[stack[--top]];
      if (nd.alive == 0 || (nd.lo.array() > hi.array()).any() || (nd.hi.array() < lo.array()).any() ||
          outside(nd.lo, nd.hi))
        continue;
      if (nd.left < 0) {
        for (int k = nd.begin; k < nd.end; ++k) {
          const int i = order_[k];
          if (!dead_[i] && hit(i)) return true;
        }
      } else {
        stack[top++] = nd.left;
        stack[top++] = nd.left + 1;
      }
    }
    return false;
  }

 private:
  struct Node {
    Vec2 lo, hi;
    int begin, end, alive;
    int left = -1;  // children left, left + 1; -1 for a leaf
  };
  // Node \p slot over order_[b, e): split at the median of its box's longer side, down to 8
  // corners, the children in two adjacent slots. The depth is at most log2(n / 8) + 1, well
  // within the query's stack.
  void build(int slot, int b, int e) {
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int t = b; t < e; ++t) {
      lo = lo.cwiseMin(p_[order_[t]]);
      hi = hi.cwiseMax(p_[order_[t]]);
    }
    Node nd;
    nd.lo = lo;
    nd.hi = hi;
    nd.begin = b;
    nd.end = e;
    nd.alive = e - b;
    if (e - b > 8) {
      const int axis = (hi - lo).x() >= (hi - lo).y() ? 0 : 1, m = b + (e - b) / 2;
      std::nth_element(order_.begin() + b, order_.begin() + m, order_.begin() + e,
                       [&](int x, int y) { return p_[x][axis] < p_[y][axis]; });
      nd.left = static_cast<int>(nodes_.size());
      nodes_.resize(nodes_.size() + 2);
      build(nd.left, b, m);
      build(nd.left + 1, m, e);
    }
    nodes_[slot] = nd;
  }

  const std::vector<Vec2>& p_;
  std::vector<int> order_, pos_;
  std::vector<char> dead_;
  std::vector<Node> nodes_;
};

// Ear clipping of a polygon projected to the plane of its normal (counter-clockwise there), the
// smallest ear first. Corners are positions 0..n-1 of the polygon, linked in a ring.
class EarClipper {
 public:
  //! \p w: the corners (local_corners()); \p normal: their Newell normal (not zero);
  //! \p min_area2: a doubled area below which a triangle is a sliver (as the mesh validation's
  //! zero area), in w's units.
  EarClipper(const std::vector<Vec3>& w, const Vec3& normal, double min_area2)
      : n_(static_cast<int>(w.size())),
        p_(w.size()),
        prev_(w.size()),
        next_(w.size()),
        version_(w.size(), 0),
        removed_(w.size(), 0) {
    eps_ = plane_coordinates(w, normal, p_);
    for (int i = 0; i < n_; ++i) {
      prev_[i] = (i + n_ - 1) % n_;
      next_[i] = (i + 1) % n_;
    }
    sliver_ = std::max(eps_, min_area2);
    std::vector<int> items;
    for (int i = 0; i < n_; ++i)
      if (!convex(i)) items.push_back(i);
    tree_ = std::make_unique<CornerTree>(p_, std::move(items));
  }

  //! The corners in the plane (plane_coordinates()).
  const std::vector<Vec2>& points() const { return p_; }
  //! The doubled area within rounding of zero, in the plane's units.
  double eps() const { return eps_; }

  //! Writes the n - 2 triangles, as positions of the polygon's corners, to \p out. Returns
  //! whether each was an ear (else some overlap: the polygon crosses itself or is degenerate).
  bool run(std::array<int, 3>* out) {
    for (int i = 0; i < n_; ++i) push(i);
    int left = n_, written = 0;
    bool ears = true;
    while (left > 3) {
      const int i = -std::get<3>(queue_.top()), version = std::get<4>(queue_.top());
      const bool ear = std::get<0>(queue_.top()) >= 2;
      queue_.pop();
      if (removed_[i] || version != version_[i]) continue;  // stale: re-pushed since
      ears = ears && ear;
      const int a = prev_[i], b = next_[i];
      out[written++] = {a, i, b};
      removed_[i] = 1;
      tree_->remove(i);
      next_[a] = b;
      prev_[b] = a;
      --left;
      for (int j : {a, b}) {
        ++version_[j];
        if (convex(j)) tree_->remove(j);  // a corner only turns convex as its neighbours go
        push(j);
      }
    }
    int i = 0;
    while (removed_[i]) ++i;
    out[written] = {prev_[i], i, next_[i]};
    return ears && turn(i) > 0;
  }

 private:
  double turn(int i) const { return orient(p_[prev_[i]], p_[i], p_[next_[i]]); }
  // Convex by more than a sliver: a corner nearly on the line of its neighbours counts as reflex,
  // so that it is cut off by a wider triangle and can block an ear whose side it lies on.
  bool convex(int i) const { return turn(i) > sliver_; }

  // Whether no other corner lies in the closed triangle (prev, i, next): only corners that are not
  // convex can, in a simple polygon (and only they are in the tree).
  bool clear(int i) const {
    const int a = prev_[i], b = next_[i];
    const Vec2 &pa = p_[a], &pi = p_[i], &pb = p_[b];
    // A box all of whose corners lie outside one side of the triangle: a long thin ear (a comb's
    // base, whose corners all fan from its two ends) skips the corners along it.
    auto outside = [&](const Vec2& lo, const Vec2& hi) {
      const Vec2 box[4] = {lo, hi, Vec2(lo.x(), hi.y()), Vec2(hi.x(), lo.y())};
      for (const auto& [s, t] : {std::pair{&pa, &pi}, std::pair{&pi, &pb}, std::pair{&pb, &pa}}) {
        bool all = true;
        for (const Vec2& q : box) all = all && orient(*s, *t, q) < -eps_;
        if (all) return true;
      }
      return false;
    };
    return !tree_->any(pa.cwiseMin(pi).cwiseMin(pb), pa.cwiseMax(pi).cwiseMax(pb), outside, [&](int q) {
      if (q == a || q == i || q == b || convex(q)) return false;
      const Vec2& pq = p_[q];
      return orient(pa, pi, pq) >= -eps_ && orient(pi, pb, pq) >= -eps_ && orient(pb, pa, pq) >= -eps_;
    });
  }

  // Queues corner i: ears first (tier 3), the smallest first (by the octave of the longest side:
  // cut in rounds, a circle of many corners gets triangles that nest, where the largest-first
  // order or a fan makes each of them cross the whole polygon), the best-shaped first among
  // those (4 sqrt(3) area over the sum of the squared sides: 1 for an equilateral triangle); then
  // ears that would be slivers (tier 2), convex corners whose triangle holds another corner
  // (tier 1) and the rest (tier 0), which only a degenerate or self-crossing polygon reaches, so
  // that the clipping always ends with n - 2 triangles.
  void push(int i) {
    const Vec2 &pa = p_[prev_[i]], &pi = p_[i], &pb = p_[next_[i]];
    const double area2 = turn(i);
    const double ab = (pi - pa).squaredNorm(), bc = (pb - pi).squaredNorm(), ca = (pa - pb).squaredNorm();
    const double sides = ab + bc + ca;
    const double quality = sides > 0 ? 2.0 * std::sqrt(3.0) * area2 / sides : 0.0;
    const int tier = area2 > eps_ ? (clear(i) ? (area2 > sliver_ ? 3 : 2) : 1) : 0;
    const int octave = tier >= 2 ? std::ilogb(std::max({ab, bc, ca})) : 0;
    queue_.push({tier, -octave, quality, -i, version_[i]});
  }

  int n_;
  std::vector<Vec2> p_;
  std::vector<int> prev_, next_, version_;
  std::vector<char> removed_;
  double eps_ = 0.0, sliver_ = 0.0;
  std::unique_ptr<CornerTree> tree_;
  // tier, -octave, quality, -corner, version
  std::priority_queue<std::tuple<int, int, double, int, int>> queue_;
};

}  // namespace

bool triangulate_polygon(const std::vector<Vec3>& v, const int* c, std::size_t n, double mesh_diagonal,
                         Face* out) {
  int exponent = 0;
  thread_local std::vector<Vec3> w;  // reused: a file of millions of quads allocates it once
  local_corners(v, c, n, w, exponent);
  Vec3 normal = Vec3::Zero();  // Newell: twice the area vector (w[0] = 0)
  for (std::size_t i = 1; i + 1 < w.size(); ++i) normal += w[i].cross(w[i + 1]);
  const double largest = normal.cwiseAbs().maxCoeff();
  const bool flat = w.empty() || !(largest > 0) || !std::isfinite(largest);
  auto fan = [&](std::size_t apex) {
    for (std::size_t i = 1; i + 1 < n; ++i) out[i - 1] = {c[apex], c[(apex + i) % n], c[(apex + i + 1) % n]};
  };
  // (A quad that crosses itself needs no test: each diagonal cuts it into triangles of opposite
  // orientations, so it has no fan below, and quads are most of the polygons files hold.) Up to
  // kExactMaxCorners corners the sweep's budget covers every pair: the exact search below never
  // meets a crossing polygon.
  if (!flat && n >= 5 && sides_cross(w, normal)) {
    fan(0);
    return false;
  }
  if (n <= 32 || flat) {
    double score = 0.0;
    const std::size_t apex = n <= 32 && !flat ? best_fan_apex(w, normal, score) : 0;
    // A fan whose every triangle faces the normal with some area: score / |normal| is a triangle's
    // doubled area along the normal, |normal| the polygon's.
    if (flat || score > 1e-10 * normal.squaredNorm()) {
      fan(apex);
      if (!flat || w.empty()) return true;
      // A zero normal with corners off a line: lobes of opposite orientation (a bow tie).
      double spread = 0.0;
      for (std::size_t i = 1; i + 1 < n; ++i) spread += w[i].cross(w[i + 1]).norm();
      return !(spread > 1e-12);
    }
  }
  std::vector<std::array<int, 3>> tri(n - 2);
  const double diagonal = std::ldexp(mesh_diagonal, -exponent);  // in w's units
  EarClipper clipper(w, normal, std::isfinite(diagonal) ? kZeroAreaRelative * diagonal * diagonal : 0.0);
  bool ears = clipper.run(tri.data());
  // Trapped by corners within rounding of a line through others (the sides do not cross, above).
  if (!ears && n <= kExactMaxCorners)
    ears = max_min_area_triangulation(clipper.points(), clipper.eps(), tri.data());
  for (std::size_t k = 0; k + 2 < n; ++k) out[k] = {c[tri[k][0]], c[tri[k][1]], c[tri[k][2]]};
  return ears;
}

}  // namespace strata::internal
