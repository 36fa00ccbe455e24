#include "app.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <stb_image_write.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "strata/atomic_file.h"
#include "strata/exceptions.h"

namespace strata::viewer {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kPi = 3.14159265358979323846;

App* app_of(GLFWwindow* w) {
  return static_cast<App*>(glfwGetWindowUserPointer(w));
}

// An exception must not unwind through GLFW's C frames: it is shown in the status line.
template <class F>
void guarded(GLFWwindow* w, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    app_of(w)->show_error(e.what());
  }
}
void key_callback(GLFWwindow* w, int key, int, int action, int mods) {
  if (action == GLFW_PRESS && !ImGui::GetIO().WantCaptureKeyboard)
    guarded(w, [&] { app_of(w)->on_key(key, mods); });
}
void scroll_callback(GLFWwindow* w, double, double dy) {
  if (!ImGui::GetIO().WantCaptureMouse) guarded(w, [&] { app_of(w)->on_scroll(dy); });
}
void drop_callback(GLFWwindow* w, int count, const char** paths) {
  if (count > 0) guarded(w, [&] { app_of(w)->on_drop(paths[0]); });
}

void copy_to(std::array<char, 512>& buffer, const std::string& text) {
  std::snprintf(buffer.data(), buffer.size(), "%s", text.c_str());
}

bool ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c, double& t) {
  const Vec3 e1 = b - a, e2 = c - a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return false;
  const double inv = 1.0 / det;
  const Vec3 s = o - a;
  const double u = s.dot(p) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3 q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0 || u + v > 1) return false;
  t = e2.dot(q) * inv;
  return t > 0;
}

}  // namespace

App::App(const Options& options, GLFWwindow* window) : options_(options), window_(window) {
  glfwSetWindowUserPointer(window_, this);
  glfwSetKeyCallback(window_, key_callback);
  glfwSetScrollCallback(window_, scroll_callback);
  glfwSetDropCallback(window_, drop_callback);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  // Installs its callbacks, chained to the ones above.
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  renderer_ = std::make_unique<Renderer>();
  style_.smooth = options.smooth;
  style_.wireframe = options.wireframe;
  view_.vectors = options.vectors;
  view_.color = options.color;
  view_.error_scale = options.error_scale;
  view_.cage = true;
  edit_band_ = options.band;
  copy_to(save_path_, "model.strata");
  copy_to(export_prefix_, "strata_export");

  Document document =
      options.input.empty() ? Document::from_mesh(TriMesh{}, "(none)") : Document::load(options.input);
  for (const std::string& note : document.load_notes())
    std::fprintf(stderr, "strata-viewer: note: %s\n", note.c_str());
  if (options.build_bands > 0) document = build_layers(document, options.build_bands);
  for (const std::string& path : options.edits) {
    const EditScript script = read_edit_script(path);
    for (const EditStep& step : script.edits) document.edit(options.band, step);
  }
  for (const auto& [k, a] : options.amplitudes) document.set_amplitude(k, a);
  document.check_band(edit_band_);
  if (options.show >= 0) {
    document.check_band(options.show);
    view_.visible.assign(static_cast<std::size_t>(document.num_bands()), 0);
    view_.visible[static_cast<std::size_t>(options.show)] = 1;
  }
  if (!options.script_drag.empty()) script_ = read_edit_script(options.script_drag);
  if (!options.color_given) view_.color = initial_color_mode(document);
  copy_to(open_path_, options.input);
  worker_ = std::make_unique<Worker>(std::move(document), view_);
  push_view();
}

