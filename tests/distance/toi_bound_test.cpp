// Time-of-impact bounds: the branch formulas, exact closed forms, and the bound never overshooting
// on 10,000 random ballistic trajectory pairs (dense sampling refined by bisection, exact motion
// from core/ballistic).
#include "distance/toi_bound.hpp"

#include "core/ballistic.hpp"
#include "core/mass_properties.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

#include <cstdio>
#include <limits>
#include <string>

using namespace palpable;
using namespace palpable::test;

namespace {

const Vec3 kGravity(0.0, 0.0, -9.81);

Body make_body(const TestShape& s, MotionKind kind, const BodyState& state) {
  Body b;
  b.name = s.name;
  b.motion = kind;
  b.shape = s.shape;
  if (kind != MotionKind::kDynamic) {
    b.mass = infinite_mass_properties();
  } else if (const auto* ball = std::get_if<LoadedBall>(s.shape.get())) {
    // A loaded ball's mass properties are given: a solid ball's, about its centre of mass.
    const double m = 1000.0 * 4.0 / 3.0 * M_PI * std::pow(ball->radius, 3);
    const double I = 0.4 * m * ball->radius * ball->radius;
    b.mass = mass_properties_from_inertia(m, Vec3(I, I, 0.8 * I).asDiagonal());
  } else {
    b.mass = mass_properties_from_density(*s.shape, 1000.0);
  }
  b.state = state;
  return b;
}

Pose pose_of(const BodyState& s) {
  return {s.x_W, s.q_WM};
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

}  // namespace

TEST_CASE("gap-closing branches", "[distance][toi]") {
  // b > 0: 2Δ / (b + sqrt(b^2 + 2aΔ)), also for a < 0 with a real root.
  CHECK(solve_gap_closing(0.0, 2.0, 1.0) == Approx(0.5));
  CHECK(solve_gap_closing(-1.0, 2.0, 1.0) == Approx((2.0 - std::sqrt(2.0)) / 1.0));
  // b > 0 but decelerating before closing: no bound.
  CHECK(solve_gap_closing(-10.0, 1.0, 1.0) == kInfinity);
  // b <= 0, a > 0 (right after a bounce): (-b + sqrt(b^2 + 2aΔ)) / a, no cancellation, no NaN.
  const double a = 9.81, b = -3.0, delta = 1e-12;
  const double t = solve_gap_closing(a, b, delta);
  CHECK(std::isfinite(t));
  CHECK(t == Approx((-b + std::sqrt(b * b + 2 * a * delta)) / a).epsilon(1e-15));
  // The tempting 2Δ / (b + sqrt(...)) for b < 0 cancels: at Δ = 1e-12 it gives a huge or NaN time.
  const double wrong = 2 * delta / (b + std::sqrt(b * b + 2 * a * delta));
  CHECK(!(std::abs(wrong - t) < 1e-6 * t));
  // Δ = 0 gives 0; b <= 0 and a <= 0 gives no bound.
  CHECK(solve_gap_closing(a, b, 0.0) == 0.0);
  CHECK(solve_gap_closing(0.0, -1.0, 1.0) == kInfinity);
  CHECK(solve_gap_closing(-1.0, 0.0, 1.0) == kInfinity);
}

TEST_CASE("rotational terms: zero for a platter spinning about its normal, never 0 x inf",
          "[distance][toi]") {
  ToiMotion platter;
  platter.kinematic = true;
  platter.spin_W = Vec3(0, 0, 2 * M_PI);
  platter.rotation_radius = kInfinity;
  CHECK(rotational_term(platter, Vec3(0, 0, -1)) == 0.0);
  CHECK(rotational_term(platter, Vec3(1, 0, 0)) == kInfinity);
  platter.rotation_radius = 0.3;
  CHECK(rotational_term(platter, Vec3(1, 0, 0)) == Approx(2 * M_PI * 0.3));
  ToiMotion ball;
  ball.omega_bound = 100.0;
  ball.rotation_radius = 0.0;
  CHECK(rotational_term(ball, Vec3(1, 0, 0)) == 0.0);
  ToiMotion block;
  block.omega_bound = 2.0;
  block.rotation_radius = 0.5;
  CHECK(rotational_term(block, Vec3(0, 1, 0)) == Approx(1.0));
  // A body whose ω is known over the interval (spherical inertia: constant) counts only the part
  // of ω across d̂: spinning about the normal moves no point along it.
  block.omega_fixed_W = Vec3(0, 0, 2.0);
  block.omega_free = 0.0;
  CHECK(rotational_term(block, Vec3(0, 0, -1)) == 0.0);
  CHECK(rotational_term(block, Vec3(1, 0, 0)) == Approx(1.0));
  block.omega_fixed_W = Vec3(0.6, 0, 1.6);  // |ω x d̂| = 0.6 for d̂ = -z
  CHECK(rotational_term(block, Vec3(0, 0, -1)) == Approx(0.3));
  block.omega_free = 10.0;  // never above ω̄ ρ
  CHECK(rotational_term(block, Vec3(0, 0, -1)) == Approx(1.0));
}

TEST_CASE("exact times of impact for spheres", "[distance][toi]") {
  Settings settings;
  settings.envelope_m = 1e-3;
  const double d_target = 0.5 * settings.envelope_m;
  const TestShape ball_shape = ball();  // radius 0.4
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  SECTION("two dynamic spheres under the same gravity") {
    BodyState s1, s2;
    s1.x_W = Vec3(0, 0, 1);
    s1.v_W = Vec3(1, 0.2, 0);
    s2.x_W = Vec3(3, 0.1, 1.2);
    s2.v_W = Vec3(-1, 0, 0);
    const Body b1 = make_body(ball_shape, MotionKind::kDynamic, s1);
    const Body b2 = make_body(ball_shape, MotionKind::kDynamic, s2);
    PairCache cache;
    const DistanceResult r = closest_features(*ball_shape.geometry, pose_of(s1),
                                              *ball_shape.geometry, pose_of(s2), cache, 100);
    const ToiBound bound = time_of_impact(b1, s1, *ball_shape.geometry, b2, s2,
                                          *ball_shape.geometry, r, kGravity, settings);
    REQUIRE(bound.exact);
    REQUIRE(std::isfinite(bound.dt));
    const BodyState a1 = advance(b1, s1, bound.dt, kGravity);
    const BodyState a2 = advance(b2, s2, bound.dt, kGravity);
    const DistanceResult at = closest_features(*ball_shape.geometry, pose_of(a1),
                                               *ball_shape.geometry, pose_of(a2), cache, 100);
    CHECK(at.distance == Approx(d_target).epsilon(1e-9));
  }
  SECTION("ball on fixed ground, and on a platter spinning about its normal and rising") {
    for (int kinematic = 0; kinematic < 2; ++kinematic) {
      BodyState s, g;
      s.x_W = Vec3(0.2, 0.1, 1.3);
      s.v_W = Vec3(0.3, 0, 1.0);
      s.w_W = Vec3(3, 1, 2);
      const Body ball_body = make_body(ball_shape, MotionKind::kDynamic, s);
      Body ground_body =
          make_body(ground, kinematic ? MotionKind::kKinematic : MotionKind::kFixed, g);
      if (kinematic) {
        ground_body.kinematic.angular_velocity_W = Vec3(0, 0, 2 * M_PI);
        ground_body.kinematic.velocity_W = Vec3(0, 0, 0.1);
      }
      PairCache cache;
      const DistanceResult r = closest_features(*ball_shape.geometry, pose_of(s), *ground.geometry,
                                                pose_of(g), cache, 100);
      const ToiBound bound = time_of_impact(ball_body, s, *ball_shape.geometry, ground_body, g,
                                            *ground.geometry, r, kGravity, settings);
      REQUIRE(bound.exact);
      const BodyState a = advance(ball_body, s, bound.dt, kGravity);
      const BodyState ag = advance(ground_body, g, bound.dt, kGravity);
      const DistanceResult at = closest_features(*ball_shape.geometry, pose_of(a), *ground.geometry,
                                                 pose_of(ag), cache, 100);
      CAPTURE(kinematic, bound.dt);
      CHECK(at.distance == Approx(d_target).epsilon(1e-9));
      CHECK(at.n_W.z() == Approx(1.0));
    }
  }
}

namespace {

struct ToiTrials {
  long trials = 0, finite = 0, exact = 0, overshoots = 0, contacts = 0;
  double sum_ratio = 0.0;
  long count_by_kind[5] = {0, 0, 0, 0, 0};
};

// `count` random trajectory pairs of a mover (one of `movers`) against another mover, a fixed
// block, a kinematic turntable, a kinematic halfspace spinning about its normal and moving up, or
// a kinematic paddle: the bound against the true first time the gap falls to the target (dense
// sampling refined by bisection, exact motion from core/ballistic).
ToiTrials toi_trials(const std::vector<TestShape>& movers, std::uint64_t seed, long count) {
  Settings settings;
  settings.envelope_m = 1e-3;
  settings.toi_min_progress_s = 0.0;  // the raw conservative bound
  const double d_target = 0.5 * settings.envelope_m;
  const TestShape platter = make_test_shape("platter", ConvexPolyhedron::prism(1.5, 0.05, 24));
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  const TestShape block = cube();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ToiTrials out;
  long& trials = out.trials;
  while (trials < count) {
    const int kind = static_cast<int>(trials % 5);
    const TestShape& s1 = movers[static_cast<std::size_t>(u(rng) * movers.size())];
    BodyState st1, st2;
    st1.q_WM = random_rotation(rng);
    st1.w_W = random_unit(rng) * (20.0 * u(rng));
    const TestShape* s2 = nullptr;
    MotionKind k2 = MotionKind::kDynamic;
    Body b2;
    if (kind == 0) {  // two dynamic bodies flying at each other
      s2 = &movers[static_cast<std::size_t>(u(rng) * movers.size())];
      const Vec3 dir = random_unit(rng);
      st1.x_W = Vec3::Zero();
      st2.x_W = dir * (1.2 + 1.5 * u(rng));
      st1.v_W = dir * (3.0 * u(rng)) + random_unit(rng) * u(rng);
      st2.v_W = -dir * (3.0 * u(rng)) + random_unit(rng) * u(rng);
      st2.q_WM = random_rotation(rng);
      st2.w_W = random_unit(rng) * (20.0 * u(rng));
    } else if (kind == 1) {  // falling onto a fixed block
      s2 = &block;
      k2 = MotionKind::kFixed;
      st2.x_W = Vec3::Zero();
      st2.q_WM = random_rotation(rng);
      st1.x_W = Vec3(0.5 * (u(rng) - 0.5), 0.5 * (u(rng) - 0.5), 1.6 + u(rng));
      st1.v_W = Vec3(u(rng) - 0.5, u(rng) - 0.5, -3.0 * u(rng));
    } else if (kind == 2) {  // falling onto a kinematic turntable (prism spinning about z)
      s2 = &platter;
      k2 = MotionKind::kKinematic;
      st2.x_W = Vec3::Zero();
      st1.x_W = Vec3(2.0 * (u(rng) - 0.5), 2.0 * (u(rng) - 0.5), 0.95 + u(rng));
      st1.v_W = Vec3(u(rng) - 0.5, u(rng) - 0.5, -2.0 * u(rng));
    } else if (kind == 4) {  // at a kinematic paddle: a block turning about an off-centre axis
      s2 = &block;
      k2 = MotionKind::kKinematic;
      st2.x_W = Vec3(0.0, 0.6, 0.0);  // the axis is the x axis through the origin
      st1.x_W = Vec3(2.0 * (u(rng) - 0.5), 0.6 + 2.0 * (u(rng) - 0.5), 2.0 + u(rng));
      st1.v_W = Vec3(u(rng) - 0.5, u(rng) - 0.5, -3.0 * u(rng));
    } else {  // onto a kinematic halfspace spinning about its normal and moving up
      s2 = &ground;
      k2 = MotionKind::kKinematic;
      st2.x_W = Vec3::Zero();
      st1.x_W = Vec3(u(rng), u(rng), 0.9 + u(rng));
      st1.v_W = Vec3(u(rng) - 0.5, u(rng) - 0.5, -2.0 * u(rng));
    }
    const Body b1 = make_body(s1, MotionKind::kDynamic, st1);
    b2 = make_body(*s2, k2, st2);
    if (k2 == MotionKind::kKinematic) {
      const Vec3 axis = kind == 4 ? Vec3::UnitX() : Vec3::UnitZ();
      b2.kinematic.angular_velocity_W = axis * (2 * M_PI * (0.5 + u(rng)));
      b2.kinematic.point_W = Vec3::Zero();
      b2.kinematic.velocity_W = kind == 3 ? Vec3(0, 0, 0.3 * u(rng)) : Vec3::Zero();
    }
    PairCache cache;
    const DistanceResult r =
        closest_features(*s1.geometry, pose_of(st1), *s2->geometry, pose_of(st2), cache, 10000);
    if (r.status != ContactStatus::kSeparated || r.distance <= 2.0 * d_target) continue;
    ++trials;
    ++out.count_by_kind[kind];
    const ToiBound bound =
        time_of_impact(b1, st1, *s1.geometry, b2, st2, *s2->geometry, r, kGravity, settings);
    REQUIRE(bound.dt >= 0.0);
    if (std::isfinite(bound.dt)) ++out.finite;
    if (bound.exact) ++out.exact;
    // The true first time the gap falls to d_target, searched over [0, min(bound, 1 s)] (a bit
    // beyond the bound when it is finite, to measure its tightness).
    const double horizon = std::min(std::isfinite(bound.dt) ? 1.5 * bound.dt : 1.0, 1.0);
    auto gap = [&](double t) {
      const BodyState a1 = advance(b1, st1, t, kGravity);
      const BodyState a2 = advance(b2, st2, t, kGravity);
      const DistanceResult q =
          closest_features(*s1.geometry, pose_of(a1), *s2->geometry, pose_of(a2), cache, 10000);
      return q.status == ContactStatus::kSeparated ? q.distance - d_target : -1.0;
    };
    const int samples = 96;
    double t_prev = 0.0;
    double t_true = kInfinity;
    for (int k = 1; k <= samples; ++k) {
      const double t = horizon * k / samples;
      if (gap(t) <= 0.0) {
        double lo = t_prev, hi = t;
        for (int it = 0; it < 50; ++it) {
          const double mid = 0.5 * (lo + hi);
          (gap(mid) <= 0.0 ? hi : lo) = mid;
        }
        t_true = hi;
        break;
      }
      t_prev = t;
    }
    if (std::isfinite(t_true)) {
      ++out.contacts;
      const double ratio = bound.dt / t_true;
      out.sum_ratio += std::min(ratio, 1.0);
      const bool over = bound.dt > t_true * (1.0 + 1e-9) + 1e-12;
      if (over) {
        ++out.overshoots;
        UNSCOPED_INFO("overshoot: kind " << kind << " " << s1.name << "-" << s2->name << " bound "
                                         << bound.dt << " true " << t_true << " exact "
                                         << bound.exact);
      }
    }
  }
  return out;
}

}  // namespace

TEST_CASE("the bound never overshoots on 10,000 random ballistic trajectory pairs",
          "[distance][toi][random]") {
  const ToiTrials t = toi_trials({cube(), tetrahedron(), coin(), sliver(), ball()}, 424242, 10000);
  std::printf(
      "TOI: %ld trajectory pairs (dynamic-dynamic %ld, on fixed block %ld, on turntable "
      "%ld, on spinning halfspace %ld, at kinematic paddle %ld), finite bounds %ld, exact "
      "%ld, reached d_target within min(1.5 bound, 1 s) %ld, overshoots %ld, mean bound/true "
      "%.3f\n",
      t.trials, t.count_by_kind[0], t.count_by_kind[1], t.count_by_kind[2], t.count_by_kind[3],
      t.count_by_kind[4], t.finite, t.exact, t.contacts, t.overshoots,
      t.contacts ? t.sum_ratio / t.contacts : 0.0);
  CHECK(t.overshoots == 0);
  CHECK(t.contacts > 1000);
}

TEST_CASE("the bound never overshoots for the smooth shapes (3,000 random trajectory pairs)",
          "[distance][toi][random][smooth]") {
  // A loaded ball far off centre (its surface sweeps |offset| + radius about the centre of mass),
  // a thin disk, an ellipsoid, a capsule.
  const ToiTrials t =
      toi_trials({make_test_shape("ellipsoid", make_ellipsoid(Vec3(0.2, 0.3, 0.45))),
                  make_test_shape("disk", make_cylinder(0.4, 0.02)),
                  make_test_shape("capsule", make_capsule(0.15, 0.3)),
                  make_test_shape("loaded ball", make_loaded_ball(0.3, 0.2))},
                 1606, 3000);
  std::printf(
      "TOI smooth: %ld pairs, finite %ld, reached %ld, overshoots %ld, mean bound/true "
      "%.3f\n",
      t.trials, t.finite, t.contacts, t.overshoots, t.contacts ? t.sum_ratio / t.contacts : 0.0);
  CHECK(t.overshoots == 0);
  CHECK(t.contacts > 300);
}

TEST_CASE("inside the target gap and receding: back down at the target gap, else after -2b/a",
          "[distance][toi]") {
  // A block just lifted off by a microcollision: 3e-5 m above a fixed plane, target 5e-5 m,
  // rising at 0.04 m/s against gravity's 9.81 along the normal. It rises above the target and
  // the bound is when it comes back down to it; the gap never falls below 3e-5 before that.
  // Receding, the bound is the same under both contact models; approaching, each has its rule.
  for (const ContactModel model : {ContactModel::kMicrocollisions, ContactModel::kPersistent}) {
    CAPTURE(std::string(to_string(model)));
    ToiMotion block, ground;
    block.v_W = Vec3(0.3, 0.0, 0.04);
    block.a_W = kGravity;
    DistanceResult closest;
    closest.status = ContactStatus::kSeparated;
    closest.distance = 3e-5;
    closest.n_W = Vec3::UnitZ();  // from the ground (body 2) to the block (body 1)
    Settings settings;
    settings.contact_model = model;
    ToiBound bound = toi_bound(block, ground, closest, 5e-5, settings);
    CHECK_FALSE(bound.floored);
    auto gap = [](double t) { return 3e-5 + 0.04 * t - 0.5 * 9.81 * t * t; };
    CHECK(gap(bound.dt) == Approx(5e-5).epsilon(1e-9));
    CHECK(bound.dt > 0.04 / 9.81);  // on the way down
    for (int k = 1; k < 100; ++k) {
      const double t = bound.dt * k / 100.0;
      CHECK(gap(t) >= 3e-5);
    }
    // Rising too slowly to reach the target (peak 3e-5 + 1e-4^2 / 19.62 < 5e-5): back at the
    // present gap, t = -2b/a.
    block.v_W.z() = 1e-4;
    CHECK(toi_bound(block, ground, closest, 5e-5, settings).dt ==
          Approx(2.0 * 1e-4 / 9.81).epsilon(1e-14));
    block.v_W.z() = 0.04;
    // Receding without a closing acceleration: never again.
    block.a_W = Vec3::Zero();
    CHECK(toi_bound(block, ground, closest, 5e-5, settings).dt == kInfinity);
    block.v_W.z() = -0.04;
    if (model == ContactModel::kMicrocollisions) {
      // Approaching inside the target gap, the microcollision model's rule: now.
      CHECK(toi_bound(block, ground, closest, 5e-5, settings).dt == settings.toi_min_progress_s);
    } else {
      // The persistent model's: when half the present gap has closed, 1.5e-5 / 0.04 s.
      bound = toi_bound(block, ground, closest, 5e-5, settings);
      CHECK_FALSE(bound.floored);
      CHECK(bound.dt == Approx(0.5 * 3e-5 / 0.04).epsilon(1e-12));
    }
  }
}

TEST_CASE("inside the target gap receding at rounding: persistent aims at half the gap",
          "[distance][toi]") {
  // Two held balls of a pile, 4.4e-5 m apart inside the 5e-5 m target gap, at rest relative to
  // each other up to rounding (receding at 1e-19 m/s) with the 1e-9 m/s^2 slack of an integrated
  // island's motion. Taken as receding, the bound was -2b/a = 2e-10 s and shrank with b: a
  // pile of 100 balls checked that pair 5.5 million times in 0.1 s and did not reach 10 s.
  // Under the persistent model such a pair is at rest, and aims at half its present gap:
  // sqrt(2 * 2.2e-5 / 1e-9) = 210 s. Receding faster than the still speed it is the receding
  // branch's (the case above); under the microcollision model always.
  ToiMotion ball, other;
  ball.accel_slack = 1e-9;
  DistanceResult closest;
  closest.status = ContactStatus::kSeparated;
  closest.distance = 4.4e-5;
  closest.n_W = Vec3::UnitX();
  Settings settings;
  settings.contact_model = ContactModel::kPersistent;
  for (const double speed : {1e-19, 1e-12, 0.9e-9}) {
    CAPTURE(speed);
    ball.v_W = Vec3(speed, 0.0, 0.0);
    const ToiBound bound = toi_bound(ball, other, closest, 5e-5, settings);
    const double half = solve_gap_closing(1e-9, -speed, 0.5 * closest.distance);
    CHECK(bound.dt == half);
    CHECK(bound.dt > 200.0);
  }
  // Faster than the still speed: the receding branch's (here back down at the target gap).
  ball.v_W.x() = 1e-6;
  CHECK(toi_bound(ball, other, closest, 5e-5, settings).dt ==
        solve_return_to_gap(1e-9, -1e-6, closest.distance - 5e-5));
  settings.contact_model = ContactModel::kMicrocollisions;
  ball.v_W.x() = 1e-19;
  CHECK(toi_bound(ball, other, closest, 5e-5, settings).dt == Approx(2e-19 / 1e-9).epsilon(1e-12));
}

TEST_CASE("the progress floor never carries a pair through contact", "[distance][toi]") {
  // A box face closing on a fixed plane at 1e4 m/s: the 1e-6 s floor alone would move it 1 cm,
  // a hundred envelopes. The floor is capped by the time the bound allows to close the whole
  // present gap, inside the target gap too: no overlap. So under both contact models.
  for (const ContactModel model : {ContactModel::kMicrocollisions, ContactModel::kPersistent}) {
    CAPTURE(std::string(to_string(model)));
    ToiMotion box, ground;
    box.v_W = Vec3(0.0, 0.0, -1e4);
    DistanceResult closest;
    closest.status = ContactStatus::kSeparated;
    closest.n_W = Vec3::UnitZ();
    Settings settings;
    settings.contact_model = model;
    const double d_target = 5e-5;
    closest.distance = 1e-3;  // the conservative bound is (1e-3 - 5e-5) / 1e4 = 9.5e-8 s
    ToiBound bound = toi_bound(box, ground, closest, d_target, settings);
    CHECK(bound.floored);
    CHECK(bound.dt == Approx(1e-3 / 1e4).epsilon(1e-12));
    closest.distance = 1e-5;  // inside the target gap, approaching: up to the plane, not past it
    bound = toi_bound(box, ground, closest, d_target, settings);
    CHECK(bound.floored);
    CHECK(bound.dt == Approx(1e-5 / 1e4).epsilon(1e-12));
    box.v_W.z() = -1.0;
    bound = toi_bound(box, ground, closest, d_target, settings);
    if (model == ContactModel::kMicrocollisions) {
      // Slow pairs keep the whole floor: at 1 m/s, 1e-6 s closes 1e-6 m < the 1e-5 m gap (the
      // microcollision model's bound inside the target gap is now, raised to the floor).
      CHECK(bound.dt == settings.toi_min_progress_s);
    } else {
      // The persistent model's bound there, half the present gap at 1 m/s, is above the floor.
      CHECK_FALSE(bound.floored);
      CHECK(bound.dt == Approx(0.5 * 1e-5 / 1.0).epsilon(1e-12));
    }
  }
}

TEST_CASE("a held body's vertices above a fixed plane: the bound never overshoots (600 motions)",
          "[distance][toi][random]") {
  // vertex_bound_above_plane with a motion that is not ballistic, as an integrated held body's:
  // its centre of mass accelerates within `slack` of a0 (a0 + slack sin(k t) e), its angular
  // velocity w0 + alpha0 t + beta sin(kappa t) u stays within w_bar over the horizon T and
  // changes at most at |alpha0| + beta kappa; the orientation is integrated by RK4 in small steps.
  // Its lowest vertex starts 1e-9 to 1e-2 m above the plane z = 0 and the bound aims at half
  // that (as a held pair within the envelope does). The first sampled instant a vertex is within
  // d_target of the plane is never before the bound.
  std::mt19937_64 rng(20261129);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<TestShape> shapes = {cube(), tetrahedron(), coin(), sliver()};
  const TestShape floor = make_test_shape("floor", make_halfspace(Vec3::UnitZ(), 0.0));
  const Vec3 n = Vec3::UnitZ();  // the floor's normal: its solid lies below z = 0
  const double T = 0.05;
  int reached = 0, overshoots = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const TestShape& shape = shapes[static_cast<std::size_t>(trial) % shapes.size()];
    const FeatureMesh& mesh = *shape.geometry->pieces().front().mesh;
    BodyState s;
    s.q_WM = random_rotation(rng);
    auto lowest = [&](const Vec3& x, const Quat& q) {
      double h = kInfinity;
      for (int v = 0; v < mesh.num_vertices(); ++v) h = std::min(h, n.dot(x + q * mesh.vertex(v)));
      return h;
    };
    const double h0 = std::pow(10.0, -9.0 + 7.0 * u(rng));
    s.x_W = Vec3(0.0, 0.0, h0 - lowest(Vec3::Zero(), s.q_WM));
    s.v_W = random_unit(rng) * (0.5 * u(rng));
    s.w_W = random_unit(rng) * (10.0 * u(rng));
    const Vec3 alpha0 = random_unit(rng) * (50.0 * u(rng));
    const double beta = 5.0 * u(rng), kappa = 200.0 * u(rng);
    const Vec3 spin_axis = random_unit(rng);
    const Vec3 a0 = kGravity + random_unit(rng) * (5.0 * u(rng));
    const double slack = 3.0 * u(rng), k = 1.0 + 300.0 * u(rng);
    const Vec3 e = random_unit(rng);
    const double w_bar = s.w_W.norm() + alpha0.norm() * T + beta;
    const double d_target = 0.5 * h0;
    const double bound =
        vertex_bound_above_plane(s, *shape.geometry, BodyState{}, *halfspace(*floor.geometry), a0,
                                 slack, w_bar * w_bar + alpha0.norm() + beta * kappa, d_target);
    REQUIRE(bound >= 0.0);
    auto omega = [&](double t) {
      return Vec3(s.w_W + alpha0 * t + beta * std::sin(kappa * t) * spin_axis);
    };
    auto position = [&](double t) {
      return Vec3(s.x_W + s.v_W * t + 0.5 * a0 * t * t +
                  slack * (t / k - std::sin(k * t) / (k * k)) * e);
    };
    auto dq = [&](double t, const Eigen::Vector4d& q) {
      const Quat w(0.0, omega(t).x(), omega(t).y(), omega(t).z());
      const Quat r = w * Quat(q(0), q(1), q(2), q(3));
      return Eigen::Vector4d(0.5 * r.w(), 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z());
    };
    const double horizon = std::min(1.5 * bound, T);
    const int steps = 2000;
    const double h = horizon / steps;
    Eigen::Vector4d q(s.q_WM.w(), s.q_WM.x(), s.q_WM.y(), s.q_WM.z());
    for (int i = 1; i <= steps; ++i) {
      const double t = (i - 1) * h;
      const Eigen::Vector4d k1 = dq(t, q), k2 = dq(t + 0.5 * h, q + 0.5 * h * k1),
                            k3 = dq(t + 0.5 * h, q + 0.5 * h * k2), k4 = dq(t + h, q + h * k3);
      q += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      q.normalize();
      if (lowest(position(t + h), Quat(q(0), q(1), q(2), q(3))) <= d_target) {
        ++reached;
        if (bound > t + h) {
          ++overshoots;
          UNSCOPED_INFO("overshoot: " << shape.name << " h0 " << h0 << " bound " << bound
                                      << " reached by " << t + h);
        }
        break;
      }
    }
  }
  std::printf(
      "held vertex bound: 600 motions, %d reached the target gap within 1.5 bounds, "
      "%d overshoots\n",
      reached, overshoots);
  CHECK(overshoots == 0);
  CHECK(reached > 200);
}

