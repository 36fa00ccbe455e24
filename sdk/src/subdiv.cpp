#include "strata/subdiv.h"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/patchMap.h>
#include <opensubdiv/far/patchTable.h>
#include <opensubdiv/far/patchTableFactory.h>
#include <opensubdiv/far/ptexIndices.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>

#include "internal/ptex_domain.h"
#include "strata/exceptions.h"

namespace strata {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

// SubdivOptions::max_refined_faces' default (0) for a cage of \p face_corners corners.
long long default_refined_faces(long long face_corners) {
  return std::max<long long>(1 << 20, 512 * face_corners);
}

// A point type for OpenSubdiv's stencil updates (Clear / AddWithWeight).
struct P3 {
  double x[3];
  void Clear(void* = nullptr) { x[0] = x[1] = x[2] = 0.0; }
  void AddWithWeight(const P3& s, double w) {
    x[0] += w * s.x[0];
    x[1] += w * s.x[1];
    x[2] += w * s.x[2];
  }
};

// OpenSubdiv reports errors through a global callback; keep the last message of this thread so
// that a failed Create() can say why. The callback is installed once.
thread_local std::string g_osd_error;
void osd_error(Far::ErrorType, const char* message) {
  g_osd_error = message ? message : "";
}
void osd_warning(const char*) {}
void install_osd_callbacks() {
  static std::once_flag once;
  std::call_once(once, [] {
    Far::SetErrorCallback(osd_error);
    Far::SetWarningCallback(osd_warning);
  });
}

std::uint64_t pair_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

std::string vtx(int v) {
  return std::to_string(v);
}

}  // namespace

Vec3 LimitSample::normal() const {
  const Vec3 n = du.cross(dv);
  const double l = n.norm();
  return l > 0 ? Vec3(n / l) : Vec3(Vec3::Zero());
}

class SubdivSurface::Impl {
 public:
  Impl(const PolyMesh& cage, const SubdivTags& tags, const SubdivOptions& options)
      : cage_(cage), tags_(tags), opt_(options) {
    install_osd_callbacks();
    validate();
    build_refiner();
    build_ptex();
    update_points();
    topology_id_ = topology_fingerprint();
  }

  // FNV-1a over what the patch table is made from (the faces, the tags, the options): equal for a
  // surface after set_control_points() or one built on the same cage topology, different (but for
  // a 2^-64 chance) where the patches differ.
  std::uint64_t topology_fingerprint() const {
    std::uint64_t h = 1469598103934665603ull;
    auto add = [&](const void* data, std::size_t n) {
      const auto* b = static_cast<const unsigned char*>(data);
      for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    };
    auto add_int = [&](long long x) { add(&x, sizeof x); };
    add_int(static_cast<int>(scheme_));  // as resolved (Auto is Loop or Catmull-Clark)
    add_int(static_cast<int>(opt_.boundary));
    add_int(opt_.isolation_level);
    for (const std::vector<int>& f : cage_.faces) {
      add_int(static_cast<long long>(f.size()));
      add(f.data(), f.size() * sizeof(int));
    }
    for (const SubdivTags::Crease& c : tags_.creases)
      add_int(c.v0), add_int(c.v1), add(&c.sharpness, sizeof(double));
    for (const SubdivTags::Corner& c : tags_.corners) add_int(c.vertex), add(&c.sharpness, sizeof(double));
    return h;
  }

  // ---- construction ----

