#include "scenarios/scene.hpp"

#include "scenarios/expression.hpp"
#include "scenarios/json_reader.hpp"
#include "scenarios/reference.hpp"

#include "core/check.hpp"
#include "core/mass_properties.hpp"
#include "core/shape.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

namespace palpable {
namespace {

using nlohmann::json;

using Reader = JsonReader;

// Sizes a body's shape may have [m]: outside, masses and inertias leave the doubles' useful range
// (a sphere of radius 1e-200 had mass NaN) or rounding swamps contact (an envelope cannot be set).
constexpr double kMinSize = 1e-6;
constexpr double kMaxSize = 1e6;
constexpr double kMinAspect = 1e-6;  // thinnest over thickest dimension of a box
constexpr const char* kSizeRange = "a size from 1e-6 to 1e6 m";
// A body's mass [kg], distance from the origin [m], speed [m/s] and angular speed [rad/s].
constexpr double kMinMass = 1e-20;
constexpr double kMaxMass = 1e20;
constexpr double kMaxPosition = 1e9;
constexpr double kMaxSpeed = 1e6;
constexpr double kMaxAngularSpeed = 1e9;

std::shared_ptr<const Shape> parse_shape(const Reader& r, const json& value,
                                         const std::string& path, bool allow_unbounded) {
  r.object(value, path);
  std::string type = r.string(r.required(value, path, "type"), path + "/type");
  try {
    if (type == "sphere") {
      r.only_keys(value, path, {"type", "radius"});
      double radius = r.positive(r.required(value, path, "radius"), path + "/radius");
      if (radius < kMinSize || radius > kMaxSize) {
        r.fail_value(path + "/radius", value["radius"], kSizeRange);
      }
      return std::make_shared<const Shape>(Sphere{radius});
    }
    if (type == "box") {
      r.only_keys(value, path, {"type", "half_extents"});
      Vec3 h = r.vec3(r.required(value, path, "half_extents"), path + "/half_extents");
      for (int i = 0; i < 3; ++i) {
        if (!(h[i] > 0.0)) {
          r.fail_value(path + "/half_extents/" + std::to_string(i), value["half_extents"][i],
                       "a positive half extent");
        }
        // A box 2e-200 m thick passed, then its first collision's inertia was not finite.
        if (h[i] < kMinSize || h[i] > kMaxSize || h[i] < kMinAspect * h.maxCoeff()) {
          r.fail_value(path + "/half_extents/" + std::to_string(i), value["half_extents"][i],
                       std::string(kSizeRange) + ", and at least 1e-6 of the largest");
        }
      }
      return std::make_shared<const Shape>(ConvexPolyhedron::box(h));
    }
    if (type == "prism") {
      r.only_keys(value, path, {"type", "radius", "half_height", "sides"});
      double radius = r.positive(r.required(value, path, "radius"), path + "/radius");
      double half_height =
          r.positive(r.required(value, path, "half_height"), path + "/half_height");
      const json& sides = r.required(value, path, "sides");
      if (!sides.is_number_integer() || sides.get<long long>() < 3 ||
          sides.get<long long>() > 100000) {
        r.fail_value(path + "/sides", sides, "an integer number of sides from 3 to 100000");
      }
      return std::make_shared<const Shape>(
          ConvexPolyhedron::prism(radius, half_height, sides.get<int>()));
    }
    // A positive size [m] within kSizeRange, and at least kMinAspect of `largest` (0: no check).
    auto size = [&](const char* key, double largest) {
      const double x = r.positive(r.required(value, path, key), path + "/" + key);
      if (x < kMinSize || x > kMaxSize || x < kMinAspect * largest) {
        r.fail_value(path + "/" + key, value[key],
                     std::string(kSizeRange) + ", and at least 1e-6 of the largest");
      }
      return x;
    };
    if (type == "ellipsoid") {
      r.only_keys(value, path, {"type", "semi_axes", "com_offset"});
      const Vec3 a = r.vec3(r.required(value, path, "semi_axes"), path + "/semi_axes");
      for (int i = 0; i < 3; ++i) {
        if (!(a[i] >= kMinSize && a[i] <= kMaxSize && a[i] >= kMinAspect * a.maxCoeff())) {
          r.fail_value(path + "/semi_axes/" + std::to_string(i), value["semi_axes"][i],
                       std::string("a positive semi-axis, ") + kSizeRange +
                           ", and at least 1e-6 of the largest");
        }
      }
      double offset = 0.0;
      if (value.contains("com_offset")) {
        offset = r.number(value["com_offset"], path + "/com_offset");
        if (!(std::abs(offset) < a.z())) {
          r.fail_value(path + "/com_offset", value["com_offset"],
                       "an offset of the centre of mass smaller in size than the z semi-axis");
        }
      }
      return std::make_shared<const Shape>(make_ellipsoid(a, offset));
    }
    if (type == "cylinder" || type == "capsule") {
      // A radius and a length along z, neither below kMinAspect of the other.
      const char* length_key = type == "cylinder" ? "half_height" : "half_length";
      r.only_keys(value, path, {"type", "radius", length_key});
      const double radius = size("radius", 0.0);
      const double length = size(length_key, radius);
      if (radius < kMinAspect * length) size("radius", length);
      if (type == "cylinder") return std::make_shared<const Shape>(make_cylinder(radius, length));
      return std::make_shared<const Shape>(make_capsule(radius, length));
    }
    if (type == "loaded_ball") {
      r.only_keys(value, path, {"type", "radius", "com_offset"});
      const double radius = size("radius", 0.0);
      const double offset = r.number(r.required(value, path, "com_offset"), path + "/com_offset");
      if (!(std::abs(offset) < radius)) {
        r.fail_value(path + "/com_offset", value["com_offset"],
                     "an offset of the centre of mass smaller in size than the radius");
      }
      return std::make_shared<const Shape>(make_loaded_ball(radius, offset));
    }
    if (type == "convex") {
      r.only_keys(value, path, {"type", "vertices"});
      const json& vertices = r.required(value, path, "vertices");
      if (!vertices.is_array() || vertices.size() < 4) {
        r.fail_value(path + "/vertices", vertices, "an array of at least 4 points [x, y, z]");
      }
      std::vector<Vec3> points;
      for (std::size_t i = 0; i < vertices.size(); ++i) {
        points.push_back(r.vec3(vertices[i], path + "/vertices/" + std::to_string(i)));
      }
      return std::make_shared<const Shape>(ConvexPolyhedron::from_points(points));
    }
    if (type == "halfspace") {
      if (!allow_unbounded) {
        r.fail(path + "/type",
               "a halfspace is unbounded: only a fixed or kinematic body may have one");
      }
      r.only_keys(value, path, {"type", "normal", "offset"});
      const Vec3 n = r.vec3(r.required(value, path, "normal"), path + "/normal");
      // |n| without squaring the components: (9e190, 0, 1) squared overflows, and normalising by
      // that infinity made the zero vector, a plane every body touched and none could meet
      // (tests/fuzz/findings/engine_timeout_distance_steps.bin); (0, 0, 1e-170) underflows to 0.
      const double length = n.stableNorm();
      if (!(length > 0.0) || !std::isfinite(length)) {
        r.fail_value(path + "/normal", value["normal"], "a non-zero vector");
      }
      double offset = value.contains("offset") ? r.number(value["offset"], path + "/offset") : 0.0;
      // n . x <= offset with |n| != 1 is the same solid as n/|n| . x <= offset/|n|.
      return std::make_shared<const Shape>(Halfspace{n / length, offset / length});
    }
    if (type == "compound") {
      if (!allow_unbounded) {
        r.fail(path + "/type", "a compound is for fixed or kinematic bodies only");
      }
      r.only_keys(value, path, {"type", "parts"});
      const json& parts = r.required(value, path, "parts");
      if (!parts.is_array() || parts.empty()) {
        r.fail_value(path + "/parts", parts, "a non-empty array of parts");
      }
      Compound compound;
      for (std::size_t i = 0; i < parts.size(); ++i) {
        std::string part_path = path + "/parts/" + std::to_string(i);
        r.object(parts[i], part_path);
        r.only_keys(parts[i], part_path, {"shape", "position", "orientation"});
        CompoundPart part;
        const json& part_shape =
            r.object(r.required(parts[i], part_path, "shape"), part_path + "/shape");
        const json& part_type = r.required(part_shape, part_path + "/shape", "type");
        if (part_type != "sphere" && part_type != "box" && part_type != "prism" &&
            part_type != "convex" && part_type != "ellipsoid" && part_type != "cylinder" &&
            part_type != "capsule") {
          r.fail_value(part_path + "/shape/type", part_type,
                       "a convex part: \"sphere\", \"box\", \"prism\", \"convex\", "
                       "\"ellipsoid\", \"cylinder\" or \"capsule\"");
        }
        if (part_type == "ellipsoid" && part_shape.contains("com_offset")) {
          r.fail_value(part_path + "/shape/com_offset", part_shape["com_offset"],
                       "no centre-of-mass offset on a compound part (place it by \"position\")");
        }
        part.shape = parse_shape(r, part_shape, part_path + "/shape", /*allow_unbounded=*/false);
        if (parts[i].contains("position")) {
          part.position_M = r.vec3(parts[i]["position"], part_path + "/position");
        }
        if (parts[i].contains("orientation")) {
          part.orientation_M = r.quaternion(parts[i]["orientation"], part_path + "/orientation");
        }
        // A convex part's points are recentred at its centre of mass when built; put it back, so
        // that a part's vertices are where the scene says (in the part frame at `position`).
        if (const auto* hull = std::get_if<ConvexPolyhedron>(part.shape.get())) {
          part.position_M += part.orientation_M * hull->com_shift_M();
        }
        compound.parts.push_back(std::move(part));
      }
      return std::make_shared<const Shape>(std::move(compound));
    }
  } catch (const InputError& e) {
    // Errors from the shape builders (degenerate hull, ...) do not know the JSON path.
    if (r.is_ours(e)) throw;
    r.fail(path, e.what());
  }
  r.fail_value(path + "/type", value["type"],
               "one of \"sphere\", \"box\", \"prism\", \"convex\", \"ellipsoid\", "
               "\"cylinder\", \"capsule\", \"loaded_ball\", \"halfspace\", \"compound\"");
}

Material parse_material(const Reader& r, const json& value, const std::string& path,
                        const Material& defaults, bool pair) {
  r.object(value, path);
  if (pair) {
    r.only_keys(value, path,
                {"bodies", "friction", "restitution", "rolling_resistance", "spinning_resistance"});
  } else {
    r.only_keys(value, path,
                {"friction", "restitution", "rolling_resistance", "spinning_resistance"});
  }
  Material m = defaults;
  if (value.contains("friction"))
    m.friction = r.non_negative(value["friction"], path + "/friction");
  if (value.contains("rolling_resistance")) {
    m.rolling_resistance =
        r.non_negative(value["rolling_resistance"], path + "/rolling_resistance");
  }
  if (value.contains("spinning_resistance")) {
    m.spinning_resistance =
        r.non_negative(value["spinning_resistance"], path + "/spinning_resistance");
  }
  if (value.contains("restitution")) {
    m.restitution = r.non_negative(value["restitution"], path + "/restitution");
    if (m.restitution > 1.0) {
      r.fail_value(path + "/restitution", value["restitution"], "a coefficient in [0, 1]");
    }
  }
  return m;
}

// Every key of core/settings.hpp's table, read and checked through it.
void parse_settings(const Reader& r, const json& value, const std::string& path, Settings& s) {
  r.object(value, path);
  std::set<std::string> keys;
  for (const SettingInfo& info : settings_table()) keys.insert(std::string(info.key));
  r.only_keys(value, path, keys);
  for (const SettingInfo& info : settings_table()) {
    auto it = value.find(std::string(info.key));
    if (it == value.end()) continue;
    const std::string where = path + "/" + std::string(info.key);
    SettingValue v;
    if (it->is_boolean()) {
      v = it->get<bool>();
    } else if (it->is_number_integer() &&
               !(it->is_number_unsigned() &&
                 it->get<unsigned long long>() > static_cast<unsigned long long>(LLONG_MAX))) {
      v = it->get<long long>();
    } else if (it->is_number()) {
      v = it->get<double>();
    } else if (it->is_string()) {
      v = it->get<std::string>();
    } else {
      r.fail_value(where, *it, std::string(info.check));
    }
    if (!info.set(s, v)) r.fail_value(where, *it, std::string(info.check));
  }
}

// A body's inertia about its centre of mass in its modelling frame [kg m^2]: [I1, I2, I3], the
// principal moments along x, y, z, or a symmetric 3 x 3 matrix [[Ixx, Ixy, Ixz], [..], [..]] whose
// products of inertia turn the principal axes (its positive definiteness and the triangle
// inequality are checked by mass_properties_from_inertia).
Mat3 parse_inertia(const Reader& r, const json& value, const std::string& path) {
  if (value.is_array() && value.size() == 3 && value[0].is_array()) {
    Mat3 I;
    for (int i = 0; i < 3; ++i) {
      I.row(i) = r.vec3(value[static_cast<std::size_t>(i)], path + "/" + std::to_string(i));
    }
    return I;
  }
  const Vec3 d = r.vec3(value, path);
  for (int i = 0; i < 3; ++i) {
    if (!(d[i] > 0.0)) {
      r.fail_value(path + "/" + std::to_string(i), value[static_cast<std::size_t>(i)],
                   "a positive principal moment");
    }
  }
  return d.asDiagonal();
}

Body parse_body(const Reader& r, const json& value, const std::string& path) {
  r.object(value, path);
  r.only_keys(value, path,
              {"name", "motion", "mass", "density", "inertia", "shape", "position", "orientation",
               "velocity", "angular_velocity"});
  Body body;
  body.name = r.string(r.required(value, path, "name"), path + "/name");
  if (body.name.empty()) r.fail_value(path + "/name", value["name"], "a non-empty name");

  const json& motion = value.contains("motion") ? value["motion"] : json("dynamic");
  if (motion == "dynamic") {
    body.motion = MotionKind::kDynamic;
  } else if (motion == "fixed") {
    body.motion = MotionKind::kFixed;
  } else if (motion.is_object() && motion.size() == 1 && motion.contains("kinematic")) {
    body.motion = MotionKind::kKinematic;
    std::string kpath = path + "/motion/kinematic";
    const json& k = r.object(motion["kinematic"], kpath);
    r.only_keys(k, kpath, {"angular_velocity", "point", "velocity"});
    if (k.contains("angular_velocity")) {
      body.kinematic.angular_velocity_W =
          r.vec3(k["angular_velocity"], kpath + "/angular_velocity");
    }
    if (k.contains("point")) body.kinematic.point_W = r.vec3(k["point"], kpath + "/point");
    if (k.contains("velocity"))
      body.kinematic.velocity_W = r.vec3(k["velocity"], kpath + "/velocity");
  } else {
    r.fail_value(path + "/motion", motion,
                 "\"dynamic\", \"fixed\" or {\"kinematic\": {\"angular_velocity\": [..], "
                 "\"point\": [..], \"velocity\": [..]}}");
  }

  body.shape = parse_shape(r, r.required(value, path, "shape"), path + "/shape",
                           /*allow_unbounded=*/!body.is_dynamic());

  if (body.is_dynamic()) {
    bool has_mass = value.contains("mass");
    bool has_density = value.contains("density");
    if (has_mass == has_density) {
      r.fail(path, has_mass ? "give either \"mass\" or \"density\", not both"
                            : "missing \"mass\" (kg) or \"density\" (kg/m^3) of a dynamic body");
    }
    // Uniform density fixes the inertia of every shape but two: a loaded ball (its centre of mass
    // is off its centre) must be given its inertia, and an ellipsoid may be (a rattleback's
    // principal axes are turned from its geometric ones).
    const bool loaded = std::holds_alternative<LoadedBall>(*body.shape);
    const auto* ellipsoid = std::get_if<Ellipsoid>(body.shape.get());
    const bool given = value.contains("inertia");
    if (ellipsoid && ellipsoid->com_offset != 0.0 && !given) {
      r.fail(path,
             "an ellipsoid with a \"com_offset\" needs \"mass\" (kg) and \"inertia\" (about its "
             "centre of mass, kg m^2): uniform density cannot put its centre of mass off its "
             "centre");
    }
    if (loaded && !given) {
      r.fail(path,
             "a loaded ball needs \"mass\" (kg) and \"inertia\" (its principal moments "
             "about its centre of mass along x, y, z, kg m^2): uniform density cannot put "
             "its centre of mass off its centre");
    }
    if (given && !loaded && !ellipsoid) {
      r.fail(path,
             "\"inertia\" is for a loaded ball or an ellipsoid only; other shapes' inertia "
             "comes from their shape and mass or density");
    }
    if (given) {
      if (!has_mass) {
        r.fail(path, loaded ? "a loaded ball needs \"mass\", not \"density\""
                            : "an ellipsoid given \"inertia\" needs \"mass\", not \"density\"");
      }
      const double mass = r.positive(value["mass"], path + "/mass");
      const Mat3 I = parse_inertia(r, value["inertia"], path + "/inertia");
      try {
        body.mass = mass_properties_from_inertia(mass, I);
      } catch (const InputError& e) {
        r.fail_value(path + "/inertia", value["inertia"], e.what());
      }
    } else if (has_mass) {
      body.mass = mass_properties_from_mass(*body.shape, r.positive(value["mass"], path + "/mass"));
    } else {
      body.mass = mass_properties_from_density(*body.shape,
                                               r.positive(value["density"], path + "/density"));
    }
  } else {
    body.mass = infinite_mass_properties();
  }

  if (value.contains("position")) body.state.x_W = r.vec3(value["position"], path + "/position");
  if (value.contains("orientation")) {
    body.state.q_WM = r.quaternion(value["orientation"], path + "/orientation");
  }
  if (value.contains("velocity")) body.state.v_W = r.vec3(value["velocity"], path + "/velocity");
  if (value.contains("angular_velocity")) {
    body.state.w_W = r.vec3(value["angular_velocity"], path + "/angular_velocity");
  }
  if (body.motion == MotionKind::kFixed &&
      (body.state.v_W.norm() != 0.0 || body.state.w_W.norm() != 0.0)) {
    r.fail(path, "a fixed body cannot have a velocity; use a kinematic motion");
  }
  if (body.motion == MotionKind::kKinematic &&
      (value.contains("velocity") || value.contains("angular_velocity"))) {
    r.fail(path,
           "a kinematic body's velocities come from its \"motion\"; remove \"velocity\" / "
           "\"angular_velocity\"");
  }
  return body;
}

}  // namespace

// Ranges that depend on more than one value, checked before anything runs: a run that could
// only hang, or silently throw bodies about, is bad input.
void check_ranges(const Reader& r, const json& doc, const Scene& scene) {
  const Settings& s = scene.world.settings;
  double smallest = kInfinity, extent = 1.0;
  for (const Body& b : scene.world.bodies) {
    const double radius = b.shape ? max_radius(*b.shape) : 0.0;
    if (std::isfinite(radius)) extent = std::max(extent, b.state.x_W.norm() + radius);
    if (b.is_dynamic() && radius > 0.0) smallest = std::min(smallest, radius);
  }
  // Each body's numbers within what the doubles carry through a collision (a mass of 1e-300
  // makes an inertia that underflows; a speed of 1e300 an energy that overflows) and what the
  // clock can resolve (positions).
  const json& bodies = doc["bodies"];
  for (std::size_t i = 0; i < scene.world.bodies.size(); ++i) {
    const Body& b = scene.world.bodies[i];
    const std::string path = "/bodies/" + std::to_string(i);
    const json& body = bodies[i];
    auto at = [&](const char* key) { return body.contains(key) ? body[key] : json(); };
    if (b.is_dynamic()) {
      const char* key = body.contains("mass") ? "mass" : "density";
      if (!(b.mass.mass >= kMinMass && b.mass.mass <= kMaxMass)) {
        const std::string made = body.contains("mass")
                                     ? ""
                                     : " (this density makes " + json(b.mass.mass).dump() + " kg)";
        r.fail_value(path + "/" + key, at(key), "a mass from 1e-20 to 1e20 kg" + made);
      }
    }
    if (!(b.state.x_W.norm() <= kMaxPosition)) {
      r.fail_value(path + "/position", at("position"), "a position within 1e9 m of the origin");
    }
    const bool kinematic = b.motion == MotionKind::kKinematic;
    const Vec3 v = kinematic ? b.kinematic.velocity_W : b.state.v_W;
    const Vec3 w = kinematic ? b.kinematic.angular_velocity_W : b.state.w_W;
    const std::string motion = kinematic ? path + "/motion/kinematic" : path;
    const json& motion_json = kinematic ? body["motion"]["kinematic"] : body;
    auto motion_at = [&](const char* key) {
      return motion_json.contains(key) ? motion_json[key] : json();
    };
    if (!(v.norm() <= kMaxSpeed)) {
      r.fail_value(motion + "/velocity", motion_at("velocity"), "a speed of at most 1e6 m/s");
    }
    if (!(w.norm() <= kMaxAngularSpeed)) {
      r.fail_value(motion + "/angular_velocity", motion_at("angular_velocity"),
                   "an angular speed of at most 1e9 rad/s");
    }
    if (kinematic && !(b.kinematic.point_W.norm() <= kMaxPosition)) {
      r.fail_value(motion + "/point", motion_at("point"), "a point within 1e9 m of the origin");
    }
    // The speed of the body's fastest point, not only of its centre: a platter (a halfspace)
    // turning at 7e8 rad/s about a level axis, under the angular limit, moved the plane under the
    // ball at 1e8 m/s, and the ball overlapped it at every other collision (found by
    // fuzz_engine). A kinematic body turns about `point`; an unbounded one counts where the
    // other bodies are (within `extent` of the origin).
    const double reach = b.shape ? max_radius(*b.shape) : 0.0;
    const Vec3 axis_point = kinematic ? b.kinematic.point_W : b.state.x_W;
    const double lever = std::isfinite(reach) ? reach + (b.state.x_W - axis_point).norm()
                                              : extent + axis_point.norm();
    // (A lever that is not finite comes from a position out of range: that body's check names it.)
    if (std::isfinite(lever) && !(v.norm() + w.norm() * lever <= kMaxSpeed)) {
      r.fail_value(motion + "/angular_velocity", motion_at("angular_velocity"),
                   "an angular speed that moves no point of the body faster than 1e6 m/s (at " +
                       json(lever).dump() + " m from the axis: at most " +
                       json((kMaxSpeed - v.norm()) / lever).dump() + " rad/s)");
    }
  }
  const json& settings = doc.contains("settings") ? doc["settings"] : json::object();
  auto value = [&](const char* key) { return settings.contains(key) ? settings[key] : json(); };
  // The envelope detects contact: larger than half the smallest dynamic body, a microcollision
  // train throws it about; below the rounding of the scene's coordinates, the clock cannot move.
  if (std::isfinite(smallest) && s.envelope_m > 0.5 * smallest) {
    r.fail_value("/settings/envelope", value("envelope"),
                 "at most half the smallest dynamic body's radius (" +
                     std::to_string(0.5 * smallest) + " m)");
  }
  if (s.envelope_m < 1e-13 * extent) {
    r.fail_value("/settings/envelope", value("envelope"),
                 "at least 1e-13 of the scene's extent (" + std::to_string(1e-13 * extent) +
                     " m): below it rounding of the positions decides contact");
  }
  if (s.microcollision_speed_mps && *s.microcollision_speed_mps > 100.0) {
    r.fail_value("/settings/microcollision_speed", value("microcollision_speed"),
                 "at most 100 m/s (every resting contact rebounds at it)");
  }
  if (s.broad_phase_horizon_s < 1e-9) {
    r.fail_value("/settings/broad_phase_horizon", value("broad_phase_horizon"),
                 "at least 1e-9 s (a body's swept box is refreshed every horizon)");
  }
  const double g = scene.world.gravity_W.norm();
  if (g > 1e6) {
    r.fail_value("/gravity", doc.value("gravity", json()), "a magnitude of at most 1e6 m/s^2");
  }
  if (scene.end_time > kMaxEndTime) {
    r.fail_value("/end_time", doc["end_time"],
                 "at most 1e9 s (the event clock resolves 1e-12 of the time)");
  }
  if (scene.output_interval > 0.0 && scene.end_time / scene.output_interval > kMaxSamples) {
    r.fail_value("/output/interval", doc["output"]["interval"],
                 "at least end_time / 1e9 (" + std::to_string(scene.end_time / 1e9) +
                     " s): more than 1e9 samples");
  }
}

Scene scene_from_json(const json& document, const std::string& source) {
  // Scene parameters first: every "=expression" becomes its number.
  const json doc = expand_parameters(document, source);
  Reader r(source);
  r.object(doc, "");
  r.only_keys(doc, "",
              {"format", "name", "description", "parameters", "gravity", "end_time", "output",
               "settings", "materials", "bodies", "reference", "plot"});
  std::string format = r.string(r.required(doc, "", "format"), "/format");
  if (format != "palpable-scene/1") r.fail_value("/format", doc["format"], "\"palpable-scene/1\"");

  Scene scene;
  scene.source = source;
  scene.name = doc.contains("name") ? r.string(doc["name"], "/name") : source;
  if (doc.contains("description")) r.string(doc["description"], "/description");
  if (doc.contains("plot")) {
    const auto& kinds = scene_plot_kinds();
    scene.plot = doc["plot"].is_string() ? doc["plot"].get<std::string>() : std::string();
    if (std::find(kinds.begin(), kinds.end(), scene.plot) == kinds.end()) {
      std::string expected;
      for (const std::string& k : kinds)
        expected += (expected.empty() ? "one of \"" : ", \"") + k + "\"";
      r.fail_value("/plot", doc["plot"],
                   expected + " (the picture palpable plot --kind auto draws)");
    }
  }
  if (doc.contains("gravity")) scene.world.gravity_W = r.vec3(doc["gravity"], "/gravity");
  scene.end_time = r.positive(r.required(doc, "", "end_time"), "/end_time");

  if (doc.contains("output")) {
    const json& out = r.object(doc["output"], "/output");
    r.only_keys(out, "/output", {"interval"});
    if (out.contains("interval"))
      scene.output_interval = r.positive(out["interval"], "/output/interval");
  }
  if (doc.contains("settings"))
    parse_settings(r, doc["settings"], "/settings", scene.world.settings);

  const json& bodies = r.required(doc, "", "bodies");
  if (!bodies.is_array() || bodies.empty())
    r.fail_value("/bodies", bodies, "a non-empty array of bodies");
  std::set<std::string> names;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    std::string path = "/bodies/" + std::to_string(i);
    Body body = parse_body(r, bodies[i], path);
    if (!names.insert(body.name).second) {
      r.fail_value(path + "/name", bodies[i]["name"], "a name no other body has");
    }
    scene.world.bodies.push_back(std::move(body));
  }

