#include "internal/hierarchy.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "strata/exceptions.h"

namespace strata::internal {
namespace {

// A bijection of the edge ids that orders equally long edges pseudo-randomly. In id order a
// regular grid's equally long edges collapsed row by row, and its coarse levels served the solver
// worse: the tests' regular cuboid came back from the round trip (unedited base) 0.60% of the
// diagonal off with the default options and 3.1% with the multigrid preset (the acceptance: 0.5%).
inline std::uint32_t scramble(int edge) {
  std::uint32_t x = static_cast<std::uint32_t>(edge) * 0x9E3779B1u;
  x ^= x >> 16;
  return x * 0x85EBCA6Bu;
}

// A collapse candidate: an edge and its squared length when queued. Packed to 12 bytes (from 16):
// the queue holds millions of entries at 1M prisms. Ties go by scramble(), so the order is total.
struct __attribute__((packed)) Entry {
  double length2;
  int edge;
};
static_assert(sizeof(Entry) == 12, "Entry is packed");

// The collapse queue: a min-queue of entries in first() order, as buckets of squared lengths
// (16 per octave), each a 4-ary heap. The pops come in the same order as from one heap of all
// the entries, since first() is a total order and the buckets split it into ranges; but the
// bucket being popped is small enough for the caches, where the sifts of one heap of the 3M edges
// of a 1M-prism mesh (36 MB) missed them.
class EdgeQueue {
 public:
  EdgeQueue() : buckets_(kBuckets) {}

  bool empty() const { return size_ == 0; }

  //! The edges' ids as the input numbered them, by current id (Decimator::compact() renumbers
  //! the edges; ties go by the input's ids so that the order is the same). Empty: the same ids.
  void set_input_ids(std::vector<int> ids) { input_id_ = std::move(ids); }
  const std::vector<int>& input_ids() const { return input_id_; }

  // a pops before b: shorter first, equally long edges in scramble() order of their input ids.
  bool first(const Entry& a, const Entry& b) const {
    if (a.length2 != b.length2) return a.length2 < b.length2;
    return input_id_.empty() ? scramble(a.edge) < scramble(b.edge)
                             : scramble(input_id_[a.edge]) < scramble(input_id_[b.edge]);
  }
  std::size_t size() const { return size_; }

  // Adds the entries at once, each bucket made a heap after.
  void assign(const std::vector<Entry>& entries) {
    for (const Entry& e : entries) buckets_[bucket(e.length2)].push_back(e);
    size_ += entries.size();
    for (std::size_t b = 0; b < kBuckets; ++b) heap_make(buckets_[b]);
    low_ = 0;
  }

  void push(const Entry& e) {
    const std::size_t b = bucket(e.length2);
    std::vector<Entry>& h = buckets_[b];
    h.push_back(e);
    sift_up(h, h.size() - 1);
    ++size_;
    low_ = std::min(low_, b);
  }

  //! \pre !empty()
  Entry pop() {
    while (buckets_[low_].empty()) ++low_;
    std::vector<Entry>& h = buckets_[low_];
    const Entry e = h.front();
    h.front() = h.back();
    h.pop_back();
    if (!h.empty()) sift_down(h, 0);
    --size_;
    return e;
  }

  //! The entries pop() likely returns next (fewer at the end of a bucket): the front, then its
  //! children in the heap. \pre !empty()
  std::pair<const Entry*, std::size_t> upcoming() const {
    std::size_t b = low_;
    while (buckets_[b].empty()) ++b;
    const std::vector<Entry>& h = buckets_[b];
    return {h.data(), std::min<std::size_t>(h.size(), 5)};
  }

  // Drops the entries for which stale(entry) holds and renames the others' edges by rename(edge).
  template <class F, class R>
  void prune(F&& stale, R&& rename) {
    size_ = 0;
    for (std::vector<Entry>& h : buckets_) {
      if (h.empty()) continue;
      h.erase(std::remove_if(h.begin(), h.end(), stale), h.end());
      for (Entry& e : h) e.edge = rename(e.edge);
      heap_make(h);
      size_ += h.size();
    }
    low_ = 0;
  }
  template <class F>
  void prune(F&& stale) {
    prune(stale, [](int e) { return e; });
  }

