#include "scenarios/reference.hpp"

#include "core/check.hpp"
#include "scenarios/json_reader.hpp"
#include "distance/closest_features.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace palpable {
namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;
// A body that moved farther than this off the plane it started on has left its support [m]
// (a microcollision train at envelope 1e-2 hops about 1.5 cm)
// (microcollisions hop a few envelopes; a block sliding off its ramp falls meters).
constexpr double kOffSupport = 2e-2;

// The parameters of each reference type: kind ('n' number, 'd' direction, 'v' vector, 's' body
// name, 'i' whole number) and whether required. Keys outside these are rejected.
struct Parameter {
  char kind;
  bool required;
};
const std::map<std::string, std::map<std::string, Parameter>>& reference_parameters() {
  static const std::map<std::string, std::map<std::string, Parameter>> table = {
      {"incline",
       {{"body", {'s', true}},
        {"support", {'s', false}},
        {"angle_deg", {'n', true}},
        {"friction", {'n', true}},
        {"gravity", {'n', true}},
        {"initial_speed", {'n', false}},
        {"down_slope", {'d', true}},
        {"normal", {'d', true}}}},
      {"turntable",
       {{"body", {'s', true}},
        {"support", {'s', false}},
        {"omega", {'n', true}},
        {"axis", {'d', false}},
        {"k", {'n', false}},
        {"position", {'v', false}},
        {"velocity", {'v', false}}}},
      {"slide_to_roll",
       {{"body", {'s', true}},
        {"support", {'s', false}},
        {"friction", {'n', true}},
        {"gravity", {'n', true}},
        {"radius", {'n', true}},
        {"k", {'n', false}},
        {"normal", {'d', false}},
        {"velocity", {'v', false}},
        {"angular_velocity", {'v', false}}}},
      {"bouncing_ball",
       {{"body", {'s', true}},
        {"restitution", {'n', true}},
        {"gravity", {'n', true}},
        {"radius", {'n', false}},
        {"ground", {'n', false}},
        {"normal", {'d', false}},
        {"apexes", {'i', false}}}},
      {"impact_1d",
       {{"body_a", {'s', true}},
        {"body_b", {'s', true}},
        {"restitution", {'n', true}},
        {"mass_a", {'n', true}},
        {"mass_b", {'n', true}},
        {"axis", {'d', false}}}},
  };
  return table;
}

// Reads one parameter of a spec through the project's JSON reader (errors name where + key).
double spec_number(const json& spec, const std::string& where, const std::string& key) {
  const JsonReader r(where, "");
  return r.number(r.required(spec, "", key), "/" + key);
}

// A direction, normalised.
Vec3 spec_vec3(const json& spec, const std::string& where, const std::string& key) {
  const JsonReader r(where, "");
  return r.direction(r.required(spec, "", key), "/" + key);
}

// A vector parameter, any length (a velocity).
Vec3 spec_vector(const json& spec, const std::string& where, const std::string& key) {
  const JsonReader r(where, "");
  return r.vec3(r.required(spec, "", key), "/" + key);
}

std::string spec_string(const json& spec, const std::string& where, const std::string& key) {
  const JsonReader r(where, "");
  return r.string(r.required(spec, "", key), "/" + key);
}

