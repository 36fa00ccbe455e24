#include "paper_cases.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

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

// A tube of `rings` + 1 rings of `segments` vertices each, alternate rings shifted by half a
// segment so that the triangles are near-equilateral. `point(theta, z)` places a vertex.
template <class PointFn>
TriMesh staggered_tube(int segments, int rings, double length, PointFn point) {
  TriMesh m;
  const int n = segments;
  m.vertices.reserve(static_cast<size_t>(n) * (rings + 1));
  m.faces.reserve(2 * static_cast<size_t>(n) * rings);
  for (int i = 0; i <= rings; ++i) {
    const double z = length * i / rings;
    const double shift = (i % 2) ? 0.5 : 0.0;
    for (int j = 0; j < n; ++j) m.vertices.push_back(point(2.0 * kPi * (j + shift) / n, z));
  }
  // Counter-clockwise in the (theta, z) parameter plane is outward (d/dtheta x d/dz points out).
  for (int i = 0; i < rings; ++i) {
    const int a = i * n, b = (i + 1) * n;
    for (int j = 0; j < n; ++j) {
      const int j1 = (j + 1) % n;
      if (i % 2 == 0) {  // ring i unshifted, ring i+1 shifted by +1/2
        m.faces.push_back({a + j, a + j1, b + j});
        m.faces.push_back({a + j1, b + j1, b + j});
      } else {  // ring i shifted, ring i+1 unshifted
        m.faces.push_back({a + j, b + j1, b + j});
        m.faces.push_back({a + j, a + j1, b + j1});
      }
    }
  }
  return m;
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

TriMesh square_tube(int segments, int rings, double a, double length) {
  TriMesh m;
  const int n = segments;
  m.vertices.reserve(static_cast<size_t>(n) * (rings + 1));
  m.faces.reserve(2 * static_cast<size_t>(n) * rings);
  const int per_side = n / 4;
  for (int i = 0; i <= rings; ++i) {
    const double z = length * i / rings;
    for (int j = 0; j < n; ++j) {
      // The coordinate that is constant along a side is set exactly, so the sides are exactly flat.
      const double u = -a + 2.0 * a * (j % per_side) / per_side;  // from -a to a along the side
      switch (j / per_side) {
        case 0:  // x = +a, y rising
          m.vertices.emplace_back(a, u, z);
          break;
        case 1:  // y = +a, x falling
          m.vertices.emplace_back(-u, a, z);
          break;
        case 2:  // x = -a, y falling
          m.vertices.emplace_back(-a, -u, z);
          break;
        default:  // y = -a, x rising
          m.vertices.emplace_back(u, -a, z);
          break;
      }
    }
  }
  for (int i = 0; i < rings; ++i) {
    const int a0 = i * n, b0 = (i + 1) * n;
    for (int j = 0; j < n; ++j) {
      const int j1 = (j + 1) % n;
      m.faces.push_back({a0 + j, a0 + j1, b0 + j1});
      m.faces.push_back({a0 + j, b0 + j1, b0 + j});
    }
  }
  return m;
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
  out.base = staggered_tube(o.base_segments, base_rings, o.length, [R](double theta, double z) {
    return Vec3(R * std::cos(theta), R * std::sin(theta), z);
  });
  out.edited_base.faces = out.base.faces;
  out.edited_base.vertices.reserve(out.base.vertices.size());
  for (const Vec3& p : out.base.vertices) out.edited_base.vertices.push_back(apply_bend(p, bend));

  const Resolution res = detail_resolution(o);
  if (o.detail == DetailKind::Cuboid) {
    out.detail = square_tube(res.segments, res.rings, R + o.detail_height, o.length);
  } else {
    out.detail = staggered_tube(res.segments, res.rings, o.length, [&o, R](double theta, double z) {
      const double r = R + detail_offset(o, theta, z);
      return Vec3(r * std::cos(theta), r * std::sin(theta), z);
    });
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

}  // namespace strata::cases