  void validate() {
    // Enums cast from integers (a wrapper's, a file's) were kept: scheme() returned 7.
    if (opt_.scheme != SubdivScheme::Auto && opt_.scheme != SubdivScheme::Loop &&
        opt_.scheme != SubdivScheme::CatmullClark)
      throw InvalidInput("subdivision scheme " + vtx(static_cast<int>(opt_.scheme)) +
                         " is not auto, loop or catmull-clark");
    if (opt_.boundary != BoundaryRule::EdgeOnly && opt_.boundary != BoundaryRule::EdgeAndCorner)
      throw InvalidInput("boundary rule " + vtx(static_cast<int>(opt_.boundary)) +
                         " is not edge-only or edge-and-corner");
    const int nv = cage_.num_vertices();
    if (nv == 0 || cage_.faces.empty()) throw InvalidInput("cage has no vertices or no faces");
    check_coordinates(cage_.vertices, "cage");
    bool all_triangles = true;
    // Undirected edges get ids and may be shared by at most 2 faces; directed ones must be unique
    // (consistent orientation).
    std::vector<int> edge_faces;
    std::unordered_map<std::uint64_t, int> directed;
    for (int f = 0; f < cage_.num_faces(); ++f) {
      const std::vector<int>& c = cage_.faces[f];
      const int n = static_cast<int>(c.size());
      if (n < 3)
        throw InvalidInput("cage face " + vtx(f) + " has " + vtx(n) + " corners (a face needs at least 3)");
      if (n > kMaxCageValence)
        throw InvalidInput("cage face " + vtx(f) + " has " + vtx(n) + " corners, over " +
                           vtx(kMaxCageValence) +
                           " (the limit patches' cost grows with about the cube of it: 300 took 30 s)");
      all_triangles = all_triangles && n == 3;
      for (int k = 0; k < n; ++k) {
        if (c[k] < 0 || c[k] >= nv)
          throw InvalidInput("cage face " + vtx(f) + " has vertex index " + vtx(c[k]) +
                             " out of range (cage has " + vtx(nv) + " vertices)");
        for (int j = 0; j < k; ++j)
          if (c[j] == c[k]) throw InvalidInput("cage face " + vtx(f) + " repeats vertex index " + vtx(c[k]));
      }
      for (int k = 0; k < n; ++k) {
        const int a = std::min(c[k], c[(k + 1) % n]), b = std::max(c[k], c[(k + 1) % n]);
        const auto [it, fresh] = edge_ids_.emplace(pair_key(a, b), static_cast<int>(edge_ends_.size()));
        if (fresh) {
          edge_ends_.push_back({a, b});
          edge_faces.push_back(0);
        }
        if (++edge_faces[it->second] > 2)
          throw InvalidInput("cage edge (" + vtx(a) + "," + vtx(b) +
                             ") is non-manifold: shared by more than 2 faces");
      }
    }
    std::vector<int> valence(nv, 0);
    for (const std::vector<int>& c : cage_.faces)
      for (int v : c)
        if (++valence[v] > kMaxCageValence)
          throw InvalidInput(
              "cage vertex " + vtx(v) + " is in over " + vtx(kMaxCageValence) +
              " faces (the limit patches' cost grows with about the cube of it: 200 took 8 s)");
    for (const std::vector<int>& c : cage_.faces)
      for (std::size_t k = 0; k < c.size(); ++k) {
        const int a = c[k], b = c[(k + 1) % c.size()];
        if (++directed[(static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
                       static_cast<std::uint32_t>(b)] > 1)
          throw InvalidInput("cage edge (" + vtx(a) + "," + vtx(b) +
                             ") is used twice in the same direction (faces are inconsistently oriented)");
      }
    scheme_ = opt_.scheme;
    if (scheme_ == SubdivScheme::Auto)
      scheme_ = all_triangles ? SubdivScheme::Loop : SubdivScheme::CatmullClark;
    if (scheme_ == SubdivScheme::Loop && !all_triangles)
      throw InvalidInput("the Loop scheme needs an all-triangle cage");
    // A tag given twice (with sharpnesses that may differ) would leave which one counts to
    // OpenSubdiv's internals: refused, naming both.
    std::unordered_map<std::uint64_t, std::size_t> tagged;
    for (std::size_t k = 0; k < tags_.creases.size(); ++k) {
      const SubdivTags::Crease& c = tags_.creases[k];
      if (!(c.sharpness >= 0))
        throw InvalidInput("crease (" + vtx(c.v0) + "," + vtx(c.v1) + ") has a " +
                           (std::isnan(c.sharpness) ? "NaN" : "negative") + " sharpness");
      if (c.v0 < 0 || c.v1 < 0 || c.v0 >= nv || c.v1 >= nv || !edge_ids_.count(pair_key(c.v0, c.v1)))
        throw InvalidInput("crease (" + vtx(c.v0) + "," + vtx(c.v1) + ") is not an edge of the cage");
      const auto [it, fresh] = tagged.emplace(pair_key(c.v0, c.v1), k);
      if (!fresh)
        throw InvalidInput("crease (" + vtx(c.v0) + "," + vtx(c.v1) + ") is tagged twice (creases " +
                           std::to_string(it->second) + " and " + std::to_string(k) + ")");
    }
    tagged.clear();
    for (std::size_t k = 0; k < tags_.corners.size(); ++k) {
      const SubdivTags::Corner& c = tags_.corners[k];
      if (c.vertex < 0 || c.vertex >= nv)
        throw InvalidInput("corner tag on vertex " + vtx(c.vertex) + ", which the cage does not have");
      if (!(c.sharpness >= 0))
        throw InvalidInput("corner tag on vertex " + vtx(c.vertex) + " has a " +
                           (std::isnan(c.sharpness) ? "NaN" : "negative") + " sharpness");
      const auto [it, fresh] = tagged.emplace(static_cast<std::uint64_t>(c.vertex), k);
      if (!fresh)
        throw InvalidInput("corner tag on vertex " + vtx(c.vertex) + " is given twice (corners " +
                           std::to_string(it->second) + " and " + std::to_string(k) + ")");
    }
    if (opt_.isolation_level < 1 || opt_.isolation_level > 10)
      throw InvalidInput("subdivision isolation level must be in 1..10, got " + vtx(opt_.isolation_level));
    if (opt_.max_refined_faces < 0)
      throw InvalidInput("max_refined_faces must be at least 0, got " +
                         std::to_string(opt_.max_refined_faces));
    // A budget is a memory bound a file can set: 2^30 let a 190 KB cage file take 4.5 GB and
    // 27.5 s. Four times the default covers isolation level 6 on a cage creased everywhere.
    const long long ceiling = max_refined_faces_ceiling(face_corners());
    if (opt_.max_refined_faces > ceiling)
      throw InvalidInput("max_refined_faces " + std::to_string(opt_.max_refined_faces) +
                         " is above this cage's ceiling of " + std::to_string(ceiling) + " (" +
                         std::to_string(kMaxRefinedFacesFactor) +
                         " times the default budget, max(2^20, 512 x its " + std::to_string(face_corners()) +
                         " face corners))");
  }

  long long face_corners() const {
    long long corners = 0;
    for (const auto& f : cage_.faces) corners += static_cast<long long>(f.size());
    return corners;
  }
  // SubdivOptions::max_refined_faces' default (0) for this cage.
  long long default_budget() const { return default_refined_faces(face_corners()); }

  // The adaptive refinement. Up to level 4 as before, at once and unchecked. Deeper, one level at
  // a time, refused once the faces pass SubdivOptions::max_refined_faces: each level has at most
  // 4 times the faces of the one before, so at most about 4 times the budget is taken before the
  // refusal, where isolating a deep level at once took it all.
  void refine_within_budget(const Far::PatchTableFactory::Options& po) {
    const long long budget = opt_.max_refined_faces > 0 ? opt_.max_refined_faces : default_budget();
    const int level = opt_.isolation_level;
    for (int l = std::min(level, 4);; ++l) {
      Far::TopologyRefiner::AdaptiveOptions ao = po.GetRefineAdaptiveOptions();
      ao.SetIsolationLevel(l);
      refiner_->Unrefine();
      refiner_->RefineAdaptive(ao);
      if (l > 4 && refiner_->GetNumFacesTotal() > budget)
        throw InvalidInput("subdivision isolation level " + vtx(level) + " refines this cage (" +
                           vtx(cage_.num_faces()) + " faces, " + vtx(static_cast<int>(tags_.creases.size())) +
                           " creases) into more than " + std::to_string(budget) + " faces by level " +
                           vtx(l) + "; a lower isolation level or fewer creases would do");
      if (l >= level) return;
    }
  }

  void build_refiner() {
    std::vector<int> sizes, indices;
    for (const auto& f : cage_.faces) {
      sizes.push_back(static_cast<int>(f.size()));
      indices.insert(indices.end(), f.begin(), f.end());
    }
    std::vector<int> crease_pairs, corner_ids;
    std::vector<float> crease_w, corner_w;
    for (const auto& c : tags_.creases) {
      crease_pairs.push_back(c.v0);
      crease_pairs.push_back(c.v1);
      crease_w.push_back(static_cast<float>(c.sharpness));
    }
    for (const auto& c : tags_.corners) {
      corner_ids.push_back(c.vertex);
      corner_w.push_back(static_cast<float>(c.sharpness));
    }
    Far::TopologyDescriptor desc;
    desc.numVertices = cage_.num_vertices();
    desc.numFaces = cage_.num_faces();
    desc.numVertsPerFace = sizes.data();
    desc.vertIndicesPerFace = indices.data();
    desc.numCreases = static_cast<int>(crease_w.size());
    desc.creaseVertexIndexPairs = crease_pairs.empty() ? nullptr : crease_pairs.data();
    desc.creaseWeights = crease_w.empty() ? nullptr : crease_w.data();
    desc.numCorners = static_cast<int>(corner_w.size());
    desc.cornerVertexIndices = corner_ids.empty() ? nullptr : corner_ids.data();
    desc.cornerWeights = corner_w.empty() ? nullptr : corner_w.data();

    Sdc::Options so;
    so.SetVtxBoundaryInterpolation(opt_.boundary == BoundaryRule::EdgeOnly
                                       ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                       : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    const Sdc::SchemeType type = scheme_ == SubdivScheme::Loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK;
    g_osd_error.clear();
    refiner_.reset(Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Create(
        desc, Far::TopologyRefinerFactory<Far::TopologyDescriptor>::Options(type, so)));
    if (!refiner_) throw SolverError("OpenSubdiv could not build the cage's topology: " + g_osd_error);

    Far::PatchTableFactory::Options po(static_cast<unsigned>(opt_.isolation_level));
    po.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
    po.useInfSharpPatch = true;
    po.generateVaryingTables = false;
    po.generateVaryingLocalPoints = false;
    po.SetPatchPrecision<double>();
    refine_within_budget(po);
    table_.reset(Far::PatchTableFactory::Create(*refiner_, po));
    if (!table_) throw SolverError("OpenSubdiv could not build the patch table: " + g_osd_error);
    map_ = std::make_unique<Far::PatchMap>(*table_);
    // The patches' points are the control points, the refined points of every isolation level and
    // the end caps' local points, in that order. One stencil table gives all but the first from
    // the control points.
    Far::StencilTableFactoryReal<double>::Options so2;
    so2.generateIntermediateLevels = true;
    so2.generateOffsets = true;
    so2.generateControlVerts = false;
    std::unique_ptr<const Far::StencilTableReal<double>> refined(
        Far::StencilTableFactoryReal<double>::Create(*refiner_, so2));
    const Far::StencilTableReal<double>* local = table_->GetLocalPointStencilTable<double>();
    if (local && local->GetNumStencils() > 0) {
      stencils_.reset(Far::StencilTableFactoryReal<double>::AppendLocalPointStencilTable(
          *refiner_, refined.get(), local, true));
    } else {
      stencils_ = std::move(refined);
    }
    if (!stencils_) throw SolverError("OpenSubdiv could not build the refinement stencils: " + g_osd_error);
    const int n = cage_.num_vertices();
    for (int idx : stencils_->GetControlIndices())
      if (idx < 0 || idx >= n)
        throw SolverError("OpenSubdiv's refinement stencils refer past the control points");
    const int num_points = n + stencils_->GetNumStencils();
    for (int a = 0; a < table_->GetNumPatchArrays(); ++a)
      for (int idx : table_->GetPatchArrayVertices(a))
        if (idx < 0 || idx >= num_points) throw SolverError("OpenSubdiv's patches refer past their points");
  }

  // Ptex faces and the lines their edges lie on (for crossings and the tessellation).
  void build_ptex() {
    Far::PtexIndices ptex(*refiner_);
    num_ptex_ = ptex.GetNumFaces();
    corners_ = scheme_ == SubdivScheme::Loop ? 3 : 4;
    first_ptex_.resize(cage_.num_faces());
    deriv_scale_.assign(num_ptex_, 1.0);
    const int ne = static_cast<int>(edge_ids_.size());
    for (int f = 0; f < cage_.num_faces(); ++f) {
      const int n = static_cast<int>(cage_.faces[f].size()), p0 = ptex.GetFaceId(f);
      first_ptex_[f] = p0;
      if (n != corners_)
        for (int k = 0; k < n; ++k) deriv_scale_[p0 + k] = 0.5;
    }
    // Each ptex edge lies on a line: a cage edge (oriented from its smaller vertex id) or, inside
    // a non-quad, the segment from an edge midpoint to the face centre. A sub-face's outer edges
    // cover half of their cage edge.
    const int nf = cage_.num_faces();
    edge_line_.assign(static_cast<std::size_t>(num_ptex_) * 4, {-1, 0.0, 0.0});
    line_kind_.assign(ne, -1);
    std::unordered_map<std::uint64_t, int> inner;  // (cage edge, face) -> line
    auto cage_line = [&](int a, int b, double sa, double sb, EdgeLine& out) {
      out.line = edge_ids_.at(pair_key(a, b));
      out.s0 = a < b ? sa : 1.0 - sa;
      out.s1 = a < b ? sb : 1.0 - sb;
    };
    auto inner_line = [&](int a, int b, int f) {
      const int e = edge_ids_.at(pair_key(a, b));
      auto [it, fresh] = inner.emplace((static_cast<std::uint64_t>(e) << 32) | static_cast<std::uint32_t>(f),
                                       static_cast<int>(line_kind_.size()));
      if (fresh) {
        line_kind_.push_back(e);
        inner_face_.push_back(f);
      }
      return it->second;
    };
    for (int f = 0; f < nf; ++f) {
      const std::vector<int>& c = cage_.faces[f];
      const int n = static_cast<int>(c.size()), p0 = first_ptex_[f];
      if (n == corners_) {
        for (int k = 0; k < n; ++k) cage_line(c[k], c[(k + 1) % n], 0.0, 1.0, edge_line_[4 * p0 + k]);
        continue;
      }
      for (int k = 0; k < n; ++k) {
        const int prev = c[(k + n - 1) % n], next = c[(k + 1) % n];
        EdgeLine* el = &edge_line_[4 * (p0 + k)];
        cage_line(c[k], next, 0.0, 0.5, el[0]);
        el[1] = {inner_line(c[k], next, f), 0.0, 1.0};
        el[2] = {inner_line(prev, c[k], f), 1.0, 0.0};
        cage_line(prev, c[k], 0.5, 1.0, el[3]);
      }
    }
    line_edges_.assign(line_kind_.size(), {});
    for (int p = 0; p < num_ptex_; ++p)
      for (int e = 0; e < corners_; ++e) line_edges_[edge_line_[4 * p + e].line].push_back({p, e});
  }

  // The cage face whose ptex face (or sub-face) \p ptex is.
  int cage_face_of(int ptex) const {
    return static_cast<int>(std::upper_bound(first_ptex_.begin(), first_ptex_.end(), ptex) -
                            first_ptex_.begin()) -
           1;
  }

  EdgeCrossing across(int face, int edge, double t) const {
    const EdgeLine& a = edge_line_[4 * face + edge];
    const double s = a.s0 + t * (a.s1 - a.s0);
    // On a cage edge, the other half of the edge in the same non-quad (at the edge's midpoint,
    // where the two halves meet) is on this side of it, not across: only other faces count.
    const bool cage_edge = line_kind_[a.line] < 0;
    const int own = cage_edge ? cage_face_of(face) : -1;
    EdgeCrossing best;
    double best_gap = 1e-9;
    for (const auto& fe : line_edges_[a.line]) {
      if (fe[0] == face && fe[1] == edge) continue;
      if (cage_edge && cage_face_of(fe[0]) == own) continue;
      const EdgeLine& b = edge_line_[4 * fe[0] + fe[1]];
      const double lo = std::min(b.s0, b.s1), hi = std::max(b.s0, b.s1);
      const double gap = s < lo ? lo - s : s > hi ? s - hi : 0.0;
      if (gap < best_gap) {
        best_gap = gap;
        best = {fe[0], fe[1], std::clamp((s - b.s0) / (b.s1 - b.s0), 0.0, 1.0)};
      }
    }
    return best;
  }

  void update_points() {
    const int n = cage_.num_vertices();
    const int nr = stencils_->GetNumStencils();
    points_.resize(static_cast<std::size_t>(n) + nr);
    for (int i = 0; i < n; ++i) points_[i] = cage_.vertices[i];
    if (nr > 0) {
      std::vector<P3> src(n), dst(nr);
      for (int i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) src[i].x[d] = cage_.vertices[i][d];
      stencils_->UpdateValues(src.data(), dst.data());
      for (int i = 0; i < nr; ++i) points_[n + i] = Vec3(dst[i].x[0], dst[i].x[1], dst[i].x[2]);
    }
  }

  // ---- evaluation ----

  void check(const LimitPoint& p) const {
    if (p.face < 0 || p.face >= num_ptex_)
      throw InvalidInput("limit point on ptex face " + vtx(p.face) + ", the surface has " + vtx(num_ptex_));
    if (!std::isfinite(p.u) || !std::isfinite(p.v)) throw InvalidInput("limit point with non-finite (u, v)");
  }

  // A Gregory end cap's interior points f+ and f- at each corner are blended by rational weights
  // G(s, t) = N / D (N and D linear, the pair's G summing to 1). Debian's OpenSubdiv 3.5 is built
  // without OPENSUBDIV_GREGORY_EVAL_TRUE_DERIVATIVES, so its derivative weights take G as
  // constant; this adds the terms of G's own derivatives, making them the patch's true
  // derivatives (they were up to 13% off on a cube cage with pentagons). The layout of the 20
  // points and the G are those of Far's EvalBasisGregory; (u, v) is the ptex point, normalized
  // here to the patch as EvaluateBasis does.
  static void add_gregory_blend_derivatives(const Far::PatchParam& param, double s, double t, double* wDs,
                                            double* wDt, double* wDss, double* wDst, double* wDtt) {
    static constexpr int kPoint[8] = {3, 4, 8, 9, 13, 14, 18, 19};  // interior points
    static constexpr int kCol[8] = {1, 1, 2, 2, 2, 2, 1, 1};        // their Bezier columns (s)
    static constexpr int kRow[8] = {1, 1, 1, 1, 2, 2, 2, 2};        // and rows (t)
    // N and D of each G, as value = c + cs s + ct t (sC = 1 - s, tC = 1 - t):
    // G = s / (s + t), t / (s + t), t / (sC + t), sC / (sC + t), sC / (sC + tC), tC / (sC + tC),
    //     tC / (s + tC), s / (s + tC).
    static constexpr double kN[8][3] = {{0, 1, 0},  {0, 0, 1},  {0, 0, 1},  {1, -1, 0},
                                        {1, -1, 0}, {1, 0, -1}, {1, 0, -1}, {0, 1, 0}};
    static constexpr double kD[8][3] = {{0, 1, 1},   {0, 1, 1},   {1, -1, 1}, {1, -1, 1},
                                        {2, -1, -1}, {2, -1, -1}, {1, 1, -1}, {1, 1, -1}};
    param.Normalize(s, t);
    const double scale = static_cast<double>(1 << param.GetDepth());
    auto bezier = [](double x, double* b, double* db, double* ddb) {
      const double xc = 1.0 - x;
      b[0] = xc * xc * xc, b[1] = 3 * x * xc * xc, b[2] = 3 * x * x * xc, b[3] = x * x * x;
      db[0] = -3 * xc * xc, db[1] = 3 * xc * (1 - 3 * x), db[2] = 3 * x * (2 - 3 * x), db[3] = 3 * x * x;
      ddb[0] = 6 * xc, ddb[1] = 18 * x - 12, ddb[2] = 6 - 18 * x, ddb[3] = 6 * x;
    };
    double Bs[4], Bds[4], Bdss[4], Bt[4], Bdt[4], Bdtt[4];
    bezier(s, Bs, Bds, Bdss);
    bezier(t, Bt, Bdt, Bdtt);
    for (int i = 0; i < 8; ++i) {
      const double n = kN[i][0] + kN[i][1] * s + kN[i][2] * t;
      const double d = kD[i][0] + kD[i][1] * s + kD[i][2] * t;
      // At the patch corner where D = 0, OpenSubdiv takes G = N (= 0) and these terms are left
      // out: the first derivatives' vanish there; the second derivatives' limit depends on the
      // direction of approach (a Gregory patch's), so OpenSubdiv's value stands.
      if (!(d > 0)) continue;
      // G = N / D with N, D linear: G_x = a_x / D with a_x = N_x - D_x G, and
      // G_xy = -(D_x a_y + D_y a_x) / D^2. The point's Bezier weights vanish linearly where D does
      // (its corner), so Bs / D and Bt / D stay below 3: taken as such, no term overflows however
      // close to the corner (G_ss alone overflowed below u ~ 1e-154).
      const double g = n / d;
      const double as = kN[i][1] - kD[i][1] * g, at = kN[i][2] - kD[i][2] * g;
      const int k = kPoint[i], c = kCol[i], r = kRow[i];
      const double bs = Bs[c] / d, bt = Bt[r] / d;  // at most 3
      wDs[k] += bs * Bt[r] * as * scale;
      wDt[k] += bs * Bt[r] * at * scale;
      if (wDss) {
        const double s2 = scale * scale;
        wDss[k] += 2 * (Bds[c] * bt - kD[i][1] * bs * bt) * as * s2;
        wDst[k] += (Bds[c] * bt * at + bs * Bdt[r] * as - bs * bt * (kD[i][1] * at + kD[i][2] * as)) * s2;
        wDtt[k] += 2 * (Bdt[r] * bs - kD[i][2] * bs * bt) * at * s2;
      }
    }
  }

  // The same for a Loop cage's end caps, quartic Gregory triangles (Far's EvalBasisGregoryTri, which
  // takes its three pairs of blend weights G as constant in the derivatives too): the terms of
  // G's derivatives on the 6 interior points (the derivatives were up to 1.7% off near an
  // extraordinary vertex of an octahedron, and its projections' feet off orthogonal by 2e-3; a
  // review, thirty-eighth session). (u, v) is the ptex point; the scales are OpenSubdiv's,
  // rotated triangles' second derivatives negated as it negates them (basis() undoes that).
  static void add_gregory_triangle_blend_derivatives(const Far::PatchParam& param, double s, double t,
                                                     double* wDs, double* wDt, double* wDss, double* wDst,
                                                     double* wDtt) {
    static constexpr int kPoint[6] = {3, 4, 8, 9, 13, 14};  // the Gregory interior points
    // N and D of each G as c + cs s + ct t, with u = s, v = t, w = 1 - s - t: G = u / (u + v),
    // v / (u + v), v / (v + w), w / (v + w), w / (w + u), u / (w + u).
    static constexpr double kN[6][3] = {{0, 1, 0}, {0, 0, 1}, {0, 0, 1}, {1, -1, -1}, {1, -1, -1}, {0, 1, 0}};
    static constexpr double kD[6][3] = {{0, 1, 1}, {0, 1, 1}, {1, -1, 0}, {1, -1, 0}, {1, 0, -1}, {1, 0, -1}};
    param.NormalizeTriangle(s, t);
    const double sign = param.IsTriangleRotated() ? -1.0 : 1.0;
    const double scale = sign * static_cast<double>(1 << param.GetDepth());
    const double scale2 = sign * scale * scale;
    const double u = s, v = t, w = 1.0 - s - t;
    // The quartic Bezier weights of the three interior points (p112, p211, p121), each pair's,
    // and their first derivatives.
    const double B[3] = {12 * w * w * u * v, 12 * u * u * v * w, 12 * v * v * u * w};
    const double Bs[3] = {12 * v * w * (w - 2 * u), 12 * u * v * (2 * w - u), 12 * v * v * (w - u)};
    const double Bt[3] = {12 * u * w * (w - 2 * v), 12 * u * u * (w - v), 12 * u * v * (2 * w - v)};
    for (int i = 0; i < 6; ++i) {
      const double d = kD[i][0] + kD[i][1] * s + kD[i][2] * t;
      if (!(d > 0)) continue;  // a corner, where Far takes G constant and B vanishes
      const double n = kN[i][0] + kN[i][1] * s + kN[i][2] * t;
      const double g = n / d;
      const double as = kN[i][1] - kD[i][1] * g, at = kN[i][2] - kD[i][2] * g;  // G_x = a_x / D
      const int b = i / 2, k = kPoint[i];
      // B / D, B_x / D and B / D^2 stay bounded where D vanishes (B vanishes as fast there).
      const double bd = B[b] / d, bsd = Bs[b] / d, btd = Bt[b] / d, bdd = bd / d;
      wDs[k] += bd * as * scale;
      wDt[k] += bd * at * scale;
      if (wDss) {
        // (B G)_xy = B_x G_y + B_y G_x + B G_xy, G_xy = -(D_x a_y + D_y a_x) / D^2.
        wDss[k] += (2 * bsd * as - 2 * kD[i][1] * as * bdd) * scale2;
        wDst[k] += (bsd * at + btd * as - (kD[i][1] * at + kD[i][2] * as) * bdd) * scale2;
        wDtt[k] += (2 * btd * at - 2 * kD[i][2] * at * bdd) * scale2;
      }
    }
  }

  // Basis weights at p (clamped into the domain) and the patch's point indices.
  Far::ConstIndexArray basis(const LimitPoint& p, double* wP, double* wDu, double* wDv, double* wDuu,
                             double* wDuv, double* wDvv) const {
    double u = p.u, v = p.v;
    internal::clamp_to_domain(corners_, u, v);
    const Far::PatchTable::PatchHandle* h = map_->FindPatch(p.face, u, v);
    if (!h) throw SolverError("no limit patch at ptex face " + vtx(p.face));
    table_->EvaluateBasis(*h, u, v, wP, wDu, wDv, wDuu, wDuv, wDvv);
    const Far::ConstIndexArray cv = table_->GetPatchVertices(*h);
    const Far::PatchDescriptor::Type type = table_->GetPatchDescriptor(*h).GetType();
    if (wDu && type == Far::PatchDescriptor::GREGORY_BASIS)
      add_gregory_blend_derivatives(table_->GetPatchParam(*h), u, v, wDu, wDv, wDuu, wDuv, wDvv);
    if (wDu && type == Far::PatchDescriptor::GREGORY_TRIANGLE)
      add_gregory_triangle_blend_derivatives(table_->GetPatchParam(*h), u, v, wDu, wDv, wDuu, wDuv, wDvv);
    // OpenSubdiv 3.5 negates the second derivatives of rotated triangle patches (the middle
    // triangle of a Loop split, parameterized backwards) along with the first ones; the chain rule
    // gives them a factor (-1)^2 = 1. Checked against finite differences in the tests.
    if (wDuu && corners_ == 3 && table_->GetPatchParam(*h).IsTriangleRotated())
      for (int k = 0; k < cv.size(); ++k) {
        wDuu[k] = -wDuu[k];
        wDuv[k] = -wDuv[k];
        wDvv[k] = -wDvv[k];
      }
    return cv;
  }

  LimitSample evaluate(const LimitPoint& p, bool second) const {
    check(p);
    double wP[20], wDu[20], wDv[20], wDuu[20], wDuv[20], wDvv[20];
    const Far::ConstIndexArray cv =
        basis(p, wP, wDu, wDv, second ? wDuu : nullptr, second ? wDuv : nullptr, second ? wDvv : nullptr);
    LimitSample s;
    for (int k = 0; k < cv.size(); ++k) {
      const Vec3& x = points_[cv[k]];
      s.position += wP[k] * x;
      s.du += wDu[k] * x;
      s.dv += wDv[k] * x;
      if (second) {
        s.duu += wDuu[k] * x;
        s.duv += wDuv[k] * x;
        s.dvv += wDvv[k] * x;
      }
    }
    const double c = deriv_scale_[p.face];
    if (c != 1.0) {
      s.du *= c;
      s.dv *= c;
      s.duu *= c * c;
      s.duv *= c * c;
      s.dvv *= c * c;
    }
    return s;
  }

  Stencil stencil(const LimitPoint& p) const {
    check(p);
    double wP[20], wDu[20], wDv[20];
    const Far::ConstIndexArray cv = basis(p, wP, wDu, wDv, nullptr, nullptr, nullptr);
    const int n = cage_.num_vertices();
    struct Entry {
      int index;
      double p, u, v;
    };
    std::vector<Entry> e;
    for (int k = 0; k < cv.size(); ++k) {
      if (cv[k] < n) {
        e.push_back({cv[k], wP[k], wDu[k], wDv[k]});
        continue;
      }
      const int l = cv[k] - n;
      const int off = stencils_->GetOffsets()[l], size = stencils_->GetSizes()[l];
      for (int t = off; t < off + size; ++t) {
        const double w = stencils_->GetWeights()[t];
        e.push_back({stencils_->GetControlIndices()[t], w * wP[k], w * wDu[k], w * wDv[k]});
      }
    }
    std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) { return a.index < b.index; });
    const double c = deriv_scale_[p.face];
    Stencil s;
    for (Entry& x : e) {
      x.u *= c;
      x.v *= c;
      if (!s.indices.empty() && s.indices.back() == x.index) {
        s.position.back() += x.p;
        s.du.back() += x.u;
        s.dv.back() += x.v;
      } else {
        s.indices.push_back(x.index);
        s.position.push_back(x.p);
        s.du.push_back(x.u);
        s.dv.push_back(x.v);
      }
    }
    return s;
  }

