// `palpable view`: one self-contained HTML page that plays a run in 3-D in the browser — every
// body's real shape from the scene, the trace's motion (downsampled to the display rate), the
// collisions from the events as arrows at their instants — with three.js from Debian's libjs-three
// inlined (no network, no server). The page is tools/view/viewer.html, compiled in; its data is
// written into it as JSON.
#include "core/check.hpp"
#include "core/shape.hpp"
#include "scenarios/json_reader.hpp"
#include "scenarios/scene.hpp"
#include "scenarios/trace.hpp"
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/viewer_page.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

namespace palpable::tools {
namespace {

using nlohmann::json;

json vec(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

// A shape as the page draws it: spheres, triangle meshes (polyhedra, and the smooth shapes
// tessellated), planes, groups.
json shape_json(const Shape& shape) {
  if (const Sphere* s = std::get_if<Sphere>(&shape))
    return {{"type", "sphere"}, {"radius", s->radius}};
  if (const Halfspace* h = std::get_if<Halfspace>(&shape)) {
    return {{"type", "plane"}, {"normal", vec(h->normal_M)}, {"offset", h->offset}};
  }
  if (const ConvexPolyhedron* p = std::get_if<ConvexPolyhedron>(&shape)) {
    json vertices = json::array(), triangles = json::array();
    for (const Vec3& v : p->vertices()) vertices.push_back(vec(v));
    const auto& he = p->half_edges();
    for (const PolyFace& f : p->faces()) {
      std::vector<int> loop;
      int h = f.half_edge;
      do {
        loop.push_back(he[h].tail);
        h = he[h].next;
      } while (h != f.half_edge && loop.size() < he.size());
      for (std::size_t k = 1; k + 1 < loop.size(); ++k) {
        triangles.push_back({loop[0], loop[k], loop[k + 1]});
      }
    }
    return {{"type", "mesh"}, {"vertices", vertices}, {"triangles", triangles}};
  }
  if (is_smooth_convex(shape)) {
    // A latitude-longitude grid of directions (no ring on the equator) mapped to the support
    // points: exact surface points, and the cylinder's flat caps and wall and the capsule's wall
    // come out of the triangles between the last northern and the first southern ring.
    constexpr int kRings = 24, kPerRing = 48;
    constexpr double kPi = 3.14159265358979323846;
    json vertices = json::array(), triangles = json::array();
    vertices.push_back(vec(smooth_support_M(shape, Vec3::UnitZ())));
    for (int i = 0; i < kRings; ++i) {
      const double theta = kPi * (i + 0.5) / kRings;
      for (int j = 0; j < kPerRing; ++j) {
        const double phi = 2.0 * kPi * j / kPerRing;
        const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                     std::cos(theta));
        vertices.push_back(vec(smooth_support_M(shape, d)));
      }
    }
    const int south = 1 + kRings * kPerRing;
    vertices.push_back(vec(smooth_support_M(shape, -Vec3::UnitZ())));
    auto at = [](int ring, int j) { return 1 + ring * kPerRing + (j % kPerRing); };
    for (int j = 0; j < kPerRing; ++j) {
      triangles.push_back({0, at(0, j), at(0, j + 1)});
      triangles.push_back({south, at(kRings - 1, j + 1), at(kRings - 1, j)});
      for (int i = 0; i + 1 < kRings; ++i) {
        triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
    return {{"type", "mesh"}, {"vertices", vertices}, {"triangles", triangles}};
  }
  const Compound& c = std::get<Compound>(shape);
  json parts = json::array();
  for (const CompoundPart& part : c.parts) {
    parts.push_back(
        {{"shape", shape_json(*part.shape)},
         {"position", vec(part.position_M)},
         {"orientation", json::array({part.orientation_M.w(), part.orientation_M.x(),
                                      part.orientation_M.y(), part.orientation_M.z()})}});
  }
  return {{"type", "group"}, {"parts", parts}};
}

// `v` to `digits` significant digits: the page needs no more, and the file is a third the size.
double rounded(double v, int digits) {
  if (v == 0.0 || !std::isfinite(v)) return v;
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return std::strtod(text, nullptr);
}

// The samples shown at `fps` frames per simulated second: for each display instant, the first
// sample at or after it, and the last sample (every sample when the trace is no denser).
std::vector<std::size_t> display_samples(const std::vector<double>& times, double fps) {
  std::vector<std::size_t> kept;
  double next = times.front();
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (times[k] >= next - 1e-12 || k + 1 == times.size()) {
      kept.push_back(k);
      while (next <= times[k] + 1e-12) next += 1.0 / fps;
    }
  }
  return kept;
}

// Per sample and body (samples[k * bodies + b]): bit 0, at rest (moved less than 0.5 mm and
// turned less than 0.01 rad over the last 0.1 s); bit 1, in persistent contact (held by the
// persistent model, or touched by a microcollision in the last 30 ms).
std::vector<std::uint8_t> body_marks(const Trace& trace) {
  const std::size_t n = trace.body_names.size(), samples = trace.times.size();
  std::vector<std::uint8_t> marks(samples * n, 0);
  std::size_t back = 0;  // the first sample within 0.1 s before sample k
  for (std::size_t k = 0; k < samples; ++k) {
    while (trace.times[k] - trace.times[back] > 0.1 + 1e-12) ++back;
    if (trace.times[k] - trace.times[0] < 0.1 - 1e-12) continue;
    for (std::size_t b = 0; b < n; ++b) {
      bool still = true;
      for (std::size_t i = back; i < k && still; ++i) {
        const BodyState &a = trace.samples[i][b], &z = trace.samples[k][b];
        still = (a.x_W - z.x_W).norm() < 5e-4 && a.q_WM.angularDistance(z.q_WM) < 0.01;
      }
      if (still) marks[k * n + b] |= 1;
    }
  }
  std::vector<int> holds(n, 0);  // held contacts per body
  std::size_t h = 0, c = 0;
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = trace.times[k];
    for (; h < trace.held.size() && trace.held[h].t <= t; ++h) {
      const HeldEvent& e = trace.held[h];
      const int change = e.kind == "hold"                                ? 1
                         : (e.kind == "release" || e.kind == "lift_off") ? -1
                                                                         : 0;
      holds[e.body_a] = std::max(0, holds[e.body_a] + change);
      holds[e.body_b] = std::max(0, holds[e.body_b] + change);
    }
    while (c < trace.contacts.size() && trace.contacts[c].t < t - 0.03) ++c;
    for (std::size_t i = c; i < trace.contacts.size() && trace.contacts[i].t <= t; ++i) {
      if (!trace.contacts[i].micro) continue;
      marks[k * n + trace.contacts[i].body_a] |= 2;
      marks[k * n + trace.contacts[i].body_b] |= 2;
    }
    for (std::size_t b = 0; b < n; ++b) {
      if (holds[b] > 0) marks[k * n + b] |= 2;
    }
  }
  return marks;
}

struct ViewOptions {
  std::string trace, scene, events, out, three = "/usr/share/javascript/three/three.min.js";
  double fps = 60.0;
};

int make_view(const ViewOptions& o) {
  if (o.out.empty()) throw InputError("--out", "required: the HTML file to write");
  const Scene scene = load_scene(o.scene);
  Trace trace = read_trace_csv(o.trace);
  if (!o.events.empty()) read_events_csv(o.events, trace);
  if (trace.times.empty()) throw InputError(o.trace, "the trace has no samples");
  if (::access(o.three.c_str(), R_OK) != 0) {
    throw InputError(o.three,
                     "cannot read three.js: install the Debian package libjs-three "
                     "(tools/setup does)");
  }
  const std::string three = read_text_file(o.three);
  const std::string page = kViewerPage;

  json data;
  data["scene"] = scene.name;
  json bodies = json::array();
  for (const std::string& name : trace.body_names) {
    const BodyId id = scene.world.find_body(name);
    if (!id.valid()) throw InputError(o.trace, "body \"" + name + "\" is not in " + o.scene);
    const Body& b = scene.world.bodies[id.index];
    bodies.push_back({{"name", name},
                      {"motion", b.is_dynamic() ? "dynamic" : "fixed"},
                      {"shape", shape_json(*b.shape)}});
  }
  data["bodies"] = bodies;
  const std::vector<std::uint8_t> marks = body_marks(trace);
  const std::size_t n = trace.body_names.size();
  json times = json::array(), frames = json::array();
  for (std::size_t k : display_samples(trace.times, o.fps)) {
    times.push_back(rounded(trace.times[k], 9));
    json f = json::array();
    for (std::size_t b = 0; b < n; ++b) {
      const BodyState& s = trace.samples[k][b];
      json row = json::array();
      for (double v :
           {s.x_W.x(), s.x_W.y(), s.x_W.z(), s.q_WM.w(), s.q_WM.x(), s.q_WM.y(), s.q_WM.z(),
            s.v_W.x(), s.v_W.y(), s.v_W.z(), s.w_W.x(), s.w_W.y(), s.w_W.z()}) {
        row.push_back(rounded(v, 6));
      }
      row.push_back(marks[k * n + b]);
      f.push_back(row);
    }
    frames.push_back(f);
  }
  data["times"] = times;
  data["frames"] = frames;
  json contacts = json::array();
  for (const ContactEvent& c : trace.contacts) {
    contacts.push_back({rounded(c.t, 9), c.body_a, c.body_b, rounded(c.p_W.x(), 6),
                        rounded(c.p_W.y(), 6), rounded(c.p_W.z(), 6), rounded(c.j_W.x(), 4),
                        rounded(c.j_W.y(), 4), rounded(c.j_W.z(), 4), c.micro ? 1 : 0});
  }
  data["contacts"] = contacts;

  std::string html = page;
  auto replace = [&html](const std::string& marker, const std::string& with) {
    const auto at = html.find(marker);
    PALPABLE_CHECK(at != std::string::npos, "viewer template without " + marker);
    html.replace(at, marker.size(), with);
  };
  replace("/*THREE_JS*/", three);
  replace("/*DATA*/", data.dump());
  AtomicFile out(o.out);
  out.stream() << html;
  out.commit();
  std::cerr << "view: " << o.out << " (" << html.size() << " bytes, " << times.size() << " frames, "
            << trace.body_names.size() << " bodies)\n";
  return kExitOk;
}

CommandRegistration reg{
    "view", [](CLI::App& app) {
      app.description(
          "Write one self-contained HTML page that plays a run in 3-D (three.js inlined from "
          "Debian's libjs-three: no network, no server): every body's shape from the scene, the "
          "trace's motion downsampled to the display rate, collisions from --events as arrows at "
          "their instants. Play/pause, step, scrub, speed; drag to orbit, wheel to zoom; follow a "
          "body and read its position, velocity and spin. Open #t=SECONDS in the URL to show a "
          "given instant, paused.");
      auto o = std::make_shared<ViewOptions>();
      app.add_option("trace", o->trace, "Trace CSV of the run (palpable run --trace)")->required();
      app.add_option("--scene", o->scene, "The scene the run was made from")->required();
      app.add_option("--events", o->events, "Events CSV (palpable run --events): contact arrows");
      app.add_option("--out", o->out, "The HTML file to write")->required();
      app.add_option("--fps", o->fps, "Samples kept per simulated second (default 60)")
          ->check(CLI::Range(1.0, 10000.0));
      return std::function<int()>([o] { return make_view(*o); });
    }};

}  // namespace
}  // namespace palpable::tools
