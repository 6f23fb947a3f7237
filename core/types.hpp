#pragma once
// Value types shared by every module: vectors, matrices and quaternions (Eigen, double precision)
// and typed ids. Frames are named by suffix (DESIGN.md §1, STYLE.md): _W world, _M the user's
// modelling frame of a body (origin at its centre of mass), _B the principal (body) frame.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <limits>

namespace palpable {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Index of a body in the world's body vector. Never a pointer.
struct BodyId {
  std::uint32_t index = std::numeric_limits<std::uint32_t>::max();
  constexpr bool valid() const { return index != std::numeric_limits<std::uint32_t>::max(); }
  friend constexpr bool operator==(BodyId a, BodyId b) { return a.index == b.index; }
  friend constexpr bool operator!=(BodyId a, BodyId b) { return a.index != b.index; }
  friend constexpr bool operator<(BodyId a, BodyId b) { return a.index < b.index; }
};

// [r]x, the matrix with skew(r) * x == r.cross(x).
inline Mat3 skew(const Vec3& r) {
  Mat3 m;
  m << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return m;
}

// Axis-aligned bounding box in the world frame.
struct Aabb {
  Vec3 min_W = Vec3::Constant(kInfinity);
  Vec3 max_W = Vec3::Constant(-kInfinity);
  bool overlaps(const Aabb& o) const {
    return (min_W.array() <= o.max_W.array()).all() && (o.min_W.array() <= max_W.array()).all();
  }
  void extend(const Aabb& o) {
    min_W = min_W.cwiseMin(o.min_W);
    max_W = max_W.cwiseMax(o.max_W);
  }
};

}  // namespace palpable
