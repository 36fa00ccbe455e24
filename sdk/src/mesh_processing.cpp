#include "strata/mesh_processing.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "internal/openmesh.h"
#include "internal/parts.h"
#include "internal/topology.h"
#include "internal/welder.h"
#include "strata/exceptions.h"

namespace strata {
namespace {

// Finite coordinates (any magnitude: a cage is fitted to a scan of 1e100 as to one of 1).
void check_finite(const std::vector<Vec3>& x, const char* what) {
  for (std::size_t v = 0; v < x.size(); ++v)
    if (!x[v].allFinite())
      throw InvalidInput(std::string(what) + ": vertex " + std::to_string(v) +
                         " has a non-finite coordinate");
}

struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

// taubin_smooth(): a pass may not leave a face with less than this share of its area in the input.
constexpr double kMinAreaRatio = 0.01;

// Twice the face's area in units of scale^-2: with scale a power of two near 1 / the face's
// extent in the input, so that the cross products neither overflow (coordinates of 1e160) nor
// underflow (1e-160, or a unit face in a mesh that reaches 1e100), where the collapse test would
// never fire; exact, so at scale 1 it is the plain area. stableNorm(): the squares of a product
// that has shrunk far below the input's would underflow.
double double_area(const std::vector<Vec3>& x, const Face& f, double scale) {
  const Vec3 a = scale * (x[f[1]] - x[f[0]]), b = scale * (x[f[2]] - x[f[0]]);
  return a.cross(b).stableNorm();
}

// The power of two just above 1 / the face's extent (the diagonal of its box; 1 for a face of one
// point).
double unit_scale(const std::vector<Vec3>& x, const Face& f) {
  Eigen::AlignedBox3d box(x[f[0]]);
  box.extend(x[f[1]]).extend(x[f[2]]);
  const double extent = box.diagonal().stableNorm();
  if (!(extent > 0) || !std::isfinite(extent)) return 1.0;
  int exponent = 0;
  std::frexp(extent, &exponent);
  return std::ldexp(1.0, -std::clamp(exponent, -1000, 1000));
}

// The mesh OpenMesh is given (the adapter): its add_face refuses a face whose directed edge
// another face holds already (an edge of three faces, or two faces that disagree in orientation),
// and a vertex whose faces form more than one fan (two sheets touching at a point, common in
// scans), with only a line on stderr; the face is then missing from the result. validate_mesh()
// rejects the first (refused here too, naming the edge) but accepts the second (the flat-array
// core has no use for it): such a vertex is split, one copy per fan, as the fans are separate
// sheets of surface. Returns the split mesh, or nothing if no vertex needed it. Faces' indices
// are in range and distinct.
std::optional<TriMesh> split_for_openmesh(const TriMesh& mesh, const char* what) {
  const int nv = mesh.num_vertices();
  const internal::Adjacency adj = internal::build_adjacency(nv, mesh.faces);
  // Per vertex v, each of its faces' corners after and before v: two faces joined at an edge
  // through v have its other end, one as the corner after v and the other as the corner before
  // (their orientations agree), and v's faces form one fan if those joins connect them all.
  struct Corner {
    int next, prev;
  };
  std::vector<Corner> corners;
  std::vector<int> parent, by_next, by_prev, copy_of_root;
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  struct Split {
    int face, corner, vertex;
  };
  std::vector<Split> splits;
  std::vector<int> copied;  // per new vertex: the vertex it copies
  for (int v = 0; v < nv; ++v) {
    const int first = adj.face_offsets[v], n = adj.face_offsets[v + 1] - first;
    if (n == 0) continue;
    corners.resize(n);
    for (int i = 0; i < n; ++i) {
      const Face& f = mesh.faces[adj.faces[first + i]];
      const int c = adj.corners[first + i];
      corners[i] = {f[(c + 1) % 3], f[(c + 2) % 3]};
    }
    auto sorted_by = [&](std::vector<int>& order, int Corner::*key) {
      order.resize(n);
      for (int i = 0; i < n; ++i) order[i] = i;
      std::sort(order.begin(), order.end(), [&](int a, int b) {
        return corners[a].*key != corners[b].*key ? corners[a].*key < corners[b].*key : a < b;
      });
      // Two faces leaving v towards the same vertex (or arriving from it) hold the same directed edge.
      for (int i = 1; i < n; ++i)
        if (corners[order[i]].*key == corners[order[i - 1]].*key) {
          const int w = corners[order[i]].*key;
          const bool out = key == &Corner::next;
          throw InvalidInput(std::string(what) + ": faces " +
                             std::to_string(adj.faces[first + order[i - 1]]) + " and " +
                             std::to_string(adj.faces[first + order[i]]) + " both run along edge (" +
                             std::to_string(out ? v : w) + "," + std::to_string(out ? w : v) +
                             ") the same way (an edge of more than two faces, or faces oriented "
                             "inconsistently; OpenMesh cannot hold it)");
        }
    };
    sorted_by(by_next, &Corner::next);
    sorted_by(by_prev, &Corner::prev);
    // Join each face to the one whose previous corner is its next corner (the face across the
    // edge from v to that corner).
    parent.resize(n);
    for (int i = 0; i < n; ++i) parent[i] = i;
    int fans = n;
    for (int i = 0, j = 0; i < n; ++i) {
      const int w = corners[by_next[i]].next;
      while (j < n && corners[by_prev[j]].prev < w) ++j;
      if (j == n || corners[by_prev[j]].prev != w) continue;
      const int a = find(by_next[i]), b = find(by_prev[j]);
      if (a != b) parent[a] = b, --fans;
    }
    if (fans == 1) continue;
    // The fan of v's first face keeps v; each other fan gets a copy.
    copy_of_root.assign(n, -1);
    copy_of_root[find(0)] = v;
    for (int i = 0; i < n; ++i) {
      int& target = copy_of_root[find(i)];
      if (target < 0) {
        target = nv + static_cast<int>(copied.size());
        copied.push_back(v);
      }
      if (target != v) splits.push_back({adj.faces[first + i], adj.corners[first + i], target});
    }
  }
  if (splits.empty()) return std::nullopt;
  TriMesh out = mesh;
  for (int v : copied) out.vertices.push_back(mesh.vertices[v]);
  for (const Split& x : splits) out.faces[x.face][x.corner] = x.vertex;
  return out;
}

}  // namespace

TriMesh weld_vertices(const TriMesh& mesh) {
  check_face_indices(mesh.vertices.size(), mesh.faces, "weld_vertices");
  internal::Welder welder;
  std::vector<int> to(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    to[i] = static_cast<int>(welder.index_of(mesh.vertices[i]));
  TriMesh w;
  w.vertices = std::move(welder.vertices);
  w.faces.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) {
    const Face g{to[f[0]], to[f[1]], to[f[2]]};
    if (g[0] != g[1] && g[1] != g[2] && g[2] != g[0]) w.faces.push_back(g);
  }
  return w;
}

std::vector<Vec3> taubin_smooth(const TriMesh& m, int steps) {
  if (steps < 0) throw InvalidInput("taubin_smooth: steps must be >= 0");
  check_face_indices(m.vertices.size(), m.faces, "taubin_smooth");
  check_finite(m.vertices, "taubin_smooth");
  std::vector<Vec3> x = m.vertices;
  if (steps == 0) return x;
  const internal::Adjacency adj = internal::build_adjacency(m.num_vertices(), m.faces);
  // The boundary edges (of one face) and their vertices, from the faces' neighbours
  // (boundary_vertices()'s definition). Per neighbour slot: whether the edge to it is a boundary
  // edge. A boundary vertex averages those neighbours only: a chord between two boundary vertices
  // (an ear's third edge, a fan over a polygon) would pull the rim inwards.
  const std::vector<std::array<int, 3>> fn = internal::face_neighbors(m.num_vertices(), m.faces);
  std::vector<char> boundary(x.size(), 0), along(adj.neighbors.size(), 0);
  auto slot = [&](int a, int b) {  // b's place among a's neighbours (sorted)
    const auto first = adj.neighbors.begin() + adj.neighbor_offsets[a];
    return std::lower_bound(first, adj.neighbors.begin() + adj.neighbor_offsets[a + 1], b) -
           adj.neighbors.begin();
  };
  for (std::size_t j = 0; j < m.faces.size(); ++j)
    for (int e = 0; e < 3; ++e) {
      if (fn[j][e] >= 0) continue;
      const int a = m.faces[j][e], b = m.faces[j][(e + 1) % 3];
      boundary[a] = boundary[b] = 1;
      along[slot(a, b)] = along[slot(b, a)] = 1;
    }
  std::vector<Vec3> next(x.size()), start;
  // Twice each face's area in the mesh, each in its own scale: no step leaves a face below
  // kMinAreaRatio of it.
  std::vector<double> scale(m.faces.size()), area0(m.faces.size());
  tbb::parallel_for(std::size_t{0}, m.faces.size(), [&](std::size_t f) {
    scale[f] = unit_scale(x, m.faces[f]);
    area0[f] = double_area(x, m.faces[f], scale[f]);
  });
  std::vector<int> reverted, queue;
  std::vector<char> is_reverted(x.size(), 0);
  auto collapsed = [&](std::size_t f) {
    return double_area(next, m.faces[f], scale[f]) < kMinAreaRatio * area0[f];
  };
  // The faces that the step into `next` collapses get their vertices back from `x`, and so do the
  // faces around those that collapse then; at worst every vertex, where no face had collapsed.
  auto keep_faces = [&] {
    std::vector<char> bad(m.faces.size(), 0);
    tbb::parallel_for(std::size_t{0}, m.faces.size(), [&](std::size_t f) { bad[f] = collapsed(f); });
    queue.clear();
    for (std::size_t f = 0; f < m.faces.size(); ++f)
      if (bad[f]) queue.push_back(static_cast<int>(f));
    while (!queue.empty()) {
      const int f = queue.back();
      queue.pop_back();
      if (!collapsed(f)) continue;
      for (int v : m.faces[f]) {
        if (is_reverted[v]) continue;
        is_reverted[v] = 1;
        reverted.push_back(v);
        next[v] = x[v];
        for (int k = adj.face_offsets[v]; k < adj.face_offsets[v + 1]; ++k) queue.push_back(adj.faces[k]);
      }
    }
    for (int v : reverted) is_reverted[v] = 0;
    reverted.clear();
  };
  auto pass = [&](double factor) {
    tbb::parallel_for(0, m.num_vertices(), [&](int v) {
      // The mean of v's neighbours (along the boundary for a boundary vertex), each scaled by s.
      auto mean_of = [&](double s) {
        Vec3 sum = Vec3::Zero();
        int n = 0;
        for (int k = adj.neighbor_offsets[v]; k < adj.neighbor_offsets[v + 1]; ++k) {
          if (boundary[v] && !along[k]) continue;
          sum += s * x[adj.neighbors[k]];
          ++n;
        }
        return n > 0 ? Vec3(sum / n) : Vec3(x[v] * s);
      };
      Vec3 mean = mean_of(1.0);
      // A sum that overflowed (coordinates near 1e308): the mean of the terms scaled by an exact
      // power of two, so that finite input stays finite (it gave inf and NaN; a review).
      if (!mean.allFinite()) mean = std::ldexp(1.0, 8) * mean_of(std::ldexp(1.0, -8));
      next[v] = x[v] + factor * (mean - x[v]);
    });
    x.swap(next);
  };
  // The floor holds per step, both passes together: a vertex held in the shrinking pass alone
  // took the expanding one, and a small part whose every shrinking pass was held grew at every
  // step (a two-face square 231 across after 100 steps; beside the camel, a 0.01-wide quad made
  // fit_cage()'s cage 2.8e5 across at 300 smoothing steps, 1.70 now; a review).
  for (int s = 0; s < steps; ++s) {
    start = x;
    pass(0.5);
    pass(-0.53);
    next.swap(x);  // next: the step's result; x: where the step began
    x.swap(start);
    keep_faces();
    x.swap(next);
  }
  return x;
}

namespace {

// decimate_mesh() of a mesh OpenMesh can hold whole (split_for_openmesh()).
TriMesh decimate_manifold(const TriMesh& mesh, int target) {
  // Relative to the centre of the bounding box: the quadrics' error terms are squares of plane
  // offsets, which cancel catastrophically far from the origin (a scan 1e6 away, as a
  // georeferenced one, was decimated in a near random order: the camel's fitted cage then missed
  // the scan by 4.9e-3 RMS where it misses it by 3.6e-3 at the origin).
  // And scaled by a power of two (exact, so the decimation of a scan of ordinary size is the
  // same to the bit) to at most 1 in each coordinate: OpenMesh's decimater keeps its priorities,
  // the quadrics' errors, in single precision, which overflowed for a scan scaled by 1e12 and
  // underflowed at 1e-100 (nothing was collapsed, and `strata build` made the whole scan its cage).
  const Vec3 centre = bbox_centre(mesh.vertices, mesh.faces);
  double radius = 0.0;
  for (const Face& f : mesh.faces)
    for (int v : f) radius = std::max(radius, (mesh.vertices[v] - centre).cwiseAbs().maxCoeff());
  int exponent = 0;
  std::frexp(radius, &exponent);
  OMesh om;
  std::vector<OMesh::VertexHandle> vh(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3 p = mesh.vertices[i] - centre;  // by ldexp(): 2^-exponent overflows for subnormals
    vh[i] = om.add_vertex(OMesh::Point(std::ldexp(p.x(), -exponent), std::ldexp(p.y(), -exponent),
                                       std::ldexp(p.z(), -exponent)));
  }
  // split_for_openmesh() leaves add_face nothing to refuse; were it to refuse a face still, the
  // decimation would run on a mesh with a hole.
  for (std::size_t j = 0; j < mesh.faces.size(); ++j) {
    const Face& f = mesh.faces[j];
    if (!om.add_face(vh[f[0]], vh[f[1]], vh[f[2]]).is_valid())
      throw InvalidInput("decimate_mesh: OpenMesh could not add face " + std::to_string(j) + " (" +
                         std::to_string(f[0]) + "," + std::to_string(f[1]) + "," + std::to_string(f[2]) +
                         ") to the faces before it");
  }
  // Unreferenced and isolated vertices would survive as stray points. Deleting needs the status
  // attributes (without them OpenMesh aborted on a scan with one unreferenced vertex).
  om.request_vertex_status();
  om.request_edge_status();
  om.request_face_status();
  bool isolated = false;
  for (auto v : om.vertices())
    if (om.is_isolated(v)) {
      om.delete_vertex(v, false);
      isolated = true;
    }
  if (isolated) om.garbage_collection();
  // The normal-flipping module needs face normals (OpenMesh prints a warning and computes them).
  om.request_face_normals();
  om.update_face_normals();
  {
    using Decimater = OpenMesh::Decimater::DecimaterT<OMesh>;
    Decimater dec(om);
    OpenMesh::Decimater::ModQuadricT<OMesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<OMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<OMesh>::Handle aspect;
    dec.add(quadric);
    dec.module(quadric).unset_max_err();
    dec.add(flipping);
    dec.module(flipping).set_max_normal_deviation(45.0);
    dec.add(aspect);
    dec.module(aspect).set_aspect_ratio(8.0f);
    dec.module(aspect).set_binary(true);
    if (!dec.initialize()) throw SolverError("decimate_mesh: the decimater could not be initialized");
    dec.decimate_to_faces(0, static_cast<size_t>(target));
    om.garbage_collection();  // while the decimater exists (OpenMesh's note)
  }
  TriMesh out;
  out.vertices.reserve(om.n_vertices());
  for (auto v : om.vertices()) {
    const OMesh::Point& p = om.point(v);
    out.vertices.push_back(
        Vec3(std::ldexp(p[0], exponent), std::ldexp(p[1], exponent), std::ldexp(p[2], exponent)) + centre);
  }
  out.faces.reserve(om.n_faces());
  for (auto f : om.faces()) {
    Face c{};
    int k = 0;
    for (auto v : om.fv_range(f)) c[k++] = v.idx();
    out.faces.push_back(c);
  }
  return out;
}

// The faces of each connected part of \p mesh (faces joined by a shared vertex), each part's in
// order, the parts in order of their first face.
std::vector<std::vector<int>> connected_parts(const TriMesh& mesh) {
  const internal::Parts p = internal::connected_parts(mesh.vertices, mesh.faces, false);
  std::vector<std::vector<int>> parts(p.count);
  for (std::size_t j = 0; j < mesh.faces.size(); ++j)
    parts[p.of_face(mesh.faces[j])].push_back(static_cast<int>(j));
  return parts;
}

// \p faces of \p mesh with the vertices they use, renumbered in order of first use. \p index
// (mesh.vertices.size() entries, all -1) is left as it was given: one array for every part, as a
// fresh one per part made many small parts quadratic in the mesh's size (a review: 160k
// tetrahedra beside a grid took 9.3 s, 88% of it clearing arrays).
TriMesh submesh(const TriMesh& mesh, const std::vector<int>& faces, std::vector<int>& index) {
  TriMesh out;
  out.faces.reserve(faces.size());
  std::vector<int> used;
  for (int j : faces) {
    Face g{};
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.faces[j][c];
      if (index[v] < 0) {
        index[v] = out.num_vertices();
        out.vertices.push_back(mesh.vertices[v]);
        used.push_back(v);
      }
      g[c] = index[v];
    }
    out.faces.push_back(g);
  }
  for (int v : used) index[v] = -1;
  return out;
}

void append(TriMesh& to, const TriMesh& part) {
  const int offset = to.num_vertices();
  to.vertices.insert(to.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (const Face& f : part.faces) to.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
}

// A part whose share of the target is under this many faces is small (a closed part cannot go
// below a tetrahedron's 4).
constexpr long long kSmallShare = 4;
// A small part is decimated alone to at most this many faces, and one of this many or fewer is
// kept whole: a collapse removes up to 2 faces, and the decimation stops at or below its target,
// so from more than 5 it ends with 4 or 5 (with a target of 4, an open part of 5 ended with 3).
constexpr int kSmallPartFaces = 5;

// decimate_manifold() of \p mesh, its small parts alone (decimate_mesh()'s contract).
TriMesh decimate_parts(const TriMesh& mesh, int target) {
  const std::vector<std::vector<int>> parts = connected_parts(mesh);
  std::size_t largest = 0;
  for (std::size_t p = 1; p < parts.size(); ++p)
    if (parts[p].size() > parts[largest].size()) largest = p;
  // A part is small when its share of the target, by its faces, is under kSmallShare faces
  // (compared in integers: target * faces_p / faces < 4): decimated together with the rest, it
  // stays at its few faces while the rest goes on to the target without it (300 tetrahedra of
  // scan debris beside the camel left the camel 78 of a 1,278-face cage).
  const long long all = static_cast<long long>(mesh.faces.size());
  std::vector<int> rest;
  std::vector<std::size_t> small;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    if (p != largest &&
        static_cast<long long>(target) * static_cast<long long>(parts[p].size()) < kSmallShare * all)
      small.push_back(p);
    else
      rest.insert(rest.end(), parts[p].begin(), parts[p].end());
  }
  if (small.empty()) return decimate_manifold(mesh, target);
  std::sort(rest.begin(), rest.end());
  std::vector<int> index(mesh.vertices.size(), -1);
  TriMesh out = decimate_manifold(submesh(mesh, rest, index), target);
  for (std::size_t p : small) {
    const TriMesh part = submesh(mesh, parts[p], index);
    append(out, part.num_faces() > kSmallPartFaces ? decimate_manifold(part, kSmallPartFaces) : part);
  }
  return out;
}

}  // namespace

