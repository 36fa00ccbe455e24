#include "paper_cases.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "strata/exceptions.h"

namespace strata::cases {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSqrt3Half = 0.86602540378443864676;
// Bumps: this many bumps around; along z as many as fit with about the same wavelength.
constexpr int kBumpsAround = 8;
// Amplitude of the Bumps/Rings pattern relative to detail_height: offsets stay in [0.5, 1.5] * height.
constexpr double kPatternAmplitude = 0.5;

void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidInput("cylinder case: " + what);
}

bool finite(double v) {
  return std::isfinite(v);
}

// Everything bend_point needs, checked and derived once.
struct Bend {
  double start, end, radius, angle;
  double sin_angle, cos_angle;
};

Bend make_bend(const CylinderCaseOptions& o) {
  require(finite(o.bend_radius) && o.bend_radius > 0.0, "bend_radius must be > 0");
  require(finite(o.bend_degrees) && o.bend_degrees >= 0.0 && o.bend_degrees <= 360.0,
          "bend_degrees must be in [0, 360]");
  require(finite(o.bend_start), "bend_start must be finite");
  require(finite(o.bend_end), "bend_end must be finite");
  Bend b;
  b.start = o.bend_start;
  b.radius = o.bend_radius;
  b.angle = o.bend_angle();
  b.end = o.effective_bend_end();
  // A bend_end set by hand must agree with the arc length, or the axis would stretch.
  if (o.bend_end != 0.0) {
    const double tol = 1e-9 * std::max({1.0, std::abs(b.start), std::abs(b.end)});
    require(
        std::abs(o.bend_end - b.end) <= tol,
        "bend_end must be 0 (derived) or bend_start + bend_radius * bend angle = " + std::to_string(b.end));
  }
  b.sin_angle = std::sin(b.angle);
  b.cos_angle = std::cos(b.angle);
  return b;
}

Vec3 apply_bend(const Vec3& p, const Bend& b) {
  if (p.z() <= b.start) return p;
  // Inside the bend: the arc parameter is the (preserved) length along the axis, and the offset
  // x from the axis becomes a radial offset from the bend centre (bend_radius, y, bend_start).
  const double z = std::min(p.z(), b.end);
  const double phi = (z - b.start) / b.radius;
  const double s = p.z() >= b.end ? b.sin_angle : std::sin(phi);
  const double c = p.z() >= b.end ? b.cos_angle : std::cos(phi);
  const double r = b.radius - p.x();
  Vec3 q(b.radius - r * c, p.y(), b.start + r * s);
  // Beyond the bend: continue along the end tangent, i.e. a rigid motion of the straight part.
  if (p.z() > b.end) q += (p.z() - b.end) * Vec3(s, 0.0, c);
  return q;
}

// Intervals along z for rings about `spacing` apart, adjusted so that the last ring is at `length`.
int rings_for(double length, double spacing) {
  return std::max(1, static_cast<int>(std::lround(length / spacing)));
}

// A tube's connectivity with its vertices' coordinates in grid units: u around (periodic with
// `segments`), z along the axis (0 to `rings`). Counter-clockwise in (u, z) is outward.
// cell_u and cell_z are the grid spacing in world units (for Delaunay tests in the unrolled plane).
struct TubeGrid {
  std::vector<Eigen::Vector2d> uv;
  std::vector<Face> faces;
  std::vector<char> fixed_u;  // vertices whose u stays put (the square tube's corners)
  int segments = 0, rings = 0;
  double cell_u = 1.0, cell_z = 1.0;
};

// A tube of `rings` + 1 rings of `segments` vertices each, alternate rings shifted by half a
// segment so that the triangles are near-equilateral (at radius rho).
TubeGrid staggered_grid(int segments, int rings, double rho, double length) {
  TubeGrid g;
  const int n = segments;
  g.segments = n;
  g.rings = rings;
  g.cell_u = 2.0 * kPi * rho / n;
  g.cell_z = length / rings;
  g.uv.reserve(static_cast<size_t>(n) * (rings + 1));
  g.faces.reserve(2 * static_cast<size_t>(n) * rings);
  for (int i = 0; i <= rings; ++i) {
    const double shift = (i % 2) ? 0.5 : 0.0;
    for (int j = 0; j < n; ++j) g.uv.emplace_back(j + shift, i);
  }
  for (int i = 0; i < rings; ++i) {
    const int a = i * n, b = (i + 1) * n;
    for (int j = 0; j < n; ++j) {
      const int j1 = (j + 1) % n;
      if (i % 2 == 0) {  // ring i unshifted, ring i+1 shifted by +1/2
        g.faces.push_back({a + j, a + j1, b + j});
        g.faces.push_back({a + j1, b + j1, b + j});
      } else {  // ring i shifted, ring i+1 unshifted
        g.faces.push_back({a + j, b + j1, b + j});
        g.faces.push_back({a + j, a + j1, b + j1});
      }
    }
  }
  g.fixed_u.assign(g.uv.size(), 0);
  return g;
}

