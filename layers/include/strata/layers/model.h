//! \file model.h
//! Layered models (issue 5; the multi-layer extension the paper closes with, section 7): a scan
//! as a stack of frequency bands. Band 0 is a subdivision control cage whose limit surface is the
//! smoothest band and the main editing target. Each band k >= 1 is a triangle mesh whose detail
//! over band k-1's surface is encoded as displacement volumes (band 1 over the limit surface,
//! band k >= 2 over band k-1's mesh). The finest band is the scan itself, unchanged.
//!
//! Frequency ranges: band 0 holds the shape at wavelengths longer than about twice the cage's
//! mean edge length (its limit surface cannot bend faster); band k >= 1 holds what lies between
//! band k-1's resolution and its own: features longer than about twice its own mean edge length
//! and shorter than band k-1's smoothing kept. Intermediate bands are the scan Taubin-smoothed,
//! decimated to a face count between the cage's and the scan's (a geometric progression) and
//! smoothed again.
//!
//! Editing band k re-encodes band k over band k-1 (the edit becomes part of band k's detail), then
//! rebuilds bands k+1 .. N-1 in order (the cascade). An amplitude a_k scales band k's target
//! volumes. Only the vertices whose base actually changed are solved; every other vertex keeps its
//! position bit for bit, and a vertex whose base and amplitude are back at rest (every base point
//! within 1e-12 of the base's rest diagonal plus 1e-14 of its own largest coordinate from its rest
//! position, so that an edit undone by its inverse, which cancels only to rounding, counts) takes
//! its rest position exactly (the exact solution of its prisms), so nothing drifts and nothing is
//! lost.
//!
//! \code
//!   strata::TriMesh scan = strata::read_mesh("armadillo.off");
//!   strata::layers::LayeredModel model = strata::layers::LayeredModel::build(scan);  // 3 bands
//!   model.edit(0, step);                // a cage edit; bands 1 and 2 follow
//!   model.set_amplitude(2, 0.0);        // mute the finest band's detail
//!   strata::layers::write_model(model, "armadillo.strata");
//!   strata::TriMesh finest = model.band_mesh(model.num_bands() - 1);
//! \endcode
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "strata/cage_fit.h"
#include "strata/edit_script.h"
#include "strata/editing.h"
#include "strata/encoding.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"
#include "strata/subdiv.h"

