#include "internal/topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "strata/exceptions.h"

namespace strata::internal {

namespace {

// f(i) for i in [0, n): with Threads::Caller on TBB's threads of the caller's task arena, else
// serially. Each index writes only its own outputs, so the result is the same either way.
template <class F>
void for_each_index(Threads threads, int n, F&& f) {
  if (threads == Threads::Serial || n < 8192) {
    for (int i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 2048), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i != r.end(); ++i) f(i);
  });
}

}  // namespace

Adjacency build_adjacency(int nv, const std::vector<Face>& faces, Threads threads) {
  Adjacency a;
  a.face_offsets.assign(nv + 1, 0);
  for (const Face& f : faces)
    for (int v : f) ++a.face_offsets[v + 1];
  for (int i = 0; i < nv; ++i) a.face_offsets[i + 1] += a.face_offsets[i];
  a.faces.resize(a.face_offsets[nv]);
  a.corners.resize(a.face_offsets[nv]);
  std::vector<int> fill(a.face_offsets.begin(), a.face_offsets.end() - 1);
  for (int fi = 0; fi < static_cast<int>(faces.size()); ++fi)
    for (int c = 0; c < 3; ++c) {
      const int slot = fill[faces[fi][c]]++;
      a.faces[slot] = fi;
      a.corners[slot] = static_cast<std::uint8_t>(c);
    }
  // Neighbours: the other two corners of every incident face, deduplicated and sorted.
  auto candidates = [&](int v, std::vector<int>::iterator out) {
    for (int k = a.face_offsets[v]; k < a.face_offsets[v + 1]; ++k) {
      const Face& f = faces[a.faces[k]];
      const int c = a.corners[k];
      *out++ = f[(c + 1) % 3];
      *out++ = f[(c + 2) % 3];
    }
    return out;
  };
  a.neighbor_offsets.assign(nv + 1, 0);
  if (threads == Threads::Serial) {
    std::vector<int> scratch;
    for (int v = 0; v < nv; ++v) {
      scratch.resize(2 * static_cast<std::size_t>(a.face_offsets[v + 1] - a.face_offsets[v]));
      std::sort(scratch.begin(), candidates(v, scratch.begin()));
      scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
      a.neighbors.insert(a.neighbors.end(), scratch.begin(), scratch.end());
      a.neighbor_offsets[v + 1] = static_cast<int>(a.neighbors.size());
    }
    return a;
  }
  // On threads: each vertex's list goes to its own stretch of a scratch array (two slots per
  // incident face), then the stretches are packed (a temporary of 24 bytes a face, which the
  // serial path, the solver's set-up, does without).
  std::vector<int> lists(2 * a.faces.size());
  auto stretch = [&](int v) { return lists.begin() + 2 * static_cast<std::ptrdiff_t>(a.face_offsets[v]); };
  for_each_index(threads, nv, [&](int v) {
    const auto b = stretch(v), e = candidates(v, b);
    std::sort(b, e);
    a.neighbor_offsets[v + 1] = static_cast<int>(std::unique(b, e) - b);
  });
  for (int i = 0; i < nv; ++i) a.neighbor_offsets[i + 1] += a.neighbor_offsets[i];
  a.neighbors.resize(a.neighbor_offsets[nv]);
  for_each_index(threads, nv, [&](int v) {
    std::copy_n(stretch(v), a.neighbor_offsets[v + 1] - a.neighbor_offsets[v],
                a.neighbors.begin() + a.neighbor_offsets[v]);
  });
  return a;
}

std::vector<std::array<int, 3>> face_neighbors(int nv, const std::vector<Face>& faces) {
  const Adjacency adj = build_adjacency(nv, faces);
  std::vector<std::array<int, 3>> out(faces.size(), {-1, -1, -1});
  for (int fi = 0; fi < static_cast<int>(faces.size()); ++fi)
    for (int e = 0; e < 3; ++e) {
      // The faces of the endpoint of fewer faces are searched for the other: over the hub's
      // faces, a fan's every edge at its hub cost its valence (quadratic in it; a review).
      int a = faces[fi][e], b = faces[fi][(e + 1) % 3];
      if (adj.face_offsets[b + 1] - adj.face_offsets[b] < adj.face_offsets[a + 1] - adj.face_offsets[a])
        std::swap(a, b);
      for (int k = adj.face_offsets[a]; k < adj.face_offsets[a + 1]; ++k) {
        const int g = adj.faces[k];
        if (g == fi) continue;
        const Face& f = faces[g];
        if (f[0] == b || f[1] == b || f[2] == b) {
          out[fi][e] = g;
          break;
        }
      }
    }
  return out;
}

std::vector<char> boundary_vertices(int nv, const std::vector<Face>& faces) {
  std::vector<char> out(nv, 0);
  const std::vector<std::array<int, 3>> fn = face_neighbors(nv, faces);
  for (std::size_t j = 0; j < faces.size(); ++j)
    for (int e = 0; e < 3; ++e)
      if (fn[j][e] < 0) out[faces[j][e]] = out[faces[j][(e + 1) % 3]] = 1;
  return out;
}

