#include "scene.h"

#include <algorithm>
#include <cmath>

namespace strata::viewer {

SceneData make_scene(const Document& document, const SceneSettings& settings) {
  SceneData s;
  s.shown_band = settings.show < 0 ? document.finest_band() : settings.show;
  document.check_band(s.shown_band);
  s.mesh = settings.vectors ? document.vectors_mesh(s.shown_band) : document.band_mesh(s.shown_band);
  if (settings.color == ColorMode::Error) {
    const std::vector<double> e = document.face_errors(s.shown_band, settings.vectors);
    for (double x : e)
      if (std::isfinite(x)) s.max_error = std::max(s.max_error, x);
    if (e.size() == s.mesh.faces.size()) s.colors = error_colors(e, settings.error_scale);
  } else if (settings.color == ColorMode::Intersections) {
    s.colors = intersection_colors(s.mesh, s.intersection_pairs);
  } else if (settings.color == ColorMode::Scan) {
    s.colors = vertex_colors(document.attributes(s.shown_band));
    s.vertex_colors = true;
  } else if (settings.color == ColorMode::Texture) {
    s.texture = document.texture(s.shown_band);  // the vectors' mesh has the same faces
  }
  if (settings.cage || (s.shown_band == 0 && settings.band0_net)) s.net = document.control_net();
  return s;
}

void scene_bounds(const SceneData& scene, Vec3f& lo, Vec3f& hi) {
  lo = Vec3f::Constant(1e30f);
  hi = Vec3f::Constant(-1e30f);
  auto add = [&](const Vec3& p) {
    lo = lo.cwiseMin(p.cast<float>());
    hi = hi.cwiseMax(p.cast<float>());
  };
  for (const Vec3& p : scene.mesh.vertices) add(p);
  for (const Vec3& p : scene.net) add(p);
  if (lo.x() > hi.x()) lo = hi = Vec3f::Zero();
}

}  // namespace strata::viewer
