#include "strata/intersections.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cassert>
#include <climits>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <unordered_set>

#include "internal/cell_grid.h"
#include "internal/intersection_update.h"
#include "strata/exceptions.h"

namespace strata {
namespace {

// Epick's predicates are filtered: interval arithmetic first, exact arithmetic when it cannot decide.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Pair = std::pair<int, int>;

// Small leaves keep the leaf-against-leaf loops short; the per-triangle box test inside them is cheap.
constexpr std::size_t kLeafSize = 4;
// Subtrees with fewer triangles than this are built or traversed as a single task: below it the
// task overhead outweighs the work.
constexpr std::size_t kParallelGrain = 4096;

Point to_point(const Vec3& p) {
  return Point(p.x(), p.y(), p.z());
}

bool is_finite(const Vec3& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Boxes are stored in float to halve the memory traffic of the traversal. They only prune (the
// exact predicate decides), so they must never be smaller than the triangle: round outward.
float round_down(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float round_up(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

// S: float, or double where float boxes would be loose (search_pairs()).
template <class S>
struct Box {
  S lo[3];
  S hi[3];
};

// Closed intervals: boxes that merely touch overlap, so touching triangles are not pruned.
template <class S>
inline bool overlap(const Box<S>& a, const Box<S>& b) {
  return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
         a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];
}

template <class S>
Box<S> merge(const Box<S>& a, const Box<S>& b) {
  Box<S> m;
  for (int k = 0; k < 3; ++k) {
    m.lo[k] = std::min(a.lo[k], b.lo[k]);
    m.hi[k] = std::max(a.hi[k], b.hi[k]);
  }
  return m;
}

// One non-degenerate face with its box, stored in leaf order so that a leaf's triangles are contiguous.
template <class S>
struct Prim {
  Box<S> box;
  std::array<int, 3> v;
  int face;  // index in the caller's face list
};

// A face as the build sees it: centroid and face index only (16 bytes), so that the median
// selections move little memory. face == -1 marks a degenerate face before compaction.
template <class S>
struct Item {
  S c[3];
  int face;
};

// Depth-first layout: an internal node (count == 0) has its left child right after it and its right
// child at `index`; a leaf owns prims [index, index + count). A node over m triangles splits them
// m/2 | m - m/2, so subtree sizes need not be stored.
template <class S>
struct Node {
  Box<S> box;
  int index;
  int count;
};

template <class S>
inline bool share_vertex(const Prim<S>& p, const Prim<S>& q) {
  for (int a : p.v)
    if (a == q.v[0] || a == q.v[1] || a == q.v[2]) return true;
  return false;
}

// Whether a separating axis proves triangles a and b disjoint in floating point, with a bound on
// the rounding: a pre-filter before CGAL's predicates, which fall back to exact arithmetic on
// (nearly) coplanar pairs, common in flat regions: on the paper's 100k cuboid a count took 0.19 s
// without this filter and 0.07 s with it (two threads). Any axis works, computed exactly or not:
// two convex sets whose projections onto some vector are disjoint are disjoint. false means only
// "not proved": CGAL decides.
//
// Bound (u = 2^-53): the points are translated to a's first vertex (each coordinate rounded once,
// |error| <= u |x|) and projected by a 3-term dot product (|error| <= 3u / (1 - 3u) sum |a_k x_k|),
// so every computed projection is within about 4u |axis|_1 M of the exact one, M the largest
// translated coordinate. The test asks for a computed gap of 32u |axis|_1 M, four times the 8u
// that two projections' errors can close, which also covers the rounding of the bound and the sum.
// Overflow gives an infinite or NaN bound, which never proves a gap.
bool separated(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
               const Vec3& b2) {
  Vec3 p[6] = {Vec3::Zero(), a1 - a0, a2 - a0, b0 - a0, b1 - a0, b2 - a0};
  double m = 0.0;
  for (const Vec3& x : p) m = std::max(m, x.cwiseAbs().maxCoeff());
  // The bound is relative: where the projections (on the in-plane axes, fourth powers of the
  // coordinates) underflow, their rounding is absolute and it fails (touching triangles at 2^-270
  // were "proved" apart). Tiny pairs are scaled by a power of 2 first, which is exact (differences
  // that small are exact too).
  if (m > 0.0 && m < 0x1p-200) {
    int e = 0;
    std::frexp(m, &e);
    for (Vec3& x : p) x = Vec3(std::ldexp(x.x(), -e), std::ldexp(x.y(), -e), std::ldexp(x.z(), -e));
    m = std::ldexp(m, -e);
  }
  constexpr double kRel = 16.0 * std::numeric_limits<double>::epsilon() / 2.0;
  auto apart = [&](const Vec3& axis) {
    const double bound = kRel * axis.cwiseAbs().sum() * m;
    const double s0 = axis.dot(p[0]), s1 = axis.dot(p[1]), s2 = axis.dot(p[2]);
    const double t0 = axis.dot(p[3]), t1 = axis.dot(p[4]), t2 = axis.dot(p[5]);
    const double alo = std::min({s0, s1, s2}), ahi = std::max({s0, s1, s2});
    const double blo = std::min({t0, t1, t2}), bhi = std::max({t0, t1, t2});
    return ahi + 2.0 * bound < blo || bhi + 2.0 * bound < alo;
  };
  const Vec3 ea[3] = {p[1], p[2] - p[1], -p[2]};
  const Vec3 eb[3] = {p[4] - p[3], p[5] - p[4], p[3] - p[5]};
  const Vec3 na = ea[0].cross(p[2]);
  const Vec3 nb = eb[0].cross(p[5] - p[3]);
  // The planes first (most pairs a box test lets through lie off each other's plane), then the
  // in-plane edge normals, which separate nearby coplanar triangles.
  if (apart(na) || apart(nb)) return true;
  for (const Vec3& e : ea)
    if (apart(na.cross(e))) return true;
  for (const Vec3& e : eb)
    if (apart(nb.cross(e))) return true;
  return false;
}

// Median-split BVH topology over the items, built top-down (in parallel for large subtrees). On
// return the items are in leaf order; boxes are filled in afterwards by fit_boxes().
template <class S>
class BvhBuilder {
 public:
  BvhBuilder(std::vector<Item<S>>& items, std::vector<Node<S>>& nodes) : items_(items), nodes_(nodes) {}

  void build() {
    if (items_.empty()) return;
    nodes_.resize(count_nodes(items_.size()));
    split(0, 0, items_.size());
  }

 private:
  // Node count of a subtree over m triangles, memoized (only O(log n) distinct sizes occur) so the
  // parallel build knows where each right subtree starts. Filled before the build, read-only during it.
  std::size_t count_nodes(std::size_t m) {
    if (m <= kLeafSize) return 1;
    const auto it = memo_.find(m);
    if (it != memo_.end()) return it->second;
    const std::size_t c = 1 + count_nodes(m / 2) + count_nodes(m - m / 2);
    memo_.emplace(m, c);
    return c;
  }
  std::size_t nodes_of(std::size_t m) const { return m <= kLeafSize ? 1 : memo_.at(m); }

  void split(std::size_t node, std::size_t b, std::size_t e) {
    Node<S>& nd = nodes_[node];
    if (e - b <= kLeafSize) {
      nd.index = static_cast<int>(b);
      nd.count = static_cast<int>(e - b);
      return;
    }
    // Split at the median centroid along the axis where the centroids spread most.
    constexpr S kMax = std::numeric_limits<S>::max();
    S lo[3] = {kMax, kMax, kMax}, hi[3] = {-kMax, -kMax, -kMax};
    for (std::size_t i = b; i < e; ++i)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], items_[i].c[k]);
        hi[k] = std::max(hi[k], items_[i].c[k]);
      }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    const std::size_t mid = b + (e - b) / 2;
    std::nth_element(items_.begin() + b, items_.begin() + mid, items_.begin() + e,
                     [axis](const Item<S>& p, const Item<S>& q) { return p.c[axis] < q.c[axis]; });

    const std::size_t left = node + 1, right = node + 1 + nodes_of(mid - b);
    if (e - b > kParallelGrain)
      tbb::parallel_invoke([&] { split(left, b, mid); }, [&] { split(right, mid, e); });
    else {
      split(left, b, mid);
      split(right, mid, e);
    }
    nd.index = static_cast<int>(right);
    nd.count = 0;
  }

  std::vector<Item<S>>& items_;
  std::vector<Node<S>>& nodes_;
  std::map<std::size_t, std::size_t> memo_;
};

// The vertices that every triangle of a subtree has (at most 3, ascending, -1 after them).
using Shared = std::array<int, 3>;
constexpr Shared kNoneShared = {-1, -1, -1};

// The vertices in both \p a and \p b.
inline Shared shared_by(const Shared& a, const std::array<int, 3>& b) {
  Shared out = kNoneShared;
  int k = 0;
  for (int v : a)
    if (v >= 0 && (v == b[0] || v == b[1] || v == b[2])) out[k++] = v;
  return out;
}

// Whether \p a and \p b list a vertex in common: then every pair of a triangle under one and a
// triangle under the other shares it, and none of them counts.
inline bool meet(const Shared& a, const Shared& b) {
  if (a[0] < 0 || b[0] < 0) return false;
  for (int v : a)
    if (v >= 0 && (v == b[0] || v == b[1] || v == b[2])) return true;
  return false;
}

// Bottom-up boxes and shared vertices: children come after their parent in the depth-first
// layout, so one backward sweep sees every child before its parent.
template <class S>
void fit_boxes(std::vector<Node<S>>& nodes, std::vector<Shared>& shared, const std::vector<Prim<S>>& prims) {
  shared.assign(nodes.size(), kNoneShared);
  for (std::size_t n = nodes.size(); n-- > 0;) {
    Node<S>& nd = nodes[n];
    if (nd.count > 0) {
      nd.box = prims[nd.index].box;
      Shared common = prims[nd.index].v;
      std::sort(common.begin(), common.end());
      for (int i = nd.index + 1; i < nd.index + nd.count; ++i) {
        nd.box = merge(nd.box, prims[i].box);
        common = shared_by(common, prims[i].v);
      }
      shared[n] = common;
    } else {
      nd.box = merge(nodes[n + 1].box, nodes[nd.index].box);
      shared[n] = shared_by(shared[n + 1], shared[nd.index]);
    }
  }
}

// A bounding-volume hierarchy over one face list: nodes in depth-first layout, prims in leaf order,
// and per node the vertices all its triangles share. A fan of k triangles around one vertex (a
// CAD cylinder's cap) has every box through that vertex: without them the search visited all k^2
// pairs (0.6 s for a 10,000-face fan) where none can count.
template <class S>
struct Tree {
  std::vector<Node<S>> nodes;
  std::vector<Prim<S>> prims;
  std::vector<Shared> shared;
};

// Traverses one tree against itself (each unordered pair of leaves whose boxes overlap is visited
// once, and each pair of triangles in them is tested once), or two trees against each other (each
// pair of a triangle of the first and one of the second, reported in that order).
template <class S>
class IntersectionSearch {
 public:
  IntersectionSearch(const std::vector<Vec3>& vertices, const Tree<S>& a, const Tree<S>& b,
                     const IntersectionOptions& options)
      : vertices_(vertices),
        a_(a),
        b_(b),
        collect_(options.collect_pairs),
        max_pairs_(options.max_pairs),
        max_tests_(options.max_tests),
        cancel_(options.cancel) {}

