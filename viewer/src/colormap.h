//! \file colormap.h
//! Colour maps of the viewer: the surface colour, the prism volume error map and the
//! intersecting-triangles map. No OpenGL here.
#pragma once

#include <string>
#include <vector>

#include "document.h"
#include "renderer.h"
#include "strata/mesh.h"

namespace strata::viewer {

//! The plain surface colour (a light blue-grey: never "red-ish" in the pixel tests).
Rgb surface_color();
//! The colour marking intersecting triangles and large errors (pure-ish red).
Rgb alarm_color();

//! What --color selects. Scan: the shown band's own vertex colours (a scan's, from its file),
//! the surface colour where it has none. Texture: its texture images (the scan's material
//! libraries' map_Kd, or a PLY's images) by its texture coordinates, the surface colour on faces
//! without one.
enum class ColorMode { None, Error, Intersections, Scan, Texture };
//! Parses "none", "error", "intersections", "scan" or "texture". \throw std::invalid_argument
//! otherwise.
ColorMode parse_color_mode(const std::string& name);

//! Per-face colours of relative errors: surface colour at 0, through yellow at scale/2, to red at
//! \p scale and above; NaN (not measured) keeps the surface colour.
std::vector<Rgb> error_colors(const std::vector<double>& errors, double scale);

//! The colour map a document opens with when none was asked for: its texture (Texture) if its
//! finest band has one (has_texture()), else its own colours (Scan) if it has vertex colours, as a
//! viewer of textured or coloured scans is expected to show them; else None.
ColorMode initial_color_mode(const Document& document);

//! Per-vertex colours of \p attributes (their RGB), or none (empty) if they have no colours.
std::vector<Rgb> vertex_colors(const MeshAttributes& attributes);

//! Per-face colours marking the faces of intersecting non-adjacent triangle pairs (exact test,
//! find_self_intersections), the rest in the surface colour. \p pairs receives the pair count.
std::vector<Rgb> intersection_colors(const TriMesh& mesh, std::size_t& pairs);

}  // namespace strata::viewer