  // ---- tessellation ----

  // Tessellation: every ptex face gets a grid; quads and Loop triangles R segments per edge, the
  // sub-faces of non-quads R/2 (R is rounded up to even then), so that the points on a line
  // (a cage edge or an inner line) fall on one lattice of R segments and are shared.
  LimitTessellation tessellate(int resolution) const {
    if (resolution < 1)
      throw InvalidInput("tessellation resolution must be at least 1, got " + vtx(resolution));
    bool has_subfaces = false;
    for (const auto& f : cage_.faces) has_subfaces = has_subfaces || static_cast<int>(f.size()) != corners_;
    // Rounded up to even in double: INT_MAX + 1 overflowed. Beyond the limit below, R is not used.
    const double R_even = has_subfaces ? resolution + static_cast<double>(resolution % 2) : resolution;
    // Resolution 1000 over a 50-face cage wrote 50M faces (2.8 GB); 100000 ran out of memory.
    double triangles = 0.0;  // as the loop below makes them: a quad grid 2 Rf^2, a triangle grid Rf^2
    for (int p = 0; p < num_ptex_; ++p) {
      const double Rf = deriv_scale_[p] == 1.0 ? R_even : std::floor(R_even / 2);
      triangles += (corners_ == 4 ? 2.0 : 1.0) * Rf * Rf;
    }
    if (triangles > kMaxTessellationTriangles) {
      char text[160];
      std::snprintf(text, sizeof text, "a tessellation at resolution %d would have %.3g triangles, over %.3g",
                    resolution, triangles, kMaxTessellationTriangles);
      throw InvalidInput(text);
    }
    const int R = static_cast<int>(R_even);
    LimitTessellation t;
    std::unordered_map<std::uint64_t, int> ids;  // (line, lattice index) or a corner key -> vertex
    const std::uint64_t corner_tag = std::uint64_t(1) << 63;
    auto add = [&](std::uint64_t key, const LimitPoint& p) {
      auto [it, fresh] = ids.emplace(key, static_cast<int>(t.vertex_points.size()));
      if (fresh) t.vertex_points.push_back(p);
      return it->second;
    };
    const int nv = cage_.num_vertices(), ne = static_cast<int>(edge_ids_.size());
    // The vertex at lattice index m of a line, with line ends folded onto their corner keys.
    std::function<std::uint64_t(int, int)> line_key = [&](int line, int m) -> std::uint64_t {
      if (line < ne) {
        if (m == 0 || m == R) {
          const std::array<int, 2> ends = edge_ends_[line];
          return corner_tag | static_cast<std::uint64_t>(m == 0 ? ends[0] : ends[1]);
        }
        return (static_cast<std::uint64_t>(line) << 32) | static_cast<std::uint32_t>(m);
      }
      if (m == 0) return line_key(line_kind_[line], R / 2);  // the cage edge's midpoint
      if (m == R)
        return corner_tag | static_cast<std::uint64_t>(nv + ne + inner_face_[line - ne]);  // face centre
      return (static_cast<std::uint64_t>(line) << 32) | static_cast<std::uint32_t>(m);
    };
    std::vector<int> grid;
    for (int p = 0; p < num_ptex_; ++p) {
      const int Rf = deriv_scale_[p] == 1.0 ? R : R / 2;
      auto node = [&](int i, int j) -> int {
        const double u = static_cast<double>(i) / Rf, v = static_cast<double>(j) / Rf;
        int edge = -1;
        if (corners_ == 4) {
          if (j == 0)
            edge = 0;
          else if (i == Rf)
            edge = 1;
          else if (j == Rf)
            edge = 2;
          else if (i == 0)
            edge = 3;
        } else {
          if (j == 0)
            edge = 0;
          else if (i + j == Rf)
            edge = 1;
          else if (i == 0)
            edge = 2;
        }
        if (edge < 0)
          return add(static_cast<std::uint64_t>(t.vertex_points.size()) | (std::uint64_t(1) << 62),
                     {p, u, v});
        const EdgeLine& el = edge_line_[4 * p + edge];
        const double s = el.s0 + internal::edge_param(corners_, edge, u, v) * (el.s1 - el.s0);
        return add(line_key(el.line, static_cast<int>(std::lround(s * R))), {p, u, v});
      };
      grid.assign(static_cast<std::size_t>(Rf + 1) * (Rf + 1), -1);
      for (int j = 0; j <= Rf; ++j)
        for (int i = 0; i <= Rf; ++i)
          if (corners_ == 4 || i + j <= Rf) grid[j * (Rf + 1) + i] = node(i, j);
      auto tri = [&](int i0, int j0, int i1, int j1, int i2, int j2) {
        t.mesh.faces.push_back(
            {grid[j0 * (Rf + 1) + i0], grid[j1 * (Rf + 1) + i1], grid[j2 * (Rf + 1) + i2]});
        t.face_ptex.push_back(p);
        t.face_uv.push_back({Eigen::Vector2d(double(i0) / Rf, double(j0) / Rf),
                             Eigen::Vector2d(double(i1) / Rf, double(j1) / Rf),
                             Eigen::Vector2d(double(i2) / Rf, double(j2) / Rf)});
      };
      for (int j = 0; j < Rf; ++j)
        for (int i = 0; i < Rf; ++i) {
          if (corners_ == 4) {
            tri(i, j, i + 1, j, i + 1, j + 1);
            tri(i, j, i + 1, j + 1, i, j + 1);
          } else {
            if (i + j < Rf) tri(i, j, i + 1, j, i, j + 1);
            if (i + j < Rf - 1) tri(i + 1, j, i + 1, j + 1, i, j + 1);
          }
        }
    }
    t.mesh.vertices.resize(t.vertex_points.size());
    for (std::size_t i = 0; i < t.vertex_points.size(); ++i)
      t.mesh.vertices[i] = evaluate(t.vertex_points[i], false).position;
    return t;
  }

