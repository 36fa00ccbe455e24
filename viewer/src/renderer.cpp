#include "renderer.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <numeric>
#include <unordered_map>

namespace strata::viewer {

namespace {

const char* kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in vec2 a_uv;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_normal;
out vec3 v_color;
out vec3 v_position;
out vec2 v_uv;
void main() {
  vec4 p = u_view * vec4(a_position, 1.0);
  v_position = p.xyz;
  v_normal = mat3(u_view) * a_normal;
  v_color = a_color;
  v_uv = a_uv;
  gl_Position = u_projection * p;
}
)";

const char* kMeshFragment = R"(#version 330 core
in vec3 v_normal;
in vec3 v_color;
in vec3 v_position;
in vec2 v_uv;
uniform int u_smooth;
uniform int u_color_mode;  // 0 uniform, 1 per vertex, 2 per face, 3 texture image
uniform vec3 u_color;
uniform samplerBuffer u_face_colors;
uniform sampler2D u_texture;
uniform int u_textured;
out vec4 frag_color;
void main() {
  vec3 n = u_smooth != 0 ? normalize(v_normal) : normalize(cross(dFdx(v_position), dFdy(v_position)));
  if (u_smooth != 0 && !gl_FrontFacing) n = -n;
  vec3 to_eye = normalize(-v_position);
  if (u_smooth == 0 && dot(n, to_eye) < 0.0) n = -n;
  vec3 key = normalize(to_eye + vec3(0.35, 0.45, 0.0));
  float diffuse = 0.65 * max(dot(n, key), 0.0) + 0.25 * max(dot(n, to_eye), 0.0);
  vec3 h = normalize(key + to_eye);
  float specular = 0.18 * pow(max(dot(n, h), 0.0), 40.0);
  vec3 base = u_color_mode == 1 ? v_color : u_color_mode == 2 ? texelFetch(u_face_colors, gl_PrimitiveID).rgb : u_color;
  if (u_color_mode == 3 && u_textured != 0) base = texture(u_texture, v_uv).rgb;
  frag_color = vec4(base * (0.22 + diffuse) + vec3(specular), 1.0);
}
)";