  void run() {
    if (&a_ == &b_) {
      if (!a_.prims.empty()) self(0, a_.prims.size());
    } else if (!a_.prims.empty() && !b_.prims.empty()) {
      cross(0, a_.prims.size(), 0, b_.prims.size());
    }
  }

  std::size_t found() const { return found_.load(); }
  bool truncated() const { return truncated_.load(); }
  bool out_of_tests() const { return out_of_tests_.load(); }
  std::size_t tests() const {
    std::size_t n = tests_.load();
    for (std::size_t t : pending_tests_) n += t;
    return n;
  }

  std::vector<Pair> take_pairs() {
    std::vector<Pair> all;
    for (const std::vector<Pair>& local : pairs_) all.insert(all.end(), local.begin(), local.end());
    std::sort(all.begin(), all.end());
    return all;
  }

 private:
  bool stopped() const {
    return truncated_.load(std::memory_order_relaxed) ||
           (cancel_ && cancel_->load(std::memory_order_relaxed));
  }

  template <class F, class G>
  static void fork(bool parallel, const F& f, const G& g) {
    if (parallel)
      tbb::parallel_invoke(f, g);
    else {
      f();
      g();
    }
  }

  // All pairs within subtree `n` (over m triangles) of the one tree (a_ == b_).
  void self(int n, std::size_t m) {
    if (stopped()) return;
    const Node<S>& nd = a_.nodes[n];
    if (a_.shared[n][0] >= 0) return;  // every pair in it shares a vertex
    if (nd.count > 0) {
      std::size_t tests = 0;
      for (int i = nd.index, end = nd.index + nd.count; i < end; ++i)
        for (int j = i + 1; j < end; ++j) tests += test(a_.prims[i], a_.prims[j]);
      count_tests(tests);
      return;
    }
    const int l = n + 1, r = nd.index;
    const std::size_t ml = m / 2, mr = m - m / 2;
    if (m > kParallelGrain)
      tbb::parallel_invoke([&] { self(l, ml); }, [&] { self(r, mr); }, [&] { cross(l, ml, r, mr); });
    else {
      self(l, ml);
      self(r, mr);
      cross(l, ml, r, mr);
    }
  }

