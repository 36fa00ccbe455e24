// Bad input to the SDK's public functions, called directly as a modeling tool embeds them: each
// gets a typed error naming the problem, never a crash, a silent NaN or a result that breaks the
// function's contract. The cases are those a probe of the API found (2026-11-28): out-of-range
// indices read past the arrays, NaN volumes scored as exact, axes whose squares overflowed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "paper_cases.h"
#include "strata/cage_editing.h"
#include "strata/cage_io.h"
#include "strata/edit_script.h"
#include "strata/editing.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/json_check.h"
#include "strata/mesh_io.h"
#include "strata/mesh_processing.h"
#include "strata/metrics.h"
#include "strata/reconstruction.h"
#include "strata/subdiv.h"
#include "test_files.h"
#include "test_meshes.h"

using namespace strata;
using test::icosphere;
using test::throws_with;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

TriMesh triangle_with(const Face& f) {
  TriMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  m.faces = {f};
  return m;
}

const cases::CylinderCase& small_case() {
  static const cases::CylinderCase c = [] {
    cases::CylinderCaseOptions o;
    o.target_detail_triangles = 800;
    return cases::make_cylinder_case(o);
  }();
  return c;
}

PolyMesh cube_cage() {
  PolyMesh c;
  c.vertices = {Vec3(-1, -1, -1), Vec3(1, -1, -1), Vec3(1, 1, -1), Vec3(-1, 1, -1),
                Vec3(-1, -1, 1),  Vec3(1, -1, 1),  Vec3(1, 1, 1),  Vec3(-1, 1, 1)};
  c.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  return c;
}

// Whether R is a rotation: orthonormal with determinant 1, to rounding.
bool is_rotation(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-14 &&
         std::abs(R.determinant() - 1) < 1e-14;
}

}  // namespace

TEST(ApiInput, MeshFunctionsCheckTheirFaceIndices) {
  for (const Face& f : {Face{0, 1, 100}, Face{0, -1, 2}}) {
    const TriMesh m = triangle_with(f);
    const std::string index = std::to_string(f[1] < 0 ? f[1] : f[2]);
    const std::string says = "face 0 has vertex index " + index + ", out of range (3 vertices)";
    EXPECT_TRUE(
        throws_with<InvalidInput>([&] { vertex_normals(m.vertices, m.faces); }, {"vertex_normals: ", says}));
    EXPECT_TRUE(throws_with<InvalidInput>([&] { signed_volume(m); }, {"signed_volume: ", says}));
    EXPECT_TRUE(
        throws_with<InvalidInput>([&] { bbox_centre(m.vertices, m.faces); }, {"bbox_centre: ", says}));
    EXPECT_TRUE(
        throws_with<InvalidInput>([&] { check_extent(m.vertices, m.faces, "scan"); }, {"scan: ", says}));
    EXPECT_TRUE(throws_with<InvalidInput>([&] { taubin_smooth(m, 1); }, {"taubin_smooth: ", says}));
    EXPECT_TRUE(throws_with<InvalidInput>([&] { decimate_mesh(m, 4); }, {"decimate_mesh: ", says}));
  }
  // In range, the same functions work as before.
  const TriMesh ok = triangle_with({0, 1, 2});
  EXPECT_EQ(vertex_normals(ok.vertices, ok.faces)[0], Vec3(0, 0, 1));
  EXPECT_EQ(signed_volume(ok), 0.0);
}

// coordinate_median(): per axis, the middle value (the upper one of an even count), whatever one
// far point does; the box centre moves halfway to it.
TEST(ApiInput, CoordinateMedianIgnoresAFarPoint) {
  EXPECT_EQ(coordinate_median({}), Vec3::Zero());
  std::vector<Vec3> p = {{3, -1, 5}, {1, -2, 4}, {2, -3, 6}};
  EXPECT_EQ(coordinate_median(p), Vec3(2, -2, 5));
  p.push_back({1e15, 1e15, -1e15});
  EXPECT_EQ(coordinate_median(p), Vec3(3, -1, 5));
  EXPECT_GT(bbox_diagonal(p), 1e15);
}

