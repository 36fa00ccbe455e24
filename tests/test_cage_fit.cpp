// Cage fitting (issue 4, item 4): a Loop cage decimated from a scan and solved so that its limit
// surface approximates the smoothed scan.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "paper_cases.h"
#include "strata/cage_fit.h"
#include "strata/cage_io.h"
#include "strata/exceptions.h"
#include "strata/mesh_processing.h"
#include "strata/subdiv.h"
#include "test_meshes.h"

using namespace strata;
using strata::test::icosphere;

namespace {

struct RadialError {
  double mean = 0.0, max = 0.0;
};

// |x| - 1 over a tessellation of the fitted cage's limit surface: an independent measure of how
// well the limit approximates the unit sphere.
RadialError radial_error(const PolyMesh& cage) {
  const SubdivSurface s(cage);
  const LimitTessellation t = s.tessellate(4);
  RadialError e;
  for (const Vec3& x : t.mesh.vertices) {
    e.mean += x.norm() - 1.0;
    e.max = std::max(e.max, std::abs(x.norm() - 1.0));
  }
  e.mean /= t.mesh.num_vertices();
  return e;
}

}  // namespace

TEST(CageFit, LimitOfTheFittedCageIsTheSphere) {
  const TriMesh scan = icosphere(5);  // 20480 faces: 1% is below min_faces, so 400
  const CageFit fit = fit_cage(scan);
  EXPECT_LE(fit.cage.num_faces(), 400);
  EXPECT_GE(fit.cage.num_faces(), 396);
  for (const auto& f : fit.cage.faces) ASSERT_EQ(f.size(), 3u);
  // A closed genus-0 triangle mesh: V - E + F = 2 with E = 3F/2.
  EXPECT_EQ(fit.cage.num_vertices() - fit.cage.num_faces() * 3 / 2 + fit.cage.num_faces(), 2);
  EXPECT_EQ(fit.scan_fallback, 0);
  EXPECT_EQ(fit.rounds, 3);
  // The diagonal is 2 sqrt(3); errors are relative to it. Measured: rms 4.7e-4, max 1.8e-3.
  EXPECT_LE(fit.rms_error, 1e-3);
  EXPECT_LE(fit.max_error, 4e-3);
  // The decimated cage's own limit shrinks inside the sphere (Loop limits lie inside their cages'
  // hull; measured: mean radius 0.98). The fitted one is neither shrunk nor inflated (measured:
  // mean radius 1 + 4e-4, worst 5.7e-3 off).
  const RadialError r = radial_error(fit.cage);
  EXPECT_LE(std::abs(r.mean), 1e-3);
  EXPECT_LE(r.max, 1e-2);
  // An overwhelming smoothness term pins the cage to the decimated one up to a translation: its
  // error is the unfitted cage's, many times the fitted one's.
  CageFitOptions pinned;
  pinned.smoothness = 1e9;
  const CageFit unfitted = fit_cage(scan, pinned);
  EXPECT_EQ(unfitted.cage.faces, fit.cage.faces);
  EXPECT_LE(radial_error(unfitted.cage).mean, -1e-2);
  EXPECT_GE(unfitted.rms_error, 5.0 * fit.rms_error);
}

TEST(CageFit, WithoutSmoothingTheReportedErrorIsTheScansDistance) {
  // With no smoothing the target is the scan itself: both reported errors must agree, and match
  // a direct measurement on the returned cage.
  const TriMesh scan = icosphere(4);
  CageFitOptions o;
  o.smoothing_steps = 0;
  o.faces = 200;
  const CageFit fit = fit_cage(scan, o);
  EXPECT_DOUBLE_EQ(fit.rms_error, fit.scan_rms_distance);
  EXPECT_DOUBLE_EQ(fit.max_error, fit.scan_max_distance);
  const SubdivSurface s(fit.cage);
  const Projection pr = project_to_limit(s, scan.vertices);
  double sum = 0.0;
  for (int i = 0; i < scan.num_vertices(); ++i)
    sum += (scan.vertices[i] - s.evaluate(pr.points[i]).position).squaredNorm();
  EXPECT_NEAR(std::sqrt(sum / scan.num_vertices()) / bbox_diagonal(scan.vertices), fit.rms_error, 1e-12);
}

