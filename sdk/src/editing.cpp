#include "strata/editing.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/SparseCore>
#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>

#include "internal/blended_map.h"
#include "internal/detail_solve.h"
#include "internal/option_error.h"
#include "internal/serial_openmp.h"
#include "internal/topology.h"
#include "strata/exceptions.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

bool finite(const Vec3& v) {
  return v.allFinite();
}

using internal::BlendedMap;

}  // namespace

Selection Selection::sphere(const Vec3& center, double radius) {
  Selection s;
  s.kind = Kind::Sphere;
  s.center = center;
  s.radius = radius;
  return s;
}
Selection Selection::halfspace(const Vec3& point, const Vec3& normal) {
  Selection s;
  s.kind = Kind::Halfspace;
  s.point = point;
  s.normal = normal;
  return s;
}
Selection Selection::box(const Vec3& min, const Vec3& max) {
  Selection s;
  s.kind = Kind::Box;
  s.min = min;
  s.max = max;
  return s;
}
Selection Selection::vertices(std::vector<int> indices) {
  Selection s;
  s.kind = Kind::Vertices;
  s.indices = std::move(indices);
  return s;
}

std::vector<char> select_vertices(const std::vector<Vec3>& x, const Selection& sel) {
  std::vector<char> out(x.size(), 0);
  switch (sel.kind) {
    case Selection::Kind::Sphere: {
      if (!finite(sel.center) || !std::isfinite(sel.radius) || sel.radius < 0)
        throw InvalidInput("sphere selection needs a finite center and a non-negative radius");
      const double r2 = sel.radius * sel.radius;
      if (std::isfinite(r2))  // (a square that overflows is farther than the radius: not selected)
        for (std::size_t i = 0; i < x.size(); ++i) out[i] = (x[i] - sel.center).squaredNorm() <= r2;
      else  // a radius of 1e200 squared overflowed, and inf <= inf selected every vertex
        for (std::size_t i = 0; i < x.size(); ++i) out[i] = (x[i] - sel.center).stableNorm() <= sel.radius;
      break;
    }
    case Selection::Kind::Halfspace: {
      // Zero tested on the largest coordinate, and the normal scaled by it: a normal of 1e-170
      // underflowed norm() (refused as zero) and the dot products.
      const double largest = finite(sel.normal) ? sel.normal.cwiseAbs().maxCoeff() : 0.0;
      if (!finite(sel.point) || !(largest > 0))
        throw InvalidInput("halfspace selection needs a finite point and a non-zero normal");
      const Vec3 n = sel.normal / largest;
      for (std::size_t i = 0; i < x.size(); ++i) out[i] = (x[i] - sel.point).dot(n) >= 0;
      break;
    }
    case Selection::Kind::Box: {
      if (!finite(sel.min) || !finite(sel.max) || (sel.min.array() > sel.max.array()).any())
        throw InvalidInput("box selection needs finite min <= max");
      for (std::size_t i = 0; i < x.size(); ++i)
        out[i] = (x[i].array() >= sel.min.array()).all() && (x[i].array() <= sel.max.array()).all();
      break;
    }
    case Selection::Kind::Vertices:
      for (int v : sel.indices) {
        if (v < 0 || v >= static_cast<int>(x.size()))
          throw InvalidInput("vertex selection index " + std::to_string(v) +
                             " is out of range (the mesh has " + std::to_string(x.size()) + " vertices)");
        out[v] = 1;
      }
      break;
    default:  // a value cast from outside the enum (an embedder's bad data)
      throw InvalidInput("selection kind " + std::to_string(static_cast<int>(sel.kind)) +
                         " is not one of the four");
  }
  return out;
}

