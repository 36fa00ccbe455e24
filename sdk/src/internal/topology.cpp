#include "internal/topology.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "strata/exceptions.h"

namespace strata::internal {

Adjacency build_adjacency(int nv, const std::vector<Face>& faces) {
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
  // Neighbours: the other two corners of every incident face, deduplicated.
  a.neighbor_offsets.assign(nv + 1, 0);
  std::vector<int> scratch;
  for (int v = 0; v < nv; ++v) {
    scratch.clear();
    for (int k = a.face_offsets[v]; k < a.face_offsets[v + 1]; ++k) {
      const Face& f = faces[a.faces[k]];
      const int c = a.corners[k];
      scratch.push_back(f[(c + 1) % 3]);
      scratch.push_back(f[(c + 2) % 3]);
    }
    std::sort(scratch.begin(), scratch.end());
    scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
    a.neighbors.insert(a.neighbors.end(), scratch.begin(), scratch.end());
    a.neighbor_offsets[v + 1] = static_cast<int>(a.neighbors.size());
  }
  return a;
}

std::vector<std::array<int, 3>> face_neighbors(int nv, const std::vector<Face>& faces) {
  const Adjacency adj = build_adjacency(nv, faces);
  std::vector<std::array<int, 3>> out(faces.size(), {-1, -1, -1});
  for (int fi = 0; fi < static_cast<int>(faces.size()); ++fi)
    for (int e = 0; e < 3; ++e) {
      const int a = faces[fi][e], b = faces[fi][(e + 1) % 3];
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

std::vector<double> clamped_cotan_weights(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                          const Adjacency& adj) {
  std::vector<double> w(adj.neighbors.size(), 0.0);
  auto slot = [&](int v, int u) {
    const auto b = adj.neighbors.begin() + adj.neighbor_offsets[v];
    const auto e = adj.neighbors.begin() + adj.neighbor_offsets[v + 1];
    return static_cast<std::size_t>(std::lower_bound(b, e, u) - adj.neighbors.begin());
  };
  for (const Face& f : faces)
    for (int c = 0; c < 3; ++c) {
      // The angle at corner c weighs the opposite edge (a,b).
      const int o = f[c], a = f[(c + 1) % 3], b = f[(c + 2) % 3];
      const Vec3 ea = x[a] - x[o], eb = x[b] - x[o];
      const double s = ea.cross(eb).norm();
      if (!(s > 0.0)) continue;
      const double cot = 0.5 * ea.dot(eb) / s;
      w[slot(a, b)] += cot;
      w[slot(b, a)] += cot;
    }
  for (double& v : w) v = std::max(v, 0.0);
  return w;
}

std::vector<double> normalized_cotan_weights(const std::vector<Vec3>& x, const std::vector<Face>& faces,
                                             const Adjacency& adj) {
  std::vector<double> w = clamped_cotan_weights(x, faces, adj);
  for (int v = 0; v < adj.num_vertices(); ++v) {
    const int b = adj.neighbor_offsets[v], e = adj.neighbor_offsets[v + 1];
    double sum = 0.0;
    for (int k = b; k < e; ++k) sum += w[k];
    for (int k = b; k < e; ++k) w[k] = sum > 0.0 ? w[k] / sum : 1.0 / (e - b);
  }
  return w;
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