TEST(CageFit, StrongerSmoothnessTradesFittingError) {
  const TriMesh scan = icosphere(4);
  CageFitOptions loose, stiff;
  loose.faces = stiff.faces = 200;
  loose.smoothness = 0.0;
  stiff.smoothness = 10.0;
  const CageFit a = fit_cage(scan, loose), b = fit_cage(scan, stiff);
  EXPECT_LT(a.rms_error, b.rms_error);
  // The same decimated cage: only the positions differ.
  EXPECT_EQ(a.cage.faces, b.cage.faces);
}

TEST(CageFit, OpenScanKeepsItsBoundary) {
  // The paper cases' base cylinder: an open tube.
  const TriMesh tube = cases::make_cylinder_case().base;
  CageFitOptions o;
  o.faces = 300;
  const CageFit fit = fit_cage(tube, o);
  EXPECT_LE(fit.cage.num_faces(), 300);
  EXPECT_LE(static_cast<double>(fit.scan_fallback), 1e-3 * tube.num_vertices());
  EXPECT_LE(fit.rms_error, 2e-3);
  // Still a tube: boundary edges (used by one face) remain, two loops' worth.
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : fit.cage.faces)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  int boundary = 0;
  for (const auto& [e, n] : uses) boundary += n == 1;
  EXPECT_GE(boundary, 6);
}