TriMesh decimate_mesh(const TriMesh& mesh, int target) {
  if (target < 4) throw InvalidInput("decimate_mesh: the target face count must be >= 4");
  check_face_indices(mesh.vertices.size(), mesh.faces, "decimate_mesh");
  for (std::size_t j = 0; j < mesh.faces.size(); ++j) {
    const Face& f = mesh.faces[j];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])  // OpenMesh's add_face asserts on it
      throw InvalidInput("decimate_mesh: face " + std::to_string(j) + " repeats a vertex (" +
                         std::to_string(f[0]) + "," + std::to_string(f[1]) + "," + std::to_string(f[2]) +
                         ")");
  }
  check_finite(mesh.vertices, "decimate_mesh");
  // The result has at least 4 faces: a smaller input is the caller's, not the decimation's.
  if (mesh.faces.size() < 4)
    throw InvalidInput("decimate_mesh: the mesh has " + std::to_string(mesh.faces.size()) +
                       " faces; at least 4 are needed");
  const std::optional<TriMesh> split = split_for_openmesh(mesh, "decimate_mesh");
  TriMesh out = decimate_parts(split ? *split : mesh, target);
  if (out.num_faces() < 4) throw SolverError("decimate_mesh: the decimation left fewer than 4 faces");
  return out;
}