  // All pairs with one triangle in subtree a of a_ (ma triangles) and the other in subtree b of b_ (mb).
  void cross(int a, std::size_t ma, int b, std::size_t mb) {
    if (stopped()) return;
    const Node<S>& na = a_.nodes[a];
    const Node<S>& nb = b_.nodes[b];
    if (!overlap(na.box, nb.box) || meet(a_.shared[a], b_.shared[b])) return;
    if (na.count > 0 && nb.count > 0) {
      std::size_t tests = 0;
      for (int i = na.index, ie = na.index + na.count; i < ie; ++i) {
        const Prim<S>& p = a_.prims[i];
        if (!overlap(p.box, nb.box)) continue;
        for (int j = nb.index, je = nb.index + nb.count; j < je; ++j) tests += test(p, b_.prims[j]);
      }
      count_tests(tests);
      return;
    }
    const bool parallel = ma + mb > kParallelGrain;
    // Descend into the bigger subtree, so both sides shrink at the same pace.
    if (nb.count > 0 || (na.count == 0 && ma >= mb)) {
      const std::size_t m1 = ma / 2, m2 = ma - ma / 2;
      fork(
          parallel, [&] { cross(a + 1, m1, b, mb); }, [&] { cross(na.index, m2, b, mb); });
    } else {
      const std::size_t m1 = mb / 2, m2 = mb - mb / 2;
      fork(
          parallel, [&] { cross(a, ma, b + 1, m1); }, [&] { cross(a, ma, nb.index, m2); });
    }
  }

