// Region edits of real scans (CGAL's demo data, extracted by tools/fetch_scans.sh into
// assets/scans/): limb bends from tests/data/edits/. Missing scans fail: run tools/setup.sh.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "strata/edit_script.h"
#include "strata/editing.h"
#include "strata/intersections.h"
#include "strata/mesh_io.h"

using namespace strata;

namespace {

struct ScanEdit {
  const char* scan;
  const char* script;
};

class RealScanBend : public ::testing::TestWithParam<ScanEdit> {};

}  // namespace

// Volumes keep the region's prisms to the acceptance bounds, add no intersecting pair to the
// scan's own, and leave every vertex outside the region where it was.
TEST_P(RealScanBend, VolumesKeepPrismsWithoutNewIntersections) {
  const std::string scan = std::string(STRATA_ASSETS_DIR) + "/scans/" + GetParam().scan + ".off";
  ASSERT_TRUE(std::ifstream(scan).good()) << scan << " is missing: run tools/setup.sh (tools/fetch_scans.sh)";
  const TriMesh m = read_mesh(scan);
  const EditScript s = read_edit_script(std::string(STRATA_TEST_DATA_DIR) + "/edits/" + GetParam().script);
  ASSERT_EQ(s.edits.size(), 1u);
  const std::vector<char> region = select_vertices(m.vertices, s.edits[0].region);
  const RegionEditor ed(m, region, select_vertices(m.vertices, s.edits[0].handle));
  const EditResult r = ed.apply(s.edits[0].transform);
  EXPECT_LE(r.volume.max_relative_error, 1e-3);
  EXPECT_LE(r.volume.rms_relative_error, 1e-4);
  IntersectionOptions all;
  all.collect_pairs = true;
  const IntersectionResult before = find_self_intersections(m.vertices, m.faces, all);
  const IntersectionResult after = find_self_intersections(r.positions, m.faces, all);
  EXPECT_EQ(0u, count_new_intersections(before, after));
  for (int i = 0; i < m.num_vertices(); ++i)
    if (!region[i]) {
      ASSERT_EQ(r.positions[i], m.vertices[i]);
    }
  // The edit did bend the limb: the handle moved.
  double moved = 0.0;
  for (int i : ed.handle_vertices()) moved = std::max(moved, (r.positions[i] - m.vertices[i]).norm());
  EXPECT_GT(moved, 0.05 * bbox_diagonal(m.vertices));
}

INSTANTIATE_TEST_SUITE_P(Scans, RealScanBend,
                         ::testing::Values(ScanEdit{"camel", "camel_neck.json"}, ScanEdit{"man", "man_arm.json"}),
                         [](const ::testing::TestParamInfo<ScanEdit>& info) { return std::string(info.param.scan); });
