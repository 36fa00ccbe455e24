// strata_bench: timings, throughput, peak memory and accuracy of the volumetric reconstruction on
// the paper's bent-cylinder cases (section 6), one forked child process per size so that the peak
// resident set size is per size. Prints one JSON document (stdout, and --out FILE if given);
// progress lines go to stderr. A measurement: exits 0 even when targets fail, non-zero on errors.
//
// Single-thread: ReconstructOptions::threads = 1 (--set threads=N to compare); CHOLMOD factorizes
// on the calling thread (the SDK caps its hard-coded num_threads(4) regions; OMP_NUM_THREADS=1,
// set by re-executing when unset, pins any other OpenMP pool); the self-intersection search runs
// with IntersectionOptions::parallel = false.
//
// --jitter J: the scan-like (irregular) triangulation of the cases (CylinderCaseOptions::jitter).
// --shuffle SEED: the detail's vertices and faces numbered at random (seeded), as a tool that
// hashes its vertices writes a scan (ReconstructOptions::renumber_for_locality; 0: the grid's order).
// --solver multigrid|cycles: multigrid_reconstruct_options() or cycle_schedule_reconstruct_options()
// instead of the defaults (--set still applies after it).
// --repeat N: N reconstructions with the same VolumeReconstructor (its hierarchy kept, as an
// application reconstructing over one encoding does); the times are their median, each run's time
// is listed, and the runs must give the same positions bit for bit (else the size is an error).
// On a shared VM single runs of the same solve vary by up to 1.5x: the median of a few is what
// another run reproduces.
// --min-run-seconds S (default 5): past --repeat, the runs go on until their wall times add up
// to S (100 runs at most), so that the small sizes, whose single runs vary most (the 100k median
// of three moved between 0.59 and 1.10 s from one benchmark run to the next), get a median of
// more runs (on this project's 2-core VM, --repeat 3 at 1M already takes longer than 5 s). Keep S
// well under --max-seconds, which kills a size's child with all its runs.
// --rounds R (default 1): the whole sequence of sizes R times over, each size's child in turn
// (10k, 100k, 1M, 10k, 100k, 1M, ...), and each size's runs of all rounds taken together: the
// machine's speed drifts over minutes (the 100k median moved 0.62-0.85 s between runs of the
// command), and a 1M child that runs long after its 100k one skews their ratio; interleaved, both
// sizes sample the same stretch of time.
// --round-trip: after the bend's runs, one more clean-start reconstruction by the same solver over
// the unedited base, reported as accuracy.round_trip: the largest distance of a detail vertex from
// its rest position over the rest detail's bounding-box diagonal (the 0.5% target), its new
// intersecting pairs and its time. The bend's memory figures are read before it.

#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "paper_cases.h"
#include "stats_json.h"
#include "strata/encoding.h"
#include "strata/intersections.h"
#include "strata/metrics.h"
#include "strata/process.h"
#include "strata/reconstruction.h"

namespace {

using json = nlohmann::json;
using namespace strata;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU seconds of this process (all threads): less sensitive than wall time to a loaded machine.
double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The multigrid passes (volume scales) that solve the finest level's volume constraints: the
// throughput counts those, not the intermediate scales' coarse-level-only passes.
int finest_passes(const ReconstructOptions& o) {
  return o.finest_intermediate_solves ? o.volume_scales : 1;
}

// The median of \p v (the mean of the middle two for an even count); v is not empty.
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

long long max_rss_bytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<long long>(ru.ru_maxrss) * 1024;  // Linux reports kilobytes
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos)
      return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

struct Args {
  std::vector<int> sizes{10000, 100000, 1000000};
  cases::DetailKind detail = cases::DetailKind::Bumps;
  std::string out;
  double max_seconds = 900.0;
  double jitter = 0.0;
  unsigned shuffle = 0;              // --shuffle SEED (0: none)
  int finest_volume_iterations = 0;  // 0: the options' own
  int repeat = 1;                    // reconstructions per size (--repeat)
  double min_run_seconds = 5.0;      // more runs until their wall times add up to this
  int rounds = 1;                    // the size sequence this many times, interleaved (--rounds)
  bool round_trip = false;           // also a clean start over the unedited base (--round-trip)
  bool help = false;
  ReconstructOptions reconstruct;  // --solver's preset on one solver thread, then --set
};

const char* solver_name(VolumeStepSolver s) {
  return s == VolumeStepSolver::Direct      ? "direct"
         : s == VolumeStepSolver::Multigrid ? "multigrid"
                                            : "jacobi_cg";
}

// Whether all of \p v is a number (std::stoll's or std::stod's, by \p out's type) within the type's
// range; if so, it is in \p out.
template <class T>
bool read_whole(const std::string& v, T& out) {
  std::size_t used = 0;
  try {
    if constexpr (std::is_same_v<T, double>)
      out = std::stod(v, &used);
    else
      out = std::stoll(v, &used);
  } catch (const std::exception&) {
    return false;  // not a number, or out of range
  }
  return used != 0 && used == v.size();
}

