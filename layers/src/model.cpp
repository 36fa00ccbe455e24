#include "strata/layers/model.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>

#include "options_io.h"
#include "strata/cage_editing.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/mesh_io.h"
#include "strata/mesh_processing.h"
#include "strata/version.h"

namespace strata::layers {
namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

bool same_bits(const Vec3& a, const Vec3& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0;
}

// Mean length of the face edges (each edge once per face it bounds); faces of any corner count.
template <class Faces>
double mean_edge_length(const std::vector<Vec3>& x, const Faces& faces) {
  double sum = 0.0;
  long long n = 0;
  for (const auto& f : faces)
    for (std::size_t c = 0; c < f.size(); ++c) {
      sum += (x[f[c]] - x[f[(c + 1) % f.size()]]).norm();
      ++n;
    }
  return n > 0 ? sum / n : 0.0;
}

EditOptions edit_options(const ModelOptions& o) {
  EditOptions e;
  e.method = o.method;
  e.smoothing_fraction = o.smoothing_fraction;
  e.handle_solved_rings = o.handle_solved_rings;
  e.encode = o.encode;
  e.reconstruct = o.reconstruct;
  return e;
}

// The detail vertices of a band whose base frame depends on each base vertex, as lists per
// detail vertex: over a limit surface the control points of its limit stencil; over a triangle
// base the corners of its base face and their neighbours (the corners' vertex normals, which the
// frame interpolates, depend on their one-rings).
struct Dependencies {
  std::vector<int> offsets;  // per detail vertex
  std::vector<int> base;     // base vertex ids
};

Dependencies dependencies(const DetailEncoding& e) {
  const int n = e.num_detail_vertices();
  std::vector<std::vector<int>> lists(n);
  if (e.over_limit_surface()) {
    const SubdivSurface surface = limit_surface_for(e, std::vector<Vec3>(e.base_num_vertices, Vec3::Zero()));
    tbb::parallel_for(0, n, [&](int i) {
      const SubdivSurface::Stencil st = surface.stencil(e.limit_points[i]);
      for (std::size_t k = 0; k < st.indices.size(); ++k)
        if (st.position[k] != 0.0 || st.du[k] != 0.0 || st.dv[k] != 0.0) lists[i].push_back(st.indices[k]);
    });
  } else {
    std::vector<std::vector<int>> ring(e.base_num_vertices);
    for (const Face& f : e.base_faces)
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) ring[f[c]].push_back(f[d]);
    for (auto& r : ring) {
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    }
    tbb::parallel_for(0, n, [&](int i) {
      const Face& f = e.base_faces[e.base_points[i].face];
      for (int c = 0; c < 3; ++c) lists[i].insert(lists[i].end(), ring[f[c]].begin(), ring[f[c]].end());
      std::sort(lists[i].begin(), lists[i].end());
      lists[i].erase(std::unique(lists[i].begin(), lists[i].end()), lists[i].end());
    });
  }
  Dependencies d;
  d.offsets.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) d.offsets[i + 1] = d.offsets[i] + static_cast<int>(lists[i].size());
  d.base.reserve(d.offsets[n]);
  for (const auto& l : lists) d.base.insert(d.base.end(), l.begin(), l.end());
  return d;
}

void check_band_index(int k, int n, bool allow_cage) {
  if (k < (allow_cage ? 0 : 1) || k >= n)
    throw InvalidInput("band " + std::to_string(k) + " out of range (the model has bands " +
                       std::string(allow_cage ? "0" : "1") + " .. " + std::to_string(n - 1) +
                       (allow_cage ? "" : "; band 0, the cage, has no amplitude") + ")");
}

// One band's solve over a changed base: the faces with a vertex to solve, restricted from the
// band's encoding, the other vertices of those faces pinned at their current positions.
struct PartSolve {
  DetailEncoding part;
  std::vector<int> vertices;  // part vertex -> band vertex
  std::unique_ptr<VolumeReconstructor> reconstructor;
  std::vector<Vec3> current;  // part positions (pinned ones fixed), warm start of drag steps
  DragState drag;             // every multigrid level's last drag solution
  // Vertices to solve that lie in no face (a scan's unreferenced points): no prism holds them, so
  // they follow their base point by displacement vectors, over the band's whole encoding (held
  // only if there are any), in the exact solve only: a drag's previews leave them where they are
  // (a pass over the whole band per step), and its end is the exact edit. The part above has only
  // vertices of faces: they stayed where they were while their base moved away.
  std::vector<int> loose;
  std::vector<Vec3> loose_positions;
  std::optional<DetailEncoding> whole;

  PartSolve(const Band& band, const std::vector<char>& solve, const ModelOptions& o) {
    std::vector<int> faces;
    std::vector<char> in_face(band.mesh.vertices.size(), 0);
    for (int j = 0; j < band.mesh.num_faces(); ++j) {
      const Face& f = band.mesh.faces[j];
      in_face[f[0]] = in_face[f[1]] = in_face[f[2]] = 1;
      if (solve[f[0]] || solve[f[1]] || solve[f[2]]) faces.push_back(j);
    }
    for (std::size_t i = 0; i < in_face.size(); ++i)
      if (solve[i] && !in_face[i]) loose.push_back(static_cast<int>(i));
    if (!loose.empty()) {
      whole = band.encoding;
      loose_positions.resize(loose.size());
      for (std::size_t l = 0; l < loose.size(); ++l) loose_positions[l] = band.mesh.vertices[loose[l]];
    }
    if (faces.empty()) return;  // loose vertices only
    part = restrict_encoding(band.encoding, faces, vertices);
    part.pinned.resize(vertices.size());
    current.resize(vertices.size());
    for (std::size_t v = 0; v < vertices.size(); ++v) {
      part.pinned[v] = !solve[vertices[v]];
      current[v] = band.mesh.vertices[vertices[v]];
    }
    if (o.method == EditOptions::Method::Volumes) {
      reconstructor = std::make_unique<VolumeReconstructor>(part, o.reconstruct);
      // The rest of the band, for the fold check: where it stands now (at rest, following its
      // base rigidly, or where earlier edits left it) and where it lay at rest, as the part.
      reconstructor->set_intersection_context(
          context_around(band.mesh.faces, solve, vertices, band.mesh.vertices, &band.encoding.detail_rest));
    }
  }

