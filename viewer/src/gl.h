//! \file gl.h
//! The one include point of OpenGL for the viewer (core 3.3 functions through GL_GLEXT_PROTOTYPES;
//! libOpenGL exports them, so no loader is needed), plus error counting and RAII handles.
#pragma once

#include <GL/gl.h>
#include <GL/glext.h>

#include <string>
#include <utility>

namespace strata::viewer {

//! Drains glGetError(); returns how many errors there were and adds them to a process-wide count.
//! \p where names the caller in the message printed to stderr for each error (when verbose).
int check_gl_errors(const char* where);
//! Total GL errors seen by check_gl_errors() since the start.
int gl_error_count();

//! Compiles and links a program from GLSL 330 core sources.
//! \throw std::runtime_error with the info log if compiling or linking fails.
GLuint build_program(const char* vertex_source, const char* fragment_source, const std::string& name);

//! Owns one GL name (buffer, vertex array, program, framebuffer, renderbuffer); deletes it on
//! destruction, which must happen while its context is current. Move-only.
class GlName {
 public:
  using Deleter = void (*)(GLuint);
  GlName() = default;
  GlName(GLuint name, Deleter deleter) : name_(name), deleter_(deleter) {}
  ~GlName() { reset(); }
  GlName(GlName&& o) noexcept : name_(std::exchange(o.name_, 0)), deleter_(o.deleter_) {}
  GlName& operator=(GlName&& o) noexcept {
    if (this != &o) {
      reset();
      name_ = std::exchange(o.name_, 0);
      deleter_ = o.deleter_;
    }
    return *this;
  }
  GlName(const GlName&) = delete;
  GlName& operator=(const GlName&) = delete;
  GLuint get() const { return name_; }
  explicit operator bool() const { return name_ != 0; }
  void reset() {
    if (name_ != 0 && deleter_ != nullptr) deleter_(name_);
    name_ = 0;
  }

 private:
  GLuint name_ = 0;
  Deleter deleter_ = nullptr;
};

GlName make_buffer();
GlName make_vertex_array();
GlName make_program(GLuint program);
GlName make_framebuffer();
GlName make_renderbuffer();
GlName make_texture();

}  // namespace strata::viewer
