//! \file app.h
//! The interactive window (GLFW, OpenGL 3.3 core, Dear ImGui): bands side by side, the band
//! panel (visibility, live amplitude, mute, the band to edit), sphere selections of region and
//! handle on the edited band's points and a brush (P) that paints them point by point, a translate/rotate
//! gizmo (axis arrows and rings at the pivot, Ctrl/Shift + drag, or sliders) whose drags run on the Worker
//! thread, undo/redo, open/save/export, drag and drop, help (F1). With --script-drag it drives a drag over
//! --frames frames and (--benchmark) prints the frame times as JSON.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "camera.h"
#include "options.h"
#include "renderer.h"
#include "worker.h"

struct GLFWwindow;

namespace strata::viewer {

//! Runs the window until it is closed (or the script ends). Returns the exit code.
//! \throw std::runtime_error if no window or GL context can be made; strata::Error for the input.
int run_window(const Options& options);

class App {
 public:
  App(const Options& options, GLFWwindow* window);
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;
  //! The main loop. Returns the exit code.
  int run();

  // GLFW callbacks (forwarded from static functions).
  void on_key(int key, int mods);
  void on_scroll(double dy);
  void on_drop(const std::string& path);
  //! Shows \p message as an error in the status line (a callback's exception).
  void show_error(const std::string& message) {
    status_ = message;
    status_error_ = true;
  }

 private:
  struct Panel {
    GpuMesh mesh;
    GpuLines net;
    SceneData scene;  // CPU copy for picking
    Vec3 offset = Vec3::Zero();
    int band = 0;
    bool vectors = false;
  };
  enum class Pick { None, Region, Handle };

  void frame();
  void take_snapshot();
  //! The document the UI shows as committed (a snapshot's, or undo's and redo's): the band to
  //! edit, the amplitudes and the selection's points follow it.
  void set_committed(std::shared_ptr<const Document> document);
  //! Places the panels side by side if \p refit (new panels); fits the camera to them if
  //! \p camera or on the first picture (fitted_ false).
  void layout_panels(bool refit, bool camera = true);
  void handle_mouse();
  void draw_scene(int width, int height);
  void draw_ui();
  void draw_band_panel();
  void draw_edit_panel();
  void draw_file_panel();
  void draw_help();
  void draw_status();
  void update_selection_points();
  //! Per point of the edited band: in the region / handle (sphere or brush). False if no document.
  bool selection_flags(std::vector<char>& region, std::vector<char>& handle) const;
  bool brushed_band() const;  //!< the brush flags are for the edited band's points
  bool region_ready() const;
  bool handle_ready() const;
  //! The region / handle as passed to the drag: the sphere alone, or the union of the sphere and
  //! the brushed points as Selection::vertices.
  Selection region_selection() const;
  Selection handle_selection() const;
  //! Adds (or, \p erase, removes) the edited band's points within brush_radius_ of \p hit.
  void brush_at(const Vec3& hit, bool handle, bool erase);
  void clear_brush();
  //! The pivot of the gizmo: the handle sphere's centre, else the brushed handle's centroid.
  Vec3 handle_pivot() const;
  // The on-screen gizmo at the handle's pivot: parts 0-2 the x/y/z arrows (translate along the
  // axis), 3-5 the rings about x/y/z (rotate). Drags feed gizmo_begin/update/end.
  //! Whether it is shown; its centre (world, panel offset included) and arm length (world).
  bool gizmo_frame(Vec3& center, double& size) const;
  //! Its parts as polylines (world), with their part index.
  std::vector<std::pair<int, std::vector<Vec3>>> gizmo_parts() const;
  //! \p world in window pixels (origin top-left); false behind the eye.
  bool to_screen(const Vec3& world, double& x, double& y) const;
  //! The part within 8 pixels of (x, y), nearest first; -1 if none.
  int gizmo_hit(double x, double y) const;
  void gizmo_mouse(double x, double y, double dx, double dy);
  bool pick(double x, double y, Vec3& hit) const;
  EditTransform gizmo_transform() const;
  void gizmo_begin();
  void gizmo_update();
  void gizmo_end();
  void checkpoint();
  void undo();
  void redo();
  void push_view();
  void fit_view();
  void run_script_step();

  Options options_;
  GLFWwindow* window_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<Worker> worker_;
  std::vector<std::unique_ptr<Panel>> panels_;
  long long version_ = 0;
  std::shared_ptr<const Document> committed_;
  std::vector<std::shared_ptr<const Document>> undo_, redo_;
  void take_checkpoints();  // the worker's, onto undo_
  Camera camera_;
  bool fitted_ = false;
  // A dropped or opened file being loaded: once it is in, the selection and the visible bands are
  // reset, the camera refits and its own colours show (take_snapshot()); if it fails, nothing
  // changes.
  std::string opening_;
  ViewSettings view_;
  MeshStyle style_;
  std::string status_;
  bool status_error_ = false;

  // Editing.
  int edit_band_ = 0;
  Pick pick_ = Pick::None;
  Vec3 region_center_ = Vec3::Zero(), handle_center_ = Vec3::Zero();
  float region_radius_ = 0.0f, handle_radius_ = 0.0f;
  bool region_set_ = false, handle_set_ = false;
  GpuLines selection_points_;
  // Brush selection (P): left drag paints the region, Shift paints the handle, Ctrl erases.
  bool brush_ = false;
  float brush_radius_ = 0.0f;                      // world units (0: 4% of the scene radius when first used)
  std::vector<char> brush_region_, brush_handle_;  // per point of band brush_band_
  int brush_band_ = -1;
  bool brush_region_any_ = false, brush_handle_any_ = false;
  bool dragging_ = false;
  std::array<float, 3> translation_{0, 0, 0};
  int axis_ = 0;  // 0 x, 1 y, 2 z, 3 view direction
  float angle_ = 0.0f;
  Vec3 view_axis_ = Vec3::UnitZ();
  Vec3 pivot_ = Vec3::Zero();        // of the running drag
  Vec3 gizmo_pivot_ = Vec3::Zero();  // handle_pivot(), updated with the selection points
  int gizmo_part_ = -1, gizmo_hover_ = -1;
  GpuLines gizmo_lines_;

  // Mouse.
  double last_x_ = 0, last_y_ = 0, press_x_ = 0, press_y_ = 0;
  int drag_button_ = -1;
  int drag_mods_ = 0;
  double scroll_ = 0;

  // Panels.
  bool show_help_ = false;
  std::array<char, 512> open_path_{}, save_path_{}, export_prefix_{};
  int export_format_ = 0;
  int build_bands_ = 3;
  std::vector<float> amplitudes_;  // UI copy while sliding

  // Script and benchmark.
  EditScript script_;
  std::size_t script_step_ = 0;
  int script_frame_ = 0;
  bool script_waiting_ = false;
  bool script_done_ = false;
  std::vector<double> frame_ms_;
  std::array<double, 5> phase_s_{};  // snapshot, ui, scene, imgui draw, swap (benchmark)
  std::vector<char> frame_in_drag_;
  std::vector<char> frame_scan_colours_;  // per scripted frame: a panel drew per-vertex colours
  std::vector<char> frame_texture_;       // per scripted frame: a panel drew a texture
  std::vector<char> frame_drag_step_;     // per scripted frame: the panels showed a drag step's preview
  bool showing_drag_step_ = false;
  long long frames_ = 0;
  long long first_picture_frame_ = -1;  // the frame that uploaded the first snapshot
};

}  // namespace strata::viewer
