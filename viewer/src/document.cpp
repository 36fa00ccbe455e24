#include "document.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "strata/editing.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"
#include "strata/metrics.h"

namespace strata::viewer {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool ends_with_strata(std::string path) {
  std::transform(path.begin(), path.end(), path.begin(), [](unsigned char c) { return std::tolower(c); });
  return path.size() >= 7 && path.compare(path.size() - 7, 7, ".strata") == 0;
}

// |V_j - a V*_j| / mean |V*| per prism.
std::vector<double> relative_errors(const std::vector<double>& volumes, const std::vector<double>& targets,
                                    double amplitude) {
  double mean = 0.0;
  for (double t : targets) mean += std::abs(t);
  mean = targets.empty() ? 0.0 : mean / static_cast<double>(targets.size());
  std::vector<double> e(volumes.size(), 0.0);
  if (mean <= 0.0) return e;
  for (std::size_t j = 0; j < volumes.size(); ++j)
    e[j] = std::abs(volumes[j] - amplitude * targets[j]) / mean;
  return e;
}
}  // namespace

Document build_layers(const Document& document, int bands) {
  if (document.is_model()) throw InvalidInput(document.name() + " is already a layered model");
  layers::BuildOptions options;
  options.bands = bands;
  layers::LayeredModel model = layers::LayeredModel::build(document.mesh(), options);
  model.set_attributes(model.num_bands() - 1, document.attributes(0));  // the scan's, on its band
  return Document::from_model(std::move(model), document.name());
}

Document Document::load(const std::string& path) {
  if (ends_with_strata(path)) return from_model(layers::read_model(path), path);
  ReadOptions ro;
  ro.orient_faces = true;
  MeshFile f = read_mesh_file(path, ro);
  std::vector<std::string> notes = read_companion_files(f.attributes, path);
  Document d = from_mesh(std::move(f.mesh), path, std::move(f.attributes));
  d.reoriented_faces_ = f.flipped_faces;
  d.load_notes_ = std::move(notes);
  return d;
}

Document Document::from_model(layers::LayeredModel model, const std::string& name) {
  Document d;
  d.name_ = name;
  d.model_ = std::move(model);
  return d;
}

Document Document::from_mesh(TriMesh mesh, const std::string& name, MeshAttributes attributes) {
  Document d;
  d.name_ = name;
  check_mesh_attributes(attributes, mesh, name);
  d.mesh_ = std::move(mesh);
  d.attributes_ = std::move(attributes);
  d.mesh_errors_.assign(d.mesh_.faces.size(), kNaN);
  return d;
}

const layers::LayeredModel& Document::model() const {
  if (!model_) throw InvalidInput(name_ + " is a plain mesh, not a layered model");
  return *model_;
}

layers::LayeredModel& Document::mutable_model() {
  if (!model_) throw InvalidInput(name_ + " is a plain mesh, not a layered model");
  return *model_;
}

int Document::num_bands() const {
  return model_ ? model_->num_bands() : 1;
}

void Document::check_band(int k) const {
  if (k < 0 || k >= num_bands())
    throw InvalidInput("band " + std::to_string(k) + " is out of range (" + name_ + " has " +
                       std::to_string(num_bands()) + (num_bands() == 1 ? " band: 0)" : " bands: 0 .. ") +
                       (num_bands() == 1 ? "" : std::to_string(num_bands() - 1) + ")"));
}

TriMesh Document::band_mesh(int k) const {
  check_band(k);
  return model_ ? model_->band_mesh(k) : mesh_;
}

const MeshAttributes& Document::attributes(int k) const {
  check_band(k);
  static const MeshAttributes none;
  if (!model_) return attributes_;
  return k == 0 ? none : model_->band(k).attributes;
}

std::shared_ptr<const SceneTexture> Document::texture(int k) const {
  const MeshAttributes& a = attributes(k);
  textures_.resize(static_cast<std::size_t>(num_bands()));
  CachedTexture& c = textures_[static_cast<std::size_t>(k)];
  const std::vector<Face>& faces = model_ ? model_->band(k).mesh.faces : mesh_.faces;
  // The same values; the files compared by their shared contents' address, not byte by byte.
  const auto same_files = [](const std::vector<CompanionFile>& x, const std::vector<CompanionFile>& y) {
    return std::equal(
        x.begin(), x.end(), y.begin(), y.end(),
        [](const CompanionFile& p, const CompanionFile& q) { return p.name == q.name && p.data == q.data; });
  };
  const MeshAttributes& s = c.source;
  const bool same = c.made && c.faces == faces.size() && same_files(s.files, a.files) &&
                    s.texcoords == a.texcoords && s.corner_uv == a.corner_uv &&
                    s.corner_uv_index == a.corner_uv_index && s.face_materials == a.face_materials &&
                    s.material_names == a.material_names && s.material_library == a.material_library &&
                    s.texture_files == a.texture_files && s.face_textures == a.face_textures;
  if (!same) {
    c.texture = make_scene_texture(a, faces);
    c.source = a;
    c.source.colors.clear();  // not needed for the comparison
    c.faces = faces.size();
    c.made = true;
  }
  return c.texture;
}

const std::vector<Vec3>& Document::band_points(int k) const {
  check_band(k);
  return model_ ? model_->band_points(k) : mesh_.vertices;
}

