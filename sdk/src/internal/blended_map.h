// Internal: an edit transform prepared for blending (RegionEditor, CageEditor).
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <sstream>
#include <string>

#include "strata/editing.h"
#include "strata/exceptions.h"

namespace strata::internal {

// What makes \p linear unusable as an edit's linear part, or "" if nothing: a reflection, or a
// map singular relative to its own size (smallest singular value below 1e-14 of the largest), so
// that a uniform scale of 1e-6 is accepted as one of 1e6 is.
inline std::string linear_map_problem(const Eigen::Matrix3d& linear) {
  const double det = linear.determinant();
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(linear).singularValues();
  if (det > 0 && sv(2) > 1e-14 * sv(0)) return "";
  std::ostringstream m;
  m << (det < 0 ? "is a reflection" : "is singular") << " (determinant " << det << ", singular values "
    << sv(0) << ", " << sv(1) << ", " << sv(2) << ")";
  return m.str();
}

// An EditTransform split once into what the blend interpolates: the rotation of the polar
// decomposition linear = R S as axis and angle, the symmetric stretch S and the translation.
class BlendedMap {
 public:
  explicit BlendedMap(const EditTransform& t) : t_(t) {
    if (!t.linear.allFinite() || !t.translation.allFinite() || !t.pivot.allFinite())
      throw InvalidInput("edit transform has a non-finite value");
    const std::string problem = linear_map_problem(t.linear);
    if (!problem.empty()) throw InvalidInput("edit transform " + problem);
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(t.linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
    stretch_ = svd.matrixV() * svd.singularValues().asDiagonal() * svd.matrixV().transpose();
    rotation_ = Eigen::AngleAxisd(R);
    // The rotation as given, if it is this one: its own angle (past 180 degrees too).
    const double largest = t.rotation_axis.cwiseAbs().maxCoeff();
    if (largest > 0 && std::isfinite(t.rotation_degrees)) {
      const Eigen::AngleAxisd given(t.rotation_degrees * M_PI / 180.0,
                                    (t.rotation_axis / largest).normalized());
      if ((given.toRotationMatrix() - R).cwiseAbs().maxCoeff() <= 1e-9) rotation_ = given;
    }
  }
  // Per point of a blend field: no EditTransform a point (the arithmetic before partial() came).
  Vec3 apply(const Vec3& x, double s) const {
    if (s == 1.0) return t_.apply(x);
    return t_.pivot + rotation_at(s) * (stretch_at(s) * (x - t_.pivot)) + s * t_.translation;
  }
  // The blend with weight s as a transform (EditTransform::partial()).
  EditTransform partial(double s) const {
    if (s == 1.0) return t_;
    EditTransform p;
    p.linear = rotation_at(s).toRotationMatrix() * stretch_at(s);
    p.translation = s * t_.translation;
    p.pivot = t_.pivot;
    p.rotation_axis = rotation_.axis();
    p.rotation_degrees = s * rotation_.angle() * 180.0 / M_PI;
    return p;
  }

 private:
  Eigen::Matrix3d stretch_at(double s) const {
    return Eigen::Matrix3d::Identity() + s * (stretch_ - Eigen::Matrix3d::Identity());
  }
  Eigen::AngleAxisd rotation_at(double s) const {
    return Eigen::AngleAxisd(s * rotation_.angle(), rotation_.axis());
  }

  EditTransform t_;
  Eigen::Matrix3d stretch_;
  Eigen::AngleAxisd rotation_;
};

}  // namespace strata::internal
