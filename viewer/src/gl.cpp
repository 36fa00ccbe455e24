#include "gl.h"

#include <atomic>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace strata::viewer {

namespace {
std::atomic<int> g_errors{0};

const char* error_name(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    default:
      return "GL error";
  }
}

GLuint compile(GLenum type, const char* source, const std::string& name) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<size_t>(len > 1 ? len : 1));
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error("shader '" + name + "' does not compile: " + log.data());
  }
  return s;
}
}  // namespace

int check_gl_errors(const char* where) {
  int n = 0;
  for (GLenum e = glGetError(); e != GL_NO_ERROR && n < 100; e = glGetError()) {
    std::fprintf(stderr, "strata-viewer: GL error %s (0x%x) at %s\n", error_name(e), e, where);
    ++n;
  }
  g_errors += n;
  return n;
}

int gl_error_count() {
  return g_errors.load();
}

GLuint build_program(const char* vertex_source, const char* fragment_source, const std::string& name) {
  GLuint vs = compile(GL_VERTEX_SHADER, vertex_source, name + ".vert");
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment_source, name + ".frag");
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<size_t>(len > 1 ? len : 1));
    glGetProgramInfoLog(p, len, nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error("program '" + name + "' does not link: " + log.data());
  }
  return p;
}

GlName make_buffer() {
  GLuint n = 0;
  glGenBuffers(1, &n);
  return GlName(n, [](GLuint x) { glDeleteBuffers(1, &x); });
}
GlName make_vertex_array() {
  GLuint n = 0;
  glGenVertexArrays(1, &n);
  return GlName(n, [](GLuint x) { glDeleteVertexArrays(1, &x); });
}
GlName make_program(GLuint program) {
  return GlName(program, [](GLuint x) { glDeleteProgram(x); });
}
GlName make_framebuffer() {
  GLuint n = 0;
  glGenFramebuffers(1, &n);
  return GlName(n, [](GLuint x) { glDeleteFramebuffers(1, &x); });
}
GlName make_renderbuffer() {
  GLuint n = 0;
  glGenRenderbuffers(1, &n);
  return GlName(n, [](GLuint x) { glDeleteRenderbuffers(1, &x); });
}

}  // namespace strata::viewer

namespace strata::viewer {
GlName make_texture() {
  GLuint n = 0;
  glGenTextures(1, &n);
  return GlName(n, [](GLuint x) { glDeleteTextures(1, &x); });
}
}  // namespace strata::viewer
