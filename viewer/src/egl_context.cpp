#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <stdexcept>

namespace strata::viewer {

namespace {

// Tries one display; on success fills display and context (current) and returns "".
std::string try_display(EGLDisplay display, EGLDisplay& out_display, EGLContext& out_context) {
  if (display == EGL_NO_DISPLAY) return "no display";
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) return "eglInitialize failed";
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    return "no desktop OpenGL API";
  }
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &count) || count < 1)
    config = nullptr;  // no-config
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                    3,
                                    EGL_CONTEXT_MINOR_VERSION,
                                    3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT) {
    eglTerminate(display);
    char code[32];
    std::snprintf(code, sizeof code, "0x%x", static_cast<unsigned>(eglGetError()));
    return std::string("no OpenGL 3.3 core context (EGL error ") + code + ")";
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    eglTerminate(display);
    return "cannot make the context current without a surface";
  }
  out_display = display;
  out_context = context;
  return "";
}

}  // namespace

EglContext::EglContext() {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string why = try_display(
      eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr), display, context);
  platform_ = "surfaceless";
  if (!why.empty()) {
    const std::string why_default = try_display(eglGetDisplay(EGL_DEFAULT_DISPLAY), display, context);
    if (!why_default.empty())
      throw std::runtime_error("no headless OpenGL context: EGL surfaceless: " + why +
                               "; EGL default: " + why_default);
    platform_ = "default";
  }
  display_ = display;
  context_ = context;
}

EglContext::~EglContext() {
  EGLDisplay display = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  eglTerminate(display);
}

}  // namespace strata::viewer
