#include "worker.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <utility>

#include "strata/exceptions.h"
#include "strata/layers/model.h"
#include "strata/mesh_io.h"

namespace strata::viewer {
namespace {

// A message not yet taken by the UI is kept: an empty new one takes it over, and an error is not
// replaced by a later success (a failed save followed within a frame by an export showed only
// "exported ...").
void keep_untaken_message(Snapshot& old, Snapshot& s) {
  if (s.message.empty() && !s.error) {
    s.message = std::move(old.message);
    s.error = old.error;
  } else if (old.error && !old.message.empty() && !s.error) {
    s.message = old.message + "; then " + s.message;
    s.error = true;
  }
}

}  // namespace

Worker::Worker(Document document, const ViewSettings& view) : doc_(std::move(document)), view_(view) {
  publish(true, "", false);
  thread_ = std::thread([this] { run(); });
}

Worker::~Worker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    // The jobs up to the last save or export run (a Ctrl+S behind a long solve, then the window
    // closed, wrote nothing); the others are dropped.
    std::size_t keep = 0;
    for (std::size_t i = 0; i < queue_.size(); ++i)
      if (queue_[i].writes_file) keep = i + 1;
    queue_.resize(keep);
  }
  wake_.notify_all();
  thread_.join();
}

void Worker::post(Job job, bool commits, const std::string& coalesce_key, bool writes_file, bool silent) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!coalesce_key.empty() && !queue_.empty() && queue_.back().key == coalesce_key) {
      queue_.back().job = std::move(job);  // only the newest step of a run of them waits
    } else {
      queue_.push_back({std::move(job), commits, coalesce_key, writes_file, silent});
    }
  }
  wake_.notify_one();
}

namespace {
// The worker's nice level: STRATA_VIEWER_WORKER_NICE (0 .. 19), default 5.
int nice_level() {
  const char* e = std::getenv("STRATA_VIEWER_WORKER_NICE");
  const int n = e ? std::atoi(e) : 5;
  return n < 0 ? 0 : n > 19 ? 19 : n;
}
}  // namespace

void Worker::run() {
  // Below the UI thread (and llvmpipe's rasterizer threads) in priority, so that drawing frames
  // wins the CPU on small machines; threads the solvers start inherit it.
  errno = 0;
  if (setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice_level()) != 0) errno = 0;
  for (;;) {
    Pending p;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (stop_ && queue_.empty()) return;
      p = std::move(queue_.front());
      queue_.pop_front();
      running_job_ = true;
      job_start_ = std::chrono::steady_clock::now();
    }
    std::string message;
    bool error = false;
    try {
      message = p.job(doc_);
    } catch (const std::exception& e) {
      message = e.what();
      error = true;
    }
    bool stopping = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping = stop_;
    }
    if (stopping) {
      // The window is gone: a failed save or export is said on stderr.
      if (error) std::fprintf(stderr, "strata-viewer: %s\n", message.c_str());
    } else if (p.silent && !error) {
      // Nothing shown changed.
    } else {
      try {
        publish(p.commits && !error, message, error);
      } catch (const std::exception& e) {
        // Not the scenes again (they may fail the same way): the message, and the job's commit,
        // whose document has changed (a load, a build or an edit).
        publish_message(message.empty() ? std::string(e.what()) : message + "; " + e.what(), true,
                        p.commits && !error);
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_job_ = false;
      if (queue_.empty()) idle_.notify_all();
    }
  }
}

void Worker::publish(bool commit, std::string message, bool error) {
  Snapshot s;
  const int n = doc_.num_bands();
  std::vector<char> visible = view_.visible;
  visible.resize(static_cast<std::size_t>(n), 0);
  bool any = false;
  for (char v : visible) any = any || v;
  if (!any) visible[static_cast<std::size_t>(n - 1)] = 1;
  // Colour maps cost a solve-sized pass (intersections: a BVH search): not during drag steps. The
  // scan's own colours and texture cost nothing (the texture is decoded once) and do not change
  // with the positions: they stay.
  const bool dragging = (doc_.is_model() && doc_.model().dragging()) || mesh_dragging_;
  const ColorMode drag_color =
      view_.color == ColorMode::Scan || view_.color == ColorMode::Texture ? view_.color : ColorMode::None;
  for (int k = 0; k < n; ++k) {
    if (!visible[static_cast<std::size_t>(k)]) continue;
    SceneSettings settings;
    settings.show = k;
    settings.vectors = view_.vectors;
    settings.color = dragging ? drag_color : view_.color;
    settings.error_scale = view_.error_scale;
    settings.band0_net = view_.cage;
    s.panels.push_back(make_scene(doc_, settings));
  }
  if (view_.compare && !view_.vectors) {
    SceneSettings settings;
    settings.show = n - 1;
    settings.vectors = true;
    settings.color = dragging ? drag_color : view_.color;
    settings.error_scale = view_.error_scale;
    s.panels.push_back(make_scene(doc_, settings));
  }
  if (commit) s.committed = last_commit_ = std::make_shared<const Document>(doc_);
  s.drag_step = dragging;
  s.message = std::move(message);
  s.error = error;
  std::lock_guard<std::mutex> lock(mutex_);
  s.version = snapshot_.version + 1;
  // A commit not yet taken by the UI survives later drag-step snapshots.
  if (!s.committed) s.committed = std::move(snapshot_.committed);
  keep_untaken_message(snapshot_, s);
  snapshot_ = std::move(s);
}