  PolyMesh cage_;
  SubdivTags tags_;
  SubdivOptions opt_;
  SubdivScheme scheme_ = SubdivScheme::Loop;
  std::unordered_map<std::uint64_t, int> edge_ids_;
  std::unique_ptr<Far::TopologyRefiner> refiner_;
  std::unique_ptr<Far::PatchTable> table_;
  std::unique_ptr<Far::PatchMap> map_;
  std::unique_ptr<const Far::StencilTableReal<double>> stencils_;  // refined and local points from the cage
  std::vector<Vec3> points_;       // the patches' points: control, refined, local
  std::uint64_t topology_id_ = 0;  // topology_fingerprint()
  int num_ptex_ = 0, corners_ = 3;
  std::vector<int> first_ptex_;
  struct EdgeLine {
    int line;
    double s0, s1;  // the line's parameter at the edge's first and second corner
  };
  std::vector<EdgeLine> edge_line_;  // 4 per ptex face
  std::vector<int> line_kind_;       // per line: -1 for a cage edge, else the cage edge of an inner line
  std::vector<int> inner_face_;      // per inner line (line - #edges): its face
  std::vector<std::array<int, 2>> edge_ends_;                // per cage edge: its vertices, smaller first
  std::vector<std::vector<std::array<int, 2>>> line_edges_;  // per line: the ptex edges on it
  // OpenSubdiv's derivatives on the sub-faces of a non-quad are with respect to half-size
  // parameters (the sub-face as a quadrant of its face); ours are with respect to the sub-face's
  // own unit square.
  std::vector<double> deriv_scale_;
};