TEST(ApiInput, SmoothingAndDecimationRefuseWhatWouldSpreadNaNOrCrashOpenMesh) {
  TriMesh m = icosphere(2);
  m.vertices[5].x() = kNaN;
  // One NaN vertex spread to 36 of the 42 smoothed ones; decimation returned a NaN vertex.
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { taubin_smooth(m, 3); }, {"taubin_smooth: vertex 5 has a non-finite"}));
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { decimate_mesh(m, 20); }, {"decimate_mesh: vertex 5 has a non-finite"}));
  // A repeated corner: OpenMesh's add_face asserted.
  TriMesh r = icosphere(2);
  r.faces[7][1] = r.faces[7][0];
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { decimate_mesh(r, 20); }, {"decimate_mesh: face 7 repeats a vertex"}));
}

TEST(ApiInput, VolumeMetricsRefuseNonFiniteInputInsteadOfScoringItExact) {
  const cases::CylinderCase& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  ASSERT_EQ(volume_metrics(e, fr, c.detail.vertices).max_relative_error, 0.0);
  std::vector<Vec3> p = c.detail.vertices;
  p[3].y() = kNaN;  // its prisms' volumes are NaN: the max error was 0 (std::max drops a NaN)
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { volume_metrics(e, fr, p); }, {"detail position 3 is not finite"}));
  BaseFrames bad = fr;
  bad.points[4].z() = kNaN;
  EXPECT_TRUE(throws_with<InvalidInput>([&] { volume_metrics(e, bad, c.detail.vertices); },
                                        {"base point 4 is not finite"}));
  EXPECT_TRUE(throws_with<InvalidInput>([&] { volume_metrics(e, fr, c.detail.vertices, kNaN); },
                                        {"the amplitude is not finite"}));
  // Amplitude 0: every target is 0. The detail at its base points is exact; the detail at rest is
  // not, and no relative error fits it (it was reported as 0).
  EXPECT_EQ(volume_metrics(e, fr, fr.points, 0.0).max_relative_error, 0.0);
  const VolumeMetrics muted = volume_metrics(e, fr, c.detail.vertices, 0.0);
  EXPECT_TRUE(std::isinf(muted.max_relative_error));
  EXPECT_TRUE(std::isinf(muted.rms_relative_error));
}