  // Adds a leaf block's exact tests to this thread's count, and that to the shared count in
  // batches, so that the threads do not contend for it (most blocks make no test at all, and skip
  // even the thread-local lookup).
  void count_tests(std::size_t tests) {
    if (tests == 0) return;
    std::size_t& pending = pending_tests_.local();
    pending += tests;
    if (pending < kTestBatch) return;
    const std::size_t done = tests_.fetch_add(pending, std::memory_order_relaxed) + pending;
    pending = 0;
    if (max_tests_ > 0 && done > max_tests_) {
      out_of_tests_.store(true, std::memory_order_relaxed);
      truncated_.store(true, std::memory_order_relaxed);
    }
  }

  // Whether the exact test ran (the boxes overlap and no vertex is shared); a hit is reported.
  bool test(const Prim<S>& p, const Prim<S>& q) {
    if (!overlap(p.box, q.box) || share_vertex(p, q)) return false;
    const Vec3 &a0 = vertices_[p.v[0]], &a1 = vertices_[p.v[1]], &a2 = vertices_[p.v[2]];
    const Vec3 &b0 = vertices_[q.v[0]], &b1 = vertices_[q.v[1]], &b2 = vertices_[q.v[2]];
    if (separated(a0, a1, a2, b0, b1, b2)) return true;
    const Triangle t(to_point(a0), to_point(a1), to_point(a2));
    const Triangle u(to_point(b0), to_point(b1), to_point(b2));
    if (CGAL::do_intersect(t, u)) report(p.face, q.face);
    return true;
  }

  void report(int f, int g) {
    const std::size_t before = found_.fetch_add(1, std::memory_order_relaxed);
    // Finding pair max_pairs + 1 proves the mesh has more than the limit: stop everyone.
    if (max_pairs_ > 0 && before >= max_pairs_) {
      truncated_.store(true, std::memory_order_relaxed);
      return;
    }
    // One tree: unordered pairs, smaller face first. Two: the first tree's face first.
    if (collect_) pairs_.local().push_back(&a_ == &b_ ? Pair(std::min(f, g), std::max(f, g)) : Pair(f, g));
  }

