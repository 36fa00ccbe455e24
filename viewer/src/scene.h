//! \file scene.h
//! What one picture shows, computed from a Document without OpenGL: the shown band's mesh (or
//! its displacement-vector rebuild), its per-face colours and the cage's control net.
#pragma once

#include <cstddef>
#include <vector>

#include "colormap.h"
#include "document.h"

namespace strata::viewer {

struct SceneSettings {
  int show = -1;  //!< band drawn (-1: the finest)
  bool vectors = false;
  ColorMode color = ColorMode::None;
  double error_scale = 0.05;
  bool cage = false;
  //! Band 0's control net where band 0 is shown (the window's "Cage net (C)" toggles it).
  bool band0_net = true;
};

struct SceneData {
  TriMesh mesh;
  std::vector<Rgb> colors;     //!< per face, per vertex (vertex_colors), or empty (surface colour)
  bool vertex_colors = false;  //!< colors are per vertex (ColorMode::Scan)
  //! ColorMode::Texture: the band's texture (Document::texture()), or nullptr.
  std::shared_ptr<const SceneTexture> texture;
  std::vector<Vec3> net;  //!< control net segments (pairs), or empty
  std::size_t intersection_pairs = 0;
  double max_error = 0.0;  //!< max relative prism error (error map), 0 otherwise
  int shown_band = 0;
};

//! \throw InvalidInput for a band out of range; as the colour maps.
SceneData make_scene(const Document& document, const SceneSettings& settings);

//! Bounding box of the mesh and the net.
void scene_bounds(const SceneData& scene, Vec3f& lo, Vec3f& hi);

}  // namespace strata::viewer