json compare_incline(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t body = trace.body_index(spec_string(spec, where, "body"), where + "/body");
  const InclineMotion motion = incline_motion(spec, where);
  const double v0 = motion.initial_speed;
  const Vec3 down = motion.down_slope;
  const Vec3 normal = spec_vec3(spec, where, "normal");
  const Vec3 across = normal.cross(down).normalized();

  std::vector<BodyState> states = trace.series(body);
  const Vec3 x0 = states.front().x_W;
  const double t0 = trace.times.front();
  std::vector<double> t, s, c;
  for (std::size_t k = 0; k < states.size(); ++k) {
    t.push_back(trace.times[k] - t0);
    s.push_back((states[k].x_W - x0).dot(down));
    c.push_back((states[k].x_W - x0).dot(across));
  }
  double cross_max = 0.0;
  for (double x : c) cross_max = std::max(cross_max, std::abs(x));
  double off_plane = 0.0;  // how far the block moved off its starting plane
  for (const BodyState& st : states) off_plane = std::max(off_plane, std::abs((st.x_W - x0).dot(normal)));

  const double a = motion.sliding_acceleration;
  json figures;
  figures["off_plane_max_m"] = off_plane;
  if (off_plane > kOffSupport) {
    figures["premise_failed"] = "the body left its support (moved " + std::to_string(off_plane) +
                                " m off its plane): the incline's closed form does not apply";
  }
  figures["acceleration_closed_form"] = a;
  figures["cross_slope_max_m"] = cross_max;

  if (v0 > 0.0 && a < 0.0) {
    // Decelerating: stops at t* and stays.
    const double t_stop = v0 / (-a);
    const double s_stop = v0 * v0 / (2.0 * -a);
    figures["mode"] = "slide_then_stop";
    if (t_stop >= t.back() && !figures.contains("premise_failed")) {
      figures["premise_failed"] = "the closed form stops at t* = " + std::to_string(t_stop) +
                                  " s, after the trace's last sample at " +
                                  std::to_string(t.back()) + " s";
    }
    figures["stop_time_closed_form_s"] = t_stop;
    figures["stop_distance_closed_form_m"] = s_stop;
    std::vector<double> tf, sf;
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k] <= 0.9 * t_stop) {
        tf.push_back(t[k]);
        sf.push_back(s[k]);
      }
    }
    if (tf.size() >= 5) {
      auto coef = polynomial_fit(tf, sf, 2);
      double t_fit = -coef[1] / (2.0 * coef[2]);
      figures["stop_time_fit_s"] = t_fit;
      figures["stop_time_error_s"] = t_fit - t_stop;
      figures["acceleration_fit"] = 2.0 * coef[2];
      figures["acceleration_rel_error"] = (2.0 * coef[2] - a) / std::abs(a);
    }
    // Creep: the displacement of the mean motion over [t* + 0.1 s, end], from a least-squares
    // line through the positions (a resting block's position jitters within each microcollision
    // flight by about a_t tau^2 / 8, which is not creep; it is reported separately).
    const double t_settled = t_stop + 0.1;
    std::vector<double> tw, sw;
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k] >= t_settled) {
        tw.push_back(t[k]);
        sw.push_back(s[k]);
      }
    }
    if (tw.size() >= 3) {
      auto line = polynomial_fit(tw, sw, 1);
      double jitter = 0.0, mean = 0.0;
      for (std::size_t k = 0; k < tw.size(); ++k) {
        jitter = std::max(jitter, std::abs(sw[k] - (line[0] + line[1] * tw[k])));
        mean += sw[k];
      }
      mean /= static_cast<double>(sw.size());
      figures["creep_window_s"] = {tw.front() + t0, tw.back() + t0};
      figures["creep_fit_m"] = std::abs(line[1]) * (tw.back() - tw.front());
      // The samples alias the microcollision flights (a beat of the sampling and bounce
      // periods), so the fitted line carries up to the jitter's amplitude. The contact points,
      // when the collisions are known, measure the creep itself: every one is taken at touch.
      double lo = kInfinity, hi = -kInfinity;
      std::size_t touches = 0;
      for (const ContactEvent& c : trace.contacts) {
        if (c.t - t0 < t_settled || (c.body_a != body && c.body_b != body)) continue;
        const double along = (c.p_W - x0).dot(down);
        lo = std::min(lo, along);
        hi = std::max(hi, along);
        ++touches;
      }
      if (touches >= 2) {
        figures["creep_m"] = hi - lo;
        figures["creep_method"] = "contact points of " + std::to_string(touches) + " collisions";
      } else {
        figures["creep_m"] = figures["creep_fit_m"];
        figures["creep_method"] = "least-squares line through the sampled positions";
      }
      figures["rest_jitter_m"] = jitter;
      figures["rest_distance_error_m"] = mean - s_stop;
    }
  } else if (a > 0.0) {
    // Sliding down with constant acceleration from the start.
    figures["mode"] = "accelerating";
    auto coef = polynomial_fit(t, s, 2);
    figures["acceleration_fit"] = 2.0 * coef[2];
    figures["acceleration_rel_error"] = (2.0 * coef[2] - a) / a;
    figures["initial_speed_fit"] = coef[1];
  } else {
    // Sticks (tan(theta) <= mu) and starts at rest: nothing may move.
    figures["mode"] = "stick";
    double creep = 0.0;
    for (double x : s) creep = std::max(creep, std::abs(x));
    figures["creep_m"] = creep;
  }
  return figures;
}