 private:
  // The top bits of a non-negative double (exponent and 4 mantissa bits) order it as its value.
  static constexpr int kShift = 48;
  static constexpr std::size_t kBuckets = std::size_t{1} << (63 - kShift);
  static std::size_t bucket(double length2) {
    std::uint64_t bits;
    std::memcpy(&bits, &length2, sizeof bits);
    // length2 >= 0 has the sign bit 0; a NaN with it set (inf - inf) goes last, in range.
    return std::min(static_cast<std::size_t>(bits >> kShift), kBuckets - 1);
  }

  // A 4-ary heap: half the depth of a binary one, and a node's children are adjacent, so a sift
  // takes about half the cache misses.
  void sift_up(std::vector<Entry>& h, std::size_t i) const {
    const Entry e = h[i];
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!first(e, h[parent])) break;
      h[i] = h[parent];
      i = parent;
    }
    h[i] = e;
  }
  void sift_down(std::vector<Entry>& h, std::size_t i) const {
    const std::size_t n = h.size();
    const Entry e = h[i];
    for (;;) {
      const std::size_t c = 4 * i + 1;
      if (c >= n) break;
      std::size_t best = c;
      for (std::size_t k = c + 1; k < std::min(c + 4, n); ++k)
        if (first(h[k], h[best])) best = k;
      if (!first(h[best], e)) break;
      h[i] = h[best];
      i = best;
    }
    h[i] = e;
  }
  void heap_make(std::vector<Entry>& h) const {
    for (std::size_t i = h.size() / 4 + 1; i-- > 0;)
      if (i < h.size()) sift_down(h, i);
  }

  std::vector<std::vector<Entry>> buckets_;
  std::size_t size_ = 0;
  std::size_t low_ = 0;  // no entry lies in a bucket below this one
  std::vector<int> input_id_;
};

// Working state of build_hierarchy(): a half-edge mesh on flat arrays and the collapse queue.
//
// Half-edges 2e and 2e + 1 are the two sides of edge e. Edges are numbered in order of first use
// (faces in order, corners 0-1, 1-2, 2-0), side 2e in the direction of that use, and a collapse
// keeps the edges of the vertex it keeps: the numbering, the collapse rules and the order of every
// circulation are OpenMesh's (TriConnectivity), which this replaced for speed (the 1M-prism setup
// spent about 4 s in OpenMesh's handle checks and property arrays); the tests check that both give
// the same hierarchy. After each level, compact() renumbers what is left densely, in the same
// order (ties in the queue still go by the input's edge ids), which changes no collapse.
//
// Input that a half-edge mesh cannot hold is handled here rather than rejected: a face with a
// repeated corner, or one that uses a directed edge an earlier face uses (a non-manifold edge or
// inconsistent orientation), is left out of the coarse levels, as OpenMesh's add_face leaves it
// out. A vertex where several fans of faces meet (a non-manifold vertex) is split into one copy
// per fan; the copies are never collapsed, and the link condition compares input vertices, so no
// coarse level joins two fans.
class Decimator {
 public:
  Decimator(const std::vector<Vec3>& x, const std::vector<Face>& faces) {
    const int n = n_ = inputs_ = static_cast<int>(x.size());
    live_ = n;
    build(faces, n);
    const int nv = static_cast<int>(out_.size());
    ident_ = copy_of_;
    pos_.resize(nv);
    for (int v = 0; v < nv; ++v) pos_[v] = x[input(v)];
    tag_.assign(nv, 0);
    // One entry per edge, both directions tried when it comes up (they have one length), and the
    // heaps made at once: pushing the 3M halfedges of a 1M-prism mesh one by one took much of the setup.
    const int ne = static_cast<int>(to_.size() / 2);
    queued_.resize(ne);
    std::vector<Entry> entries(ne);
    for (int e = 0; e < ne; ++e) entries[e] = Entry{queued_[e] = length2(2 * e), e};
    queue_.assign(entries);
  }