TEST(CageFit, RejectsBadInput) {
  const TriMesh scan = icosphere(2);  // 320 faces
  EXPECT_THROW(fit_cage(TriMesh{}), InvalidInput);
  TriMesh nan = scan;
  nan.vertices[3].x() = NAN;
  EXPECT_THROW(fit_cage(nan), InvalidInput);
  // A cage as fine as the scan, or finer, is refused (the default is a quarter of a small scan).
  EXPECT_THROW(fit_cage(scan,
                        [] {
                          CageFitOptions o;
                          o.faces = 400;
                          return o;
                        }()),
               InvalidInput);
  auto with = [](auto set) {
    CageFitOptions o;
    o.faces = 100;
    set(o);
    return o;
  };
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.faces = -1; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.faces = 0, o.face_fraction = 0.0; })),
               InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.smoothing_steps = -1; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.smoothness = NAN; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.rounds = 0; })), InvalidInput);
  // Upper bounds (10^5 rounds or 10^7 smoothing steps ran for minutes; 1e308 failed the solve).
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.rounds = 101; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.smoothing_steps = 1001; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.smoothness = 1e308; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.faces = 3; })), InvalidInput);
  EXPECT_NO_THROW(fit_cage(scan, with([](CageFitOptions&) {})));
  // Coordinates beyond the engine's range are refused (at 1e160 the limit projection crashed).
  TriMesh far = scan;
  for (Vec3& v : far.vertices) v *= 1e160;
  EXPECT_THROW(fit_cage(far, with([](CageFitOptions&) {})), InvalidInput);
  // A valid scan whose decimation keeps a vertex in 200 faces, more than a cage may have: the
  // fit's failure (SolverError), where it was an InvalidInput naming a cage the caller never gave.
  TriMesh fan;
  fan.vertices.push_back(Vec3::Zero());
  const int n = 200;
  for (int i = 0; i < n; ++i)
    fan.vertices.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n),
                              0.1 * std::sin(6.0 * i / n));
  for (int i = 0; i < n; ++i) fan.faces.push_back({0, 1 + i, 1 + (i + 1) % n});
  EXPECT_THROW(fit_cage(fan, with([](CageFitOptions& o) { o.faces = 190; })), SolverError);
  // The caller's own subdivision options stay InvalidInput (a review found them rethrown as the
  // fit's SolverError, after the decimation had run).
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.subdiv.isolation_level = 0; })), InvalidInput);
  EXPECT_THROW(fit_cage(scan, with([](CageFitOptions& o) { o.subdiv.isolation_level = 11; })), InvalidInput);
  // So is a refinement budget over the cage's ceiling (4 times its default), named up front; at
  // the ceiling of a cage of 2 triangles fewer than the target, the fit runs.
  try {
    (void)fit_cage(scan, with([](CageFitOptions& o) {
                     o.faces = 40;
                     o.subdiv.max_refined_faces = SubdivSurface::max_refined_faces_ceiling(3 * 38) + 1;
                   }));
    ADD_FAILURE() << "a budget over the ceiling was taken";
  } catch (const InvalidInput& e) {
    EXPECT_NE(
        std::string(e.what()).find("cage fit: subdiv.max_refined_faces 4194305 is above the ceiling of a "
                                   "cage of 40 triangles, 4194304"),
        std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(fit_cage(scan, with([](CageFitOptions& o) {
                             o.faces = 40;
                             o.subdiv.max_refined_faces = SubdivSurface::max_refined_faces_ceiling(3 * 38);
                           })));
}

// The decimation, the cage fit and the builder do not depend on the scan's size: OpenMesh keeps
// the quadrics' errors in single precision, which overflowed for a scan scaled by 1e12 and
// underflowed at 1e-100, so that nothing collapsed (the "cage" was the whole scan). Scaled by a
// power of two the decimation is the same to the bit; by 1e12 it still reaches its target. A scan
// whose extent is below kMinExtent is refused (at 1e-200 a model was built that its reader then
// refused); bbox_diagonal() still measures it.
TEST(CageFit, TheScansSizeDoesNotMatter) {
  const TriMesh scan = icosphere(3);  // 1280 faces
  const TriMesh unit = decimate_mesh(scan, 200);
  ASSERT_EQ(unit.num_faces(), 200);
  for (const int e : {40, -40, 330, -330}) {
    TriMesh scaled = scan;
    for (Vec3& v : scaled.vertices) v = std::ldexp(1.0, e) * v;
    const TriMesh d = decimate_mesh(scaled, 200);
    ASSERT_EQ(d.faces, unit.faces) << "2^" << e;
    for (int i = 0; i < d.num_vertices(); ++i)
      ASSERT_EQ(std::ldexp(1.0, -e) * d.vertices[i], unit.vertices[i]) << "2^" << e;
  }
  for (const double s : {1e12, 1e18, 1e-19, 1e-100}) {
    TriMesh scaled = scan;
    for (Vec3& v : scaled.vertices) v *= s;
    EXPECT_EQ(decimate_mesh(scaled, 200).num_faces(), 200) << s;
  }
  CageFitOptions o;
  o.faces = 100;
  TriMesh big = scan;
  for (Vec3& v : big.vertices) v *= 1e12;
  const CageFit fit = fit_cage(big, o);
  EXPECT_LE(fit.cage.num_faces(), 110);
  TriMesh tiny = scan;
  for (Vec3& v : tiny.vertices) v *= 1e-200;
  EXPECT_NEAR(bbox_diagonal(tiny.vertices) / (1e-200 * bbox_diagonal(scan.vertices)), 1.0, 1e-12);
  EXPECT_EQ(bbox_diagonal({Vec3::Zero(), Vec3(1e-310, 0, 0)}), 1e-310);  // subnormal: was NaN
  EXPECT_EQ(bbox_diagonal({Vec3::Zero(), Vec3(0, 3e300, 4e300)}), 5e300);
  try {
    fit_cage(tiny, o);
    ADD_FAILURE() << "a scan of extent 3.5e-200 was fitted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("below the engine's range (1e-20)"), std::string::npos) << e.what();
  }
}

// A scan may hold vertices in no face (validate_mesh() allows them): the decimation drops them
// (deleting one without OpenMesh's status attributes aborted the process), and the cage is the
// one fitted to the scan without them up to the decimation's order (the vertices' numbering
// differs): as many faces, neither stray point among its vertices, the same fit to the sphere.
TEST(CageFit, UnreferencedScanVerticesAreDropped) {
  const TriMesh clean = icosphere(3);
  TriMesh scan = clean;
  scan.vertices.push_back(Vec3(5, 5, 5));
  scan.vertices.insert(scan.vertices.begin(), Vec3(-5, 0, 0));
  for (Face& f : scan.faces)
    for (int& v : f) ++v;
  CageFitOptions o;
  o.faces = 200;
  const CageFit fit = fit_cage(scan, o), reference = fit_cage(clean, o);
  EXPECT_EQ(fit.cage.num_faces(), reference.cage.num_faces());
  for (const Vec3& x : fit.cage.vertices) {
    EXPECT_GT((x - Vec3(5, 5, 5)).norm(), 1.0);
    EXPECT_GT((x - Vec3(-5, 0, 0)).norm(), 1.0);
  }
  const RadialError e = radial_error(fit.cage), r = radial_error(reference.cage);
  EXPECT_NEAR(e.max, r.max, 0.2 * r.max);
  EXPECT_NEAR(e.mean, r.mean, 0.2 * std::abs(r.mean) + 1e-4);
}

TEST(CageIo, ParsesTagsAndNamesTheProblem) {
  const SubdivTags t = parse_subdiv_tags(
      R"({"creases": [{"edge": [0, 1], "sharpness": 2.5}, {"edge": [1, 2]}], "corners": [{"vertex": 4}]})",
      "t.json");
  ASSERT_EQ(t.creases.size(), 2u);
  EXPECT_EQ(t.creases[0].v0, 0);
  EXPECT_EQ(t.creases[0].v1, 1);
  EXPECT_EQ(t.creases[0].sharpness, 2.5);
  EXPECT_EQ(t.creases[1].sharpness, 10.0);
  ASSERT_EQ(t.corners.size(), 1u);
  EXPECT_EQ(t.corners[0].vertex, 4);
  EXPECT_TRUE(parse_subdiv_tags("{}", "t.json").creases.empty());
  auto message = [](const std::string& text) -> std::string {
    try {
      parse_subdiv_tags(text, "t.json");
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message("{").find("t.json: not valid JSON: parse error at line 1, column 2"), std::string::npos);
  EXPECT_EQ(message("{").find("json.exception"), std::string::npos);  // the parser's class name
  // A NUL byte ended the parse, and what came before was read; 1e999 gave a raw library message.
  EXPECT_NE(message(std::string("{}\0", 3)).find("t.json: not valid JSON: it holds a NUL byte"),
            std::string::npos);
  EXPECT_NE(message(R"({"corners": [{"vertex": 1, "sharpness": 1e999}]})").find("t.json: not valid JSON"),
            std::string::npos);
  EXPECT_NE(message(R"({"crease": []})").find("unknown key \"crease\""), std::string::npos);
  EXPECT_NE(message(R"({"creases": [{"edge": [0]}]})").find("creases[0].edge"), std::string::npos);
  EXPECT_NE(message(R"({"creases": [{"edge": [0, -1]}]})").find("creases[0].edge"), std::string::npos);
  EXPECT_NE(message(R"({"corners": [{"vertex": 1, "sharpness": -1}]})").find("corners[0].sharpness"),
            std::string::npos);
  EXPECT_NE(message(R"({"corners": [{"sharpness": 1}]})").find("missing \"vertex\""), std::string::npos);
  // A key twice: the parser kept the last value (two "corners" lists read as the second).
  EXPECT_NE(message(R"({"corners": [{"vertex": 1, "sharpness": 2}], "corners": [{"vertex": 7}]})")
                .find("t.json: the key \"corners\" appears twice in one object"),
            std::string::npos);
  EXPECT_NE(message(R"({"corners": [{"vertex": 1, "sharpness": 2, "sharpness": 9}]})").find("appears twice"),
            std::string::npos);
  EXPECT_THROW(read_subdiv_tags("/nonexistent/tags.json"), IoError);
  // Not a regular file (a FIFO or device would block the reader): refused, naming the path.
  try {
    read_subdiv_tags("/dev/zero");
    ADD_FAILURE() << "/dev/zero was read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: cannot read: not a regular file"), std::string::npos)
        << e.what();
  }
}

// The cage's default size: 1% of the scan, at least min_faces (400), at most a quarter of the
// scan (at least 4); a count that is set is taken as it is.
TEST(CageFit, TheDefaultCageIsAtMostAQuarterOfTheScan) {
  const CageFitOptions o;
  EXPECT_EQ(default_cage_faces(o, 100000), 1000);
  EXPECT_EQ(default_cage_faces(o, 20480), 400);
  EXPECT_EQ(default_cage_faces(o, 1600), 400);
  EXPECT_EQ(default_cage_faces(o, 1000), 250);
  EXPECT_EQ(default_cage_faces(o, 320), 80);
  EXPECT_EQ(default_cage_faces(o, 12), 4);
  CageFitOptions set = o;
  set.faces = 500;
  EXPECT_EQ(default_cage_faces(set, 320), 500);
  // A 320-face sphere, which failed with "fewer than the cage's 400", gets an 80-face cage whose
  // limit surface follows the sphere.
  const CageFit fit = fit_cage(test::icosphere(2));
  EXPECT_EQ(fit.cage.num_faces(), 80);
  const RadialError e = radial_error(fit.cage);
  EXPECT_LT(e.max, 0.05);
}
