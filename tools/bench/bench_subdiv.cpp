// strata_bench_subdiv: limit surfaces as bases (issue 4). Projects --points points (default 1M)
// onto a cage's limit surface and re-evaluates their base frames after a cage edit. Two cages: the
// paper's cylinder as a Catmull-Clark tube (open boundary, mostly regular) and a Loop sphere from
// an icosahedron (valence-5 extraordinary vertices). The points are known limit points moved along
// the normal by up to 5% of the size, so the projection's answer is checked too. Prints one JSON
// document. --threads 1 runs the projection and the frame evaluation on one thread.
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "bench_args.h"
#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/process.h"
#include "strata/subdiv.h"

using namespace strata;
using Clock = std::chrono::steady_clock;

static double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

namespace {

// An icosahedron refined once by midpoint subdivision and pushed onto the unit sphere: a Loop
// cage with 12 valence-5 vertices among valence-6 ones.
PolyMesh loop_sphere() {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::vector<int>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                     {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                     {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                     {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::map<std::pair<int, int>, int> mid;
  auto midpoint = [&](int a, int b) {
    const auto k = std::minmax(a, b);
    auto it = mid.find(k);
    if (it != mid.end()) return it->second;
    v.push_back((v[a] + v[b]) / 2);
    return mid[k] = static_cast<int>(v.size()) - 1;
  };
  PolyMesh m;
  for (const auto& t3 : f) {
    const int a = midpoint(t3[0], t3[1]), b = midpoint(t3[1], t3[2]), c = midpoint(t3[2], t3[0]);
    m.faces.push_back({t3[0], a, c});
    m.faces.push_back({t3[1], b, a});
    m.faces.push_back({t3[2], c, b});
    m.faces.push_back({a, b, c});
  }
  for (Vec3& p : v) p.normalize();
  m.vertices = v;
  return m;
}

nlohmann::json run(const char* name, const PolyMesh& cage, int num_points, unsigned seed) {
  auto t0 = Clock::now();
  SubdivSurface s(cage);
  const double build = since(t0);
  // Known limit points, moved along the normal.
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> F(0, s.num_ptex_faces() - 1);
  std::uniform_real_distribution<double> U(0.0, 1.0), H(-0.05, 0.05);
  const double size = bbox_diagonal(cage.vertices);
  std::vector<Vec3> pts(num_points);
  std::vector<LimitPoint> truth(num_points);
  for (int i = 0; i < num_points; ++i) {
    LimitPoint p{F(rng), U(rng), U(rng)};
    if (s.ptex_corners() == 3 && p.u + p.v > 1) p = {p.face, 1 - p.u, 1 - p.v};
    const LimitSample x = s.evaluate(p);
    truth[i] = p;
    pts[i] = x.position + H(rng) * size * x.normal();
  }
  t0 = Clock::now();
  const Projection pr = project_to_limit(s, pts);
  const double project = since(t0);
  int same = 0;
  for (int i = 0; i < num_points; i += 97)
    same += (s.evaluate(pr.points[i]).position - s.evaluate(truth[i]).position).norm() <= 1e-8 * size;
  // Re-evaluation after a cage edit: the control points move, every base frame is recomputed.
  DetailEncoding e;
  e.detail_rest = pts;
  e.limit_points = pr.points;
  e.base_num_vertices = s.num_control_points();
  std::vector<Vec3> edited = cage.vertices;
  for (Vec3& p : edited) p += 0.05 * size * Vec3(std::sin(3 * p.z()), std::cos(2 * p.x()), 0.0);
  t0 = Clock::now();
  const LimitPointSet set(s, pr.points);
  const double weights = since(t0);
  t0 = Clock::now();
  s.set_control_points(edited);
  const double update = since(t0);
  t0 = Clock::now();
  const BaseFrames fr = evaluate_base_frames(e, set, s);
  const double frames = since(t0);
  // The base points alone (positions and derivatives), into kept buffers: the sparse product.
  std::vector<Vec3> P, Du, Dv;
  set.evaluate(s, P, Du, Dv);
  t0 = Clock::now();
  set.evaluate(s, P, Du, Dv);
  const double points_only = since(t0);
  return {{"cage", name},
          {"scheme", s.scheme() == SubdivScheme::Loop ? "loop" : "catmull_clark"},
          {"cage_vertices", cage.num_vertices()},
          {"cage_faces", cage.num_faces()},
          {"ptex_faces", s.num_ptex_faces()},
          {"points", num_points},
          {"projection",
           {{"converged", pr.num_converged},
            {"fallback", pr.num_fallback},
            {"converged_fraction", static_cast<double>(pr.num_converged) / num_points},
            {"max_iterations_used", pr.max_iterations_used},
            {"found_the_known_foot_point_fraction_of_sample", same / std::ceil(num_points / 97.0)}}},
          {"seconds",
           {{"build_surface", build},
            {"project", project},
            {"limit_point_set_weights_once", weights},
            {"cage_edit_set_control_points", update},
            {"reevaluate_base_frames", frames},
            {"reevaluate_points_and_derivatives_kept_buffers", points_only},
            {"reevaluate_total", update + frames}}},
          {"frames_checksum", fr.points.empty() ? 0.0 : fr.points.back().sum()}};
}

}  // namespace

int main(int argc, char** argv) {
  strata::reexec_with_huge_page_malloc(argv);  // as the strata tool runs (process.h)
  int num_points = 1000000, threads = 0;
  const char* usage = "usage: strata_bench_subdiv [--points N] [--threads T]\n";
  if (const int rc = bench::help_or_usage_error(argc, argv, usage); rc >= 0) return rc;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string k = argv[a];
    if (k == "--points")
      num_points = std::atoi(argv[a + 1]);
    else if (k == "--threads")
      threads = std::atoi(argv[a + 1]);
    else {
      std::cerr << usage;
      return 2;
    }
  }
  if (num_points < 1 || threads < 0) {
    std::cerr << "strata_bench_subdiv: --points >= 1, --threads >= 0 (0: all cores)\n";
    return 2;
  }
  std::unique_ptr<tbb::global_control> gc;
  if (threads > 0)
    gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  cases::CylinderCaseOptions co;
  nlohmann::json results = nlohmann::json::array();
  results.push_back(run("cylinder_tube", cases::make_cylinder_cage(co, 32), num_points, 1));
  results.push_back(run("loop_sphere", loop_sphere(), num_points, 2));
  nlohmann::json j{
      {"benchmark",
       "strata_bench_subdiv: projection onto limit surfaces and re-evaluation after a cage edit"},
      {"threads", threads == 0 ? "all (" + std::to_string(tbb::this_task_arena::max_concurrency()) + ")"
                               : std::to_string(threads)},
      {"targets",
       {{"project_1m_le_5s", nullptr},
        {"reevaluate_1m_le_50ms", nullptr},
        {"reevaluate_frames_1m_le_50ms", nullptr}}},
      {"results", results}};
  // The target: the base points (positions, and the derivatives with them) after a cage
  // edit. The full base frames (unit normals and tangents too, into fresh arrays) are reported
  // against the same bound separately.
  bool proj_ok = true, reev_ok = true, frames_ok = true;
  for (const auto& r : results) {
    const double scale = 1e6 / r["points"].get<double>();
    const auto& sec = r["seconds"];
    proj_ok = proj_ok && sec["project"].get<double>() * scale <= 5.0;
    reev_ok = reev_ok && (sec["cage_edit_set_control_points"].get<double>() +
                          sec["reevaluate_points_and_derivatives_kept_buffers"].get<double>()) *
                                 scale <=
                             0.05;
    frames_ok = frames_ok && sec["reevaluate_total"].get<double>() * scale <= 0.05;
  }
  j["targets"]["project_1m_le_5s"] = proj_ok;
  j["targets"]["reevaluate_1m_le_50ms"] = reev_ok;
  j["targets"]["reevaluate_frames_1m_le_50ms"] = frames_ok;
  j["targets"]["note"] =
      "per-cage seconds scaled to 1M points; reevaluate: cage_edit_set_control_points + "
      "reevaluate_points_and_derivatives_kept_buffers; reevaluate_frames: reevaluate_total";
  std::cout << j.dump(2) << std::endl;
  return 0;
}