TEST(ApiInput, RotationsAboutHugeOrTinyAxesAreRotations) {
  const EditTransform unit = EditTransform::rotation(Vec3(1, 0, 0), 90.0, Vec3::Zero(), Vec3::Zero());
  for (double s : {1e160, 1e300, 1e-160, 1e-300}) {
    // The squares of 1e160 overflowed (the "rotation" was 6e-17 I); those of 1e-160 lost digits.
    const EditTransform t = EditTransform::rotation(Vec3(s, 0, 0), 90.0, Vec3::Zero(), Vec3::Zero());
    EXPECT_TRUE(is_rotation(t.linear)) << s << "\n" << t.linear;
    EXPECT_LT((t.linear - unit.linear).norm(), 1e-15) << s;
  }
  // An edit script's axis likewise (its coordinates are within the engine's range, 1e20).
  for (const char* axis : {"1e-160", "1e-300", "1e20"}) {
    const EditScript script =
        parse_edit_script(std::string(R"({"region": {"box": {"min": [-9, -9, -9], "max": [9, 9, 0]}},
                        "handle": {"box": {"min": [-9, -9, -9], "max": [9, 9, -1]}},
                        "transform": {"rotate": {"axis": [)") +
                              axis + R"(, 0, 0], "degrees": 90}}})",
                          "s.json");
    EXPECT_TRUE(is_rotation(script.edits.at(0).transform.linear)) << axis;
    EXPECT_LT((script.edits.at(0).transform.linear - unit.linear).norm(), 1e-15) << axis;
  }
  EXPECT_TRUE(throws_with<InvalidInput>(
      [] { EditTransform::rotation(Vec3::Zero(), 90.0, Vec3::Zero(), Vec3::Zero()); }, {"axis is zero"}));
}

TEST(ApiInput, AnEditScriptWithAKeyTwiceIsRefused) {
  // JSON keeps the later value: the second "region" (or "degrees") won, silently.
  const std::string R = R"("region": {"box": {"min": [-9, -9, -9], "max": [9, 9, 0]}})";
  const std::string H = R"("handle": {"box": {"min": [-9, -9, -9], "max": [9, 9, -1]}})";
  const std::string T = R"("transform": {"rotate": {"axis": [1, 0, 0], "degrees": 90}})";
  EXPECT_NO_THROW(parse_edit_script("{" + R + ", " + H + ", " + T + "}", "ok.json"));
  EXPECT_TRUE(throws_with<InvalidInput>(
      [&] { parse_edit_script("{" + R + ", " + R + ", " + H + ", " + T + "}", "r.json"); },
      {"r.json: the key \"region\" appears twice in one object"}));
  const std::string T2 = R"("transform": {"rotate": {"axis": [1, 0, 0], "degrees": 90, "degrees": 45}})";
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { parse_edit_script("{" + R + ", " + H + ", " + T2 + "}", "d.json"); },
                                {"d.json: the key \"degrees\" appears twice"}));
  // A file that is not JSON is called that, even with a key twice before its syntax error.
  EXPECT_TRUE(throws_with<InvalidInput>([&] { parse_edit_script("{" + R + ", " + R, "cut.json"); },
                                        {"cut.json: not valid JSON"}));
  // The same key in two objects is no repetition.
  EXPECT_NO_THROW(parse_edit_script(
      R"({"edits": [{)" + R + ", " + H + ", " + T + "}, {" + R + ", " + H + ", " + T + "}]}", "two.json"));
}

TEST(ApiInput, JsonStructureLimits) {
  // The checks that edit scripts and .strata headers share, at their limits.
  EXPECT_EQ(json_structure_problem(std::string(256, '[') + std::string(256, ']')), "");
  EXPECT_EQ(json_structure_problem(std::string(257, '[') + std::string(257, ']')),
            "nested deeper than 256 levels");
  // Stops at the level too many: the rest is not read (a million levels, at once).
  EXPECT_EQ(json_structure_problem(std::string(1000000, '[')), "nested deeper than 256 levels");
  std::string keys = "{";
  for (int k = 0; k < 1025; ++k) keys += (k ? ",\"" : "\"") + std::to_string(k) + "\":0";
  EXPECT_EQ(json_structure_problem(keys + "}"), "an object has more than 1024 keys");
  EXPECT_EQ(json_structure_problem(keys + "}", JsonLimits{256, 0, true}), "");
  EXPECT_EQ(json_structure_problem(R"({"a":{"b":1},"c":[{"b":2,"b":3}]})"),
            "the key \"b\" appears twice in one object");
  EXPECT_EQ(json_structure_problem(R"({"a":{"b":1},"c":[{"b":2,"b":3}]})", JsonLimits{256, 1024, false}), "");
  // A key is shown printable and short: a terminal would act on its control characters.
  EXPECT_EQ(json_structure_problem("{\"a\\u001b[2Jb\":1,\"a\\u001b[2Jb\":2}"),
            "the key \"a?[2Jb\" appears twice in one object");
  const std::string long_key = "\"" + std::string(100000, 'k') + "\"";
  EXPECT_EQ(json_structure_problem("{" + long_key + ":1," + long_key + ":2}"),
            "the key \"" + std::string(64, 'k') + "...\" appears twice in one object");
  EXPECT_EQ(printable_key("caf\xc3\xa9\t"), "caf???");
  EXPECT_EQ(printable_key(""), "");
  // An unknown key too, in an edit script (cage files and .strata headers print theirs alike).
  EXPECT_TRUE(throws_with<InvalidInput>([] { parse_edit_script("{\"regi\\u001b[2Jon\": 1}", "k.json"); },
                                        {"unknown key \"regi?[2Jon\""}));
  // A syntax error is the parse's to report; so is an empty text.
  EXPECT_EQ(json_structure_problem("{\"a\": }"), "");
  EXPECT_EQ(json_structure_problem(""), "");
  // An edit script too deep is refused (and a million levels are no crash).
  EXPECT_TRUE(throws_with<InvalidInput>(
      [] {
        parse_edit_script(R"({"edits": )" + std::string(300, '[') + std::string(300, ']') + "}", "deep.json");
      },
      {"deep.json: nested deeper than 256 levels"}));
  EXPECT_TRUE(throws_with<InvalidInput>(
      [] {
        parse_edit_script(R"({"edits": )" + std::string(1000000, '[') + std::string(1000000, ']') + "}",
                          "deeper.json");
      },
      {"deeper.json: nested deeper than 256 levels"}));
}

TEST(ApiInput, DisplacementVectorsCheckTheAmplitudeFramesAndOffsets) {
  const cases::CylinderCase& c = small_case();
  DetailEncoding e = encode_detail(c.detail, c.base);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  EXPECT_TRUE(throws_with<InvalidInput>([&] { reconstruct_vectors(e, fr, kNaN); }, {"the amplitude nan"}));
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { reconstruct_vectors(e, fr, 1e308); }, {"is not within +-1000"}));
  BaseFrames shorter = fr;
  shorter.normals.pop_back();
  const std::string n = std::to_string(e.num_detail_vertices());
  EXPECT_TRUE(throws_with<InvalidInput>(
      [&] { reconstruct_vectors(e, shorter); },
      {"base frames with " + n + " points, " + std::to_string(fr.normals.size() - 1) + " normals and " + n +
       " tangents for " + n + " detail vertices"}));
  e.normal_offsets[6] = kNaN;
  EXPECT_TRUE(throws_with<InvalidInput>([&] { reconstruct_vectors(e, fr); },
                                        {"detail vertex 6: its base frame or its offsets are not finite"}));
}

