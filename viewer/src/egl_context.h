//! \file egl_context.h
//! A windowless OpenGL 3.3 core context through EGL: the Mesa surfaceless platform first
//! (no display server needed), then EGL's default display. Current on the creating thread.
#pragma once

#include <string>

namespace strata::viewer {

class EglContext {
 public:
  //! Creates the context and makes it current.
  //! \throw std::runtime_error naming what failed on every platform tried.
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  //! "surfaceless" or "default": the EGL platform that worked.
  const std::string& platform() const { return platform_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string platform_;
};

}  // namespace strata::viewer