json compare_turntable(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t body = trace.body_index(spec_string(spec, where, "body"), where + "/body");
  std::vector<BodyState> states = trace.series(body);
  // The launch state: the scene's (given or derived), else the first sample's — which, for a
  // ball starting on the platter, already holds the impulses of any collision at t = 0.
  const Vec3 x0 = spec.contains("position") ? spec_vector(spec, where, "position")
                                            : states.front().x_W;
  const Vec3 v_start =
      spec.contains("velocity") ? spec_vector(spec, where, "velocity") : states.front().v_W;
  const TurntableCircle circle = turntable_circle(spec, where, x0, v_start);
  const Vec3 axis = circle.axis;
  const double rate = circle.rate;  // dv/dt = rate * axis x v
  const Vec3 centre = circle.centre;
  const double radius = circle.radius;
  const double t0 = trace.times.front();

  double circle_dev = 0.0, path_dev = 0.0;
  std::vector<double> t, angle;
  const Vec3 e1 = (x0 - centre).normalized();
  const Vec3 e2 = axis.cross(e1);
  double previous = 0.0, unwrapped = 0.0;
  for (std::size_t i = 0; i < states.size(); ++i) {
    Vec3 r = states[i].x_W - centre;
    r -= axis * axis.dot(r);
    circle_dev = std::max(circle_dev, std::abs(r.norm() - radius));
    double dt = trace.times[i] - t0;
    Vec3 expected = centre + Eigen::AngleAxisd(rate * dt, axis) * (x0 - centre);
    Vec3 d = states[i].x_W - expected;
    d -= axis * axis.dot(d);
    path_dev = std::max(path_dev, d.norm());
    double a = std::atan2(r.dot(e2), r.dot(e1));
    if (i == 0) {
      unwrapped = a;
    } else {
      double step = std::remainder(a - previous, 2.0 * kPi);
      unwrapped += step;
    }
    previous = a;
    t.push_back(dt);
    angle.push_back(unwrapped);
  }
  auto coef = polynomial_fit(t, angle, 1);
  // Centre drift: the centre of a circle fitted (Kasa) to the last tenth of the path.
  std::size_t first = states.size() - std::max<std::size_t>(states.size() / 10, 3);
  Eigen::MatrixXd A(states.size() - first, 3);
  Eigen::VectorXd b(states.size() - first);
  for (std::size_t i = first; i < states.size(); ++i) {
    Vec3 r = states[i].x_W - centre;
    double u = r.dot(e1), w = r.dot(e2);
    A.row(i - first) << u, w, 1.0;
    b(i - first) = u * u + w * w;
  }
  Eigen::Vector3d sol = A.colPivHouseholderQr().solve(b);
  double drift = std::hypot(sol(0) / 2.0, sol(1) / 2.0);

  json figures;
  figures["rate_closed_form"] = rate;
  figures["rate_fit"] = coef[1];
  figures["rate_rel_error"] = (coef[1] - rate) / rate;
  figures["radius_closed_form_m"] = radius;
  figures["circle_deviation_max_m"] = circle_dev;
  figures["path_deviation_max_m"] = path_dev;
  figures["centre_drift_m"] = drift;
  return figures;
}

// Sphere sliding on a plane (DESIGN.md §6): friction -mu m g u_hat acts at the contact point
// -R n while the slip u = v + w x (-R n) is non-zero; the slip decreases at (1 + 1/k) mu g in a
// fixed direction, so the sphere rolls from t_roll = k s0 / ((1 + k) mu g) at
// v_final = v0 - k/(1+k) u0 (= (v0 + k R w0 x n)/(1+k); 5 v0/7 for a solid sphere without spin).
json compare_slide_to_roll(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t body = trace.body_index(spec_string(spec, where, "body"), where + "/body");
  const double mu = spec_number(spec, where, "friction");
  const double g = spec_number(spec, where, "gravity");
  const double radius = spec_number(spec, where, "radius");
  const double k = spec.contains("k") ? spec_number(spec, where, "k") : 0.4;
  const Vec3 n = spec.contains("normal") ? spec_vec3(spec, where, "normal") : Vec3::UnitZ();
  if (!(mu > 0.0)) throw InputError(where + "/friction", "expected friction > 0");
  if (!(g > 0.0)) throw InputError(where + "/gravity", "expected gravity > 0 (its magnitude)");
  if (!(radius > 0.0)) throw InputError(where + "/radius", "expected radius > 0");
  if (!(k > 0.0)) throw InputError(where + "/k", "expected k > 0 (I = k m R^2)");

  std::vector<BodyState> states = trace.series(body);
  const double t0 = trace.times.front();
  const Vec3 x0 = states.front().x_W;
  // The launch state: the first sample unless given (a body starting in contact has its first
  // collisions at t = 0 before that sample, which then already carries their impulses).
  const Vec3 v_start =
      spec.contains("velocity") ? spec_vector(spec, where, "velocity") : states.front().v_W;
  const Vec3 w_start = spec.contains("angular_velocity")
                           ? spec_vector(spec, where, "angular_velocity")
                           : states.front().w_W;
  const Vec3 v0 = v_start - n * n.dot(v_start);
  Vec3 u0 = v0 + w_start.cross(-radius * n);
  u0 -= n * n.dot(u0);
  const double s0 = u0.norm();
  const double t_roll = k * s0 / ((1.0 + k) * mu * g);
  const Vec3 v_final = v0 - k / (1.0 + k) * u0;

  json figures;
  figures["initial_slip_speed"] = s0;
  figures["roll_time_closed_form_s"] = t_roll;
  figures["final_speed_closed_form"] = v_final.norm();
  figures["deceleration_closed_form"] = mu * g;
  double height_dev = 0.0;
  for (const BodyState& s : states) height_dev = std::max(height_dev, std::abs(n.dot(s.x_W - x0)));
  figures["height_deviation_max_m"] = height_dev;

  // Along the slip direction (constant while sliding) the centre's position is a parabola with
  // second derivative -mu g until t_roll and a line after it: fit both, meet them.
  Vec3 along = Vec3::Zero();
  if (s0 > 0.0) along = u0 / s0;
  std::vector<double> ts, ss, tr, sr;
  std::vector<Vec3> xr;
  for (std::size_t i = 0; i < states.size(); ++i) {
    const double t = trace.times[i] - t0;
    const double s = (states[i].x_W - x0).dot(along);
    if (t <= 0.9 * t_roll) {
      ts.push_back(t);
      ss.push_back(s);
    } else if (t >= 1.1 * t_roll) {
      tr.push_back(t);
      sr.push_back(s);
      xr.push_back(states[i].x_W - x0);
    }
  }
  if (tr.size() >= 3) {
    // Final velocity: a least-squares line through each tangential position component.
    Vec3 v_fit = Vec3::Zero();
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> comp;
      for (const Vec3& x : xr) comp.push_back(x[axis]);
      v_fit[axis] = polynomial_fit(tr, comp, 1)[1];
    }
    v_fit -= n * n.dot(v_fit);
    figures["final_speed_fit"] = v_fit.norm();
    if (v_final.norm() > 0.0) {
      figures["final_speed_rel_error"] = (v_fit.norm() - v_final.norm()) / v_final.norm();
    }
    figures["final_velocity_error"] = (v_fit - v_final).norm();
  }
  if (s0 > 0.0 && ts.size() >= 5) {
    auto slide = polynomial_fit(ts, ss, 2);
    const double deceleration = -2.0 * slide[2];
    figures["deceleration_fit"] = deceleration;
    figures["deceleration_rel_error"] = (deceleration - mu * g) / (mu * g);
    if (tr.size() >= 3 && deceleration > 0.0) {
      const double v_roll = polynomial_fit(tr, sr, 1)[1];
      const double t_fit = (slide[1] - v_roll) / deceleration;
      figures["roll_time_fit_s"] = t_fit;
      figures["roll_time_error_s"] = t_fit - t_roll;
    }
  }
  figures["mode"] = s0 > 0.0 ? "slide_then_roll" : "rolling";
  return figures;
}

