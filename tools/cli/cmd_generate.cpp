// `strata generate`: write one of the paper's Fig. 6 cases as three OBJ files.
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "common.h"
#include "strata/exceptions.h"
#include "strata/mesh_io.h"

namespace strata::cli {

namespace {

struct GenerateCmdOptions {
  std::string case_name;
  int triangles = 0;
  double bend_degrees = 90.0;
  double jitter = 0.0;
  std::string out_dir;
};

int run_generate(const GenerateCmdOptions& o) {
  const std::optional<cases::DetailKind> kind = cases::parse_detail_kind(o.case_name);
  if (!kind) throw InvalidInput("unknown case '" + o.case_name + "' (expected bumps, rings or cuboid)");
  cases::CylinderCaseOptions options = paper_case_options(*kind, o.triangles, o.bend_degrees);
  options.jitter = o.jitter;
  const cases::CylinderCase c = cases::make_cylinder_case(options);
  ensure_directory(o.out_dir);
  const std::filesystem::path dir(o.out_dir);
  const std::pair<const TriMesh*, const char*> files[] = {
      {&c.detail, "detail.obj"}, {&c.base, "base.obj"}, {&c.edited_base, "edited_base.obj"}};
  StagedOutputs staged;  // a failed write leaves none of the three (detail.obj was left alone)
  for (const auto& [mesh, file] : files)
    staged.write((dir / file).string(), [&, m = mesh](const std::string& p) { write_mesh(*m, p); });
  staged.commit();
  for (const auto& [mesh, file] : files)
    std::cout << "wrote " << (dir / file).string() << ": " << mesh->num_vertices() << " vertices, "
              << mesh->num_faces() << " faces\n";
  std::cout << "case " << c.name << ": bend " << o.bend_degrees << " degrees, inner bend radius "
            << c.inner_bend_radius << ", max detail height " << c.max_detail_height << std::endl;
  return 0;
}

}  // namespace

Subcommand register_generate(CLI::App& parent) {
  auto o = std::make_shared<GenerateCmdOptions>();
  CLI::App* app = parent.add_subcommand(
      "generate", "Write a paper case (Fig. 6): detail.obj, base.obj and the bent edited_base.obj");
  app->add_option("--case", o->case_name, "bumps, rings or cuboid")
      ->required()
      ->check(CLI::IsMember({"bumps", "rings", "cuboid"}));
  app->add_option("--triangles", o->triangles, "About this many detail triangles (0: the paper's resolution)")
      ->check(in_range(0, 50000000))
      ->capture_default_str();
  app->add_option("--bend-degrees", o->bend_degrees, "Bend angle of the edited base, in degrees")
      ->check(in_range(0.0, 360.0))
      ->capture_default_str();
  app->add_option("--jitter", o->jitter,
                  "Irregular detail triangulation, as a scan's: vertices moved by up to this fraction of the "
                  "grid spacing, then Delaunay in the tube's parameter plane (0: the regular grid)")
      ->check(in_range(0.0, 0.45))
      ->capture_default_str();
  app->add_option("--out-dir", o->out_dir, "Directory to write the three meshes to (created if needed)")
      ->required();
  return {app, [o] { return run_generate(*o); }};
}

}  // namespace strata::cli