TEST(ApiInput, EncodingsWithNonFiniteOrMixedBasePointsAreRefused) {
  const cases::CylinderCase& c = small_case();
  DetailEncoding e = encode_detail(c.detail, c.base);
  DetailEncoding nan_bary = e;
  nan_bary.base_points[2].bary[1] = kNaN;  // a NaN base point was returned
  EXPECT_TRUE(throws_with<InvalidInput>([&] { evaluate_base_frames(nan_bary, c.base.vertices); },
                                        {"base point 2 has non-finite barycentric coordinates"}));
  DetailEncoding both = e;
  both.limit_points.assign(both.base_points.size(), LimitPoint{0, 0.5, 0.5});
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { check_encoding(both); }, {"both base points", "and limit points"}));
}

TEST(ApiInput, AnEmptyEncodingIsCalledEmpty) {
  // It was reported by its weight offsets' count ("0 weight offsets for 1 ...").
  EXPECT_TRUE(throws_with<InvalidInput>([] { check_encoding(DetailEncoding{}); }, {"encoding is empty"}));
  EXPECT_TRUE(
      throws_with<InvalidInput>([] { VolumeReconstructor r{DetailEncoding{}}; }, {"encoding is empty"}));
  EXPECT_TRUE(throws_with<InvalidInput>([] { reconstruct_vectors(DetailEncoding{}, BaseFrames{}); },
                                        {"encoding is empty"}));
}

TEST(ApiInput, ADegenerateLimitSurfaceHasNoNormalsAndSaysSo) {
  const TriMesh sphere = icosphere(2, 1.2);
  const DetailEncoding e = encode_detail(sphere, SubdivSurface(cube_cage()));
  std::vector<Vec3> collapsed(8, Vec3(1, 1, 1));  // the cage edited to a point
  // Its frames were taken with an arbitrary normal, and the reconstruction returned positions.
  EXPECT_TRUE(throws_with<InvalidInput>([&] { evaluate_base_frames(e, collapsed); },
                                        {"has no normal: the limit surface is degenerate there"}));
  EXPECT_TRUE(throws_with<InvalidInput>([&] { reconstruct_vectors(e, collapsed); }, {"has no normal"}));
  const VolumeReconstructor r(e);
  EXPECT_TRUE(throws_with<InvalidInput>([&] { r.reconstruct(collapsed); }, {"has no normal"}));
}

// Frames passed in by the caller keep BaseFrames' contract (unit normal and tangent, orthogonal):
// a normal of length 2 doubled the displacement along it without a word.
TEST(ApiInput, CallerFramesMustBeOrthonormal) {
  const cases::CylinderCase& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor r(e);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  EXPECT_EQ(r.reconstruct(fr).positions, r.reconstruct(c.base.vertices).positions);
  const std::size_t k = 5;
  std::vector<std::pair<BaseFrames, std::string>> bad(4, {fr, ""});
  bad[0].first.normals[k] *= 2.0, bad[0].second = "base frame 5: the normal is not of unit length";
  bad[1].first.tangents[k] *= 1.0 + 1e-5, bad[1].second = "base frame 5: the tangent is not of unit length";
  bad[2].first.tangents[k] = fr.normals[k],
  bad[2].second = "base frame 5: the normal and the tangent are not";
  bad[3].first.normals[k] = Vec3::Zero(), bad[3].second = "base frame 5: the normal is not of unit length";
  for (const auto& [frames, message] : bad) {
    SCOPED_TRACE(message);
    EXPECT_TRUE(throws_with<InvalidInput>([&] { r.reconstruct(frames); }, {message}));
    EXPECT_TRUE(throws_with<InvalidInput>([&] { reconstruct_vectors(e, frames); },
                                          {"reconstruct_vectors: " + message}));
    DragState s;
    EXPECT_TRUE(
        throws_with<InvalidInput>([&] { s.reset(frames, c.detail.vertices); }, {"drag start's " + message}));
    s.reset(fr, c.detail.vertices);
    EXPECT_TRUE(throws_with<InvalidInput>([&] { r.drag_step(frames, s); }, {message}));
  }
  // Float frames' rounding (a few 1e-8) passes.
  BaseFrames rounded = fr;
  for (std::size_t i = 0; i < rounded.normals.size(); ++i) {
    rounded.normals[i] = rounded.normals[i].cast<float>().cast<double>();
    rounded.tangents[i] = rounded.tangents[i].cast<float>().cast<double>();
  }
  EXPECT_NO_THROW(r.reconstruct(rounded));
}