EditTransform EditTransform::rotation(const Vec3& axis, double degrees, const Vec3& pivot,
                                      const Vec3& translation) {
  if (!finite(axis) || !std::isfinite(degrees) || !finite(pivot) || !finite(translation))
    throw InvalidInput("rotation has a non-finite value");
  // Normalized after scaling by its largest coordinate: the squares of an axis of 1e160 overflowed
  // (a zero axis, the "rotation" 6e-17 I) and those of 1e-160 lost their digits (not orthonormal).
  const double largest = axis.cwiseAbs().maxCoeff();
  if (!(largest > 0)) throw InvalidInput("rotation axis is zero");
  EditTransform t;
  // The angle modulo a turn first: 1e308 degrees overflowed to an infinite angle, a NaN matrix.
  t.linear = Eigen::AngleAxisd(std::fmod(degrees, 360.0) * M_PI / 180.0, (axis / largest).normalized())
                 .toRotationMatrix();
  t.pivot = pivot;
  t.translation = translation;
  t.rotation_axis = (axis / largest).normalized();
  t.rotation_degrees = degrees;
  return t;
}

Vec3 EditTransform::apply(const Vec3& x) const {
  return pivot + linear * (x - pivot) + translation;
}

bool EditTransform::is_rigid(double tolerance) const {
  if (!linear.allFinite() || !translation.allFinite() || !pivot.allFinite()) return false;
  const double off = (linear.transpose() * linear - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return off <= tolerance && linear.determinant() > 0.0;
}

Vec3 EditTransform::apply_blended(const Vec3& x, double s) const {
  if (!std::isfinite(s)) throw InvalidInput("blend weight is not finite");
  return BlendedMap(*this).apply(x, s);
}

EditTransform EditTransform::partial(double s) const {
  if (!std::isfinite(s)) throw InvalidInput("blend weight is not finite");
  return BlendedMap(*this).partial(s);
}

std::vector<Vec3> blend_transform(const std::vector<Vec3>& points, const std::vector<double>& s,
                                  const EditTransform& transform) {
  if (points.size() != s.size())
    throw InvalidInput("blend: " + std::to_string(s.size()) + " blend values for " +
                       std::to_string(points.size()) + " points");
  const BlendedMap map(transform);
  std::vector<Vec3> out = points;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!std::isfinite(s[i]))
      throw InvalidInput("blend: the value of point " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < points.size(); ++i)
    if (s[i] != 0.0) {
      out[i] = map.apply(points[i], s[i]);
      // Named here with the point's own index: a script's matrix 1e15 times scale 1e6 was reported
      // by the reconstruction as a vertex of its region's sub-mesh, naming no edit.
      if (!(out[i].allFinite() && out[i].cwiseAbs().maxCoeff() <= kMaxCoordinate)) {
        std::ostringstream m;
        m << "the edit moves vertex " << i << " to (" << out[i].transpose()
          << "), beyond the engine's range (" << kMaxCoordinate << ")";
        throw InvalidInput(m.str());
      }
    }
  return out;
}

// NaN or negative smoothing options were taken as 0 (or reported as a region without extent), and
// negative solved rings changed the result without a word.
static void check_edit_options(const EditOptions& o) {
  auto fail = [](const char* name, double value, const char* range) {
    internal::option_out_of_range("edit", name, value, range);
  };
  if (!(o.smoothing_wavelength >= 0 && std::isfinite(o.smoothing_wavelength)))
    fail("smoothing_wavelength", o.smoothing_wavelength, "at least 0, finite; 0 is smoothing_fraction's");
  if (!(o.smoothing_fraction > 0 && std::isfinite(o.smoothing_fraction)))
    fail("smoothing_fraction", o.smoothing_fraction, "above 0, finite");
  if (o.handle_solved_rings < 0 || o.handle_solved_rings > 1000)
    fail("handle_solved_rings", o.handle_solved_rings, "0-1000");
  if (o.drag_end_cycles < 1 || o.drag_end_cycles > 100000)
    fail("drag_end_cycles", o.drag_end_cycles, "1-100000");
}

// RegionEditor's blend field: values beyond [-kBlendSlack, 1 + kBlendSlack] mark a nearly
// singular first system (decompose()).
constexpr double kBlendSlack = 0.5;

