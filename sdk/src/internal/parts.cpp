#include "internal/parts.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "internal/closest_point.h"
#include "internal/welder.h"

namespace strata::internal {

Parts connected_parts(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                      bool join_equal_positions) {
  const int nv = static_cast<int>(vertices.size());
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto join = [&](int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (const Face& f : faces)
    for (int c = 1; c < 3; ++c) join(f[0], f[c]);
  if (join_equal_positions) {
    Welder welder;
    std::vector<int> first;  // per welded position: the first vertex there
    for (int v = 0; v < nv; ++v) {
      const auto w = static_cast<std::size_t>(welder.index_of(vertices[v]));
      if (w == first.size())
        first.push_back(v);
      else
        join(first[w], v);
    }
  }
  Parts p;
  p.of_vertex.assign(nv, -1);
  std::vector<int> part_of_root(nv, -1);
  for (const Face& f : faces) {
    int& part = part_of_root[find(f[0])];
    if (part < 0) part = p.count++;
  }
  for (const Face& f : faces)
    for (int v : f) p.of_vertex[v] = part_of_root[find(v)];
  return p;
}

namespace {

// The points of each part that decide where it lies: its vertices and its faces' centroids,
// at most kSamples of each (evenly strided: the cost stays bounded by the parts' count, and a
// large part's side of the vote is clear from a few), and the centroid of its vertices.
constexpr int kSamples = 128;

std::vector<std::vector<Vec3>> part_samples(const Parts& bp, const std::vector<Vec3>& x,
                                            const std::vector<Face>& faces) {
  std::vector<int> nv(bp.count, 0), nf(bp.count, 0);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (bp.of_vertex[v] >= 0) ++nv[bp.of_vertex[v]];
  for (const Face& f : faces) ++nf[bp.of_face(f)];
  auto stride = [](int n) { return (n + kSamples - 1) / kSamples; };
  std::vector<std::vector<Vec3>> samples(bp.count);
  std::vector<Vec3> sum(bp.count, Vec3::Zero());
  std::vector<int> seen(bp.count, 0);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (const int p = bp.of_vertex[v]; p >= 0) {
      sum[p] += x[v];
      if (seen[p]++ % stride(nv[p]) == 0) samples[p].push_back(x[v]);
    }
  std::fill(seen.begin(), seen.end(), 0);
  for (const Face& f : faces)
    if (const int p = bp.of_face(f); seen[p]++ % stride(nf[p]) == 0)
      samples[p].push_back((x[f[0]] + x[f[1]] + x[f[2]]) / 3.0);
  for (int p = 0; p < bp.count; ++p) samples[p].push_back(sum[p] / nv[p]);
  return samples;
}

// The closest points of \p points on \p tree, as distances (on TBB's threads).
std::vector<double> distances_to(const TriangleTree& tree, const std::vector<Vec3>& points) {
  std::vector<double> d(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        d[i] = std::sqrt(tree.closest(points[i]).distance_sq);
                    });
  return d;
}

// For each part of mesh A (given by its samples), the part of mesh B (\p x, \p faces, parts
// \p parts) that its samples lie nearest to on average, among the parts of their closest faces
// (the lower part on a tie): a closest face alone gave debris that lies against a surface to the
// surface. Each contested candidate gets a tree of its own faces.
std::vector<int> nearest_parts(const std::vector<std::vector<Vec3>>& samples, const std::vector<Vec3>& x,
                               const std::vector<Face>& faces, const Parts& parts) {
  const int na = static_cast<int>(samples.size());
  const TriangleTree tree(x, faces);
  std::vector<std::vector<int>> candidates(na);
  tbb::parallel_for(tbb::blocked_range<int>(0, na, 1), [&](const tbb::blocked_range<int>& r) {
    for (int p = r.begin(); p != r.end(); ++p) {
      for (const Vec3& y : samples[p]) candidates[p].push_back(parts.of_face(faces[tree.closest(y).face]));
      std::sort(candidates[p].begin(), candidates[p].end());
      candidates[p].erase(std::unique(candidates[p].begin(), candidates[p].end()), candidates[p].end());
    }
  });
  std::vector<std::vector<int>> faces_of(parts.count);
  for (int j = 0; j < static_cast<int>(faces.size()); ++j) faces_of[parts.of_face(faces[j])].push_back(j);
  std::vector<std::unique_ptr<TriangleTree>> part_tree(parts.count);
  std::vector<int> nearest(na, -1);
  for (int p = 0; p < na; ++p) {
    nearest[p] = candidates[p].front();  // were every mean not finite
    if (candidates[p].size() == 1) continue;
    double best = std::numeric_limits<double>::infinity();
    for (int b : candidates[p]) {
      if (!part_tree[b]) part_tree[b] = std::make_unique<TriangleTree>(x, faces, faces_of[b]);
      const std::vector<double> dist = distances_to(*part_tree[b], samples[p]);
      const double mean = std::accumulate(dist.begin(), dist.end(), 0.0) / static_cast<double>(dist.size());
      if (mean < best) {
        best = mean;
        nearest[p] = b;
      }
    }
  }
  return nearest;
}

}  // namespace

PartMatch match_parts(const TriMesh& detail, const std::vector<Vec3>& base_vertices,
                      const std::vector<Face>& base_faces) {
  PartMatch m;
  const Parts dp = connected_parts(detail.vertices, detail.faces, true);
  if (dp.count < 2) return m;
  if (base_faces == detail.faces && base_vertices.size() == detail.vertices.size()) {
    // The detail's own connectivity (a base smoothed from it, as the region editors' and
    // `strata deform`'s): each part's base is its own faces, whatever the smoothing moved.
    m.part_faces.resize(dp.count);
    for (int j = 0; j < static_cast<int>(base_faces.size()); ++j)
      m.part_faces[dp.of_face(base_faces[j])].push_back(j);
    m.groups.resize(dp.count);
    for (int d = 0; d < dp.count; ++d) m.groups[d] = {d};
    m.group_of_vertex = dp.of_vertex;
    return m;
  }
  const Parts bp = connected_parts(base_vertices, base_faces, true);
  if (bp.count < 2) return m;
  // Both ways: each base part lies on a detail part (its owner), and each detail part on a base
  // part. A detail part's base is the base parts that lie on it and the one it lies on: a base
  // part that no detail part lies on (debris of the base alone) went to a nearby detail part and,
  // with only the owners, became that part's whole base.
  const std::vector<int> owner =
      nearest_parts(part_samples(bp, base_vertices, base_faces), detail.vertices, detail.faces, dp);
  const std::vector<int> under =
      nearest_parts(part_samples(dp, detail.vertices, detail.faces), base_vertices, base_faces, bp);
  std::vector<std::vector<int>> base_parts(dp.count);  // each detail part's, sorted
  for (int b = 0; b < bp.count; ++b) base_parts[owner[b]].push_back(b);
  for (int d = 0; d < dp.count; ++d) {
    std::vector<int>& s = base_parts[d];
    if (!std::binary_search(s.begin(), s.end(), under[d]))
      s.insert(std::upper_bound(s.begin(), s.end(), under[d]), under[d]);
  }
  // One group per distinct set of base parts (detail parts on one base part share its tree).
  std::vector<int> group_of_part(dp.count, -1);
  std::vector<int> order(dp.count);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return base_parts[a] < base_parts[b]; });
  std::vector<std::vector<int>> groups_parts;
  for (int d : order) {
    if (groups_parts.empty() || groups_parts.back() != base_parts[d]) groups_parts.push_back(base_parts[d]);
    group_of_part[d] = static_cast<int>(groups_parts.size()) - 1;
  }
  // One group holds every base part (each is in its owner's set), so it restricts nothing.
  if (groups_parts.size() == 1) return m;
  m.part_faces.resize(bp.count);
  for (int j = 0; j < static_cast<int>(base_faces.size()); ++j)
    m.part_faces[bp.of_face(base_faces[j])].push_back(j);
  m.groups = std::move(groups_parts);
  m.group_of_vertex.resize(detail.vertices.size());
  for (std::size_t v = 0; v < detail.vertices.size(); ++v)
    m.group_of_vertex[v] = dp.of_vertex[v] < 0 ? -1 : group_of_part[dp.of_vertex[v]];
  return m;
}

