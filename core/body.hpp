#pragma once
// A rigid body: immutable shape and mass properties, a changing state with its own clock, and a
// motion kind (DESIGN.md §2).
#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "core/types.hpp"

#include <memory>
#include <string>

namespace palpable {

enum class MotionKind { kDynamic, kFixed, kKinematic };

// Prescribed motion of a kinematic body: rotation at constant angular velocity about the axis
// through `point_W` (a point that itself moves at `velocity_W`), plus that constant translation.
// Position of a material point at time t: p(t) = c(t) + R(w (t - t0)) (p(t0) - c(t0)), with
// c(t) = point_W + velocity_W (t - t0).
struct KinematicMotion {
  Vec3 angular_velocity_W = Vec3::Zero();  // [rad/s]
  Vec3 point_W = Vec3::Zero();             // [m] a point of the axis at t0 = 0
  Vec3 velocity_W = Vec3::Zero();          // [m/s]
};

// The changing state. Positions and orientations are of the modelling frame M (origin at the
// centre of mass), so files and traces never see the principal frame.
struct BodyState {
  double t = 0.0;                   // the body's own clock [s]
  Vec3 x_W = Vec3::Zero();          // centre of mass [m]
  Quat q_WM = Quat::Identity();     // unit quaternion, modelling frame in world
  Vec3 v_W = Vec3::Zero();          // centre-of-mass velocity [m/s]
  Vec3 w_W = Vec3::Zero();          // angular velocity [rad/s]
};

// The members an event reads first (motion, state, then mass) lead, so that advancing a body
// reads two or three cache lines of it, not five (the scheduler touches the bodies of a 10,000-
// sphere gas in no useful order).
struct Body {
  MotionKind motion = MotionKind::kDynamic;
  BodyState state;
  MassProperties mass;
  std::shared_ptr<const Shape> shape;
  KinematicMotion kinematic;  // used when motion == kKinematic
  std::string name;

  bool is_dynamic() const { return motion == MotionKind::kDynamic; }
};

}  // namespace palpable