// Parabola vertex through three equally spaced samples (y_m, y_0, y_p) at spacing h around t_0:
// exact for a ballistic flight covering all three.
std::pair<double, double> parabola_vertex(double t0, double h, double ym, double y0, double yp) {
  const double curvature = ym - 2.0 * y0 + yp;
  if (curvature >= 0.0) return {t0, y0};
  const double dt = 0.5 * h * (ym - yp) / curvature;
  const double a = curvature / (2.0 * h * h), b = (yp - ym) / (2.0 * h);
  return {t0 + dt, y0 + b * dt + a * dt * dt};
}

// Bouncing ball (DESIGN.md §6): dropped from height h0 (above the ground plane n.x = ground, of
// the sphere's lowest point) with normal speed w0, it hits at t1 = (w0 + v1)/g with
// v1 = sqrt(w0^2 + 2 g h0); then apex n at t_n + e^n v1/g, height e^(2n) v1^2/(2g); impacts
// t_(n+1) = t_n + 2 e^n v1/g; rest (Zeno) at t1 + 2 e v1/(g (1 - e)) (= sqrt(2h0/g)(1+e)/(1-e)
// from rest).
json compare_bouncing_ball(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t body = trace.body_index(spec_string(spec, where, "body"), where + "/body");
  const double e = spec_number(spec, where, "restitution");
  const double g = spec_number(spec, where, "gravity");
  const double radius = spec.contains("radius") ? spec_number(spec, where, "radius") : 0.0;
  const double ground = spec.contains("ground") ? spec_number(spec, where, "ground") : 0.0;
  const Vec3 n = spec.contains("normal") ? spec_vec3(spec, where, "normal") : Vec3::UnitZ();
  int count = 3;
  if (spec.contains("apexes")) {
    const json& a = spec["apexes"];
    if (!a.is_number_integer() || a.get<int>() < 1) {
      throw InputError(where + "/apexes", "got " + a.dump() + ", expected an integer >= 1");
    }
    count = a.get<int>();
  }
  if (!(e >= 0.0 && e < 1.0)) throw InputError(where + "/restitution", "expected 0 <= e < 1");
  if (!(g > 0.0)) throw InputError(where + "/gravity", "expected gravity > 0 (its magnitude)");
  if (!(radius >= 0.0)) throw InputError(where + "/radius", "expected radius >= 0");

  std::vector<BodyState> states = trace.series(body);
  const double t0 = trace.times.front();
  std::vector<double> h;
  for (const BodyState& s : states) h.push_back(n.dot(s.x_W) - ground - radius);
  const double h0 = h.front();
  if (!(h0 > 0.0)) throw InputError(where + "/body", "the ball starts on or below the ground");
  const double w0 = n.dot(states.front().v_W);
  const double v1 = std::sqrt(w0 * w0 + 2.0 * g * h0);
  const double t1 = (w0 + v1) / g;

  std::vector<double> impact(count + 1), apex_t(count), apex_h(count);
  impact[0] = t1;
  double en = 1.0;
  for (int i = 0; i < count; ++i) {
    en *= e;
    apex_t[i] = impact[i] + en * v1 / g;
    apex_h[i] = en * en * v1 * v1 / (2.0 * g);
    impact[i + 1] = impact[i] + 2.0 * en * v1 / g;
  }
  json figures;
  figures["first_impact_closed_form_s"] = t1;
  figures["rest_time_closed_form_s"] = t1 + 2.0 * e * v1 / (g * (1.0 - e));
  figures["apex_height_closed_form_m"] = apex_h;

  // Apexes in the trace: samples higher than both neighbours, refined by the parabola through
  // the three. The first sample is not an apex (the drop).
  std::vector<double> found_t, found_h;
  for (std::size_t i = 1; i + 1 < h.size() && static_cast<int>(found_t.size()) < count; ++i) {
    if (h[i] > h[i - 1] && h[i] >= h[i + 1]) {
      const double dt = trace.times[i] - trace.times[i - 1];
      auto [t, y] = parabola_vertex(trace.times[i] - t0, dt, h[i - 1], h[i], h[i + 1]);
      found_t.push_back(t);
      found_h.push_back(y);
    }
  }
  std::vector<double> rel_error, t_error;
  double worst = 0.0, worst_t = 0.0;
  for (std::size_t i = 0; i < found_t.size(); ++i) {
    rel_error.push_back((found_h[i] - apex_h[i]) / apex_h[i]);
    t_error.push_back(found_t[i] - apex_t[i]);
    worst = std::max(worst, std::abs(rel_error.back()));
    worst_t = std::max(worst_t, std::abs(t_error.back()));
  }
  figures["apexes_found"] = found_t.size();
  figures["apex_height_fit_m"] = found_h;
  figures["apex_height_rel_error"] = rel_error;
  figures["apex_height_rel_error_max"] = worst;
  figures["apex_time_error_max_s"] = worst_t;
  if (static_cast<int>(found_t.size()) < count) {
    figures["note"] =
        "fewer apexes in the trace than asked for (sampling too coarse or trace too "
        "short)";
  }

  // Impact times from the collisions of the body, when known: the first `count + 1` of them.
  std::vector<double> impact_error;
  double worst_impact = 0.0;
  for (const ContactEvent& c : trace.contacts) {
    if (c.body_a != body && c.body_b != body) continue;
    if (static_cast<int>(impact_error.size()) > count) break;
    impact_error.push_back(c.t - t0 - impact[impact_error.size()]);
    worst_impact = std::max(worst_impact, std::abs(impact_error.back()));
  }
  if (!impact_error.empty()) {
    figures["impact_time_error_s"] = impact_error;
    figures["impact_time_error_max_s"] = worst_impact;
  }
  return figures;
}