class RegionEditor::Impl {
 public:
  Impl(const TriMesh& mesh, const std::vector<char>& region, const std::vector<char>& handle, EditOptions o)
      : mesh_(mesh),
        opt_(std::move(o)),
        detail_(opt_.method, opt_.reconstruct, opt_.drag, opt_.drag_end, opt_.drag_end_cycles) {
    const int n = mesh.num_vertices();
    if (static_cast<int>(region.size()) != n || static_cast<int>(handle.size()) != n)
      throw InvalidInput("region and handle flags must have one entry per mesh vertex (" + std::to_string(n) +
                         ")");
    check_edit_options(opt_);
    // Out-of-range face indices crashed the adjacency below. Only what the editor indexes with is
    // checked: a model's band muted to its base may hold zero-area faces, and is edited.
    internal::check_face_indices(mesh.faces, n, "region editor's mesh");
    check_coordinates(mesh.vertices, "region editor's mesh");
    const auto t0 = Clock::now();
    in_region_.assign(n, 0);
    in_handle_.assign(n, 0);
    for (int i = 0; i < n; ++i) {
      if (!region[i]) continue;
      in_region_[i] = 1;
      if (handle[i]) {
        in_handle_[i] = 1;
        handle_.push_back(i);
      }
    }
    list_region();
    if (region_.empty()) throw InvalidInput("the region selects no vertex");
    if (handle_.empty()) throw InvalidInput("the handle selects no vertex of the region");
    if (handle_.size() == region_.size())
      throw InvalidInput("the handle is the whole region: nothing to blend");
    if (static_cast<int>(region_.size()) == n)
      throw InvalidInput("the region is the whole mesh: nothing is held fixed");
    const internal::Adjacency adj = internal::build_adjacency(n, mesh.faces);
    leave_out_floating_parts(adj);
    decompose(adj);
    // After the decomposition: the vertices that fill the corners are solved, over the base and
    // blend of the selection (the mesh itself there, s = 0), which they leave as they were.
    if (opt_.fill_region_corners && fill_corners(in_region_, mesh.faces)) list_region();
    decompose_seconds_ = seconds_since(t0);
    const auto t1 = Clock::now();
    encode(adj);
    encode_seconds_ = seconds_since(t1);
  }

  std::vector<Vec3> edited_base(const EditTransform& t) const { return blend_transform(base_, s_, t); }

  EditResult apply(const EditTransform& t) const {
    return finish(t, [&](const std::vector<Vec3>& sub_base, EditResult& res) {
      return detail_.solve(sub_base, res, t.is_rigid());
    });
  }

  // An exact edit by transform t whose region detail \p solve rebuilds over the region's base.
  template <class Solve>
  EditResult finish(const EditTransform& t, Solve&& solve) const {
    EditResult res;
    auto t0 = Clock::now();
    res.base_positions = edited_base(t);
    const std::vector<Vec3> sub_base = gather(res.base_positions);
    res.times.edit = seconds_since(t0);
    const std::vector<Vec3> sub = solve(sub_base, res);
    res.times.decompose = decompose_seconds_;
    res.times.encode = encode_seconds_;
    res.positions = mesh_.vertices;
    scatter(sub, res.positions);
    return res;
  }

  void begin_drag() {
    detail_.begin_drag(gather(edited_base(EditTransform{})));
    drag_positions_ = mesh_.vertices;
    drag_transform_ = EditTransform{};
    dragging_ = true;
  }

  const std::vector<Vec3>& update_drag(const EditTransform& t) {
    if (!dragging_) throw InvalidInput("update_drag() without begin_drag()");
    scatter(detail_.drag_step(gather(edited_base(t))), drag_positions_);
    drag_transform_ = t;
    return drag_positions_;
  }

