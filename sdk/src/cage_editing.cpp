#include "strata/cage_editing.h"

#include <tbb/parallel_for.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <string>

#include "internal/cage_graph.h"
#include "internal/detail_solve.h"
#include "internal/topology.h"
#include "strata/exceptions.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Region and handle flags on a cage of n vertices: sizes, and a handle that leaves something to blend.
void check_cage_selection(int n, const std::vector<char>& region, const std::vector<char>& handle) {
  if (static_cast<int>(region.size()) != n || static_cast<int>(handle.size()) != n)
    throw InvalidInput("region and handle flags must have one entry per cage vertex (" + std::to_string(n) +
                       ")");
  int nr = 0, nh = 0;
  for (int i = 0; i < n; ++i) {
    nr += region[i] != 0;
    nh += region[i] && handle[i];
  }
  if (nr == 0) throw InvalidInput("the region selects no cage vertex");
  if (nh == 0) throw InvalidInput("the handle selects no cage vertex of the region");
  if (nh == nr) throw InvalidInput("the handle is the whole region: nothing to blend");
  // A region that is the whole cage is well posed (the handle holds the field at 1, which then is
  // 1 everywhere: the model moves rigidly); a mesh's is refused because its fairing needs a rest.
}

}  // namespace

std::vector<double> cage_blend_field(const PolyMesh& cage, const std::vector<char>& region,
                                     const std::vector<char>& handle) {
  const int n = cage.num_vertices();
  check_cage_selection(n, region, handle);
  // The cage's faces index its points (an out-of-range index overflowed the Laplacian's assembly).
  for (std::size_t f = 0; f < cage.faces.size(); ++f) {
    if (cage.faces[f].size() < 3)  // a face of 0-2 corners shapes no surface
      throw InvalidInput("cage face " + std::to_string(f) + " has " + std::to_string(cage.faces[f].size()) +
                         " corners, fewer than 3");
    for (int v : cage.faces[f])
      if (v < 0 || v >= n)
        throw InvalidInput("cage face " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                           " out of range (the cage has " + std::to_string(n) + " points)");
  }
  const Eigen::SparseMatrix<double> L = internal::cage_laplacian(cage, false);
  const Eigen::SparseMatrix<double> B = L.transpose() * L;
  std::vector<int> free_id(n, -1), free;
  Eigen::VectorXd fixed = Eigen::VectorXd::Zero(n);
  std::vector<double> s(n, 0.0);
  // A cage vertex in no face shapes no surface: it keeps s = 0 (1 on the handle) and stays out of
  // the system, where its row would be empty (a cage with one failed as "could not be factorized").
  std::vector<char> in_face(n, 0);
  for (const std::vector<int>& f : cage.faces)
    for (int v : f) in_face[v] = 1;
  // The connected parts of the free vertices that touch no held one (outside the region or on the
  // handle) keep s = 0 too: their field would be undetermined (a cage of several pieces, one of
  // them inside the region away from the handle: CGAL's boeing failed as "could not be
  // factorized"), and connected to nothing that moves, they stay. Over the edge graph: L's column
  // v holds v's neighbours.
  std::vector<char> is_free(n, 0);
  for (int v = 0; v < n; ++v) is_free[v] = region[v] && !handle[v] && in_face[v];
  Eigen::SparseMatrix<double> graph = L;
  graph.makeCompressed();
  const std::vector<char> floating =
      internal::floating_parts(graph.outerIndexPtr(), graph.innerIndexPtr(), is_free);
  for (int v = 0; v < n; ++v) {
    if (is_free[v] && !floating[v]) {
      free_id[v] = static_cast<int>(free.size());
      free.push_back(v);
    } else if (region[v] && handle[v]) {
      fixed[v] = 1.0;
      s[v] = 1.0;
    }
  }
  if (free.empty()) return s;
  const int m = static_cast<int>(free.size());
  std::vector<Eigen::Triplet<double>> tf;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
  const Eigen::VectorXd Bfixed = B * fixed;
  for (int k = 0; k < B.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(B, k); it; ++it)
      if (free_id[it.row()] >= 0 && free_id[it.col()] >= 0)
        tf.emplace_back(free_id[it.row()], free_id[it.col()], it.value());
  for (int k = 0; k < m; ++k) rhs[k] = -Bfixed[free[k]];
  Eigen::SparseMatrix<double> A(m, m);
  A.setFromTriplets(tf.begin(), tf.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  if (ldlt.info() != Eigen::Success) throw SolverError("the cage's blend field could not be factorized");
  const Eigen::VectorXd x = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !x.allFinite())
    throw SolverError("the cage's blend field solve failed");
  for (int k = 0; k < m; ++k) s[free[k]] = x[k];
  return s;
}

