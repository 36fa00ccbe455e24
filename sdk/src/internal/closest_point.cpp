#include "internal/closest_point.h"

#include <algorithm>
#include <limits>

namespace strata::internal {

namespace {

// The closest point to p on segment [a, b] (a point if a == b), as the parameter t along it.
double segment_param(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len_sq = ab.squaredNorm();
  return len_sq > 0.0 ? std::clamp((p - a).dot(ab) / len_sq, 0.0, 1.0) : 0.0;
}

}  // namespace

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  // A degenerate or sliver triangle (sin of its angle at a below 1e-6): the closest of its three
  // sides. The regions' tests below divide by differences that vanish there: two equal corners
  // gave 0/0 (a NaN point, and the tree returned a farther face or none), and a sliver's last
  // division by rounding noise a point off the triangle.
  if (ab.cross(ac).squaredNorm() <= 1e-12 * ab.squaredNorm() * ac.squaredNorm()) {
    const double tab = segment_param(p, a, b), tbc = segment_param(p, b, c), tca = segment_param(p, c, a);
    const Vec3 xab = a + tab * ab, xbc = b + tbc * (c - b), xca = c + tca * (a - c);
    const double dab = (xab - p).squaredNorm(), dbc = (xbc - p).squaredNorm(), dca = (xca - p).squaredNorm();
    if (dab <= dbc && dab <= dca) return bary = Vec3(1 - tab, tab, 0), xab;
    if (dbc <= dca) return bary = Vec3(0, 1 - tbc, tbc), xbc;
    return bary = Vec3(tca, 0, 1 - tca), xca;
  }
  // Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions of the triangle's features.
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return bary = Vec3(1, 0, 0), a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bary = Vec3(0, 1, 0), b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return bary = Vec3(1 - v, v, 0), a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return bary = Vec3(0, 0, 1), c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return bary = Vec3(1 - w, 0, w), a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return bary = Vec3(0, 1 - w, w), b + w * (c - b);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0.0)) return bary = Vec3(1, 0, 0), a;  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return bary = Vec3(1 - v - w, v, w), a + ab * v + ac * w;
}

TriangleTree::TriangleTree(const std::vector<Vec3>& vertices, const std::vector<Face>& faces)
    : vertices_(vertices), faces_(faces) {
  build_over(nullptr);
}

TriangleTree::TriangleTree(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                           const std::vector<int>& subset)
    : vertices_(vertices), faces_(faces) {
  build_over(&subset);
}

// Builds over local indices 0..n-1 (the subset's positions), then names the faces: over the whole
// mesh the local index is the face's, and the tree is the one built before subsets existed.
void TriangleTree::build_over(const std::vector<int>* subset) {
  const int n = static_cast<int>(subset ? subset->size() : faces_.size());
  order_.resize(n);
  std::vector<Eigen::AlignedBox3d> boxes(n);
  std::vector<Vec3> centroids(n);
  for (int i = 0; i < n; ++i) {
    order_[i] = i;
    const Face& f = faces_[subset ? (*subset)[i] : i];
    boxes[i] = Eigen::AlignedBox3d(vertices_[f[0]]);
    boxes[i].extend(vertices_[f[1]]).extend(vertices_[f[2]]);
    centroids[i] = (vertices_[f[0]] + vertices_[f[1]] + vertices_[f[2]]) / 3.0;
  }
  nodes_.reserve(2 * n / 4 + 2);
  if (n > 0) build(0, n, boxes, centroids);
  if (subset)
    for (int& i : order_) i = (*subset)[i];
}

int TriangleTree::build(int begin, int end, std::vector<Eigen::AlignedBox3d>& boxes,
                        std::vector<Vec3>& centroids) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box;
  Eigen::AlignedBox3d cbox;
  for (int i = begin; i < end; ++i) {
    box.extend(boxes[order_[i]]);
    cbox.extend(centroids[order_[i]]);
  }
  nodes_[id].box = box;
  if (end - begin <= 4) {
    nodes_[id].begin = begin;
    nodes_[id].end = end;
    return id;
  }
  int axis;
  cbox.sizes().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  const int left = build(begin, mid, boxes, centroids);
  const int right = build(mid, end, boxes, centroids);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

TriangleTree::Hit TriangleTree::closest(const Vec3& p) const {
  return closest(p, std::numeric_limits<double>::infinity());
}

const Eigen::AlignedBox3d& TriangleTree::bounds() const {
  static const Eigen::AlignedBox3d empty;
  return nodes_.empty() ? empty : nodes_.front().box;
}

TriangleTree::Hit TriangleTree::closest(const Vec3& p, double bound_sq) const {
  Hit best;
  best.distance_sq = bound_sq;
  if (nodes_.empty()) return best;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.box.squaredExteriorDistance(p) >= best.distance_sq) continue;
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const Face& f = faces_[order_[i]];
        Vec3 bary;
        const Vec3 x = closest_point_on_triangle(p, vertices_[f[0]], vertices_[f[1]], vertices_[f[2]], bary);
        const double d = (x - p).squaredNorm();
        if (d < best.distance_sq) best = Hit{order_[i], x, bary, d};
      }
      continue;
    }
    // Visit the nearer child first so the bound tightens early.
    const double dl = nodes_[node.left].box.squaredExteriorDistance(p);
    const double dr = nodes_[node.right].box.squaredExteriorDistance(p);
    if (dl < dr) {
      stack[top++] = node.right;
      stack[top++] = node.left;
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  return best;
}

}  // namespace strata::internal
