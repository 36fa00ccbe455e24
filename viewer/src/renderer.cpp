#include "renderer.h"

#include <cstddef>

namespace strata::viewer {

namespace {

const char* kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in vec3 a_bary;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_color;
out vec3 v_bary;
out vec3 v_position;
void main() {
  vec4 p = u_view * vec4(a_position, 1.0);
  v_position = p.xyz;
  v_normal = mat3(u_view) * a_normal;
  v_color = a_color;
  v_bary = a_bary;
  gl_Position = u_projection * p;
}
)";

const char* kMeshFragment = R"(#version 330 core
in vec3 v_normal;
in vec3 v_color;
in vec3 v_bary;
in vec3 v_position;
uniform int u_wireframe;
uniform vec3 u_wire_color;
out vec4 frag_color;
void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 to_eye = normalize(-v_position);
  vec3 key = normalize(to_eye + vec3(0.35, 0.45, 0.0));
  float diffuse = 0.65 * max(dot(n, key), 0.0) + 0.25 * max(dot(n, to_eye), 0.0);
  vec3 h = normalize(key + to_eye);
  float specular = 0.18 * pow(max(dot(n, h), 0.0), 40.0);
  vec3 c = v_color * (0.22 + diffuse) + vec3(specular);
  if (u_wireframe != 0) {
    vec3 d = fwidth(v_bary);
    vec3 a = smoothstep(vec3(0.0), 1.2 * d, v_bary);
    float edge = min(min(a.x, a.y), a.z);
    c = mix(u_wire_color, c, edge);
  }
  frag_color = vec4(c, 1.0);
}
)";

const char* kLineVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_color;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform float u_point_size;
out vec3 v_color;
void main() {
  v_color = a_color;
  gl_Position = u_projection * u_view * vec4(a_position, 1.0);
  gl_PointSize = u_point_size;
}
)";

const char* kLineFragment = R"(#version 330 core
in vec3 v_color;
out vec4 frag_color;
void main() { frag_color = vec4(v_color, 1.0); }
)";

struct MeshVertex {
  float position[3], normal[3], color[3], bary[3];
};

struct LineVertex {
  float position[3], color[3];
};

void put(float out[3], const Vec3& v) {
  out[0] = static_cast<float>(v.x()), out[1] = static_cast<float>(v.y()), out[2] = static_cast<float>(v.z());
}
void put(float out[3], const Rgb& v) {
  out[0] = v.x(), out[1] = v.y(), out[2] = v.z();
}

void attribute(GLuint index, int size, std::size_t stride, std::size_t offset) {
  glEnableVertexAttribArray(index);
  glVertexAttribPointer(index, size, GL_FLOAT, GL_FALSE, static_cast<GLsizei>(stride),
                        reinterpret_cast<const void*>(offset));
}

void set_matrices(GLuint program, const Mat4& view, const Mat4& projection) {
  glUniformMatrix4fv(glGetUniformLocation(program, "u_view"), 1, GL_FALSE, view.data());
  glUniformMatrix4fv(glGetUniformLocation(program, "u_projection"), 1, GL_FALSE, projection.data());
}

}  // namespace

void GpuMesh::upload(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                     const std::vector<Rgb>& colors, bool smooth, const Rgb& color) {
  const bool per_face = !colors.empty() && colors.size() == faces.size();
  const bool per_vertex = !colors.empty() && !per_face && colors.size() == vertices.size();
  std::vector<Vec3> normals;
  if (smooth) normals = vertex_normals(vertices, faces);
  std::vector<MeshVertex> data(3 * faces.size());
  static const float kBary[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Face& t = faces[f];
    const Vec3 fn = triangle_area_normal(vertices[t[0]], vertices[t[1]], vertices[t[2]]).normalized();
    for (int c = 0; c < 3; ++c) {
      MeshVertex& v = data[3 * f + c];
      put(v.position, vertices[t[c]]);
      put(v.normal, smooth && normals[t[c]].squaredNorm() > 0 ? normals[t[c]] : fn);
      put(v.color, per_face ? colors[f] : per_vertex ? colors[t[c]] : color);
      for (int k = 0; k < 3; ++k) v.bary[k] = kBary[c][k];
    }
  }
  if (!vao_) vao_ = make_vertex_array();
  if (!vbo_) vbo_ = make_buffer();
  glBindVertexArray(vao_.get());
  glBindBuffer(GL_ARRAY_BUFFER, vbo_.get());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(MeshVertex)), data.data(),
               GL_DYNAMIC_DRAW);
  attribute(0, 3, sizeof(MeshVertex), offsetof(MeshVertex, position));
  attribute(1, 3, sizeof(MeshVertex), offsetof(MeshVertex, normal));
  attribute(2, 3, sizeof(MeshVertex), offsetof(MeshVertex, color));
  attribute(3, 3, sizeof(MeshVertex), offsetof(MeshVertex, bary));
  glBindVertexArray(0);
  triangles_ = static_cast<int>(faces.size());
}