void Worker::publish_message(std::string message, bool error, bool commit) noexcept {
  try {
    Snapshot s;
    s.message_only = true;
    s.message = message;  // a copy: the catch below prints it
    s.error = error;
    if (commit) s.committed = last_commit_ = std::make_shared<const Document>(doc_);
    std::lock_guard<std::mutex> lock(mutex_);
    s.version = snapshot_.version + 1;
    if (!s.committed) s.committed = std::move(snapshot_.committed);
    // Panels not yet taken stay (the UI draws the newest it has).
    if (snapshot_.version > 0 && !snapshot_.message_only && !snapshot_.panels.empty()) {
      s.panels = std::move(snapshot_.panels);
      s.drag_step = snapshot_.drag_step;
      s.message_only = false;
    }
    keep_untaken_message(snapshot_, s);
    snapshot_ = std::move(s);
  } catch (...) {
    std::fprintf(stderr, "strata-viewer: out of memory publishing: %s\n", message.c_str());
  }
}

void Worker::drop_mesh_drag(Document& d, std::vector<Vec3> positions) {
  d.set_mesh_positions(std::move(positions));
  mesh_editor_.reset();
  mesh_dragging_ = false;
}

std::optional<Snapshot> Worker::take(long long version) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (snapshot_.version <= version) return std::nullopt;
  Snapshot s = std::move(snapshot_);
  snapshot_ = Snapshot();
  snapshot_.version = s.version;
  return s;
}

bool Worker::busy(double* seconds) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (seconds != nullptr)
    *seconds = running_job_
                   ? std::chrono::duration<double>(std::chrono::steady_clock::now() - job_start_).count()
                   : 0;
  return running_job_ || !queue_.empty();
}

long long Worker::drag_steps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drag_steps_;
}

double Worker::drag_seconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drag_seconds_;
}

void Worker::wait_idle() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [&] { return !running_job_ && queue_.empty(); });
}

void Worker::set_view(const ViewSettings& settings) {
  post(
      [this, settings](Document&) {
        view_ = settings;
        return std::string();
      },
      false, "view");
}

void Worker::begin_drag(int band, const Selection& region, const Selection& handle) {
  post(
      [this, band, region, handle](Document& d) {
        drag_failed_ = true;  // until it succeeds
        d.check_band(band);
        if (d.is_model()) {
          d.mutable_model().begin_drag(band, region, handle);
        } else {
          const TriMesh mesh = d.band_mesh(0);
          mesh_editor_ = std::make_unique<RegionEditor>(mesh, select_vertices(mesh.vertices, region),
                                                        select_vertices(mesh.vertices, handle));
          mesh_editor_->begin_drag();
          mesh_dragging_ = true;
        }
        drag_failed_ = false;
        return std::string();
      },
      false);
}

void Worker::update_drag(const EditTransform& transform) {
  post(
      [this, transform](Document& d) {
        if (drag_failed_) return std::string();  // the begin's error stays the one shown
        const auto t0 = std::chrono::steady_clock::now();
        if (d.is_model()) {
          if (!d.model().dragging()) throw InvalidInput("no drag is active");
          // The model is only reachable const through the document: drag on it in place.
          d.mutable_model().update_drag(transform);
        } else {
          if (!mesh_editor_) throw InvalidInput("no drag is active");
          d.set_mesh_positions(mesh_editor_->update_drag(transform));
        }
        last_transform_ = transform;
        std::lock_guard<std::mutex> lock(mutex_);
        ++drag_steps_;
        drag_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return std::string();
      },
      false, "drag");
}

void Worker::end_drag() {
  post(
      [this](Document& d) {
        if (drag_failed_) {  // nothing was dragged: no exact solve to report
          drag_failed_ = false;
          // Nor an undo step: its checkpoint goes, as a cancelled drag's (it was the document as
          // it still is, and undo stepped to it; a review, thirty-eighth session).
          std::lock_guard<std::mutex> lock(mutex_);
          checkpoints_.push_back(nullptr);
          return std::string();
        }
        const auto t0 = std::chrono::steady_clock::now();
        if (d.is_model()) {
          if (!d.model().dragging()) return std::string();
          d.mutable_model().end_drag(R"({"source": "strata-viewer", "op": "drag"})");
        } else if (mesh_editor_) {
          EditResult r;
          try {
            r = mesh_editor_->end_drag();
          } catch (...) {
            // As a model's failed end_drag(): the mesh as before the drag, and the error shown.
            drop_mesh_drag(d, mesh_editor_->mesh().vertices);
            throw;
          }
          drop_mesh_drag(d, std::move(r.positions));
        } else {
          return std::string();
        }
        return "exact solve: " +
               std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()) +
               " s";
      },
      true);
}

