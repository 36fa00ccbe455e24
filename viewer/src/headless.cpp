#include "headless.h"

#include <stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "document.h"
#include "egl_context.h"
#include "renderer.h"
#include "scene.h"
#include "strata/atomic_file.h"
#include "strata/edit_script.h"
#include "strata/exceptions.h"
#include "strata/layers/model.h"
#include "strata/mesh_io.h"

namespace strata::viewer {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

//! A framebuffer object of RGBA8 colour and 24-bit depth, multisampled when samples > 0 (then
//! resolved into a single-sample one for reading).
class Offscreen {
 public:
  Offscreen(int width, int height, int samples) : width_(width), height_(height) {
    GLint max_samples = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    samples = std::min(samples, static_cast<int>(max_samples));
    resolve_ = make_target(0);
    draw_ = samples > 0 ? make_target(samples) : Target{};
  }
  void bind() const { glBindFramebuffer(GL_FRAMEBUFFER, draw_.fbo ? draw_.fbo.get() : resolve_.fbo.get()); }
  //! RGBA rows, top row first.
  std::vector<std::uint8_t> read() const {
    if (draw_.fbo) {
      glBindFramebuffer(GL_READ_FRAMEBUFFER, draw_.fbo.get());
      glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_.fbo.get());
      glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_.fbo.get());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    const std::size_t row = 4 * static_cast<std::size_t>(width_);
    std::vector<std::uint8_t> pixels(row * static_cast<std::size_t>(height_));
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    std::vector<std::uint8_t> flipped(pixels.size());
    for (int y = 0; y < height_; ++y)
      std::memcpy(&flipped[row * static_cast<std::size_t>(y)],
                  &pixels[row * static_cast<std::size_t>(height_ - 1 - y)], row);
    return flipped;
  }

 private:
  struct Target {
    GlName fbo, color, depth;
  };
  Target make_target(int samples) const {
    Target t{make_framebuffer(), make_renderbuffer(), make_renderbuffer()};
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.get());
    auto storage = [&](GLuint rb, GLenum format, GLenum attachment) {
      glBindRenderbuffer(GL_RENDERBUFFER, rb);
      if (samples > 0)
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, width_, height_);
      else
        glRenderbufferStorage(GL_RENDERBUFFER, format, width_, height_);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, rb);
    };
    storage(t.color.get(), GL_RGBA8, GL_COLOR_ATTACHMENT0);
    storage(t.depth.get(), GL_DEPTH_COMPONENT24, GL_DEPTH_ATTACHMENT);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("the offscreen framebuffer (" + std::to_string(width_) + "x" +
                               std::to_string(height_) + ", " + std::to_string(samples) +
                               " samples) is incomplete");
    return t;
  }
  int width_, height_;
  Target resolve_, draw_;
};

void write_png(const std::string& path, const std::vector<std::uint8_t>& rgba, int width, int height) {
  write_file_atomically(path, [&](const std::string& tmp) {
    if (!stbi_write_png(tmp.c_str(), width, height, 4, rgba.data(), 4 * width))
      throw IoError(path + ": cannot write the PNG");
  });
}

// The render's outputs (the PNG, --save, --export) are writable and neither the input nor one
// another, before anything is loaded: an export over the input scan, or a screenshot over the
// saved model, replaced it and exited 0 (a review, thirty-eighth session).
void check_outputs(const Options& o) {
  namespace fs = std::filesystem;
  auto same = [](const std::string& a, const std::string& b) {
    std::error_code ec, ec2;
    if (fs::equivalent(a, b, ec)) return true;
    return fs::weakly_canonical(fs::absolute(a, ec2), ec2).lexically_normal() ==
           fs::weakly_canonical(fs::absolute(b, ec2), ec2).lexically_normal();
  };
  const std::vector<std::pair<const char*, const std::string*>> outputs = {
      {"--screenshot", &o.screenshot}, {"--save", &o.save}, {"--export", &o.export_mesh}};
  for (std::size_t a = 0; a < outputs.size(); ++a) {
    const std::string& path = *outputs[a].second;
    if (path.empty()) continue;
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw IoError(path + ": is a directory, expected a file name");
    check_replaceable(path);
    const fs::path dir = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
    if (!fs::is_directory(dir, ec))
      throw IoError(path + ": cannot write: directory " + dir.string() + " does not exist");
    if (same(path, o.input))
      throw InvalidInput(path + ": " + outputs[a].first +
                         " would replace the input; write it to another file");
    for (std::size_t b = a + 1; b < outputs.size(); ++b)
      if (!outputs[b].second->empty() && same(path, *outputs[b].second))
        throw InvalidInput(path + ": " + outputs[a].first + " and " + outputs[b].first +
                           " name the same file");
  }
}

}  // namespace

