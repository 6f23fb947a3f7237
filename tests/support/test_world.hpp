#pragma once
// One test world for every suite that runs the simulator (after Jolt's PhysicsTestContext): bodies
// in one line each, an observer that keeps what a run produces, and a run in one call.
//
//   World world;
//   world.add(test::fixed_ground());
//   world.add(test::sphere_body("ball", 0.1, 1.0, Vec3(0, 0, 0.5)));
//   const test::Run run = test::run(world, 1.0, 1e-3);   // samples every 1 ms up to 1 s
#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "scheduler/simulation.hpp"

#include <memory>
#include <string>
#include <vector>

namespace palpable::test {

inline Body dynamic_body(const std::string& name, const Shape& shape, double mass, const Vec3& x,
                         const Quat& q = Quat::Identity(), const Vec3& v = Vec3::Zero(),
                         const Vec3& w = Vec3::Zero()) {
  Body b;
  b.name = name;
  b.shape = std::make_shared<const Shape>(shape);
  b.mass = mass_properties_from_mass(*b.shape, mass);
  b.state.x_W = x;
  b.state.q_WM = q;
  b.state.v_W = v;
  b.state.w_W = w;
  return b;
}

inline Body sphere_body(const std::string& name, double radius, double mass, const Vec3& x,
                        const Vec3& v = Vec3::Zero(), const Vec3& w = Vec3::Zero()) {
  return dynamic_body(name, make_sphere(radius), mass, x, Quat::Identity(), v, w);
}

inline Body box_body(const std::string& name, const Vec3& half, double mass, const Vec3& x,
                     const Quat& q = Quat::Identity(), const Vec3& v = Vec3::Zero(),
                     const Vec3& w = Vec3::Zero()) {
  return dynamic_body(name, ConvexPolyhedron::box(half), mass, x, q, v, w);
}

inline Body fixed_body(const std::string& name, const Shape& shape, const Vec3& x = Vec3::Zero(),
                       const Quat& q = Quat::Identity()) {
  Body b;
  b.name = name;
  b.motion = MotionKind::kFixed;
  b.shape = std::make_shared<const Shape>(shape);
  b.mass = infinite_mass_properties();
  b.state.x_W = x;
  b.state.q_WM = q;
  return b;
}

// A fixed horizontal ground, the halfspace z <= 0.
inline Body fixed_ground(const std::string& name = "ground") {
  return fixed_body(name, make_halfspace(Vec3::UnitZ(), 0.0));
}

inline Quat about(const Vec3& axis, double angle) {
  return Quat(Eigen::AngleAxisd(angle, axis.normalized()));
}

// Keeps everything a run produces.
struct Recorder : SimulationObserver {
  std::vector<CollisionRecord> collisions;
  std::vector<std::vector<BodyState>> samples;  // samples[k][body]
  std::vector<double> times;
  void on_sample(double t, const std::vector<BodyState>& states) override {
    times.push_back(t);
    samples.push_back(states);
  }
  void on_collision(const CollisionRecord& r) override { collisions.push_back(r); }
};

struct Run {
  Recorder recorded;
  SimulationStats stats;
  std::vector<BodyState> final_states;  // every body at t_end
};

// Runs `world` to t_end with samples every `interval` (0: none).
inline Run run(const World& world, double t_end, double interval = 0.0) {
  Simulation sim(world, SimulationOptions{interval});
  Run out;
  sim.run_until(t_end, &out.recorded);
  out.stats = sim.stats();
  for (std::uint32_t i = 0; i < sim.world().bodies.size(); ++i) {
    out.final_states.push_back(sim.state_at(BodyId{i}, t_end));
  }
  return out;
}

}  // namespace palpable::test