const char* kWireFragment = R"(#version 330 core
uniform vec3 u_color;
out vec4 frag_color;
void main() { frag_color = vec4(u_color, 1.0); }
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
                     const std::vector<Rgb>& colors, const Rgb& color, bool per_vertex,
                     const SceneTexture* texture) {
  color_ = color;
  const bool textured =
      texture && texture->face_image.size() == faces.size() && texture->corner_uv.size() == 6 * faces.size();
  color_mode_ = textured                                         ? 3
                : colors.empty()                                 ? 0
                : per_vertex && colors.size() == vertices.size() ? 1
                : !per_vertex && colors.size() == faces.size()   ? 2
                                                                 : 0;
  if (!vao_) {
    vao_ = make_vertex_array();
    positions_ = make_buffer();
    colors_ = make_buffer();
    indices_ = make_buffer();
  }
  glBindVertexArray(vao_.get());
  vertex_count_ = static_cast<int>(vertices.size());
  std::vector<GLuint> idx(3 * faces.size());
  order_.clear();
  ranges_.clear();
  images_.clear();
  if (textured) {
    upload_texture(*texture, faces, idx);
  } else {
    std::vector<int> gpu_index(vertices.size(), -1);
    order_.reserve(vertices.size());
    for (const Face& f : faces)
      for (int v : f)
        if (gpu_index[static_cast<std::size_t>(v)] < 0) {
          gpu_index[static_cast<std::size_t>(v)] = static_cast<int>(order_.size());
          order_.push_back(v);
        }
    for (std::size_t v = 0; v < vertices.size(); ++v)
      if (gpu_index[v] < 0) {
        gpu_index[v] = static_cast<int>(order_.size());
        order_.push_back(static_cast<int>(v));
      }
    for (std::size_t f = 0; f < faces.size(); ++f)
      for (int c = 0; c < 3; ++c)
        idx[3 * f + c] = static_cast<GLuint>(gpu_index[static_cast<std::size_t>(faces[f][c])]);
    glDisableVertexAttribArray(3);
  }
  update_positions(vertices, faces);
  glBindVertexArray(vao_.get());
  glBindBuffer(GL_ARRAY_BUFFER, positions_.get());
  attribute(0, 3, 6 * sizeof(float), 0);
  attribute(1, 3, 6 * sizeof(float), 3 * sizeof(float));
  if (color_mode_ == 1) {
    std::vector<float> c(3 * colors.size());
    for (std::size_t i = 0; i < colors.size(); ++i)
      put(&c[3 * i], colors[static_cast<std::size_t>(order_[i])]);
    glBindBuffer(GL_ARRAY_BUFFER, colors_.get());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(c.size() * sizeof(float)), c.data(),
                 GL_STATIC_DRAW);
    attribute(2, 3, 3 * sizeof(float), 0);
  } else {
    glDisableVertexAttribArray(2);
    glVertexAttrib3f(2, color.x(), color.y(), color.z());
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(GLuint)), idx.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  triangles_ = static_cast<int>(faces.size());
  // Closed: every undirected edge used by exactly two faces (then back faces are never seen).
  {
    std::map<std::pair<int, int>, int> uses;
    for (const Face& f : faces)
      for (int c = 0; c < 3; ++c) ++uses[{std::min(f[c], f[(c + 1) % 3]), std::max(f[c], f[(c + 1) % 3])}];
    closed_ = !faces.empty();
    for (const auto& [edge, n] : uses) closed_ = closed_ && n == 2;
  }
  if (color_mode_ == 2) {
    std::vector<unsigned char> c(4 * colors.size());
    for (std::size_t i = 0; i < colors.size(); ++i)
      for (int k = 0; k < 3; ++k)
        c[4 * i + k] = static_cast<unsigned char>(std::clamp(colors[i][k], 0.0f, 1.0f) * 255.0f + 0.5f);
    if (!face_buffer_) {
      face_buffer_ = make_buffer();
      face_texture_ = make_texture();
    }
    glBindBuffer(GL_TEXTURE_BUFFER, face_buffer_.get());
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(c.size()), c.data(), GL_STATIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, face_texture_.get());
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA8, face_buffer_.get());
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
  }
}