SubdivSurface::SubdivSurface(const PolyMesh& cage, const SubdivTags& tags, const SubdivOptions& options)
    : impl_(std::make_unique<Impl>(cage, tags, options)) {}
SubdivSurface::~SubdivSurface() = default;

long long SubdivSurface::max_refined_faces_ceiling(long long face_corners) {
  return kMaxRefinedFacesFactor * default_refined_faces(face_corners);
}
SubdivSurface::SubdivSurface(SubdivSurface&&) noexcept = default;
SubdivSurface& SubdivSurface::operator=(SubdivSurface&&) noexcept = default;

SubdivScheme SubdivSurface::scheme() const {
  return impl_->scheme_;
}
const PolyMesh& SubdivSurface::cage() const {
  return impl_->cage_;
}
const SubdivTags& SubdivSurface::tags() const {
  return impl_->tags_;
}
const SubdivOptions& SubdivSurface::options() const {
  return impl_->opt_;
}
int SubdivSurface::num_control_points() const {
  return impl_->cage_.num_vertices();
}
int SubdivSurface::num_ptex_faces() const {
  return impl_->num_ptex_;
}
int SubdivSurface::ptex_corners() const {
  return impl_->corners_;
}
int SubdivSurface::first_ptex_face(int cage_face) const {
  if (cage_face < 0 || cage_face >= impl_->cage_.num_faces())
    throw InvalidInput("cage face " + vtx(cage_face) + " out of range");
  return impl_->first_ptex_[cage_face];
}