  // The exact solve from the clean start (volumes) or the vectors' placement.
  BandRebuild solve_exact(const std::vector<Vec3>& base, double amplitude) {
    BandRebuild r;
    place_loose(base, amplitude);
    if (vertices.empty()) return r;
    const BaseFrames frames = evaluate_base_frames(part, base);
    std::vector<Vec3> x;
    if (reconstructor) {
      ReconstructRequest req;
      req.amplitude = amplitude;
      req.pinned_positions = &current;
      ReconstructResult res = reconstructor->reconstruct(frames, req);
      x = std::move(res.positions);
      r.stats = std::move(res.stats);
    } else {
      x = reconstruct_vectors(part, frames, amplitude);
      for (std::size_t v = 0; v < x.size(); ++v)
        if (part.pinned[v]) x[v] = current[v];
    }
    r.solved_prisms = static_cast<int>(part.detail_faces.size());
    r.volume = volume_metrics(part, frames, x, amplitude);
    current = std::move(x);
    return r;
  }

  void place_loose(const std::vector<Vec3>& base, double amplitude) {
    if (loose.empty()) return;
    const std::vector<Vec3> v = reconstruct_vectors(*whole, evaluate_base_frames(*whole, base), amplitude);
    for (std::size_t l = 0; l < loose.size(); ++l) loose_positions[l] = v[loose[l]];
  }

  // Starts a drag from the current positions over \p base, the band's base before the drag.
  void begin_drag(const std::vector<Vec3>& base) {
    if (reconstructor) drag.reset(evaluate_base_frames(part, base), current);
  }

  // One interactive step (section 5): each multigrid level goes on from its own last solution
  // carried along with the base frames (DragState), volumes on the coarse levels only, with the
  // editors' step budget (EditOptions::drag).
  void solve_drag(const std::vector<Vec3>& base, double amplitude) {
    if (vertices.empty()) return;
    const BaseFrames frames = evaluate_base_frames(part, base);
    if (reconstructor) {
      ReconstructRequest req;
      req.amplitude = amplitude;
      req.pinned_positions = &current;
      current = reconstructor->drag_step(frames, drag, EditOptions().drag, req).positions;
    } else {
      std::vector<Vec3> x = reconstruct_vectors(part, frames, amplitude);
      for (std::size_t v = 0; v < x.size(); ++v)
        if (!part.pinned[v]) current[v] = x[v];
    }
  }

  void scatter(std::vector<Vec3>& band_positions) const {
    for (std::size_t v = 0; v < vertices.size(); ++v)
      if (!part.pinned[v]) band_positions[vertices[v]] = current[v];
    for (std::size_t l = 0; l < loose.size(); ++l) band_positions[loose[l]] = loose_positions[l];
  }
};

}  // namespace

class LayeredModel::Impl {
 public:
  std::vector<Band> bands;
  ModelOptions options;
  std::vector<std::string> history;
  // Caches, rebuilt on demand (not copied): each band's dependency lists.
  mutable std::vector<std::optional<Dependencies>> deps;

  // Drag state.
  struct Drag {
    int band = 0;
    EditStep step;
    std::vector<Band> saved;
    std::vector<double> cage_blend;                 // band 0
    std::unique_ptr<RegionEditor> editor;           // band k >= 1
    std::vector<std::unique_ptr<PartSolve>> finer;  // index j - band - 1
    std::vector<std::vector<Vec3>> finer_base_rest;
  };
  std::unique_ptr<Drag> drag;

  Impl() = default;
  // A copy is the model's committed state: during a drag, the state before it (a preview is no
  // edit, and the drag's solver state stays with the original).
  Impl(const Impl& o) : bands(o.drag ? o.drag->saved : o.bands), options(o.options), history(o.history) {}

  int n() const { return static_cast<int>(bands.size()); }

  const std::vector<Vec3>& points(int k) const {
    return k == 0 ? bands[0].cage.vertices : bands[k].mesh.vertices;
  }

  const Dependencies& deps_of(int k) const {
    if (deps.size() != bands.size()) deps.assign(bands.size(), std::nullopt);
    if (!deps[k]) deps[k] = dependencies(bands[k].encoding);
    return *deps[k];
  }
  void invalidate(int k) {
    if (deps.size() == bands.size()) deps[k].reset();
  }

  // Flags of band k's vertices whose frame depends on a flagged base vertex.
  std::vector<char> reached(int k, const std::vector<char>& base_flags) const {
    const Dependencies& d = deps_of(k);
    const int nv = bands[k].mesh.num_vertices();
    std::vector<char> out(nv, 0);
    tbb::parallel_for(0, nv, [&](int i) {
      for (int t = d.offsets[i]; t < d.offsets[i + 1]; ++t)
        if (base_flags[d.base[t]]) {
          out[i] = 1;
          return;
        }
    });
    return out;
  }

  // How a band's base changed: its old positions, and optionally the base vertices that moved
  // by exactly one rigid map (an edit's handle, s = 1), whose dependants follow that map exactly.
  struct BaseChange {
    std::vector<Vec3> old;
    std::vector<char> rigid;  // empty: none
    const EditTransform* map = nullptr;
  };