App::~App() {
  worker_.reset();  // joins the thread before the GL objects go
  panels_.clear();
  selection_points_ = GpuLines();
  gizmo_lines_ = GpuLines();
  renderer_.reset();
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

void App::push_view() {
  worker_->set_view(view_);
}

int App::run() {
  const bool scripted = !options_.script_drag.empty();
  while (!glfwWindowShouldClose(window_)) {
    const auto t0 = Clock::now();
    frame();
    ++frames_;
    if (scripted) {
      frame_ms_.push_back(1e3 * std::chrono::duration<double>(Clock::now() - t0).count());
      frame_in_drag_.push_back(dragging_ ? 1 : 0);
      bool coloured = false, textured = false;
      for (const auto& p : panels_) {
        coloured = coloured || p->mesh.color_mode() == 1;
        textured = textured || p->mesh.color_mode() == 3;
      }
      frame_scan_colours_.push_back(coloured ? 1 : 0);
      frame_texture_.push_back(textured ? 1 : 0);
      frame_drag_step_.push_back(showing_drag_step_ ? 1 : 0);
      if (script_done_) break;
    }
  }
  if (scripted && options_.benchmark) {
    nlohmann::json r;
    std::vector<double> drag_ms, all = frame_ms_;
    for (std::size_t i = 0; i < frame_ms_.size(); ++i)
      if (frame_in_drag_[i]) drag_ms.push_back(frame_ms_[i]);
    auto stats = [](std::vector<double> v) {
      nlohmann::json s;
      if (v.empty()) return s;
      std::sort(v.begin(), v.end());
      double sum = 0;
      for (double x : v) sum += x;
      s["count"] = v.size();
      s["mean_ms"] = sum / static_cast<double>(v.size());
      s["median_ms"] = v[v.size() / 2];
      s["p95_ms"] = v[std::min(v.size() - 1, static_cast<std::size_t>(0.95 * static_cast<double>(v.size())))];
      s["max_ms"] = v.back();
      return s;
    };
    r["frames"] = stats(all);
    r["drag_frames"] = stats(drag_ms);
    // Frames that showed a drag step's preview, and of those the ones that drew the scan's own
    // colours (--color scan keeps them on during drags), or its texture (--color texture).
    long long previews = 0, coloured = 0, textured = 0;
    for (std::size_t i = 0; i < frame_ms_.size(); ++i) {
      previews += frame_drag_step_[i];
      coloured += frame_drag_step_[i] && frame_scan_colours_[i];
      textured += frame_drag_step_[i] && frame_texture_[i];
    }
    r["preview_frames"] = previews;
    r["preview_frames_scan_colours"] = coloured;
    r["preview_frames_texture"] = textured;
    r["drag_steps_solved"] = worker_->drag_steps();
    r["drag_step_mean_s"] =
        worker_->drag_seconds() / static_cast<double>(std::max(1LL, worker_->drag_steps()));
    r["triangles"] = 0;
    for (const auto& p : panels_) r["triangles"] = r["triangles"].get<int>() + p->mesh.triangles();
    r["gl_errors"] = gl_error_count();
    const double n = static_cast<double>(std::max<std::size_t>(frame_ms_.size(), 1));
    r["phase_mean_ms"] = {{"snapshot", 1e3 * phase_s_[0] / n},
                          {"ui", 1e3 * phase_s_[1] / n},
                          {"scene", 1e3 * phase_s_[2] / n},
                          {"imgui_draw", 1e3 * phase_s_[3] / n},
                          {"swap", 1e3 * phase_s_[4] / n}};
    r["frame_ms"] = frame_ms_;
    r["status"] = status_;
    std::cout << r.dump() << std::endl;
  }
  if (gl_error_count() > 0)
    throw std::runtime_error(std::to_string(gl_error_count()) + " OpenGL errors (listed above)");
  if (scripted && status_error_) throw std::runtime_error(status_);
  return 0;
}

void App::frame() {
  const bool timing = options_.benchmark;
  auto t = Clock::now();
  auto lap = [&](int phase) {
    if (!timing) return;  // CPU-side times: the GPU work of a frame lands in the swap
    const auto now = Clock::now();
    phase_s_[static_cast<std::size_t>(phase)] += std::chrono::duration<double>(now - t).count();
    t = now;
  };
  glfwPollEvents();
  // Idle before the snapshot is taken: then every job's snapshot is in it, and a file still
  // opening failed (its error is the snapshot's message).
  const bool idle = !worker_->busy();
  take_snapshot();
  take_checkpoints();
  if (idle) opening_.clear();
  if (!options_.script_drag.empty()) run_script_step();
  lap(0);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  try {  // a bad pick or brush (the selection's band gone) is shown, not fatal
    handle_mouse();
  } catch (const std::exception& e) {
    show_error(e.what());
  }
  draw_ui();
  ImGui::Render();
  lap(1);
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  draw_scene(width, height);
  lap(2);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  lap(3);
  check_gl_errors("frame");
  if (script_done_ && !options_.screenshot.empty()) {
    std::vector<unsigned char> pixels(4 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    std::vector<unsigned char> flipped(pixels.size());
    const std::size_t row = 4 * static_cast<std::size_t>(width);
    for (int y = 0; y < height; ++y)
      std::memcpy(&flipped[row * static_cast<std::size_t>(y)],
                  &pixels[row * static_cast<std::size_t>(height - 1 - y)], row);
    write_file_atomically(options_.screenshot, [&](const std::string& tmp) {
      if (!stbi_write_png(tmp.c_str(), width, height, 4, flipped.data(), static_cast<int>(row)))
        throw IoError(options_.screenshot + ": cannot write the PNG");
    });
  }
  glfwSwapBuffers(window_);
  lap(4);
}

void App::set_committed(std::shared_ptr<const Document> document) {
  committed_ = std::move(document);
  amplitudes_.assign(static_cast<std::size_t>(committed_->num_bands()), 1.0f);
  for (int k = 0; k < committed_->num_bands(); ++k)
    amplitudes_[static_cast<std::size_t>(k)] = static_cast<float>(committed_->amplitude(k));
  edit_band_ = std::clamp(edit_band_, 0, committed_->num_bands() - 1);
  update_selection_points();
}

void App::take_snapshot() {
  std::optional<Snapshot> s = worker_->take(version_);
  if (!s) return;
  version_ = s->version;
  showing_drag_step_ = s->drag_step;
  if (!s->message.empty()) {
    status_ = s->message;
    status_error_ = s->error;
  }
  const bool message_only = s->message_only;
  if (s->committed) {
    if (!committed_) first_picture_frame_ = frames_;
    const bool opened = !opening_.empty() && s->committed->name() == opening_;
    if (opened) {  // another document: the old one's selection and layout do not apply
      region_set_ = handle_set_ = false;
      clear_brush();
      selection_points_ = GpuLines();
      view_.visible.clear();
      fitted_ = false;
    }
    set_committed(s->committed);
    if (opened) {
      opening_.clear();
      const ColorMode initial = initial_color_mode(*committed_);
      if (initial == ColorMode::Scan || initial == ColorMode::Texture || view_.color == ColorMode::Scan ||
          view_.color == ColorMode::Texture) {
        view_.color = initial;
        push_view();
      }
    }
  }
  if (message_only) return;  // the worker could not make the scenes: the panels stay
  // Same panels and connectivity: move the vertices only; else upload anew. The same bands at the
  // same sizes (a colour map changed) are uploaded anew, but the camera stays where the user put
  // it (it refitted on every colour change).
  auto panels_match = [&](bool colours) {
    return s->panels.size() == panels_.size() &&
           std::equal(s->panels.begin(), s->panels.end(), panels_.begin(),
                      [&](const SceneData& a, const std::unique_ptr<Panel>& b) {
                        const bool layout = a.shown_band == b->band &&
                                            a.mesh.faces.size() == b->scene.mesh.faces.size() &&
                                            a.mesh.vertices.size() == b->scene.mesh.vertices.size();
                        return layout &&
                               (!colours ||
                                ((a.colors.empty() && !a.texture) == (b->mesh.color_mode() == 0) &&
                                 a.vertex_colors == b->scene.vertex_colors && a.texture == b->scene.texture &&
                                 (!a.vertex_colors || a.colors == b->scene.colors) &&
                                 (a.mesh.faces.empty() || a.mesh.faces[0] == b->scene.mesh.faces[0])));
                      });
  };
  const bool same_layout = panels_match(false), same = same_layout && panels_match(true);
  if (!same) panels_.clear();
  for (std::size_t i = 0; i < s->panels.size(); ++i) {
    if (!same) panels_.push_back(std::make_unique<Panel>());
    Panel& p = *panels_[i];
    p.scene = std::move(s->panels[i]);
    p.band = p.scene.shown_band;
    p.vectors = view_.compare && i + 1 == s->panels.size() && !view_.vectors && s->panels.size() > 1;
    if (!same && p.scene.texture &&
        !p.scene.texture->problems.empty()) {  // drawn in the surface colour instead
      status_ = "texture image not drawn: " + p.scene.texture->problems.front();
      status_error_ = true;
    }
    // The scan's colours (per vertex) or texture are already on the GPU when they are the same:
    // positions only.
    if (same && (p.scene.colors.empty() || p.scene.vertex_colors))
      p.mesh.update_positions(p.scene.mesh.vertices, p.scene.mesh.faces);
    else
      p.mesh.upload(p.scene.mesh.vertices, p.scene.mesh.faces, p.scene.colors, surface_color(),
                    p.scene.vertex_colors, p.scene.texture.get());
    if (!p.scene.net.empty())
      p.net.upload(p.scene.net, std::vector<Rgb>(p.scene.net.size(), Rgb(0.95f, 0.5f, 0.05f)));
    else
      p.net = GpuLines();
  }
  layout_panels(!same || !fitted_, !same_layout || !fitted_);
}

void App::layout_panels(bool refit, bool camera) {
  // Side by side along x, in panel order, with a gap of 10% of the widest.
  double x = 0, widest = 0;
  std::vector<std::pair<Vec3, Vec3>> boxes;
  for (const auto& p : panels_) {
    Vec3f lo, hi;
    scene_bounds(p->scene, lo, hi);
    boxes.push_back({lo.cast<double>(), hi.cast<double>()});
    widest = std::max(widest, static_cast<double>(hi.x() - lo.x()));
  }
  if (!refit) return;
  Vec3f all_lo = Vec3f::Constant(1e30f), all_hi = Vec3f::Constant(-1e30f);
  for (std::size_t i = 0; i < panels_.size(); ++i) {
    const auto& [lo, hi] = boxes[i];
    panels_[i]->offset = Vec3(x - lo.x(), 0, 0);
    all_lo = all_lo.cwiseMin((lo + panels_[i]->offset).cast<float>());
    all_hi = all_hi.cwiseMax((hi + panels_[i]->offset).cast<float>());
    x += (hi.x() - lo.x()) + 0.1 * widest;
  }
  if (!panels_.empty() && !fitted_) {
    camera_.fit(all_lo, all_hi);
    camera_.set_view(options_.view);
    fitted_ = true;
  } else if (!panels_.empty() && camera) {
    camera_.fit(all_lo, all_hi);
  }
}

void App::fit_view() {
  fitted_ = false;
  layout_panels(true);
}

bool App::pick(double x, double y, Vec3& hit) const {
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  Vec3f of, df;
  camera_.ray(static_cast<float>(x), static_cast<float>(y), static_cast<float>(w), static_cast<float>(h), of,
              df);
  const Vec3 o = of.cast<double>(), d = df.cast<double>();
  double best = std::numeric_limits<double>::infinity();
  // On the edited band's panel if it is shown, else on any band (they share one frame).
  bool shown = false;
  for (const auto& p : panels_) shown = shown || (p->band == edit_band_ && !p->vectors);
  for (const auto& p : panels_) {
    if ((shown && p->band != edit_band_) || p->vectors) continue;
    const auto& v = p->scene.mesh.vertices;
    for (const Face& f : p->scene.mesh.faces) {
      double t = 0;
      if (ray_triangle(o, d, v[f[0]] + p->offset, v[f[1]] + p->offset, v[f[2]] + p->offset, t) && t < best) {
        best = t;
        hit = o + t * d - p->offset;
      }
    }
  }
  return std::isfinite(best);
}

void App::handle_mouse() {
  ImGuiIO& io = ImGui::GetIO();
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x;
  last_y_ = y;
  if (scroll_ != 0) {
    camera_.zoom(static_cast<float>(scroll_));
    scroll_ = 0;
  }
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  if (drag_button_ < 0) {
    gizmo_hover_ = -1;
    if (io.WantCaptureMouse) return;
    gizmo_hover_ = gizmo_hit(x, y);
    for (int b : {GLFW_MOUSE_BUTTON_LEFT, GLFW_MOUSE_BUTTON_RIGHT, GLFW_MOUSE_BUTTON_MIDDLE}) {
      if (glfwGetMouseButton(window_, b) == GLFW_PRESS) {
        drag_button_ = b;
        press_x_ = x;
        press_y_ = y;
        drag_mods_ = (glfwGetKey(window_, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ? GLFW_MOD_CONTROL : 0) |
                     (glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ? GLFW_MOD_SHIFT : 0);
        if (b == GLFW_MOUSE_BUTTON_LEFT && brush_) {
          // painted below, every frame of the drag
        } else if (b == GLFW_MOUSE_BUTTON_LEFT && drag_mods_ == 0 && (gizmo_hover_ = gizmo_hit(x, y)) >= 0) {
          gizmo_begin();
          if (dragging_) {
            gizmo_part_ = gizmo_hover_;
            if (gizmo_part_ >= 3) axis_ = gizmo_part_ - 3;
          }
        } else if (b == GLFW_MOUSE_BUTTON_LEFT && drag_mods_ != 0 && region_ready() && handle_ready()) {
          const Mat4 v = camera_.view();
          view_axis_ = -v.block<1, 3>(2, 0).transpose().cast<double>();
          axis_ = drag_mods_ & GLFW_MOD_SHIFT ? 3 : axis_;
          gizmo_begin();
        }
        break;
      }
    }
    return;
  }
  if (glfwGetMouseButton(window_, drag_button_) != GLFW_PRESS) {
    const bool click = std::abs(x - press_x_) + std::abs(y - press_y_) < 4;
    if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && dragging_) {
      gizmo_end();
    } else if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && brush_) {
      // the brush painted during the drag
    } else if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && click && pick_ != Pick::None) {
      Vec3 hit;
      if (pick(x, y, hit)) {
        if (pick_ == Pick::Region) {
          region_center_ = hit;
          region_set_ = true;
          if (region_radius_ <= 0) region_radius_ = 0.25f * camera_.radius();
        } else {
          handle_center_ = hit;
          handle_set_ = true;
          if (handle_radius_ <= 0) handle_radius_ = 0.08f * camera_.radius();
        }
        update_selection_points();
      }
    }
    drag_button_ = -1;
    return;
  }
  if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && dragging_) {
    const float world_per_pixel =
        2.0f * camera_.distance() * std::tan(0.5f * 0.61f) / static_cast<float>(std::max(h, 1));
    if (gizmo_part_ >= 0) {
      gizmo_mouse(x, y, dx, dy);
    } else if (drag_mods_ & GLFW_MOD_SHIFT) {
      angle_ = std::clamp(angle_ + static_cast<float>(dx) * 0.5f, -180.0f, 180.0f);
    } else {
      const Mat4 v = camera_.view();
      const Vec3f right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
      const Vec3f delta = world_per_pixel * (static_cast<float>(dx) * right - static_cast<float>(dy) * up);
      for (int k = 0; k < 3; ++k) translation_[static_cast<std::size_t>(k)] += delta[k];
    }
    if (dx != 0 || dy != 0) gizmo_update();
  } else if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT && brush_) {
    Vec3 hit;
    if (pick(x, y, hit)) brush_at(hit, drag_mods_ & GLFW_MOD_SHIFT, drag_mods_ & GLFW_MOD_CONTROL);
  } else if (drag_button_ == GLFW_MOUSE_BUTTON_LEFT) {
    camera_.orbit(static_cast<float>(dx), static_cast<float>(dy));
  } else {
    camera_.pan(static_cast<float>(dx), static_cast<float>(dy), static_cast<float>(h));
  }
}