// Rings for a staggered tube of mean radius rho: equilateral triangles have height sqrt(3)/2 side.
int staggered_rings(int segments, double rho, double length) {
  const double side = 2.0 * rho * std::sin(kPi / segments);
  return rings_for(length, kSqrt3Half * side);
}

// The square tube of half side a around the z axis: a regular grid with straight diagonals whose
// columns are uniform in arc length along the square's perimeter, starting at the corner (a, -a)
// and turning counter-clockwise, so that the four corners are grid columns (sharp edges).
int cuboid_rings(int segments, double a, double length) {
  return rings_for(length, 8.0 * a / segments);
}

// The square tube's grid: columns uniform in arc length along the perimeter, starting at the
// corner (a, -a) and turning counter-clockwise, so that the four corners are grid columns.
TubeGrid square_grid(int segments, int rings, double a, double length) {
  TubeGrid g;
  const int n = segments;
  g.segments = n;
  g.rings = rings;
  g.cell_u = 8.0 * a / n;
  g.cell_z = length / rings;
  const int per_side = n / 4;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < n; ++j) {
      g.uv.emplace_back(j, i);
      g.fixed_u.push_back(j % per_side == 0);
    }
  for (int i = 0; i < rings; ++i) {
    const int a0 = i * n, b0 = (i + 1) * n;
    for (int j = 0; j < n; ++j) {
      const int j1 = (j + 1) % n;
      g.faces.push_back({a0 + j, a0 + j1, b0 + j1});
      g.faces.push_back({a0 + j, b0 + j1, b0 + j});
    }
  }
  return g;
}

// The point of the square tube of half side a at column u (of `segments`, from the corner (a, -a)
// counter-clockwise) and height z. The coordinate that is constant along a side is set exactly, so
// the sides are exactly flat, and whole columns give the grid's points exactly.
Vec3 square_point(double a, int segments, double u, double z) {
  const int per_side = segments / 4;
  const double w = u - segments * std::floor(u / segments);
  const int k = std::min(3, static_cast<int>(std::floor(w / per_side)));
  const double t = -a + 2.0 * a * (w - k * per_side) / per_side;  // from -a to a along the side
  switch (k) {
    case 0:  // x = +a, y rising
      return {a, t, z};
    case 1:  // y = +a, x falling
      return {-t, a, z};
    case 2:  // x = -a, y falling
      return {-a, -t, z};
    default:  // y = -a, x rising
      return {t, -a, z};
  }
}