  // Rebuilds band k after its base (band k-1) changed (\p change), or after its amplitude changed
  // (\p change null: every vertex is affected). A vertex whose base frame cannot have changed keeps
  // its position; one whose base and amplitude are back at rest takes its rest position (the exact
  // solution of its prisms); one whose base moved rigidly follows the map (volumes and the
  // regularization are invariant under rigid maps); the others are solved, with their neighbours
  // pinned. Returns how band k changed, for band k+1; nothing if it did not.
  std::optional<BaseChange> rebuild(int k, const BaseChange* change, CascadeReport& report) {
    const auto t0 = Clock::now();
    Band& b = bands[k];
    const std::vector<Vec3>& base = points(k - 1);
    const int nb = static_cast<int>(base.size()), nv = b.mesh.num_vertices();
    std::vector<char> moved(nb, 0), at_rest(nb, 0);
    // Back at rest up to rounding (back_at_rest()): an edit and its inverse (a rotation by s a,
    // then by -s a) bring the cage back only to the last bits, and the rest position is then the
    // exact solution to within as much, where a solve from the clean start lands elsewhere.
    const double scale = bbox_diagonal(b.base_rest);
    for (int v = 0; v < nb; ++v) {
      moved[v] = !change || !same_bits(base[v], change->old[v]);
      at_rest[v] = back_at_rest(base[v], b.base_rest[v], scale);
    }
    const bool rigid_base = change && change->map && !change->rigid.empty();
    std::vector<char> affected = reached(k, moved);
    const Dependencies& d = deps_of(k);
    std::vector<char> solve(nv, 0), rigid(rigid_base ? nv : 0, 0);
    BandRebuild r;
    r.band = k;
    BaseChange out;
    out.old = b.mesh.vertices;
    bool changed = false;
    for (int i = 0; i < nv; ++i) {
      if (!affected[i]) continue;
      bool rest = b.amplitude == 1.0, follows = rigid_base;
      for (int t = d.offsets[i]; t < d.offsets[i + 1]; ++t) {
        rest = rest && at_rest[d.base[t]];
        follows = follows && change->rigid[d.base[t]];
      }
      if (rest) {
        changed |= !same_bits(b.mesh.vertices[i], b.encoding.detail_rest[i]);
        b.mesh.vertices[i] = b.encoding.detail_rest[i];
        ++r.rest_vertices;
      } else if (follows) {
        b.mesh.vertices[i] = change->map->apply(b.mesh.vertices[i]);
        rigid[i] = 1;
        ++r.rigid_vertices;
        changed = true;
      } else {
        solve[i] = 1;
        ++r.solved_vertices;
      }
    }
    if (rigid_base && r.solved_vertices > 0) {
      // Rigidly moved vertices next to solved ones are solved too (handle_solved_rings rings), so
      // that the solved part is not squeezed between two pinned borders.
      for (int ring = 0; ring < options.handle_solved_rings; ++ring) {
        std::vector<char> grow = solve;
        for (const Face& f : b.mesh.faces)
          if (solve[f[0]] || solve[f[1]] || solve[f[2]])
            for (int c = 0; c < 3; ++c)
              if (rigid[f[c]]) {
                grow[f[c]] = 1;
                rigid[f[c]] = 0;
                b.mesh.vertices[f[c]] = out.old[f[c]];
                --r.rigid_vertices;
                ++r.solved_vertices;
              }
        solve.swap(grow);
      }
    }
    if (r.solved_vertices > 0) {
      PartSolve part(b, solve, options);
      BandRebuild s = part.solve_exact(base, b.amplitude);
      r.solved_prisms = s.solved_prisms;
      r.volume = s.volume;
      r.stats = std::move(s.stats);
      part.scatter(b.mesh.vertices);
      changed = true;
    }
    r.seconds = seconds_since(t0);
    report.rebuilt.push_back(std::move(r));
    if (!changed) return std::nullopt;
    if (rigid_base) {
      out.rigid = std::move(rigid);
      out.map = change->map;
    }
    return out;
  }

  // Rebuilds bands first .. N-1 in order, band first's base having changed by \p change.
  void cascade(int first, BaseChange change, CascadeReport& report) {
    for (int k = first; k < n(); ++k) {
      std::optional<BaseChange> next = rebuild(k, &change, report);
      if (!next) break;  // nothing moved: the finer bands keep their positions
      change = std::move(*next);
    }
  }

  // Re-encodes band k (k >= 1) at its current positions over band k-1's current surface.
  void reencode(int k) {
    Band& b = bands[k];
    if (k == 1) {
      const SubdivSurface surface(bands[0].cage, bands[0].tags, bands[0].subdiv);
      b.encoding = encode_detail(b.mesh, surface, options.projection);
    } else {
      b.encoding = encode_detail(b.mesh, bands[k - 1].mesh, options.encode);
    }
    b.base_rest = points(k - 1);
    b.amplitude = 1.0;
    invalidate(k);
  }

  std::vector<char> selection_flags(int k, const Selection& region, const Selection& handle,
                                    std::vector<char>& handle_flags) const {
    std::vector<char> r = select_vertices(points(k), region);
    handle_flags = select_vertices(points(k), handle);
    return r;
  }
};

LayeredModel::LayeredModel() : impl_(std::make_unique<Impl>()) {}
LayeredModel::~LayeredModel() = default;
LayeredModel::LayeredModel(const LayeredModel& o) : impl_(std::make_unique<Impl>(*o.impl_)) {}
LayeredModel& LayeredModel::operator=(const LayeredModel& o) {
  if (this != &o) impl_ = std::make_unique<Impl>(*o.impl_);
  return *this;
}
LayeredModel::LayeredModel(LayeredModel&&) noexcept = default;
LayeredModel& LayeredModel::operator=(LayeredModel&&) noexcept = default;

int LayeredModel::num_bands() const {
  return impl_->n();
}
void LayeredModel::set_attributes(int k, MeshAttributes attributes) {
  if (impl_->drag) throw InvalidInput("set_attributes() during a drag: end or cancel the drag first");
  if (k < 1 || k >= impl_->n())
    throw InvalidInput("band " + std::to_string(k) + " out of range (vertex attributes go on bands 1 .. " +
                       std::to_string(impl_->n() - 1) + "; band 0 is the cage)");
  Band& b = impl_->bands[k];
  check_mesh_attributes(attributes, b.mesh, "band " + std::to_string(k));
  b.attributes = std::move(attributes);
}