void App::draw_scene(int width, int height) {
  renderer_->begin_frame(width, height, Rgb(0.16f, 0.17f, 0.19f));
  const Mat4 view = camera_.view();
  const Mat4 projection =
      camera_.projection(static_cast<float>(width) / static_cast<float>(std::max(height, 1)));
  for (const auto& p : panels_) {
    Mat4 model = Mat4::Identity();
    model.block<3, 1>(0, 3) = p->offset.cast<float>();
    renderer_->set_camera(view * model, projection);
    renderer_->draw_mesh(p->mesh, style_);
    if (!p->net.empty()) renderer_->draw_lines(p->net);
    if (p->band == edit_band_ && !p->vectors && !selection_points_.empty() && !dragging_)
      renderer_->draw_points(selection_points_, 6.0f);
  }
  // The gizmo, over everything (no depth test); the hovered or dragged part in yellow.
  const auto parts = gizmo_parts();
  if (parts.empty()) return;
  std::vector<Vec3> segments;
  std::vector<Rgb> colors;
  const int lit = gizmo_part_ >= 0 ? gizmo_part_ : gizmo_hover_;
  for (const auto& [part, line] : parts) {
    Rgb color = Rgb::Constant(0.15f);
    color[part % 3] = 0.95f;
    if (part == lit) color = Rgb(1.0f, 0.9f, 0.1f);
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
      segments.push_back(line[i]);
      segments.push_back(line[i + 1]);
      colors.push_back(color);
      colors.push_back(color);
    }
  }
  gizmo_lines_.upload(segments, colors);
  renderer_->set_camera(view, projection);
  glDisable(GL_DEPTH_TEST);
  renderer_->draw_lines(gizmo_lines_);
  glEnable(GL_DEPTH_TEST);
}

