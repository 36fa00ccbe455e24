// Internal: closest-point queries on a triangle mesh through an axis-aligned bounding-box tree.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "strata/mesh.h"

namespace strata::internal {

//! Closest point on triangle (a,b,c) to p, returned with its barycentric coordinates.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary);

//! A static AABB tree over the faces of a mesh. The mesh must outlive the tree.
class TriangleTree {
 public:
  TriangleTree(const std::vector<Vec3>& vertices, const std::vector<Face>& faces);
  //! A tree over the faces \p subset of the mesh only (indices into \p faces; copied). Hits name
  //! the mesh's own face indices.
  TriangleTree(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
               const std::vector<int>& subset);

  struct Hit {
    int face = -1;
    Vec3 point = Vec3::Zero();
    Vec3 bary = Vec3::Zero();
    double distance_sq = 0.0;
  };
  //! The closest point on the mesh to p. \pre the mesh has at least one face.
  Hit closest(const Vec3& p) const;
  //! The closest point nearer than sqrt(\p bound_sq), or a Hit with face -1 and distance_sq
  //! bound_sq if there is none. Where there is one it is closest(p)'s, the same face (the bound
  //! only skips what closest() would not take).
  Hit closest(const Vec3& p, double bound_sq) const;
  //! The box around the tree's faces (empty for a tree of no faces).
  const Eigen::AlignedBox3d& bounds() const;

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int begin = 0, end = 0;     // leaf range in order_
  };
  void build_over(const std::vector<int>* subset);
  int build(int begin, int end, std::vector<Eigen::AlignedBox3d>& boxes, std::vector<Vec3>& centroids);

  const std::vector<Vec3>& vertices_;
  const std::vector<Face>& faces_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

}  // namespace strata::internal