// One-dimensional impact along `axis` (DESIGN.md §6): v1' = [m1 v1 + m2 v2 + m2 e (v2 - v1)] /
// (m1 + m2) and symmetrically for v2'; the first sample must precede the impact and the last
// follow it. Errors are relative to the approach speed |v1 - v2|.
json compare_impact_1d(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t a = trace.body_index(spec_string(spec, where, "body_a"), where + "/body_a");
  std::size_t b = trace.body_index(spec_string(spec, where, "body_b"), where + "/body_b");
  if (a == b) throw InputError(where + "/body_b", "expected a body other than body_a");
  const double e = spec_number(spec, where, "restitution");
  const double m1 = spec_number(spec, where, "mass_a");
  const double m2 = spec_number(spec, where, "mass_b");
  const Vec3 axis = spec.contains("axis") ? spec_vec3(spec, where, "axis") : Vec3::UnitX();
  if (!(e >= 0.0 && e <= 1.0)) throw InputError(where + "/restitution", "expected 0 <= e <= 1");
  if (!(m1 > 0.0)) throw InputError(where + "/mass_a", "expected mass_a > 0");
  if (!(m2 > 0.0)) throw InputError(where + "/mass_b", "expected mass_b > 0");

  const double v1 = axis.dot(trace.samples.front()[a].v_W);
  const double v2 = axis.dot(trace.samples.front()[b].v_W);
  const double v1_after = (m1 * v1 + m2 * v2 + m2 * e * (v2 - v1)) / (m1 + m2);
  const double v2_after = (m1 * v1 + m2 * v2 + m1 * e * (v1 - v2)) / (m1 + m2);
  const double w1 = axis.dot(trace.samples.back()[a].v_W);
  const double w2 = axis.dot(trace.samples.back()[b].v_W);
  const double approach = std::abs(v1 - v2);
  const double scale = approach > 0.0 ? approach : 1.0;

  json figures;
  figures["approach_speed"] = approach;
  figures["velocity_a_closed_form"] = v1_after;
  figures["velocity_b_closed_form"] = v2_after;
  figures["velocity_a_final"] = w1;
  figures["velocity_b_final"] = w2;
  figures["velocity_a_rel_error"] = (w1 - v1_after) / scale;
  figures["velocity_b_rel_error"] = (w2 - v2_after) / scale;
  const double p0 = m1 * v1 + m2 * v2;
  figures["momentum_error"] = (m1 * w1 + m2 * w2 - p0) / ((m1 + m2) * scale);
  figures["restitution_fit"] = approach > 0.0 ? (w2 - w1) / (v1 - v2) : 0.0;
  return figures;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A numeric figure, NaN if absent.
double figure(const json& figures, const std::string& key) {
  auto it = figures.find(key);
  if (it == figures.end() || !it->is_number()) return kNaN;
  return it->get<double>();
}

// max(|a|, |b|), NaN if either is NaN (a figure the error needs is missing).
double worst(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return kNaN;
  return std::max(std::abs(a), std::abs(b));
}

}  // namespace