void SubdivSurface::set_control_points(const std::vector<Vec3>& points) {
  if (static_cast<int>(points.size()) != impl_->cage_.num_vertices())
    throw InvalidInput("cage edit has " + vtx(static_cast<int>(points.size())) +
                       " control points, the cage has " + vtx(impl_->cage_.num_vertices()));
  check_coordinates(points, "edited cage");
  impl_->cage_.vertices = points;
  impl_->update_points();
}
const std::vector<Vec3>& SubdivSurface::control_points() const {
  return impl_->cage_.vertices;
}

LimitSample SubdivSurface::evaluate(const LimitPoint& p, bool second_derivatives) const {
  return impl_->evaluate(p, second_derivatives);
}
SubdivSurface::Stencil SubdivSurface::stencil(const LimitPoint& p) const {
  return impl_->stencil(p);
}
LimitTessellation SubdivSurface::tessellate(int resolution) const {
  return impl_->tessellate(resolution);
}

SubdivSurface::EdgeCrossing SubdivSurface::across_edge(int face, int edge, double t) const {
  if (face < 0 || face >= impl_->num_ptex_ || edge < 0 || edge >= impl_->corners_)
    throw InvalidInput("ptex edge (" + vtx(face) + "," + vtx(edge) + ") out of range");
  if (!std::isfinite(t)) throw InvalidInput("across_edge: the edge parameter t is not finite");
  return impl_->across(face, edge, std::clamp(t, 0.0, 1.0));
}

