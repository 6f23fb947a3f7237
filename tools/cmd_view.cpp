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
#include <iostream>
#include <memory>
#include <string>

#include <unistd.h>

namespace palpable::tools {
namespace {

using nlohmann::json;

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

// A shape as the page draws it: spheres, triangle meshes (polyhedra), planes, groups.
json shape_json(const Shape& shape) {
  if (const Sphere* s = std::get_if<Sphere>(&shape)) return {{"type", "sphere"}, {"radius", s->radius}};
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
  const Compound& c = std::get<Compound>(shape);
  json parts = json::array();
  for (const CompoundPart& part : c.parts) {
    parts.push_back({{"shape", shape_json(*part.shape)},
                     {"position", vec(part.position_M)},
                     {"orientation", json::array({part.orientation_M.w(), part.orientation_M.x(),
                                                  part.orientation_M.y(), part.orientation_M.z()})}});
  }
  return {{"type", "group"}, {"parts", parts}};
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
    throw InputError(o.three, "cannot read three.js: install the Debian package libjs-three "
                              "(tools/setup does)");
  }
  const std::string three = read_text_file(o.three);
  const std::string page = kViewerPage;

  json data;
  data["scene"] = scene.name;
  json bodies = json::array();
  for (const std::string& name : trace.body_names) {
    const BodyId id = scene.world.find_body(name);
    const Body& b = scene.world.bodies[id.index];
    bodies.push_back({{"name", name},
                      {"motion", b.is_dynamic() ? "dynamic" : "fixed"},
                      {"shape", shape_json(*b.shape)}});
  }
  data["bodies"] = bodies;
  // Downsampled to the display rate: at most fps samples per simulated second.
  const double span = trace.times.back() - trace.times.front();
  const std::size_t wanted = static_cast<std::size_t>(std::ceil(span * o.fps)) + 1;
  const std::size_t stride = std::max<std::size_t>(1, trace.times.size() / std::max<std::size_t>(wanted, 1));
  json times = json::array(), frames = json::array();
  for (std::size_t k = 0; k < trace.times.size(); k += stride) {
    times.push_back(trace.times[k]);
    json f = json::array();
    for (const BodyState& s : trace.samples[k]) {
      f.push_back({s.x_W.x(), s.x_W.y(), s.x_W.z(), s.q_WM.w(), s.q_WM.x(), s.q_WM.y(), s.q_WM.z(),
                   s.v_W.x(), s.v_W.y(), s.v_W.z(), s.w_W.x(), s.w_W.y(), s.w_W.z()});
    }
    frames.push_back(f);
  }
  data["times"] = times;
  data["frames"] = frames;
  json contacts = json::array();
  for (const ContactEvent& c : trace.contacts) {
    contacts.push_back({c.t, c.body_a, c.body_b, c.p_W.x(), c.p_W.y(), c.p_W.z()});
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
  std::cerr << "view: " << o.out << " (" << html.size() << " bytes, " << times.size()
            << " frames, " << trace.body_names.size() << " bodies)\n";
  return kExitOk;
}

CommandRegistration reg{"view", [](CLI::App& app) {
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