class CageEditor::Impl {
 public:
  Impl(const TriMesh& mesh, SubdivSurface base, const std::vector<char>& region,
       const std::vector<char>& handle, CageEditOptions o)
      : mesh_(mesh),
        base_(std::move(base)),
        opt_(std::move(o)),
        detail_(opt_.method, opt_.reconstruct, opt_.drag, opt_.drag_end, opt_.drag_end_cycles) {
    const int n = base_.num_control_points();
    check_cage_selection(n, region, handle);
    if (mesh.faces.empty() || mesh.vertices.empty()) throw InvalidInput("cage edit: the mesh has no faces");
    // INT_MAX rings overflowed the ring search's bound.
    if (opt_.handle_solved_rings > 1000)
      throw InvalidInput(
          "cage edit option handle_solved_rings = " + std::to_string(opt_.handle_solved_rings) +
          " is out of range (at most 1000; negative solves every vertex)");
    if (opt_.drag_end_cycles < 1 || opt_.drag_end_cycles > 100000)
      throw InvalidInput("cage edit option drag_end_cycles = " + std::to_string(opt_.drag_end_cycles) +
                         " is out of range (1-100000)");
    internal::check_face_indices(mesh.faces, mesh.num_vertices(), "cage editor's mesh");
    check_coordinates(mesh.vertices, "cage editor's mesh");
    for (int i = 0; i < n; ++i) {
      if (!region[i]) continue;
      region_.push_back(i);
      if (handle[i]) handle_.push_back(i);
    }
    const auto t0 = Clock::now();
    s_ = cage_blend_field(base_.cage(), region, handle);
    decompose_seconds_ = seconds_since(t0);
    const auto t1 = Clock::now();
    encode(region, handle);
    encode_seconds_ = seconds_since(t1);
  }

  std::vector<Vec3> edited_cage(const EditTransform& t) const {
    return blend_transform(base_.control_points(), s_, t);
  }

  EditResult apply(const EditTransform& t) const {
    return finish(t, [&](const std::vector<Vec3>& cage, EditResult& res) {
      return detail_.solve(cage, res, t.is_rigid());
    });
  }

  // An exact edit by transform t whose detail \p solve rebuilds over the edited cage.
  template <class Solve>
  EditResult finish(const EditTransform& t, Solve&& solve) const {
    EditResult res;
    auto t0 = Clock::now();
    res.base_positions = edited_cage(t);
    res.times.edit = seconds_since(t0);
    const std::vector<Vec3> sub = solve(res.base_positions, res);
    res.times.decompose = decompose_seconds_;
    res.times.encode = encode_seconds_;
    res.positions = mesh_.vertices;
    scatter(sub, res.positions);
    return res;
  }

  void begin_drag() {
    detail_.begin_drag(edited_cage(EditTransform{}));
    drag_positions_ = mesh_.vertices;
    drag_transform_ = EditTransform{};
    dragging_ = true;
  }

  const std::vector<Vec3>& update_drag(const EditTransform& t) {
    if (!dragging_) throw InvalidInput("update_drag() without begin_drag()");
    scatter(detail_.drag_step(edited_cage(t)), drag_positions_);
    drag_transform_ = t;
    return drag_positions_;
  }

  // The exact solve as CageEditOptions::drag_end says (RegionEditor::end_drag).
  EditResult end_drag() {
    if (!dragging_) throw InvalidInput("end_drag() without begin_drag()");
    // The drag stays on until the solve returns: a cancelled or failed end leaves it to be
    // ended (or dragged on) again.
    EditResult r = opt_.drag_end == EditOptions::DragEnd::CleanStart || !drag_transform_.is_rigid()
                       ? apply(drag_transform_)
                       : finish(drag_transform_, [&](const std::vector<Vec3>& cage, EditResult& res) {
                           return detail_.end_drag(cage, res);
                         });
    dragging_ = false;
    return r;
  }

  const TriMesh& mesh() const { return mesh_; }
  const SubdivSurface& base() const { return base_; }
  const std::vector<double>& blend() const { return s_; }
  const std::vector<int>& region() const { return region_; }
  const std::vector<int>& handle() const { return handle_; }
  int region_faces() const { return static_cast<int>(encoding().detail_faces.size()); }
  const DetailEncoding& encoding() const { return detail_.encoding(); }
  const CageEditOptions& options() const { return opt_; }
  bool dragging() const { return dragging_; }

