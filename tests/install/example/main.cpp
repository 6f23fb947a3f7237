// Embedding Palpable: a ball dropped 1 m onto the ground with e = 0.5; prints its first impact
// time and the height of its first rebound apex (closed forms: sqrt(2 h / g), e^2 h).
#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "scheduler/simulation.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

int main() {
  using namespace palpable;
  World world;
  world.default_material = Material{0.0, 0.5};
  Body ground;
  ground.name = "ground";
  ground.motion = MotionKind::kFixed;
  ground.shape = std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), 0.0));
  ground.mass = infinite_mass_properties();
  world.add(ground);
  Body ball;
  ball.name = "ball";
  ball.shape = std::make_shared<const Shape>(make_sphere(0.1));
  ball.mass = mass_properties_from_mass(*ball.shape, 1.0);
  ball.state.x_W = Vec3(0, 0, 1.1);
  world.add(ball);

  struct FirstImpact : SimulationObserver {
    double t = -1.0;
    void on_collision(const CollisionRecord& r) override {
      if (t < 0.0) t = r.t;
    }
  } observer;
  Simulation sim(world, SimulationOptions{});
  sim.run_until(0.7, &observer);
  const BodyState s = sim.state_at(BodyId{1}, 0.7);
  std::printf("first impact at %.12f s (closed form %.12f s); height at 0.7 s %.6f m\n", observer.t,
              std::sqrt(2.0 / 9.81), s.x_W.z() - 0.1);
  return std::abs(observer.t - std::sqrt(2.0 / 9.81)) < 1e-9 ? 0 : 1;
}