  if (doc.contains("materials")) {
    const json& materials = r.object(doc["materials"], "/materials");
    r.only_keys(materials, "/materials", {"default", "pairs"});
    if (materials.contains("default")) {
      scene.world.default_material = parse_material(r, materials["default"], "/materials/default",
                                                    scene.world.default_material, false);
    }
    if (materials.contains("pairs")) {
      const json& pairs = materials["pairs"];
      if (!pairs.is_array()) r.fail_value("/materials/pairs", pairs, "an array");
      for (std::size_t i = 0; i < pairs.size(); ++i) {
        std::string path = "/materials/pairs/" + std::to_string(i);
        PairMaterial pm;
        pm.material = parse_material(r, pairs[i], path, scene.world.default_material, true);
        const json& names_json = r.required(pairs[i], path, "bodies");
        if (!names_json.is_array() || names_json.size() != 2) {
          r.fail_value(path + "/bodies", names_json, "an array of two body names");
        }
        BodyId ids[2];
        for (int k = 0; k < 2; ++k) {
          std::string name = r.string(names_json[k], path + "/bodies/" + std::to_string(k));
          if (name == "*" && k == 1) continue;  // the first body with every other body
          ids[k] = scene.world.find_body(name);
          if (!ids[k].valid()) {
            r.fail_value(path + "/bodies/" + std::to_string(k), names_json[k],
                         k == 0 ? "the name of a body in /bodies"
                                : "the name of a body in /bodies, or \"*\" for every other body");
          }
        }
        if (ids[0] == ids[1]) r.fail_value(path + "/bodies", names_json, "two different bodies");
        pm.a = ids[0];
        pm.b = ids[1];
        scene.world.pair_materials.push_back(pm);
      }
    }
  }
  if (doc.contains("reference")) {
    // Checked whole before anything runs: a bad reference must not cost a run.
    std::vector<std::string> names;
    for (const Body& b : scene.world.bodies) names.push_back(b.name);
    validate_reference(doc["reference"], source + ":/reference", names, false);
    scene.reference = complete_reference(doc["reference"], source + ":/reference", scene.world);
    validate_reference(scene.reference, source + ":/reference", names, true);
  }
  check_ranges(r, doc, scene);
  return scene;
}

