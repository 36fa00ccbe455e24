//! \file worker.h
//! The reconstruction thread of the window: it owns the working Document and runs every edit,
//! drag step, amplitude change and rebuild off the UI thread. The UI posts requests (drag steps
//! and amplitudes are coalesced: only the newest one waits) and takes the newest Snapshot under
//! a mutex each frame, so the camera never waits for a solve. No OpenGL here.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "document.h"
#include "scene.h"

namespace strata::viewer {

//! What the window draws, as of one worker state.
struct Snapshot {
  long long version = 0;
  //! One scene per visible band (band order), then the vectors comparison if requested.
  std::vector<SceneData> panels;
  //! Set after an operation that finished (not a drag step): the document for undo and saving.
  std::shared_ptr<const Document> committed;
  std::string message;  //!< the last operation's outcome or error ("" if none)
  bool error = false;
  bool drag_step = false;     //!< the panels show a drag step's preview
  bool message_only = false;  //!< no panels: only the message (and the commit) are new
};

//! What the panels show (the UI's settings, applied by the worker).
struct ViewSettings {
  std::vector<char> visible;  //!< per band; empty: the finest band only
  bool vectors = false;       //!< show bands rebuilt by displacement vectors instead
  bool compare = false;       //!< add the finest band by displacement vectors beside it
  ColorMode color = ColorMode::None;
  double error_scale = 0.05;
  bool cage = true;
};

class Worker {
 public:
  //! Publishes the first snapshot of \p document as \p view shows it (its colour map too: a
  //! texture is decoded here, so that the first picture is the one asked for), then starts the
  //! thread.
  explicit Worker(Document document, const ViewSettings& view = {});
  //! Stops the thread after the running job; pending jobs are dropped, but for saves and exports
  //! and the jobs queued before them (the file the user asked for is written; an error is printed
  //! on stderr, as no window shows it).
  ~Worker();
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  // Requests; each returns at once. Errors come back in Snapshot::message.
  void set_view(const ViewSettings& settings);
  void begin_drag(int band, const Selection& region, const Selection& handle);
  void update_drag(const EditTransform& transform);  //!< coalesced
  void end_drag();
  void cancel_drag();
  void set_amplitude(int band, double amplitude);  //!< coalesced per band
  void edit(int band, const EditStep& step);
  void replace(Document document);  //!< undo, redo, open
  //! Records an undo checkpoint when the worker reaches this request: the document as committed
  //! after every request before it (take_checkpoints()). The UI's own last commit can be older,
  //! when a job is queued or running (an amplitude change, then a drag started at once, left the
  //! amplitude change without an undo step of its own).
  void checkpoint();
  void load(const std::string& path);
  void build_layers(int bands);
  void save(const std::string& path);
  void export_meshes(const std::string& path_prefix, const std::string& extension);

  //! The newest snapshot if it is newer than \p version, else nothing.
  std::optional<Snapshot> take(long long version);
  //! The checkpoints recorded since the last call, in order: a document to push on the undo
  //! stack, or null where a cancelled drag drops the last one (its checkpoint() went before it).
  std::vector<std::shared_ptr<const Document>> take_checkpoints();
  //! Whether a job runs or waits, and for how long the current one has run.
  bool busy(double* seconds = nullptr) const;
  //! Drag steps completed since the start (for the benchmark).
  long long drag_steps() const;
  //! Seconds spent in drag steps since the start.
  double drag_seconds() const;
  //! Blocks until no job runs or waits.
  void wait_idle();

 private:
  //! A job returns its success message ("" for none) or throws.
  using Job = std::function<std::string(Document&)>;
  void post(Job job, bool commits, const std::string& coalesce_key = "", bool writes_file = false,
            bool silent = false);
  void run();
  void publish(bool commit, std::string message, bool error);
  //! A snapshot with \p message only (Snapshot::message_only): when publish() itself failed.
  void publish_message(std::string message, bool error, bool commit) noexcept;
  //! Ends a plain mesh's drag: \p positions into the document, the editor dropped.
  void drop_mesh_drag(Document& d, std::vector<Vec3> positions);

  struct Pending {
    Job job;
    bool commits = false;
    std::string key;
    bool writes_file = false;  // a save or an export: run even when the window closes
    bool silent = false;       // no snapshot after it (a checkpoint changes nothing shown)
  };

  Document doc_;  // worker thread only (and the constructor)
  // The last document published as committed (worker thread only): what a checkpoint records.
  std::shared_ptr<const Document> last_commit_;
  std::vector<std::shared_ptr<const Document>> checkpoints_;  // under mutex_
  ViewSettings view_;
  // Plain meshes are dragged with a RegionEditor kept between steps.
  std::unique_ptr<RegionEditor> mesh_editor_;
  EditTransform last_transform_;
  bool mesh_dragging_ = false;
  // The last begin_drag() failed: its drag's steps and end do nothing (their "no drag is active"
  // replaced the cause, and a plain mesh's end reported an exact solve that never ran).
  bool drag_failed_ = false;

  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<Pending> queue_;
  bool running_job_ = false, stop_ = false;
  std::chrono::steady_clock::time_point job_start_;
  Snapshot snapshot_;
  long long drag_steps_ = 0;
  double drag_seconds_ = 0.0;
  std::thread thread_;
};

}  // namespace strata::viewer