namespace strata::layers {

namespace internal {
struct ModelAccess;  // the file reader's way in (layers/src/model_access.h)
}

//! Options of edits and rebuilds, kept with the model (and in its file).
struct ModelOptions {
  //! Detail rebuilt by displacement volumes (the paper) or vectors (the baseline, for comparison).
  EditOptions::Method method = EditOptions::Method::Volumes;
  //! The volume reconstruction of every band (its progress callback, cancel flag and thread
  //! count are not stored: a model outlives the calls that set them, and a file the machine).
  ReconstructOptions reconstruct;
  //! Edits of triangle bands (RegionEditor): the region's cut-off wavelength relative to its
  //! bounding-box diagonal, and the handle's solved rings (see EditOptions).
  double smoothing_fraction = 0.25;
  int handle_solved_rings = 3;
  //! Re-encoding after an edit: band 1 by projection onto the limit surface, bands >= 2 by normal
  //! projection onto the next coarser band.
  ProjectOptions projection;
  EncodeOptions encode;
};

//! Checks \p options against the ranges a .strata file's are read with (check_reconstruct_options()
//! for the reconstruction; smoothing_fraction 0.001-100; handle_solved_rings 0-1000; the
//! projection's and encoding's ranges in layers/FORMAT.md; and the file's own: every number
//! finite, every count at most 2^30), so that a model written with them reads back.
//! LayeredModel::build(), assemble() and set_options() call it.
//! \throw InvalidInput naming the option ("the model's ...").
void check_model_options(const ModelOptions& options);

//! Options of LayeredModel::build(), with their defaults.
struct BuildOptions {
  //! Bands in all, 2 to 8: the cage (band 0) plus bands-1 triangle bands, the finest the scan.
  int bands = 3;
  //! Band 0: the cage fitted to the scan (faces 0: 1% of the scan's faces, at least 400).
  CageFitOptions cage;
  //! Taubin smoothing steps of the scan before an intermediate band is decimated from it, and
  //! again of the decimated band.
  int band_smoothing_steps = 10;
  ModelOptions model;
  //! Optional progress reports (phase, fraction done).
  ProgressCallback progress;
};

//! One band of a model. Band 0 uses cage, tags and subdiv; bands >= 1 the rest.
struct Band {
  PolyMesh cage;                //!< band 0: the control cage, current control points
  SubdivTags tags;              //!< band 0: crease and corner tags
  SubdivOptions subdiv;         //!< band 0: scheme and boundary rule
  TriMesh mesh;                 //!< band k >= 1: connectivity and current positions
  DetailEncoding encoding;      //!< band k >= 1: over band k-1 at rest (detail_rest: rest positions)
  std::vector<Vec3> base_rest;  //!< band k >= 1: band k-1's vertices (cage points for k = 1) at encoding
  double amplitude = 1.0;       //!< band k >= 1: scales the target volumes
  //! Band k >= 1: colours, texture coordinates and materials carried with the band's vertices
  //! and faces through every edit (the finest band: the scan's, set_attributes()); empty for none.
  MeshAttributes attributes;
};

//! Detail magnitude of a band at rest: |p_i - q_i| over its vertices (q_i on band k-1).
struct DetailMagnitude {
  double rms = 0.0, max = 0.0;
  double mean_edge_length = 0.0;  //!< of the band's mesh (the cage for band 0)
};

//! What one band's rebuild did in a cascade.
struct BandRebuild {
  int band = 0;
  int solved_vertices = 0;  //!< vertices solved (their base moved)
  int rest_vertices = 0;    //!< vertices put back at rest (base and amplitude at rest)
  int rigid_vertices = 0;   //!< vertices moved by the edit's rigid map (their whole base did)
  int solved_prisms = 0;
  VolumeMetrics volume;    //!< over the solved prisms (zero when none)
  ReconstructStats stats;  //!< volumes only
  double seconds = 0.0;
};

//! What an edit or an amplitude change did.
struct CascadeReport {
  int edited_band = 0;
  double edit_seconds = 0.0;    //!< the edit of the band itself (and its re-encoding)
  VolumeMetrics edit_volume;    //!< the edited band's region prisms (triangle bands, volumes)
  ReconstructStats edit_stats;  //!< the edited band's region solve (triangle bands, volumes)
  std::vector<BandRebuild> rebuilt;
  double total_seconds = 0.0;
};

//! A layered model: bands, their encodings and amplitudes, options and the edit history. A value
//! type (copies are independent, e.g. for undo); the solvers it caches are rebuilt on demand.
//! Not thread-safe: one thread at a time per object.
class LayeredModel {
 public:
  //! Builds a model from a scan: the scan as the finest band, intermediate bands (each smoothed and
  //! decimated from the next finer one), and band 0, a cage fitted to band 1; each band encoded
  //! over the next coarser one.
  //! \pre nothing: the scan is validated.
  //! \throw InvalidInput if the scan is not a valid triangle mesh (validate_mesh) or an option is
  //!        out of range; SolverError if fitting or decimation fails.
  static LayeredModel build(const TriMesh& scan, const BuildOptions& options = {});

  //! Assembles a model from its parts (the file reader): checks that the cage makes a limit
  //! surface, that every triangle band's faces have 3 distinct vertices and each directed edge
  //! in one face at most (no repeated face, no edge of more than two faces, one orientation), and
  //! that every band's encoding fits its mesh and its base (check_encoding() too) and holds the
  //! values its base points give over its base at rest (band.base_rest; encode_detail_at(), to a
  //! relative 1e-9: a file keeps only the base points), that the cage's
  //! scheme is Loop or Catmull-Clark, the options (check_model_options()), 2 to 64 bands and
  //! history entries of UTF-8 text (write_model() stores an entry beyond the header's JSON limits
  //! as its text).
  //! The progress callback and cancel flag of the options are not kept (as in set_options()).
  //! \throw InvalidInput naming the band and the problem.
  static LayeredModel assemble(std::vector<Band> bands, ModelOptions options,
                               std::vector<std::string> history);

  LayeredModel();
  ~LayeredModel();
  //! A copy holds the committed state: during a drag of \p other, its state before the drag (the
  //! copy is not dragging).
  LayeredModel(const LayeredModel& other);
  LayeredModel& operator=(const LayeredModel& other);
  //! A moved-from object may only be assigned to or destroyed (its other calls are undefined).
  LayeredModel(LayeredModel&&) noexcept;
  LayeredModel& operator=(LayeredModel&&) noexcept;