const Band& LayeredModel::band(int k) const {
  check_band_index(k, impl_->n(), true);
  return impl_->bands[k];
}
const std::vector<Vec3>& LayeredModel::band_points(int k) const {
  check_band_index(k, impl_->n(), true);
  return impl_->points(k);
}
const ModelOptions& LayeredModel::options() const {
  return impl_->options;
}
void check_model_options(const ModelOptions& options) {
  // The ranges the .strata reader takes, so that a model written with them reads back.
  try {
    check_reconstruct_options(options.reconstruct);
    check_encode_options(options.encode);
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("the model's ") + e.what());
  }
  if (options.method != EditOptions::Method::Volumes && options.method != EditOptions::Method::Vectors)
    throw InvalidInput("the model's method is neither volumes nor vectors");
  if (!(options.smoothing_fraction >= 1e-3 && options.smoothing_fraction <= 100))
    throw InvalidInput("the model's smoothing_fraction must be within 0.001-100");
  // A billion rings made a band-0 edit loop for hours.
  if (options.handle_solved_rings < 0 || options.handle_solved_rings > 1000)
    throw InvalidInput("the model's handle_solved_rings must be within 0-1000");
  const ProjectOptions& po = options.projection;
  if (po.seed_resolution < 1 || po.seed_resolution > 64 || po.max_iterations < 1 ||
      po.max_iterations > 10000 || !(po.orthogonality_tolerance > 0 && po.orthogonality_tolerance <= 1) ||
      !(po.seam_tolerance >= po.orthogonality_tolerance && po.seam_tolerance <= 1))
    throw InvalidInput(
        "the model's projection options are out of range (seed_resolution 1-64, max_iterations 1-10000, "
        "0 < orthogonality_tolerance <= seam_tolerance <= 1)");
  // The file's own ranges: infinite tolerances (written as null) and counts above 2^30 passed
  // the checks above and made a file the reader refused.
  internal::check_options_round_trip(options);
}

void LayeredModel::set_options(const ModelOptions& options) {
  if (impl_->drag) throw InvalidInput("set_options() during a drag");
  check_model_options(options);
  impl_->options = options;
  impl_->options.reconstruct.progress = nullptr;
  impl_->options.reconstruct.cancel = nullptr;
}
const std::vector<std::string>& LayeredModel::history() const {
  return impl_->history;
}

TriMesh LayeredModel::band_mesh(int k, int resolution) const {
  check_band_index(k, impl_->n(), true);
  if (k > 0) return impl_->bands[k].mesh;
  const Band& b = impl_->bands[0];
  return SubdivSurface(b.cage, b.tags, b.subdiv).tessellate(resolution).mesh;
}

DetailMagnitude LayeredModel::detail_magnitude(int k) const {
  check_band_index(k, impl_->n(), true);
  const Band& b = impl_->bands[k];
  DetailMagnitude m;
  if (k == 0) {
    m.mean_edge_length = mean_edge_length(b.cage.vertices, b.cage.faces);
    return m;
  }
  m.mean_edge_length = mean_edge_length(b.mesh.vertices, b.mesh.faces);
  const DetailEncoding& e = b.encoding;
  double sum = 0.0;
  for (int i = 0; i < e.num_detail_vertices(); ++i) {
    const double d2 = e.normal_offsets[i] * e.normal_offsets[i] + e.tangential_offsets[i].squaredNorm();
    sum += d2;
    m.max = std::max(m.max, std::sqrt(d2));
  }
  m.rms = e.num_detail_vertices() > 0 ? std::sqrt(sum / e.num_detail_vertices()) : 0.0;
  return m;
}

namespace {

// \p scan with its coincident vertices joined (weld_vertices()), for the coarse bands: a scan whose
// parts share vertex positions but not vertices (seams cut into slabs, a triangle soup) was
// smoothed, decimated and fitted as separate sheets, and an edit opened its seams (the camel in
// 4 slabs: 0.222 apart after the neck bend; a review, thirty-eighth session). The scan itself
// stays the finest band. The scan as it is if nothing coincides, or if joining makes it invalid
// (an edge of more than two faces: sheets that touch along a line).
TriMesh welded_for_bands(const TriMesh& scan) {
  TriMesh w = weld_vertices(scan);
  if (w.vertices.size() == scan.vertices.size()) return scan;
  try {
    validate_mesh(w, "the welded scan");
  } catch (const InvalidInput&) {
    return scan;
  }
  return w;
}

}  // namespace

