#include "internal/renumber.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <numeric>

namespace strata::internal {

double scattered_edge_fraction(const std::vector<Face>& faces, int window) {
  if (faces.empty()) return 0.0;
  std::size_t far = 0;
  for (const Face& f : faces)
    for (int c = 0; c < 3; ++c) far += std::abs(f[c] - f[(c + 1) % 3]) > window;
  return static_cast<double>(far) / (3.0 * static_cast<double>(faces.size()));
}

namespace {

// Spreads the low 21 bits of x to every third bit.
std::uint64_t spread(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

Renumbering locality_renumbering(const std::vector<Vec3>& points, const std::vector<Face>& faces) {
  const int n = static_cast<int>(points.size());
  Renumbering r;
  if (n < kMinVertices || scattered_edge_fraction(faces, kWindow) <= kMaxScatteredFraction) return r;
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Vec3 extent = hi - lo;
  const double scale = extent.maxCoeff() > 0 ? static_cast<double>((1 << 21) - 1) / extent.maxCoeff() : 0.0;
  std::vector<std::pair<std::uint64_t, int>> keys(static_cast<std::size_t>(n));
  for (int v = 0; v < n; ++v) {
    const Vec3 q = (points[v] - lo) * scale;
    const auto cell = [&](int d) { return static_cast<std::uint64_t>(std::clamp(q[d], 0.0, 2097151.0)); };
    keys[v] = {spread(cell(0)) | spread(cell(1)) << 1 | spread(cell(2)) << 2, v};
  }
  std::sort(keys.begin(), keys.end());
  r.old_of_new.resize(n);
  r.new_of_old.resize(n);
  for (int i = 0; i < n; ++i) {
    r.old_of_new[i] = keys[i].second;
    r.new_of_old[keys[i].second] = i;
  }
  return r;
}

namespace {

// \p e's regularization graph with its rows in the order \p row_of (row i of the result is row
// row_of[i] of e) and its neighbours renamed by \p name; each row keeps its neighbours' order.
void reorder_graph(const DetailEncoding& e, const std::vector<int>& row_of, const std::vector<int>& name,
                   DetailEncoding& o) {
  const std::size_t n = row_of.size();
  o.weight_offsets.assign(1, 0);
  o.weight_offsets.reserve(n + 1);
  o.weight_neighbors.reserve(e.weight_neighbors.size());
  o.weights.reserve(e.weights.size());
  for (std::size_t i = 0; i < n; ++i) {
    const int v = row_of[i];
    for (int t = e.weight_offsets[v]; t < e.weight_offsets[v + 1]; ++t) {
      o.weight_neighbors.push_back(name[e.weight_neighbors[t]]);
      o.weights.push_back(e.weights[t]);
    }
    o.weight_offsets.push_back(static_cast<int>(o.weight_neighbors.size()));
  }
}

// Everything but the faces, their targets and the regularization graph: the base's data as is,
// the per-vertex arrays gathered by \p gather.
template <class Gather>
void copy_vertices(const DetailEncoding& e, Gather&& gather, DetailEncoding& o) {
  o.detail_rest = gather(e.detail_rest);
  o.base_num_vertices = e.base_num_vertices;
  o.base_faces = e.base_faces;
  o.base_points = gather(e.base_points);
  o.limit_points = gather(e.limit_points);
  o.cage_faces = e.cage_faces;
  o.cage_tags = e.cage_tags;
  o.cage_options = e.cage_options;
  o.base_rest_points = gather(e.base_rest_points);
  o.normal_offsets = gather(e.normal_offsets);
  o.tangential_offsets = gather(e.tangential_offsets);
  o.base_rest_normals = gather(e.base_rest_normals);
  o.base_rest_tangents = gather(e.base_rest_tangents);
  o.pinned = gather(e.pinned);
  o.report = e.report;
}

}  // namespace

DetailEncoding renumber(const DetailEncoding& e, const Renumbering& r, std::vector<int>* face_order_out) {
  const auto& nw = r.new_of_old;
  DetailEncoding o;
  // Faces: corners renamed (their order kept), ordered by their sorted new corners.
  const std::size_t nf = e.detail_faces.size();
  std::vector<Face> renamed(nf);
  std::vector<std::array<int, 3>> key(nf);
  for (std::size_t j = 0; j < nf; ++j) {
    for (int c = 0; c < 3; ++c) renamed[j][c] = nw[e.detail_faces[j][c]];
    key[j] = {renamed[j][0], renamed[j][1], renamed[j][2]};
    std::sort(key[j].begin(), key[j].end());
  }
  std::vector<int> face_order(nf);
  std::iota(face_order.begin(), face_order.end(), 0);
  std::stable_sort(face_order.begin(), face_order.end(), [&](int a, int b) { return key[a] < key[b]; });
  o.detail_faces.reserve(nf);
  o.target_volumes.reserve(nf);
  for (int j : face_order) {
    o.detail_faces.push_back(renamed[j]);
    o.target_volumes.push_back(e.target_volumes[j]);
  }
  copy_vertices(
      e, [&](const auto& v) { return to_new(r, v); }, o);
  reorder_graph(e, r.old_of_new, nw, o);
  if (face_order_out) *face_order_out = std::move(face_order);
  return o;
}

DetailEncoding restore(const DetailEncoding& o, const Renumbering& r, const std::vector<int>& face_order) {
  DetailEncoding e;
  const std::size_t nf = o.detail_faces.size();
  e.detail_faces.resize(nf);
  e.target_volumes.resize(nf);
  for (std::size_t j = 0; j < nf; ++j) {
    Face& f = e.detail_faces[static_cast<std::size_t>(face_order[j])];
    for (int c = 0; c < 3; ++c) f[c] = r.old_of_new[o.detail_faces[j][c]];
    e.target_volumes[static_cast<std::size_t>(face_order[j])] = o.target_volumes[j];
  }
  copy_vertices(
      o, [&](const auto& v) { return to_old(r, v); }, e);
  reorder_graph(o, r.new_of_old, r.old_of_new, e);
  return e;
}

}  // namespace strata::internal