  int num_bands() const;
  //! \throw InvalidInput if k is out of range.
  const Band& band(int k) const;
  //! Band k's current surface as a triangle mesh: for k >= 1 its mesh; for band 0 the limit
  //! surface tessellated at \p resolution segments per ptex edge.
  TriMesh band_mesh(int k, int resolution = 4) const;
  //! The positions an edit of band k selects on: cage control points (k = 0) or band k's vertices.
  const std::vector<Vec3>& band_points(int k) const;
  DetailMagnitude detail_magnitude(int k) const;
  const ModelOptions& options() const;
  //! Replaces the options used by later edits and rebuilds (e.g. the method, for a comparison).
  //! \throw InvalidInput during a drag, or as check_model_options().
  void set_options(const ModelOptions& options);
  //! JSON objects, one per operation (build, edit, amplitude), oldest first: provenance. Each
  //! has "op" and "strata", the version of the SDK that ran it (strata::version(); entries of
  //! files written before 2026-11-29 have none).
  const std::vector<std::string>& history() const;
  //! Sets band k's colours, texture coordinates and materials (Band::attributes; typically the
  //! scan's, from read_mesh_file(), on the finest band). Edits move the vertices and leave these
  //! as they are; write_model() stores them and `strata export` writes them.
  //! \throw InvalidInput if k is 0 or out of range, during a drag, or if \p attributes fail
  //!        check_mesh_attributes() for the band's mesh.
  void set_attributes(int k, MeshAttributes attributes);

  //! Edits band k with one edit step (selections on band_points(k)). Band 0: the transform is
  //! blended over the region's cage vertices (cage_blend_field). Band k >= 1: RegionEditor on the
  //! band's mesh, then band k is re-encoded over band k-1 (an amplitude other than 1 is baked in
  //! and reset to 1). Then bands k+1 .. N-1 are rebuilt. \p provenance (JSON text, e.g. the edit
  //! script) goes into the history.
  //! \throw InvalidInput for a band out of range, empty selections or a bad transform (as the
  //!        editors); SolverError if a solve fails. On any error the model is unchanged.
  CascadeReport edit(int k, const EditStep& step, const std::string& provenance = "{}");

  //! Sets band k's amplitude (k >= 1) and rebuilds bands k .. N-1. The same amplitude again
  //! (bit for bit) changes nothing and returns a report with nothing rebuilt. A vertex whose base
  //! is not at rest, or whose band's amplitude is not 1, is solved from the clean start, so two
  //! paths to the same amplitudes and cage (muting and unmuting an edited model) agree to the
  //! solver's volume tolerance, not bit for bit.
  //! \throw InvalidInput if k is 0 or out of range or the amplitude is not finite or beyond
  //!        +-kMaxAmplitude.
  CascadeReport set_amplitude(int k, double amplitude);
  //! Amplitudes are within +-this: the target volumes scale with it, and 1e308 overflowed the
  //! solve into a message about its options.
  static constexpr double kMaxAmplitude = strata::kMaxAmplitude;

  // Interactive editing (paper, section 5), for the viewer: while dragging, band(j) holds the
  // preview (band k by the editor's warm-started drag step, finer bands by warm-started
  // coarse-level solves of the vertices the region reaches); end_drag() runs the exact edit.
  //! \throw as edit() for the selections.
  void begin_drag(int k, const Selection& region, const Selection& handle);
  //! \throw InvalidInput if no drag is active or the transform is bad.
  void update_drag(const EditTransform& transform);
  //! The exact edit() with the last transform, from the state before the drag.
  //! \throw InvalidInput if no drag is active; otherwise as edit(), and the drag is then over
  //!        with the model as it was before it (as after cancel_drag()).
  CascadeReport end_drag(const std::string& provenance = "{}");
  //! Restores the state before the drag.
  void cancel_drag();
  bool dragging() const;

 private:
  friend struct internal::ModelAccess;
  // assemble(), without the check of the encodings' derived values when \p check_derived is false
  // (the reader computes them from the base points itself).
  static LayeredModel assemble_parts(std::vector<Band> bands, ModelOptions options,
                                     std::vector<std::string> history, bool check_derived);

  class Impl;
  std::unique_ptr<Impl> impl_;
};

//! Writes \p model to \p path (.strata; layout in layers/FORMAT.md), atomically. During a drag it
//! writes the state before the drag (the preview is not an edit).
//! \throw IoError if the file cannot be written; InvalidInput for a model without bands (a
//!        default-constructed one).
void write_model(const LayeredModel& model, const std::string& path);

//! Reads a model written by write_model().
//! \throw IoError "<path>: <problem>" for unreadable, foreign, newer, truncated or corrupted
//!        files; InvalidInput "<path>: <problem>" for contents that do not form a valid model.
LayeredModel read_model(const std::string& path);

}  // namespace strata::layers
