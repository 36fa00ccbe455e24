#include "colormap.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "strata/intersections.h"

namespace strata::viewer {

Rgb surface_color() {
  return Rgb(0.66f, 0.71f, 0.78f);
}
Rgb alarm_color() {
  return Rgb(0.92f, 0.08f, 0.06f);
}

ColorMode parse_color_mode(const std::string& name) {
  if (name == "none") return ColorMode::None;
  if (name == "error") return ColorMode::Error;
  if (name == "intersections") return ColorMode::Intersections;
  if (name == "scan") return ColorMode::Scan;
  if (name == "texture") return ColorMode::Texture;
  throw std::invalid_argument("unknown colour map '" + name +
                              "' (error, intersections, scan, texture or none)");
}

std::vector<Rgb> error_colors(const std::vector<double>& errors, double scale) {
  const Rgb base = surface_color(), yellow(0.95f, 0.85f, 0.15f), red = alarm_color();
  std::vector<Rgb> colors(errors.size(), base);
  for (std::size_t i = 0; i < errors.size(); ++i) {
    if (!std::isfinite(errors[i])) continue;
    const float t = static_cast<float>(std::clamp(errors[i] / std::max(scale, 1e-300), 0.0, 1.0));
    colors[i] =
        t < 0.5f ? Rgb(base + 2.0f * t * (yellow - base)) : Rgb(yellow + (2.0f * t - 1.0f) * (red - yellow));
  }
  return colors;
}

ColorMode initial_color_mode(const Document& document) {
  const MeshAttributes& a = document.attributes(document.finest_band());
  return has_texture(a) ? ColorMode::Texture : a.colors.empty() ? ColorMode::None : ColorMode::Scan;
}

std::vector<Rgb> vertex_colors(const MeshAttributes& attributes) {
  std::vector<Rgb> colors;
  colors.reserve(attributes.colors.size());
  for (const auto& c : attributes.colors)
    colors.emplace_back(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]));
  return colors;
}

std::vector<Rgb> intersection_colors(const TriMesh& mesh, std::size_t& pairs) {
  IntersectionOptions options = bounded_intersection_options(mesh.faces.size());
  options.collect_pairs = true;
  options.max_pairs = 1000000;
  const IntersectionResult r = find_self_intersections(mesh.vertices, mesh.faces, options);
  pairs = r.num_pairs;
  std::vector<Rgb> colors(mesh.faces.size(), surface_color());
  for (int f : r.faces) colors[static_cast<std::size_t>(f)] = alarm_color();
  return colors;
}

}  // namespace strata::viewer