LimitPointSet::LimitPointSet(const SubdivSurface& surface, const std::vector<LimitPoint>& points) {
  const SubdivSurface::Impl& S = *surface.impl_;
  num_patch_points_ = static_cast<int>(S.points_.size());
  topology_id_ = S.topology_id_;
  offsets_.assign(points.size() + 1, 0);
  index_.reserve(points.size() * 16);
  wp_.reserve(points.size() * 16);
  wu_.reserve(points.size() * 16);
  wv_.reserve(points.size() * 16);
  double wP[20], wDu[20], wDv[20];
  for (std::size_t i = 0; i < points.size(); ++i) {
    S.check(points[i]);
    const Far::ConstIndexArray cv = S.basis(points[i], wP, wDu, wDv, nullptr, nullptr, nullptr);
    const double c = S.deriv_scale_[points[i].face];
    for (int k = 0; k < cv.size(); ++k) {
      index_.push_back(cv[k]);
      wp_.push_back(static_cast<float>(wP[k]));
      wu_.push_back(static_cast<float>(c * wDu[k]));
      wv_.push_back(static_cast<float>(c * wDv[k]));
    }
    offsets_[i + 1] = static_cast<int>(index_.size());
  }
}

void LimitPointSet::check(const SubdivSurface& surface) const {
  if (static_cast<int>(surface.impl_->points_.size()) != num_patch_points_)
    throw InvalidInput("limit point set was built on a surface with " + vtx(num_patch_points_) +
                       " patch points, this one has " + vtx(static_cast<int>(surface.impl_->points_.size())));
  // The same count is not the same patches (a cage with its faces' corners rotated evaluated
  // silently to other points).
  if (surface.impl_->topology_id_ != topology_id_)
    throw InvalidInput("limit point set was built on a surface of another topology (faces, tags or options)");
}