std::vector<double> polynomial_fit(const std::vector<double>& t, const std::vector<double>& y,
                                   int degree) {
  PALPABLE_CHECK(t.size() == y.size(), "polynomial_fit needs as many times as values");
  if (t.size() <= static_cast<std::size_t>(degree)) {
    // Data, not a bug: a trace too short or too coarse for the reference's window.
    throw InputError("trace", "a degree-" + std::to_string(degree) + " fit needs more than " +
                                  std::to_string(degree) + " samples in its window, got " +
                                  std::to_string(t.size()) +
                                  " (run longer or sample more often)");
  }
  double mean = 0.0;
  for (double x : t) mean += x;
  mean /= static_cast<double>(t.size());
  double scale = 0.0;
  for (double x : t) scale = std::max(scale, std::abs(x - mean));
  if (scale == 0.0) scale = 1.0;
  Eigen::MatrixXd A(t.size(), degree + 1);
  Eigen::VectorXd b(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    double tau = (t[i] - mean) / scale, p = 1.0;
    for (int k = 0; k <= degree; ++k, p *= tau) A(i, k) = p;
    b(i) = y[i];
  }
  Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  // Expand sum_k c_k ((t - mean)/scale)^k into powers of t.
  std::vector<double> out(degree + 1, 0.0);
  for (int k = 0; k <= degree; ++k) {
    // ((t - m)/s)^k = s^-k sum_j binom(k, j) t^j (-m)^(k-j)
    double binom = 1.0;
    for (int j = 0; j <= k; ++j) {
      out[j] += c(k) * binom * std::pow(-mean, k - j) / std::pow(scale, k);
      binom = binom * (k - j) / (j + 1);
    }
  }
  return out;
}

double InclineMotion::distance(double t) const {
  const double tc = std::min(t, stop_time);
  return initial_speed * tc + 0.5 * acceleration * tc * tc;
}

double InclineMotion::speed(double t) const {
  return t < stop_time ? initial_speed + acceleration * t : 0.0;
}

InclineMotion incline_motion(const json& spec, const std::string& where) {
  const double theta = spec_number(spec, where, "angle_deg") * kPi / 180.0;
  const double mu = spec_number(spec, where, "friction");
  const double g = spec_number(spec, where, "gravity");
  InclineMotion m;
  m.initial_speed = spec.contains("initial_speed") ? spec_number(spec, where, "initial_speed") : 0.0;
  m.down_slope = spec_vec3(spec, where, "down_slope");
  m.sliding_acceleration = g * (std::sin(theta) - mu * std::cos(theta));
  m.acceleration = m.sliding_acceleration <= 0.0 && m.initial_speed <= 0.0 ? 0.0
                                                                            : m.sliding_acceleration;
  m.stop_time = m.acceleration < 0.0 && m.initial_speed > 0.0 ? m.initial_speed / -m.acceleration
                                                              : kInfinity;
  return m;
}

TurntableCircle turntable_circle(const json& spec, const std::string& where, const Vec3& x0,
                                 const Vec3& v0_W) {
  TurntableCircle c;
  const double omega = spec_number(spec, where, "omega");
  c.axis = spec.contains("axis") ? spec_vec3(spec, where, "axis") : Vec3::UnitZ();
  const double k = spec.contains("k") ? spec_number(spec, where, "k") : 0.4;
  if (!(k > 0.0)) throw InputError(where + "/k", "expected k > 0 (I = k m r^2)");
  if (omega == 0.0) throw InputError(where + "/omega", "expected a non-zero rate");
  c.rate = k / (1.0 + k) * omega;
  const Vec3 v0 = v0_W - c.axis * c.axis.dot(v0_W);
  c.centre = x0 + c.axis.cross(v0) / c.rate;
  c.radius = v0.norm() / c.rate;
  return c;
}

