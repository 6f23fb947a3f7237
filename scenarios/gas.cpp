#include "scenarios/gas.hpp"

#include "core/check.hpp"
#include "core/mass_properties.hpp"
#include "core/shape.hpp"

#include <cmath>
#include <random>
#include <string>

namespace palpable {

namespace {

constexpr double kPi = 3.14159265358979323846;

Body fixed_body(const std::string& name, std::shared_ptr<const Shape> shape, const Vec3& x_W) {
  Body b;
  b.name = name;
  b.motion = MotionKind::kFixed;
  b.shape = std::move(shape);
  b.mass = infinite_mass_properties();
  b.state.x_W = x_W;
  return b;
}

int lattice_side(int count) {
  int m = 1;
  while (static_cast<long long>(m) * m * m < count) ++m;
  return m;
}

}  // namespace

double gas_container_side(const GasOptions& options) {
  const double r = options.radius_m;
  return std::cbrt(options.count * (4.0 / 3.0) * kPi * r * r * r / options.volume_fraction);
}

World make_sphere_gas(const GasOptions& options) {
  if (options.count < 1) throw InputError("count", "expected at least one sphere");
  if (!(options.volume_fraction > 0.0 && options.volume_fraction < kPi / 6.0)) {
    throw InputError("volume_fraction", "expected a fraction in (0, pi / 6)");
  }
  World world;
  world.gravity_W = Vec3::Zero();
  world.default_material.friction = options.friction;
  world.default_material.restitution = options.restitution;
  const double side = gas_container_side(options);
  if (options.walls == GasWalls::kHalfspaces) {
    for (int axis = 0; axis < 3; ++axis) {
      // Solid below x_axis = 0 (outward normal +e) and above x_axis = side (outward normal -e).
      world.add(fixed_body("wall_low_" + std::to_string(axis),
                           std::make_shared<const Shape>(make_halfspace(Vec3::Unit(axis), 0.0)),
                           Vec3::Zero()));
      world.add(fixed_body("wall_high_" + std::to_string(axis),
                           std::make_shared<const Shape>(make_halfspace(-Vec3::Unit(axis), -side)),
                           Vec3::Zero()));
    }
  } else {
    // Slabs of thickness side / 4 overlapping at the edges of the container.
    const double t = 0.25 * side;
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 half = Vec3::Constant(0.5 * side + t);
      half[axis] = 0.5 * t;
      auto slab = std::make_shared<const Shape>(ConvexPolyhedron::box(half));
      Vec3 centre = Vec3::Constant(0.5 * side);
      centre[axis] = -0.5 * t;
      world.add(fixed_body("wall_low_" + std::to_string(axis), slab, centre));
      centre[axis] = side + 0.5 * t;
      world.add(fixed_body("wall_high_" + std::to_string(axis), slab, centre));
    }
  }
  auto sphere = std::make_shared<const Shape>(make_sphere(options.radius_m));
  const MassProperties mass = mass_properties_from_mass(*sphere, 1.0);
  const int m = lattice_side(options.count);
  const double spacing = side / m;
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < options.count; ++i) {
    Body b;
    b.name = "sphere_" + std::to_string(i);
    b.shape = sphere;
    b.mass = mass;
    b.state.x_W = (Vec3(i % m, (i / m) % m, i / (m * m)) + Vec3::Constant(0.5)) * spacing;
    Vec3 direction(normal(rng), normal(rng), normal(rng));
    b.state.v_W = options.speed_mps * direction.normalized();
    world.add(std::move(b));
  }
  return world;
}

void add_idle_bodies(World& world, int count, IdleKind kind, const Vec3& corner_W, double size_m) {
  const bool spheres = kind == IdleKind::kRestingSpheres;
  auto shape = std::make_shared<const Shape>(
      spheres ? Shape(make_sphere(0.5 * size_m))
              : Shape(ConvexPolyhedron::box(Vec3::Constant(0.5 * size_m))));
  const MassProperties mass =
      spheres ? mass_properties_from_mass(*shape, 1.0) : infinite_mass_properties();
  const int m = lattice_side(count);
  const double spacing = 2.0 * size_m;
  for (int i = 0; i < count; ++i) {
    Body b;
    b.name = "idle_" + std::to_string(i);
    b.motion = spheres ? MotionKind::kDynamic : MotionKind::kFixed;
    b.shape = shape;
    b.mass = mass;
    b.state.x_W = corner_W + Vec3(i % m, (i / m) % m, i / (m * m)) * spacing;
    world.add(std::move(b));
  }
}

}  // namespace palpable