  // The exact solve as EditOptions::drag_end says. (Warm-started exact solves from the finest
  // positions alone were measured to drift into folds over long drags; from the drag's per-level
  // state they did not on the bumpy cylinder; they end near the last preview, up to 2% of the
  // diagonal away from apply(), and are checked, with apply()'s clean start as the fallback.)
  EditResult end_drag() {
    if (!dragging_) throw InvalidInput("end_drag() without begin_drag()");
    // The drag stays on until the solve returns: a cancelled or failed end leaves it to be
    // ended (or dragged on) again.
    // A map that is not rigid is solved with the handle free (apply()), not from the drag's
    // state, whose handle was pinned.
    EditResult r = opt_.drag_end == EditOptions::DragEnd::CleanStart || !drag_transform_.is_rigid()
                       ? apply(drag_transform_)
                       : finish(drag_transform_, [&](const std::vector<Vec3>& sub_base, EditResult& res) {
                           return detail_.end_drag(sub_base, res);
                         });
    dragging_ = false;
    return r;
  }

  const TriMesh& mesh() const { return mesh_; }
  const std::vector<Vec3>& base() const { return base_; }
  const std::vector<double>& blend() const { return s_; }
  const std::vector<int>& region() const { return region_; }
  const std::vector<int>& handle() const { return handle_; }
  int left_out() const { return left_out_; }
  const DetailEncoding& encoding() const { return detail_.encoding(); }
  const std::vector<int>& sub_vertices() const { return sub_vertices_; }
  const EditOptions& options() const { return opt_; }
  double decompose_seconds() const { return decompose_seconds_; }
  double encode_seconds() const { return encode_seconds_; }
  bool dragging() const { return dragging_; }