LayeredModel LayeredModel::build(const TriMesh& scan, const BuildOptions& o) {
  const auto t0 = Clock::now();
  validate_mesh(scan, "scan");
  check_extent(scan.vertices, scan.faces, "scan");
  if (o.bands < 2 || o.bands > 8)
    throw InvalidInput("build: bands must be 2 to 8, not " + std::to_string(o.bands));
  if (o.band_smoothing_steps < 0 || o.band_smoothing_steps > 1000)
    throw InvalidInput("build: band_smoothing_steps must be 0 to 1000, not " +
                       std::to_string(o.band_smoothing_steps));
  check_model_options(o.model);
  // The file format's bound on counts: a larger budget built a model that did not read back. (The
  // cage's own ceiling, SubdivSurface::max_refined_faces_ceiling(), is lower: below, with the
  // cage's other fit options.)
  if (o.cage.subdiv.max_refined_faces > (1LL << 30))
    throw InvalidInput("build: the cage's max_refined_faces must be at most 2^30, got " +
                       std::to_string(o.cage.subdiv.max_refined_faces));
  auto progress = [&](const std::string& phase, double f) {
    if (o.progress) o.progress(phase, f);
  };
  const int nb = o.bands;
  const int scan_faces = scan.num_faces();
  const int cage_faces = default_cage_faces(o.cage, scan_faces);
  if (cage_faces >= scan_faces)
    throw InvalidInput("build: the scan has " + std::to_string(scan_faces) +
                       " faces, not more than the cage's " + std::to_string(cage_faces));
  // The cage's fit options, checked before the bands are built (fit_cage() checks them after).
  CageFitOptions co = o.cage;
  co.faces = cage_faces;
  try {
    check_cage_fit_options(co, scan_faces);
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("build: ") + e.what());
  }
  LayeredModel model;
  Impl& m = *model.impl_;
  m.options = o.model;
  m.options.reconstruct.progress = nullptr;
  m.options.reconstruct.cancel = nullptr;
  m.bands.resize(nb);
  m.bands[nb - 1].mesh = scan;
  // Intermediate bands, finest first, each decimated from the smoothed next finer band.
  TriMesh finer = welded_for_bands(scan);
  for (int k = nb - 2; k >= 1; --k) {
    progress("bands", static_cast<double>(nb - 1 - k) / nb);
    const double t = static_cast<double>(k) / (nb - 1);
    const int faces = std::max(cage_faces + 1,
                               static_cast<int>(std::lround(
                                   cage_faces * std::pow(static_cast<double>(scan_faces) / cage_faces, t))));
    TriMesh smoothed{taubin_smooth(finer, o.band_smoothing_steps), finer.faces};
    TriMesh band = decimate_mesh(smoothed, std::min(faces, finer.num_faces()));
    band.vertices = taubin_smooth(band, o.band_smoothing_steps);
    try {
      validate_mesh(band, "band " + std::to_string(k));
    } catch (const InvalidInput& e) {
      throw SolverError(std::string("build: the decimated band is not a valid mesh: ") + e.what());
    }
    m.bands[k].mesh = band;
    finer = std::move(band);
  }
  // Band 0: a cage fitted to band 1 (the smoothest triangle band).
  progress("cage", 0.5);
  const CageFit fit = fit_cage(m.bands[1].mesh, co);
  m.bands[0].cage = fit.cage;
  m.bands[0].subdiv = co.subdiv;
  m.bands[0].subdiv.scheme = SubdivScheme::Loop;
  // Encodings, coarsest first.
  for (int k = 1; k < nb; ++k) {
    progress("encode", 0.6 + 0.4 * k / nb);
    m.reencode(k);
  }
  progress("done", 1.0);
  json h = {{"op", "build"},
            {"strata", version()},
            {"bands", nb},
            {"scan_vertices", scan.num_vertices()},
            {"scan_faces", scan_faces},
            {"cage_faces", fit.cage.num_faces()},
            {"cage_fit_rms", fit.rms_error},
            {"cage_fit_max", fit.max_error},
            {"seconds", seconds_since(t0)}};
  m.history.push_back(h.dump());
  return model;
}

namespace {

// Amplitudes within +-LayeredModel::kMaxAmplitude.
void check_amplitude(double amplitude, const std::string& what) {
  if (std::abs(amplitude) <= LayeredModel::kMaxAmplitude) return;
  std::ostringstream s;
  s << what << " must be a number within +-" << LayeredModel::kMaxAmplitude << ", not " << amplitude;
  throw InvalidInput(s.str());
}

}  // namespace

namespace {

// Band 1's encoding subdivides band 0's cage as band 0 does (its tags and options).
bool same_subdivision(const DetailEncoding& e, const Band& cage) {
  const SubdivTags &a = e.cage_tags, &b = cage.tags;
  if (a.creases.size() != b.creases.size() || a.corners.size() != b.corners.size()) return false;
  for (std::size_t i = 0; i < a.creases.size(); ++i)
    if (a.creases[i].v0 != b.creases[i].v0 || a.creases[i].v1 != b.creases[i].v1 ||
        a.creases[i].sharpness != b.creases[i].sharpness)
      return false;
  for (std::size_t i = 0; i < a.corners.size(); ++i)
    if (a.corners[i].vertex != b.corners[i].vertex || a.corners[i].sharpness != b.corners[i].sharpness)
      return false;
  const SubdivOptions &x = e.cage_options, &y = cage.subdiv;
  return x.scheme == y.scheme && x.boundary == y.boundary && x.isolation_level == y.isolation_level &&
         x.max_refined_faces == y.max_refined_faces;
}

// Relative difference allowed between an encoding's derived values and those its base points
// give: encode_detail_at() restores them bit for bit, so this only absorbs another compiler's
// rounding.
constexpr double kDerivedTolerance = 1e-9;

// The encoding's values that follow from its base points over the base at rest (band.base_rest)
// and its rest detail are those values: a file stores only the base points and base_rest, and the
// reader computes the rest again, so an encoding that disagreed (base_rest scaled by 1.01 after
// encoding, target volumes doubled) was assembled and then changed by a save and a load (an
// amplitude of 0.5 then moved the finest band by 0.8% of its diagonal).
void check_derived_values(const std::string& name, const Band& b, const Band& base_band) {
  const DetailEncoding& e = b.encoding;
  const TriMesh rest{e.detail_rest, e.detail_faces};
  DetailEncoding d;
  try {
    if (e.over_limit_surface()) {
      PolyMesh cage = base_band.cage;
      cage.vertices = b.base_rest;
      d = encode_detail_at(rest, SubdivSurface(cage, base_band.tags, base_band.subdiv), e.limit_points);
    } else {
      d = encode_detail_at(rest, TriMesh{b.base_rest, base_band.mesh.faces}, e.base_points);
    }
  } catch (const Error& x) {
    throw InvalidInput(name + ": its base points over its base at rest: " + x.what());
  }
  auto compare = [&](const auto& have, const auto& want, const char* what) {
    double scale = 0.0;
    for (const auto& w : want) {
      if constexpr (std::is_arithmetic_v<std::decay_t<decltype(w)>>)
        scale = std::max(scale, std::abs(w));
      else
        scale = std::max(scale, w.cwiseAbs().maxCoeff());
    }
    const double tol = kDerivedTolerance * std::max(scale, 1e-300);
    for (std::size_t i = 0; i < want.size(); ++i) {
      double diff;
      if constexpr (std::is_arithmetic_v<std::decay_t<decltype(want[i])>>)
        diff = std::abs(have[i] - want[i]);
      else
        diff = (have[i] - want[i]).cwiseAbs().maxCoeff();
      if (!(diff <= tol))
        throw InvalidInput(name + ": the encoding's " + what + " " + std::to_string(i) +
                           " is not the one its base point over the base at rest gives (a file keeps "
                           "only the base points and base_rest)");
    }
  };
  if (e.weight_offsets != d.weight_offsets || e.weight_neighbors != d.weight_neighbors)
    throw InvalidInput(name + ": the encoding's regularization neighbours are not its rest detail's");
  compare(e.base_rest_points, d.base_rest_points, "rest base point");
  compare(e.base_rest_normals, d.base_rest_normals, "rest base normal");
  compare(e.base_rest_tangents, d.base_rest_tangents, "rest base tangent");
  compare(e.normal_offsets, d.normal_offsets, "normal offset");
  compare(e.tangential_offsets, d.tangential_offsets, "tangential offset");
  compare(e.target_volumes, d.target_volumes, "target volume");
  compare(e.weights, d.weights, "regularization weight");
}

}  // namespace

