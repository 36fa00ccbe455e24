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

namespace strata::viewer {

using Rgb = Eigen::Vector3f;

//! A triangle mesh on the GPU: every face's three corners stored apart (position, normal, colour,
//! barycentric coordinate), so flat normals and per-face colours need no extra pass.
class GpuMesh {
 public:
  //! Uploads \p vertices / \p faces. \p colors: empty (all \p color), one per face or one per
  //! vertex. \p smooth: angle-weighted vertex normals, else face normals.
  //! \pre face indices are in range; colors.size() is 0, faces.size() or vertices.size().
  void upload(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
              const std::vector<Rgb>& colors, bool smooth, const Rgb& color);
  void draw() const;
  int triangles() const { return triangles_; }
  bool empty() const { return triangles_ == 0; }

 private:
  GlName vao_, vbo_;
  int triangles_ = 0;
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
  GlName mesh_program_, line_program_;
  Mat4 view_ = Mat4::Identity(), projection_ = Mat4::Identity();
};

}  // namespace strata::viewer