// Makes the grid irregular, as a scanned surface is: every vertex off the two end rings moves by
// up to `jitter` grid cells in the parameter plane (deterministically; the square tube's corner
// columns only along z), then edges are flipped until the triangulation is Delaunay in the
// unrolled plane (edges along a corner column are kept, so the sharp edges stay).
void make_irregular(TubeGrid& g, double jitter, unsigned seed) {
  const int n = g.segments;
  const double du = g.cell_u, dz = g.cell_z;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (std::size_t v = 0; v < g.uv.size(); ++v) {
    const double ju = unit(rng), jz = unit(rng);  // drawn for every vertex: the sequence is fixed
    const int ring = static_cast<int>(v) / n;
    if (ring == 0 || ring == g.rings) continue;
    if (!g.fixed_u[v]) g.uv[v].x() += jitter * ju;
    g.uv[v].y() += jitter * jz;
  }
  // Metric coordinates in the unrolled plane, periodic in u with period n * du.
  const double period = n * du;
  std::vector<Eigen::Vector2d> xy(g.uv.size());
  for (std::size_t v = 0; v < g.uv.size(); ++v) xy[v] = Eigen::Vector2d(g.uv[v].x() * du, g.uv[v].y() * dz);
  // The image of vertex v nearest to the reference point r (u is periodic).
  auto near = [&](int v, const Eigen::Vector2d& r) {
    Eigen::Vector2d p = xy[v];
    p.x() -= period * std::round((p.x() - r.x()) / period);
    return p;
  };
  auto orient = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  };
  // d strictly inside the circumcircle of the counter-clockwise triangle (a, b, c).
  auto in_circle = [du, dz](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                            const Eigen::Vector2d& d) {
    const Eigen::Vector2d pa = a - d, pb = b - d, pc = c - d;
    return pa.squaredNorm() * (pb.x() * pc.y() - pb.y() * pc.x()) -
               pb.squaredNorm() * (pa.x() * pc.y() - pa.y() * pc.x()) +
               pc.squaredNorm() * (pa.x() * pb.y() - pa.y() * pb.x()) >
           1e-12 * (pa.squaredNorm() + pb.squaredNorm() + pc.squaredNorm()) * (du * dz);
  };
  // Edge -> its (up to two) faces, kept up to date through the flips.
  std::map<std::pair<int, int>, std::array<int, 2>> edges;
  auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  auto link = [&](int j) {
    for (int k = 0; k < 3; ++k) {
      auto& e = edges.try_emplace(key(g.faces[j][k], g.faces[j][(k + 1) % 3]), std::array<int, 2>{-1, -1})
                    .first->second;
      (e[0] < 0 ? e[0] : e[1]) = j;
    }
  };
  auto unlink = [&](int j) {
    for (int k = 0; k < 3; ++k) {
      auto& e = edges[key(g.faces[j][k], g.faces[j][(k + 1) % 3])];
      if (e[0] == j) e[0] = e[1];
      e[1] = -1;
    }
  };
  for (int j = 0; j < static_cast<int>(g.faces.size()); ++j) link(j);
  auto corner_edge = [&](int a, int b) { return g.fixed_u[a] && g.fixed_u[b] && g.uv[a].x() == g.uv[b].x(); };
  std::vector<std::pair<int, int>> stack;
  for (const auto& [e, f] : edges) stack.push_back(e);
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const auto it = edges.find(key(a, b));
    if (it == edges.end() || it->second[1] < 0 || corner_edge(a, b)) continue;
    const int j1 = it->second[0], j2 = it->second[1];
    // j1 holds the edge as (s, t) in its counter-clockwise order; c and d are the opposite corners.
    int k = 0;
    while (!((g.faces[j1][k] == a && g.faces[j1][(k + 1) % 3] == b) ||
             (g.faces[j1][k] == b && g.faces[j1][(k + 1) % 3] == a)))
      ++k;
    const int s = g.faces[j1][k], t = g.faces[j1][(k + 1) % 3], c = g.faces[j1][(k + 2) % 3];
    int d = -1;
    for (int v : g.faces[j2])
      if (v != a && v != b) d = v;
    const Eigen::Vector2d ps = xy[s], pt = near(t, ps), pc = near(c, ps), pd = near(d, ps);
    if (!in_circle(ps, pt, pc, pd)) continue;
    if (orient(ps, pd, pc) <= 0 || orient(pd, pt, pc) <= 0) continue;  // not convex: no flip
    if (edges.count(key(c, d))) continue;
    unlink(j1);
    unlink(j2);
    edges.erase(key(s, t));
    g.faces[j1] = {s, d, c};
    g.faces[j2] = {d, t, c};
    link(j1);
    link(j2);
    for (const auto& e : {key(s, d), key(d, t), key(t, c), key(c, s)}) stack.push_back(e);
  }
}

// Detail resolution: segments around and rings along z.
struct Resolution {
  int segments, rings;
};