  int live_vertices() const { return live_; }

  // Collapses until at most `target` vertices are live or nothing more can collapse. Appends the
  // removed vertices and their rings.
  void decimate_to(int target, std::vector<int>& removed, std::vector<int>& ring_offsets,
                   std::vector<int>& rings, const HierarchyOptions& o) {
    for (unsigned pops = 1; live_ > target && !queue_.empty(); ++pops) {
      if ((pops & 1023u) == 0 && o.cancel && o.cancel->load(std::memory_order_relaxed))
        throw Cancelled("reconstruction setup cancelled (ReconstructOptions::cancel)");
      if ((pops & 65535u) == 0 && o.progress) o.progress(1.0 - static_cast<double>(live_) / n_);
      // A live edge has one current entry (rarely a duplicate): about 3 per live vertex. The rest
      // are deleted edges' and stale lengths' entries, which are dropped once they would double the queue:
      // popping them one by one from millions took longer than the collapses.
      // Once more only after the queue has doubled since: where most edges cannot collapse (their
      // vertices split and locked, as in a soup of triangles sharing only vertices) the queue stays
      // above that size after pruning, and a prune at every pop would be quadratic.
      if (queue_.size() > 6 * static_cast<std::size_t>(live_) && queue_.size() > 2 * pruned_size_) {
        queue_.prune([&](const Entry& e) { return queued_[e.edge] != e.length2; });
        pruned_size_ = queue_.size();
        if (queue_.empty()) break;
      }
      const Entry e = queue_.pop();
      prefetch_upcoming();
      // Deleted, stale (a fresh entry exists) or already tried at this length: every change of an
      // edge's length queues it again, so its current entry is the one queued_ records.
      if (queued_[e.edge] != e.length2) continue;
      queued_[e.edge] = -1.0;
      const int h0 = 2 * e.edge;
      int h = h0;
      if (!collapse_ok(h)) {
        h = h0 ^ 1;
        if (!collapse_ok(h)) continue;
      }
      const int v0 = to_[h ^ 1], v1 = to_[h];
      removed.push_back(input(v0));
      for_ring(v0, [&](int w) { rings.push_back(input(w)); });
      ring_offsets.push_back(static_cast<int>(rings.size()));
      collapse(h);
      --live_;
      // v1's edges: v0's former ones changed length; the others may pass the checks now.
      for_outgoing(v1, [&](int g) { push(g >> 1); });
    }
  }

  std::vector<Face> faces() const {
    std::vector<Face> out;
    for (std::size_t f = 0; f < face_halfedge_.size(); ++f) {
      const int h = face_halfedge_[f];
      if (h < 0) continue;  // deleted
      out.push_back(Face{input(to_[h]), input(to_[next_[h]]), input(to_[next_[next_[h]]])});
    }
    return out;
  }

  // Input vertices not collapsed (a split vertex's copies are never collapsed; its first copy
  // keeps its id), ascending.
  std::vector<int> vertices() const {
    std::vector<int> out;
    for (int v = 0; v < inputs_; ++v)
      if (!vertex_deleted_[v]) out.push_back(input(v));
    return out;
  }

