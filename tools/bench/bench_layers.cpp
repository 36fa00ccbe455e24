// strata_bench_layers: layered models (issue 5). For each scan given: the time of
// LayeredModel::build (3 bands by default), of writing and reading the .strata file, its size
// against the scan written as OBJ (write_mesh), whether the finest band reads back bit for bit,
// and the time of a 90-degree bend at band 0 and of muting and restoring band 1. --min-faces N
// first refines a scan by midpoint subdivision (every triangle into 4, the surface unchanged)
// until it has at least N faces, to reach a size no bundled scan has. Prints one JSON document.
//
//   strata_bench_layers assets/scans/armadillo.off [--min-faces 100000] [--bands 3]
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stats_json.h"
#include "strata/layers/model.h"
#include "strata/mesh_io.h"
#include "strata/process.h"
#include "strata/reconstruction.h"

using namespace strata;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

long long peak_rss_bytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<long long>(ru.ru_maxrss) * 1024;
}

// Every triangle into four, new vertices at the edge midpoints.
TriMesh midpoint_subdivide(const TriMesh& m) {
  TriMesh out;
  out.vertices = m.vertices;
  std::map<std::pair<int, int>, int> mid;
  auto midpoint = [&](int a, int b) {
    const auto k = std::minmax(a, b);
    auto it = mid.find(k);
    if (it != mid.end()) return it->second;
    out.vertices.push_back((m.vertices[a] + m.vertices[b]) / 2);
    return mid[k] = out.num_vertices() - 1;
  };
  for (const Face& f : m.faces) {
    const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
    out.faces.insert(out.faces.end(), {{f[0], a, c}, {f[1], b, a}, {f[2], c, b}, {a, b, c}});
  }
  return out;
}

// A generic 90-degree bend of the top of the model (+y) at band 0: region = the cage vertices above
// 60% of the cage's height, handle = those above 80%, rotated about x.
layers::CascadeReport bend_top(layers::LayeredModel& model) {
  const std::vector<Vec3>& c = model.band_points(0);
  Vec3 lo = c[0], hi = c[0];
  for (const Vec3& p : c) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double h = hi.y() - lo.y();
  EditStep step;
  step.region = Selection::halfspace(Vec3(0, lo.y() + 0.6 * h, 0), Vec3(0, 1, 0));
  step.handle = Selection::halfspace(Vec3(0, lo.y() + 0.8 * h, 0), Vec3(0, 1, 0));
  const Vec3 pivot = (lo + hi) / 2 + Vec3(0, 0.2 * h, 0);
  step.transform = EditTransform::rotation(Vec3(1, 0, 0), 90.0, pivot);
  return model.edit(0, step);
}

}  // namespace

int main(int argc, char** argv) {
  strata::reexec_with_huge_page_malloc(argv);  // as the strata tool runs (process.h)
  std::vector<std::string> scans;
  int min_faces = 0, bands = 3;
  std::vector<std::string> sets;  // --set NAME=VALUE: ReconstructOptions of the model
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc)
      sets.push_back(argv[++i]);
    else if (a == "--min-faces" && i + 1 < argc)
      min_faces = std::stoi(argv[++i]);
    else if (a == "--bands" && i + 1 < argc)
      bands = std::stoi(argv[++i]);
    else if (a == "--help" || a == "-h") {
      std::cout
          << "usage: strata_bench_layers SCAN... [--min-faces N] [--bands B] [--set OPTION=VALUE]\n"
             "  --set: a ReconstructOptions field of the model's solves (as strata reconstruct --set)\n";
      return 0;
    } else
      scans.push_back(a);
  }
  if (scans.empty()) {
    std::cerr << "strata_bench_layers: give at least one scan\n";
    return 2;
  }
  const fs::path tmp = fs::temp_directory_path() / ("strata_bench_layers_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  nlohmann::json runs = nlohmann::json::array();
  for (const std::string& path : scans) {
    nlohmann::json r{{"scan", path}};
    try {
      TriMesh scan = read_mesh(path);
      int refinements = 0;
      while (scan.num_faces() < min_faces) {
        scan = midpoint_subdivide(scan);
        ++refinements;
      }
      r["midpoint_refinements"] = refinements;
      r["faces"] = scan.num_faces();
      r["vertices"] = scan.num_vertices();
      const std::string obj = (tmp / "scan.obj").string(), model_path = (tmp / "model.strata").string();
      write_mesh(scan, obj);
      layers::BuildOptions o;
      o.bands = bands;
      for (const std::string& kv : sets) set_reconstruct_option(o.model.reconstruct, kv);
      auto t = Clock::now();
      layers::LayeredModel model = layers::LayeredModel::build(scan, o);
      r["build_seconds"] = since(t);
      t = Clock::now();
      layers::write_model(model, model_path);
      r["write_seconds"] = since(t);
      t = Clock::now();
      layers::LayeredModel back = layers::read_model(model_path);
      r["read_seconds"] = since(t);
      const auto strata_bytes = fs::file_size(model_path), obj_bytes = fs::file_size(obj);
      r["strata_bytes"] = strata_bytes;
      r["obj_bytes"] = obj_bytes;
      r["size_ratio_to_obj"] = static_cast<double>(strata_bytes) / static_cast<double>(obj_bytes);
      const std::vector<Vec3>& fin = back.band(back.num_bands() - 1).mesh.vertices;
      r["finest_band_bit_exact"] =
          back.band(back.num_bands() - 1).mesh.faces == scan.faces && fin.size() == scan.vertices.size() &&
          std::memcmp(fin.data(), scan.vertices.data(), fin.size() * sizeof(Vec3)) == 0;
      nlohmann::json band_sizes = nlohmann::json::array();
      for (int k = 0; k < model.num_bands(); ++k)
        band_sizes.push_back(k == 0 ? model.band(0).cage.num_faces() : model.band(k).mesh.num_faces());
      r["band_faces"] = band_sizes;
      t = Clock::now();
      const layers::CascadeReport bend = bend_top(model);
      r["bend_band0_seconds"] = since(t);
      nlohmann::json rebuilt = nlohmann::json::array();
      for (const layers::BandRebuild& b : bend.rebuilt)
        rebuilt.push_back({{"band", b.band},
                           {"solved_vertices", b.solved_vertices},
                           {"rigid_vertices", b.rigid_vertices},
                           {"max_relative_error", b.volume.max_relative_error},
                           {"seconds", b.seconds},
                           {"stats", strata::tools::stats_json(b.stats)},
                           {"solve_phases", strata::tools::solve_phases_json(b.stats)}});
      r["bend_band0_rebuilt"] = rebuilt;
      t = Clock::now();
      back.set_amplitude(1, 0.0);
      r["mute_band1_seconds"] = since(t);
      t = Clock::now();
      back.set_amplitude(1, 1.0);
      r["unmute_band1_seconds"] = since(t);
      r["peak_rss_bytes"] = peak_rss_bytes();
      r["targets"] = {{"build_seconds_at_100k_faces", 10.0}, {"size_ratio_to_obj", 2.0}};
    } catch (const std::exception& e) {
      r["error"] = e.what();
    }
    runs.push_back(r);
  }
  fs::remove_all(tmp);
  std::cout << nlohmann::json{{"benchmark", "strata_bench_layers"}, {"runs", runs}}.dump(2) << std::endl;
  return 0;
}
