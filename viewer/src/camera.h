//! \file camera.h
//! An orbit camera: it looks at a target from a distance along a direction given by yaw and
//! pitch (y is up). Orbit turns yaw/pitch, pan moves the target in the view plane, zoom scales
//! the distance. Pure math, no OpenGL.
#pragma once

#include <Eigen/Core>
#include <string>

namespace strata::viewer {

using Mat4 = Eigen::Matrix4f;
using Vec3f = Eigen::Vector3f;

//! The named views of --view: the camera looks from the named side at the target.
enum class ViewPreset { Front, Back, Left, Right, Top, Bottom, Iso };

//! Parses "front", "back", "left", "right", "top", "bottom" or "iso".
//! \throw std::invalid_argument naming the accepted values otherwise.
ViewPreset parse_view_preset(const std::string& name);

class Camera {
 public:
  //! Frames the box [lo, hi]: the target is its centre, the distance shows its bounding sphere
  //! whole at any aspect ratio >= 1/2, the clip planes enclose it.
  void fit(const Vec3f& lo, const Vec3f& hi);
  void set_view(ViewPreset view);
  //! Turns by pixel deltas (0.01 rad per pixel); pitch stays within +-89.9 degrees.
  void orbit(float dx_pixels, float dy_pixels);
  //! Moves the target by pixel deltas, scaled so that the point at the target follows the mouse
  //! in a viewport \p viewport_height pixels high.
  void pan(float dx_pixels, float dy_pixels, float viewport_height);
  //! Zooms by scroll steps (positive: closer), 10% per step.
  void zoom(float steps);

  Mat4 view() const;
  //! Perspective projection for \p aspect (width / height).
  Mat4 projection(float aspect) const;
  Vec3f eye() const;
  //! The world-space ray through the pixel (x, y) (origin top-left) of a w x h viewport.
  void ray(float x, float y, float w, float h, Vec3f& origin, Vec3f& direction) const;

  float radius() const { return radius_; }
  float distance() const { return distance_; }
  const Vec3f& target() const { return target_; }

 private:
  Vec3f direction() const;  // unit vector from the target to the eye

  Vec3f target_ = Vec3f::Zero();
  float radius_ = 1.0f;  // of the fitted scene
  float distance_ = 3.0f;
  float yaw_ = 0.0f, pitch_ = 0.0f;
  float fov_y_ = 0.61f;  // 35 degrees
};

}  // namespace strata::viewer