 private:
  // The base: the thin-plate energy x^T L M^-1 L x over the region, the rest of the mesh held
  // (so the base is tangent-continuous with it), plus a pull w M (x - x0) of every region vertex
  // towards its own position. Pure fairing would shrink a limb to a thin neck (a tube's
  // thin-plate minimizer necks in) and make its whole thickness "detail"; with the pull it is a
  // low-pass filter, w / (w + k^4) for a mode of wavenumber k, that keeps the limb's shape and
  // removes the detail. The blend field: the same operator without the pull on the region minus
  // the handle, s = 1 held on the handle and 0 on the rest.
  void decompose(const internal::Adjacency& adj) {
    const int n = mesh_.num_vertices();
    const std::vector<Vec3>& x = mesh_.vertices;
    std::vector<int> region_id(n, -1), free_id(n, -1);
    std::vector<int> free;
    for (std::size_t k = 0; k < region_.size(); ++k) {
      const int i = region_[k];
      region_id[i] = static_cast<int>(k);
      if (!in_handle_[i]) {
        free_id[i] = static_cast<int>(free.size());
        free.push_back(i);
      }
    }

    // Clamped cotangent weights on the edges (a small floor keeps every edge connected, so the
    // systems stay definite on meshes with obtuse triangles), barycentric vertex areas.
    std::vector<double> w = internal::clamped_cotan_weights(x, mesh_.faces, adj);
    std::vector<double> area(n, 0.0);
    for (const Face& f : mesh_.faces) {
      const double a = triangle_area_normal(x[f[0]], x[f[1]], x[f[2]]).norm() / 2;
      for (int v : f) area[v] += a / 3;
    }
    double mean_w = 0.0, mean_a = 0.0;
    for (double v : w) mean_w += v;
    for (double a : area) mean_a += a;
    mean_w = w.empty() ? 1.0 : mean_w / w.size();
    mean_a /= n;
    for (double& v : w) v += 1e-6 * mean_w;
    for (double& a : area) a = std::max(a, 1e-9 * mean_a);
    const std::vector<char> on_boundary = internal::boundary_vertices(n, mesh_.faces);
    std::vector<double> diag(n, 0.0);
    for (int v = 0; v < n; ++v)
      for (int t = adj.neighbor_offsets[v]; t < adj.neighbor_offsets[v + 1]; ++t) diag[v] += w[t];
    // Filter response w / (w + k^4) for a mode of wavenumber k (Q ~ M Laplacian^2).
    std::vector<Vec3> region_points;
    for (int i : region_) region_points.push_back(x[i]);
    const double region_diagonal = bbox_diagonal(region_points);
    double wavelength = opt_.smoothing_wavelength;
    if (!(wavelength > 0)) wavelength = opt_.smoothing_fraction * region_diagonal;
    if (!(wavelength > 0) || !std::isfinite(wavelength))
      throw InvalidInput("the region has no extent to smooth over");
    const double pull = std::pow(2 * M_PI / wavelength, 4);
    // The open rim's vertices have no fairing rows of their own (assemble(): they would pull the
    // rim in), so only the pull holds them, and as the wavelength grows past the region's size
    // it lets the rim flare: a tube's end region moved 0.52 / 4.94 / 632 from the input at
    // smoothing 1 / 3 / 100 (a closed region 0.24 / 0.28 / 0.29). There the rim keeps the pull
    // of a wavelength of the region's diagonal.
    const double rim_pull =
        region_diagonal > 0 ? std::max(pull, std::pow(2 * M_PI / region_diagonal, 4)) : pull;
    double largest_area = 0.0, largest_coordinate = 0.0;
    for (int i : region_) {
      largest_area = std::max(largest_area, area[i]);
      largest_coordinate = std::max(largest_coordinate, x[i].cwiseAbs().maxCoeff());
    }
    // A tiny wavelength: the fairing's weights overflow (pull itself, or its products with the
    // areas and positions, which the system holds).
    if (!std::isfinite(rim_pull) ||
        !std::isfinite(rim_pull * largest_area * std::max(1.0, largest_coordinate))) {
      std::ostringstream m;
      m << "the smoothing wavelength " << wavelength << " is too small (the fairing's weights overflow)";
      throw InvalidInput(m.str());
    }

    // Rows of Q = L M^-1 L for the unknowns: Q_ij = sum_k L_ik L_kj / M_k over k in {i} and i's
    // neighbours; held columns j go to the right-hand side.
    // rim_rows: the rows of open-edge vertices too (see the blend field below).
    auto assemble = [&](const std::vector<int>& unknowns, const std::vector<int>& id, int cols,
                        const std::function<void(int, int, double, Eigen::MatrixXd&)>& held,
                        Eigen::MatrixXd& rhs, bool rim_rows) {
      const int m = static_cast<int>(unknowns.size());
      std::vector<Eigen::Triplet<double>> trip;
      trip.reserve(static_cast<std::size_t>(m) * 50);
      rhs = Eigen::MatrixXd::Zero(m, cols);
      auto add_row_k = [&](int r, int k, double lik) {
        if (on_boundary[k] && !rim_rows) return;  // open edges: no Laplacian term (it would pull the rim in)
        const double c = lik / area[k];
        auto add = [&](int j, double lkj) {
          if (id[j] >= 0)
            trip.emplace_back(r, id[j], c * lkj);
          else
            held(r, j, c * lkj, rhs);
        };
        add(k, diag[k]);
        for (int t = adj.neighbor_offsets[k]; t < adj.neighbor_offsets[k + 1]; ++t)
          add(adj.neighbors[t], -w[t]);
      };
      for (int r = 0; r < m; ++r) {
        const int i = unknowns[r];
        add_row_k(r, i, diag[i]);
        for (int t = adj.neighbor_offsets[i]; t < adj.neighbor_offsets[i + 1]; ++t)
          add_row_k(r, adj.neighbors[t], -w[t]);
      }
      return trip;
    };
    // may_fail: a singular system returns an empty matrix instead of throwing.
    auto solve = [](const std::vector<int>& unknowns, std::vector<Eigen::Triplet<double>>& trip,
                    const Eigen::MatrixXd& rhs, const char* what, bool may_fail) {
      const int m = static_cast<int>(unknowns.size());
      Eigen::SparseMatrix<double> Q(m, m);
      Q.setFromTriplets(trip.begin(), trip.end());
      // A vertex whose neighbours all lie on open edges has no Laplacian row (a mesh of triangles
      // that share no edge): CHOLMOD was handed an empty column and the process crashed.
      for (int r = 0; r < m; ++r)
        if (!(Q.coeff(r, r) > 0)) {
          if (may_fail) return Eigen::MatrixXd();
          throw InvalidInput(std::string("the region's ") + what + " system is singular at vertex " +
                             std::to_string(unknowns[r]) +
                             ": it and its neighbours lie on open edges, with no interior vertex to fair");
        }
      const internal::SerialOpenMp serial;
      Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt;
      llt.cholmod().print = 0;  // its failures are thrown; CHOLMOD printed them on stdout too
      llt.compute(Q);
      if (llt.info() != Eigen::Success) {
        if (may_fail) return Eigen::MatrixXd();
        throw SolverError(std::string("the region's ") + what + " system could not be factorized");
      }
      Eigen::MatrixXd sol = llt.solve(rhs);
      if (llt.info() != Eigen::Success || !sol.allFinite())
        throw SolverError(std::string("the region's ") + what + " solve failed");
      return sol;
    };

    Eigen::MatrixXd rhs;
    std::vector<Eigen::Triplet<double>> trip = assemble(
        region_, region_id, 3,
        [&](int r, int j, double v, Eigen::MatrixXd& b) { b.row(r) -= v * x[j].transpose(); }, rhs, false);
    for (int i : region_) {
      const int r = region_id[i];
      const double p = on_boundary[i] ? rim_pull : pull;
      trip.emplace_back(r, r, p * area[i]);
      rhs.row(r) += p * area[i] * x[i].transpose();
    }
    const Eigen::MatrixXd faired = solve(region_, trip, rhs, "fairing", false);
    base_ = x;
    for (std::size_t k = 0; k < region_.size(); ++k)
      base_[region_[k]] = faired.row(static_cast<Eigen::Index>(k)).transpose();

    auto handle_held = [&](int r, int j, double v, Eigen::MatrixXd& b) {
      if (in_handle_[j]) b(r, 0) -= v;
    };
    trip = assemble(free, free_id, 1, handle_held, rhs, false);
    Eigen::MatrixXd blend = solve(free, trip, rhs, "blend field", true);
    // A nearly singular system can factorize at a rounding-level pivot and give finite values far
    // out of [0, 1] (a review's fan of two rim vertices off one interior vertex: -8.7e5 to 1.8e6
    // in 16 of 200 jittered grids). A bi-harmonic blend between 0 and 1 overshoots far less.
    if (blend.size() > 0 && (blend.minCoeff() < -kBlendSlack || blend.maxCoeff() > 1 + kBlendSlack))
      blend.resize(0, 0);
    if (blend.size() == 0) {
      // Without the pull, open edges can leave the blend undetermined: a free vertex whose
      // neighbours all lie on them (CGAL's elephant-with-holes), or a strip of rim vertices that
      // no interior row ties to a held one (its holes, ALSTOM_TEST4). With the rim's rows the
      // system is definite wherever every connected part touches a held vertex
      // (leave_out_floating_parts()): s^T Q s = |M^-1/2 L s|^2 vanishes only for s constant on each part.
      trip = assemble(free, free_id, 1, handle_held, rhs, true);
      blend = solve(free, trip, rhs, "blend field", false);
    }
    s_.assign(n, 0.0);
    for (int i : handle_) s_[i] = 1.0;
    for (std::size_t k = 0; k < free.size(); ++k) s_[free[k]] = blend(static_cast<Eigen::Index>(k), 0);
  }