namespace {

// Half the cotangent of the angle at corner o of a face with corners x0, x1, x2, the weight it
// gives the opposite edge; false for a degenerate corner (no weight).
bool half_cot(const Vec3* x, int o, double& cot) {
  const Vec3 ea = x[(o + 1) % 3] - x[o], eb = x[(o + 2) % 3] - x[o];
  const double s = ea.cross(eb).norm();
  if (!(s > 0.0)) return false;
  cot = 0.5 * ea.dot(eb) / s;
  return true;
}

// Vertex v's clamped weights, into w at v's neighbour slots. Gathered per vertex: the slot (v, u)
// sums the angles opposite the edge (v, u) in its faces in ascending order, as a scatter over the
// faces in order would, so the weights do not depend on the order the vertices are visited in.
void vertex_cotan_weights(const std::vector<Vec3>& x, const std::vector<Face>& faces, const Adjacency& adj,
                          int v, std::vector<double>& w) {
  const int b = adj.neighbor_offsets[v], e = adj.neighbor_offsets[v + 1];
  auto slot = [&](int u) {
    return static_cast<std::size_t>(
        std::lower_bound(adj.neighbors.begin() + b, adj.neighbors.begin() + e, u) - adj.neighbors.begin());
  };
  for (int k = b; k < e; ++k) w[k] = 0.0;
  for (int k = adj.face_offsets[v]; k < adj.face_offsets[v + 1]; ++k) {
    const Face& f = faces[adj.faces[k]];
    const int c = adj.corners[k];
    const Vec3 p[3] = {x[f[0]], x[f[1]], x[f[2]]};
    double cot;
    // The edge (v, f[c + 1]) is opposite corner c + 2, the edge (v, f[c + 2]) corner c + 1.
    if (half_cot(p, (c + 2) % 3, cot)) w[slot(f[(c + 1) % 3])] += cot;
    if (half_cot(p, (c + 1) % 3, cot)) w[slot(f[(c + 2) % 3])] += cot;
  }
  for (int k = b; k < e; ++k) w[k] = std::max(w[k], 0.0);
}

}  // namespace

std::vector<double> clamped_cotan_weights(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                          const Adjacency& adj, Threads threads) {
  std::vector<double> w(adj.neighbors.size());
  for_each_index(threads, adj.num_vertices(), [&](int v) { vertex_cotan_weights(x, faces, adj, v, w); });
  return w;
}

std::vector<double> normalized_cotan_weights(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                             const Adjacency& adj, Threads threads) {
  std::vector<double> w(adj.neighbors.size());
  for_each_index(threads, adj.num_vertices(), [&](int v) {
    vertex_cotan_weights(x, faces, adj, v, w);
    const int b = adj.neighbor_offsets[v], e = adj.neighbor_offsets[v + 1];
    double sum = 0.0;
    for (int k = b; k < e; ++k) sum += w[k];
    for (int k = b; k < e; ++k) w[k] = sum > 0.0 ? w[k] / sum : 1.0 / (e - b);
  });
  return w;
}

std::vector<char> floating_parts(const int* offsets, const int* neighbors, const std::vector<char>& free) {
  const std::size_t n = free.size();
  std::vector<char> seen(n, 0), floating(n, 0);
  std::vector<int> part;  // also the search's queue
  for (std::size_t start = 0; start < n; ++start) {
    if (!free[start] || seen[start]) continue;
    bool anchored = false;
    seen[start] = 1;
    part.assign(1, static_cast<int>(start));
    for (std::size_t q = 0; q < part.size(); ++q)
      for (int t = offsets[part[q]]; t < offsets[part[q] + 1]; ++t) {
        const int u = neighbors[t];
        if (!free[u]) {
          anchored = true;
        } else if (!seen[u]) {
          seen[u] = 1;
          part.push_back(u);
        }
      }
    if (!anchored)
      for (int v : part) floating[v] = 1;
  }
  return floating;
}

std::vector<int> ring_distance(const Adjacency& adj, const std::vector<char>& seeds, int cap) {
  const int n = adj.num_vertices();
  std::vector<int> dist(n, cap), frontier, next;
  for (int i = 0; i < n; ++i)
    if (seeds[i]) {
      dist[i] = 0;
      frontier.push_back(i);
    }
  for (int d = 1; d < cap && !frontier.empty(); ++d) {
    next.clear();
    for (int v : frontier)
      for (int t = adj.neighbor_offsets[v]; t < adj.neighbor_offsets[v + 1]; ++t) {
        const int u = adj.neighbors[t];
        if (dist[u] > d) {
          dist[u] = d;
          next.push_back(u);
        }
      }
    frontier.swap(next);
  }
  return dist;
}

void check_face_indices(const std::vector<Face>& faces, int num_vertices, const std::string& what) {
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int v : faces[f])
      if (v < 0 || v >= num_vertices)
        throw InvalidInput(what + ": face " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                           " out of range (" + std::to_string(num_vertices) + " vertices)");
}

}  // namespace strata::internal
