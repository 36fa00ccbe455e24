#include "internal/vertex_multigrid.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <type_traits>
#include <utility>

#include "internal/parallel.h"
#include "internal/topology.h"

namespace strata::internal {
namespace {

using Mat3 = Eigen::Matrix3d;

// Greedy aggregation of a graph in CSR form (no self loops): a vertex whose neighbours are all
// free takes them as its aggregate; the others join an aggregate of such a root next to them, or
// form their own with their free neighbours. Deterministic (vertex order). Returns the count.
int aggregate(int n, const std::vector<int>& off, const std::vector<int>& nb, std::vector<int>& agg) {
  agg.assign(n, -1);
  int na = 0;
  for (int i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    bool free = true;
    for (int t = off[i]; t < off[i + 1] && free; ++t) free = agg[nb[t]] < 0;
    if (!free) continue;
    agg[i] = na;
    for (int t = off[i]; t < off[i + 1]; ++t) agg[nb[t]] = na;
    ++na;
  }
  const std::vector<int> roots = agg;
  for (int i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    for (int t = off[i]; t < off[i + 1]; ++t)
      if (roots[nb[t]] >= 0) {
        agg[i] = roots[nb[t]];
        break;
      }
  }
  for (int i = 0; i < n; ++i) {
    if (agg[i] >= 0) continue;
    agg[i] = na;
    for (int t = off[i]; t < off[i + 1]; ++t)
      if (agg[nb[t]] < 0) agg[nb[t]] = na;
    ++na;
  }
  return na;
}

// Block CSR pattern (rows, sorted columns, diagonal slots) from (row, col) pairs; every row gets
// its diagonal block. The pairs are bucketed by row and each row sorted on its own: a sort of all
// the pairs at once (9.5M at 1M prisms) took most of the setup outside the hierarchy.
void build_pattern(int n, std::vector<std::pair<int, int>>& pairs, std::vector<int>& row,
                   std::vector<int>& col, std::vector<int>& diag) {
  for (int i = 0; i < n; ++i) pairs.emplace_back(i, i);
  std::vector<int> start(n + 1, 0);
  for (const auto& p : pairs) ++start[p.first + 1];
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> bucket(pairs.size());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (const auto& p : pairs) bucket[fill[p.first]++] = p.second;
  }
  row.assign(n + 1, 0);
  col.clear();
  for (int i = 0; i < n; ++i) {
    const auto b = bucket.begin() + start[i], e = bucket.begin() + start[i + 1];
    std::sort(b, e);
    col.insert(col.end(), b, std::unique(b, e));
    row[i + 1] = static_cast<int>(col.size());
  }
  diag.resize(n);
  for (int i = 0; i < n; ++i)
    diag[i] =
        static_cast<int>(std::lower_bound(col.begin() + row[i], col.begin() + row[i + 1], i) - col.begin());
}

int slot_of(const std::vector<int>& row, const std::vector<int>& col, int i, int j) {
  const auto b = col.begin() + row[i], e = col.begin() + row[i + 1];
  const auto it = std::lower_bound(b, e, j);
  assert(it != e && *it == j);
  return static_cast<int>(it - col.begin());
}

// The graph of a block pattern without its diagonal, in CSR form.
void pattern_graph(const std::vector<int>& row, const std::vector<int>& col, std::vector<int>& off,
                   std::vector<int>& nb) {
  const int n = static_cast<int>(row.size()) - 1;
  off.assign(n + 1, 0);
  nb.clear();
  for (int i = 0; i < n; ++i) {
    for (int t = row[i]; t < row[i + 1]; ++t)
      if (col[t] != i) nb.push_back(col[t]);
    off[i + 1] = static_cast<int>(nb.size());
  }
}

// How far ahead the fine products prefetch their per-face data, in faces (of 8-64, 32-64 were
// best).
constexpr std::size_t kPrefetchFaces = 48;

// Prefetches the per-face data (face, J and, with the smoothness term, its edge weights) of face
// j + kPrefetchFaces, or of the last face. The index is clamped, not tested: GCC 12 dropped the
// prefetches from the loops when they sat behind a test of it.
template <bool lap>
inline void prefetch_face(std::size_t j, std::size_t m, const Face* faces, const float* gf,
                          const float* flw) {
  j = j + kPrefetchFaces < m ? j + kPrefetchFaces : m - 1;
  __builtin_prefetch(gf + 9 * j);
  __builtin_prefetch(faces + j);
  if (lap) __builtin_prefetch(flw + 3 * j);
}

constexpr int kCorners[6][2] = {{0, 1}, {1, 0}, {0, 2}, {2, 0}, {1, 2}, {2, 1}};
// Corners (p, q), p < q -> their entry of kCorners (q, p is the next one).
constexpr int kCornerPair[3][3] = {{-1, 0, 2}, {-1, -1, 4}, {-1, -1, -1}};
// Face edge e = (f[e], f[e + 1]) -> its two entries of kCorners (both directions).
constexpr int kEdgeSlots[3][2] = {{0, 1}, {4, 5}, {2, 3}};

}  // namespace