void LimitPointSet::evaluate_unchecked(const std::vector<Vec3>& P, int begin, int end, Vec3* positions,
                                       Vec3* du, Vec3* dv) const {
  for (int i = begin; i < end; ++i) {
    const int b = offsets_[i], e = offsets_[i + 1];
    const Vec3 o = P[index_[b]];
    // Sums of weights times (point - origin): the weights of the position sum to 1 and those
    // of the derivatives to 0, so the origin drops out and single-precision weights lose
    // nothing relative to the coordinates' magnitude.
    Vec3 sp = Vec3::Zero(), su = Vec3::Zero(), sv = Vec3::Zero();
    for (int k = b + 1; k < e; ++k) {
      const Vec3 d = P[index_[k]] - o;
      sp += static_cast<double>(wp_[k]) * d;
      su += static_cast<double>(wu_[k]) * d;
      sv += static_cast<double>(wv_[k]) * d;
    }
    positions[i - begin] = o + sp;
    du[i - begin] = su;
    dv[i - begin] = sv;
  }
}

void LimitPointSet::evaluate(const SubdivSurface& surface, std::vector<Vec3>& positions,
                             std::vector<Vec3>& du, std::vector<Vec3>& dv) const {
  check(surface);
  const int n = size();
  positions.resize(n);
  du.resize(n);
  dv.resize(n);
  const std::vector<Vec3>& P = surface.impl_->points_;
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    evaluate_unchecked(P, r.begin(), r.end(), positions.data() + r.begin(), du.data() + r.begin(),
                       dv.data() + r.begin());
  });
}

void LimitPointSet::evaluate(const SubdivSurface& surface, int begin, int end, Vec3* positions, Vec3* du,
                             Vec3* dv) const {
  check(surface);
  if (begin < 0 || end > size() || begin > end)
    throw InvalidInput("limit point range [" + vtx(begin) + ", " + vtx(end) + ") out of [0, " + vtx(size()) +
                       ")");
  evaluate_unchecked(surface.impl_->points_, begin, end, positions, du, dv);
}

}  // namespace strata
