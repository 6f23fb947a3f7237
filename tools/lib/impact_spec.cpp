#include "tools/lib/impact_spec.hpp"

#include "scenarios/json_reader.hpp"

#include "core/check.hpp"
#include "core/settings.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <iomanip>
#include <ostream>
#include <set>

namespace palpable::tools {

const char* const kImpactSpecHelp =
    R"(SPEC is a JSON file ("-" reads standard input) describing one collision, either
in the contact frame (normal = third axis, from body 2 to body 1):
  "K":  3x3 collision matrix, nested arrays, row-major, symmetric positive definite
  "u0": initial relative contact velocity u1 - u2 (3 numbers; u0[2] <= 0 approaches)
or by two bodies (world frame):
  "bodies": [body1, body2], each with
      "mass":             positive number [kg]; null or "inf" for infinite mass
      "fixed":            optional, true = infinite mass (as mass null)
      "inertia":          3x3 world-frame inertia about the centre of mass [kg m^2]
                          (required for finite mass, not allowed for infinite mass)
      "velocity":         centre-of-mass velocity (3 numbers, default 0) [m/s]
      "angular_velocity": (3 numbers, default 0) [rad/s]; kept for infinite mass too
      "offset":           contact point minus centre of mass (3 numbers) [m]
  "normal": contact normal from body 2 to body 1 (3 numbers, normalised here)
and in both cases:
  "friction":    Coulomb mu >= 0
  "restitution": e in [0, 1]
  "law":         "stronge" | "poisson" | "newton"
  "tolerance":   optional relative integration tolerance (default 1e-9)
Unknown keys are rejected. Output: one JSON object with "status", "impulse" (contact frame),
"u_final", "energy_change", "phases", "steps", "compression_impulse", ... and, for bodies,
"impulse_world" and the bodies' velocities after the collision.
Example (a thin rod striking the ground, the README's thin-rod table):
  {"K": [[2.5, 0, -1.5], [0, 4, 0], [-1.5, 0, 2.5]], "u0": [0.5, 0, -1],
   "friction": 0.5, "restitution": 0.5, "law": "stronge"}
)";

namespace {

using nlohmann::json;

// The project's one JSON reader (scenarios/json_reader.hpp); the caller prefixes the spec's file.
const JsonReader& reader() {
  static const JsonReader r("", "");
  return r;
}

[[noreturn]] void fail(const std::string& where, const json& value, const std::string& expected) {
  reader().fail_value(where, value, expected);
}

void reject_unknown_keys(const json& object, const std::string& where,
                         const std::set<std::string>& allowed) {
  reader().only_keys(object, where, allowed);
}

const json& require(const json& object, const std::string& key, const std::string& where) {
  return reader().required(object, where, key);
}

double number(const json& value, const std::string& where, const std::string& expected) {
  if (!value.is_number() || !std::isfinite(value.get<double>())) fail(where, value, expected);
  return value.get<double>();
}

Vec3 vec3(const json& value, const std::string& where) { return reader().vec3(value, where); }

Mat3 mat3(const json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3) {
    fail(where, value, "a 3x3 matrix as 3 rows of 3 numbers");
  }
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    m.row(i) = vec3(value[i], where + "/" + std::to_string(i)).transpose();
  return m;
}

void require_spd(const Mat3& m, const json& value, const std::string& where) {
  const double scale = m.cwiseAbs().maxCoeff();
  if (!((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale)) {
    fail(where, value, "a symmetric matrix");
  }
  const double smallest =
      Eigen::SelfAdjointEigenSolver<Mat3>(0.5 * (m + m.transpose())).eigenvalues().minCoeff();
  if (!(smallest > 1e-14 * scale)) fail(where, value, "a positive definite matrix");
}

ContactBody parse_body(const json& value, const std::string& where) {
  if (!value.is_object()) fail(where, value, "an object describing a body");
  reject_unknown_keys(value, where,
                      {"mass", "fixed", "inertia", "velocity", "angular_velocity", "offset"});
  bool infinite = false;
  if (auto it = value.find("fixed"); it != value.end()) {
    if (!it->is_boolean()) fail(where + "/fixed", *it, "true or false");
    infinite = it->get<bool>();
  }
  ContactBody body;
  auto mass = value.find("mass");
  if (mass == value.end() && !infinite) {
    throw InputError(where + "/mass", "missing required key (or give \"fixed\": true)");
  }
  if (mass != value.end()) {
    if (mass->is_null() || (mass->is_string() && mass->get<std::string>() == "inf")) {
      infinite = true;
    } else if (infinite) {
      fail(where + "/mass", *mass, "null or \"inf\" for a fixed body");
    } else {
      const double m = number(*mass, where + "/mass", "a positive number, null or \"inf\"");
      if (!(m > 0.0)) fail(where + "/mass", *mass, "a positive number, null or \"inf\"");
      body.inv_mass = 1.0 / m;
    }
  }
  auto inertia = value.find("inertia");
  if (infinite) {
    if (inertia != value.end()) {
      fail(where + "/inertia", *inertia, "no inertia for an infinite-mass body");
    }
  } else {
    if (inertia == value.end()) throw InputError(where + "/inertia", "missing required key");
    const Mat3 I = mat3(*inertia, where + "/inertia");
    require_spd(I, *inertia, where + "/inertia");
    body.inv_inertia_W = I.inverse();
    body.inv_inertia_W = 0.5 * (body.inv_inertia_W + body.inv_inertia_W.transpose()).eval();
  }
  if (auto it = value.find("velocity"); it != value.end())
    body.v_W = vec3(*it, where + "/velocity");
  if (auto it = value.find("angular_velocity"); it != value.end()) {
    body.w_W = vec3(*it, where + "/angular_velocity");
  }
  body.r_W = vec3(require(value, "offset", where), where + "/offset");
  return body;
}

json to_json(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

json to_json(const Mat3& m) {
  return json::array({to_json(Vec3(m.row(0))), to_json(Vec3(m.row(1))), to_json(Vec3(m.row(2)))});
}

}  // namespace

ImpactSpec parse_impact_spec(const json& spec) {
  if (!spec.is_object()) fail("", spec, "a JSON object (see palpable impact --help)");
  reject_unknown_keys(
      spec, "", {"K", "u0", "bodies", "normal", "friction", "restitution", "law", "tolerance"});
  ImpactSpec out;
  const bool has_K = spec.contains("K") || spec.contains("u0");
  const bool has_bodies = spec.contains("bodies") || spec.contains("normal");
  if (has_K == has_bodies) {
    throw InputError("", has_K
                             ? "give either \"K\" and \"u0\" or \"bodies\" and \"normal\", not both"
                             : "missing \"K\" and \"u0\" (contact frame) or \"bodies\" and "
                               "\"normal\"");
  }
  if (has_K) {
    const json& K = require(spec, "K", "");
    out.K_c = mat3(K, "/K");
    require_spd(out.K_c, K, "/K");
    out.K_c = 0.5 * (out.K_c + out.K_c.transpose()).eval();
    out.u0_c = vec3(require(spec, "u0", ""), "/u0");
  } else {
    const json& bodies = require(spec, "bodies", "");
    if (!bodies.is_array() || bodies.size() != 2) fail("/bodies", bodies, "an array of 2 bodies");
    out.from_bodies = true;
    for (int i = 0; i < 2; ++i)
      out.bodies[i] = parse_body(bodies[i], "/bodies/" + std::to_string(i));
    if (out.bodies[0].inv_mass == 0.0 && out.bodies[1].inv_mass == 0.0) {
      throw InputError("/bodies", "both bodies have infinite mass; expected at least one finite");
    }
    const json& normal = require(spec, "normal", "");
    const Vec3 n = vec3(normal, "/normal");
    if (!(n.norm() > 1e-12)) fail("/normal", normal, "a non-zero vector");
    out.R_WC = contact_frame_W(n / n.norm());
    out.K_c = out.R_WC.transpose() * collision_matrix_W(out.bodies[0], out.bodies[1]) * out.R_WC;
    out.K_c = 0.5 * (out.K_c + out.K_c.transpose()).eval();
    out.u0_c = out.R_WC.transpose() *
               (contact_point_velocity_W(out.bodies[0]) - contact_point_velocity_W(out.bodies[1]));
    if (!(Eigen::SelfAdjointEigenSolver<Mat3>(out.K_c).eigenvalues().minCoeff() > 0.0)) {
      throw InputError("/bodies", "the collision matrix is not positive definite");
    }
  }
  const json& friction = require(spec, "friction", "");
  out.params.friction = number(friction, "/friction", "a number >= 0");
  if (!(out.params.friction >= 0.0)) fail("/friction", friction, "a number >= 0");
  const json& restitution = require(spec, "restitution", "");
  out.params.restitution = number(restitution, "/restitution", "a number in [0, 1]");
  if (!(out.params.restitution >= 0.0 && out.params.restitution <= 1.0)) {
    fail("/restitution", restitution, "a number in [0, 1]");
  }
  const json& law = require(spec, "law", "");
  const std::string laws = "\"stronge\", \"poisson\" or \"newton\"";
  if (!law.is_string()) fail("/law", law, laws);
  const std::string name = law.get<std::string>();
  if (name == "stronge") {
    out.params.law = RestitutionLaw::kStronge;
  } else if (name == "poisson") {
    out.params.law = RestitutionLaw::kPoisson;
  } else if (name == "newton") {
    out.params.law = RestitutionLaw::kNewton;
  } else {
    fail("/law", law, laws);
  }
  out.params.tolerance = Settings{}.integration_tolerance;
  if (auto it = spec.find("tolerance"); it != spec.end()) {
    out.params.tolerance = number(*it, "/tolerance", "a number in (0, 1)");
    if (!(out.params.tolerance > 0.0 && out.params.tolerance < 1.0)) {
      fail("/tolerance", *it, "a number in (0, 1)");
    }
  }
  return out;
}

ImpactSpec parse_impact_spec_text(const std::string& text, const std::string& source) {
  const json spec = parse_json_text(text, source);
  try {
    return parse_impact_spec(spec);
  } catch (const InputError& e) {
    // Name the file as well as the JSON path, as scene errors do.
    // The message is what() after "where: ", unless a "\u0000" in a key ended what() early.
    const std::string what = e.what();
    const std::size_t cut = e.where().empty() ? 0 : e.where().size() + 2;
    throw InputError(source + ":" + e.where(), what.size() >= cut ? what.substr(cut) : what);
  }
}

void write_impulse_path_csv(std::ostream& out, const std::vector<ImpulsePathPoint>& path) {
  out << "p_z,p_x,p_y,u_x,u_y,u_z\n";
  out << std::setprecision(17);
  for (const ImpulsePathPoint& q : path) {
    out << q.p_c.z() << ',' << q.p_c.x() << ',' << q.p_c.y() << ',' << q.u_c.x() << ','
        << q.u_c.y() << ',' << q.u_c.z() << '\n';
  }
}

json resolve_impact(const ImpactSpec& spec, std::vector<ImpulsePathPoint>* path) {
  CollisionParameters params = spec.params;
  params.path = path;
  const CollisionResult r = integrate_collision(spec.K_c, spec.u0_c, params);
  json out;
  out["status"] = std::string(to_string(r.status));
  out["law"] = std::string(to_string(spec.params.law));
  out["friction"] = spec.params.friction;
  out["restitution"] = spec.params.restitution;
  out["tolerance"] = spec.params.tolerance;
  out["K"] = to_json(spec.K_c);
  out["u0"] = to_json(r.u0_c);
  out["impulse"] = to_json(r.p_c);
  out["u_final"] = to_json(r.u_final_c);
  out["energy_change"] = r.energy_change;
  out["compression_impulse"] = r.p_z_compression;
  out["compression_work"] = r.work_compression;
  out["normal_work"] = r.work_normal;
  json phases = json::array();
  for (int i = 0; i < r.phase_count; ++i) phases.push_back(describe(r.phases[i]));
  out["phases"] = phases;
  out["steps"] = r.steps;
  out["rejected_steps"] = r.rejected_steps;
  out["rhs_evaluations"] = r.rhs_evaluations;
  out["stalled_slip_landings"] = r.stalled_slip_landings;
  if (spec.from_bodies) {
    const Vec3 p_W = spec.R_WC * r.p_c;
    out["normal"] = to_json(Vec3(spec.R_WC.col(2)));
    out["frame"] = to_json(spec.R_WC);
    out["impulse_world"] = to_json(p_W);
    ContactBody b1 = spec.bodies[0], b2 = spec.bodies[1];
    if (succeeded(r.status)) apply_impulse(p_W, b1, b2);
    out["bodies_after"] =
        json::array({json{{"velocity", to_json(b1.v_W)}, {"angular_velocity", to_json(b1.w_W)}},
                     json{{"velocity", to_json(b2.v_W)}, {"angular_velocity", to_json(b2.w_W)}}});
  }
  return out;
}

}  // namespace palpable::tools