TEST_CASE("a body's vertices above a moving body's face: the bound never overshoots (600 motions)",
          "[distance][toi][random]") {
  // vertex_bound_above_face: two bodies, each moving as an integrated held body may - its centre
  // of mass accelerating within `slack` of a0 (a0 + slack sin(k t) e), its angular velocity
  // w0 + alpha0 t + beta sin(kappa t) u within w_bar and changing at most at |alpha0| + beta
  // kappa, its orientation integrated by RK4 in small steps. A's lowest vertex starts 1e-9 to
  // 1e-2 m above the plane of a random face of B, and the bound aims at half that (as a pair of
  // held bodies within the envelope does). The first sampled instant a vertex of A is within
  // d_target of that face's plane (which B, convex, lies below: a lower bound of their distance)
  // is never before the bound. Dropping the face's turning from the bound (its w_B terms) gives
  // overshoots.
  std::mt19937_64 rng(20261130);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<TestShape> shapes = {cube(), tetrahedron(), coin(), sliver()};
  const double T = 0.01;
  struct Motion {
    BodyState s;
    Vec3 alpha0, spin_axis, a0, e;
    double beta, kappa, slack, k;
    Vec3 omega(double t) const {
      return s.w_W + alpha0 * t + beta * std::sin(kappa * t) * spin_axis;
    }
    Vec3 position(double t) const {
      return s.x_W + s.v_W * t + 0.5 * a0 * t * t + slack * (t / k - std::sin(k * t) / (k * k)) * e;
    }
    VertexMotion bounds() const {
      VertexMotion m;
      m.accel_W = a0;
      m.accel_slack = slack;
      m.w_bound = s.w_W.norm() + alpha0.norm() * 0.01 + beta;
      m.alpha_bound = alpha0.norm() + beta * kappa;
      return m;
    }
  };
  auto random_motion = [&](BodyState s) {
    Motion m;
    s.v_W = random_unit(rng) * (0.5 * u(rng));
    s.w_W = random_unit(rng) * (10.0 * u(rng));
    m.s = s;
    m.alpha0 = random_unit(rng) * (50.0 * u(rng));
    m.beta = 5.0 * u(rng);
    m.kappa = 200.0 * u(rng);
    m.spin_axis = random_unit(rng);
    m.a0 = kGravity + random_unit(rng) * (5.0 * u(rng));
    m.slack = 3.0 * u(rng);
    m.k = 1.0 + 300.0 * u(rng);
    m.e = random_unit(rng);
    return m;
  };
  int reached = 0, overshoots = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const TestShape& shape_a = shapes[static_cast<std::size_t>(trial) % shapes.size()];
    const TestShape& shape_b = shapes[static_cast<std::size_t>(trial / 4) % shapes.size()];
    const FeatureMesh& mesh_a = *shape_a.geometry->pieces().front().mesh;
    const ShapeGeometry::Piece& piece_b = shape_b.geometry->pieces().front();
    const FeatureMesh& mesh_b = *piece_b.mesh;
    const int face = static_cast<int>(u(rng) * mesh_b.num_faces()) % mesh_b.num_faces();
    BodyState sb;
    sb.q_WM = random_rotation(rng);
    sb.x_W = random_unit(rng) * 0.01;
    // The face's plane at B's state: normal and offset in the world.
    auto plane = [&](const Vec3& x, const Quat& q) {
      const Vec3 n = q * (piece_b.R_M * mesh_b.face_normal(face));
      return std::make_pair(n, n.dot(x + q * piece_b.p_M) + mesh_b.face_offset(face));
    };
    auto lowest = [&](const Vec3& xa, const Quat& qa, const Vec3& xb, const Quat& qb) {
      const auto [n, d] = plane(xb, qb);
      double h = kInfinity;
      for (int v = 0; v < mesh_a.num_vertices(); ++v) {
        h = std::min(h, n.dot(xa + qa * mesh_a.vertex(v)) - d);
      }
      return h;
    };
    BodyState sa;
    sa.q_WM = random_rotation(rng);
    const double h0 = std::pow(10.0, -9.0 + 7.0 * u(rng));
    {
      const auto [n, d] = plane(sb.x_W, sb.q_WM);
      // A's centre placed along n above the face's centroid region, its lowest vertex at h0.
      const double low = lowest(Vec3::Zero(), sa.q_WM, sb.x_W, sb.q_WM);
      sa.x_W = (h0 - low) * n;
    }
    REQUIRE(std::abs(lowest(sa.x_W, sa.q_WM, sb.x_W, sb.q_WM) - h0) <= 1e-12 + 1e-9 * h0);
    const Motion ma = random_motion(sa), mb = random_motion(sb);
    const double d_target = 0.5 * h0;
    const double bound = vertex_bound_above_face(ma.s, *shape_a.geometry, ma.bounds(), mb.s,
                                                 piece_b, face, mb.bounds(), d_target);
    REQUIRE(bound >= 0.0);
    REQUIRE(bound <= 1e-2);
    auto dq = [&](const Motion& m, double t, const Eigen::Vector4d& q) {
      const Vec3 w3 = m.omega(t);
      const Quat w(0.0, w3.x(), w3.y(), w3.z());
      const Quat r = w * Quat(q(0), q(1), q(2), q(3));
      return Eigen::Vector4d(0.5 * r.w(), 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z());
    };
    auto rk4 = [&](const Motion& m, double t, double h, Eigen::Vector4d& q) {
      const Eigen::Vector4d k1 = dq(m, t, q), k2 = dq(m, t + 0.5 * h, q + 0.5 * h * k1),
                            k3 = dq(m, t + 0.5 * h, q + 0.5 * h * k2),
                            k4 = dq(m, t + h, q + h * k3);
      q += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      q.normalize();
    };
    const double horizon = std::min(1.5 * bound, T);
    const int steps = 2000;
    const double h = horizon / steps;
    Eigen::Vector4d qa(ma.s.q_WM.w(), ma.s.q_WM.x(), ma.s.q_WM.y(), ma.s.q_WM.z());
    Eigen::Vector4d qb(mb.s.q_WM.w(), mb.s.q_WM.x(), mb.s.q_WM.y(), mb.s.q_WM.z());
    for (int i = 1; i <= steps; ++i) {
      const double t = (i - 1) * h;
      rk4(ma, t, h, qa);
      rk4(mb, t, h, qb);
      if (lowest(ma.position(t + h), Quat(qa(0), qa(1), qa(2), qa(3)), mb.position(t + h),
                 Quat(qb(0), qb(1), qb(2), qb(3))) <= d_target) {
        ++reached;
        if (bound > t + h) {
          ++overshoots;
          UNSCOPED_INFO("overshoot: " << shape_a.name << " on " << shape_b.name << " h0 " << h0
                                      << " bound " << bound << " reached by " << t + h);
        }
        break;
      }
    }
  }
  std::printf(
      "vertex bound above a moving face: 600 motions, %d reached the target gap within 1.5 "
      "bounds, %d overshoots\n",
      reached, overshoots);
  CHECK(overshoots == 0);
  CHECK(reached > 200);
}