void GpuMesh::update_positions(const std::vector<Vec3>& vertices, const std::vector<Face>& faces) {
  const std::vector<Vec3> normals = vertex_normals(vertices, faces);
  std::vector<float> data(6 * order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const auto v = static_cast<std::size_t>(order_[i]);
    put(&data[6 * i], vertices[v]);
    put(&data[6 * i + 3], normals[v]);
  }
  glBindBuffer(GL_ARRAY_BUFFER, positions_.get());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void GpuMesh::upload_texture(const SceneTexture& texture, const std::vector<Face>& faces,
                             std::vector<GLuint>& idx) {
  // Faces in groups by image, each group one draw call.
  std::vector<int> face_order(faces.size());
  std::iota(face_order.begin(), face_order.end(), 0);
  std::stable_sort(face_order.begin(), face_order.end(),
                   [&](int a, int b) { return texture.face_image[a] < texture.face_image[b]; });
  // One GPU vertex per (vertex, texture coordinate) pair that some corner uses.
  struct Key {
    int vertex;
    float u, v;
    bool operator==(const Key& o) const { return vertex == o.vertex && u == o.u && v == o.v; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint32_t u = 0, v = 0;
      std::memcpy(&u, &k.u, 4);
      std::memcpy(&v, &k.v, 4);
      return std::hash<std::uint64_t>()((static_cast<std::uint64_t>(k.vertex) << 32) ^ (u * 2654435761u) ^ v);
    }
  };
  std::unordered_map<Key, GLuint, KeyHash> gpu_index;
  gpu_index.reserve(3 * faces.size());
  std::vector<float> uv;
  for (std::size_t i = 0; i < face_order.size(); ++i) {
    const std::size_t f = static_cast<std::size_t>(face_order[i]);
    const int image = texture.face_image[f];
    if (ranges_.empty() || ranges_.back().image != image) ranges_.push_back({image, static_cast<int>(i), 0});
    ++ranges_.back().count;
    for (int c = 0; c < 3; ++c) {
      const Key key{faces[f][c], texture.corner_uv[6 * f + 2 * c], texture.corner_uv[6 * f + 2 * c + 1]};
      const auto [it, added] = gpu_index.emplace(key, static_cast<GLuint>(order_.size()));
      if (added) {
        order_.push_back(key.vertex);
        uv.insert(uv.end(), {key.u, key.v});
      }
      idx[3 * i + c] = it->second;
    }
  }
  if (!uvs_) uvs_ = make_buffer();
  glBindBuffer(GL_ARRAY_BUFFER, uvs_.get());
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(uv.size() * sizeof(float)), uv.data(),
               GL_STATIC_DRAW);
  attribute(3, 2, 2 * sizeof(float), 0);
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (const TextureImage& image : texture.images) {
    images_.push_back(make_texture());
    glBindTexture(GL_TEXTURE_2D, images_.back().get());
    // Levels larger than the GL takes are skipped: the image is drawn from its smaller mipmaps.
    int level = 0;
    for (const TextureLevel& l : image.levels)
      if (l.width <= max_size && l.height <= max_size)
        glTexImage2D(GL_TEXTURE_2D, level++, GL_RGBA8, l.width, l.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                     l.rgba.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, std::max(0, level - 1));
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);  // OBJ's texture coordinates repeat
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

void GpuMesh::draw(GLint textured_uniform) const {
  if (triangles_ == 0) return;
  glBindVertexArray(vao_.get());
  if (color_mode_ == 3 && textured_uniform >= 0) {
    glActiveTexture(GL_TEXTURE1);
    for (const ImageRange& r : ranges_) {
      const bool has = r.image >= 0 && static_cast<std::size_t>(r.image) < images_.size();
      glUniform1i(textured_uniform, has ? 1 : 0);
      glBindTexture(GL_TEXTURE_2D, has ? images_[static_cast<std::size_t>(r.image)].get() : 0);
      glDrawElements(GL_TRIANGLES, 3 * r.count, GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(3 * static_cast<std::size_t>(r.first) * sizeof(GLuint)));
    }
    glBindTexture(GL_TEXTURE_2D, 0);
    glActiveTexture(GL_TEXTURE0);
  } else {
    glDrawElements(GL_TRIANGLES, 3 * triangles_, GL_UNSIGNED_INT, nullptr);
  }
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
      line_program_(make_program(build_program(kLineVertex, kLineFragment, "line"))),
      wire_program_(make_program(build_program(kMeshVertex, kWireFragment, "wire"))) {}

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
  glUniform1i(glGetUniformLocation(p, "u_smooth"), style.smooth ? 1 : 0);
  glUniform1i(glGetUniformLocation(p, "u_color_mode"), mesh.color_mode());
  glUniform3fv(glGetUniformLocation(p, "u_color"), 1, mesh.color().data());
  glUniform1i(glGetUniformLocation(p, "u_face_colors"), 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, mesh.color_mode() == 2 ? mesh.face_color_texture() : 0);
  // Pushed back a little so that the wireframe, lines and points on the surface win the depth test.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  // Back faces of a closed mesh are hidden anyway: culling them halves llvmpipe's triangle setup.
  if (mesh.closed()) glEnable(GL_CULL_FACE);
  glUniform1i(glGetUniformLocation(p, "u_texture"), 1);
  mesh.draw(glGetUniformLocation(p, "u_textured"));
  glDisable(GL_CULL_FACE);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  if (style.wireframe) {
    const GLuint w = wire_program_.get();
    glUseProgram(w);
    set_matrices(w, view_, projection_);
    glUniform3fv(glGetUniformLocation(w, "u_color"), 1, style.wire_color.data());
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    mesh.draw();
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
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
