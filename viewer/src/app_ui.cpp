// The ImGui panels of the window (App's drawing half; input and the loop are in app.cpp).
#include <imgui.h>

#include <cmath>
#include <string>

#include "app.h"

namespace strata::viewer {

void App::draw_ui() {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(340, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Strata");
  if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("Smooth (S)", &style_.smooth);
    ImGui::SameLine();
    ImGui::Checkbox("Wireframe (W)", &style_.wireframe);
    bool changed = ImGui::Checkbox("Cage net (C)", &view_.cage);
    int color = static_cast<int>(view_.color);
    changed |= ImGui::Combo(
        "Colour", &color,
        "none\0prism volume error (E)\0intersecting triangles (I)\0scan colours (K)\0scan texture (T)\0");
    view_.color = static_cast<ColorMode>(color);
    float scale = static_cast<float>(view_.error_scale);
    if (view_.color == ColorMode::Error &&
        ImGui::SliderFloat("Error scale", &scale, 0.001f, 1.0f, "%.3f", ImGuiSliderFlags_Logarithmic)) {
      view_.error_scale = scale;
      changed = true;
    }
    changed |= ImGui::Checkbox("Displacement vectors (V)", &view_.vectors);
    ImGui::SameLine();
    changed |= ImGui::Checkbox("Compare (B)", &view_.compare);
    if (changed) push_view();
    if (ImGui::Button("Fit (F)")) fit_view();
  }
  draw_band_panel();
  draw_edit_panel();
  draw_file_panel();
  ImGui::End();
  draw_status();
  if (show_help_) draw_help();
}

void App::draw_band_panel() {
  if (!committed_ || !ImGui::CollapsingHeader("Bands", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const int n = committed_->num_bands();
  if (static_cast<int>(view_.visible.size()) != n) {
    view_.visible.assign(static_cast<std::size_t>(n), 0);
    view_.visible[static_cast<std::size_t>(n - 1)] = 1;
    push_view();  // the worker draws what the boxes say (it kept the old document's flags)
  }
  for (int k = 0; k < n; ++k) {
    ImGui::PushID(k);
    const auto uk = static_cast<std::size_t>(k);
    bool visible = view_.visible[uk];
    if (ImGui::Checkbox("##visible", &visible)) {
      view_.visible[uk] = visible;
      push_view();
    }
    ImGui::SameLine();
    ImGui::RadioButton("##edit", &edit_band_, k);
    if (ImGui::IsItemClicked()) update_selection_points();
    ImGui::SameLine();
    const std::string label = committed_->is_model()
                                  ? (k == 0 ? "0 cage" : std::to_string(k) + (k == n - 1 ? " scan" : " band"))
                                  : std::string("mesh");
    ImGui::Text("%-8s %6zu pts", label.c_str(), committed_->band_points(k).size());
    if (committed_->is_model() && k > 0 && uk < amplitudes_.size()) {
      ImGui::SameLine();
      ImGui::SetNextItemWidth(110);
      // The checkpoint before the change: the slider moves to the click on the frame it
      // activates, and undo went back to the clicked value (a review, thirty-eighth session).
      const bool changed = ImGui::SliderFloat("##amplitude", &amplitudes_[uk], 0.0f, 2.0f, "a=%.2f");
      if (ImGui::IsItemActivated()) checkpoint();
      if (changed) worker_->set_amplitude(k, amplitudes_[uk]);
      ImGui::SameLine();
      const bool muted = amplitudes_[uk] == 0.0f;
      if (ImGui::SmallButton(muted ? "unmute" : "mute")) {
        checkpoint();
        amplitudes_[uk] = muted ? 1.0f : 0.0f;
        worker_->set_amplitude(k, amplitudes_[uk]);
      }
    }
    ImGui::PopID();
  }
  ImGui::TextDisabled("checkbox: visible (side by side); dot: band to edit");
  if (!committed_->is_model()) {
    ImGui::SetNextItemWidth(100);
    ImGui::SliderInt("bands", &build_bands_, 2, 8);
    ImGui::SameLine();
    if (ImGui::Button("Build layered model")) {
      checkpoint();
      worker_->build_layers(build_bands_);
    }
  }
}

void App::draw_edit_panel() {
  if (!ImGui::CollapsingHeader("Edit", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::Text("band %d: click on it to place", edit_band_);
  int pick = static_cast<int>(pick_);
  ImGui::RadioButton("orbit", &pick, 0);
  ImGui::SameLine();
  ImGui::RadioButton("region (R)", &pick, 1);
  ImGui::SameLine();
  ImGui::RadioButton("handle (H)", &pick, 2);
  pick_ = static_cast<Pick>(pick);
  if (pick_ != Pick::None) brush_ = false;
  if (ImGui::Checkbox("brush (P)", &brush_) && brush_) pick_ = Pick::None;
  ImGui::SameLine();
  if (brush_radius_ <= 0) brush_radius_ = 0.04f * camera_.radius();
  ImGui::SetNextItemWidth(120);
  ImGui::SliderFloat("brush radius", &brush_radius_, 0.0f, 0.5f * camera_.radius(), "%.3f");
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) {
    clear_brush();
    update_selection_points();
  }
  if (brush_) ImGui::TextDisabled("drag: paint region, Shift: handle (and region), Ctrl: erase");
  const float r = camera_.radius();
  if (ImGui::SliderFloat("region radius", &region_radius_, 0.0f, r, "%.3f")) update_selection_points();
  if (ImGui::SliderFloat("handle radius", &handle_radius_, 0.0f, r, "%.3f")) update_selection_points();
  ImGui::TextDisabled(region_ready() ? "region: yellow points" : "region: not set");
  ImGui::SameLine();
  ImGui::TextDisabled(handle_ready() ? "handle: red points" : "handle: not set");
  ImGui::BeginDisabled(!region_ready() || !handle_ready());
  ImGui::TextUnformatted("Gizmo: drag an arrow / ring, or Ctrl+drag translates, Shift+drag rotates");
  ImGui::Combo("axis", &axis_, "x\0y\0z\0view\0");
  bool changed = ImGui::SliderFloat("angle", &angle_, -180.0f, 180.0f, "%.1f deg");
  bool active = ImGui::IsItemActive(), activated = ImGui::IsItemActivated(),
       released = ImGui::IsItemDeactivated();
  changed |= ImGui::DragFloat3("translate", translation_.data(), 0.002f * r);
  active |= ImGui::IsItemActive();
  activated |= ImGui::IsItemActivated();
  released |= ImGui::IsItemDeactivated();
  if (activated && !dragging_) {
    const std::array<float, 3> t = translation_;
    const float a = angle_;
    const Mat4 v = camera_.view();
    view_axis_ = -v.block<1, 3>(2, 0).transpose().cast<double>();
    gizmo_begin();
    translation_ = t;  // the sliders start from their values
    angle_ = a;
  }
  if (changed && dragging_) gizmo_update();
  if (released && !active) {
    gizmo_end();  // which starts the next drag from the identity
  }
  ImGui::EndDisabled();
  ImGui::BeginDisabled(undo_.empty());
  if (ImGui::Button("Undo (Ctrl+Z)")) undo();
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(redo_.empty());
  if (ImGui::Button("Redo (Ctrl+Y)")) redo();
  ImGui::EndDisabled();
}

void App::draw_file_panel() {
  if (!ImGui::CollapsingHeader("Files")) return;
  ImGui::InputText("##open", open_path_.data(), open_path_.size());
  ImGui::SameLine();
  if (ImGui::Button("Open")) on_drop(open_path_.data());
  ImGui::InputText("##save", save_path_.data(), save_path_.size());
  ImGui::SameLine();
  ImGui::BeginDisabled(!committed_ || !committed_->is_model());
  if (ImGui::Button("Save .strata")) worker_->save(save_path_.data());
  ImGui::EndDisabled();
  ImGui::InputText("##export", export_prefix_.data(), export_prefix_.size());
  ImGui::SameLine();
  ImGui::SetNextItemWidth(60);
  ImGui::Combo("##format", &export_format_, "obj\0ply\0off\0");
  ImGui::SameLine();
  if (ImGui::Button("Export"))
    worker_->export_meshes(export_prefix_.data(), export_format_ == 0   ? ".obj"
                                                  : export_format_ == 1 ? ".ply"
                                                                        : ".off");
  ImGui::TextDisabled("or drop a .strata / mesh file on the window");
}

void App::draw_status() {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->Pos.x + 8, vp->Pos.y + vp->Size.y - 8), ImGuiCond_Always, ImVec2(0, 1));
  ImGui::SetNextWindowBgAlpha(0.6f);
  ImGui::Begin("##status", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing |
                   ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoInputs);
  double seconds = 0;
  const bool busy = worker_->busy(&seconds);
  if (busy && seconds > 0.1) {
    static const char* spin = "|/-\\";
    ImGui::Text("%c solving... %.1f s", spin[static_cast<int>(ImGui::GetTime() * 8) & 3], seconds);
  } else if (dragging_) {
    ImGui::TextUnformatted("dragging (interactive solve); release for the exact solve");
  }
  if (!status_.empty())
    ImGui::TextColored(status_error_ ? ImVec4(1, 0.4f, 0.3f, 1) : ImVec4(0.7f, 0.9f, 0.7f, 1), "%s",
                       status_.c_str());
  int triangles = 0;
  for (const auto& p : panels_) triangles += p->mesh.triangles();
  ImGui::Text("%d triangles  %.1f fps  F1: help", triangles, ImGui::GetIO().Framerate);
  ImGui::End();
}

void App::draw_help() {
  ImGui::SetNextWindowPos(ImVec2(360, 8), ImGuiCond_FirstUseEver);
  ImGui::Begin("Help (F1)", &show_help_, ImGuiWindowFlags_AlwaysAutoResize);
  static const char* rows[][2] = {
      {"left drag", "orbit"},
      {"right / middle drag", "pan"},
      {"wheel", "zoom"},
      {"F", "fit to view"},
      {"1 .. 7", "front, back, left, right, top, bottom, iso"},
      {"S / W", "smooth-flat shading / wireframe"},
      {"C", "cage control net"},
      {"E / I / K / T", "prism volume error / intersecting triangles / scan colours / scan texture"},
      {"V / B", "displacement vectors / compare side by side"},
      {"R / H", "click to place the region / handle sphere"},
      {"P", "brush mode: left drag paints the region's points"},
      {"P + Shift / Ctrl drag", "brush: paint the handle / erase (radius in Edit)"},
      {"drag a gizmo arrow", "translate the handle along x / y / z"},
      {"drag a gizmo ring", "rotate the handle about x / y / z"},
      {"Ctrl + left drag", "translate the handle (drag runs live)"},
      {"Shift + left drag", "rotate the handle about the view axis"},
      {"Esc", "cancel the drag / selection mode"},
      {"Ctrl+Z / Ctrl+Y", "undo / redo"},
      {"Ctrl+S / Ctrl+E", "save .strata / export band meshes"},
      {"drop a file", "open it (.strata, obj, ply, off, stl)"},
      {"F1", "this help"},
  };
  if (ImGui::BeginTable("keys", 2)) {
    for (const auto& r : rows) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r[0]);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r[1]);
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

}  // namespace strata::viewer