  // Renumbers the live vertices, edges and faces densely, each in its order, and drops the
  // deleted ones and the queue's stale entries. The collapses that follow are the same (the
  // queue's order and every circulation are kept), but the coarse levels' decimation no longer
  // reads state spread over the input's arrays: at 1M prisms the collapses of the second level
  // on took twice as long each as the first level's, for a quarter of the vertices.
  void compact() {
    const int nv = static_cast<int>(out_.size()), ne = static_cast<int>(to_.size() / 2),
              nf = static_cast<int>(face_halfedge_.size());
    std::vector<int> vnew(nv, -1), enew(ne, -1), fnew(nf, -1);
    int kv = 0, kin = 0;
    for (int v = 0; v < nv; ++v)
      if (!vertex_deleted_[v]) {
        vnew[v] = kv++;
        kin += v < inputs_;
        for_outgoing(v, [&](int g) { enew[g >> 1] = 0; });
      }
    int ke = 0, kf = 0;
    for (int e = 0; e < ne; ++e)
      if (enew[e] == 0) enew[e] = ke++;
    for (int f = 0; f < nf; ++f)
      if (face_halfedge_[f] >= 0) fnew[f] = kf++;
    auto he = [&](int h) { return 2 * enew[h >> 1] + (h & 1); };
    std::vector<int> to(2 * static_cast<std::size_t>(ke)), next(to.size()), prev(to.size()), face(to.size());
    std::vector<double> queued(ke);
    std::vector<int> input_id(ke);
    const std::vector<int>& old_input_id = queue_.input_ids();  // replaced only after the loop
    for (int e = 0; e < ne; ++e) {
      if (enew[e] < 0) continue;
      for (int h = 2 * e; h <= 2 * e + 1; ++h) {
        const int g = he(h);
        to[g] = vnew[to_[h]];
        next[g] = he(next_[h]);
        prev[g] = he(prev_[h]);
        face[g] = face_[h] < 0 ? -1 : fnew[face_[h]];
      }
      queued[enew[e]] = queued_[e];
      input_id[enew[e]] = old_input_id.empty() ? e : old_input_id[e];
    }
    std::vector<int> face_halfedge(kf);
    for (int f = 0; f < nf; ++f)
      if (fnew[f] >= 0) face_halfedge[fnew[f]] = he(face_halfedge_[f]);
    std::vector<int> out(kv), vin(kv), copy_ident(kv - kin);
    std::vector<char> locked(kv);
    std::vector<Vec3> pos(kv);
    for (int v = 0; v < nv; ++v) {
      const int w = vnew[v];
      if (w < 0) continue;
      out[w] = out_[v] < 0 ? -1 : he(out_[v]);
      vin[w] = input(v);
      if (w >= kin) copy_ident[w - kin] = vnew[ident(v)];  // a split vertex's first copy is never collapsed
      locked[w] = locked_[v];
      pos[w] = pos_[v];
    }
    queue_.set_input_ids(std::move(input_id));  // before the heaps are remade by the new ids
    queue_.prune([&](const Entry& e) { return queued_[e.edge] != e.length2; },
                 [&](int e) { return enew[e]; });
    pruned_size_ = queue_.size();
    to_ = std::move(to), next_ = std::move(next), prev_ = std::move(prev), face_ = std::move(face);
    queued_ = std::move(queued);
    face_halfedge_ = std::move(face_halfedge);
    out_ = std::move(out), vin_ = std::move(vin), ident_ = std::move(copy_ident);
    locked_ = std::move(locked), pos_ = std::move(pos);
    vertex_deleted_.assign(kv, 0);
    tag_.assign(kv, 0);
    stamp_ = 0;
    inputs_ = kin;
  }

 private:
  // The queue goes by length, so the edges of consecutive pops lie anywhere in the mesh, and at
  // 1M prisms each pop stalled on its edge's state (queued_, then the half-edges and vertices
  // collapse_ok() reads). The next pops' state is fetched while this one is tried and collapsed:
  // the half-edges of the next few edges, and the vertices of the next one. (The 1M bumps'
  // decimation: 1.4-1.9 s before, 0.95-1.4 s with the bucketed queue and this, the machine busy.)
  void prefetch_upcoming() const {
    if (queue_.empty()) return;
    const auto [up, k] = queue_.upcoming();
    for (std::size_t i = 0; i < k; ++i) {
      const int e = up[i].edge;
      __builtin_prefetch(&queued_[e]);
      for (const int* a : {to_.data(), next_.data(), prev_.data(), face_.data()})
        __builtin_prefetch(a + 2 * e);
    }
    for (int h = 2 * up[0].edge; h <= 2 * up[0].edge + 1; ++h) {
      __builtin_prefetch(&out_[to_[h]]);
      __builtin_prefetch(&pos_[to_[h]]);
    }
  }