int orient_faces(TriMesh& mesh) {
  const long long nv = static_cast<long long>(mesh.vertices.size());
  const int nf = mesh.num_faces();
  auto usable = [&](const Face& f) {
    for (int c = 0; c < 3; ++c)
      if (f[c] < 0 || f[c] >= nv || f[c] == f[(c + 1) % 3]) return false;
    return true;
  };
  // Per undirected edge, its usable faces' uses: (face, whether it runs from the smaller vertex).
  struct Use {
    long long key;
    int face;
    bool forward;
  };
  std::vector<Use> uses;
  uses.reserve(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.faces[f];
    if (!usable(t)) continue;
    for (int c = 0; c < 3; ++c) {
      const int a = t[c], b = t[(c + 1) % 3];
      uses.push_back({std::min(a, b) * nv + std::max(a, b), f, a < b});
    }
  }
  std::sort(uses.begin(), uses.end(),
            [](const Use& x, const Use& y) { return x.key != y.key ? x.key < y.key : x.face < y.face; });
  // Faces joined across the edges of exactly two faces; `same`: whether they traverse it alike.
  struct Link {
    int other;
    bool same;
    long long key;
  };
  std::vector<std::vector<Link>> links(nf);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if (j - i == 2) {
      const bool same = uses[i].forward == uses[i + 1].forward;
      links[uses[i].face].push_back({uses[i + 1].face, same, uses[i].key});
      links[uses[i + 1].face].push_back({uses[i].face, same, uses[i].key});
    }
    i = j;
  }
  std::vector<signed char> flip(nf, -1);  // per face: 1 flipped, 0 kept, -1 unusable
  std::vector<int> part;                  // also the search's queue
  for (int start = 0; start < nf; ++start) {
    if (flip[start] >= 0 || !usable(mesh.faces[start])) continue;
    flip[start] = 0;
    part.assign(1, start);
    for (std::size_t q = 0; q < part.size(); ++q) {
      const int f = part[q];
      for (const Link& l : links[f]) {
        // Alike, the two must end with opposite flips; opposite, with the same.
        const signed char want = static_cast<signed char>(l.same ? 1 - flip[f] : flip[f]);
        if (flip[l.other] < 0) {
          flip[l.other] = want;
          part.push_back(l.other);
        } else if (flip[l.other] != want) {
          throw InvalidInput("orient faces: the part of face " + std::to_string(start) +
                             " is not orientable (a Moebius strip): its faces cannot agree across edge (" +
                             std::to_string(l.key / nv) + "," + std::to_string(l.key % nv) + ")");
        }
      }
    }
    // The side that flips fewer faces (a tie keeps the lowest-numbered face): a part already
    // consistent is left as it is, even inside out or the inner shell of a cavity.
    std::size_t flips = 0;
    for (int f : part) flips += flip[f] == 1;
    if (2 * flips > part.size())
      for (int f : part) flip[f] = static_cast<signed char>(1 - flip[f]);
  }
  // Only now, so that a part found not orientable leaves the mesh unchanged.
  int flipped = 0;
  for (int f = 0; f < nf; ++f)
    if (flip[f] == 1) {
      std::swap(mesh.faces[f][1], mesh.faces[f][2]);
      ++flipped;
    }
  return flipped;
}

}  // namespace strata