Resolution detail_resolution(const CylinderCaseOptions& o) {
  const bool cuboid = o.detail == DetailKind::Cuboid;
  const double a = o.radius + o.detail_height;  // mean radius (Bumps/Rings) or half side (Cuboid)
  auto rings = [&](int n) { return cuboid ? cuboid_rings(n, a, o.length) : staggered_rings(n, a, o.length); };
  const int step = cuboid ? 4 : 1;
  const int min_segments = cuboid ? 4 : 3;
  if (o.target_detail_triangles <= 0) {
    int n = o.detail_segments;
    if (cuboid) n = std::max(4, static_cast<int>(std::lround(n / 4.0)) * 4);
    return {n, rings(n)};
  }
  // faces = 2 n rings(n) and rings(n) grows linearly with n: estimate n, then search nearby.
  const double target = o.target_detail_triangles;
  const double spacing_times_n = cuboid ? 8.0 * a : kSqrt3Half * 2.0 * kPi * a;  // ring spacing * n
  const double estimate = std::sqrt(target * spacing_times_n / (2.0 * o.length));
  const int centre = std::max(min_segments, static_cast<int>(std::lround(estimate / step)) * step);
  Resolution best{0, 0};
  double best_error = std::numeric_limits<double>::infinity();
  for (int n = std::max(min_segments, centre - 4 * step); n <= centre + 4 * step; n += step) {
    const int r = rings(n);
    const double error = std::abs(2.0 * n * static_cast<double>(r) - target);
    if (error < best_error) best_error = error, best = {n, r};
  }
  return best;
}

void check_options(const CylinderCaseOptions& o) {
  require(finite(o.radius) && o.radius > 0.0, "radius must be > 0");
  require(finite(o.length) && o.length > 0.0, "length must be > 0");
  require(o.base_segments >= 3, "base_segments must be >= 3");
  require(o.target_detail_triangles > 0 || o.detail_segments >= 3, "detail_segments must be >= 3");
  require(o.target_detail_triangles >= 0, "target_detail_triangles must be >= 0");
  require(finite(o.jitter) && o.jitter >= 0.0 && o.jitter <= 0.45, "jitter must be in [0, 0.45]");
  require(finite(o.detail_height) && o.detail_height > 0.0, "detail_height must be > 0");
  require(o.detail == DetailKind::Bumps || o.detail == DetailKind::Rings || o.detail == DetailKind::Cuboid,
          "unknown detail kind");
  make_bend(o);
  // The base itself must not fold on the inner side of the bend.
  require(o.bend_radius > o.radius, "bend_radius must be > radius");
}

}  // namespace

const char* to_string(DetailKind kind) {
  switch (kind) {
    case DetailKind::Bumps:
      return "bumps";
    case DetailKind::Rings:
      return "rings";
    case DetailKind::Cuboid:
      return "cuboid";
  }
  return "unknown";
}

std::optional<DetailKind> parse_detail_kind(std::string_view text) {
  for (DetailKind k : {DetailKind::Bumps, DetailKind::Rings, DetailKind::Cuboid})
    if (text == to_string(k)) return k;
  return std::nullopt;
}

double CylinderCaseOptions::bend_angle() const {
  return bend_degrees * kPi / 180.0;
}

double CylinderCaseOptions::effective_bend_end() const {
  return bend_start + bend_radius * bend_angle();
}

Vec3 bend_point(const Vec3& p, const CylinderCaseOptions& options) {
  return apply_bend(p, make_bend(options));
}

double detail_offset(const CylinderCaseOptions& o, double theta, double z) {
  const double h = o.detail_height;
  switch (o.detail) {
    case DetailKind::Bumps: {
      // Along z: an integer number of bumps over the length, about as long as they are wide.
      const double around_wavelength = 2.0 * kPi * o.radius / kBumpsAround;
      const double along = std::max(1.0, std::round(o.length / around_wavelength));
      return h * (1.0 + kPatternAmplitude * std::cos(kBumpsAround * theta) *
                            std::cos(2.0 * kPi * along * z / o.length));
    }
    case DetailKind::Rings: {
      const double wavelength = 2.0 * kPi * o.radius / kBumpsAround;
      const double rings = std::max(1.0, std::round(o.length / wavelength));
      return h * (1.0 + kPatternAmplitude * std::cos(2.0 * kPi * rings * z / o.length));
    }
    case DetailKind::Cuboid: {
      // Radial distance to the square of half side R + h, minus R.
      const double a = o.radius + h;
      return a / std::max(std::abs(std::cos(theta)), std::abs(std::sin(theta))) - o.radius;
    }
  }
  return h;
}