  // region_ from in_region_.
  void list_region() {
    region_.clear();
    for (int i = 0; i < static_cast<int>(in_region_.size()); ++i)
      if (in_region_[i]) region_.push_back(i);
  }

  // EditOptions::fill_region_corners: the outside vertices of the faces whose only region vertex
  // has two or more such faces join the region (once: a joined vertex keeps its base and its
  // displacement, zero, so its own faces with two outside vertices keep their volumes where it
  // stands); the selection as it was if that would take in the whole mesh. Whether any joined.
  static bool fill_corners(std::vector<char>& in_region, const std::vector<Face>& faces) {
    const std::vector<char> selected = in_region;
    // Per face, its only region vertex (-1 if it has none or several); per vertex, how many.
    auto only = [&](const Face& f) {
      const int inside = selected[f[0]] + selected[f[1]] + selected[f[2]];
      if (inside != 1) return -1;
      return selected[f[0]] ? f[0] : selected[f[1]] ? f[1] : f[2];
    };
    std::vector<int> lone(selected.size(), 0);
    for (const Face& f : faces)
      if (const int v = only(f); v >= 0) ++lone[v];
    for (const Face& f : faces)
      if (const int v = only(f); v >= 0 && lone[v] >= 2)
        for (int u : f) in_region[u] = 1;
    if (std::all_of(in_region.begin(), in_region.end(), [](char c) { return c != 0; })) in_region = selected;
    return in_region != selected;
  }

