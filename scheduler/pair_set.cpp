#include "scheduler/pair_set.hpp"

#include "core/check.hpp"
#include "scheduler/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace palpable {

namespace {

// The box swept by a point moving as x0 + v s + g s^2 / 2 for s in [0, dt], per axis.
Aabb parabola_box(const Vec3& x0, const Vec3& v, const Vec3& g, double dt) {
  Aabb box;
  box.min_W = x0;
  box.max_W = x0;
  auto include = [&](double s) {
    Vec3 x = x0 + v * s + 0.5 * g * s * s;
    box.min_W = box.min_W.cwiseMin(x);
    box.max_W = box.max_W.cwiseMax(x);
  };
  include(dt);
  for (int i = 0; i < 3; ++i) {
    if (g[i] != 0.0) {
      double s = -v[i] / g[i];
      if (s > 0.0 && s < dt) include(s);
    }
  }
  return box;
}

Aabb grown(Aabb box, double margin) {
  box.min_W.array() -= margin;
  box.max_W.array() += margin;
  return box;
}

}  // namespace

static_assert(sizeof(PairSet::Pair) <= 64, "a pair record fits one cache line");

PairSet::PairSet(const World& world, EventQueue& queue, SimulationStats& stats)
    : world_(world), queue_(queue), stats_(stats) {
  std::map<const Shape*, std::shared_ptr<const ShapeGeometry>> geometries;
  bodies_.resize(world.bodies.size());
  for (std::size_t i = 0; i < world.bodies.size(); ++i) {
    const Body& b = world.bodies[i];
    if (!b.shape) throw InputError("/bodies/" + std::to_string(i) + "/shape", "body has no shape");
    auto& g = geometries[b.shape.get()];
    if (!g) g = std::make_shared<const ShapeGeometry>(b.shape);
    bodies_[i].geometry = g;
  }
}

bool PairSet::compute_box(BodyId id, const BodyState& s, double t, bool limit_sweep,
                          const HeldMotion* held) {
  BodyRuntime& rt = bodies_[id.index];
  const Body& b = world_.bodies[id.index];
  const Settings& settings = world_.settings;
  const double margin = settings.envelope_m;
  const double reach = rt.geometry->reach();
  if (b.motion == MotionKind::kFixed) {
    rt.box = grown(bounding_box_W(*b.shape, s.x_W, s.q_WM), margin);
    rt.horizon = kInfinity;
    return false;
  }
  if (b.motion == MotionKind::kKinematic) {
    const KinematicMotion& k = b.kinematic;
    const bool translating = k.velocity_W.squaredNorm() > 0.0;
    const bool spinning = k.angular_velocity_W.squaredNorm() > 0.0;
    if (!std::isfinite(reach)) {
      // A halfspace: a static set unless it translates or spins about a non-normal axis.
      const Halfspace& h = std::get<Halfspace>(*b.shape);
      const Vec3 n_W = s.q_WM * h.normal_M;
      const bool maps_onto_itself =
          !translating && (!spinning || n_W.cross(k.angular_velocity_W).norm() <=
                                            1e-12 * k.angular_velocity_W.norm());
      rt.box = maps_onto_itself ? grown(bounding_box_W(*b.shape, s.x_W, s.q_WM), margin)
                                : Aabb{Vec3::Constant(-kInfinity), Vec3::Constant(kInfinity)};
      rt.horizon = kInfinity;
      return false;
    }
    // Every material point stays within |x - c| + reach of the axis point c(t).
    const Vec3 c = k.point_W + k.velocity_W * t;
    const double radius = (s.x_W - c).norm() + reach;
    const double horizon = translating ? settings.broad_phase_horizon_s : kInfinity;
    const double dt = translating ? horizon : 0.0;
    rt.box = grown(parabola_box(c, k.velocity_W, Vec3::Zero(), dt), radius + margin);
    rt.horizon = t + horizon;
    return false;
  }
  const Vec3& g = held ? held->a_W : world_.gravity_W;
  const double slack = held ? held->a_slack : 0.0;
  if (s.v_W.squaredNorm() == 0.0 && g.squaredNorm() == 0.0 && slack == 0.0) {
    rt.box = grown(parabola_box(s.x_W, s.v_W, g, 0.0), reach + margin);
    rt.horizon = kInfinity;
    return false;
  }
  double dt = settings.broad_phase_horizon_s;
  const double travel = s.v_W.norm() * dt;
  const double max_travel = settings.broad_phase_max_sweep * reach;
  const bool cut = limit_sweep && travel > max_travel;
  if (cut) dt *= max_travel / travel;
  rt.box = grown(parabola_box(s.x_W, s.v_W, g, dt), reach + margin + 0.5 * slack * dt * dt);
  rt.horizon = t + dt;
  return cut;
}

bool PairSet::refresh_box(BodyId id, const BodyState& s, double t, bool limit_sweep,
                          const HeldMotion* held) {
  const bool cut = compute_box(id, s, t, limit_sweep, held);
  (world_.bodies[id.index].is_dynamic() ? dynamic_boxes_ : static_boxes_)
      .set(id.index, bodies_[id.index].box);
  return cut;
}

void PairSet::set_box(BodyId id, const BodyState& s, double t) {
  refresh_box(id, s, t, /*limit_sweep=*/false);
}

