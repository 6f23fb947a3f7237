#include "distance/impact_instant.hpp"

#include "core/ballistic.hpp"
#include "distance/toi_bound.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace palpable {

const char* to_string(InstantStatus status) {
  switch (status) {
    case InstantStatus::kFound: return "found";
    case InstantStatus::kReceding: return "receding";
    case InstantStatus::kStalled: return "stalled";
    case InstantStatus::kNotConverged: return "not_converged";
    case InstantStatus::kNotApplicable: return "not_applicable";
  }
  return "?";
}

namespace {

// A point whose height along n0 follows h + hdot s + c s^2 / 2 as a bound: from below (c the
// least curvature) on body 1's side, from above (c the greatest) on body 2's.
struct Support {
  double h = 0.0;
  double hdot = 0.0;
  double c = 0.0;
};

// How one body moves, as the model needs it.
struct BodyMotion {
  bool fixed = false;
  Vec3 x_W = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();
  Vec3 w_W = Vec3::Zero();
  Mat3 R_WM = Mat3::Identity();
  Vec3 g_W = Vec3::Zero();
  double kappa = 0.0;  // w^2 + |w'| bound: |alpha x r + w x (w x r)| <= |r| kappa
};

BodyMotion body_motion(const Body& body, const BodyState& s, const Vec3& gravity_W,
                       const Settings& settings) {
  BodyMotion m;
  m.fixed = body.motion == MotionKind::kFixed;
  m.x_W = s.x_W;
  m.R_WM = s.q_WM.toRotationMatrix();
  if (m.fixed) return m;
  m.v_W = s.v_W;
  m.w_W = s.w_W;
  m.g_W = gravity_W;
  const double w_bar = angular_speed_bound(body, s, settings);
  const Vec3& I = body.mass.principal_moments;
  const double alpha_bar = w_bar == 0.0 ? 0.0
                           : I.minCoeff() > 0.0
                               ? w_bar * w_bar * (I.maxCoeff() - I.minCoeff()) / I.minCoeff()
                               : kInfinity;
  m.kappa = w_bar * w_bar + alpha_bar;
  return m;
}

// The supports of one piece along n0 (its vertices, a sphere's centre offset by its radius, a
// halfspace's plane), body 1's side (`lower`: bounded from below, its surface toward -n0) or body
// 2's. False if the piece has no bounded model (a halfspace not facing along n0, a smooth
// piece).
bool piece_supports(const ShapeGeometry::Piece& piece, const BodyMotion& m, const Vec3& n0,
                    bool lower, std::vector<Support>& out) {
  out.clear();
  const double side = lower ? -1.0 : 1.0;
  const double g_n = n0.dot(m.g_W);
  auto add = [&](const Vec3& r_W, double offset) {
    Support s;
    s.h = n0.dot(m.x_W + r_W) + side * offset;
    if (!m.fixed) {
      s.hdot = n0.dot(m.v_W + m.w_W.cross(r_W));
      const double spin = r_W.norm() * m.kappa;
      s.c = g_n + side * (std::isfinite(spin) ? spin : kInfinity);
    }
    out.push_back(s);
  };
  switch (piece.kind) {
    case ShapeGeometry::PieceKind::kHalfspace: {
      if (!m.fixed) return false;
      const Vec3 n_W = m.R_WM * piece.normal_M;
      // {x : n . x <= offset}: its greatest height along n0 is finite for n0 = n (body 2's
      // side), its least for n0 = -n (body 1's).
      if (std::abs(n_W.dot(n0) - side) > 1e-12) return false;
      const double offset_W = piece.offset + n_W.dot(m.x_W);
      Support s;
      s.h = side * offset_W;
      out.push_back(s);
      return true;
    }
    case ShapeGeometry::PieceKind::kSphere: add(m.R_WM * piece.p_M, piece.radius); return true;
    case ShapeGeometry::PieceKind::kPolyhedron: {
      const FeatureMesh& mesh = *piece.mesh;
      const Mat3 R = m.R_WM * piece.R_M;
      const Vec3 p = m.R_WM * piece.p_M;
      for (int k = 0; k < mesh.num_vertices(); ++k) add(p + R * mesh.vertex(k), 0.0);
      return true;
    }
    case ShapeGeometry::PieceKind::kSmooth:
      return false;  // no finite support set (ellipsoid, cylinder, capsule): not refined yet
  }
  return false;
}

// The earliest time the slab model of one piece pair can close (see the header).
double piece_pair_step(const std::vector<Support>& lower, const std::vector<Support>& upper,
                       double target_m, std::vector<Support>& sorted1,
                       std::vector<Support>& sorted2) {
  sorted1 = lower;
  sorted2 = upper;
  std::sort(sorted1.begin(), sorted1.end(),
            [](const Support& a, const Support& b) { return a.h < b.h; });
  std::sort(sorted2.begin(), sorted2.end(),
            [](const Support& a, const Support& b) { return a.h > b.h; });
  // Every pair closes no faster than at B, with no more curvature than A: a pair further apart
  // than the distance those close by the best time so far cannot come first.
  double B = -kInfinity, A = -kInfinity, B2 = -kInfinity, A2 = -kInfinity;
  for (const Support& s : sorted1) {
    B = std::max(B, -s.hdot);
    A = std::max(A, -s.c);
  }
  for (const Support& s : sorted2) {
    B2 = std::max(B2, s.hdot);
    A2 = std::max(A2, s.c);
  }
  const double B_plus = std::max(B + B2, 0.0);
  const double A_plus = std::max(A + A2, 0.0);
  double best = kInfinity;
  double limit = kInfinity;
  for (const Support& v : sorted1) {
    if (v.h - sorted2.front().h - target_m > limit) break;
    for (const Support& w : sorted2) {
      const double delta = v.h - w.h - target_m;
      if (delta > limit) break;
      const double a = w.c - v.c;        // closing acceleration
      const double b = w.hdot - v.hdot;  // closing speed
      const double dt = std::isnan(a) ? 0.0 : solve_gap_closing(a, b, delta);
      if (dt < best) {
        best = dt;
        if (!(best > 0.0)) return 0.0;
        limit = B_plus * best + 0.5 * A_plus * best * best;
      }
    }
  }
  return best;
}

}  // namespace