LayeredModel LayeredModel::assemble(std::vector<Band> bands, ModelOptions options,
                                    std::vector<std::string> history) {
  return assemble_parts(std::move(bands), std::move(options), std::move(history), true);
}

LayeredModel LayeredModel::assemble_parts(std::vector<Band> bands, ModelOptions options,
                                          std::vector<std::string> history, bool check_derived) {
  const int nb = static_cast<int>(bands.size());
  if (nb < 2) throw InvalidInput("a model needs at least 2 bands, not " + std::to_string(nb));
  // The reader's bound (layers/FORMAT.md): more were assembled and written, and not read back.
  if (nb > 64) throw InvalidInput("a model has at most 64 bands, not " + std::to_string(nb));
  check_model_options(options);
  for (std::size_t i = 0; i < history.size(); ++i) {
    try {
      (void)json(history[i]).dump();  // throws for text that is not UTF-8, which no file can hold
    } catch (const json::exception&) {
      throw InvalidInput("history entry " + std::to_string(i) + " is not UTF-8 text");
    }
  }
  // The scheme is stored by name: Auto (or a cast integer) wrote a file the reader refused.
  if (bands[0].subdiv.scheme != SubdivScheme::Loop && bands[0].subdiv.scheme != SubdivScheme::CatmullClark)
    throw InvalidInput("band 0: the cage's scheme must be loop or catmull-clark (not auto)");
  // The reader's bound on counts (the cage's own ceiling is checked as its surface is built below).
  if (bands[0].subdiv.max_refined_faces > (1LL << 30))
    throw InvalidInput("band 0: the cage's max_refined_faces must be at most 2^30, got " +
                       std::to_string(bands[0].subdiv.max_refined_faces));
  // What the reader refuses is refused here too (a review, thirty-eighth session: an infinite
  // sharpness, which the cage's surface takes as infinitely sharp, was written as null and the
  // file refused).
  for (const SubdivTags::Crease& c : bands[0].tags.creases)
    if (!std::isfinite(c.sharpness))
      throw InvalidInput("band 0: a crease's sharpness is not finite (10 or more is infinitely sharp)");
  for (const SubdivTags::Corner& c : bands[0].tags.corners)
    if (!std::isfinite(c.sharpness))
      throw InvalidInput("band 0: a corner's sharpness is not finite (10 or more is infinitely sharp)");
  // The cage's current points make a limit surface (a NaN point passed `info` and `export`, and an
  // edit blamed its script).
  std::optional<SubdivSurface> surface;
  try {
    surface.emplace(bands[0].cage, bands[0].tags, bands[0].subdiv);
  } catch (const InvalidInput& e) {
    throw InvalidInput("band 0: " + std::string(e.what()));
  }
  // A band collapsed to a point (all its points equal) was read; export then blamed its output.
  if (!(bbox_diagonal(bands[0].cage.vertices) > 0))
    throw InvalidInput("band 0: the cage's points all coincide");
  for (int k = 1; k < nb; ++k) {
    const Band& b = bands[k];
    const std::string name = "band " + std::to_string(k);
    const DetailEncoding& e = b.encoding;
    const int nv = b.mesh.num_vertices();
    if (e.num_detail_vertices() != nv || e.detail_faces != b.mesh.faces)
      throw InvalidInput(name + ": the encoding does not match the band's mesh");
    check_mesh_attributes(b.attributes, b.mesh, name);
    // Its arrays fit together (a short offsets array was read past by detail_magnitude()).
    try {
      check_encoding(e);
    } catch (const InvalidInput& x) {
      throw InvalidInput(name + ": " + x.what());
    }
    // A face with a repeated corner spans no prism (such a band passed every command).
    for (std::size_t f = 0; f < b.mesh.faces.size(); ++f) {
      const Face& t = b.mesh.faces[f];
      for (int c = 0; c < 3; ++c)
        if (t[c] < 0 || t[c] >= nv || t[c] == t[(c + 1) % 3])
          throw InvalidInput(name + ": face " + std::to_string(f) + " has corners (" + std::to_string(t[0]) +
                             "," + std::to_string(t[1]) + "," + std::to_string(t[2]) +
                             "), not 3 distinct vertices of " + std::to_string(nv));
    }
    // Each directed edge in one face at most: a repeated face, an edge of three faces or
    // neighbours of opposite orientation passed info, amplitude and edit, which wrote them on.
    std::unordered_map<std::uint64_t, std::size_t> directed;
    directed.reserve(3 * b.mesh.faces.size());
    for (std::size_t f = 0; f < b.mesh.faces.size(); ++f)
      for (int c = 0; c < 3; ++c) {
        const int u = b.mesh.faces[f][c], v = b.mesh.faces[f][(c + 1) % 3];
        const auto [it, fresh] =
            directed.emplace((static_cast<std::uint64_t>(u) << 32) | static_cast<std::uint32_t>(v), f);
        if (!fresh)
          throw InvalidInput(name + ": faces " + std::to_string(it->second) + " and " + std::to_string(f) +
                             " both run from vertex " + std::to_string(u) + " to " + std::to_string(v) +
                             " (a repeated face, an edge of more than two faces, or an inconsistent "
                             "orientation)");
      }
    check_coordinates(b.mesh.vertices, name + ":");
    // Finite first: a NaN rest point was reported as all the points coinciding.
    check_coordinates(e.detail_rest, name + ": the encoding's rest");
    check_coordinates(b.base_rest, name + ": its base's rest");
    if (!(bbox_diagonal(b.mesh.vertices) > 0) || !(bbox_diagonal(e.detail_rest) > 0) ||
        !(bbox_diagonal(b.base_rest) > 0))
      throw InvalidInput(name + ": its points (current, at rest, or its base's at rest) all coincide");
    check_amplitude(b.amplitude, name + ": the amplitude");
    const int base_n = k == 1 ? bands[0].cage.num_vertices() : bands[k - 1].mesh.num_vertices();
    if (e.base_num_vertices != base_n || static_cast<int>(b.base_rest.size()) != base_n)
      throw InvalidInput(name + ": its base has " + std::to_string(base_n) +
                         " vertices; the encoding's base " + std::to_string(e.base_num_vertices) +
                         " and the band's base_rest " + std::to_string(b.base_rest.size()));
    if (k == 1 ? (!e.over_limit_surface() || e.cage_faces != bands[0].cage.faces)
               : (e.over_limit_surface() || e.base_faces != bands[k - 1].mesh.faces))
      throw InvalidInput(name + ": the encoding's base is not band " + std::to_string(k - 1) + "'s surface");
    // Band 1's encoding evaluates the limit surface with its own tags and options: others than
    // band 0's gave another surface (the file stores band 0's, so the model read back changed).
    if (k == 1 && !same_subdivision(e, bands[0]))
      throw InvalidInput(name + ": the encoding's subdivision tags or options are not band 0's");
    // Its values are finite (a NaN target volume or offset was assembled, and every later edit
    // or amplitude failed on it), and band 1's limit points lie on band 0's surface (whose tags and
    // options it has): one on a face past the cage's, or with a NaN (u, v), was assembled and
    // written, and the reader refused the file. (A triangle base's points: check_encoding().)
    auto finite = [&](const auto& values, const char* what) {
      for (std::size_t i = 0; i < values.size(); ++i) {
        bool ok = true;
        if constexpr (std::is_arithmetic_v<std::decay_t<decltype(values[i])>>)
          ok = std::isfinite(values[i]);
        else
          ok = values[i].allFinite();
        if (!ok)
          throw InvalidInput(name + ": the encoding's " + what + " " + std::to_string(i) + " is not finite");
      }
    };
    finite(e.target_volumes, "target volume");
    finite(e.normal_offsets, "normal offset");
    finite(e.tangential_offsets, "tangential offset");
    finite(e.base_rest_points, "rest base point");
    finite(e.weights, "regularization weight");
    // The encoding's report as the reader checks it (a count of -5 was written and refused).
    const EncodeReport& rep = e.report;
    for (const auto& [count, what] : {std::pair<int, const char*>{rep.num_projected, "projected"},
                                      {rep.num_fallback, "fallback"},
                                      {rep.num_ambiguous, "ambiguous"}})
      if (count < 0 || count > nv)
        throw InvalidInput(name + ": the encoding report's " + what + " count " + std::to_string(count) +
                           " is outside 0.." + std::to_string(nv));
    if (!std::isfinite(rep.max_tangential_offset))
      throw InvalidInput(name + ": the encoding report's max_tangential_offset is not finite");
    if (k == 1) {
      try {
        check_limit_points(e.limit_points, *surface);
      } catch (const InvalidInput& x) {
        throw InvalidInput(name + ": the encoding's " + x.what());
      }
    }
    if (check_derived) check_derived_values(name, b, k == 1 ? bands[0] : bands[k - 1]);
  }
  LayeredModel model;
  model.impl_->bands = std::move(bands);
  model.impl_->options = std::move(options);
  // As build() and set_options(): a model keeps no caller's callback or flag (a callback that
  // captured a caller's local was called by later edits).
  model.impl_->options.reconstruct.progress = nullptr;
  model.impl_->options.reconstruct.cancel = nullptr;
  model.impl_->history = std::move(history);
  return model;
}