void Worker::cancel_drag() {
  post(
      [this](Document& d) {
        drag_failed_ = false;
        if (d.is_model()) {
          d.mutable_model().cancel_drag();
        } else if (mesh_editor_) {
          drop_mesh_drag(d, mesh_editor_->mesh().vertices);
        }
        // Its checkpoint goes: the document is the one before the drag again.
        std::lock_guard<std::mutex> lock(mutex_);
        checkpoints_.push_back(nullptr);
        return std::string("drag cancelled");
      },
      false);
}

void Worker::checkpoint() {
  post(
      [this](Document&) {
        std::lock_guard<std::mutex> lock(mutex_);
        checkpoints_.push_back(last_commit_);
        return std::string();
      },
      false, "", false, /*silent=*/true);
}

std::vector<std::shared_ptr<const Document>> Worker::take_checkpoints() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(checkpoints_, {});
}

void Worker::set_amplitude(int band, double amplitude) {
  post(
      [band, amplitude](Document& d) {
        d.set_amplitude(band, amplitude);
        return std::string();
      },
      true, "amplitude " + std::to_string(band));
}

void Worker::edit(int band, const EditStep& step) {
  post(
      [band, step](Document& d) {
        d.edit(band, step, R"({"source": "strata-viewer", "op": "edit"})");
        return std::string("edit applied to band ") + std::to_string(band);
      },
      true);
}

void Worker::replace(Document document) {
  auto shared = std::make_shared<Document>(std::move(document));
  post(
      [this, shared](Document& d) {
        mesh_editor_.reset();
        mesh_dragging_ = false;
        d = *shared;
        // What the next checkpoint records: the document undo or redo went to, not the one
        // before it (the next undo brought back the change just undone; a review, thirty-eighth
        // session).
        last_commit_ = shared;
        return std::string();
      },
      false);
}

void Worker::load(const std::string& path) {
  post(
      [this, path](Document& d) {
        Document loaded = [&] {
          try {
            return Document::load(path);
          } catch (...) {
            // The document stays: so does the undo stack (drop the open's checkpoint).
            std::lock_guard<std::mutex> lock(mutex_);
            checkpoints_.push_back(nullptr);
            throw;
          }
        }();
        mesh_editor_.reset();
        mesh_dragging_ = false;
        view_.visible.clear();
        d = std::move(loaded);
        const int flipped = d.reoriented_faces();
        std::string status = "opened " + path;
        if (flipped > 0)
          status += " (" + std::to_string(flipped) + " faces flipped to agree with their neighbours)";
        for (const std::string& note : d.load_notes()) status += "; " + note;
        return status;
      },
      true);
}

void Worker::build_layers(int bands) {
  post(
      [bands](Document& d) {
        d = viewer::build_layers(d, bands);
        return "built a model of " + std::to_string(bands) + " bands";
      },
      true);
}

void Worker::save(const std::string& path) {
  post(
      [path](Document& d) {
        layers::write_model(d.model(), path);
        return "saved " + path;
      },
      false, "", true);
}

void Worker::export_meshes(const std::string& prefix, const std::string& extension) {
  post(
      [this, prefix, extension](Document& d) {
        // The preview is no result (Ctrl+E while Ctrl-dragging wrote the unconverged step; a save
        // writes the state before the drag).
        if ((d.is_model() && d.model().dragging()) || mesh_dragging_)
          throw InvalidInput("export during a drag: release or cancel it first");
        std::string notes;
        for (int k = 0; k < d.num_bands(); ++k) {
          const std::string path = prefix + "_band" + std::to_string(k) + extension;
          // Its images named as the format names them (a PLY's as an OBJ's material library).
          std::vector<std::string> format_notes;
          const MeshAttributes attributes = attributes_for_format(d.attributes(k), path, &format_notes);
          write_mesh(d.band_mesh(k), attributes, path);
          // The material library and images beside it; a file of that name already there is kept.
          for (const std::string& note : format_notes) notes += "; " + note;
          for (const std::string& note : write_companion_files(attributes, path)) notes += "; " + note;
        }
        return "exported " + std::to_string(d.num_bands()) + " meshes to " + prefix + "_band*" + extension +
               notes;
      },
      false, "", true);
}

}  // namespace strata::viewer
