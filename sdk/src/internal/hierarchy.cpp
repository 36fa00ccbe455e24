#include "internal/hierarchy.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cmath>
#include <queue>

namespace strata::internal {
namespace {

struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

// Working state of build_hierarchy(): the mesh under decimation and the collapse queue.
class Decimator {
 public:
  Decimator(const std::vector<Vec3>& x, const std::vector<Face>& faces) : x_(x) {
    mesh_.request_vertex_status();
    mesh_.request_edge_status();
    mesh_.request_halfedge_status();
    mesh_.request_face_status();
    for (const Vec3& p : x) mesh_.add_vertex(OMesh::Point(p[0], p[1], p[2]));
    for (const Face& f : faces)
      mesh_.add_face(OMesh::VertexHandle(f[0]), OMesh::VertexHandle(f[1]), OMesh::VertexHandle(f[2]));
    live_ = static_cast<int>(x.size());
    for (auto h : mesh_.halfedges()) push(h);
  }

  int live_vertices() const { return live_; }

  // Collapses until at most `target` vertices are live or nothing more can collapse. Appends the
  // removed vertices and their rings.
  void decimate_to(int target, std::vector<int>& removed, std::vector<int>& ring_offsets,
                   std::vector<int>& rings) {
    while (live_ > target && !queue_.empty()) {
      const Entry e = queue_.top();
      queue_.pop();
      const OMesh::HalfedgeHandle h(e.halfedge);
      if (mesh_.status(mesh_.edge_handle(h)).deleted()) continue;
      if (length2(h) != e.length2) continue;  // stale: a fresh entry exists
      if (!collapse_ok(h)) continue;
      const OMesh::VertexHandle v0 = mesh_.from_vertex_handle(h), v1 = mesh_.to_vertex_handle(h);
      removed.push_back(v0.idx());
      for (auto vv : mesh_.vv_range(v0)) rings.push_back(vv.idx());
      ring_offsets.push_back(static_cast<int>(rings.size()));
      mesh_.collapse(h);
      --live_;
      for (auto oh : mesh_.voh_range(v1)) {
        push(oh);
        push(mesh_.opposite_halfedge_handle(oh));
      }
    }
  }

  std::vector<Face> faces() const {
    std::vector<Face> out;
    for (auto f : mesh_.faces()) {
      if (mesh_.status(f).deleted()) continue;
      Face F;
      int k = 0;
      for (auto v : mesh_.fv_range(f)) F[k++] = v.idx();
      out.push_back(F);
    }
    return out;
  }

  std::vector<int> vertices() const {
    std::vector<int> out;
    for (auto v : mesh_.vertices())
      if (!mesh_.status(v).deleted()) out.push_back(v.idx());
    return out;
  }

 private:
  // Packed to 12 bytes (from 16): the queue holds millions of entries at 1M prisms (5.9M at its
  // largest), most of them stale, and its sifts are cache misses. The order is the same.
  struct __attribute__((packed)) Entry {
    double length2;
    int halfedge;
    bool operator<(const Entry& o) const { return length2 > o.length2; }  // min-heap
  };
  static_assert(sizeof(Entry) == 12, "Entry is packed");

  double length2(OMesh::HalfedgeHandle h) const {
    return (x_[mesh_.from_vertex_handle(h).idx()] - x_[mesh_.to_vertex_handle(h).idx()]).squaredNorm();
  }
  void push(OMesh::HalfedgeHandle h) { queue_.push(Entry{length2(h), h.idx()}); }

  bool collapse_ok(OMesh::HalfedgeHandle h) {
    if (!mesh_.is_collapse_ok(h)) return false;
    const OMesh::VertexHandle v0 = mesh_.from_vertex_handle(h), v1 = mesh_.to_vertex_handle(h);
    // Keep the boundary's shape: a boundary vertex may only slide along its boundary edge.
    if (mesh_.is_boundary(v0) && !mesh_.is_boundary(mesh_.edge_handle(h))) return false;
    // Faces that survive around v0 must not flip or degenerate when v0 moves onto v1.
    const Vec3 target = x_[v1.idx()];
    for (auto f : mesh_.vf_range(v0)) {
      Vec3 c[3], m[3];
      int k = 0;
      bool has_v1 = false;
      for (auto v : mesh_.fv_range(f)) {
        c[k] = x_[v.idx()];
        m[k] = v == v0 ? target : c[k];
        has_v1 |= v == v1;
        ++k;
      }
      if (has_v1) continue;
      const Vec3 n0 = triangle_area_normal(c[0], c[1], c[2]), n1 = triangle_area_normal(m[0], m[1], m[2]);
      const double l0 = n0.norm(), l1 = n1.norm();
      if (!(l1 > 1e-3 * l0) || n0.dot(n1) < 0.5 * l0 * l1) return false;
    }
    return true;
  }

  const std::vector<Vec3>& x_;
  OMesh mesh_;
  std::priority_queue<Entry> queue_;
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
      dec.decimate_to(target, removed, offsets, rings);
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
    }
  }
  h.levels.assign(std::make_move_iterator(fine_to_coarse.rbegin()),
                  std::make_move_iterator(fine_to_coarse.rend()));
  return h;
}

}  // namespace strata::internal
