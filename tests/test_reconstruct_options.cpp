// set_reconstruct_option(): ReconstructOptions by field name, as the CLI's and the benchmark's
// --set NAME=VALUE give them.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "paper_cases.h"
#include "strata/encoding.h"
#include "strata/exceptions.h"
#include "strata/reconstruction.h"

namespace strata {
namespace {

TEST(ReconstructOptionNames, SetEachKindOfField) {
  ReconstructOptions o;
  set_reconstruct_option(o, "volume_scales", "7");
  set_reconstruct_option(o, "tolerance", "2.5e-5");
  set_reconstruct_option(o, "retry_on_new_intersections", "false");
  set_reconstruct_option(o, "polish_solver", "multigrid");
  set_reconstruct_option(o, "step_solver", "direct");
  set_reconstruct_option(o, "multigrid.iterations", "20");
  set_reconstruct_option(o, "multigrid.smoothness", "0.1");
  set_reconstruct_option(o, "threads", "-1");  // parsed; VolumeReconstructor checks the range
  set_reconstruct_option(o, "tangential_regularization", "rest_laplacian");
  set_reconstruct_option(o, "coarsest_max_cycles", "10");
  EXPECT_EQ(o.tangential_regularization, TangentialRegularization::RestLaplacian);
  EXPECT_EQ(o.coarsest_max_cycles, 10);
  EXPECT_EQ(o.volume_scales, 7);
  EXPECT_EQ(o.tolerance, 2.5e-5);
  EXPECT_FALSE(o.retry_on_new_intersections);
  EXPECT_EQ(o.polish_solver, VolumeStepSolver::Multigrid);
  EXPECT_EQ(o.step_solver, VolumeStepSolver::Direct);
  EXPECT_EQ(o.multigrid.iterations, 20);
  EXPECT_EQ(o.multigrid.smoothness, 0.1);
  EXPECT_EQ(o.threads, -1);
  // Nothing else moved.
  ReconstructOptions d;
  EXPECT_EQ(o.volume_iterations, d.volume_iterations);
  EXPECT_EQ(o.multigrid.polish_iterations, d.multigrid.polish_iterations);
}

// Every listed name is settable by a value of one of the five kinds, and exactly one kind: the
// table and the names agree.
TEST(ReconstructOptionNames, EveryNameTakesExactlyOneKindOfValue) {
  const std::vector<std::string> names = reconstruct_option_names();
  ASSERT_GE(names.size(), 38u);
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const std::string& n : names) {
    int accepted = 0;
    for (const char* v : {"3", "true", "direct", "rest_laplacian"}) {
      ReconstructOptions o;
      try {
        set_reconstruct_option(o, n, v);
        ++accepted;
      } catch (const InvalidInput&) {
      }
    }
    EXPECT_EQ(accepted, 1) << n;
  }
}

TEST(ReconstructOptionNames, RejectsUnknownNamesAndMalformedValuesNamingThem) {
  auto message = [](const std::string& name, const std::string& value) {
    ReconstructOptions o;
    try {
      set_reconstruct_option(o, name, value);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("volume_scale", "3").find("unknown reconstruction option 'volume_scale'"),
            std::string::npos);
  EXPECT_NE(message("volume_scales", "3.5").find("volume_scales: '3.5' is not a whole number"),
            std::string::npos);
  EXPECT_NE(message("volume_scales", "").find("is not a whole number"), std::string::npos);
  EXPECT_NE(message("volume_scales", "99999999999").find("is not a whole number"), std::string::npos);
  EXPECT_NE(message("tolerance", "nan").find("tolerance: 'nan' is not a finite number"), std::string::npos);
  EXPECT_NE(message("tolerance", "1e999").find("is not a finite number"), std::string::npos);
  EXPECT_NE(message("tolerance", "0.1x").find("is not a finite number"), std::string::npos);
  EXPECT_NE(message("retry_on_new_intersections", "1").find("is not true or false"), std::string::npos);
  EXPECT_NE(message("polish_solver", "cholesky").find("is not jacobi_cg, direct or multigrid"),
            std::string::npos);
  EXPECT_NE(message("tangential_regularization", "laplacian").find("is not rest_offset or rest_laplacian"),
            std::string::npos);
  EXPECT_NE(message("progress", "x").find("unknown"), std::string::npos);  // a callback: not settable
  // Plain decimals only, blanks on either side refused alike (strtod took leading ones only, and
  // hexadecimal for reals only); a subnormal is a number.
  for (const char* v : {" 3", "3 ", "\t3", "0x10", "+", "1e", ".e3"}) {
    EXPECT_NE(message("volume_scales", v).find("is not a whole number"), std::string::npos) << v;
    EXPECT_NE(message("tolerance", v).find("is not a finite number"), std::string::npos) << v;
  }
  ReconstructOptions d;
  set_reconstruct_option(d, "tolerance", "1e-310");
  EXPECT_EQ(d.tolerance, 1e-310);
  set_reconstruct_option(d, "tolerance", "-.5E+2");
  EXPECT_EQ(d.tolerance, -50.0);
  set_reconstruct_option(d, "volume_scales", "+7");
  EXPECT_EQ(d.volume_scales, 7);
  // One NAME=VALUE argument, as --set gives it: split at the first '='.
  ReconstructOptions o;
  set_reconstruct_option(o, "multigrid.tolerance=0.05");
  EXPECT_EQ(o.multigrid.tolerance, 0.05);
  EXPECT_THROW(set_reconstruct_option(o, "tolerance"), InvalidInput);
  EXPECT_THROW(set_reconstruct_option(o, "tolerance=1=2"), InvalidInput);  // value '1=2'
}

// named_reconstruct_options(): the tools' --solver names give the presets' functions, field by
// field where the presets differ; any other name is refused by name.
TEST(ReconstructOptionNames, PresetsByName) {
  auto expect_same = [](const ReconstructOptions& a, const ReconstructOptions& b) {
    EXPECT_EQ(a.step_solver, b.step_solver);
    EXPECT_EQ(a.polish_solver, b.polish_solver);
    EXPECT_EQ(a.tangential_regularization, b.tangential_regularization);
    EXPECT_EQ(a.volume_scales, b.volume_scales);
    EXPECT_EQ(a.max_cycles, b.max_cycles);
    EXPECT_EQ(a.finest_intermediate_solves, b.finest_intermediate_solves);
    EXPECT_EQ(a.intermediate_regularized_levels, b.intermediate_regularized_levels);
    EXPECT_EQ(a.local_polish_max_fraction, b.local_polish_max_fraction);
    EXPECT_EQ(a.multigrid.smoothing_degree, b.multigrid.smoothing_degree);
    EXPECT_EQ(a.multigrid.polish_damping, b.multigrid.polish_damping);
    EXPECT_EQ(a.multigrid.tangential_damping, b.multigrid.tangential_damping);
  };
  expect_same(named_reconstruct_options("legacy"), ReconstructOptions{});
  expect_same(named_reconstruct_options("multigrid"), multigrid_reconstruct_options());
  expect_same(named_reconstruct_options("cycles"), cycle_schedule_reconstruct_options());
  // The three differ where the test looks, so that it would see a name mapped to the wrong one.
  EXPECT_NE(ReconstructOptions{}.step_solver, multigrid_reconstruct_options().step_solver);
  EXPECT_NE(multigrid_reconstruct_options().volume_scales,
            cycle_schedule_reconstruct_options().volume_scales);
  for (const std::string name : {"", "Multigrid", "auto", "direct"}) {
    try {
      named_reconstruct_options(name);
      ADD_FAILURE() << "accepted '" << name << "'";
    } catch (const InvalidInput& ex) {
      EXPECT_EQ(std::string(ex.what()),
                "unknown reconstruction preset '" + name + "' (legacy, multigrid or cycles)");
    }
  }
}

// An option out of the solver's range is refused by VolumeReconstructor with its name and value,
// so that a --set that parses but cannot work says which one it was.
TEST(ReconstructOptionNames, TheSolverNamesAnOptionOutOfRange) {
  cases::CylinderCaseOptions co;
  co.target_detail_triangles = 500;
  const cases::CylinderCase c = cases::make_cylinder_case(co);
  const DetailEncoding e = encode_detail(c.detail, c.base);
  auto refusal = [&](const std::string& name, const std::string& value) {
    ReconstructOptions o;
    set_reconstruct_option(o, name, value);
    try {
      VolumeReconstructor rec(e, o);
    } catch (const InvalidInput& ex) {
      return std::string(ex.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal("volume_scales", "0"),
            "reconstruction option volume_scales = 0 is out of range (1-1000)");
  // Counts are bounded above too: 2^31 volume scales ran for ever.
  EXPECT_EQ(refusal("volume_scales", "2147483647"),
            "reconstruction option volume_scales = 2147483647 is out of range (1-1000)");
  EXPECT_EQ(refusal("threads", "-2"),
            "reconstruction option threads = -2 is out of range (0-1024; 0 is all cores)");
  // TBB crashed on an arena of 65,537 threads.
  EXPECT_EQ(refusal("threads", "100000"),
            "reconstruction option threads = 100000 is out of range (0-1024; 0 is all cores)");
  EXPECT_EQ(refusal("coarsening_ratio", "1"),
            "reconstruction option coarsening_ratio = 1 is out of range (between 0 and 1)");
  EXPECT_EQ(refusal("multigrid.damping", "0"),
            "reconstruction option multigrid.damping = 0 is out of range (above 0)");
  EXPECT_EQ(refusal("polish_solver", "jacobi_cg"),
            "reconstruction option polish_solver = jacobi_cg is out of range (direct or multigrid)");
  EXPECT_EQ(refusal("tangential_lambda", "-0.5"),
            "reconstruction option tangential_lambda = -0.5 is out of range (0-1000)");
  EXPECT_EQ(refusal("local_polish_max_fraction", "1.5"),
            "reconstruction option local_polish_max_fraction = 1.5 is out of range (0 to 1)");
  EXPECT_EQ(refusal("multigrid.retry_iterations", "-1"),
            "reconstruction option multigrid.retry_iterations = -1 is out of range (0-100000)");
  EXPECT_EQ(
      refusal("multigrid.polish_smoothness_decay", "0"),
      "reconstruction option multigrid.polish_smoothness_decay = 0 is out of range (above 0, at most 1)");
  EXPECT_EQ(
      refusal("multigrid.polish_smoothness_decay", "1.5"),
      "reconstruction option multigrid.polish_smoothness_decay = 1.5 is out of range (above 0, at most 1)");
  EXPECT_EQ(refusal("multigrid.smoothing_degree", "9"),
            "reconstruction option multigrid.smoothing_degree = 9 is out of range (1-8)");
  EXPECT_EQ(refusal("coarsest_max_cycles", "-1"),
            "reconstruction option coarsest_max_cycles = -1 is out of range (0-100000; 0 is max_cycles)");
  EXPECT_EQ(refusal("volume_scales", "3"), "accepted");
  // The rest Laplacian needs the original base's frames, which an encoding built by hand may lack.
  DetailEncoding bare = e;
  bare.base_rest_normals.clear();
  bare.base_rest_tangents.clear();
  ReconstructOptions o;
  o.tangential_regularization = TangentialRegularization::RestLaplacian;
  try {
    VolumeReconstructor rec(bare, o);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& ex) {
    EXPECT_NE(std::string(ex.what()).find("tangential_regularization = rest_laplacian"), std::string::npos);
  }
  EXPECT_NO_THROW(VolumeReconstructor(bare, ReconstructOptions{}));
}

}  // namespace
}  // namespace strata
