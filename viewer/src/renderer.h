//! \file renderer.h
//! The OpenGL 3.3 core rendering core: triangle meshes (flat or smooth shading, a wireframe
//! overlay drawn in the same pass from barycentric coordinates, per-face or per-vertex colours),
//! line sets (the cage's control net) and point sets (selections). Every function needs a current
//! GL 3.3+ core context; GPU objects must be destroyed while it is current.
#pragma once

#include <vector>

#include "camera.h"
#include "gl.h"
#include "strata/mesh.h"
#include "texture.h"

namespace strata::viewer {

using Rgb = Eigen::Vector3f;

//! A triangle mesh on the GPU, indexed (each vertex shaded once: llvmpipe runs vertex shaders on
//! one thread): positions and smooth normals per vertex, colours per vertex (an attribute) or
//! per face (a buffer texture read with gl_PrimitiveID). Flat shading derives the face normal
//! in the fragment shader, and the wireframe is a second pass in line mode, so neither needs
//! the corners stored apart.
class GpuMesh {
 public:
  //! Uploads \p vertices / \p faces. \p colors: empty (all \p color), or one per face, or one
  //! per vertex if \p per_vertex (a tetrahedron has as many of each); any other count draws
  //! \p color. With \p texture (faces.size() faces), its images are drawn instead of colours: a
  //! vertex is stored once per texture coordinate its corners use (texture seams), and faces are
  //! drawn in groups by image. \pre face indices are in range.
  void upload(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
              const std::vector<Rgb>& colors, const Rgb& color, bool per_vertex = false,
              const SceneTexture* texture = nullptr);
  //! New positions for the same vertices and faces (normals recomputed).
  //! \pre vertices.size() is the uploaded vertex count.
  void update_positions(const std::vector<Vec3>& vertices, const std::vector<Face>& faces);
  //! Binds the state and issues the draw call(s) of the fill pass; used by Renderer. Textured
  //! (color_mode() 3) with \p textured_uniform >= 0: one call per image, with its texture bound
  //! on unit 1 and the uniform set to whether the group has one; else one call for all faces.
  void draw(GLint textured_uniform = -1) const;
  int triangles() const { return triangles_; }
  int vertices() const { return vertex_count_; }
  bool empty() const { return triangles_ == 0; }
  //! 0: uniform colour, 1: per vertex, 2: per face, 3: texture images.
  int color_mode() const { return color_mode_; }
  //! Every edge has exactly two faces: back faces are culled.
  bool closed() const { return closed_; }
  const Rgb& color() const { return color_; }
  GLuint face_color_texture() const { return face_texture_.get(); }

 private:
  GlName vao_, positions_, colors_, indices_, face_buffer_, face_texture_, uvs_;
  std::vector<GlName> images_;
  struct ImageRange {
    int image, first, count;  // image -1: no texture; first and count in triangles
  };
  std::vector<ImageRange> ranges_;
  // Texture mode: the GPU vertices, index buffer (faces grouped by image), texture coordinates
  // and images.
  void upload_texture(const SceneTexture& texture, const std::vector<Face>& faces, std::vector<GLuint>& idx);
  // Vertices are stored in order of first use by the faces (locality for llvmpipe's vertex
  // cache): order_[gpu index] = mesh index.
  std::vector<int> order_;
  int triangles_ = 0, vertex_count_ = 0, color_mode_ = 0;
  bool closed_ = false;
  Rgb color_ = Rgb(1, 1, 1);
};

//! Coloured line segments (GL_LINES) or points (GL_POINTS).
class GpuLines {
 public:
  //! \p points: segment end points in pairs (lines) or single points; \p colors: one per point.
  void upload(const std::vector<Vec3>& points, const std::vector<Rgb>& colors);
  void draw_lines() const;
  void draw_points() const;
  bool empty() const { return count_ == 0; }

 private:
  GlName vao_, vbo_;
  int count_ = 0;
};

//! How a mesh is drawn.
struct MeshStyle {
  bool smooth = true;
  bool wireframe = false;
  Rgb wire_color = Rgb(0.08f, 0.08f, 0.1f);
};

//! The shader programs and per-frame state.
class Renderer {
 public:
  //! Compiles the programs. \throw std::runtime_error if a shader fails.
  Renderer();
  //! Sets the viewport and clears colour and depth to \p background; depth test on.
  void begin_frame(int width, int height, const Rgb& background);
  void set_camera(const Mat4& view, const Mat4& projection);
  void draw_mesh(const GpuMesh& mesh, const MeshStyle& style);
  void draw_lines(const GpuLines& lines);
  void draw_points(const GpuLines& points, float size_pixels);

 private:
  GlName mesh_program_, line_program_, wire_program_;
  Mat4 view_ = Mat4::Identity(), projection_ = Mat4::Identity();
};

}  // namespace strata::viewer