double primary_error(const json& reference) {
  if (!reference.is_object()) return kNaN;
  const std::string type = reference.value("reference", std::string());
  if (type == "incline") {
    const std::string mode = reference.value("mode", std::string());
    if (mode == "slide_then_stop") {
      const double t_error =
          figure(reference, "stop_time_error_s") / figure(reference, "stop_time_closed_form_s");
      const double creep =
          figure(reference, "creep_m") / figure(reference, "stop_distance_closed_form_m");
      return worst(t_error, creep);
    }
    if (mode == "accelerating") return std::abs(figure(reference, "acceleration_rel_error"));
    if (mode == "stick") return figure(reference, "creep_m");
    return kNaN;
  }
  if (type == "turntable") {
    return worst(
        figure(reference, "rate_rel_error"),
        figure(reference, "circle_deviation_max_m") / figure(reference, "radius_closed_form_m"));
  }
  if (type == "slide_to_roll") {
    return worst(
        figure(reference, "roll_time_error_s") / figure(reference, "roll_time_closed_form_s"),
        figure(reference, "final_speed_rel_error"));
  }
  if (type == "bouncing_ball") return std::abs(figure(reference, "apex_height_rel_error_max"));
  if (type == "impact_1d") {
    return worst(figure(reference, "velocity_a_rel_error"),
                 figure(reference, "velocity_b_rel_error"));
  }
  return kNaN;
}

void validate_reference(const json& spec, const std::string& where,
                        const std::vector<std::string>& body_names, bool require_all) {
  const JsonReader r(where, "");
  if (!spec.is_object()) r.fail_value("", spec, "a reference object with a \"type\"");
  const std::string type = r.string(r.required(spec, "", "type"), "/type");
  const auto& table = reference_parameters();
  auto it = table.find(type);
  if (it == table.end()) {
    std::string names;
    for (const auto& [name, parameters] : table) names += (names.empty() ? "\"" : ", \"") + name + "\"";
    r.fail_value("/type", spec["type"], "one of " + names);
  }
  std::set<std::string> keys{"type"};
  for (const auto& [key, parameter] : it->second) keys.insert(key);
  r.only_keys(spec, "", keys);
  for (const auto& [key, parameter] : it->second) {
    auto value = spec.find(key);
    if (value == spec.end()) {
      if (parameter.required && require_all) {
        r.fail("/" + key, spec.contains("support") || !it->second.count("support")
                              ? "missing reference parameter"
                              : "missing reference parameter (give it, or \"support\": the body "
                                "it rests on, to derive it from the scene)");
      }
      continue;
    }
    const std::string path = "/" + key;
    switch (parameter.kind) {
      case 'n': r.number(*value, path); break;
      case 'd': r.direction(*value, path); break;
      case 'v': r.vec3(*value, path); break;
      case 'i':
        if (!value->is_number_integer() || value->get<long long>() < 1 ||
            value->get<long long>() > 1000) {
          r.fail_value(path, *value, "a whole number from 1 to 1000");
        }
        break;
      case 's': {
        const std::string name = r.string(*value, path);
        if (!body_names.empty() &&
            std::find(body_names.begin(), body_names.end(), name) == body_names.end()) {
          r.fail_value(path, *value, "the name of a body of the scene");
        }
        break;
      }
    }
  }
  // The ranges the comparisons need, checked here too, so that a scene's reference that could
  // only fail does so before its run rather than after it.
  auto check = [&](const char* key, bool (*ok)(double), const char* expected) {
    auto value = spec.find(key);
    if (value != spec.end() && !ok(value->get<double>())) {
      r.fail_value(std::string("/") + key, *value, expected);
    }
  };
  auto positive = [](double x) { return x > 0.0; };
  auto non_negative = [](double x) { return x >= 0.0; };
  auto below_one = [](double e) { return e >= 0.0 && e < 1.0; };
  auto up_to_one = [](double e) { return e >= 0.0 && e <= 1.0; };
  auto non_zero = [](double x) { return x != 0.0; };
  if (type == "slide_to_roll") {
    check("friction", positive, "friction > 0");
    check("gravity", positive, "gravity > 0 (its magnitude)");
    check("radius", positive, "radius > 0");
    check("k", positive, "k > 0 (I = k m R^2)");
  } else if (type == "bouncing_ball") {
    check("restitution", below_one, "0 <= e < 1");
    check("gravity", positive, "gravity > 0 (its magnitude)");
    check("radius", non_negative, "radius >= 0");
  } else if (type == "impact_1d") {
    check("restitution", up_to_one, "0 <= e <= 1");
    check("mass_a", positive, "mass_a > 0");
    check("mass_b", positive, "mass_b > 0");
    if (spec.contains("body_a") && spec.contains("body_b") && spec["body_a"] == spec["body_b"]) {
      r.fail_value("/body_b", spec["body_b"], "a body other than body_a");
    }
  } else if (type == "turntable") {
    check("k", positive, "k > 0 (I = k m r^2)");
    check("omega", non_zero, "a non-zero rate");
  }
}