void App::update_selection_points() {
  selection_points_ = GpuLines();
  if (!committed_ || (!region_ready() && !handle_ready())) return;
  try {
    gizmo_pivot_ = handle_pivot();
    const std::vector<Vec3>& points = committed_->band_points(edit_band_);
    std::vector<char> in_region, in_handle;
    if (!selection_flags(in_region, in_handle)) return;
    std::vector<Vec3> p;
    std::vector<Rgb> c;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (in_handle[i] && (in_region[i] || brush_handle_any_)) {
        p.push_back(points[i]);
        c.push_back(Rgb(0.95f, 0.1f, 0.1f));
      } else if (in_region[i]) {
        p.push_back(points[i]);
        c.push_back(Rgb(0.95f, 0.85f, 0.1f));
      }
    }
    if (!p.empty()) selection_points_.upload(p, c);
  } catch (const std::exception& e) {
    status_ = e.what();
    status_error_ = true;
  }
}

bool App::selection_flags(std::vector<char>& region, std::vector<char>& handle) const {
  if (!committed_) return false;
  const std::vector<Vec3>& points = committed_->band_points(edit_band_);
  region.assign(points.size(), 0);
  handle.assign(points.size(), 0);
  if (region_set_) region = select_vertices(points, Selection::sphere(region_center_, region_radius_));
  if (handle_set_) handle = select_vertices(points, Selection::sphere(handle_center_, handle_radius_));
  const bool brushed = brushed_band();
  for (std::size_t i = 0; brushed && i < points.size(); ++i) {
    region[i] = region[i] || brush_region_[i];
    handle[i] = handle[i] || brush_handle_[i];
  }
  return true;
}