TEST(ApiInput, AMovedFromDragStateIsNotStartedAndCanStartAgain) {
  const cases::CylinderCase& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  const VolumeReconstructor r(e);
  const BaseFrames fr = evaluate_base_frames(e, c.base.vertices);
  DragState s;
  s.reset(fr, c.detail.vertices);
  DragState taken(std::move(s));
  EXPECT_TRUE(taken.started());
  EXPECT_FALSE(s.started());  // NOLINT(bugprone-use-after-move): what the test is about
  EXPECT_TRUE(throws_with<InvalidInput>([&] { r.drag_step(c.base.vertices, s); }, {"moved-from DragState"}));
  EXPECT_TRUE(throws_with<InvalidInput>([&] { r.drag_step(fr, s); }, {"moved-from DragState"}));
  s.reset(fr, c.detail.vertices);
  EXPECT_TRUE(s.started());
  EXPECT_EQ(r.drag_step(c.base.vertices, s).positions.size(), c.detail.vertices.size());
}

TEST(ApiInput, PinnedPositionsAreCheckedWithoutPinnedVertices) {
  const cases::CylinderCase& c = small_case();
  const DetailEncoding e = encode_detail(c.detail, c.base);
  ASSERT_TRUE(e.pinned.empty());
  const VolumeReconstructor r(e);
  const std::vector<Vec3> three(3, Vec3::Zero());
  ReconstructRequest q;
  q.pinned_positions = &three;
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { r.reconstruct(c.base.vertices, q); },
                                {"3 pinned positions for " + std::to_string(e.num_detail_vertices())}));
}

TEST(ApiInput, EditorsRefuseEnumsOutOfRangeAndEmptyMeshes) {
  const TriMesh m = icosphere(2);
  std::vector<char> region(m.vertices.size(), 0), handle(m.vertices.size(), 0);
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    region[v] = m.vertices[v].z() > -0.5;
    handle[v] = m.vertices[v].z() > 0.5;
  }
  EditOptions o;
  o.method = static_cast<EditOptions::Method>(9);  // ran as volumes
  EXPECT_TRUE(throws_with<InvalidInput>([&] { const RegionEditor ed(m, region, handle, o); },
                                        {"edit option method = 9 is not volumes or vectors"}));
  o = EditOptions{};
  o.drag_end = static_cast<EditOptions::DragEnd>(7);
  EXPECT_TRUE(throws_with<InvalidInput>([&] { const RegionEditor ed(m, region, handle, o); },
                                        {"edit option drag_end = 7"}));
  const std::vector<char> cage_region = {1, 1, 1, 1, 1, 1, 1, 1}, cage_handle = {0, 0, 0, 0, 1, 1, 1, 1};
  EXPECT_TRUE(throws_with<InvalidInput>(
      [&] { const CageEditor ed(TriMesh{}, SubdivSurface(cube_cage()), cage_region, cage_handle); },
      {"cage edit: the mesh has no faces"}));
  PolyMesh two = cube_cage();
  two.faces.push_back({0, 1});
  EXPECT_TRUE(throws_with<InvalidInput>([&] { cage_blend_field(two, cage_region, cage_handle); },
                                        {"cage face 6 has 2 corners, fewer than 3"}));
  // Two cubes, the second wholly inside the region and away from the handle: its field would be
  // undetermined (it failed as "the cage's blend field could not be factorized"); it keeps s = 0,
  // and the first cube gets the field it gets alone.
  PolyMesh pair = cube_cage();
  for (int v = 0; v < 8; ++v) pair.vertices.push_back(pair.vertices[v] + Vec3(5, 0, 0));
  for (int f = 0; f < 6; ++f) {
    std::vector<int> g = pair.faces[f];
    for (int& v : g) v += 8;
    pair.faces.push_back(g);
  }
  std::vector<char> pair_region(16, 1), pair_handle(16, 0);
  for (int v = 4; v < 8; ++v) pair_handle[v] = 1;
  const std::vector<char> one_region(8, 1), one_handle(pair_handle.begin(), pair_handle.begin() + 8);
  const std::vector<double> s = cage_blend_field(pair, pair_region, pair_handle),
                            alone = cage_blend_field(cube_cage(), one_region, one_handle);
  for (int v = 0; v < 8; ++v) EXPECT_NEAR(s[v], alone[v], 1e-12) << v;
  for (int v = 8; v < 16; ++v) EXPECT_EQ(s[v], 0.0) << v;
}