CascadeReport LayeredModel::edit(int k, const EditStep& step, const std::string& provenance) {
  if (impl_->drag) throw InvalidInput("edit() during a drag: end or cancel the drag first");
  check_band_index(k, impl_->n(), true);
  const auto t0 = Clock::now();
  // Work on a copy, so that the model is unchanged on any error.
  Impl work(*impl_);
  work.deps = impl_->deps;
  CascadeReport report;
  report.edited_band = k;
  std::vector<char> handle;
  const std::vector<char> region = work.selection_flags(k, step.region, step.handle, handle);
  Impl::BaseChange change;
  change.old = work.points(k);
  if (k == 0) {
    // The handle's cage vertices (s = 1) move by exactly the transform; so do the parts of the
    // finer bands that depend on them only, if the transform is rigid: a scale of 1.5 carried
    // the detail over the handle with 1.5^3 its volumes. Other maps solve those parts too.
    Band& c = work.bands[0];
    const std::vector<double> s = cage_blend_field(c.cage, region, handle);
    c.cage.vertices = blend_transform(c.cage.vertices, s, step.transform);
    if (step.transform.is_rigid()) {
      change.rigid.resize(s.size());
      for (std::size_t v = 0; v < s.size(); ++v) change.rigid[v] = s[v] == 1.0;
      change.map = &step.transform;
    }
  } else {
    RegionEditor editor(work.bands[k].mesh, region, handle, edit_options(work.options));
    EditResult r = editor.apply(step.transform);
    report.edit_volume = r.volume;
    report.edit_stats = std::move(r.stats);
    work.bands[k].mesh.vertices = std::move(r.positions);
    work.reencode(k);
  }
  report.edit_seconds = seconds_since(t0);
  if (k + 1 < work.n()) work.cascade(k + 1, std::move(change), report);
  json h = {{"op", "edit"}, {"strata", version()}, {"band", k}};
  // Provenance that is JSON is kept as JSON, within the file format's limits; otherwise as text
  // (a caller's JSON of 2,000 keys would have made every later write of the model fail).
  try {
    // The provenance sits three levels below the model object in the file (history, its entry,
    // "edit"): at most 253 deep, so that the model is within the header's 256.
    JsonLimits limits;
    limits.max_depth -= 3;
    if (!json_structure_problem(provenance, limits).empty())
      throw std::length_error("over the file's JSON limits");
    h["edit"] = json::parse(provenance);
  } catch (const std::exception&) {
    h["edit"] = provenance;
  }
  // Text that is not UTF-8 is kept with U+FFFD for its bad bytes: dump() threw a JSON library
  // type_error for it, out of edit() and end_drag().
  work.history.push_back(h.dump(-1, ' ', false, json::error_handler_t::replace));
  report.total_seconds = seconds_since(t0);
  std::swap(impl_->bands, work.bands);
  std::swap(impl_->history, work.history);
  std::swap(impl_->deps, work.deps);
  return report;
}