std::vector<int> PartMatch::faces(int g) const {
  std::vector<int> f;
  for (int b : groups[g]) f.insert(f.end(), part_faces[b].begin(), part_faces[b].end());
  std::sort(f.begin(), f.end());
  return f;
}

namespace {
// A group of at most this many parts is searched part by part (each part's box tested first).
constexpr std::size_t kPartsSearchedInTurn = 8;
}  // namespace

GroupedTrees::GroupedTrees(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                           const PartMatch& match)
    : match_(match) {
  trees_.reserve(match.part_faces.size());
  for (const std::vector<int>& part : match.part_faces) trees_.emplace_back(vertices, faces, part);
  boxes_.resize(match.groups.size());
  for (std::size_t g = 0; g < match.groups.size(); ++g) {
    if (match.groups[g].size() <= kPartsSearchedInTurn) continue;
    PartBoxes& t = boxes_[g];
    t.parts = match.groups[g];
    t.nodes.reserve(t.parts.size() / 2 + 2);
    build(t, 0, static_cast<int>(t.parts.size()));
  }
}

// Median split of the parts' box centres along the longest axis; leaves of at most 4 parts.
int GroupedTrees::build(PartBoxes& t, int begin, int end) const {
  const int id = static_cast<int>(t.nodes.size());
  t.nodes.emplace_back();
  Eigen::AlignedBox3d box, centres;
  for (int i = begin; i < end; ++i) {
    box.extend(trees_[t.parts[i]].bounds());
    centres.extend(trees_[t.parts[i]].bounds().center());
  }
  t.nodes[id].box = box;
  if (end - begin <= 4) {
    t.nodes[id].begin = begin;
    t.nodes[id].end = end;
    return id;
  }
  int axis;
  centres.sizes().maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(t.parts.begin() + begin, t.parts.begin() + mid, t.parts.begin() + end, [&](int a, int b) {
    const double ca = trees_[a].bounds().center()[axis], cb = trees_[b].bounds().center()[axis];
    return ca < cb || (ca == cb && a < b);
  });
  const int left = build(t, begin, mid);
  const int right = build(t, mid, end);
  t.nodes[id].left = left;
  t.nodes[id].right = right;
  return id;
}