  const std::vector<Vec3>& vertices_;
  const Tree<S>& a_;
  const Tree<S>& b_;
  static constexpr std::size_t kTestBatch = 4096;
  const bool collect_;
  const std::size_t max_pairs_;
  const std::size_t max_tests_;
  const std::atomic<bool>* cancel_;
  std::atomic<std::size_t> found_{0};
  std::atomic<bool> truncated_{false};
  std::atomic<bool> out_of_tests_{false};
  std::atomic<std::size_t> tests_{0};
  tbb::enumerable_thread_specific<std::size_t> pending_tests_{0};
  tbb::enumerable_thread_specific<std::vector<Pair>> pairs_;
};

void validate(const std::vector<Vec3>& vertices, const std::vector<Face>& faces, const char* caller) {
  if (faces.size() > static_cast<std::size_t>(INT_MAX))
    throw InvalidInput(std::string(caller) + ": more faces than fit in an int");
  const std::size_t nv = vertices.size();
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int v : faces[f]) {
      if (v < 0 || static_cast<std::size_t>(v) >= nv)
        throw InvalidInput(std::string(caller) + ": face " + std::to_string(f) + " has vertex index " +
                           std::to_string(v) + " out of range [0, " + std::to_string(nv) + ")");
      if (!is_finite(vertices[v]))
        throw InvalidInput(std::string(caller) + ": vertex " + std::to_string(v) + " (used by face " +
                           std::to_string(f) + ") has a non-finite coordinate");
    }
}

// Order-sensitive 64-bit hash of the face list; a multiply-xorshift step per index.
std::uint64_t fingerprint(const std::vector<Face>& faces) {
  std::uint64_t h = 0x9E3779B97F4A7C15ull ^ faces.size();
  for (const Face& f : faces)
    for (int v : f) {
      h = (h ^ static_cast<std::uint32_t>(v)) * 0xFF51AFD7ED558CCDull;
      h ^= h >> 32;
    }
  return h;
}

// Faces with at least this many loose float boxes (loose_in_float()) make the search take double
// boxes: a lone stray face is left to its loose box (the median keeps the others tight), a
// cluster of them is not, since its faces would all overlap one another.
constexpr std::size_t kLooseFacesForDouble = 16;

// Whether triangle (a, b, c)'s float box relative to \p origin is loose: its sides, rounded
// outward to floats at their distance from the origin (R), move by up to about 2 float steps,
// R 2^-22; loose where that exceeds a sixteenth of the triangle's extent (on a scan at the
// origin with a million faces it is about 1e-4 of it). Faces far from the median
// in a mesh of two clusters far apart (two scans in one georeferenced frame) are; their float
// boxes overlapped one another, up to every pair of the far cluster (two overlapping level-5
// icospheres 2e7 from two others along each axis: 23.9M exact tests and 1.57 s, one thread,
// against 13.5k and 0.07 s with double boxes).
bool loose_in_float(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& origin) {
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  const double reach = (lo - origin).cwiseAbs().cwiseMax((hi - origin).cwiseAbs()).maxCoeff();
  return std::ldexp(reach, -22) > 0.0625 * (hi - lo).maxCoeff();
}

// The non-degenerate faces, in face order; centroids relative to \p origin. \p loose, if given,
// counts the faces whose float boxes would be loose.
template <class S>
std::vector<Item<S>> make_items(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                const Vec3& origin, std::atomic<std::size_t>* loose) {
  std::vector<Item<S>> items(faces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces.size(), 1024), [&](const auto& range) {
    for (std::size_t f = range.begin(); f < range.end(); ++f) {
      const Vec3& a = vertices[faces[f][0]];
      const Vec3& b = vertices[faces[f][1]];
      const Vec3& c = vertices[faces[f][2]];
      Item<S>& item = items[f];
      // Exact: zero-area triangles have no plane, and CGAL's triangle test requires one.
      if (CGAL::collinear(to_point(a), to_point(b), to_point(c))) {
        item.face = -1;
        continue;
      }
      item.face = static_cast<int>(f);
      // Divide first so that huge coordinates cannot overflow (the difference with the origin may
      // be infinite, never NaN); the centroid only guides the split.
      const Vec3 centroid = a / 3.0 + b / 3.0 + c / 3.0 - origin;
      for (int k = 0; k < 3; ++k) item.c[k] = static_cast<S>(centroid[k]);
      if (loose && loose_in_float(a, b, c, origin)) loose->fetch_add(1, std::memory_order_relaxed);
    }
  });
  items.erase(std::remove_if(items.begin(), items.end(), [](const Item<S>& i) { return i.face < 0; }),
              items.end());
  return items;
}

// The per-axis median of the faces' first corners, over both lists (at most 65,536 faces, evenly
// spread, are read): most faces are near it, whatever a few far ones do.
Vec3 median_corner(const std::vector<Vec3>& vertices, const std::vector<Face>& faces_a,
                   const std::vector<Face>* faces_b) {
  const std::size_t na = faces_a.size(), n = na + (faces_b ? faces_b->size() : 0);
  constexpr std::size_t kSamples = 65536;
  const std::size_t step = std::max<std::size_t>(1, (n + kSamples - 1) / kSamples);
  std::vector<Vec3> corners;
  for (std::size_t f = 0; f < n; f += step)
    corners.push_back(vertices[f < na ? faces_a[f][0] : (*faces_b)[f - na][0]]);
  return coordinate_median(corners);
}

// x - origin (computed in double, so within half a unit in its last place) rounded outward to S,
// and one step of S more, which covers that rounding: the boxes still hold the triangles.
template <class S>
S lower_side(double x) {
  return std::nextafter(static_cast<S>(round_down(x)), -std::numeric_limits<S>::infinity());
}
template <>
double lower_side<double>(double x) {
  return std::nextafter(x, -std::numeric_limits<double>::infinity());
}
template <class S>
S upper_side(double x) {
  return std::nextafter(static_cast<S>(round_up(x)), std::numeric_limits<S>::infinity());
}
template <>
double upper_side<double>(double x) {
  return std::nextafter(x, std::numeric_limits<double>::infinity());
}

