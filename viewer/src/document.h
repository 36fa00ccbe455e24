//! \file document.h
//! What the viewer shows and edits: a layered model (.strata, bands 0 .. N-1) or a plain scan
//! mesh (one band, 0, edited by a RegionEditor). No OpenGL here; the headless renderer and the
//! window share it. A value type: copies are independent (undo and redo keep copies).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "strata/edit_script.h"
#include "strata/layers/model.h"
#include "strata/mesh.h"
#include "texture.h"

namespace strata::viewer {

class Document;

//! A layered model of \p bands bands built from a plain mesh document (LayeredModel::build).
//! \throw InvalidInput if \p document is already a model; as LayeredModel::build.
Document build_layers(const Document& document, int bands);

class Document {
 public:
  //! Reads a .strata model (by extension, any case) or a mesh (.obj, .ply, .off, .stl); a mesh's
  //! faces that disagree with their neighbours' orientation are flipped (ReadOptions::
  //! orient_faces, as the CLI's scan commands do), counted by reoriented_faces(); the files it
  //! names (material libraries, images) are read from beside it (read_companion_files()), so
  //! that they go with saves and exports, and what cannot is in load_notes().
  //! \throw IoError / InvalidInput with the reader's message.
  static Document load(const std::string& path);
  //! Faces that load() flipped.
  int reoriented_faces() const { return reoriented_faces_; }
  //! load()'s notes on the files the mesh names that cannot go with it (not there, or outside
  //! its directory).
  const std::vector<std::string>& load_notes() const { return load_notes_; }
  //! Wraps an existing model or mesh (with its vertex colours and texture coordinates, if any).
  static Document from_model(layers::LayeredModel model, const std::string& name);
  static Document from_mesh(TriMesh mesh, const std::string& name, MeshAttributes attributes = {});
  //! The plain mesh. \pre !is_model().
  const TriMesh& mesh() const { return mesh_; }

  const std::string& name() const { return name_; }
  bool is_model() const { return model_.has_value(); }
  const layers::LayeredModel& model() const;
  //! The model, for drags in place. \throw InvalidInput for a plain mesh.
  layers::LayeredModel& mutable_model();
  int num_bands() const;
  int finest_band() const { return num_bands() - 1; }
  //! \throw InvalidInput "band K is out of range (NAME has N bands: 0 .. N-1)".
  void check_band(int k) const;

  //! Band k's surface: the limit surface of the cage for band 0 of a model, else the band's mesh.
  TriMesh band_mesh(int k) const;
  //! The vertex colours and texture coordinates of band_mesh(k): a plain mesh's (from its file), a
  //! model's triangle band's (Band::attributes: the scan's on the finest band); none for band 0
  //! of a model.
  const MeshAttributes& attributes(int k) const;
  //! Band k's texture, decoded for drawing (make_scene_texture()), or nullptr if it has none.
  //! Decoded once and kept while the band's attributes are the same (their values, and the same
  //! file contents: copies of a model share them), so that drag steps, which copy bands, do not
  //! decode it anew. Not thread-safe: one thread per Document.
  std::shared_ptr<const SceneTexture> texture(int k) const;
  //! Where selections of band k are evaluated: cage points for band 0 of a model, else vertices.
  const std::vector<Vec3>& band_points(int k) const;
  //! Band 0's control net as pairs of segment end points (empty for a plain mesh).
  std::vector<Vec3> control_net() const;
  //! Band k's amplitude (1 for band 0 and for plain meshes).
  double amplitude(int k) const;
  //! \throw InvalidInput for a plain mesh, band 0 or a band out of range.
  void set_amplitude(int k, double amplitude);

  //! Applies one edit step to band k: LayeredModel::edit for a model; for a plain mesh (k = 0) a
  //! RegionEditor with \p method, keeping the region's prism errors for face_errors() and the
  //! displacement-vector result for vectors_mesh().
  //! \throw InvalidInput / SolverError as the editors; the document is unchanged then.
  void edit(int k, const EditStep& step, const std::string& provenance = "{}");

  //! Per face of band_mesh(k): the prism volume error |V - a V*| / mean |V*| of the band's
  //! encoding over the current band k-1 (a: the amplitude), NaN where nothing is measured (band
  //! 0; a plain mesh outside its last edit's region or before any edit). \p vectors: the errors
  //! of vectors_mesh(k) instead.
  std::vector<double> face_errors(int k, bool vectors = false) const;
  //! Band k rebuilt by displacement vectors over the current band k-1, for comparison (band 0 and
  //! unedited plain meshes: band_mesh(k)).
  TriMesh vectors_mesh(int k) const;

  //! Replaces the model (after a drag ran on a copy). \pre is_model().
  void set_model(layers::LayeredModel model);
  //! Replaces a plain mesh's positions (after a drag ran on a copy). \pre !is_model().
  void set_mesh_positions(std::vector<Vec3> positions);

 private:
  std::string name_;
  std::optional<layers::LayeredModel> model_;
  TriMesh mesh_;               // plain mesh
  MeshAttributes attributes_;  // plain mesh: its file's colours and texture coordinates
  int reoriented_faces_ = 0;
  std::vector<std::string> load_notes_;
  std::vector<double> mesh_errors_;         // plain mesh: per face, NaN outside the last edit's region
  std::vector<Vec3> mesh_vectors_;          // plain mesh: the last edit by displacement vectors
  std::vector<double> mesh_vector_errors_;  // plain mesh: their prism errors, as mesh_errors_
  struct CachedTexture {
    MeshAttributes source;  // the attributes it was made from (the files' bytes shared, not copied)
    std::size_t faces = 0;
    bool made = false;
    std::shared_ptr<const SceneTexture> texture;  // nullptr: the band has none
  };
  mutable std::vector<CachedTexture> textures_;  // per band
};

}  // namespace strata::viewer
