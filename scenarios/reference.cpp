#include "scenarios/reference.hpp"

#include "core/check.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace palpable {
namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

double spec_number(const json& spec, const std::string& where, const std::string& key) {
  auto it = spec.find(key);
  if (it == spec.end()) throw InputError(where + "/" + key, "missing reference parameter");
  if (!it->is_number() || !std::isfinite(it->get<double>())) {
    throw InputError(where + "/" + key, "got " + it->dump() + ", expected a finite number");
  }
  return it->get<double>();
}

Vec3 spec_vec3(const json& spec, const std::string& where, const std::string& key) {
  auto it = spec.find(key);
  if (it == spec.end()) throw InputError(where + "/" + key, "missing reference parameter");
  if (!it->is_array() || it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() ||
      !(*it)[2].is_number()) {
    throw InputError(where + "/" + key, "got " + it->dump() + ", expected [x, y, z]");
  }
  Vec3 v((*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>());
  if (!(v.norm() > 0.0)) throw InputError(where + "/" + key, "expected a non-zero vector");
  return v.normalized();
}

std::string spec_string(const json& spec, const std::string& where, const std::string& key) {
  auto it = spec.find(key);
  if (it == spec.end() || !it->is_string()) {
    throw InputError(where + "/" + key, "expected a string");
  }
  return it->get<std::string>();
}

json compare_incline(const json& spec, const Trace& trace, const std::string& where) {
  std::size_t body = trace.body_index(spec_string(spec, where, "body"), where + "/body");
  const double theta = spec_number(spec, where, "angle_deg") * kPi / 180.0;
  const double mu = spec_number(spec, where, "friction");
  const double g = spec_number(spec, where, "gravity");
  const double v0 =
      spec.contains("initial_speed") ? spec_number(spec, where, "initial_speed") : 0.0;
  const Vec3 down = spec_vec3(spec, where, "down_slope");
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

  const double a = g * (std::sin(theta) - mu * std::cos(theta));  // along-slope while sliding
  json figures;
  figures["acceleration_closed_form"] = a;
  figures["cross_slope_max_m"] = cross_max;

  if (v0 > 0.0 && a < 0.0) {
    // Decelerating: stops at t* and stays.
    const double t_stop = v0 / (-a);
    const double s_stop = v0 * v0 / (2.0 * -a);
    figures["mode"] = "slide_then_stop";
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
  const double omega = spec_number(spec, where, "omega");
  const Vec3 axis = spec.contains("axis") ? spec_vec3(spec, where, "axis") : Vec3::UnitZ();
  const double k = spec.contains("k") ? spec_number(spec, where, "k") : 0.4;
  if (!(k > 0.0)) throw InputError(where + "/k", "expected k > 0 (I = k m r^2)");
  const double rate = k / (1.0 + k) * omega;  // dv/dt = rate * axis x v
  std::vector<BodyState> states = trace.series(body);
  const Vec3 x0 = states.front().x_W;
  const Vec3 v0 = states.front().v_W - axis * axis.dot(states.front().v_W);
  const double t0 = trace.times.front();
  // Circle centre: x0 + axis x v0 / rate; radius |v0| / rate.
  const Vec3 centre = x0 + axis.cross(v0) / rate;
  const double radius = v0.norm() / rate;

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

}  // namespace

std::vector<double> polynomial_fit(const std::vector<double>& t, const std::vector<double>& y,
                                   int degree) {
  PALPABLE_CHECK(t.size() == y.size() && t.size() > static_cast<std::size_t>(degree),
                 "polynomial_fit needs more points than the degree");
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

json compare_with_reference(const json& spec, const Trace& trace, const std::string& where) {
  if (!spec.is_object()) throw InputError(where, "expected a reference object with a \"type\"");
  std::string type = spec_string(spec, where, "type");
  json figures;
  if (type == "incline") {
    figures = compare_incline(spec, trace, where);
  } else if (type == "turntable") {
    figures = compare_turntable(spec, trace, where);
  } else {
    throw InputError(where + "/type",
                     "got \"" + type + "\", expected \"incline\" or \"turntable\"");
  }
  figures["reference"] = type;
  return figures;
}

}  // namespace palpable
