// `strata stats`: size, boundary, extent, volume and self-intersections of one mesh.
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

struct StatsCmdOptions {
  std::string mesh;
  bool json = false;
  //! Exact triangle-pair tests of the self-intersection search at most; 0: the tools' bound,
  //! bounded_intersection_options() (50 million + 200 per face).
  long long max_tests = 0;
};

//! Undirected edges used by exactly one face.
std::size_t count_boundary_edges(const TriMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * mesh.faces.size());
  for (const Face& f : mesh.faces)
    for (int k = 0; k < 3; ++k) edges.emplace_back(std::minmax(f[k], f[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  std::size_t boundary = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) ++boundary;
    i = j;
  }
  return boundary;
}

int run_stats(const StatsCmdOptions& o) {
  const NamedMesh m = read_named_mesh(o.mesh);
  const std::size_t boundary = count_boundary_edges(m.mesh);
  Stopwatch sw;
  IntersectionOptions search = bounded_intersection_options(m.mesh.faces.size());
  if (o.max_tests > 0) search.max_tests = static_cast<std::size_t>(o.max_tests);
  const IntersectionResult isect = find_self_intersections(m.mesh.vertices, m.mesh.faces, search);
  const double isect_seconds = sw.seconds();
  if (isect.truncated) std::cerr << "strata: warning: " << cut_short_text(isect, m.name) << std::endl;
  json r{{"mesh", m.name},
         {"vertices", m.mesh.num_vertices()},
         {"faces", m.mesh.num_faces()},
         {"boundary_edges", boundary},
         {"closed", boundary == 0},
         {"bbox_diagonal", bbox_diagonal(m.mesh.vertices)},
         {"signed_volume", signed_volume(m.mesh)},
         {"self_intersecting_pairs", isect.num_pairs},
         {"self_intersections_cut_short", isect.truncated},
         {"self_intersection_tests", isect.num_tests},
         {"intersection_seconds", isect_seconds}};
  r.update(attributes_json(m.attributes));
  r.erase("companion_files");  // not read here: stats reads the mesh alone
  if (o.json) {
    std::cout << r.dump(2, ' ', false, json::error_handler_t::replace) << std::endl;
    return 0;
  }
  std::cout << "mesh                     " << m.name << "\n"
            << "vertices                 " << m.mesh.num_vertices() << "\n"
            << "faces                    " << m.mesh.num_faces() << "\n"
            << "boundary edges           " << boundary << (boundary == 0 ? " (closed)" : " (open)") << "\n"
            << "bbox diagonal            " << r["bbox_diagonal"].get<double>() << "\n"
            << "signed volume            " << r["signed_volume"].get<double>()
            << (boundary == 0 ? "" : " (open mesh: not an enclosed volume)") << "\n"
            << "self-intersecting pairs  " << (isect.truncated ? "at least " : "") << isect.num_pairs
            << " (non-adjacent triangles, found in " << fixed(isect_seconds, 3) << " s)\n"
            << "vertex colours           " << r["vertex_colors"].get<std::string>() << "\n"
            << "texture coordinates      "
            << (!m.attributes.texcoords.empty()         ? "per vertex"
                : !m.attributes.corner_uv_index.empty() ? "per face corner (texture seams)"
                                                        : "none")
            << "\n"
            << "materials                " << m.attributes.material_names.size()
            << (m.attributes.material_library.empty() ? ""
                                                      : " (library " + m.attributes.material_library + ")")
            << "\n"
            << "texture images           " << m.attributes.texture_files.size() << std::endl;
  return 0;
}

}  // namespace

Subcommand register_stats(CLI::App& parent) {
  auto o = std::make_shared<StatsCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "stats", "Print a mesh's size, boundary, extent, volume and self-intersecting triangle pairs");
  app->add_option("mesh", o->mesh, "Mesh file (.obj, .off, .ply, .stl)")->required();
  app->add_flag("--json", o->json, "Print the statistics as JSON");
  // Why: a pipeline that checks many scans bounds each search's time (a search cut short gives a
  // lower bound and a warning, as at the default bound).
  app->add_option("--max-intersection-tests", o->max_tests,
                  "Exact triangle-pair tests of the self-intersection search at most; past them the "
                  "count is a lower bound, with a warning (0: 50 million + 200 per face)")
      ->check(in_range(0, 1e12))
      ->capture_default_str();
  return {app, [o] { return run_stats(*o); }};
}

}  // namespace strata::cli
