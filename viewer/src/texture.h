//! \file texture.h
//! A textured scan's pictures, decoded for drawing: per face corner its texture coordinates and
//! per face its image, from the band's MeshAttributes and the images among its companion files
//! (face_texture_files()). No OpenGL here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "strata/mesh.h"

namespace strata::viewer {

//! One level of an image as OpenGL takes it: RGBA8 rows, the first row at texture coordinate
//! v = 0 (the image's bottom row: OBJ and PLY put v = 0 at the bottom).
struct TextureLevel {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
};

//! An image and its mipmaps (each level half the previous, 2x2 box filtered, down to 1x1), made
//! here on the calling thread (the viewer's worker): glGenerateMipmap on llvmpipe took 0.14 s of
//! a 2048x2048 image's upload on the UI thread.
struct TextureImage {
  std::vector<TextureLevel> levels;
};

struct SceneTexture {
  std::vector<float> corner_uv;  //!< (u, v) per face corner: 6 per face
  std::vector<int> face_image;   //!< per face, an index into images, or -1 (the surface colour)
  std::vector<TextureImage> images;
  //! Images that could not be decoded ("<name>: <reason>"); their faces get the surface colour.
  std::vector<std::string> problems;
};

//! The most pixels of an image the viewer decodes (8192 x 8192: 256 MB as RGBA, a third more with
//! its mipmaps); a larger one is a problem and its faces get the surface colour.
constexpr long long kMaxTexturePixels = 8192LL * 8192;

//! Whether \p attributes give some face a texture image and every face texture coordinates (per
//! vertex or per corner): what the texture view needs. Cheap: no image is decoded.
bool has_texture(const MeshAttributes& attributes);

//! Decodes the images that \p attributes' faces use (PNG, JPEG, BMP, TGA, ...: stb_image) and
//! gathers each face corner's texture coordinates. nullptr if !has_texture(attributes).
//! \pre check_mesh_attributes(attributes, mesh) passes for the mesh of \p faces.
std::shared_ptr<const SceneTexture> make_scene_texture(const MeshAttributes& attributes,
                                                       const std::vector<Face>& faces);

}  // namespace strata::viewer