bool App::brushed_band() const {
  return committed_ && brush_band_ == edit_band_ &&
         brush_region_.size() == committed_->band_points(edit_band_).size();
}

bool App::region_ready() const {
  return region_set_ || (brushed_band() && brush_region_any_);
}

bool App::handle_ready() const {
  return handle_set_ || (brushed_band() && brush_handle_any_);
}

namespace {
Selection indices_of(const std::vector<char>& flags) {
  std::vector<int> indices;
  for (std::size_t i = 0; i < flags.size(); ++i)
    if (flags[i]) indices.push_back(static_cast<int>(i));
  return Selection::vertices(std::move(indices));
}
}  // namespace

Selection App::region_selection() const {
  if (!(brushed_band() && brush_region_any_)) return Selection::sphere(region_center_, region_radius_);
  std::vector<char> region, handle;
  selection_flags(region, handle);
  return indices_of(region);
}

Selection App::handle_selection() const {
  if (!(brushed_band() && brush_handle_any_)) return Selection::sphere(handle_center_, handle_radius_);
  std::vector<char> region, handle;
  selection_flags(region, handle);
  return indices_of(handle);
}

Vec3 App::handle_pivot() const {
  if (handle_set_ || !committed_) return handle_center_;
  std::vector<char> region, handle;
  if (!selection_flags(region, handle)) return handle_center_;
  const std::vector<Vec3>& points = committed_->band_points(edit_band_);
  Vec3 sum = Vec3::Zero();
  double n = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (handle[i]) sum += points[i], n += 1;
  return n > 0 ? Vec3(sum / n) : handle_center_;
}

void App::clear_brush() {
  brush_region_.clear();
  brush_handle_.clear();
  brush_band_ = -1;
  brush_region_any_ = brush_handle_any_ = false;
}

