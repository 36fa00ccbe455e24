#include "camera.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace strata::viewer {

namespace {
constexpr float kPi = 3.14159265358979f;
constexpr float kMaxPitch = 89.9f * kPi / 180.0f;
}  // namespace

ViewPreset parse_view_preset(const std::string& name) {
  if (name == "front") return ViewPreset::Front;
  if (name == "back") return ViewPreset::Back;
  if (name == "left") return ViewPreset::Left;
  if (name == "right") return ViewPreset::Right;
  if (name == "top") return ViewPreset::Top;
  if (name == "bottom") return ViewPreset::Bottom;
  if (name == "iso") return ViewPreset::Iso;
  throw std::invalid_argument("unknown view '" + name + "' (front, back, left, right, top, bottom or iso)");
}

void Camera::fit(const Vec3f& lo, const Vec3f& hi) {
  target_ = 0.5f * (lo + hi);
  radius_ = std::max(0.5f * (hi - lo).norm(), 1e-6f);
  // The sphere fits the vertical field of view; at aspect < 1 the horizontal one is smaller.
  distance_ = 1.1f * radius_ / std::sin(0.5f * fov_y_);
}

void Camera::set_view(ViewPreset view) {
  switch (view) {
    case ViewPreset::Front:
      yaw_ = 0.0f, pitch_ = 0.0f;
      break;
    case ViewPreset::Back:
      yaw_ = kPi, pitch_ = 0.0f;
      break;
    case ViewPreset::Left:
      yaw_ = -0.5f * kPi, pitch_ = 0.0f;
      break;
    case ViewPreset::Right:
      yaw_ = 0.5f * kPi, pitch_ = 0.0f;
      break;
    case ViewPreset::Top:
      yaw_ = 0.0f, pitch_ = kMaxPitch;
      break;
    case ViewPreset::Bottom:
      yaw_ = 0.0f, pitch_ = -kMaxPitch;
      break;
    case ViewPreset::Iso:
      yaw_ = 0.25f * kPi, pitch_ = std::atan(1.0f / std::sqrt(2.0f));
      break;
  }
}

void Camera::orbit(float dx, float dy) {
  yaw_ -= 0.01f * dx;
  pitch_ = std::clamp(pitch_ + 0.01f * dy, -kMaxPitch, kMaxPitch);
}

void Camera::pan(float dx, float dy, float viewport_height) {
  const float world_per_pixel = 2.0f * distance_ * std::tan(0.5f * fov_y_) / std::max(viewport_height, 1.0f);
  const Mat4 v = view();
  const Vec3f right = v.block<1, 3>(0, 0).transpose();
  const Vec3f up = v.block<1, 3>(1, 0).transpose();
  target_ += world_per_pixel * (-dx * right + dy * up);
}

void Camera::zoom(float steps) {
  distance_ = std::clamp(distance_ * std::pow(0.9f, steps), 1e-4f * radius_, 1e3f * radius_);
}

Vec3f Camera::direction() const {
  return Vec3f(std::sin(yaw_) * std::cos(pitch_), std::sin(pitch_), std::cos(yaw_) * std::cos(pitch_));
}

Vec3f Camera::eye() const {
  return target_ + distance_ * direction();
}

Mat4 Camera::view() const {
  const Vec3f f = -direction();  // forward
  const Vec3f s = f.cross(Vec3f::UnitY()).normalized();
  const Vec3f u = s.cross(f);
  const Vec3f e = eye();
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(e);
  m(1, 3) = -u.dot(e);
  m(2, 3) = f.dot(e);
  return m;
}

Mat4 Camera::projection(float aspect) const {
  const float n = std::max(distance_ - 2.0f * radius_, 1e-3f * distance_);
  const float far = distance_ + 2.0f * radius_;
  const float t = 1.0f / std::tan(0.5f * fov_y_);
  Mat4 p = Mat4::Zero();
  p(0, 0) = t / std::max(aspect, 1e-6f);
  p(1, 1) = t;
  p(2, 2) = -(far + n) / (far - n);
  p(2, 3) = -2.0f * far * n / (far - n);
  p(3, 2) = -1.0f;
  return p;
}

void Camera::ray(float x, float y, float w, float h, Vec3f& origin, Vec3f& dir) const {
  const float t = std::tan(0.5f * fov_y_);
  const float ndc_x = 2.0f * x / std::max(w, 1.0f) - 1.0f;
  const float ndc_y = 1.0f - 2.0f * y / std::max(h, 1.0f);
  const Mat4 v = view();
  const Vec3f right = v.block<1, 3>(0, 0).transpose();
  const Vec3f up = v.block<1, 3>(1, 0).transpose();
  origin = eye();
  dir = (-direction() + ndc_x * t * (w / std::max(h, 1.0f)) * right + ndc_y * t * up).normalized();
}

}  // namespace strata::viewer