// The faces of `items` (in leaf order) with their outward-rounded boxes relative to \p origin.
template <class S>
std::vector<Prim<S>> make_prims(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                const std::vector<Item<S>>& items, const Vec3& origin) {
  std::vector<Prim<S>> prims(items.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, items.size(), 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      Prim<S>& p = prims[i];
      p.face = items[i].face;
      p.v = faces[p.face];
      const Vec3& a = vertices[p.v[0]];
      const Vec3& b = vertices[p.v[1]];
      const Vec3& c = vertices[p.v[2]];
      for (int k = 0; k < 3; ++k) {
        p.box.lo[k] = lower_side<S>(std::min({a[k], b[k], c[k]}) - origin[k]);
        p.box.hi[k] = upper_side<S>(std::max({a[k], b[k], c[k]}) - origin[k]);
      }
    }
  });
  return prims;
}

bool lists_all_pairs(const IntersectionResult& r) {
  return r.pairs.size() == r.num_pairs;
}

// The tree of \p items (make_items() of \p faces), its boxes relative to \p origin.
template <class S, class F>
Tree<S> build_tree(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                   std::vector<Item<S>> items, const Vec3& origin, const F& check_cancel) {
  Tree<S> tree;
  BvhBuilder<S>(items, tree.nodes).build();
  check_cancel();
  tree.prims = make_prims(vertices, faces, items, origin);
  std::vector<Item<S>>().swap(items);  // keep the peak memory down on big meshes
  fit_boxes(tree.nodes, tree.shared, tree.prims);
  return tree;
}

// The search over the trees of \p items_a and, if \p faces_b, \p items_b, into \p result.
template <class S, class F>
void search_trees(const std::vector<Vec3>& vertices, const std::vector<Face>& faces_a,
                  const std::vector<Face>* faces_b, std::vector<Item<S>> items_a,
                  std::vector<Item<S>> items_b, const Vec3& origin, const IntersectionOptions& options,
                  const F& check_cancel, IntersectionResult& result) {
  const Tree<S> a = build_tree(vertices, faces_a, std::move(items_a), origin, check_cancel);
  std::unique_ptr<Tree<S>> b;
  if (faces_b)
    b = std::make_unique<Tree<S>>(build_tree(vertices, *faces_b, std::move(items_b), origin, check_cancel));
  IntersectionSearch<S> search(vertices, a, b ? *b : a, options);
  search.run();
  check_cancel();  // the search stopped at a node, and its count is short
  const std::size_t found = search.found();
  result.num_tests = search.tests();
  // The batches let a search finish a little past max_tests: it counts as cut short all the
  // same, so that whether it is does not depend on the threads (a whole search makes the same
  // tests on any number of them).
  result.out_of_tests =
      search.out_of_tests() || (options.max_tests > 0 && result.num_tests > options.max_tests);
  result.truncated = search.truncated() || result.out_of_tests;
  result.num_pairs = options.max_pairs > 0 ? std::min(found, options.max_pairs) : found;
  if (options.collect_pairs) result.pairs = search.take_pairs();  // at most max_pairs: report()
}

// The search of find_self_intersections() (\p faces_b null) or find_intersections_between().
IntersectionResult search_pairs(const std::vector<Vec3>& vertices, const std::vector<Face>& faces_a,
                                const std::vector<Face>* faces_b, const IntersectionOptions& options) {
  IntersectionResult result;
  auto check_cancel = [&] {
    if (options.cancel && options.cancel->load(std::memory_order_relaxed))
      throw Cancelled("intersection search cancelled");
  };
  auto work = [&] {
    check_cancel();
    // Boxes and centroids are stored relative to the median of the faces: in absolute
    // coordinates, a scan 1e6 from the origin (a georeferenced one) got float boxes a float step
    // (0.06) wide at least and split on centroids that coincide (the camel 1e6 away took 20.7M
    // exact tests and 0.73 s where it takes 11k and 0.02 s at the origin). Relative to the box
    // centre, one stray face far from a scan did the same to all the others. In float (half the
    // memory traffic of the traversal) unless that leaves faces far from the median loose.
    const Vec3 origin = median_corner(vertices, faces_a, faces_b);
    std::atomic<std::size_t> loose{0};
    std::vector<Item<float>> items_a = make_items<float>(vertices, faces_a, origin, &loose);
    std::vector<Item<float>> items_b;
    if (faces_b) items_b = make_items<float>(vertices, *faces_b, origin, &loose);
    check_cancel();
    if (loose.load() < kLooseFacesForDouble) {
      search_trees(vertices, faces_a, faces_b, std::move(items_a), std::move(items_b), origin, options,
                   check_cancel, result);
      return;
    }
    std::vector<Item<float>>().swap(items_a);
    std::vector<Item<float>>().swap(items_b);
    std::vector<Item<double>> wide_a = make_items<double>(vertices, faces_a, origin, nullptr), wide_b;
    if (faces_b) wide_b = make_items<double>(vertices, *faces_b, origin, nullptr);
    check_cancel();
    search_trees(vertices, faces_a, faces_b, std::move(wide_a), std::move(wide_b), origin, options,
                 check_cancel, result);
  };
  if (options.parallel) {
    work();
  } else {
    tbb::task_arena single(1);
    single.execute(work);
  }
  return result;
}
}  // namespace

