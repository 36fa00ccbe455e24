// Internal: the connected parts of a mesh, and which parts of a base lie under which parts of a
// detail mesh, so that a detail vertex takes its base point on its own part's base (scan debris
// near a surface is not that surface's base). Used by the encodings (encode_detail()) and the
// decimation (connected_parts() only). Not part of the API.
#pragma once

#include <vector>

#include "internal/closest_point.h"
#include "strata/mesh.h"

namespace strata::internal {

//! The connected parts of a mesh's faces: the corners of a face are in one part.
struct Parts {
  std::vector<int> of_vertex;  //!< each vertex's part, -1 for a vertex that no face uses
  int count = 0;               //!< parts, numbered in order of their first face
  int of_face(const Face& f) const { return of_vertex[f[0]]; }
};

//! The parts of (\p vertices, \p faces). With \p join_equal_positions, vertices at bitwise-equal
//! positions are in one part too (a scan's unwelded seams: its sheets are one surface).
//! \pre every face index is in range.
Parts connected_parts(const std::vector<Vec3>& vertices, const std::vector<Face>& faces,
                      bool join_equal_positions);

//! The base faces on which each detail vertex may take its base point: those of its part's base.
//! Parts are matched both ways, each part to the part of the other mesh that its samples (up to
//! 128 vertices and 128 face centroids, evenly strided, and the centroid of its vertices) lie
//! nearest to on average, among the parts of their closest faces. A detail part's base is the
//! base parts matched to it and the base part it is matched to: a base part that no detail part
//! lies on (debris of the base alone) is matched to a nearby detail part, and would otherwise
//! have been its whole base. Such a part stays in that detail part's base, so debris that lies
//! against a surface can still be its base where its vertices are nearer to it than to their own
//! base. Over a base with the detail's own connectivity (a smoothed copy) each part's base is its
//! own faces. A vertex of no face may take its base point anywhere (group -1).
//! empty() when that restricts nothing: one detail part, or (over a base of another
//! connectivity) one base part (the common case), or every detail part's base the whole base, so
//! that such encodings are those of a search over the whole base.
struct PartMatch {
  std::vector<std::vector<int>> part_faces;  //!< the base faces of each base part
  std::vector<std::vector<int>> groups;      //!< the base parts open to each group, ascending
  std::vector<int> group_of_vertex;          //!< per detail vertex: its group, or -1 for any base face
  bool empty() const { return groups.empty(); }
  int group(int vertex) const { return groups.empty() ? -1 : group_of_vertex[vertex]; }
  //! The base faces open to group \p g, ascending.
  std::vector<int> faces(int g) const;
};

//! Closest points within a PartMatch's groups: one tree per base part, which every group that
//! holds the part shares (a copy of the surface's faces per group was k times the surface for k
//! pieces of debris beside it), and over a group of many parts a tree of its parts' boxes, so
//! that a query visits the parts near it only (searching every part's tree in turn cost 20.7 s
//! for a sphere's 10k vertices over a base with 50,000 pieces of debris against 0.13 s without).
class GroupedTrees {
 public:
  //! The base mesh (\p vertices, \p faces) and \p match must outlive this.
  GroupedTrees(const std::vector<Vec3>& vertices, const std::vector<Face>& faces, const PartMatch& match);
  //! The closest point on group \p g's faces: the nearest part's closest point, the lower part's
  //! on a tie, as a search of each part's tree in ascending order would find it.
  TriangleTree::Hit closest(int g, const Vec3& p) const;

 private:
  struct BoxNode {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int begin = 0, end = 0;     // leaf range in PartBoxes::parts
  };
  struct PartBoxes {
    std::vector<int> parts;  // the group's parts, in leaf order
    std::vector<BoxNode> nodes;
  };
  int build(PartBoxes& t, int begin, int end) const;

  const PartMatch& match_;
  std::vector<TriangleTree> trees_;  // one per base part
  std::vector<PartBoxes> boxes_;     // per group: empty for a group of few parts (searched in turn)
};

//! Matches the parts of the base (\p base_vertices, \p base_faces) to those of \p detail (parts
//! joined at equal positions on both). Runs on TBB's threads; the result does not depend on them.
//! \pre both meshes have faces and every face index is in range.
PartMatch match_parts(const TriMesh& detail, const std::vector<Vec3>& base_vertices,
                      const std::vector<Face>& base_faces);

}  // namespace strata::internal
