#pragma once
// Rotation helpers shared by the held link's geometry (scheduler/held_link.cpp) and an island's
// motion (scheduler/island.cpp), which belong to neither. Private to those two files: not
// installed, and no other file includes it.
#include "core/body.hpp"

namespace palpable {

inline Mat3 rotation(const BodyState& s) {
  return s.q_WM.toRotationMatrix();
}

// The rotation exp([theta]x) as a quaternion.
inline Quat rotation_quat(const Vec3& theta) {
  const double angle = theta.norm();
  if (angle == 0.0) return Quat::Identity();
  return Quat(Eigen::AngleAxisd(angle, theta / angle));
}

}  // namespace palpable