IntersectionResult find_self_intersections(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                                           const IntersectionOptions& options) {
  validate(vertices, faces, "find_self_intersections");
  IntersectionResult result = search_pairs(vertices, faces, nullptr, options);
  result.num_faces = faces.size();
  result.connectivity_hash = fingerprint(faces);
  if (options.collect_pairs) {
    result.faces.reserve(2 * result.pairs.size());
    for (const Pair& p : result.pairs) {
      result.faces.push_back(p.first);
      result.faces.push_back(p.second);
    }
    std::sort(result.faces.begin(), result.faces.end());
    result.faces.erase(std::unique(result.faces.begin(), result.faces.end()), result.faces.end());
  }
  return result;
}

IntersectionResult find_intersections_between(const std::vector<Vec3>& vertices,
                                              const std::vector<Face>& faces_a,
                                              const std::vector<Face>& faces_b,
                                              const IntersectionOptions& options) {
  validate(vertices, faces_a, "find_intersections_between (first face list)");
  validate(vertices, faces_b, "find_intersections_between (second face list)");
  IntersectionResult result = search_pairs(vertices, faces_a, &faces_b, options);
  result.num_faces = faces_a.size() + faces_b.size();
  // Not the fingerprint of either list alone, nor of their concatenation: a result between two
  // lists is never compared with one within a list.
  result.connectivity_hash =
      (fingerprint(faces_a) * 0x9E3779B97F4A7C15ull) ^ fingerprint(faces_b) ^ 0x5bd1e995ull;
  if (options.collect_pairs) {
    result.faces.reserve(result.pairs.size());
    for (const Pair& p : result.pairs) result.faces.push_back(p.first);
    std::sort(result.faces.begin(), result.faces.end());
    result.faces.erase(std::unique(result.faces.begin(), result.faces.end()), result.faces.end());
  }
  return result;
}

IntersectionOptions bounded_intersection_options(std::size_t num_faces) {
  IntersectionOptions o;
  o.max_pairs = 10'000'000;
  o.max_tests = 50'000'000 + 200 * num_faces;
  return o;
}

namespace {

// The pairs of \p after that \p before lacks; 0 if \p before was cut short. \p caller names the
// public function in the errors.
std::size_t count_new(const IntersectionResult& before, const IntersectionResult& after, const char* caller) {
  for (const IntersectionResult* r : {&before, &after})
    if (!lists_all_pairs(*r))
      throw InvalidInput(std::string(caller) + ": '" + (r == &before ? "before" : "after") +
                         "' does not list its pairs (compute it with collect_pairs)");
  if (before.num_faces != after.num_faces || before.connectivity_hash != after.connectivity_hash)
    throw InvalidInput(std::string(caller) + ": the two results come from different face lists");
  if (before.truncated) return 0;

  // Results from find_self_intersections() are sorted already; hand-made ones may not be.
  std::vector<Pair> b_storage, a_storage;
  auto sorted = [](const std::vector<Pair>& pairs, std::vector<Pair>& storage) -> const std::vector<Pair>& {
    if (std::is_sorted(pairs.begin(), pairs.end())) return pairs;
    storage = pairs;
    std::sort(storage.begin(), storage.end());
    return storage;
  };
  const std::vector<Pair>& b = sorted(before.pairs, b_storage);
  const std::vector<Pair>& a = sorted(after.pairs, a_storage);
  std::size_t fresh = 0;
  auto it = b.begin();
  for (const Pair& p : a) {
    it = std::lower_bound(it, b.end(), p);
    if (it == b.end() || *it != p) ++fresh;
  }
  return fresh;
}

}  // namespace

std::size_t count_new_intersections(const IntersectionResult& before, const IntersectionResult& after) {
  for (const IntersectionResult* r : {&before, &after})
    if (r->truncated)
      throw InvalidInput(std::string("count_new_intersections: '") + (r == &before ? "before" : "after") +
                         "' was cut short by a search limit, its pair list is incomplete");
  return count_new(before, after, "count_new_intersections");
}

std::size_t count_new_intersections_at_least(const IntersectionResult& before,
                                             const IntersectionResult& after) {
  return count_new(before, after, "count_new_intersections_at_least");
}

bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  for (const auto* t : {&a, &b})
    for (const Vec3& p : *t)
      if (!is_finite(p)) throw InvalidInput("triangles_intersect: non-finite coordinate");
  const Triangle t(to_point(a[0]), to_point(a[1]), to_point(a[2]));
  const Triangle u(to_point(b[0]), to_point(b[1]), to_point(b[2]));
  if (t.is_degenerate() || u.is_degenerate()) return false;
  return CGAL::do_intersect(t, u);
}

