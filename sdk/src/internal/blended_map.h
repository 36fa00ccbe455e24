// Internal: an edit transform prepared for blending (RegionEditor, CageEditor).
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <string>

#include "strata/editing.h"
#include "strata/exceptions.h"

namespace strata::internal {

// An EditTransform split once into what the blend interpolates: the rotation of the polar
// decomposition linear = R S as axis and angle, the symmetric stretch S and the translation.
class BlendedMap {
 public:
  explicit BlendedMap(const EditTransform& t) : t_(t) {
    if (!t.linear.allFinite() || !t.translation.allFinite() || !t.pivot.allFinite())
      throw InvalidInput("edit transform has a non-finite value");
    const double det = t.linear.determinant();
    if (!(det > 1e-12))
      throw InvalidInput("edit transform is singular or a reflection (determinant " + std::to_string(det) +
                         ")");
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(t.linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
    stretch_ = svd.matrixV() * svd.singularValues().asDiagonal() * svd.matrixV().transpose();
    rotation_ = Eigen::AngleAxisd(R);
  }
  Vec3 apply(const Vec3& x, double s) const {
    if (s == 1.0) return t_.apply(x);
    const Eigen::Matrix3d S = Eigen::Matrix3d::Identity() + s * (stretch_ - Eigen::Matrix3d::Identity());
    const Eigen::AngleAxisd r(s * rotation_.angle(), rotation_.axis());
    return t_.pivot + r * (S * (x - t_.pivot)) + s * t_.translation;
  }

 private:
  EditTransform t_;
  Eigen::Matrix3d stretch_;
  Eigen::AngleAxisd rotation_;
};

}  // namespace strata::internal