  // The half-edge mesh of the faces that fit one (see the class comment).
  void build(const std::vector<Face>& faces, int n) {
    const int nf = static_cast<int>(faces.size());
    auto degenerate = [&](const Face& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; };
    // Directed corners (corner k = 3 f + c runs from faces[f][c] to faces[f][c + 1]) bucketed by
    // their start vertex, sorted by (end vertex, corner): a counting sort, no hashing.
    std::vector<int> start(static_cast<std::size_t>(n) + 1, 0);
    for (const Face& t : faces)
      if (!degenerate(t))
        for (int c = 0; c < 3; ++c) ++start[t[c] + 1];
    for (int v = 0; v < n; ++v) start[v + 1] += start[v];
    std::vector<std::pair<int, int>> out_corners(start[n]);  // (end vertex, corner)
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (int f = 0; f < nf; ++f)
        if (!degenerate(faces[f]))
          for (int c = 0; c < 3; ++c) out_corners[fill[faces[f][c]]++] = {faces[f][(c + 1) % 3], 3 * f + c};
    }
    for (int v = 0; v < n; ++v) std::sort(out_corners.begin() + start[v], out_corners.begin() + start[v + 1]);
    // The first entry of the run of (a -> b) in a's bucket, or -1.
    auto find = [&](int a, int b) {
      const auto first = out_corners.begin() + start[a], last = out_corners.begin() + start[a + 1];
      const auto it = std::lower_bound(first, last, std::make_pair(b, -1));
      return it != last && it->first == b ? static_cast<int>(it - out_corners.begin()) : -1;
    };
    // Faces in order; one is kept if no kept face uses one of its directed edges.
    std::vector<int> kept_corner(out_corners.size(), -1);  // per run head: the kept face's corner
    std::vector<int> kept_faces;
    for (int f = 0; f < nf; ++f) {
      const Face& t = faces[f];
      if (degenerate(t)) continue;
      int heads[3];
      bool ok = true;
      for (int c = 0; c < 3 && ok; ++c) ok = kept_corner[heads[c] = find(t[c], t[(c + 1) % 3])] < 0;
      if (!ok) continue;
      for (int c = 0; c < 3; ++c) kept_corner[heads[c]] = 3 * f + c;
      kept_faces.push_back(f);
    }
    // Edges in order of first use; the half-edge of each kept corner.
    std::vector<int> corner_he(3 * static_cast<std::size_t>(nf), -1);
    for (int f : kept_faces)
      for (int c = 0; c < 3; ++c) {
        const int k = 3 * f + c;
        if (corner_he[k] >= 0) continue;
        const int e = static_cast<int>(to_.size() / 2);
        const int a = faces[f][c], b = faces[f][(c + 1) % 3];
        to_.push_back(b);
        to_.push_back(a);
        corner_he[k] = 2 * e;
        const int twin = find(b, a);
        if (twin >= 0 && kept_corner[twin] >= 0) corner_he[kept_corner[twin]] = 2 * e + 1;
      }
    const std::size_t nh = to_.size();
    next_.assign(nh, -1);
    prev_.assign(nh, -1);
    face_.assign(nh, -1);
    face_halfedge_.resize(kept_faces.size());
    for (std::size_t i = 0; i < kept_faces.size(); ++i) {
      const int* he = &corner_he[3 * static_cast<std::size_t>(kept_faces[i])];
      for (int c = 0; c < 3; ++c) {
        face_[he[c]] = static_cast<int>(i);
        link(he[c], he[(c + 1) % 3]);
      }
      face_halfedge_[i] = he[2];  // OpenMesh's add_face: the face's last half-edge
    }
    locked_.assign(n, 0);
    split_fans(out_corners, start, corner_he, n);
    // Boundary half-edges: each runs into the boundary half-edge leaving its end (one per vertex,
    // the fans being split).
    std::vector<int> boundary_out(locked_.size(), -1);
    for (std::size_t h = 0; h < nh; ++h)
      if (face_[h] < 0) boundary_out[to_[h ^ 1]] = static_cast<int>(h);
    for (std::size_t h = 0; h < nh; ++h)
      if (face_[h] < 0) link(static_cast<int>(h), boundary_out[to_[h]]);
    // Each vertex's outgoing half-edge: a boundary one if it has one (OpenMesh's invariant, which
    // is_boundary(v) and the ring's first vertex rely on).
    out_.assign(locked_.size(), -1);
    for (std::size_t h = 0; h < nh; ++h) {
      const int v = to_[h ^ 1];
      if (out_[v] < 0 || face_[h] < 0) out_[v] = static_cast<int>(h);
    }
    vertex_deleted_.assign(locked_.size(), 0);
  }

  // Gives each fan of faces around a vertex after its first a vertex copy of its own (see the
  // class comment). A fan: the kept faces around the vertex reached from one another across edges
  // with a face on both sides.
  void split_fans(const std::vector<std::pair<int, int>>& out_corners, const std::vector<int>& start,
                  const std::vector<int>& corner_he, int n) {
    std::vector<int> fan;
    std::vector<char> seen(to_.size(), 0);
    for (int v = 0; v < n; ++v) {
      int fans = 0;
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const int h0 = corner_he[out_corners[i].second];
        if (h0 < 0 || seen[h0]) continue;  // a face left out, or a fan already walked
        // The fan's outgoing half-edges, both ways round from h0 until the boundary or back.
        fan.clear();
        for (int h = h0; h >= 0 && !seen[h]; h = face_[h ^ 1] >= 0 ? next_[h ^ 1] : -1)
          seen[h] = 1, fan.push_back(h);
        for (int h = h0; face_[prev_[h] ^ 1] >= 0;) {
          h = prev_[h] ^ 1;
          if (seen[h]) break;
          seen[h] = 1, fan.push_back(h);
        }
        if (fans++ == 0) continue;
        const int copy = static_cast<int>(locked_.size());
        copy_of_.push_back(v);
        locked_.push_back(1);
        locked_[v] = 1;
        for (int h : fan) to_[prev_[h]] = copy, to_[h ^ 1] = copy;
      }
    }
  }

  void link(int h, int next) {
    next_[h] = next;
    prev_[next] = h;
  }

  // f(h) for each half-edge h leaving v, from out_[v], turning as OpenMesh's circulators do.
  template <class F>
  void for_outgoing(int v, F&& f) const {
    const int first = out_[v];
    if (first < 0) return;
    int h = first;
    do {
      f(h);
      h = next_[h ^ 1];
    } while (h != first);
  }
  template <class F>
  void for_ring(int v, F&& f) const {
    for_outgoing(v, [&](int h) { f(to_[h]); });
  }

  bool boundary_vertex(int v) const { return face_[out_[v]] < 0; }

  // A vertex's input vertex: itself before compact(), or a fan's copy's original.
  int input(int v) const { return !vin_.empty() ? vin_[v] : v < n_ ? v : copy_of_[v - n_]; }
  // The vertex that stands for v's input vertex in the link condition: v, or a copy's original.
  int ident(int v) const { return v < inputs_ ? v : ident_[v - inputs_]; }

  double length2(int h) const { return (pos_[to_[h ^ 1]] - pos_[to_[h]]).squaredNorm(); }

  // An edge is queued again unless its entry in the heap is still current (the same length):
  // a duplicate would only be popped and checked twice.
  void push(int e) {
    const double l = length2(2 * e);
    if (queued_[e] == l) return;
    queued_[e] = l;
    queue_.push(Entry{l, e});
  }

  // Whether the collapse of h (its start onto its end) keeps the mesh a manifold of the same
  // topology (OpenMesh's is_collapse_ok, over input vertices), keeps the boundary's shape and
  // flips no face.
  bool collapse_ok(int h) {
    const int o = h ^ 1, v0 = to_[o], v1 = to_[h];
    if (locked_[v0] || locked_[v1]) return false;
    int vl = -1, vr = -1;
    // Neither side's triangle may have its other two edges on the boundary.
    if (face_[h] >= 0) {
      const int h1 = next_[h], h2 = next_[h1];
      vl = ident(to_[h1]);
      if (face_[h1 ^ 1] < 0 && face_[h2 ^ 1] < 0) return false;
    }
    if (face_[o] >= 0) {
      const int h1 = next_[o], h2 = next_[h1];
      vr = ident(to_[h1]);
      if (face_[h1 ^ 1] < 0 && face_[h2 ^ 1] < 0) return false;
    }
    if (vl == vr) return false;
    // The link condition: the rings of v0 and v1 share vl and vr only.
    ++stamp_;
    for_ring(v1, [&](int w) { tag_[ident(w)] = stamp_; });
    bool shared = false;
    for_ring(v0, [&](int w) {
      const int u = ident(w);
      shared = shared || (tag_[u] == stamp_ && u != vl && u != vr);
    });
    if (shared) return false;
    // Keep the boundary's shape: a boundary vertex may only slide along its boundary edge. (This
    // covers OpenMesh's test against an interior edge between two boundary vertices, which would
    // pinch the surface.)
    if (boundary_vertex(v0) && face_[h] >= 0 && face_[o] >= 0) return false;
    // Faces that survive around v0 must not flip or degenerate when v0 moves onto v1.
    const Vec3& target = pos_[v1];
    const Vec3& origin = pos_[v0];
    bool flips = false;
    // Each face around v0 is (v0, a, b) for an outgoing halfedge v0 -> a and its next a -> b.
    for_outgoing(v0, [&](int g) {
      if (flips || face_[g] < 0) return;  // no face on this side
      const int a = to_[g], b = to_[next_[g]];
      if (a == v1 || b == v1) return;  // one of the two faces the collapse removes
      const Vec3& pa = pos_[a];
      const Vec3& pb = pos_[b];
      const Vec3 n0 = triangle_area_normal(origin, pa, pb), n1 = triangle_area_normal(target, pa, pb);
      const double l0 = n0.norm(), l1 = n1.norm();
      flips = !(l1 > 1e-3 * l0) || n0.dot(n1) < 0.5 * l0 * l1;
    });
    return !flips;
  }

  // OpenMesh's collapse of h: the edge, then the two triangles that became loops of two edges,
  // each dropping the edge at the removed vertex and keeping the one at the kept vertex.
  void collapse(int h0) {
    const int h1 = next_[h0], o1 = next_[h0 ^ 1];
    collapse_edge(h0);
    if (next_[next_[h1]] == h1) collapse_loop(next_[h1]);
    if (next_[next_[o1]] == o1) collapse_loop(o1);
  }

  void collapse_edge(int h) {
    const int hn = next_[h], hp = prev_[h], o = h ^ 1, on = next_[o], op = prev_[o];
    const int fh = face_[h], fo = face_[o], vh = to_[h], vo = to_[o];
    for_outgoing(vo, [&](int g) { to_[g ^ 1] = vh; });
    link(hp, hn);
    link(op, on);
    if (fh >= 0) face_halfedge_[fh] = hn;
    if (fo >= 0) face_halfedge_[fo] = on;
    if (out_[vh] == o) out_[vh] = hn;
    adjust_outgoing(vh);
    out_[vo] = -1;
    vertex_deleted_[vo] = 1;
    queued_[h >> 1] = -1.0;
  }

  void collapse_loop(int h0) {
    const int h1 = next_[h0], o0 = h0 ^ 1, o1 = h1 ^ 1, v0 = to_[h0], v1 = to_[h1];
    const int fh = face_[h0], fo = face_[o0];
    const int after = next_[o0], before = prev_[o0];
    link(h1, after);
    link(before, h1);
    face_[h1] = fo;
    out_[v0] = h1;
    adjust_outgoing(v0);
    out_[v1] = o1;
    adjust_outgoing(v1);
    if (fo >= 0 && face_halfedge_[fo] == o0) face_halfedge_[fo] = h1;
    if (fh >= 0) face_halfedge_[fh] = -1;
    queued_[h0 >> 1] = -1.0;
  }

  // A boundary vertex's outgoing half-edge is a boundary one.
  void adjust_outgoing(int v) {
    for_outgoing(v, [&](int g) {
      if (face_[g] < 0) out_[v] = g;
    });
  }

  // Per half-edge: its end vertex, the next and previous half-edges of its face or boundary
  // loop, its face (-1 on the boundary).
  std::vector<int> to_, next_, prev_, face_;
  std::vector<int> face_halfedge_;  // per kept face: a half-edge (-1: deleted); its corners start at its end
  std::vector<int> out_;            // per vertex: an outgoing half-edge (-1: isolated or deleted)
  int n_ = 0;                       // input vertices
  int inputs_ = 0;                  // vertices 0..inputs_ - 1 are input vertices, the others fans' copies
  std::vector<int> copy_of_;        // built: per copy (vertex n_ + k), the input vertex it was split from
  std::vector<int> vin_;            // after compact(), per vertex: its input vertex (see input())
  std::vector<int> ident_;          // per copy (vertex inputs_ + k): the vertex it was split from
  std::vector<Vec3> pos_;           // per vertex: its input vertex's position
  std::vector<char> locked_;        // per vertex: split (never collapsed)
  std::vector<char> vertex_deleted_;
  std::vector<int> tag_;  // per vertex: the link condition's stamp (on ident_ vertices)
  int stamp_ = 0;
  EdgeQueue queue_;
  std::vector<double> queued_;   // per edge: the length2 of its current entry, -1 if none (or deleted)
  std::size_t pruned_size_ = 0;  // the queue's size after the last prune
  int live_ = 0;
};

}  // namespace