CylinderCase make_cylinder_case(const CylinderCaseOptions& o) {
  check_options(o);
  const Bend bend = make_bend(o);
  const double R = o.radius;
  CylinderCase out;
  out.name = o.detail == DetailKind::Cuboid ? "cuboid" : std::string("cylinder-") + to_string(o.detail);
  out.inner_bend_radius = o.bend_radius - R;

  const int base_rings = staggered_rings(o.base_segments, R, o.length);
  const TubeGrid base = staggered_grid(o.base_segments, base_rings, R, o.length);
  out.base.faces = base.faces;
  for (const Eigen::Vector2d& p : base.uv) {
    const double theta = 2.0 * kPi * p.x() / base.segments, z = o.length * p.y() / base.rings;
    out.base.vertices.emplace_back(R * std::cos(theta), R * std::sin(theta), z);
  }
  out.edited_base.faces = out.base.faces;
  out.edited_base.vertices.reserve(out.base.vertices.size());
  for (const Vec3& p : out.base.vertices) out.edited_base.vertices.push_back(apply_bend(p, bend));

  const Resolution res = detail_resolution(o);
  const double a = R + o.detail_height;  // mean radius (Bumps/Rings) or half side (Cuboid)
  TubeGrid grid = o.detail == DetailKind::Cuboid ? square_grid(res.segments, res.rings, a, o.length)
                                                 : staggered_grid(res.segments, res.rings, a, o.length);
  if (o.jitter > 0) make_irregular(grid, o.jitter, 20261125u);
  out.detail.faces = std::move(grid.faces);
  out.detail.vertices.reserve(grid.uv.size());
  for (const Eigen::Vector2d& p : grid.uv) {
    const double z = o.length * p.y() / grid.rings;
    if (o.detail == DetailKind::Cuboid) {
      out.detail.vertices.push_back(square_point(a, grid.segments, p.x(), z));
    } else {
      const double theta = 2.0 * kPi * p.x() / grid.segments;
      const double r = R + detail_offset(o, theta, z);
      out.detail.vertices.emplace_back(r * std::cos(theta), r * std::sin(theta), z);
    }
  }
  out.max_detail_height = 0.0;
  for (const Vec3& p : out.detail.vertices)
    out.max_detail_height = std::max(out.max_detail_height, std::hypot(p.x(), p.y()) - R);
  return out;
}

PolyMesh make_cylinder_cage(const CylinderCaseOptions& o, int segments) {
  if (segments < 6)
    throw InvalidInput("cylinder cage needs at least 6 segments, got " + std::to_string(segments));
  if (!(o.radius > 0) || !(o.length > 0)) throw InvalidInput("cylinder cage: radius and length must be > 0");
  const double seg = 2.0 * kPi * o.radius / segments;
  const int rings = std::max(2, static_cast<int>(std::lround(o.length / seg))) + 1;
  auto build = [&](double r) {
    PolyMesh m;
    for (int j = 0; j < rings; ++j)
      for (int i = 0; i < segments; ++i) {
        const double t = 2.0 * kPi * i / segments;
        m.vertices.emplace_back(r * std::cos(t), r * std::sin(t), o.length * j / (rings - 1));
      }
    for (int j = 0; j + 1 < rings; ++j)
      for (int i = 0; i < segments; ++i) {
        const int a = j * segments + i, b = j * segments + (i + 1) % segments;
        m.faces.push_back({a, b, b + segments, a + segments});  // counter-clockwise seen from outside
      }
    return m;
  };
  // The limit of a regular polygon of radius 1 has radius (2 + cos(2 pi / n)) / 3 at its vertices
  // (the cubic B-spline's vertex rule); invert it.
  return build(o.radius * 3.0 / (2.0 + std::cos(2.0 * kPi / segments)));
}

TriMesh shuffled_numbering(const TriMesh& mesh, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<int> new_of_old(mesh.vertices.size());
  for (std::size_t v = 0; v < new_of_old.size(); ++v) new_of_old[v] = static_cast<int>(v);
  std::shuffle(new_of_old.begin(), new_of_old.end(), rng);
  TriMesh s;
  s.vertices.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) s.vertices[new_of_old[v]] = mesh.vertices[v];
  s.faces.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) s.faces.push_back({new_of_old[f[0]], new_of_old[f[1]], new_of_old[f[2]]});
  std::shuffle(s.faces.begin(), s.faces.end(), rng);
  return s;
}

}  // namespace strata::cases
