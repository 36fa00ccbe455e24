// The fold checks' contact test (internal/contact.h): a pair of intersecting detail triangles is a
// contact when the path between their base points along the base is much longer than the straight
// line between them, as across a sheet bent back over itself.
#include <gtest/gtest.h>

#include <cmath>

#include "internal/contact.h"
#include "internal/topology.h"

using namespace strata;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A strip of cells x cells_across unit squares (two triangles each), bent into a U: a flat sheet
// of `flat` cells at z = 0, a half circle of radius r, and the same sheet back over the first at
// z = 2r. Face 2 * (i * across + j) is cell (i, j)'s first triangle, i along the strip.
struct Strip {
  std::vector<Vec3> points;
  std::vector<Face> faces;
  int along = 0, across = 0;
  int face(int i, int j) const { return 2 * (i * across + j); }
};

Strip u_strip(int flat, int bend, int across, double r) {
  Strip s;
  s.along = 2 * flat + bend;
  s.across = across;
  const double len = static_cast<double>(flat);
  for (int i = 0; i <= s.along; ++i) {
    Vec3 c;  // the strip's centre line at arc length i
    if (i <= flat) {
      c = Vec3(i, 0, 0);
    } else if (i <= flat + bend) {
      const double t = kPi * (i - flat) / bend;
      c = Vec3(len + r * std::sin(t), 0, r - r * std::cos(t));
    } else {
      c = Vec3(len - (i - flat - bend), 0, 2 * r);
    }
    for (int j = 0; j <= across; ++j) s.points.push_back(c + Vec3(0, j, 0));
  }
  auto id = [&](int i, int j) { return i * (across + 1) + j; };
  for (int i = 0; i < s.along; ++i)
    for (int j = 0; j < across; ++j) {
      s.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

}  // namespace

TEST(Contact, TheSheetsOfAUAreAContactAndNeighboursOnOneSheetAreNot) {
  // 20 cells flat, the half circle over 6, sheets 0.5 apart (r = 0.25, cells of 1).
  const Strip s = u_strip(20, 6, 4, 0.25);
  const internal::Adjacency adj = internal::build_adjacency(static_cast<int>(s.points.size()), s.faces);
  std::vector<int> vf;
  for (std::size_t k = 0; k < adj.faces.size(); ++k) vf.push_back(3 * adj.faces[k] + adj.corners[k]);
  internal::ContactTest contact({&s.faces, &adj.face_offsets, &vf, &s.points}, 3.0);
  // Cell 5 of the lower sheet and the cell of the upper sheet right above it (i = 2 * 20 + 6 - 6):
  // 0.5 apart, about 36 apart along the strip.
  const int lower = s.face(5, 1), upper = s.face(40, 1);
  EXPECT_LT((s.points[s.faces[lower][0]] - s.points[s.faces[upper][1]]).norm(), 1.0);
  EXPECT_TRUE(contact(lower, upper));
  EXPECT_TRUE(contact(upper, lower));  // symmetric (and remembered)
  // Cells 6 apart on one sheet, or across the bend's two sides near its start: a path about as
  // long as the straight line.
  EXPECT_FALSE(contact(s.face(5, 0), s.face(11, 3)));
  EXPECT_FALSE(contact(s.face(19, 1), s.face(27, 1)));
  // With a ratio so large that the bound exceeds the way around, no pair is a contact.
  internal::ContactTest lenient({&s.faces, &adj.face_offsets, &vf, &s.points}, 100.0);
  EXPECT_FALSE(lenient(lower, upper));
  // A spent budget of visits answers "fold" (the solver's retries as before): the contact above
  // needs more than a few of them.
  internal::ContactTest spent({&s.faces, &adj.face_offsets, &vf, &s.points}, 3.0, 1e-3);
  EXPECT_FALSE(spent(lower, upper));
}
