// Unit tests of the viewer's worker thread (no OpenGL): the undo checkpoints it records.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "document.h"
#include "strata/editing.h"
#include "strata/mesh_io.h"
#include "worker.h"

namespace strata::viewer {
namespace {

// The bumps scan of the bundled assets, as a plain mesh document.
Document bumps() {
  const std::string path = std::string(STRATA_SOURCE_DIR) + "/assets/bumps-75/detail.obj";
  return Document::load(path);
}

// A checkpoint is the document as committed after every request before it: an amplitude change
// queued or running when the UI asked for the checkpoint (a drag started at once) is in it. The
// UI took its own last commit, the state before the amplitude change.
TEST(ViewerWorker, ACheckpointFollowsTheJobsQueuedBeforeIt) {
  Worker w(bumps());
  w.build_layers(2);
  w.checkpoint();
  w.set_amplitude(1, 0.5);
  w.checkpoint();
  w.wait_idle();
  const std::vector<std::shared_ptr<const Document>> cps = w.take_checkpoints();
  ASSERT_EQ(cps.size(), 2u);
  ASSERT_TRUE(cps[0] && cps[1]);
  EXPECT_TRUE(cps[0]->is_model());  // after the build, not the plain mesh before it
  EXPECT_EQ(cps[0]->amplitude(1), 1.0);
  EXPECT_EQ(cps[1]->amplitude(1), 0.5);  // after the amplitude change
  EXPECT_TRUE(w.take_checkpoints().empty());
}

// A cancelled drag, a drag whose start fails (its region selects nothing) and a failed open drop
// the checkpoint taken for them (null entries), so that undo does not step to the state it is
// already in (the failed drag's was kept until a review, thirty-eighth session).
TEST(ViewerWorker, CancelledOrFailedDragsAndAFailedOpenDropTheirCheckpoints) {
  Worker w(bumps());
  const EditTransform turn = EditTransform::rotation(Vec3(1, 0, 0), 10.0, Vec3(0, 0, 1));
  w.checkpoint();
  w.begin_drag(0, Selection::halfspace(Vec3(0, 0, 0.5), Vec3(0, 0, 1)),
               Selection::halfspace(Vec3(0, 0, 1.0), Vec3(0, 0, 1)));
  w.update_drag(turn);
  w.cancel_drag();
  w.checkpoint();
  w.begin_drag(0, Selection::halfspace(Vec3(0, 0, 100), Vec3(0, 0, 1)),
               Selection::halfspace(Vec3(0, 0, 101), Vec3(0, 0, 1)));
  w.update_drag(turn);
  w.end_drag();
  w.checkpoint();
  w.load("/nonexistent/strata/scan.obj");
  w.wait_idle();
  const std::vector<std::shared_ptr<const Document>> cps = w.take_checkpoints();
  ASSERT_EQ(cps.size(), 6u);
  for (int k = 0; k < 6; k += 2) {
    EXPECT_TRUE(cps[k]) << k;
    EXPECT_FALSE(cps[k + 1]) << k + 1;  // the cancelled drag's, the failed drag's, the open's
  }
  const std::optional<Snapshot> s = w.take(0);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->error);
  EXPECT_NE(s->message.find("/nonexistent/strata/scan.obj"), std::string::npos) << s->message;
}

// After an undo (replace() with the checkpoint), the next checkpoint is the document undo went
// to: it recorded the one before the undo, so the next undo brought back the change just undone
// (a review, thirty-eighth session).
TEST(ViewerWorker, ACheckpointAfterAnUndoIsTheDocumentUndoWentTo) {
  Worker w(bumps());
  w.build_layers(3);
  w.checkpoint();
  w.set_amplitude(2, 0.0);
  w.wait_idle();
  std::vector<std::shared_ptr<const Document>> cps = w.take_checkpoints();
  ASSERT_EQ(cps.size(), 1u);
  ASSERT_TRUE(cps[0]);
  EXPECT_EQ(cps[0]->amplitude(2), 1.0);
  w.replace(*cps[0]);  // undo
  w.checkpoint();
  w.set_amplitude(1, 0.5);
  w.wait_idle();
  cps = w.take_checkpoints();
  ASSERT_EQ(cps.size(), 1u);
  ASSERT_TRUE(cps[0]);
  EXPECT_EQ(cps[0]->amplitude(2), 1.0);
  EXPECT_EQ(cps[0]->amplitude(1), 1.0);
}

}  // namespace
}  // namespace strata::viewer