TriangleTree::Hit GroupedTrees::closest(int g, const Vec3& p) const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  TriangleTree::Hit best;
  best.distance_sq = inf;
  int best_part = std::numeric_limits<int>::max();
  // Part b's closest point replaces the best if nearer, or as near from a lower part: the result
  // of searching the parts in ascending order, in any order. Each part's search is bounded by the
  // best so far (then it finds its closest point only if that is the nearer one, and the same).
  auto visit = [&](int b) {
    const double box = trees_[b].bounds().squaredExteriorDistance(p);
    if (box > best.distance_sq || (box == best.distance_sq && b > best_part)) return;
    const double bound = b < best_part ? std::nextafter(best.distance_sq, inf) : best.distance_sq;
    const TriangleTree::Hit h = trees_[b].closest(p, bound);
    if (h.face >= 0) {
      best = h;
      best_part = b;
    }
  };
  const PartBoxes& t = boxes_[g];
  if (t.nodes.empty()) {
    for (int b : match_.groups[g]) visit(b);
    return best;
  }
  int stack[128];  // a balanced tree: depth log2(parts / 4), and at most one more entry per level
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BoxNode& node = t.nodes[stack[--top]];
    if (node.box.squaredExteriorDistance(p) > best.distance_sq) continue;
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i) visit(t.parts[i]);
      continue;
    }
    // The nearer child first, so that the bound tightens early.
    const bool left_first = t.nodes[node.left].box.squaredExteriorDistance(p) <=
                            t.nodes[node.right].box.squaredExteriorDistance(p);
    stack[top++] = left_first ? node.right : node.left;
    stack[top++] = left_first ? node.left : node.right;
  }
  return best;
}

}  // namespace strata::internal