CascadeReport LayeredModel::set_amplitude(int k, double amplitude) {
  if (impl_->drag) throw InvalidInput("set_amplitude() during a drag: end or cancel the drag first");
  check_band_index(k, impl_->n(), false);
  check_amplitude(amplitude, "the amplitude");
  CascadeReport unchanged;
  unchanged.edited_band = k;
  // The same amplitude again (a slider released where it was) changes nothing: a rebuild would
  // solve every vertex off its rest again from the clean start, and move it within the tolerance.
  if (std::memcmp(&amplitude, &impl_->bands[k].amplitude, sizeof amplitude) == 0) return unchanged;
  const auto t0 = Clock::now();
  Impl work(*impl_);
  work.deps = impl_->deps;
  CascadeReport report;
  report.edited_band = k;
  work.bands[k].amplitude = amplitude;
  std::optional<Impl::BaseChange> change = work.rebuild(k, nullptr, report);
  if (change && k + 1 < work.n()) work.cascade(k + 1, std::move(*change), report);
  work.history.push_back(
      json({{"op", "amplitude"}, {"strata", version()}, {"band", k}, {"scale", amplitude}}).dump());
  report.total_seconds = seconds_since(t0);
  std::swap(impl_->bands, work.bands);
  std::swap(impl_->history, work.history);
  std::swap(impl_->deps, work.deps);
  return report;
}

void LayeredModel::begin_drag(int k, const Selection& region, const Selection& handle) {
  Impl& m = *impl_;
  if (m.drag) throw InvalidInput("begin_drag() during a drag");
  check_band_index(k, m.n(), true);
  auto d = std::make_unique<Impl::Drag>();
  d->band = k;
  d->step.region = region;
  d->step.handle = handle;
  std::vector<char> hflags;
  const std::vector<char> rflags = m.selection_flags(k, region, handle, hflags);
  std::vector<char> moved;
  if (k == 0) {
    d->cage_blend = cage_blend_field(m.bands[0].cage, rflags, hflags);
    moved.resize(d->cage_blend.size());
    for (std::size_t v = 0; v < moved.size(); ++v) moved[v] = d->cage_blend[v] != 0.0;
  } else {
    d->editor = std::make_unique<RegionEditor>(m.bands[k].mesh, rflags, hflags, edit_options(m.options));
    d->editor->begin_drag();
    // What the editor moves: the selection with its corners filled (the finer detail over a fill
    // vertex is reached through its base normal's ring anyway; this says so directly).
    moved.assign(rflags.size(), 0);
    for (int v : d->editor->region_vertices()) moved[v] = 1;
  }
  // The finer bands' parts the region reaches, set up once for the whole drag.
  for (int j = k + 1; j < m.n(); ++j) {
    std::vector<char> reach = m.reached(j, moved);
    d->finer.push_back(std::make_unique<PartSolve>(m.bands[j], reach, m.options));
    d->finer.back()->begin_drag(m.points(j - 1));
    moved = std::move(reach);
  }
  d->saved = m.bands;
  m.drag = std::move(d);
}

void LayeredModel::update_drag(const EditTransform& transform) {
  Impl& m = *impl_;
  if (!m.drag) throw InvalidInput("update_drag() without begin_drag()");
  Impl::Drag& d = *m.drag;
  // The transform is the drag's last only once it is accepted: a refused one (not finite, or
  // moving points out of range) was end_drag()'s, which then failed and lost the drag.
  if (d.band == 0)
    m.bands[0].cage.vertices = blend_transform(d.saved[0].cage.vertices, d.cage_blend, transform);
  else
    m.bands[d.band].mesh.vertices = d.editor->update_drag(transform);
  d.step.transform = transform;
  for (std::size_t t = 0; t < d.finer.size(); ++t) {
    const int j = d.band + 1 + static_cast<int>(t);
    d.finer[t]->solve_drag(m.points(j - 1), m.bands[j].amplitude);
    d.finer[t]->scatter(m.bands[j].mesh.vertices);
  }
}

CascadeReport LayeredModel::end_drag(const std::string& provenance) {
  Impl& m = *impl_;
  if (!m.drag) throw InvalidInput("end_drag() without begin_drag()");
  std::unique_ptr<Impl::Drag> d = std::move(m.drag);
  m.bands = std::move(d->saved);
  return edit(d->band, d->step, provenance);
}

void LayeredModel::cancel_drag() {
  Impl& m = *impl_;
  if (!m.drag) return;
  m.bands = std::move(m.drag->saved);
  m.drag.reset();
}

bool LayeredModel::dragging() const {
  return impl_->drag != nullptr;
}

}  // namespace strata::layers