double certified_step(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                      const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                      const DistanceResult& closest, const PairCache& cache, const Vec3& gravity_W,
                      const Settings& settings, double target_m) {
  if (body1.motion == MotionKind::kKinematic || body2.motion == MotionKind::kKinematic) return 0.0;
  const BodyMotion m1 = body_motion(body1, state1, gravity_W, settings);
  const BodyMotion m2 = body_motion(body2, state2, gravity_W, settings);
  std::vector<Support> lower, upper, sorted1, sorted2;
  auto step_of = [&](const DistanceResult& r) {
    if (r.status != ContactStatus::kSeparated && r.status != ContactStatus::kTouching) return 0.0;
    const auto& p1 = geometry1.pieces()[static_cast<std::size_t>(r.piece1)];
    const auto& p2 = geometry2.pieces()[static_cast<std::size_t>(r.piece2)];
    if (!piece_supports(p1, m1, r.n_W, /*lower=*/true, lower) ||
        !piece_supports(p2, m2, r.n_W, /*lower=*/false, upper)) {
      return 0.0;
    }
    return piece_pair_step(lower, upper, target_m, sorted1, sorted2);
  };
  if (cache.piece_results().empty()) return step_of(closest);
  double best = kInfinity;
  for (const DistanceResult& r : cache.piece_results()) {
    best = std::min(best, step_of(r));
    if (!(best > 0.0)) return 0.0;
  }
  return best;
}

ImpactInstant impact_instant(const Body& body1, const BodyState& state1,
                             const ShapeGeometry& geometry1, const Body& body2,
                             const BodyState& state2, const ShapeGeometry& geometry2,
                             const DistanceResult& closest, const PairCache& cache,
                             const Vec3& gravity_W, const Settings& settings, double touching_gap_m,
                             int max_iterations) {
  ImpactInstant out;
  auto apart = [](const DistanceResult& r) {
    return r.status == ContactStatus::kSeparated || r.status == ContactStatus::kTouching;
  };
  if (body1.motion == MotionKind::kKinematic || body2.motion == MotionKind::kKinematic ||
      !apart(closest)) {
    return out;
  }
  PairCache local;
  local.single = cache.single;
  if (cache.compound) local.compound = std::make_unique<PairCache::Compound>(*cache.compound);
  const double t0 = std::max(state1.t, state2.t);
  BodyState s1 = state1, s2 = state2;
  DistanceResult dr = closest;
  out.gap_m = dr.distance;
  while (true) {
    if (dr.distance <= touching_gap_m) {
      out.status = InstantStatus::kFound;
      return out;
    }
    if (dr.distance > settings.envelope_m) {
      out.status = InstantStatus::kReceding;
      return out;
    }
    if (out.iterations >= max_iterations) {
      out.status = InstantStatus::kNotConverged;
      return out;
    }
    // Aimed at half the touching gap: an exact model (a body that does not turn) then lands
    // inside the touching gap, not at zero, where rounding may overlap the features.
    const double step = certified_step(body1, s1, geometry1, body2, s2, geometry2, dr, local,
                                       gravity_W, settings, 0.5 * touching_gap_m);
    if (step == kInfinity) {
      out.status = InstantStatus::kReceding;
      out.dt = kInfinity;
      return out;
    }
    const double dt = out.dt + step;
    // The bodies' clocks are all at t0: every iterate is advanced from the given states in one
    // call (as the scheduler will commit them), never chained.
    if (!(step > 0.0) || !(t0 + dt > t0 + out.dt)) {
      out.status = InstantStatus::kStalled;
      return out;
    }
    const BodyState n1 = advance(body1, state1, t0 + dt, gravity_W, settings);
    const BodyState n2 = advance(body2, state2, t0 + dt, gravity_W, settings);
    const DistanceResult next =
        closest_features(geometry1, Pose{n1.x_W, n1.q_WM}, geometry2, Pose{n2.x_W, n2.q_WM}, local,
                         settings.distance_max_steps);
    ++out.iterations;
    if (!apart(next)) {
      // Overlap at a certified instant: rounding at a gap of a few ulps. The last instant stands.
      out.status = InstantStatus::kStalled;
      return out;
    }
    s1 = n1;
    s2 = n2;
    dr = next;
    out.dt = dt;
    out.gap_m = dr.distance;
  }
}

}  // namespace palpable