std::string run_headless(const Options& options) {
  check_outputs(options);
  nlohmann::json report;
  const auto t_load = Clock::now();
  Document document = Document::load(options.input);
  for (const std::string& note : document.load_notes())
    std::cerr << "strata-viewer: note: " << note << std::endl;
  report["load_s"] = seconds_since(t_load);
  if (options.build_bands > 0) {
    const auto t_build = Clock::now();
    document = build_layers(document, options.build_bands);
    report["build_s"] = seconds_since(t_build);
  }
  document.check_band(options.band);
  if (!options.save.empty()) (void)document.model();  // a plain mesh has none: said before the work
  if (options.show >= 0) document.check_band(options.show);
  for (const auto& [k, a] : options.amplitudes) document.check_band(k);

  const auto t_edit = Clock::now();
  int steps = 0;
  for (const std::string& path : options.edits) {
    const EditScript script = read_edit_script(path);
    for (std::size_t i = 0; i < script.edits.size(); ++i) {
      nlohmann::json provenance = {{"source", "strata-viewer"}, {"script", path}, {"step", i}};
      // The script and step behind an engine error, as the CLI names them.
      const std::string where =
          path + ": edit " + std::to_string(i + 1) + " of " + std::to_string(script.edits.size());
      try {
        document.edit(options.band, script.edits[i], provenance.dump());
      } catch (const InvalidInput& e) {
        throw InvalidInput(where + ": " + e.what());
      } catch (const SolverError& e) {
        throw SolverError(where + ": " + e.what());
      }
      ++steps;
    }
  }
  for (const auto& [k, a] : options.amplitudes) document.set_amplitude(k, a);
  report["edit_steps"] = steps;
  report["edit_s"] = seconds_since(t_edit);

  const auto t_scene = Clock::now();
  SceneSettings settings;
  settings.show = options.show;
  settings.vectors = options.vectors;
  settings.color = options.color_given ? options.color : initial_color_mode(document);
  settings.error_scale = options.error_scale;
  settings.cage = options.cage;
  const SceneData scene = make_scene(document, settings);
  report["scene_s"] = seconds_since(t_scene);
  report["band_shown"] = scene.shown_band;
  report["bands"] = document.num_bands();
  report["triangles"] = scene.mesh.num_faces();
  if (options.color == ColorMode::Error) report["max_relative_error"] = scene.max_error;
  if (options.color == ColorMode::Intersections) report["intersecting_pairs"] = scene.intersection_pairs;
  if (scene.texture) {  // faces drawn with an image, and images that could not be decoded
    report["textured_faces"] = std::count_if(scene.texture->face_image.begin(),
                                             scene.texture->face_image.end(), [](int i) { return i >= 0; });
    report["texture_images"] = scene.texture->images.size();
    report["texture_problems"] = scene.texture->problems;
  }

  const auto t_context = Clock::now();
  EglContext context;
  report["context_s"] = seconds_since(t_context);
  report["platform"] = context.platform();
  report["gl_renderer"] = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  std::vector<std::uint8_t> pixels;
  std::vector<double> frame_ms;
  {
    Renderer renderer;
    Offscreen target(options.width, options.height, options.samples);
    const auto t_upload = Clock::now();
    GpuMesh mesh;
    mesh.upload(scene.mesh.vertices, scene.mesh.faces, scene.colors, surface_color(), scene.vertex_colors,
                scene.texture.get());
    GpuLines net;
    if (!scene.net.empty())
      net.upload(scene.net, std::vector<Rgb>(scene.net.size(), Rgb(0.85f, 0.45f, 0.05f)));
    glFinish();
    report["upload_s"] = seconds_since(t_upload);
    check_gl_errors("setup");

    Camera camera;
    Vec3f lo, hi;
    scene_bounds(scene, lo, hi);
    camera.fit(lo, hi);
    camera.set_view(options.view);
    MeshStyle style;
    style.wireframe = options.wireframe;
    style.smooth = options.smooth;
    for (int f = 0; f < options.frames; ++f) {
      const auto t_frame = Clock::now();
      target.bind();
      renderer.begin_frame(options.width, options.height, Rgb(1.0f, 1.0f, 1.0f));
      renderer.set_camera(camera.view(), camera.projection(static_cast<float>(options.width) /
                                                           static_cast<float>(options.height)));
      renderer.draw_mesh(mesh, style);
      if (!net.empty()) renderer.draw_lines(net);
      glFinish();
      frame_ms.push_back(1e3 * seconds_since(t_frame));
      check_gl_errors("frame");
    }
    const auto t_read = Clock::now();
    pixels = target.read();
    report["readback_s"] = seconds_since(t_read);
    check_gl_errors("readback");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  report["frame_ms"] = frame_ms;
  report["gl_errors"] = gl_error_count();
  if (gl_error_count() > 0)
    throw std::runtime_error(std::to_string(gl_error_count()) +
                             " OpenGL errors while rendering (listed above)");
  // The files last, once the render succeeded (a failed render left the model and the mesh
  // written, exiting 1), the PNG after them.
  if (!options.save.empty()) layers::write_model(document.model(), options.save);
  // The shown band's colours, texture coordinates and materials go with it (its vertex numbering).
  if (!options.export_mesh.empty()) {
    std::vector<std::string> notes;  // images named as the format names them (attributes_for_format())
    const MeshAttributes attributes =
        attributes_for_format(document.attributes(scene.shown_band), options.export_mesh, &notes);
    write_mesh(scene.mesh, attributes, options.export_mesh);
    // Its material library and images beside it, but never at the screenshot's path.
    std::error_code ec;
    const auto screenshot = std::filesystem::weakly_canonical(options.screenshot, ec);
    const CompanionWriter write = [&](const std::string& path, const std::string& bytes) {
      std::error_code ec2;
      if (std::filesystem::weakly_canonical(path, ec2) == screenshot)
        std::cerr << "strata-viewer: note: " << path
                  << " is the screenshot; the scan's file of that name is not written" << std::endl;
      else
        write_text_file_atomically(path, bytes);
    };
    for (const std::string& note : write_companion_files(attributes, options.export_mesh, write))
      notes.push_back(note);
    for (const std::string& note : notes) std::cerr << "strata-viewer: note: " << note << std::endl;
  }
  const auto t_write = Clock::now();
  write_png(options.screenshot, pixels, options.width, options.height);
  report["write_s"] = seconds_since(t_write);
  report["size"] = {options.width, options.height};
  report["png"] = options.screenshot;
  return report.dump();
}

}  // namespace strata::viewer