Args parse_args(int argc, char** argv) {
  Args a;
  std::string solver = "legacy";
  std::vector<std::string> sets;  // applied after the --solver preset, whatever the order
  auto value = [&](int& i) -> std::string {
    if (i + 1 >= argc) throw std::runtime_error(std::string(argv[i]) + " needs a value");
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string opt = argv[i];
    if (opt == "--help" || opt == "-h") {
      a.help = true;
      return a;
    }
    if (opt == "--sizes") {
      a.sizes.clear();
      std::stringstream ss(value(i));
      for (std::string s; std::getline(ss, s, ',');) {
        std::size_t used = 0;
        const int n = std::stoi(s, &used);
        if (used != s.size() || n <= 0) throw std::runtime_error("bad size '" + s + "'");
        a.sizes.push_back(n);
      }
      if (a.sizes.empty()) throw std::runtime_error("--sizes is empty");
    } else if (opt == "--case") {
      const std::string v = value(i);
      const auto kind = cases::parse_detail_kind(v);
      if (!kind) throw std::runtime_error("unknown case '" + v + "' (bumps, rings or cuboid)");
      a.detail = *kind;
    } else if (opt == "--out") {
      a.out = value(i);
    } else if (opt == "--jitter") {
      a.jitter = std::stod(value(i));
    } else if (opt == "--shuffle") {
      const std::string v = value(i);
      long long seed = -1;
      if (!read_whole(v, seed) || seed < 0 || seed > 4294967295LL)
        throw std::runtime_error("--shuffle is a seed from 0 to 4294967295, got '" + v + "'");
      a.shuffle = static_cast<unsigned>(seed);
    } else if (opt == "--round-trip") {
      a.round_trip = true;
    } else if (opt == "--finest-volume-iterations") {
      a.finest_volume_iterations = std::stoi(value(i));
    } else if (opt == "--solver") {
      solver = value(i);  // an unknown name is refused below, by name
    } else if (opt == "--set") {
      sets.push_back(value(i));
    } else if (opt == "--repeat" || opt == "--rounds") {
      const std::string v = value(i);
      const long long most = opt == "--repeat" ? 100 : 20;
      long long n = 0;
      if (!read_whole(v, n) || n < 1 || n > most)
        throw std::runtime_error(opt + " is a whole number from 1 to " + std::to_string(most) + ", got '" +
                                 v + "'");
      (opt == "--repeat" ? a.repeat : a.rounds) = static_cast<int>(n);
    } else if (opt == "--min-run-seconds") {
      const std::string v = value(i);
      if (!read_whole(v, a.min_run_seconds) || !(a.min_run_seconds >= 0 && a.min_run_seconds <= 3600))
        throw std::runtime_error("--min-run-seconds is a number of seconds from 0 to 3600, got '" + v + "'");
    } else if (opt == "--max-seconds") {
      a.max_seconds = std::stod(value(i));
      if (!(a.max_seconds > 0)) throw std::runtime_error("--max-seconds must be > 0");
    } else {
      throw std::runtime_error("unknown argument '" + opt + "'");
    }
  }
  a.reconstruct = named_reconstruct_options(solver);
  a.reconstruct.threads = 1;  // the measure is single-threaded; --set threads=N to compare
  if (a.finest_volume_iterations > 0) a.reconstruct.finest_volume_iterations = a.finest_volume_iterations;
  for (const std::string& kv : sets) set_reconstruct_option(a.reconstruct, kv);  // --set NAME=VALUE
  return a;
}