namespace {

// k of I = k m r^2 for a body about its centre, from its largest principal moment and the radius
// of its sphere shape.
double inertia_ratio(const Body& b, double radius) {
  return b.mass.principal_moments.maxCoeff() / (b.mass.mass * radius * radius);
}

double sphere_radius(const Body& b, const std::string& where) {
  const Sphere* sphere = b.shape ? std::get_if<Sphere>(b.shape.get()) : nullptr;
  if (!sphere) throw InputError(where + "/body", "\"" + b.name + "\" is not a sphere");
  return sphere->radius;
}

json vec_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

json complete_reference(const json& spec, const std::string& where, const World& world) {
  validate_reference(spec, where, {}, false);
  json out = spec;
  if (!spec.contains("support")) return out;
  const std::string type = spec["type"].get<std::string>();
  const BodyId body_id = world.find_body(spec["body"].get<std::string>());
  const BodyId support_id = world.find_body(spec["support"].get<std::string>());
  const Body& body = world.bodies[body_id.index];
  const Body& support = world.bodies[support_id.index];
  if (body_id == support_id) throw InputError(where + "/support", "must be another body");
  if (!body.is_dynamic()) throw InputError(where + "/body", "must be a dynamic body");
  // The contact normal from the support up to the body, from their closest features at t = 0.
  const ShapeGeometry g_body(body.shape), g_support(support.shape);
  PairCache cache;
  const DistanceResult dr = closest_features(
      g_body, Pose{body.state.x_W, body.state.q_WM}, g_support,
      Pose{support.state.x_W, support.state.q_WM}, cache, world.settings.distance_max_steps);
  const double reach = g_body.reach();
  if (dr.status == ContactStatus::kFailed || dr.distance > 1e-3 * reach) {
    throw InputError(where + "/support", "\"" + support.name + "\" is not under \"" + body.name +
                                             "\" at the start (gap " +
                                             std::to_string(dr.distance) + " m)");
  }
  const Vec3 n = dr.n_W.normalized();  // from the support (body 2) to the body (body 1)
  const Vec3 g_W = world.gravity_W;
  const Material& material = world.material(body_id, support_id);
  auto put = [&out](const char* key, const json& value) {
    if (!out.contains(key)) out[key] = value;
  };
  if (type == "incline") {
    const Vec3 along = g_W - n * n.dot(g_W);
    if (!(along.norm() > 0.0)) throw InputError(where + "/support", "the support is level");
    const Vec3 down = along.normalized();
    put("normal", vec_json(n));
    put("down_slope", vec_json(down));
    put("angle_deg", std::acos(std::clamp(-n.dot(g_W.normalized()), -1.0, 1.0)) * 180.0 / kPi);
    put("friction", material.friction);
    put("gravity", g_W.norm());
    put("initial_speed", body.state.v_W.dot(down));
  } else if (type == "turntable") {
    const Vec3 omega = support.kinematic.angular_velocity_W;
    if (support.motion != MotionKind::kKinematic || !(omega.norm() > 0.0)) {
      throw InputError(where + "/support", "\"" + support.name + "\" is not a spinning body");
    }
    put("axis", vec_json(omega.normalized()));
    put("omega", omega.norm());
    put("k", inertia_ratio(body, sphere_radius(body, where)));
    put("position", vec_json(body.state.x_W));
    put("velocity", vec_json(body.state.v_W));
  } else if (type == "slide_to_roll") {
    const double radius = sphere_radius(body, where);
    put("friction", material.friction);
    put("gravity", std::abs(g_W.dot(n)));
    put("radius", radius);
    put("k", inertia_ratio(body, radius));
    put("normal", vec_json(n));
    put("velocity", vec_json(body.state.v_W));
    put("angular_velocity", vec_json(body.state.w_W));
  } else {
    throw InputError(where + "/support", "a " + type + " reference has no support");
  }
  return out;
}

json compare_with_reference(const json& spec, const Trace& trace, const std::string& where) {
  validate_reference(spec, where, trace.body_names);
  const std::string type = spec["type"].get<std::string>();
  json figures;
  if (type == "incline") {
    figures = compare_incline(spec, trace, where);
  } else if (type == "turntable") {
    figures = compare_turntable(spec, trace, where);
  } else if (type == "slide_to_roll") {
    figures = compare_slide_to_roll(spec, trace, where);
  } else if (type == "bouncing_ball") {
    figures = compare_bouncing_ball(spec, trace, where);
  } else {
    figures = compare_impact_1d(spec, trace, where);
  }
  figures["reference"] = type;
  if (figures.contains("premise_failed")) {
    // Figures measured against a closed form that does not apply are not figures: null, so that
    // `compare --max` fails on them instead of passing a wrong number.
    for (auto& [key, value] : figures.items()) {
      if (value.is_number() && key.find("closed_form") == std::string::npos &&
          key != "off_plane_max_m") {
        value = nullptr;
      }
    }
  }
  return figures;
}


}  // namespace palpable