TEST_CASE("a vertex sliding fast over a turning face (Coriolis) and unbounded motions",
          "[distance][toi]") {
  // A review's cases for vertex_bound_above_face. A tetrahedron's lowest vertex 1e-6 m above the
  // top face of a coin turning at 1 rad/s about an axis in that face, sliding across it at 10 m/s:
  // the turning of the face's normal meets the sliding vertex (2 w U, 20 m/s^2), and the gap
  // closes mostly by it. The bound must not come after the first instant (sampled exactly: the
  // face turns rigidly, the vertex translates) the vertex is within the target; without the
  // 2 w_B U term the bound was 14 times too late. And an infinite bound on either motion bounds
  // nothing (0), where a NaN once let the whole 1e-2 s horizon through.
  const TestShape a = tetrahedron(), b = coin();
  const ShapeGeometry::Piece& piece_b = b.geometry->pieces().front();
  const ShapeGeometry::Piece& pa = a.geometry->pieces().front();
  int top = -1;
  for (int f = 0; f < piece_b.mesh->num_faces(); ++f) {
    if ((piece_b.R_M * piece_b.mesh->face_normal(f)).z() > 0.999) top = f;
  }
  REQUIRE(top >= 0);
  const double w = 1.0, U = 10.0, h0 = 1e-6, d_target = 0.5e-6;
  BodyState sb;
  sb.w_W = Vec3(w, 0, 0);
  const Vec3 n0 = piece_b.R_M * piece_b.mesh->face_normal(top);
  const double off0 = n0.dot(piece_b.p_M) + piece_b.mesh->face_offset(top);
  BodyState sa;
  sa.q_WM = Quat(Eigen::AngleAxisd(0.2, Vec3::UnitX()));
  const Mat3 RA = sa.q_WM.toRotationMatrix();
  int lowest = 0;
  for (int k = 0; k < pa.mesh->num_vertices(); ++k) {
    if ((RA * pa.mesh->vertex(k)).z() < (RA * pa.mesh->vertex(lowest)).z()) lowest = k;
  }
  sa.x_W = Vec3(0, 0, off0 + h0) - RA * (pa.p_M + pa.R_M * pa.mesh->vertex(lowest));
  sa.v_W = Vec3(0, U, 0);
  VertexMotion ma, mb;
  mb.w_bound = w;
  const double bound = vertex_bound_above_face(sa, *a.geometry, ma, sb, piece_b, top, mb, d_target);
  REQUIRE(bound > 0.0);
  double reached = -1.0;
  const int steps = 200000;
  const double horizon = std::min(0.01, 1.5 * bound);
  for (int i = 1; i <= steps && reached < 0.0; ++i) {
    const double t = horizon * i / steps;
    const Mat3 RB = Eigen::AngleAxisd(w * t, Vec3::UnitX()).toRotationMatrix();
    const Vec3 n = RB * n0;
    const double off = n.dot(RB * piece_b.p_M) + piece_b.mesh->face_offset(top);
    for (int k = 0; k < pa.mesh->num_vertices(); ++k) {
      const Vec3 q = sa.x_W + sa.v_W * t + RA * (pa.p_M + pa.R_M * pa.mesh->vertex(k));
      if (n.dot(q) - off <= d_target) reached = t;
    }
  }
  REQUIRE(reached > 0.0);  // it is reached within 1.5 bounds: the bound is near, and not late
  CHECK(bound <= reached);
  const double inf = std::numeric_limits<double>::infinity();
  VertexMotion spinning_a;  // A's angular acceleration unbounded
  spinning_a.alpha_bound = inf;
  CHECK(vertex_bound_above_face(sa, *a.geometry, spinning_a, sb, piece_b, top, mb, d_target) ==
        0.0);
  VertexMotion turning_b;  // B's angular speed unbounded
  turning_b.w_bound = inf;
  CHECK(vertex_bound_above_face(sa, *a.geometry, ma, sb, piece_b, top, turning_b, d_target) == 0.0);
}