// Everything measured for one size; runs in the child process.
json run_size(const Args& args, int size) {
  const long long start_rss = max_rss_bytes();
  // The whole child on the solver's threads (1 unless --set threads=N): the encoding and the
  // intersection counts used both cores through TBB's default arena.
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(std::max(1, args.reconstruct.threads)));
  const std::string tag = "strata_bench [" + std::to_string(size) + "]: ";
  auto log = [&](const std::string& s) { std::cerr << tag << s << std::endl; };
  json sec, cpu, rss;
  auto timed = [&](const char* name, auto&& f) {
    log(std::string(name) + "...");
    const auto t0 = Clock::now();
    const double c0 = cpu_seconds();
    auto r = f();
    sec[name] = since(t0);
    cpu[name] = cpu_seconds() - c0;
    rss[name] = max_rss_bytes();
    log(std::string(name) + " done in " + std::to_string(sec[name].get<double>()) + " s");
    return r;
  };
  IntersectionOptions io;
  io.collect_pairs = true;
  io.parallel = false;

  cases::CylinderCaseOptions co;
  co.detail = args.detail;
  co.target_detail_triangles = size;
  co.jitter = args.jitter;
  cases::CylinderCase c = timed("generate", [&] { return cases::make_cylinder_case(co); });
  if (args.shuffle != 0) c.detail = cases::shuffled_numbering(c.detail, args.shuffle);
  DetailEncoding enc = timed("encode", [&] { return encode_detail(c.detail, c.base); });
  const std::vector<Vec3> edited = std::move(c.edited_base.vertices);
  const std::vector<Vec3> unedited = args.round_trip ? std::move(c.base.vertices) : std::vector<Vec3>{};
  const int base_vertices = c.base.num_vertices(), base_faces = c.base.num_faces();
  c = {};  // an application keeps only the encoding and the edited base

  log("setup (hierarchy + factorization analysis)...");
  const VolumeReconstructor rec(std::move(enc), args.reconstruct);
  sec["setup"] = rec.setup_seconds();
  rss["setup"] = max_rss_bytes();
  const ReconstructResult r = timed("reconstruct", [&] { return rec.reconstruct(edited); });
  const ReconstructStats& st = r.stats;
  // --repeat: the same reconstruction again; every run's wall, CPU and solve seconds, then their
  // medians in place of the first run's.
  std::vector<double> wall{sec["reconstruct"].get<double>()}, cpus{cpu["reconstruct"].get<double>()},
      solves{st.seconds_solve}, frame_secs{st.seconds_frames};
  std::vector<json> phases{strata::tools::solve_phases_json(st)};
  constexpr int kMaxRuns = 100;
  auto more = [&](int k) {
    if (k < args.repeat) return true;
    return k < kMaxRuns && std::accumulate(wall.begin(), wall.end(), 0.0) < args.min_run_seconds;
  };
  for (int k = 1; more(k); ++k) {
    const auto t0 = Clock::now();
    const double c0 = cpu_seconds();
    const ReconstructResult again = rec.reconstruct(edited);
    wall.push_back(since(t0));
    cpus.push_back(cpu_seconds() - c0);
    solves.push_back(again.stats.seconds_solve);
    frame_secs.push_back(again.stats.seconds_frames);
    phases.push_back(strata::tools::solve_phases_json(again.stats));
    if (again.positions != r.positions)
      throw std::runtime_error("run " + std::to_string(k + 1) + " gave other positions than the first");
    log("reconstruct run " + std::to_string(k + 1) + " in " + std::to_string(wall.back()) + " s");
  }
  sec["reconstruct_runs"] = wall;
  // One reconstruction over a new encoding: the solver's setup (the hierarchy) and the first call,
  // which also counts the rest detail's own intersecting pairs once.
  sec["first_reconstruction"] = sec["setup"].get<double>() + wall.front();
  cpu["reconstruct_runs"] = cpus;
  sec["reconstruct"] = median(wall);
  cpu["reconstruct"] = median(cpus);
  sec["frames"] = median(frame_secs);
  sec["solve"] = median(solves);
  sec["solve_runs"] = solves;
  // The phases of the run whose solve took the median time (of an even count, the lower middle one).
  std::vector<std::size_t> order(solves.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return solves[i] < solves[j]; });
  sec["solve_phases"] = phases[order[(order.size() - 1) / 2]];

  // The caller's encoding: after the solves (a renumbering solver restores it on first use).
  const DetailEncoding& e = rec.encoding();
  const BaseFrames frames = evaluate_base_frames(e, edited);
  const VolumeMetrics vm = timed("volume_metrics", [&] { return volume_metrics(e, frames, r.positions); });
  const std::vector<Vec3> vec = timed("vectors", [&] { return reconstruct_vectors(e, frames); });
  const VolumeMetrics vv = volume_metrics(e, frames, vec);
  const auto in = timed("intersections_input",
                        [&] { return find_self_intersections(e.detail_rest, e.detail_faces, io); });
  const auto out = timed("intersections_volumes",
                         [&] { return find_self_intersections(r.positions, e.detail_faces, io); });
  const auto outv =
      timed("intersections_vectors", [&] { return find_self_intersections(vec, e.detail_faces, io); });
  const std::size_t new_pairs = count_new_intersections(in, out),
                    new_pairs_v = count_new_intersections(in, outv);

  const long long prisms = static_cast<long long>(e.detail_faces.size());
  const long long peak = max_rss_bytes();
  // --round-trip: the same solver over the unedited base, from the clean start.
  json round_trip = nullptr;
  if (args.round_trip) {
    const ReconstructResult t = timed("round_trip", [&] { return rec.reconstruct(unedited); });
    double off = 0.0;
    for (std::size_t i = 0; i < t.positions.size(); ++i)
      off = std::max(off, (t.positions[i] - e.detail_rest[i]).norm());
    const double diag = bbox_diagonal(e.detail_rest);
    const auto trip_out = find_self_intersections(t.positions, e.detail_faces, io);
    round_trip = json{{"max_vertex_distance", off},
                      {"bbox_diagonal", diag},
                      {"max_vertex_distance_over_diagonal", off / diag},
                      {"max_relative_error", t.stats.max_relative_error},
                      {"converged", t.stats.converged},
                      {"new_pairs", count_new_intersections(in, trip_out)},
                      {"within_half_a_percent", off <= 0.005 * diag}};
  }
  const double solve = sec["solve"].get<double>() > 0 ? sec["solve"].get<double>() : 1e-300;
  const bool err_ok = vm.max_relative_error <= 1e-3, rms_ok = vm.rms_relative_error <= 1e-4;
  // The measure (|V_j - V*_j| / mean |V*_j|, volume_metrics()), and each prism's error
  // relative to its own target as well (larger where targets are small: they span a factor of
  // about 80 on the bend).
  auto metrics = [&](const VolumeMetrics& m, const std::vector<Vec3>& positions) {
    const std::vector<double> v = prism_volumes(e.detail_faces, positions, frames.points);
    double mx = 0.0, sq = 0.0;
    std::size_t counted = 0;
    for (std::size_t j = 0; j < v.size(); ++j) {
      const double target = e.target_volumes[j];
      if (target == 0.0) continue;
      const double rel = std::abs(v[j] - target) / std::abs(target);
      mx = std::max(mx, rel);
      sq += rel * rel;
      ++counted;
    }
    return json{{"max_relative_error", m.max_relative_error},
                {"rms_relative_error", m.rms_relative_error},
                {"max_error_relative_to_own_target", mx},
                {"rms_error_relative_to_own_target", counted ? std::sqrt(sq / counted) : 0.0},
                {"total_volume_change", m.total_volume_change},
                {"dihedral_change_degrees", strata::tools::dihedral_change_json(
                                                dihedral_change(e.detail_faces, e.detail_rest, positions))}};
  };
  return json{{"size", size},
              {"repeat", args.repeat},
              {"runs", wall.size()},
              {"case", cases::to_string(args.detail)},
              {"jitter", args.jitter},
              {"shuffle", args.shuffle},
              {"prisms", prisms},
              {"detail_vertices", e.num_detail_vertices()},
              {"base_vertices", base_vertices},
              {"base_faces", base_faces},
              {"seconds", sec},
              {"cpu_seconds", cpu},
              {"stats", strata::tools::stats_json(st)},
              {"throughput",
               {{"constraint_updates_per_second", static_cast<double>(st.constraint_updates) / solve},
                {"prisms_per_second_per_multigrid_pass",
                 static_cast<double>(prisms) * finest_passes(rec.options()) / solve},
                {"finest_passes", finest_passes(rec.options())}}},
              {"accuracy",
               {{"definition",
                 "max / rms_relative_error: max_j and RMS_j of |V_j - V*_j| / mean_j |V*_j| (the issue's "
                 "metric, volume_metrics()); *_relative_to_own_target: of |V_j - V*_j| / |V*_j|"},
                {"volumes", metrics(vm, r.positions)},
                {"vectors", metrics(vv, vec)},
                {"round_trip", round_trip}}},
              {"intersections",
               {{"input_pairs", in.num_pairs},
                {"volumes_pairs", out.num_pairs},
                {"volumes_new_pairs", new_pairs},
                {"vectors_pairs", outv.num_pairs},
                {"vectors_new_pairs", new_pairs_v}}},
              {"memory",
               {{"child_start_rss_bytes", start_rss},
                {"peak_rss_bytes", peak},
                {"peak_rss_bytes_after_phase", rss},
                // bytes_per_prism (against the floor run's peak) is added by main().
                {"whole_process_bytes_per_prism", static_cast<double>(peak) / static_cast<double>(prisms)}}},
              {"targets",
               {{"max_relative_error_le_1e-3", err_ok},
                {"rms_relative_error_le_1e-4", rms_ok},
                {"no_new_intersections", new_pairs == 0},
                {"all", err_ok && rms_ok && new_pairs == 0}}}};
}