Hierarchy build_hierarchy(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                          const HierarchyOptions& o) {
  Hierarchy h;
  // Fine to coarse; reversed at the end.
  std::vector<Hierarchy::Level> fine_to_coarse;
  Hierarchy::Level finest;
  finest.vertices.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) finest.vertices[i] = static_cast<int>(i);
  finest.faces = faces;
  fine_to_coarse.push_back(std::move(finest));
  if (o.max_levels > 1 && static_cast<int>(x.size()) > o.coarsest_vertices) {
    Decimator dec(x, faces);
    while (static_cast<int>(fine_to_coarse.size()) < o.max_levels) {
      const int target = static_cast<int>(std::ceil(dec.live_vertices() * o.ratio));
      if (target < o.coarsest_vertices) break;
      std::vector<int> removed, offsets{0}, rings;
      dec.decimate_to(target, removed, offsets, rings, o);
      if (o.progress)
        o.progress(1.0 - static_cast<double>(dec.live_vertices()) / static_cast<double>(x.size()));
      // Not enough progress (e.g. everything left is locked by the checks): stop here.
      if (removed.size() < 0.25 * (dec.live_vertices() + removed.size()) * (1.0 - o.ratio)) break;
      // The finer level inserts these vertices in reverse removal order.
      Hierarchy::Level& finer = fine_to_coarse.back();
      finer.ring_offsets.push_back(0);
      for (int k = static_cast<int>(removed.size()) - 1; k >= 0; --k) {
        finer.inserted.push_back(removed[k]);
        finer.ring_vertices.insert(finer.ring_vertices.end(), rings.begin() + offsets[k],
                                   rings.begin() + offsets[k + 1]);
        finer.ring_offsets.push_back(static_cast<int>(finer.ring_vertices.size()));
      }
      Hierarchy::Level coarse;
      coarse.vertices = dec.vertices();
      coarse.faces = dec.faces();
      fine_to_coarse.push_back(std::move(coarse));
      dec.compact();
    }
  }
  h.levels.assign(std::make_move_iterator(fine_to_coarse.rbegin()),
                  std::make_move_iterator(fine_to_coarse.rend()));
  return h;
}

}  // namespace strata::internal