TEST_CASE("two cubes or balls flying together: the relative bound never overshoots (600 pairs)",
          "[distance][toi]") {
  // co_flying_time against the exact motion (core/ballistic): random cubes and balls, a few
  // millimetres to a micrometre apart, spinning at up to 20 rad/s and moving nearly as one body
  // (b's velocity close to a's rigid motion, w_b close to w_a) or not at all alike. Over the
  // bound, sampled densely, the gap never closes by more than asked.
  std::mt19937_64 rng(20261201);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const TestShape shapes[] = {cube(), ball()};
  int checked = 0, longer = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const TestShape& s1 = shapes[trial % 2];
    const TestShape& s2 = shapes[(trial / 2) % 2];
    BodyState st1, st2;
    st1.x_W = Vec3::Zero();
    st1.q_WM = Quat(Eigen::AngleAxisd(M_PI * u(rng), random_unit(rng)));
    st2.q_WM = Quat(Eigen::AngleAxisd(M_PI * u(rng), random_unit(rng)));
    // b placed along a random direction, then moved back to a small gap.
    const Vec3 dir = random_unit(rng);
    st2.x_W = 3.0 * dir;
    PairCache cache;
    DistanceResult r =
        closest_features(*s1.geometry, pose_of(st1), *s2.geometry, pose_of(st2), cache, 10000);
    REQUIRE(r.status == ContactStatus::kSeparated);
    const double gap0 = std::pow(10.0, -6.0 + 3.0 * u(rng));
    st2.x_W -= (r.distance - gap0) / std::max(dir.dot(-r.n_W), 1e-3) * dir;
    r = closest_features(*s1.geometry, pose_of(st1), *s2.geometry, pose_of(st2), cache, 10000);
    if (r.status != ContactStatus::kSeparated) continue;
    const bool together = trial % 3 != 0;
    st1.w_W = 20.0 * u(rng) * random_unit(rng);
    st1.v_W = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    const double jitter = together ? 1e-4 : 1.0;
    st2.w_W = st1.w_W + jitter * random_unit(rng);
    st2.v_W = st1.v_W + st1.w_W.cross(st2.x_W - st1.x_W) + jitter * random_unit(rng);
    const Body b1 = make_body(s1, MotionKind::kDynamic, st1);
    const Body b2 = make_body(s2, MotionKind::kDynamic, st2);
    const double closing = 0.5 * r.distance;
    const double dt = co_flying_time(b1, st1, *s1.geometry, b2, st2, *s2.geometry, closing);
    REQUIRE(dt > 0.0);
    const ToiBound own =
        time_of_impact(b1, st1, *s1.geometry, b2, st2, *s2.geometry, r, kGravity, Settings{});
    if (dt > own.dt) ++longer;
    const double horizon = std::min(dt, 1.0);
    for (int k = 1; k <= 64; ++k) {
      const double t = horizon * k / 64;
      const BodyState a1 = advance(b1, st1, t, kGravity);
      const BodyState a2 = advance(b2, st2, t, kGravity);
      const DistanceResult q =
          closest_features(*s1.geometry, pose_of(a1), *s2.geometry, pose_of(a2), cache, 10000);
      CAPTURE(trial, t, dt, r.distance);
      REQUIRE(q.status == ContactStatus::kSeparated);
      CHECK(q.distance >= r.distance - closing - 1e-12);
    }
    ++checked;
  }
  CHECK(checked > 500);
  // Where the pair moves nearly as one body, the relative bound is the longer one.
  CHECK(longer > 200);
}

TEST_CASE("co_flying_time applies only to bodies of the same inertia about every axis",
          "[distance][toi]") {
  const TestShape c = cube(), s = sliver();
  BodyState st1, st2;
  st2.x_W = Vec3(3, 0, 0);
  const Body b1 = make_body(c, MotionKind::kDynamic, st1);
  const Body b2 = make_body(s, MotionKind::kDynamic, st2);
  CHECK(co_flying_time(b1, st1, *c.geometry, b2, st2, *s.geometry, 0.1) == 0.0);
  const Body fixed = make_body(c, MotionKind::kFixed, st2);
  CHECK(co_flying_time(b1, st1, *c.geometry, fixed, st2, *c.geometry, 0.1) == 0.0);
  // Two cubes at rest relative to each other: nothing closes their gap.
  const Body b3 = make_body(c, MotionKind::kDynamic, st2);
  CHECK(co_flying_time(b1, st1, *c.geometry, b3, st2, *c.geometry, 0.1) == kInfinity);
}