namespace internal {
namespace {

// A face's box in double, exactly its corners' extremes.
Eigen::AlignedBox3d face_box(const std::vector<Vec3>& vertices, const Face& f) {
  Eigen::AlignedBox3d b(vertices[f[0]]);
  b.extend(vertices[f[1]]);
  b.extend(vertices[f[2]]);
  return b;
}

// The cells of a uniform grid that boxes cover (internal::CellGrid): a conservative test, never
// a missed pair.
class CellSet {
 public:
  explicit CellSet(double cell) { grid_.cell = cell; }
  // Calls f(key) for each cell of \p b; false (without calls) if they are more than \p limit.
  template <class F>
  bool for_cells(const Eigen::AlignedBox3d& b, double limit, const F& f) const {
    if (grid_.span(b) > limit) return false;
    grid_.for_each_cell(b, f);
    return true;
  }
  void insert(std::uint64_t k) { cells_.insert(k); }
  bool contains(std::uint64_t k) const { return cells_.count(k) > 0; }

 private:
  CellGrid grid_;
  std::unordered_set<std::uint64_t> cells_;
};

}  // namespace

IntersectionResult update_self_intersections(const std::vector<Vec3>& vertices,
                                             const std::vector<Face>& faces, const IntersectionResult& before,
                                             const std::vector<int>& changed,
                                             const IntersectionOptions& options) {
  assert(options.collect_pairs);
  validate(vertices, faces, "update_self_intersections");
  const std::size_t n = faces.size();
  const auto whole = [&] { return find_self_intersections(vertices, faces, options); };
  if (before.truncated || !lists_all_pairs(before) || before.num_faces != n ||
      before.connectivity_hash != fingerprint(faces))
    return whole();
  std::vector<char> moved(n, 0);
  std::vector<int> list;  // the changed faces, each once
  for (int f : changed) {
    if (f < 0 || static_cast<std::size_t>(f) >= n)
      throw InvalidInput("update_self_intersections: changed face " + std::to_string(f) +
                         " out of range [0, " + std::to_string(n) + ")");
    if (!moved[f]) moved[f] = 1, list.push_back(f);
  }
  if (4 * list.size() > n) return whole();
  IntersectionResult result;
  result.num_faces = n;
  result.connectivity_hash = before.connectivity_hash;
  if (!list.empty()) {
    // Cells as large as the largest changed box, so that each of those covers at most 8.
    Eigen::AlignedBox3d all;
    double cell = 0.0;
    for (int f : list) {
      const Eigen::AlignedBox3d b = face_box(vertices, faces[f]);
      all.extend(b);
      cell = std::max(cell, b.sizes().maxCoeff());
    }
    if (!(cell > 0) || !std::isfinite(cell)) cell = std::max(all.sizes().maxCoeff(), 1.0);
    // A box as wide as a cell covers 2 a side, 3 where the division rounds up at its far side.
    CellSet cells(cell);
    for (int f : list)
      if (!cells.for_cells(face_box(vertices, faces[f]), 27.0, [&](std::uint64_t k) { cells.insert(k); }))
        return whole();
    // The faces near a changed one: theirs included, as the search must see pairs among them.
    std::vector<Face> near;
    std::vector<int> global;
    for (std::size_t f = 0; f < n; ++f) {
      const Eigen::AlignedBox3d b = face_box(vertices, faces[f]);
      bool in = moved[f] != 0;
      if (!in && all.intersects(b)) {
        bool hit = false;
        const bool few = cells.for_cells(b, 64.0, [&](std::uint64_t k) { hit = hit || cells.contains(k); });
        in = hit || !few;  // a box over many cells (a long face) is taken without looking
      }
      if (in) near.push_back(faces[f]), global.push_back(static_cast<int>(f));
    }
    if (2 * near.size() > n) return whole();
    const IntersectionResult local = search_pairs(vertices, near, nullptr, options);
    if (local.truncated) return whole();
    result.num_tests = local.num_tests;
    for (const Pair& p : local.pairs) {
      const int a = global[p.first], b = global[p.second];
      if (moved[a] || moved[b]) result.pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  for (const Pair& p : before.pairs)
    if (!moved[p.first] && !moved[p.second]) result.pairs.push_back(p);
  std::sort(result.pairs.begin(), result.pairs.end());
  if (options.max_pairs > 0 && result.pairs.size() > options.max_pairs) return whole();
  result.num_pairs = result.pairs.size();
  for (const Pair& p : result.pairs) result.faces.insert(result.faces.end(), {p.first, p.second});
  std::sort(result.faces.begin(), result.faces.end());
  result.faces.erase(std::unique(result.faces.begin(), result.faces.end()), result.faces.end());
  return result;
}

}  // namespace internal

}  // namespace strata