std::vector<Vec3> Document::control_net() const {
  std::vector<Vec3> segments;
  if (!model_) return segments;
  const PolyMesh& cage = model_->band(0).cage;
  std::set<std::pair<int, int>> edges;
  for (const auto& f : cage.faces)
    for (std::size_t c = 0; c < f.size(); ++c) {
      const int a = f[c], b = f[(c + 1) % f.size()];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  segments.reserve(2 * edges.size());
  for (const auto& [a, b] : edges) {
    segments.push_back(cage.vertices[a]);
    segments.push_back(cage.vertices[b]);
  }
  return segments;
}

double Document::amplitude(int k) const {
  check_band(k);
  return model_ && k > 0 ? model_->band(k).amplitude : 1.0;
}

void Document::set_amplitude(int k, double amplitude) {
  if (!model_) throw InvalidInput("amplitudes need a layered model (" + name_ + " is a plain mesh)");
  check_band(k);
  if (k == 0) throw InvalidInput("band 0 (the cage) has no amplitude; bands 1 .. N-1 have");
  model_->set_amplitude(k, amplitude);
}

void Document::edit(int k, const EditStep& step, const std::string& provenance) {
  check_band(k);
  if (model_) {
    model_->edit(k, step, provenance);
    return;
  }
  const std::vector<char> region = select_vertices(mesh_.vertices, step.region);
  const std::vector<char> handle = select_vertices(mesh_.vertices, step.handle);
  EditOptions options;
  RegionEditor editor(mesh_, region, handle, options);
  EditResult volumes = editor.apply(step.transform);
  // The displacement-vector baseline of the same edit, for the compare view.
  std::vector<Vec3> vectors = volumes.positions;
  {
    const DetailEncoding& enc = editor.encoding();
    const std::vector<int>& sub = editor.region_submesh_vertices();
    std::vector<Vec3> base(sub.size());
    for (std::size_t i = 0; i < sub.size(); ++i) base[i] = volumes.base_positions[sub[i]];
    const std::vector<Vec3> v = reconstruct_vectors(enc, base);
    for (std::size_t i = 0; i < sub.size(); ++i) vectors[sub[i]] = v[i];
    // Region prisms: the faces with a region vertex, in mesh order (the encoding's face order).
    std::vector<Vec3> detail(sub.size());
    for (std::size_t i = 0; i < sub.size(); ++i) detail[i] = volumes.positions[sub[i]];
    const BaseFrames frames = evaluate_base_frames(enc, base);
    const std::vector<double> err =
        relative_errors(prism_volumes(enc.detail_faces, detail, frames.points), enc.target_volumes, 1.0);
    const std::vector<double> err_vectors =
        relative_errors(prism_volumes(enc.detail_faces, v, frames.points), enc.target_volumes, 1.0);
    std::vector<char> in_region(mesh_.vertices.size(), 0);
    for (int r : editor.region_vertices()) in_region[r] = 1;
    std::vector<double> errors(mesh_.faces.size(), kNaN), errors_vectors(mesh_.faces.size(), kNaN);
    std::size_t j = 0;
    for (std::size_t f = 0; f < mesh_.faces.size() && j < err.size(); ++f) {
      const Face& t = mesh_.faces[f];
      if (in_region[t[0]] || in_region[t[1]] || in_region[t[2]]) {
        errors[f] = err[j];
        errors_vectors[f] = err_vectors[j++];
      }
    }
    mesh_errors_ = std::move(errors);
    mesh_vector_errors_ = std::move(errors_vectors);
  }
  mesh_.vertices = std::move(volumes.positions);
  mesh_vectors_ = std::move(vectors);
  (void)provenance;
}

std::vector<double> Document::face_errors(int k, bool vectors) const {
  check_band(k);
  if (!model_) return vectors && !mesh_vectors_.empty() ? mesh_vector_errors_ : mesh_errors_;
  if (k == 0) return std::vector<double>(band_mesh(0).faces.size(), kNaN);
  const layers::Band& b = model_->band(k);
  const BaseFrames frames = evaluate_base_frames(b.encoding, model_->band_points(k - 1));
  const std::vector<Vec3> positions =
      vectors ? reconstruct_vectors(b.encoding, frames, b.amplitude) : b.mesh.vertices;
  return relative_errors(prism_volumes(b.encoding.detail_faces, positions, frames.points),
                         b.encoding.target_volumes, b.amplitude);
}

TriMesh Document::vectors_mesh(int k) const {
  check_band(k);
  if (!model_) {
    TriMesh m = mesh_;
    if (mesh_vectors_.size() == m.vertices.size()) m.vertices = mesh_vectors_;
    return m;
  }
  if (k == 0) return band_mesh(0);
  const layers::Band& b = model_->band(k);
  const BaseFrames frames = evaluate_base_frames(b.encoding, model_->band_points(k - 1));
  TriMesh m = b.mesh;
  m.vertices = reconstruct_vectors(b.encoding, frames, b.amplitude);
  return m;
}

void Document::set_model(layers::LayeredModel model) {
  model_ = std::move(model);
}

void Document::set_mesh_positions(std::vector<Vec3> positions) {
  mesh_.vertices = std::move(positions);
  mesh_errors_.assign(mesh_.faces.size(), kNaN);
  mesh_vectors_.clear();
  mesh_vector_errors_.clear();
}

}  // namespace strata::viewer