TEST(ApiInput, SubdivisionMessagesNameTheProblem) {
  SubdivTags tags;
  tags.creases.push_back({0, 1, kNaN});
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { const SubdivSurface s(cube_cage(), tags); }, {"has a NaN sharpness"}));
  tags.creases[0].sharpness = -1;
  EXPECT_TRUE(throws_with<InvalidInput>([&] { const SubdivSurface s(cube_cage(), tags); },
                                        {"has a negative sharpness"}));
  const SubdivSurface s(cube_cage());
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { s.across_edge(0, 0, kNaN); }, {"the edge parameter t is not finite"}));
  EXPECT_TRUE(throws_with<InvalidInput>([&] { s.across_edge(0, 9, 0.5); }, {"ptex edge (0,9) out of range"}));
}

TEST(ApiInput, FilesRefuseAmbiguityAndWhatCouldNotBeReadBack) {
  test::ScratchDir dir("strata_api");
  // Two x properties: which holds the coordinate? The second was read, silently.
  const std::string ply = dir.file("twice.ply");
  std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float x\n"
                        "property float y\nproperty float z\nelement face 1\n"
                        "property list uchar int vertex_indices\nend_header\n"
                        "0 0 0 0\n1 7 0 0\n0 7 1 0\n3 0 1 2\n";
  EXPECT_TRUE(throws_with<IoError>([&] { read_mesh(ply); }, {ply + ": vertex property x declared twice"}));
  const std::string faces = dir.file("lists.ply");
  std::ofstream(faces) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                          "property list uchar int vertex_index\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 3 0 2 1\n";
  EXPECT_TRUE(throws_with<IoError>([&] { read_mesh(faces); },
                                   {faces + ": face properties vertex_indices and vertex_index"}));
  // A cage that read_cage() would refuse is not written.
  PolyMesh far = cube_cage();
  far.vertices[2].x() = 1e300;
  const std::string cage = dir.file("far.obj");
  EXPECT_TRUE(
      throws_with<InvalidInput>([&] { write_cage(far, cage); }, {"far.obj: vertex 2 has a coordinate"}));
  EXPECT_TRUE(dir.listing().count("far.obj") == 0);
  // Nor one in STL, which renumbers the vertices that tags name and rounds to floats (a review,
  // thirty-eighth session: a tetrahedron's cage came back renumbered), and none is read from it.
  PolyMesh tet;
  tet.vertices = {Vec3(0.1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  tet.faces = {{2, 1, 0}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  const std::string stl = dir.file("tet.STL");
  EXPECT_TRUE(throws_with<IoError>([&] { write_cage(tet, stl); }, {"tet.STL: a cage is not kept in STL"}));
  EXPECT_TRUE(dir.listing().count("tet.STL") == 0);
  write_mesh(TriMesh{tet.vertices, {{2, 1, 0}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}}}, stl);
  EXPECT_TRUE(throws_with<IoError>([&] { read_cage(stl); }, {"tet.STL: a cage is not kept in STL"}));
  const std::string obj = dir.file("tet.obj");
  write_cage(tet, obj);
  const PolyMesh back = read_cage(obj);
  EXPECT_EQ(back.vertices, tet.vertices);
  EXPECT_EQ(back.faces, tet.faces);
}