  // The connected parts of the region minus the handle that touch neither the handle nor the rest
  // of the mesh (a part of a multi-part model, or a scan's loose fragment, that the selection takes
  // in whole away from the handle) leave the region: their blend, and so their edit, would be
  // undetermined, and connected to nothing that moves, they stay where they are. The region left
  // must still hold a vertex to blend.
  void leave_out_floating_parts(const internal::Adjacency& adj) {
    std::vector<char> free(in_region_.size(), 0);
    for (int v : region_) free[v] = !in_handle_[v];
    const std::vector<char> floating =
        internal::floating_parts(adj.neighbor_offsets.data(), adj.neighbors.data(), free);
    for (std::size_t v = 0; v < floating.size(); ++v)
      if (floating[v]) in_region_[v] = 0, ++left_out_;
    if (left_out_ == 0) return;
    list_region();
    if (handle_.size() == region_.size())
      throw InvalidInput(
          "the handle is the whole region once the " + std::to_string(left_out_) +
          " vertices of its parts connected to neither the handle nor the rest of the mesh are "
          "left out: nothing to blend");
  }

  // The region's prisms: every face with a region vertex. Its vertices outside the region have
  // zero displacement (the base is the mesh there) and are pinned.
  void encode(const internal::Adjacency& adj) {
    const int n = mesh_.num_vertices();
    std::vector<int> sub_id(n, -1);
    TriMesh detail, base;
    for (const Face& f : mesh_.faces) {
      if (!in_region_[f[0]] && !in_region_[f[1]] && !in_region_[f[2]]) continue;
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
    base.faces = detail.faces;
    for (int v : sub_vertices_) {
      detail.vertices.push_back(mesh_.vertices[v]);
      base.vertices.push_back(base_[v]);
    }
    if (detail.faces.empty()) throw InvalidInput("the region has no face");
    DetailEncoding& enc = detail_.encoding();
    enc = encode_detail(detail, base, opt_.encode);
    // The rest of the mesh, fixed, for the solver's fold check: a region that folds into its
    // surroundings (a free vertex at the border pushed through a neighbouring triangle) makes new
    // pairs that the detail's own triangles do not show. Its vertices shared with the detail are
    // the detail's (indices below sub_vertices_.size()), so that triangles sharing one count as
    // adjacent.
    detail_.set_intersection_context(context_around(mesh_.faces, in_region_, sub_vertices_, mesh_.vertices));
    // The handle moves rigidly, and so does its detail: its vertices farther than a few rings
    // from the blended part are placed by the (then exact) vector rule, not solved. Exact only if
    // the base frame moves rigidly too: the vertex's base point must lie on a base face whose
    // vertices (and so their interpolated normals) are at least two rings inside the handle. A
    // thick detail layer projects farther than that, onto the blended part.
    // Around a vertex whose base frame is not rigid, the same rings as at the handle's border are
    // solved too, so that no solved vertex is left among pinned ones with more prisms than it can
    // satisfy.
    const int rings = opt_.handle_solved_rings;
    std::vector<char> outside_handle(n);
    for (int i = 0; i < n; ++i) outside_handle[i] = !in_handle_[i];
    // Capped at 2 at least: the rigid-frame test below asks for depth 2 whatever the rings.
    const std::vector<int> depth = internal::ring_distance(adj, outside_handle, std::max(rings + 1, 2));
    std::vector<char> nonrigid(n, 0);
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k) {
      const int v = sub_vertices_[k];
      if (!in_region_[v] || depth[v] <= rings) continue;
      for (int c : enc.base_faces[enc.base_points[k].face])
        if (depth[sub_vertices_[c]] < 2) nonrigid[v] = 1;
    }
    const std::vector<int> near_nonrigid = internal::ring_distance(adj, nonrigid, rings + 1);
    enc.pinned.resize(sub_vertices_.size());
    std::vector<char> outside(sub_vertices_.size());
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k) {
      const int v = sub_vertices_[k];
      enc.pinned[k] = !in_region_[v] || (depth[v] > rings && near_nonrigid[v] > rings);
      outside[k] = !in_region_[v];
    }
    detail_.set_nonrigid_pins(std::move(outside));
  }

  std::vector<Vec3> gather(const std::vector<Vec3>& whole) const {
    std::vector<Vec3> out(sub_vertices_.size());
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k) out[k] = whole[sub_vertices_[k]];
    return out;
  }

  // Region vertices take the solution; all others keep the mesh's positions exactly.
  void scatter(const std::vector<Vec3>& sub, std::vector<Vec3>& whole) const {
    for (std::size_t k = 0; k < sub_vertices_.size(); ++k)
      if (in_region_[sub_vertices_[k]]) whole[sub_vertices_[k]] = sub[k];
  }

  TriMesh mesh_;
  EditOptions opt_;
  internal::DetailSolve detail_;
  std::vector<char> in_region_, in_handle_;
  std::vector<int> region_, handle_;
  int left_out_ = 0;  // vertices of the selection left out (leave_out_floating_parts())
  std::vector<Vec3> base_;
  std::vector<double> s_;
  std::vector<int> sub_vertices_;
  double decompose_seconds_ = 0.0, encode_seconds_ = 0.0;
  bool dragging_ = false;
  std::vector<Vec3> drag_positions_;
  EditTransform drag_transform_;
};