void GpuMesh::draw() const {
  if (triangles_ == 0) return;
  glBindVertexArray(vao_.get());
  glDrawArrays(GL_TRIANGLES, 0, 3 * triangles_);
  glBindVertexArray(0);
}

void GpuLines::upload(const std::vector<Vec3>& points, const std::vector<Rgb>& colors) {
  std::vector<LineVertex> data(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    put(data[i].position, points[i]);
    put(data[i].color, i < colors.size() ? colors[i] : Rgb(1, 1, 1));
  }
  if (!vao_) vao_ = make_vertex_array();
  if (!vbo_) vbo_ = make_buffer();
  glBindVertexArray(vao_.get());
  glBindBuffer(GL_ARRAY_BUFFER, vbo_.get());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(LineVertex)), data.data(),
               GL_DYNAMIC_DRAW);
  attribute(0, 3, sizeof(LineVertex), offsetof(LineVertex, position));
  attribute(1, 3, sizeof(LineVertex), offsetof(LineVertex, color));
  glBindVertexArray(0);
  count_ = static_cast<int>(data.size());
}

void GpuLines::draw_lines() const {
  if (count_ < 2) return;
  glBindVertexArray(vao_.get());
  glDrawArrays(GL_LINES, 0, count_ & ~1);
  glBindVertexArray(0);
}

void GpuLines::draw_points() const {
  if (count_ == 0) return;
  glBindVertexArray(vao_.get());
  glDrawArrays(GL_POINTS, 0, count_);
  glBindVertexArray(0);
}

Renderer::Renderer()
    : mesh_program_(make_program(build_program(kMeshVertex, kMeshFragment, "mesh"))),
      line_program_(make_program(build_program(kLineVertex, kLineFragment, "line"))) {}

void Renderer::begin_frame(int width, int height, const Rgb& background) {
  glViewport(0, 0, width, height);
  glClearColor(background.x(), background.y(), background.z(), 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
}

void Renderer::set_camera(const Mat4& view, const Mat4& projection) {
  view_ = view;
  projection_ = projection;
}

void Renderer::draw_mesh(const GpuMesh& mesh, const MeshStyle& style) {
  const GLuint p = mesh_program_.get();
  glUseProgram(p);
  set_matrices(p, view_, projection_);
  glUniform1i(glGetUniformLocation(p, "u_wireframe"), style.wireframe ? 1 : 0);
  glUniform3fv(glGetUniformLocation(p, "u_wire_color"), 1, style.wire_color.data());
  // Pushed back a little so that lines and points on the surface win the depth test.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  mesh.draw();
  glDisable(GL_POLYGON_OFFSET_FILL);
}

void Renderer::draw_lines(const GpuLines& lines) {
  const GLuint p = line_program_.get();
  glUseProgram(p);
  set_matrices(p, view_, projection_);
  glUniform1f(glGetUniformLocation(p, "u_point_size"), 1.0f);
  lines.draw_lines();
}

void Renderer::draw_points(const GpuLines& points, float size_pixels) {
  const GLuint p = line_program_.get();
  glUseProgram(p);
  set_matrices(p, view_, projection_);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glUniform1f(glGetUniformLocation(p, "u_point_size"), size_pixels);
  points.draw_points();
  glDisable(GL_PROGRAM_POINT_SIZE);
}

}  // namespace strata::viewer