VertexMultigrid::VertexMultigrid(int num_vertices, const std::vector<Face>& faces,
                                 const std::vector<int>& nb_offsets, const std::vector<int>& nb,
                                 const std::vector<double>& weights, const VertexMultigridOptions& options)
    : n0_(num_vertices), opt_(options) {
  if (n0_ == 0) return;
  // The smoothness term's graph: w_kl = (w(k,l) + w(l,k)) / 2 over the union of both directions,
  // each row's halves gathered into a bucket and summed in column order.
  std::vector<int> lap_off, lap_nb;
  std::vector<double> lap_w;
  {
    std::vector<int> start(n0_ + 1, 0);
    for (int k = 0; k < n0_; ++k)
      for (int t = nb_offsets[k]; t < nb_offsets[k + 1]; ++t) {
        ++start[k + 1];
        ++start[nb[t] + 1];
      }
    for (int k = 0; k < n0_; ++k) start[k + 1] += start[k];
    std::vector<std::pair<int, double>> bucket(start[n0_]);
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (int k = 0; k < n0_; ++k)
        for (int t = nb_offsets[k]; t < nb_offsets[k + 1]; ++t) {
          bucket[fill[k]++] = {nb[t], 0.5 * weights[t]};
          bucket[fill[nb[t]]++] = {k, 0.5 * weights[t]};
        }
    }
    lap_off.assign(n0_ + 1, 0);
    for (int k = 0; k < n0_; ++k) {
      const auto b = bucket.begin() + start[k], e = bucket.begin() + start[k + 1];
      std::sort(b, e, [](const auto& x, const auto& y) { return x.first < y.first; });
      for (auto it = b; it != e;) {
        auto next = it;
        double w = 0.0;
        for (; next != e && next->first == it->first; ++next) w += next->second;
        if (it->first != k) {
          lap_nb.push_back(it->first);
          lap_w.push_back(w);
        }
        it = next;
      }
      lap_off[k + 1] = static_cast<int>(lap_nb.size());
    }
  }
  // Each graph edge onto the first face that has it (face_lap_w_); the rest per vertex.
  {
    std::vector<char> taken(lap_nb.size(), 0);
    auto slot = [&](int a, int b) {
      const auto first = lap_nb.begin() + lap_off[a], last = lap_nb.begin() + lap_off[a + 1];
      const auto it = std::lower_bound(first, last, b);
      return it != last && *it == b ? static_cast<int>(it - lap_nb.begin()) : -1;
    };
    face_lap_w_.assign(3 * faces.size(), 0.0f);
    for (std::size_t j = 0; j < faces.size(); ++j)
      for (int e = 0; e < 3; ++e) {
        const int a = faces[j][e], b = faces[j][(e + 1) % 3];
        const int ab = a == b ? -1 : slot(a, b), ba = ab < 0 ? -1 : slot(b, a);
        if (ab < 0 || ba < 0 || taken[ab]) continue;
        taken[ab] = taken[ba] = 1;
        face_lap_w_[3 * j + e] = static_cast<float>(lap_w[ab]);
      }
    rest_offsets_.assign(n0_ + 1, 0);
    lap_diag_.assign(n0_, 0.0);
    for (int k = 0; k < n0_; ++k) {
      for (int t = lap_off[k]; t < lap_off[k + 1]; ++t) {
        lap_diag_[k] += lap_w[t];
        if (!taken[t]) {
          rest_nb_.push_back(lap_nb[t]);
          rest_w_.push_back(lap_w[t]);
        }
      }
      rest_offsets_[k + 1] = static_cast<int>(rest_nb_.size());
    }
  }
  // Level 0 -> 1: aggregates of the mesh's vertex graph.
  const Adjacency adj = build_adjacency(n0_, faces);
  const int n1 = aggregate(n0_, adj.neighbor_offsets, adj.neighbors, agg0_);
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(6 * faces.size());
  for (const Face& f : faces)
    for (const auto& c : kCorners) pairs.emplace_back(agg0_[f[c[0]]], agg0_[f[c[1]]]);
  for (int k = 0; k < n0_; ++k)
    for (int t = lap_off[k]; t < lap_off[k + 1]; ++t) pairs.emplace_back(agg0_[k], agg0_[lap_nb[t]]);
  coarse_.emplace_back();
  Coarse* c = &coarse_.back();
  c->n = n1;
  build_pattern(n1, pairs, c->row, c->col, c->diag);
  rest_slot_.resize(rest_nb_.size());
  for (int k = 0; k < n0_; ++k)
    for (int t = rest_offsets_[k]; t < rest_offsets_[k + 1]; ++t)
      rest_slot_[t] = slot_of(c->row, c->col, agg0_[k], agg0_[rest_nb_[t]]);
  face_slot_.resize(faces.size());
  for (std::size_t j = 0; j < faces.size(); ++j)
    for (int k = 0; k < 6; ++k)
      face_slot_[j][k] =
          slot_of(c->row, c->col, agg0_[faces[j][kCorners[k][0]]], agg0_[faces[j][kCorners[k][1]]]);
  // Coarser levels: aggregates of each level's block graph, until it is small enough to solve
  // densely or stops shrinking.
  std::vector<int> off, gnb;
  while (static_cast<int>(coarse_.size()) + 1 < opt_.max_levels &&
         coarse_.back().n > opt_.max_coarse_vertices) {
    c = &coarse_.back();
    pattern_graph(c->row, c->col, off, gnb);
    std::vector<int> agg;
    const int na = aggregate(c->n, off, gnb, agg);
    if (na >= c->n) break;
    pairs.clear();
    for (int i = 0; i < c->n; ++i)
      for (int t = c->row[i]; t < c->row[i + 1]; ++t) pairs.emplace_back(agg[i], agg[c->col[t]]);
    Coarse next;
    next.n = na;
    build_pattern(na, pairs, next.row, next.col, next.diag);
    c->to_coarse_slot.resize(c->col.size());
    for (int i = 0; i < c->n; ++i)
      for (int t = c->row[i]; t < c->row[i + 1]; ++t)
        c->to_coarse_slot[t] = slot_of(next.row, next.col, agg[i], agg[c->col[t]]);
    c->agg = std::move(agg);
    coarse_.push_back(std::move(next));
  }
}