RegionEditor::RegionEditor(const TriMesh& mesh, const std::vector<char>& region,
                           const std::vector<char>& handle, EditOptions options)
    : impl_(std::make_unique<Impl>(mesh, region, handle, std::move(options))) {}
RegionEditor::~RegionEditor() = default;
RegionEditor::RegionEditor(RegionEditor&&) noexcept = default;
RegionEditor& RegionEditor::operator=(RegionEditor&&) noexcept = default;
const TriMesh& RegionEditor::mesh() const {
  return impl_->mesh();
}
const std::vector<Vec3>& RegionEditor::base() const {
  return impl_->base();
}
const std::vector<double>& RegionEditor::blend() const {
  return impl_->blend();
}
const std::vector<int>& RegionEditor::region_vertices() const {
  return impl_->region();
}
const std::vector<int>& RegionEditor::handle_vertices() const {
  return impl_->handle();
}
int RegionEditor::left_out_vertices() const {
  return impl_->left_out();
}
int RegionEditor::region_faces() const {
  return static_cast<int>(impl_->encoding().detail_faces.size());
}
const DetailEncoding& RegionEditor::encoding() const {
  return impl_->encoding();
}
const std::vector<int>& RegionEditor::region_submesh_vertices() const {
  return impl_->sub_vertices();
}
const EditOptions& RegionEditor::options() const {
  return impl_->options();
}
double RegionEditor::decompose_seconds() const {
  return impl_->decompose_seconds();
}
double RegionEditor::encode_seconds() const {
  return impl_->encode_seconds();
}
std::vector<Vec3> RegionEditor::edited_base(const EditTransform& t) const {
  return impl_->edited_base(t);
}
EditResult RegionEditor::apply(const EditTransform& t) const {
  return impl_->apply(t);
}
void RegionEditor::begin_drag() {
  impl_->begin_drag();
}
const std::vector<Vec3>& RegionEditor::update_drag(const EditTransform& t) {
  return impl_->update_drag(t);
}
EditResult RegionEditor::end_drag() {
  return impl_->end_drag();
}
bool RegionEditor::dragging() const {
  return impl_->dragging();
}

}  // namespace strata