void App::brush_at(const Vec3& hit, bool handle, bool erase) {
  if (!committed_) return;
  const std::vector<Vec3>& points = committed_->band_points(edit_band_);
  if (brush_band_ != edit_band_ || brush_region_.size() != points.size()) {
    clear_brush();
    brush_band_ = edit_band_;
    brush_region_.assign(points.size(), 0);
    brush_handle_.assign(points.size(), 0);
  }
  if (brush_radius_ <= 0) brush_radius_ = 0.04f * camera_.radius();
  const double r2 = static_cast<double>(brush_radius_) * brush_radius_;
  bool changed = false;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if ((points[i] - hit).squaredNorm() > r2) continue;
    if (erase) {
      changed |= brush_region_[i] || brush_handle_[i];
      brush_region_[i] = brush_handle_[i] = 0;
    } else {
      // The handle is part of the region: painting it paints both.
      changed |= !brush_region_[i] || (handle && !brush_handle_[i]);
      brush_region_[i] = 1;
      if (handle) brush_handle_[i] = 1;
    }
  }
  if (!changed) return;
  brush_region_any_ = std::find(brush_region_.begin(), brush_region_.end(), 1) != brush_region_.end();
  brush_handle_any_ = std::find(brush_handle_.begin(), brush_handle_.end(), 1) != brush_handle_.end();
  update_selection_points();
}

EditTransform App::gizmo_transform() const {
  Vec3 axis = axis_ == 3 ? view_axis_ : Vec3::Unit(axis_);
  return EditTransform::rotation(axis, angle_, pivot_,
                                 Vec3(translation_[0], translation_[1], translation_[2]));
}

void App::gizmo_begin() {
  if (dragging_ || !region_ready() || !handle_ready()) return;
  checkpoint();
  translation_ = {0, 0, 0};
  angle_ = 0;
  pivot_ = gizmo_pivot_ = handle_pivot();
  try {
    worker_->begin_drag(edit_band_, region_selection(), handle_selection());
  } catch (const std::exception& e) {
    status_ = e.what();
    status_error_ = true;
    return;
  }
  dragging_ = true;
}

bool App::gizmo_frame(Vec3& center, double& size) const {
  if (brush_ || !region_ready() || !handle_ready()) return false;
  const Panel* panel = nullptr;
  for (const auto& p : panels_)
    if (p->band == edit_band_ && !p->vectors) panel = p.get();
  if (panel == nullptr) return false;
  center = (dragging_ ? gizmo_transform().apply(pivot_) : gizmo_pivot_) + panel->offset;
  if (!center.allFinite()) return false;
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  const double distance = (center - camera_.eye().cast<double>()).norm();
  // About 90 pixels long at any zoom.
  size = 90.0 * 2.0 * distance * std::tan(0.5 * 0.61) / std::max(h, 1);
  return size > 0;
}

std::vector<std::pair<int, std::vector<Vec3>>> App::gizmo_parts() const {
  std::vector<std::pair<int, std::vector<Vec3>>> parts;
  Vec3 c;
  double size = 0;
  if (!gizmo_frame(c, size)) return parts;
  for (int a = 0; a < 3; ++a) {
    const Vec3 e = Vec3::Unit(a), u = Vec3::Unit((a + 1) % 3), v = Vec3::Unit((a + 2) % 3);
    const Vec3 tip = c + size * e;
    // Shaft and a four-line arrow head.
    parts.push_back({a, {c + 0.25 * size * e, tip}});
    for (const Vec3& side : {u, Vec3(-u), v, Vec3(-v)})
      parts.push_back({a, {tip, tip - 0.15 * size * e + 0.06 * size * side}});
    std::vector<Vec3> ring;
    for (int i = 0; i <= 48; ++i) {
      const double t = 2.0 * kPi * i / 48.0;
      ring.push_back(c + 0.7 * size * (std::cos(t) * u + std::sin(t) * v));
    }
    parts.push_back({3 + a, std::move(ring)});
  }
  return parts;
}

bool App::to_screen(const Vec3& world, double& x, double& y) const {
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  const Mat4 m =
      camera_.projection(static_cast<float>(w) / static_cast<float>(std::max(h, 1))) * camera_.view();
  const Eigen::Vector4f clip =
      m * Eigen::Vector4f(static_cast<float>(world.x()), static_cast<float>(world.y()),
                          static_cast<float>(world.z()), 1.0f);
  if (clip.w() <= 1e-6f) return false;
  x = 0.5 * (clip.x() / clip.w() + 1.0) * w;
  y = 0.5 * (1.0 - clip.y() / clip.w()) * h;
  return true;
}

int App::gizmo_hit(double x, double y) const {
  int best = -1;
  double best_d = 8.0;
  for (const auto& [part, line] : gizmo_parts()) {
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
      double ax = 0, ay = 0, bx = 0, by = 0;
      if (!to_screen(line[i], ax, ay) || !to_screen(line[i + 1], bx, by)) continue;
      const double vx = bx - ax, vy = by - ay, len2 = vx * vx + vy * vy;
      const double t = len2 > 0 ? std::clamp(((x - ax) * vx + (y - ay) * vy) / len2, 0.0, 1.0) : 0.0;
      const double d = std::hypot(x - ax - t * vx, y - ay - t * vy);
      // Arrows win over rings where they cross (an edge-on ring lies along an arrow).
      const bool better = best < 0 || (part < 3) == (best < 3) ? d < best_d : part < 3;
      if (d < 8.0 && better) {
        best_d = d;
        best = part;
      }
    }
  }
  return best;
}