// Runs run_size() in a forked child; kills it after max_seconds. Returns its JSON object, or
// {"timed_out": true} or {"error": ...}.
json run_forked(const Args& args, int size) {
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    close(fd[0]);
    int code = 0;
    std::string text;
    try {
      text = run_size(args, size).dump();
    } catch (const std::exception& ex) {
      text = json{{"size", size}, {"error", ex.what()}}.dump();
      code = 1;
    }
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t w = write(fd[1], text.data() + done, text.size() - done);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) _exit(2);
      done += static_cast<std::size_t>(w);
    }
    _exit(code);
  }
  close(fd[1]);
  const auto deadline = Clock::now() + std::chrono::duration<double>(args.max_seconds);
  std::string text;
  bool timed_out = false;
  for (char buf[4096];;) {
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fd[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::min(left * 1000.0 + 1.0, 60000.0)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) throw std::runtime_error(std::string("poll: ") + std::strerror(errno));
    if (ready == 0) continue;
    const ssize_t n = read(fd[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // EOF: the child has exited (or closed the pipe on its way out)
    text.append(buf, static_cast<std::size_t>(n));
  }
  close(fd[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    std::cerr << "strata_bench [" << size << "]: killed after " << args.max_seconds << " s" << std::endl;
    return json{{"size", size}, {"timed_out", true}, {"max_seconds", args.max_seconds}};
  }
  json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    std::ostringstream why;
    why << "child produced no result (status " << status;
    if (WIFSIGNALED(status)) why << ", signal " << WTERMSIG(status);
    why << ")";
    j = json{{"size", size}, {"error", why.str()}};
  }
  return j;
}

const json* find_size(const json& results, int size) {
  for (const json& r : results)
    if (r.value("size", 0) == size) return &r;
  return nullptr;
}
bool completed(const json* r) {
  return r && r->contains("prisms");
}

// One size's result from its children of every round (--rounds): the first child's, with the
// runs of all of them together and the medians taken over those (the first reconstruction's over
// the rounds), the largest peak memory, and `rounds` listing each child's own medians. A child
// that failed, or whose results differ from the first's (the same solve in another process must
// give the same errors, pairs and iteration counts), makes the size an error.
json merge_rounds(std::vector<json>& rounds) {
  json r = std::move(rounds.front());
  if (rounds.size() == 1 || !completed(&r)) return r;
  std::vector<double> wall, cpus, solves, firsts;
  json per_round = json::array();
  long long peak = 0;
  for (std::size_t k = 0; k < rounds.size(); ++k) {
    const json& c = k == 0 ? r : rounds[k];
    if (!completed(&c)) return c;
    if (c["accuracy"] != r["accuracy"] || c["intersections"] != r["intersections"] ||
        c["stats"]["cg_iterations"] != r["stats"]["cg_iterations"])
      return json{{"size", r["size"]},
                  {"error", "round " + std::to_string(k + 1) + " gave other results than the first"}};
    for (const json& x : c["seconds"]["reconstruct_runs"]) wall.push_back(x.get<double>());
    for (const json& x : c["cpu_seconds"]["reconstruct_runs"]) cpus.push_back(x.get<double>());
    for (const json& x : c["seconds"]["solve_runs"]) solves.push_back(x.get<double>());
    firsts.push_back(c["seconds"]["first_reconstruction"].get<double>());
    peak = std::max(peak, c["memory"]["peak_rss_bytes"].get<long long>());
    per_round.push_back({{"reconstruct", c["seconds"]["reconstruct"]},
                         {"first_reconstruction", c["seconds"]["first_reconstruction"]},
                         {"setup", c["seconds"]["setup"]},
                         {"runs", c["runs"]},
                         {"peak_rss_bytes", c["memory"]["peak_rss_bytes"]}});
  }
  json& sec = r["seconds"];
  sec["reconstruct_runs"] = wall;
  sec["reconstruct"] = median(wall);
  sec["solve_runs"] = solves;
  sec["solve"] = median(solves);
  sec["first_reconstruction"] = median(firsts);
  r["cpu_seconds"]["reconstruct_runs"] = cpus;
  r["cpu_seconds"]["reconstruct"] = median(cpus);
  r["runs"] = wall.size();
  r["rounds"] = per_round;
  const double prisms = r["prisms"].get<double>();
  r["memory"]["peak_rss_bytes"] = peak;
  r["memory"]["whole_process_bytes_per_prism"] = static_cast<double>(peak) / prisms;
  // The throughputs, as run_size() defines them, over the median solve of all rounds (the solve
  // phases stay the first round's median run's).
  const double solve = std::max(sec["solve"].get<double>(), 1e-300);
  json& thr = r["throughput"];
  thr["constraint_updates_per_second"] = r["stats"]["constraint_updates"].get<double>() / solve;
  thr["prisms_per_second_per_multigrid_pass"] = prisms * thr["finest_passes"].get<double>() / solve;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  // libgomp reads OMP_NUM_THREADS when it is loaded, before main: re-execute with it set (and
  // with malloc on huge pages, as the strata tool and the viewer run: process.h).
  const bool omp_unset = !std::getenv("OMP_NUM_THREADS");
  if (omp_unset) {
    setenv("OMP_NUM_THREADS", "1", 1);
    setenv("OPENBLAS_NUM_THREADS", "1", 1);
  }
  strata::reexec_with_huge_page_malloc(argv, omp_unset);
  if (omp_unset) {  // not re-executed there (a program it started, say): for OMP_NUM_THREADS alone
    execv("/proc/self/exe", argv);
    std::perror("strata_bench: re-exec");
    return 1;
  }
  const char* usage =
      "usage: strata_bench [--sizes 10000,100000,1000000] [--case bumps|rings|cuboid] [--jitter J] "
      "[--shuffle SEED] [--solver legacy|multigrid|cycles] [--finest-volume-iterations N] [--set "
      "OPTION=VALUE] "
      "[--repeat N] [--min-run-seconds S] [--rounds R] [--round-trip] [--out FILE.json] [--max-seconds S]\n"
      "  Reconstructs the paper's 90-degree bend (section 6) at each size, in a child process per "
      "size,\n  and prints JSON: times, peak memory, accuracy, intersecting pairs and the issue's "
      "targets.\n  --jitter J: scan-like irregular detail triangulation (0: the regular grid)\n"
      "  --shuffle SEED: the detail's vertices and faces numbered at random (0: the grid's order)\n"
      "  --solver: legacy (the default options), multigrid (multigrid_reconstruct_options()) or cycles\n"
      "    (cycle_schedule_reconstruct_options(): the paper's schedule, a cycle per volume scale)\n"
      "  --set OPTION=VALUE: a ReconstructOptions field (multigrid.* for MultigridStepOptions)\n"
      "  --repeat N: N reconstructions per size with one solver object; times are their median, and\n"
      "    the runs must agree bit for bit\n"
      "  --min-run-seconds S: more runs past --repeat until their wall times add up to S seconds\n"
      "    (default 5; at most 100 runs): a steadier median for the small sizes\n"
      "  --rounds R: the sizes R times over, interleaved (a child per size and round); each size's\n"
      "    times are the medians over the runs of all its rounds (default 1)\n"
      "  --round-trip: also one clean-start reconstruction over the unedited base (accuracy.round_trip:\n"
      "    the largest vertex distance from the rest detail over its bounding-box diagonal)\n";
  Args args;
  try {
    args = parse_args(argc, argv);
  } catch (const std::exception& ex) {
    std::cerr << "strata_bench: " << ex.what() << "\n" << usage;
    return 2;
  }
  if (args.help) {
    std::cout << usage;
    return 0;
  }
  try {
    const std::string load_avg = load_average();
    // The memory floor: the same pipeline at kFloorSize prisms in a child of its own (the
    // libraries' pages and fixed allocations). A size's bytes per prism is its peak's growth over
    // the floor's per prism added: the slope of peak memory against prisms.
    constexpr int kFloorSize = 500;
    std::cerr << "strata_bench: memory floor (" << kFloorSize << " prisms)" << std::endl;
    const json floor = run_forked(args, kFloorSize);
    if (!completed(&floor)) throw std::runtime_error("the memory floor's run failed: " + floor.dump());
    const long long floor_rss = floor["memory"]["peak_rss_bytes"].get<long long>();
    const long long floor_prisms = floor["prisms"].get<long long>();
    json results = json::array();
    bool errors = false;
    // Each size's children, round by round (--rounds): the sizes interleaved, so that all of them
    // sample the same stretch of the machine's drifting speed.
    std::vector<std::vector<json>> children(args.sizes.size());
    for (int round = 0; round < args.rounds; ++round)
      for (std::size_t k = 0; k < args.sizes.size(); ++k) {
        const int size = args.sizes[k];
        std::cerr << "strata_bench: size " << size << " (" << cases::to_string(args.detail) << ")";
        if (args.rounds > 1) std::cerr << ", round " << round + 1 << " of " << args.rounds;
        std::cerr << std::endl;
        children[k].push_back(run_forked(args, size));
      }
    for (std::vector<json>& rounds : children) {
      json r = merge_rounds(rounds);
      if (completed(&r)) {
        json& m = r["memory"];
        const long long prisms = r["prisms"].get<long long>();
        m["floor_rss_bytes"] = floor_rss;
        m["floor_prisms"] = floor_prisms;
        m["bytes_per_prism"] =
            prisms > floor_prisms
                ? json(static_cast<double>(m["peak_rss_bytes"].get<long long>() - floor_rss) /
                       static_cast<double>(prisms - floor_prisms))
                : json(nullptr);
      }
      results.push_back(std::move(r));
      errors = errors || results.back().contains("error");
    }

    const ReconstructOptions& ro = args.reconstruct;
    const json* r100k = find_size(results, 100000);
    const json* r1m = find_size(results, 1000000);
    auto reconstruct_seconds = [](const json* r) { return (*r)["seconds"]["reconstruct"].get<double>(); };
    json ratio = nullptr;
    if (completed(r100k) && completed(r1m)) ratio = reconstruct_seconds(r1m) / reconstruct_seconds(r100k);
    // The same of the CPU times (informational: less sensitive than wall time to other work on a
    // shared machine).
    json cpu_ratio = nullptr;
    if (completed(r100k) && completed(r1m))
      cpu_ratio = (*r1m)["cpu_seconds"]["reconstruct"].get<double>() /
                  (*r100k)["cpu_seconds"]["reconstruct"].get<double>();
    // The same for a first reconstruction, setup included (a target of its own below: a pipeline
    // that reconstructs once pays the setup).
    json first_ratio = nullptr;
    if (completed(r100k) && completed(r1m))
      first_ratio = (*r1m)["seconds"]["first_reconstruction"].get<double>() /
                    (*r100k)["seconds"]["first_reconstruction"].get<double>();

    json per_size_throughput = json::object(), per_size_bytes = json::object(),
         per_size_whole_bytes = json::object(), per_size_trip = json::object();
    bool any_done = false, thr_ok = true, mem_ok = true, whole_mem_ok = true, acc_ok = true, trip_ok = true;
    for (const json& r : results) {
      if (!completed(&r)) continue;
      any_done = true;
      const std::string key = std::to_string(r["size"].get<int>());
      const double thr = r["throughput"]["prisms_per_second_per_multigrid_pass"].get<double>();
      per_size_throughput[key] = thr;
      thr_ok = thr_ok && thr >= 1e6;
      const json& bpp = r["memory"]["bytes_per_prism"];
      per_size_bytes[key] = bpp;
      mem_ok = mem_ok && bpp.is_number() && bpp.get<double>() <= 1024.0;
      const double whole = r["memory"]["whole_process_bytes_per_prism"].get<double>();
      per_size_whole_bytes[key] = whole;
      whole_mem_ok = whole_mem_ok && whole <= 1024.0;
      acc_ok = acc_ok && r["targets"]["all"].get<bool>();
      const json& trip = r["accuracy"]["round_trip"];
      if (!trip.is_null()) {
        per_size_trip[key] = trip["max_vertex_distance_over_diagonal"];
        trip_ok = trip_ok && trip["within_half_a_percent"].get<bool>();
      }
    }
    auto verdict = [&](bool ok) { return any_done ? json(ok) : json(nullptr); };
    const json trip_target = {
        {"definition",
         "--round-trip: the largest distance of a detail vertex from its rest position after a "
         "clean-start reconstruction over the unedited base, over the rest detail's bounding-box "
         "diagonal, at most 0.005, every completed size (null without --round-trip)"},
        {"values", per_size_trip},
        {"pass", args.round_trip ? verdict(trip_ok) : json(nullptr)}};
    json t100k = nullptr, tscale = nullptr, tscale_first = nullptr;
    if (completed(r100k))
      t100k = reconstruct_seconds(r100k) <= 2.0;
    else if (r100k && r100k->value("timed_out", false))
      t100k = false;
    if (ratio.is_number())
      tscale = ratio.get<double>() <= 12.0;
    else if (completed(r100k) && r1m && r1m->value("timed_out", false))
      tscale = false;
    if (first_ratio.is_number())
      tscale_first = first_ratio.get<double>() <= 12.0;
    else if (tscale.is_boolean())
      tscale_first = tscale;

    const json report {
      {"benchmark", "strata_bench: volumetric reconstruction over the bent cylinder (paper, section 6)"},
          {"case", cases::to_string(args.detail)}, {"jitter", args.jitter}, {"shuffle", args.shuffle},
          {"sizes", args.sizes}, {"max_seconds", args.max_seconds}, {"min_run_seconds", args.min_run_seconds},
          {"rounds", args.rounds},
          {"machine",
           {{"nproc", sysconf(_SC_NPROCESSORS_ONLN)},
            {"cpu_model", cpu_model()},
            {"compiler", __VERSION__},
            {"load_average_at_start", load_avg},
            {"load_average_at_end", load_average()},
#ifdef NDEBUG
            {"ndebug", true}}},
#else
            {"ndebug", false}}},
#endif
          {"threads",
           {{"note",
             "every phase of a size's child runs on reconstruct_options.threads (1 unless --set "
             "threads=N; tbb::global_control); CHOLMOD factorizes on the calling thread; the intersection "
             "search runs with IntersectionOptions::parallel = false"},
            {"OMP_NUM_THREADS", std::getenv("OMP_NUM_THREADS")},
            {"intersections_parallel", false}}},
          {"malloc",
           {{"note",
             "GLIBC_TUNABLES as the process started (reexec_with_huge_page_malloc(), strata/process.h)"},
            {"GLIBC_TUNABLES", std::getenv("GLIBC_TUNABLES") ? std::getenv("GLIBC_TUNABLES") : ""}}},
          {"reconstruct_options",
           {{"volume_scales", ro.volume_scales},
            {"max_levels", ro.max_levels},
            {"volume_iterations", ro.volume_iterations},
            {"finest_volume_iterations", ro.finest_volume_iterations},
            {"finest_intermediate_solves", ro.finest_intermediate_solves},
            {"intermediate_regularized_levels", ro.intermediate_regularized_levels},
            {"retry_volume_iterations", ro.retry_volume_iterations},
            {"retry_on_new_intersections", ro.retry_on_new_intersections},
            {"renumber_for_locality", ro.renumber_for_locality},
            {"contact_ratio", ro.contact_ratio},
            {"base_crossing_rings", ro.base_crossing_rings},
            {"fallback_schedule", ro.fallback_schedule},
            {"retry_other_regularization", ro.retry_other_regularization},
            {"fold_repair_rounds", ro.fold_repair_rounds},
            {"fold_repair_local_first", ro.fold_repair_local_first},
            {"fold_repair_local_rings", ro.fold_repair_local_rings},
            {"fold_repair_local_rounds", ro.fold_repair_local_rounds},
            {"fold_repair_rings", ro.fold_repair_rings},
            {"fold_repair_sweeps", ro.fold_repair_sweeps},
            {"local_polish_max_fraction", ro.local_polish_max_fraction},
            {"local_polish_rings", ro.local_polish_rings},
            {"local_polish_max_motion", ro.local_polish_max_motion},
            {"fold_repair_max_fraction", ro.fold_repair_max_fraction},
            {"regularization_iterations", ro.regularization_iterations},
            {"coarse_regularization_iterations", ro.coarse_regularization_iterations},
            {"coarsest_regularization_iterations", ro.coarsest_regularization_iterations},
            {"coarsest_max_cycles", ro.coarsest_max_cycles},
            {"tangential_regularization", to_string(ro.tangential_regularization)},
            {"max_cycles", ro.max_cycles},
            {"final_max_cycles", ro.final_max_cycles},
            {"max_final_steps", ro.max_final_steps},
            {"max_factorized_steps", ro.max_factorized_steps},
            {"max_constraint_motion", ro.max_constraint_motion},
            {"cg_max_iterations", ro.cg_max_iterations},
            {"threads", ro.threads},
            {"cg_tolerance", ro.cg_tolerance},
            {"level_tolerance", ro.level_tolerance},
            {"tangential_lambda", ro.tangential_lambda},
            {"length_lambda", ro.length_lambda},
            {"regularization_decay", ro.regularization_decay},
            {"direct_max_prisms", ro.direct_max_prisms},
            {"tolerance", ro.tolerance},
            {"multigrid",
             {{"iterations", ro.multigrid.iterations},
              {"retry_iterations", ro.multigrid.retry_iterations},
              {"tolerance", ro.multigrid.tolerance},
              {"damping", ro.multigrid.damping},
              {"smoothness", ro.multigrid.smoothness},
              {"polish_iterations", ro.multigrid.polish_iterations},
              {"polish_tolerance", ro.multigrid.polish_tolerance},
              {"polish_damping", ro.multigrid.polish_damping},
              {"polish_smoothness", ro.multigrid.polish_smoothness},
              {"polish_smoothness_decay", ro.multigrid.polish_smoothness_decay},
              {"single_precision_cycles", ro.multigrid.single_precision_cycles},
              {"smoothing_degree", ro.multigrid.smoothing_degree},
              {"tangential_damping", ro.multigrid.tangential_damping},
              {"tangential_damping_bend", ro.multigrid.tangential_damping_bend},
              {"tangential_damping_margin", ro.multigrid.tangential_damping_margin}}},
            {"step_solver", solver_name(ro.step_solver)},
            {"polish_solver", solver_name(ro.polish_solver)}}},
          {"memory_floor", {{"prisms", floor_prisms}, {"peak_rss_bytes", floor_rss}}}, {"results", results},
          {"time_ratio_1m_over_100k", ratio}, {"time_ratio_1m_over_100k_first_reconstruction", first_ratio},
          {"cpu_time_ratio_1m_over_100k", cpu_ratio}, {
        "targets", {
          {"throughput_ge_1e6_per_cycle",
           {{"definition",
             "prisms_per_second_per_multigrid_pass = prisms * finest_passes / seconds_solve, "
             "finest_passes the volume scales whose pass solves the finest level's volumes "
             "(volume_scales, or 1 without finest_intermediate_solves), "
             "every completed size"},
            {"values", per_size_throughput},
            {"pass", verdict(thr_ok)}}},
              {"reconstruct_100k_le_2s",
               {{"definition",
                 "wall time of VolumeReconstructor::reconstruct() (frames + solve; setup excluded), "
                 "the median of the runs (--repeat, then --min-run-seconds)"},
                {"seconds", completed(r100k) ? json(reconstruct_seconds(r100k)) : json(nullptr)},
                {"pass", t100k}}},
              {"scaling_1m_le_12x_100k",
               {{"definition",
                 "seconds.reconstruct at 1M over that at 100k (a kept solver's reconstructions)"},
                {"ratio", ratio},
                {"pass", tscale}}},
              {"scaling_1m_le_12x_100k_first_reconstruction",
               {{"definition",
                 "seconds.first_reconstruction (setup + the first reconstruct()) at 1M over that at 100k"},
                {"ratio", first_ratio},
                {"pass", tscale_first}}},
              {"memory_le_1kb_per_prism",
               {{"definition",
                 "(peak rss - the floor run's peak rss) / (prisms - the floor run's prisms): the peak's "
                 "growth per prism, the whole pipeline (generation, encoding, setup, reconstructions, "
                 "metrics, intersection counts) in one child per size, every completed size"},
                {"values", per_size_bytes},
                {"pass", verdict(mem_ok)}}},
              {"memory_whole_process_le_1kb_per_prism",
               {{"definition",
                 "peak rss / prisms, the libraries and fixed allocations included, every completed size"},
                {"values", per_size_whole_bytes},
                {"pass", verdict(whole_mem_ok)}}},
              {"accuracy_and_no_new_intersections", verdict(acc_ok)}, {
            "round_trip_within_half_a_percent", trip_target
          }
        }
      }
    };
    const std::string text = report.dump(2);
    std::cout << text << std::endl;
    if (!args.out.empty()) {
      std::ofstream f(args.out);
      f << text << '\n';
      if (!f) throw std::runtime_error("cannot write " + args.out);
    }
    return errors ? 1 : 0;
  } catch (const std::exception& ex) {
    std::cerr << "strata_bench: error: " << ex.what() << std::endl;
    return 1;
  }
}