std::vector<int> VertexMultigrid::level_sizes() const {
  std::vector<int> out{n0_};
  for (const Coarse& c : coarse_) out.push_back(c.n);
  return out;
}

VertexStepResult VertexMultigrid::solve(const VertexStepSystem& sys, double tolerance, int max_iterations,
                                        std::vector<Vec3>& delta, Workspace& ws, tbb::task_arena* arena,
                                        bool single_precision_cycle) const {
  const std::vector<Face>& faces = *sys.faces;
  const std::vector<int>& vfo = *sys.vf_offsets;
  const std::vector<int>& vf = *sys.vf;
  const std::vector<double>& r = *sys.r;
  const double eps = sys.eps, eps_lap = sys.eps_lap;
  const double eps_t = sys.normals ? sys.eps_tangential : 0.0;
  const Eigen::Vector3f* nrm = sys.normals ? sys.normals->data() : nullptr;
  // The term's 3 x 3 block at vertex v, eps_t (|u|^2 I - u u^T).
  auto tangential_block = [&](std::size_t v) {
    const Vec3 u = nrm[v].cast<double>();
    return Mat3(eps_t * (u.squaredNorm() * Mat3::Identity() - u * u.transpose()));
  };
  const std::size_t m = faces.size();
  const std::size_t n = static_cast<std::size_t>(n0_);
  const int nc = static_cast<int>(coarse_.size());
  assert(sys.gf->size() == 9 * m && r.size() == m && vfo.size() == n + 1 && eps > 0 &&
         sys.smoothing_degree >= 0 && (!sys.normals || sys.normals->size() == n) && eps_t >= 0);
  VertexStepResult result;
  delta.assign(n, Vec3::Zero());
  double rr0 = 0.0;
  for (double v : r) rr0 += v * v;
  result.relative_residual = rr0 > 0 ? 1.0 : 0.0;
  if (n == 0 || m == 0 || !(rr0 > 0)) return result;

  // --- This solve's operators: the fine block diagonal, the Galerkin coarse blocks (assembled
  // face by face in face order), their inverses and the coarsest factor.
  const float* gf = sys.gf->data();
  auto g_at = [gf](std::size_t entry) {  // the gradient of vertex-face entry face * 3 + corner
    const float* g = gf + 3 * entry;
    return Vec3(g[0], g[1], g[2]);
  };
  ws.fine.dinv.resize(n);
  parallel_for_each(arena, n, [&](std::size_t v) {
    Mat3 d = (eps + eps_lap * lap_diag_[v]) * Mat3::Identity();
    if (eps_t > 0) d.noalias() += tangential_block(v);
    // The block is symmetric: its six upper entries are summed, in the order and with the
    // roundings of the full outer products (g_i g_j is g_j g_i), and mirrored. A third fewer
    // products than Eigen's 3 x 3 outer product, with its column broadcasts, in what was 5-6% of
    // the cycles preset's solve.
    double a00 = d(0, 0), a01 = d(0, 1), a02 = d(0, 2), a11 = d(1, 1), a12 = d(1, 2), a22 = d(2, 2);
    for (int t = vfo[v]; t < vfo[v + 1]; ++t) {
      const float* g = gf + 3 * static_cast<std::size_t>(vf[t]);
      const double x = g[0], y = g[1], z = g[2];
      a00 += x * x;
      a01 += x * y;
      a02 += x * z;
      a11 += y * y;
      a12 += y * z;
      a22 += z * z;
    }
    d << a00, a01, a02, a01, a11, a12, a02, a12, a22;
    ws.fine.dinv[v] = d.inverse().cast<float>();
  });
  ws.levels.resize(nc);
  {
    std::vector<Eigen::Matrix3f>& val = ws.levels[0].val;
    const Coarse& c = coarse_[0];
    val.assign(c.col.size(), Eigen::Matrix3f::Zero());
    // A face's J^T J term, 3 x 3 blocks of g_a g_b^T, lands in the blocks of its corners'
    // aggregates: the gradients of corners in one aggregate are summed first (one outer product
    // for a face inside an aggregate, four for a face across two, instead of nine), and each
    // off-diagonal block is the transpose of its mirror. In single precision, as the blocks are
    // kept.
    using V3f = Eigen::Vector3f;
    for (std::size_t j = 0; j < m; ++j) {
      const Face& f = faces[j];
      const float* gj = gf + 9 * j;
      // The face's aggregates in corner order: each one's first corner and gradient sum.
      int first[3], groups = 0;
      V3f sum[3];
      for (int q = 0; q < 3; ++q) {
        const V3f g(gj[3 * q], gj[3 * q + 1], gj[3 * q + 2]);
        int i = 0;
        while (i < groups && agg0_[f[first[i]]] != agg0_[f[q]]) ++i;
        if (i == groups) {
          first[groups++] = q;
          sum[i] = g;
        } else {
          sum[i] += g;
        }
      }
      for (int a = 0; a < groups; ++a) {
        val[c.diag[agg0_[f[first[a]]]]] += sum[a] * sum[a].transpose();
        for (int b = a + 1; b < groups; ++b) {
          const int k = kCornerPair[first[a]][first[b]];  // even: the pair's mirror is k + 1
          const Eigen::Matrix3f x = sum[a] * sum[b].transpose();
          val[face_slot_[j][k]] += x;
          val[face_slot_[j][k + 1]] += x.transpose();
        }
      }
    }
    // The smoothness term's off-diagonal blocks: each face's edges (both directions), then the
    // rest edges; its diagonal with eps.
    if (eps_lap > 0)
      for (std::size_t j = 0; j < m; ++j)
        for (int e = 0; e < 3; ++e) {
          const float w = static_cast<float>(eps_lap * face_lap_w_[3 * j + e]);
          if (w == 0.0f) continue;
          for (int k : kEdgeSlots[e]) val[face_slot_[j][k]].diagonal().array() -= w;
        }
    for (std::size_t v = 0; v < n; ++v) {
      for (int t = rest_offsets_[v]; t < rest_offsets_[v + 1]; ++t)
        val[rest_slot_[t]].diagonal().array() -= static_cast<float>(eps_lap * rest_w_[t]);
      val[c.diag[agg0_[v]]].diagonal().array() += static_cast<float>(eps + eps_lap * lap_diag_[v]);
      if (eps_t > 0) val[c.diag[agg0_[v]]] += tangential_block(v).cast<float>();
    }
  }
  for (int l = 0; l + 1 < nc; ++l) {
    const Coarse& c = coarse_[l];
    std::vector<Eigen::Matrix3f>& next = ws.levels[l + 1].val;
    next.assign(coarse_[l + 1].col.size(), Eigen::Matrix3f::Zero());
    for (std::size_t t = 0; t < c.col.size(); ++t) next[c.to_coarse_slot[t]] += ws.levels[l].val[t];
  }
  for (int l = 0; l < nc; ++l) {
    const Coarse& c = coarse_[l];
    Workspace::Level& L = ws.levels[l];
    L.dinv.resize(c.n);
    for (int i = 0; i < c.n; ++i) L.dinv[i] = L.val[c.diag[i]].cast<double>().inverse().cast<float>();
  }
  {
    const Coarse& c = coarse_.back();
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * c.n, 3 * c.n);
    const std::vector<Eigen::Matrix3f>& val = ws.levels.back().val;
    for (int i = 0; i < c.n; ++i)
      for (int t = c.row[i]; t < c.row[i + 1]; ++t)
        dense.block<3, 3>(3 * i, 3 * c.col[t]) = val[t].cast<double>();
    ws.coarsest.compute(dense);
  }

  // --- Products with the level operators.
  // y = (J^T J + eps I + eps_lap L) x on the fine level, and J x into *jx_out if given. Per
  // vertex the terms are summed in one order, eps x and the rest edges' L x first, then per face
  // in ascending face order its J^T J term and its edges' L x terms (edges in face order), in the
  // serial pass (faces scattered) as in the threaded one (faces gathered, J x kept in between). T
  // is double for the conjugate gradients' product and the polish's V-cycle, float for the cycle
  // steps' V-cycle.
  const float* flw = face_lap_w_.data();
  // Lap: whether the smoothness term is applied, a compile-time flag so that the pass without it
  // (the polish's) is compiled as if the term did not exist.
  // Tan: whether the tangential damping is applied, a compile-time flag as Lap (with a branch per
  // vertex instead, three 20k bends of the multigrid preset, which has no such term, ran 2.8% more
  // instructions than before the term, against 1.0% with the flag; engine log, forty-fifth session).
  auto fine_product_with = [&](auto lap_flag, auto tan_flag, const auto& x, auto& y, auto* jx_out) {
    constexpr bool lap = decltype(lap_flag)::value;
    constexpr bool tan = decltype(tan_flag)::value;
    using V3 = std::decay_t<decltype(x[0])>;
    using T = typename V3::Scalar;
    y.resize(n);
    auto start = [&](std::size_t v) {
      V3 acc = static_cast<T>(eps) * x[v];
      if constexpr (tan) {
        const V3 nv = nrm[v].cast<T>();
        acc += static_cast<T>(eps_t) * (nv.squaredNorm() * x[v] - nv * nv.dot(x[v]));
      }
      if constexpr (lap)
        for (int t = rest_offsets_[v]; t < rest_offsets_[v + 1]; ++t)
          acc += static_cast<T>(eps_lap * rest_w_[t]) * (x[v] - x[rest_nb_[t]]);
      return acc;
    };
    auto jdot = [&](std::size_t j) {
      const Face& f = faces[j];
      const float* g = gf + 9 * j;
      const V3 &a = x[f[0]], &b = x[f[1]], &c = x[f[2]];
      return (g[0] * a[0] + g[1] * a[1] + g[2] * a[2]) + (g[3] * b[0] + g[4] * b[1] + g[5] * b[2]) +
             (g[6] * c[0] + g[7] * c[1] + g[8] * c[2]);
    };
    // With the smoothness term, face j's edges add eps_lap w (x_a - x_b) at a = f[e] and subtract
    // it at b = f[e + 1]. edge() is the one expression of a term for both passes, and both take a
    // corner's sum as (edge leaving it) - (edge arriving), so that they sum the same numbers.
    // Without the term the passes are as before it existed.
    // eps_lap in T: a float product multiplies in float, without two conversions per edge.
    const T lap_scale = static_cast<T>(eps_lap);
    auto edge = [&](const Face& f, const float* w, int e) {  // eps_lap w (x_a - x_b) of edge e
      return V3((lap_scale * static_cast<T>(w[e])) * (x[f[e]] - x[f[(e + 1) % 3]]));
    };
    auto lap_terms = [&](std::size_t j, V3& l0, V3& l1, V3& l2) {
      const Face& f = faces[j];
      const float* w = flw + 3 * j;
      const V3 d0 = edge(f, w, 0), d1 = edge(f, w, 1), d2 = edge(f, w, 2);
      l0 = d0 - d2;
      l1 = d1 - d0;
      l2 = d2 - d1;
    };
    // y_c += t g_c (+ l_c): the face's J^T J term at a corner and its smoothness terms there.
    auto add = [](V3& y_c, T t, const float* g_c) {
      y_c[0] += t * g_c[0];
      y_c[1] += t * g_c[1];
      y_c[2] += t * g_c[2];
    };
    auto add_lap = [](V3& y_c, T t, const float* g_c, const V3& l_c) {
      y_c += V3(t * g_c[0], t * g_c[1], t * g_c[2]) + l_c;
    };
    // The per-face data a few dozen faces ahead is prefetched: at 1M prisms these arrays stream
    // from memory, and the hardware's prefetcher alone left the pass waiting on them (18.2 against
    // 10.4 ns a face for the float product at 1M prisms, 21 against 16 for the double one).
    if (!arena || n < 4096) {
      for (std::size_t v = 0; v < n; ++v) y[v] = start(v);
      for (std::size_t j = 0; j < m; ++j) {
        prefetch_face<lap>(j, m, faces.data(), gf, flw);
        const T t = jdot(j);
        if (jx_out) (*jx_out)[j] = t;
        const Face& f = faces[j];
        const float* g = gf + 9 * j;
        if constexpr (lap) {
          V3 l0, l1, l2;
          lap_terms(j, l0, l1, l2);
          add_lap(y[f[0]], t, g, l0);
          add_lap(y[f[1]], t, g + 3, l1);
          add_lap(y[f[2]], t, g + 6, l2);
        } else {
          add(y[f[0]], t, g);
          add(y[f[1]], t, g + 3);
          add(y[f[2]], t, g + 6);
        }
      }
    } else {
      std::vector<T>& jx = jx_out ? *jx_out : ws.jx_scratch(T{});
      jx.resize(m);
      // With the smoothness term the face pass also keeps each face's edge terms, which the
      // vertex pass combines per corner as the serial pass does (computing them per corner there
      // made the threaded product slower than the neighbour lists it replaced).
      std::vector<V3>& el = ws.edge_scratch(T{});
      if constexpr (lap) el.resize(3 * m);
      parallel_for_each(arena, m, [&](std::size_t j) {
        prefetch_face<lap>(j, m, faces.data(), gf, flw);
        jx[j] = jdot(j);
        if constexpr (lap) {
          const Face& f = faces[j];
          const float* w = flw + 3 * j;
          for (int e = 0; e < 3; ++e) el[3 * j + e] = edge(f, w, e);
        }
      });
      parallel_for_each(arena, n, [&](std::size_t v) {
        V3 acc = start(v);
        for (int t = vfo[v]; t < vfo[v + 1]; ++t) {
          const std::size_t j = static_cast<std::size_t>(vf[t] / 3);
          const float* g = gf + 3 * vf[t];
          if constexpr (lap) {
            const int c = vf[t] % 3;  // edge c leaves the corner, edge c - 1 arrives
            add_lap(acc, jx[j], g, V3(el[3 * j + c] - el[3 * j + (c + 2) % 3]));
          } else {
            add(acc, jx[j], g);
          }
        }
        y[v] = acc;
      });
    }
  };
  auto fine_product = [&](const auto& x, auto& y, auto* jx_out) {
    if (eps_lap > 0 && eps_t > 0)
      fine_product_with(std::true_type{}, std::true_type{}, x, y, jx_out);
    else if (eps_lap > 0)
      fine_product_with(std::true_type{}, std::false_type{}, x, y, jx_out);
    else if (eps_t > 0)
      fine_product_with(std::false_type{}, std::true_type{}, x, y, jx_out);
    else
      fine_product_with(std::false_type{}, std::false_type{}, x, y, jx_out);
  };
  // The V-cycle, in scalar type T (float or double): its vectors are ws's T-typed ones.
  auto coarse_apply = [&](int l, const auto& x, auto& y) {
    using V3 = std::decay_t<decltype(x[0])>;
    using T = typename V3::Scalar;
    const Coarse& c = coarse_[l];
    const std::vector<Eigen::Matrix3f>& val = ws.levels[l].val;
    y.resize(c.n);
    parallel_for_each(arena, static_cast<std::size_t>(c.n), [&](std::size_t i) {
      V3 acc = V3::Zero();
      for (int t = c.row[i]; t < c.row[i + 1]; ++t) acc.noalias() += val[t].cast<T>() * x[c.col[t]];
      y[i] = acc;
    });
  };
  // Level l's operator and data: l = 0 fine, l >= 1 coarse_[l - 1].
  auto apply = [&](int l, const auto& x, auto& y) {
    using T = typename std::decay_t<decltype(x[0])>::Scalar;
    if (l > 0)
      coarse_apply(l - 1, x, y);
    else
      fine_product(x, y, static_cast<std::vector<T>*>(nullptr));
  };
  auto data = [&](int l) -> Workspace::Level& { return l == 0 ? ws.fine : ws.levels[l - 1]; };

  // Chebyshev smoothing of level l's system A x = b from x = 0 or the given x: the polynomial in
  // D^-1 A that is smallest on [bound / ratio, bound].
  const double lmax = 3.0 * 1.02, lmin = lmax / opt_.smoothing_ratio;
  const double theta = 0.5 * (lmax + lmin), half = 0.5 * (lmax - lmin), sigma = theta / half;
  auto smooth = [&](int l, const auto& b, auto& x, bool from_zero) {
    using V3 = std::decay_t<decltype(b[0])>;
    using T = typename V3::Scalar;
    Workspace::Level& L = data(l);
    auto& vec = L.vectors(T{});
    const std::size_t k = b.size();
    auto& res = vec.r;
    auto& d = vec.d;
    auto& t = vec.t;
    const int degree = sys.smoothing_degree > 0 ? sys.smoothing_degree : opt_.smoothing_degree;
    res.resize(k);
    d.resize(k);
    // One pass per degree: residual, search direction and update together (the same operations
    // in the same order as separate loops, so the same result). What no later degree reads is not
    // stored: from zero, the residual is b itself and x starts as 0 + d (not a pass of zeros
    // first; 0 + d, not d, keeps the sign of a zero as before); the last degree's residual and
    // direction are not kept. On the polish's double-precision vectors at 1M prisms, which the
    // caches do not hold, each vector pass saved is memory traffic saved.
    if (from_zero) {
      x.resize(k);
      for (std::size_t i = 0; i < k; ++i) {
        const V3 di = L.dinv[i].cast<T>() * b[i] / static_cast<T>(theta);
        if (degree > 1) d[i] = di;
        x[i] = V3::Zero() + di;
      }
    } else {
      apply(l, x, t);
      for (std::size_t i = 0; i < k; ++i) {
        res[i] = b[i] - t[i];
        d[i] = L.dinv[i].cast<T>() * res[i] / static_cast<T>(theta);
        x[i] += d[i];
      }
    }
    double rho0 = 1.0 / sigma;
    for (int deg = 2; deg <= degree; ++deg) {
      apply(l, d, t);
      const double rho1 = 1.0 / (2.0 * sigma - rho0);
      const T cd = static_cast<T>(rho1 * rho0), cr = static_cast<T>(2.0 * rho1 / half);
      const auto& prev = from_zero && deg == 2 ? b : res;  // the residual so far
      if (deg < degree) {
        for (std::size_t i = 0; i < k; ++i) {
          res[i] = prev[i] - t[i];
          d[i] = cd * d[i] + cr * (L.dinv[i].cast<T>() * res[i]);
          x[i] += d[i];
        }
      } else {
        for (std::size_t i = 0; i < k; ++i) {
          const V3 ri = prev[i] - t[i];
          x[i] += cd * d[i] + cr * (L.dinv[i].cast<T>() * ri);
        }
      }
      rho0 = rho1;
    }
  };
  // One V-cycle for level l: x ~ A_l^-1 b. Symmetric (the same smoother before and after the
  // coarse correction), so it preconditions conjugate gradients.
  auto vcycle = [&](int l, const auto& b, auto& x, auto&& self) -> void {
    using V3 = std::decay_t<decltype(b[0])>;
    using T = typename V3::Scalar;
    if (l == nc) {
      const int k = static_cast<int>(b.size());
      Eigen::VectorXd rhs(3 * k);
      for (int i = 0; i < k; ++i) rhs.segment<3>(3 * i) = b[i].template cast<double>();
      const Eigen::VectorXd sol = ws.coarsest.solve(rhs);
      x.resize(k);
      for (int i = 0; i < k; ++i) x[i] = sol.segment<3>(3 * i).template cast<T>();
      return;
    }
    auto& vl = data(l).vectors(T{});
    auto& vc = ws.levels[l].vectors(T{});
    const std::vector<int>& agg = l == 0 ? agg0_ : coarse_[l - 1].agg;
    smooth(l, b, x, true);
    apply(l, x, vl.t);
    vc.b.assign(coarse_[l].n, V3::Zero());
    for (std::size_t i = 0; i < b.size(); ++i) vc.b[agg[i]] += b[i] - vl.t[i];
    self(l + 1, vc.b, vc.x, self);
    for (std::size_t i = 0; i < b.size(); ++i) x[i] += vc.x[agg[i]];
    smooth(l, b, x, false);
  };
  // The other precision's vectors are released, so that the peak memory is one set's (the
  // polish follows the cycles once per solve; reallocating then costs little).
  auto release = [](auto& v) {
    for (auto* a : {&v.x, &v.b, &v.r, &v.d, &v.t}) std::decay_t<decltype(*a)>().swap(*a);
  };
  auto release_other = [&](Workspace::Level& L) {
    if (single_precision_cycle)
      release(L.f64);
    else
      release(L.f32);
  };
  release_other(ws.fine);
  for (Workspace::Level& L : ws.levels) release_other(L);
  auto release_cg = [](auto& c) {
    for (auto* a : {&c.p, &c.kp, &c.delta}) std::decay_t<decltype(*a)>().swap(*a);
    for (auto* a : {&c.rho, &c.jp}) std::decay_t<decltype(*a)>().swap(*a);
  };
  if (single_precision_cycle) {
    std::vector<double>().swap(ws.jx64);
    release_cg(ws.cg64);
  } else {
    std::vector<float>().swap(ws.jx32);
    std::vector<Eigen::Vector3f>().swap(ws.el32);
    release_cg(ws.cg32);
  }
  if (!(eps_lap > 0) || !arena || n < 4096) {  // no threaded product with the smoothness term
    std::vector<Eigen::Vector3f>().swap(ws.el32);
    std::vector<Vec3>().swap(ws.el64);
  }
  // Fixed vertices: their entries of the residual, the preconditioned residual and K p are held
  // at 0, so that delta stays 0 there (CG on the free vertices' block, preconditioned by the
  // free block of the V-cycle).
  const std::vector<char>* fixed = sys.fixed;
  auto clear_fixed = [&](auto& v) {
    if (fixed)
      for (std::size_t i = 0; i < n; ++i)
        if ((*fixed)[i]) v[i].setZero();
  };
  auto dot = [](const auto& a, const auto& b) {  // summed in double, in vertex order
    double s = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) s += static_cast<double>(a[i].dot(b[i]));
    return s;
  };

  // --- Preconditioned conjugate gradients from delta = 0, tracking rho = r - J delta, in the
  // V-cycle's precision T: the cycle steps' few inexact iterations need a few digits, and in
  // single precision their vectors are half the memory traffic (at 1M prisms they stream from
  // memory); the polish's nearly singular systems keep double. The residual is the fine level's
  // V-cycle right-hand side (b) and the preconditioned residual z its solution (x), 0 on fixed
  // vertices. A stop read here spares the first V-cycle too (at 1M prisms a cancel at a step's
  // start waited up to 0.25 s, for the step's gradients, these operators and that cycle, before
  // the first iteration's check).
  if (sys.stop && sys.stop->load(std::memory_order_relaxed)) return result;
  auto conjugate_gradients = [&](auto scalar) {
    using T = decltype(scalar);
    using V3 = Eigen::Matrix<T, 3, 1>;
    auto& fv = ws.fine.vectors(T{});
    auto& cg = ws.cg_vectors(T{});
    std::vector<V3>&res = fv.b, &z = fv.x, &p = cg.p, &kp = cg.kp;
    std::vector<T>&rho = cg.rho, &jp = cg.jp;
    std::vector<V3>* d = &cg.delta;
    if constexpr (std::is_same_v<T, double>) d = &delta;  // the caller's, without a copy
    d->assign(n, V3::Zero());
    rho.resize(m);
    for (std::size_t j = 0; j < m; ++j) rho[j] = static_cast<T>(r[j]);
    res.resize(n);
    parallel_for_each(arena, n, [&](std::size_t v) {
      Vec3 acc = Vec3::Zero();
      for (int t = vfo[v]; t < vfo[v + 1]; ++t) acc += r[vf[t] / 3] * g_at(vf[t]);
      res[v] = acc.cast<T>();
    });
    clear_fixed(res);
    auto precondition = [&] {  // z = the V-cycle of res; returns res . z
      vcycle(0, res, z, vcycle);
      clear_fixed(z);
      return dot(res, z);
    };
    double rz = precondition();
    p = z;
    const double stop = tolerance * tolerance * rr0;
    jp.resize(m);
    for (int it = 0; it < max_iterations; ++it) {
      if (sys.stop && sys.stop->load(std::memory_order_relaxed)) break;
      fine_product(p, kp, &jp);
      clear_fixed(kp);
      const double pkp = dot(p, kp);
      if (!(pkp > 0)) break;
      const double alpha = rz / pkp;
      const T a = static_cast<T>(alpha);
      for (std::size_t v = 0; v < n; ++v) {
        (*d)[v] += a * p[v];
        res[v] -= a * kp[v];
      }
      double rr = 0.0;
      for (std::size_t j = 0; j < m; ++j) {
        rho[j] -= a * jp[j];
        rr += static_cast<double>(rho[j]) * rho[j];
      }
      result.iterations = it + 1;
      result.relative_residual = std::sqrt(rr / rr0);
      // After the last iteration no direction is needed: its V-cycle (two of an iteration's three
      // fine products) would be thrown away. The cycle steps run 6 iterations, so this was 2 of
      // every 20 products.
      if (rr <= stop || it + 1 == max_iterations) break;
      const double rz_new = precondition();
      const T beta = static_cast<T>(rz_new / rz);
      rz = rz_new;
      for (std::size_t v = 0; v < n; ++v) p[v] = z[v] + beta * p[v];
    }
    if constexpr (!std::is_same_v<T, double>)
      for (std::size_t v = 0; v < n; ++v) delta[v] = (*d)[v].template cast<double>();
  };
  if (single_precision_cycle)
    conjugate_gradients(0.0f);
  else
    conjugate_gradients(0.0);
  return result;
}

}  // namespace strata::internal