void App::gizmo_mouse(double x, double y, double dx, double dy) {
  Vec3 c;
  double size = 0, cx = 0, cy = 0;
  if (!gizmo_frame(c, size) || !to_screen(c, cx, cy)) return;
  const int a = gizmo_part_ % 3;
  const Vec3 e = Vec3::Unit(a);
  if (gizmo_part_ < 3) {
    // Along the arrow's screen direction: the world distance its pixels stand for.
    double tx = 0, ty = 0;
    if (!to_screen(c + size * e, tx, ty)) return;
    const double sx = tx - cx, sy = ty - cy, len2 = sx * sx + sy * sy;
    if (len2 < 4.0) return;  // the axis points at the eye
    const double amount = (dx * sx + dy * sy) / len2 * size;
    translation_[static_cast<std::size_t>(a)] += static_cast<float>(amount);
  } else {
    const double a0 = std::atan2(y - dy - cy, x - dx - cx), a1 = std::atan2(y - cy, x - cx);
    double delta = a1 - a0;
    if (delta > kPi) delta -= 2 * kPi;
    if (delta < -kPi) delta += 2 * kPi;
    // Screen y is down: a growing atan2 turns clockwise on screen, negative about an axis
    // that faces the eye.
    const bool facing = e.dot(camera_.eye().cast<double>() - c) > 0;
    const double degrees = -delta * 180.0 / kPi * (facing ? 1.0 : -1.0);
    angle_ = std::clamp(angle_ + static_cast<float>(degrees), -180.0f, 180.0f);
  }
}

void App::gizmo_update() {
  if (dragging_) worker_->update_drag(gizmo_transform());
}

void App::gizmo_end() {
  gizmo_part_ = -1;
  if (!dragging_) return;
  worker_->end_drag();
  dragging_ = false;
  // The next drag starts from the identity (the sliders' next drag re-applied this one's).
  translation_ = {0, 0, 0};
  angle_ = 0;
}

void App::checkpoint() {
  if (!committed_) return;
  // Recorded by the worker when it gets there (take_checkpoints()): committed_ is older while a
  // job is queued or runs.
  worker_->checkpoint();  // redo_ is cleared once it arrives (take_checkpoints())
}

void App::take_checkpoints() {
  for (std::shared_ptr<const Document>& d : worker_->take_checkpoints()) {
    if (!d) {  // a cancelled drag's
      if (!undo_.empty()) undo_.pop_back();
      continue;
    }
    undo_.push_back(std::move(d));
    if (undo_.size() > 32) undo_.erase(undo_.begin());
    // A new step: what was undone before it is gone. Cleared here, not when the checkpoint was
    // asked for: a drag that failed to start drops its checkpoint and keeps the redo stack.
    redo_.clear();
  }
}

void App::undo() {
  if (dragging_ || worker_->busy()) return;
  // A job that finished since this frame's snapshot was taken (the key callbacks run first):
  // its commit is committed_ before the undo, not after it (the UI and the worker went apart; a
  // review, thirty-eighth session).
  take_snapshot();
  take_checkpoints();  // one the worker recorded since this frame took them
  if (undo_.empty()) return;
  redo_.push_back(committed_);
  // Through set_committed(): the band to edit, the amplitudes and the selection follow the
  // document (a brush stroke after undoing a build read band 2 of a one-band mesh and ended the
  // program).
  set_committed(undo_.back());
  undo_.pop_back();
  worker_->replace(*committed_);
  status_ = "undo";
  status_error_ = false;
}

void App::redo() {
  if (dragging_ || worker_->busy()) return;
  take_snapshot();  // as undo()
  take_checkpoints();
  if (redo_.empty()) return;
  undo_.push_back(committed_);
  set_committed(redo_.back());
  redo_.pop_back();
  worker_->replace(*committed_);
  status_ = "redo";
  status_error_ = false;
}