 private:
  // The prisms whose base points depend on a region cage vertex (a non-zero weight in their
  // limit stencil), encoded over the limit surface; their vertices that do not depend on the
  // region are pinned (their frames cannot change), and so are those that depend on handle
  // vertices only (their frames move rigidly) unless within handle_solved_rings of one that
  // does not.
  void encode(const std::vector<char>& region, const std::vector<char>& handle) {
    const int nv = mesh_.num_vertices();
    // Projected once, on the whole mesh's parts (a region's submesh may be of other parts, or one).
    const Projection pr = project_mesh_to_limit(base_, mesh_, opt_.projection);
    std::vector<char> moves(nv, 0), nonrigid(nv, 0);
    tbb::parallel_for(0, nv, [&](int i) {
      const SubdivSurface::Stencil st = base_.stencil(pr.points[i]);
      for (std::size_t k = 0; k < st.indices.size(); ++k) {
        if (st.position[k] == 0.0 && st.du[k] == 0.0 && st.dv[k] == 0.0) continue;
        const int c = st.indices[k];
        if (region[c]) moves[i] = 1;
        if (!region[c] || !handle[c]) nonrigid[i] = 1;
      }
    });
    // Rigid (all weights on the handle) and far enough from every non-rigid vertex: pinned.
    const internal::Adjacency adj = internal::build_adjacency(nv, mesh_.faces);
    const int rings = opt_.handle_solved_rings;
    const std::vector<int> near_nonrigid =
        rings < 0 ? std::vector<int>(nv, 0) : internal::ring_distance(adj, nonrigid, rings + 1);
    std::vector<int> sub_id(nv, -1);
    TriMesh detail;
    for (const Face& f : mesh_.faces) {
      if (!moves[f[0]] && !moves[f[1]] && !moves[f[2]]) continue;
      Face g;
      for (int c = 0; c < 3; ++c) {
        int& id = sub_id[f[c]];
        if (id < 0) {
          id = static_cast<int>(sub_vertices_.size());
          sub_vertices_.push_back(f[c]);
        }
        g[c] = id;
      }
      detail.faces.push_back(g);
    }
    if (detail.faces.empty()) throw InvalidInput("no detail vertex depends on the region's cage vertices");
    for (int v : sub_vertices_) detail.vertices.push_back(mesh_.vertices[v]);
    DetailEncoding& enc = detail_.encoding();
    std::vector<LimitPoint> points;
    points.reserve(sub_vertices_.size());
    int fallback = 0;
    for (int v : sub_vertices_) {
      points.push_back(pr.points[v]);
      fallback += !pr.converged[v];
    }
    enc = encode_detail_at(detail, base_, std::move(points));
    enc.report.num_projected = detail.num_vertices() - fallback;
    enc.report.num_fallback = fallback;
    enc.report.seconds += pr.seconds;  // the projection: the whole mesh's
    // The rest of the mesh, fixed, for the solver's fold check (as RegionEditor's).
    detail_.set_intersection_context(context_around(mesh_.faces, moves, sub_vertices_, mesh_.vertices));
    moves_.swap(moves);
    enc.pinned.resize(sub_vertices_.size());
    std::vector<char> outside(sub_vertices_.size());
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k) {
      const int v = sub_vertices_[k];
      enc.pinned[k] = !moves_[v] || (rings >= 0 && near_nonrigid[v] > rings);
      outside[k] = !moves_[v];
    }
    detail_.set_nonrigid_pins(std::move(outside));
  }

  // Vertices that depend on the region take the solution; all others keep theirs exactly.
  void scatter(const std::vector<Vec3>& sub, std::vector<Vec3>& whole) const {
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k)
      if (moves_[sub_vertices_[k]]) whole[sub_vertices_[k]] = sub[k];
  }

  TriMesh mesh_;
  SubdivSurface base_;
  CageEditOptions opt_;
  internal::DetailSolve detail_;
  std::vector<int> region_, handle_;
  std::vector<double> s_;
  std::vector<char> moves_;
  std::vector<int> sub_vertices_;
  double decompose_seconds_ = 0.0, encode_seconds_ = 0.0;
  bool dragging_ = false;
  std::vector<Vec3> drag_positions_;
  EditTransform drag_transform_;
};

CageEditor::CageEditor(const TriMesh& mesh, SubdivSurface base, const std::vector<char>& region,
                       const std::vector<char>& handle, CageEditOptions options)
    : impl_(std::make_unique<Impl>(mesh, std::move(base), region, handle, std::move(options))) {}
CageEditor::~CageEditor() = default;
CageEditor::CageEditor(CageEditor&&) noexcept = default;
CageEditor& CageEditor::operator=(CageEditor&&) noexcept = default;

const TriMesh& CageEditor::mesh() const {
  return impl_->mesh();
}
const SubdivSurface& CageEditor::base() const {
  return impl_->base();
}
const std::vector<double>& CageEditor::blend() const {
  return impl_->blend();
}
const std::vector<int>& CageEditor::region_vertices() const {
  return impl_->region();
}
const std::vector<int>& CageEditor::handle_vertices() const {
  return impl_->handle();
}
int CageEditor::region_faces() const {
  return impl_->region_faces();
}
const DetailEncoding& CageEditor::encoding() const {
  return impl_->encoding();
}
const CageEditOptions& CageEditor::options() const {
  return impl_->options();
}
std::vector<Vec3> CageEditor::edited_cage(const EditTransform& t) const {
  return impl_->edited_cage(t);
}
EditResult CageEditor::apply(const EditTransform& t) const {
  return impl_->apply(t);
}
void CageEditor::begin_drag() {
  impl_->begin_drag();
}
const std::vector<Vec3>& CageEditor::update_drag(const EditTransform& t) {
  return impl_->update_drag(t);
}
EditResult CageEditor::end_drag() {
  return impl_->end_drag();
}
bool CageEditor::dragging() const {
  return impl_->dragging();
}

}  // namespace strata