std::string read_text_file(const std::string& path) {
  std::ostringstream text;
  if (path == "-") {
    text << std::cin.rdbuf();
  } else {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      throw InputError(path, "is a directory, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "cannot open file");
    text << in.rdbuf();
  }
  return text.str();
}

json read_json_file(const std::string& path) {
  return parse_json_text(read_text_file(path), path);
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides,
                 std::string* text) {
  std::string bytes = read_text_file(path);
  json document = parse_json_text(bytes, path);
  for (const std::string& assignment : overrides) apply_override(document, assignment);
  Scene scene = scene_from_json(document, path);
  if (text) *text = std::move(bytes);
  return scene;
}

void apply_override(json& doc, const std::string& assignment) {
  auto eq = assignment.find('=');
  if (eq == std::string::npos || assignment.empty() || assignment[0] != '/') {
    throw InputError("--set " + assignment, "expected /json/pointer=value (RFC 6901 pointer)");
  }
  std::string pointer_text = assignment.substr(0, eq);
  std::string value_text = assignment.substr(eq + 1);
  const json value = parse_command_line_value(value_text, "--set " + assignment);
  try {
    json::json_pointer pointer(pointer_text);
    // Missing optional objects on the way are created (`/settings/envelope` on a scene with no
    // "settings"); the scene parser then checks every key, so a misspelt one is still named.
    std::vector<json::json_pointer> ancestors;
    for (json::json_pointer q = pointer.parent_pointer(); !q.empty(); q = q.parent_pointer()) {
      ancestors.push_back(q);
    }
    for (auto q = ancestors.rbegin(); q != ancestors.rend(); ++q) {
      json& container = doc.at(q->parent_pointer());
      if (container.is_object() && !container.contains(q->back())) {
        container[q->back()] = json::object();
      }
    }
    json& parent = doc.at(pointer.parent_pointer());
    if (parent.is_array()) {
      const std::string& last = pointer.back();
      if (last != "-") {
        std::size_t index = std::stoul(last);
        if (index >= parent.size()) {
          throw InputError("--set " + assignment, "index " + last +
                                                      " is past the end of the array at " +
                                                      pointer.parent_pointer().to_string());
        }
      }
    } else if (!parent.is_object()) {
      throw InputError("--set " + assignment,
                       pointer.parent_pointer().to_string() + " is not an object or array");
    }
    doc[pointer] = value;
  } catch (const json::exception& e) {
    throw InputError("--set " + assignment, std::string("no such place in the scene: ") + e.what());
  } catch (const std::invalid_argument&) {
    throw InputError("--set " + assignment, "array index is not a number");
  }
}

json settings_json(const Settings& settings, double gravity_mps2) {
  json out = json::object();
  for (const SettingInfo& info : settings_table()) {
    const SettingValue v = info.get(settings);
    json& slot = out[std::string(info.key)];
    std::visit([&slot](const auto& x) { slot = x; }, v);
  }
  json derived = json::object();
  for (const DerivedSetting& d : derived_settings(settings, gravity_mps2)) {
    derived[std::string(d.name)] = d.value;
  }
  out["derived"] = derived;
  return out;
}

}  // namespace palpable