void App::on_key(int key, int mods) {
  const bool ctrl = mods & GLFW_MOD_CONTROL;
  switch (key) {
    case GLFW_KEY_F1:
      show_help_ = !show_help_;
      break;
    case GLFW_KEY_F:
      fit_view();
      break;
    case GLFW_KEY_1:
      camera_.set_view(ViewPreset::Front);
      break;
    case GLFW_KEY_2:
      camera_.set_view(ViewPreset::Back);
      break;
    case GLFW_KEY_3:
      camera_.set_view(ViewPreset::Left);
      break;
    case GLFW_KEY_4:
      camera_.set_view(ViewPreset::Right);
      break;
    case GLFW_KEY_5:
      camera_.set_view(ViewPreset::Top);
      break;
    case GLFW_KEY_6:
      camera_.set_view(ViewPreset::Bottom);
      break;
    case GLFW_KEY_7:
      camera_.set_view(ViewPreset::Iso);
      break;
    case GLFW_KEY_W:
      style_.wireframe = !style_.wireframe;
      break;
    case GLFW_KEY_S:
      if (ctrl) {
        worker_->save(save_path_.data());
      } else {
        style_.smooth = !style_.smooth;
      }
      break;
    case GLFW_KEY_C:
      view_.cage = !view_.cage, push_view();
      break;
    case GLFW_KEY_V:
      view_.vectors = !view_.vectors, push_view();
      break;
    case GLFW_KEY_B:
      view_.compare = !view_.compare, push_view();
      break;
    case GLFW_KEY_E:
      if (ctrl) {
        worker_->export_meshes(export_prefix_.data(), export_format_ == 0   ? ".obj"
                                                      : export_format_ == 1 ? ".ply"
                                                                            : ".off");
      } else {
        view_.color = view_.color == ColorMode::Error ? ColorMode::None : ColorMode::Error;
        push_view();
      }
      break;
    case GLFW_KEY_I:
      view_.color = view_.color == ColorMode::Intersections ? ColorMode::None : ColorMode::Intersections;
      push_view();
      break;
    case GLFW_KEY_K:
      view_.color = view_.color == ColorMode::Scan ? ColorMode::None : ColorMode::Scan;
      push_view();
      break;
    case GLFW_KEY_T:
      view_.color = view_.color == ColorMode::Texture ? ColorMode::None : ColorMode::Texture;
      push_view();
      break;
    case GLFW_KEY_R:
      pick_ = pick_ == Pick::Region ? Pick::None : Pick::Region;
      brush_ = false;
      break;
    case GLFW_KEY_H:
      pick_ = pick_ == Pick::Handle ? Pick::None : Pick::Handle;
      brush_ = false;
      break;
    case GLFW_KEY_P:
      brush_ = !brush_;
      if (brush_) pick_ = Pick::None;
      break;
    case GLFW_KEY_Z:
      if (ctrl && (mods & GLFW_MOD_SHIFT))
        redo();
      else if (ctrl)
        undo();
      break;
    case GLFW_KEY_Y:
      if (ctrl) redo();
      break;
    case GLFW_KEY_ESCAPE:
      if (dragging_) {
        worker_->cancel_drag();  // drops the drag's checkpoint (take_checkpoints())
        dragging_ = false;
        translation_ = {0, 0, 0};
        angle_ = 0;
      }
      gizmo_part_ = -1;
      pick_ = Pick::None;
      brush_ = false;
      break;
    default:
      break;
  }
}

void App::on_scroll(double dy) {
  scroll_ += dy;
}

void App::on_drop(const std::string& path) {
  if (dragging_) return;
  checkpoint();
  copy_to(open_path_, path);
  opening_ = path;  // the selection and the view change once it is in (take_snapshot())
  worker_->load(path);
}

void App::run_script_step() {
  // Each edit step: begin, options.frames update steps (one per frame, the worker taking the
  // newest), end; then frames until the worker is idle.
  // Starts once the first picture is up (its upload and shader compiles are not drag frames): 3
  // frames in, and 2 after the frame that uploaded it.
  if (script_done_ || !committed_ || frames_ < 3 || frames_ < first_picture_frame_ + 2) return;
  if (script_waiting_) {
    if (!worker_->busy()) {
      script_waiting_ = false;
      ++script_step_;
      script_frame_ = 0;
    }
    return;
  }
  if (script_step_ >= script_.edits.size()) {
    // One more frame after the last snapshot so the final picture is drawn.
    script_done_ = true;
    return;
  }
  const EditStep& step = script_.edits[script_step_];
  if (script_frame_ == 0) {
    checkpoint();
    worker_->begin_drag(edit_band_, step.region, step.handle);
    dragging_ = true;
  }
  ++script_frame_;
  worker_->update_drag(step.transform.partial(static_cast<double>(script_frame_) / options_.frames));
  // Orbit a little so every frame draws a new view, as a user's camera would.
  camera_.orbit(2.0f, 0.0f);
  if (script_frame_ >= options_.frames) {
    worker_->end_drag();
    dragging_ = false;
    script_waiting_ = true;
  }
}

int run_window(const Options& options) {
  glfwSetErrorCallback(
      [](int code, const char* text) { std::fprintf(stderr, "strata-viewer: GLFW %d: %s\n", code, text); });
  if (!glfwInit())
    throw std::runtime_error("cannot initialize GLFW (no display? use --screenshot for headless renders)");
  struct Terminate {
    ~Terminate() { glfwTerminate(); }
  } terminate;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  const std::string title = "strata-viewer" + (options.input.empty() ? std::string() : " - " + options.input);
  GLFWwindow* window = glfwCreateWindow(options.width, options.height, title.c_str(), nullptr, nullptr);
  if (window == nullptr) throw std::runtime_error("cannot create an OpenGL 3.3 core window");
  struct Destroy {
    GLFWwindow* w;
    ~Destroy() { glfwDestroyWindow(w); }
  } destroy{window};
  glfwMakeContextCurrent(window);
  glfwSwapInterval(options.script_drag.empty() ? 1 : 0);
  App app(options, window);
  return app.run();
}

}  // namespace strata::viewer