void PairSet::schedule_horizon(BodyId id) {
  BodyRuntime& rt = bodies_[id.index];
  if (std::isfinite(rt.horizon)) {
    Event e;
    e.t = rt.horizon;
    e.kind = EventKind::kHorizon;
    e.a = id;
    if (rt.horizon_event == EventQueue::kNoEvent) {
      rt.horizon_event = queue_.push(e);
    } else {
      queue_.update(rt.horizon_event, e);
    }
  } else if (rt.horizon_event != EventQueue::kNoEvent) {
    queue_.erase(rt.horizon_event);
    rt.horizon_event = EventQueue::kNoEvent;
  }
}

std::uint32_t PairSet::create_pair(BodyId a, BodyId b) {
  std::uint32_t index;
  if (!free_pairs_.empty()) {
    index = free_pairs_.back();
    free_pairs_.pop_back();
  } else {
    index = static_cast<std::uint32_t>(pairs_.size());
    pairs_.emplace_back();
  }
  PALPABLE_CHECK(world_.bodies[a.index].is_dynamic() || world_.bodies[b.index].is_dynamic(),
                 "a pair of two fixed or kinematic bodies");
  Pair& p = pairs_[index];
  p = Pair{};
  p.a = a;
  p.b = b;
  p.live = true;
  bodies_[a.index].pairs.push_back(index);
  bodies_[b.index].pairs.push_back(index);
  ++live_pairs_;
  ++stats_.pairs_created;
  stats_.max_pairs = std::max<std::uint64_t>(stats_.max_pairs, live_pairs_);
  return index;
}

void PairSet::remove_pair(std::uint32_t index) {
  Pair& p = pairs_[index];
  if (p.event != EventQueue::kNoEvent) queue_.erase(p.event);
  for (BodyId id : {p.a, p.b}) {
    auto& list = bodies_[id.index].pairs;
    list.erase(std::find(list.begin(), list.end(), index));
  }
  --live_pairs_;
  p.live = false;
  free_pairs_.push_back(index);
}

std::size_t PairSet::find_overlaps(BodyId id, std::vector<std::uint32_t>& out) {
  out.clear();
  const Aabb& box = bodies_[id.index].box;
  dynamic_boxes_.query(box, id.index, out);
  const std::size_t dynamic_count = out.size();
  if (world_.bodies[id.index].is_dynamic()) {
    static_boxes_.query(box, id.index, out);
    // Two ascending runs: sorted in place (inplace_merge allocates a buffer on every call).
    if (dynamic_count > 0 && dynamic_count < out.size()) std::sort(out.begin(), out.end());
  }
  stats_.box_tests = dynamic_boxes_.box_tests() + static_boxes_.box_tests();
  return dynamic_count;
}

void PairSet::refresh(BodyId id, const BodyState& s, double t, const HeldMotion* held) {
  bool found = false;  // `overlapping_` holds the overlaps of the box stored
  if (refresh_box(id, s, t, /*limit_sweep=*/true, held)) {
    found = find_overlaps(id, overlapping_) > 0;
    if (!found) refresh_box(id, s, t, /*limit_sweep=*/false, held);
  }
  schedule_horizon(id);
  if (!found) find_overlaps(id, overlapping_);
  partners_.clear();
  for (std::uint32_t index : bodies_[id.index].pairs) {
    const Pair& p = pairs_[index];
    partners_.emplace_back(p.a == id ? p.b.index : p.a.index, index);
  }
  std::sort(partners_.begin(), partners_.end());
  auto o = overlapping_.begin();
  auto q = partners_.begin();
  while (o != overlapping_.end() || q != partners_.end()) {
    const std::uint32_t j =
        q == partners_.end() || (o != overlapping_.end() && *o < q->first) ? *o : q->first;
    const bool overlap = o != overlapping_.end() && *o == j;
    const bool paired = q != partners_.end() && q->first == j;
    const std::uint32_t pair = paired ? q->second : 0;
    if (overlap) ++o;
    if (paired) ++q;
    if (overlap == paired) continue;
    if (overlap) {
      create_pair(BodyId{std::min(id.index, j)}, BodyId{std::max(id.index, j)});
    } else {
      remove_pair(pair);
    }
  }
}

const std::vector<std::uint32_t>& PairSet::collect_rebounds(const std::vector<BodyId>& moved) {
  rebounds_.clear();
  ++rebound_round_;
  for (BodyId id : moved) {
    if (!world_.bodies[id.index].is_dynamic()) continue;
    for (std::uint32_t index : bodies_[id.index].pairs) {
      Pair& p = pairs_[index];
      if (p.rebound_round == rebound_round_) continue;  // a pair of two moved bodies: once
      p.rebound_round = rebound_round_;
      rebounds_.push_back(index);
    }
  }
  // The other bodies of these pairs lie anywhere in memory: ask for all of them before using
  // any, so that their cache misses overlap instead of following one another (see the
  // README's gas benchmark: at 10,000 spheres the bodies no longer fit the cache).
  for (std::uint32_t index : rebounds_) {
    const Pair& p = pairs_[index];
    for (BodyId id : {p.a, p.b}) {
      const char* first = reinterpret_cast<const char*>(&world_.bodies[id.index]);
      __builtin_prefetch(first);
      __builtin_prefetch(first + 64);
      __builtin_prefetch(first + 128);
      __builtin_prefetch(&bodies_[id.index]);
    }
  }
  return rebounds_;
}

}  // namespace palpable
