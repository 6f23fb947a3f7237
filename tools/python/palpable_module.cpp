// The compiled half of the Python module `palpable` (tools/python/package/__init__.py is the
// other): runs scenes through `palpable run`'s own code path, steps a Simulation, resolves one
// impact. Errors in the input arrive as palpable.InputError (a ValueError) carrying the same
// file / JSON-pointer message as the command line.
#include "core/check.hpp"
#include "scenarios/json_reader.hpp"
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"
#include "tools/lib/heap.hpp"
#include "tools/lib/impact_spec.hpp"
#include "tools/lib/run_scene.hpp"
#include "tools/version.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <deque>
#include <limits>
#include <memory>
#include <optional>

namespace py = pybind11;
using namespace pybind11::literals;
using namespace palpable;

namespace {

// nlohmann JSON to a Python object, through Python's json module (exact for every value).
py::object to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

// Through the one JSON reader: its depth and size limits hold here too, and a value it cannot
// read (NaN, inf) is an InputError, not nlohmann's parse error.
nlohmann::json from_python(const py::object& o, const std::string& where) {
  return parse_json_text(py::module_::import("json").attr("dumps")(o).cast<std::string>(), where);
}

// A trace as numpy: t (samples), states (samples x bodies x 13: x y z qw qx qy qz vx vy vz wx wy wz).
py::dict trace_arrays(const Trace& trace) {
  const std::size_t n = trace.times.size(), m = trace.body_names.size();
  py::array_t<double> t(static_cast<py::ssize_t>(n));
  py::array_t<double> states({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(m),
                              static_cast<py::ssize_t>(13)});
  auto tt = t.mutable_unchecked<1>();
  auto s = states.mutable_unchecked<3>();
  for (std::size_t k = 0; k < n; ++k) {
    tt(k) = trace.times[k];
    for (std::size_t b = 0; b < m; ++b) {
      const BodyState& x = trace.samples[k][b];
      const double row[13] = {x.x_W.x(),   x.x_W.y(),   x.x_W.z(),   x.q_WM.w(), x.q_WM.x(),
                              x.q_WM.y(),  x.q_WM.z(),  x.v_W.x(),   x.v_W.y(),  x.v_W.z(),
                              x.w_W.x(),   x.w_W.y(),   x.w_W.z()};
      for (int c = 0; c < 13; ++c) s(k, b, c) = row[c];
    }
  }
  py::dict out;
  out["t"] = t;
  out["bodies"] = trace.body_names;
  out["states"] = states;
  return out;
}

// A run's events, kept in C++ and turned into numpy columns only when asked (a fine envelope
// makes hundreds of thousands of them; a run whose events are not read pays nothing for them).
class EventTable {
 public:
  EventTable(std::deque<tools::EventRow> rows, std::vector<std::string> names)
      : rows_(std::move(rows)), names_(std::move(names)) {}
  std::size_t size() const { return rows_.size(); }
  // The columns of the events CSV, each a numpy array (kind, body_a, body_b, phases: str).
  py::dict columns() const {
    const auto n = static_cast<py::ssize_t>(rows_.size());
    py::dict out;
    auto numbers = [&](const char* name, auto get) {
      py::array_t<double> a(n);
      auto m = a.mutable_unchecked<1>();
      for (py::ssize_t k = 0; k < n; ++k) m(k) = get(rows_[static_cast<std::size_t>(k)]);
      out[name] = a;
    };
    auto strings = [&](const char* name, auto get) {
      py::list l(static_cast<std::size_t>(n));
      for (py::ssize_t k = 0; k < n; ++k) {
        l[static_cast<std::size_t>(k)] = py::str(get(rows_[static_cast<std::size_t>(k)]));
      }
      out[name] = py::module_::import("numpy").attr("array")(l, "dtype"_a = "U");
    };
    const double nan = std::numeric_limits<double>::quiet_NaN();
    numbers("t", [](const tools::EventRow& r) { return r.t; });
    strings("kind", [](const tools::EventRow& r) { return std::string(r.kind); });
    strings("body_a", [&](const tools::EventRow& r) { return names_[r.a]; });
    strings("body_b", [&](const tools::EventRow& r) { return names_[r.b]; });
    const char* axes[] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) {
      numbers(("p" + std::string(axes[i])).c_str(), [i](const tools::EventRow& r) { return r.p_W[i]; });
    }
    for (int i = 0; i < 3; ++i) {
      numbers(("n" + std::string(axes[i])).c_str(), [i](const tools::EventRow& r) { return r.n_W[i]; });
    }
    for (int i = 0; i < 3; ++i) {
      numbers(("j" + std::string(axes[i])).c_str(),
              [i](const tools::EventRow& r) { return r.impulse_W[i]; });
    }
    numbers("approach_speed", [](const tools::EventRow& r) { return r.approach_speed; });
    numbers("energy_change", [](const tools::EventRow& r) { return r.energy_change; });
    numbers("centre_of_pressure",
            [](const tools::EventRow& r) { return r.centre_of_pressure ? 1.0 : 0.0; });
    strings("phases", [](const tools::EventRow& r) { return tools::phases_text(r); });
    // Slips and normal impulses: NaN where there are none (mode changes, a group's contacts).
    for (int i = 0; i < 3; ++i) {
      numbers(("slip_before_" + std::string(axes[i])).c_str(), [i, nan](const tools::EventRow& r) {
        return r.detail ? r.slip_before_W[i] : nan;
      });
    }
    for (int i = 0; i < 3; ++i) {
      numbers(("slip_after_" + std::string(axes[i])).c_str(), [i, nan](const tools::EventRow& r) {
        return r.detail ? r.slip_after_W[i] : nan;
      });
    }
    numbers("normal_impulse_compression", [nan](const tools::EventRow& r) {
      return r.detail ? r.normal_impulse_compression : nan;
    });
    numbers("normal_impulse_restitution", [nan](const tools::EventRow& r) {
      return r.detail ? r.normal_impulse_restitution : nan;
    });
    return out;
  }

 private:
  std::deque<tools::EventRow> rows_;
  std::vector<std::string> names_;
};

py::dict run(const std::string& path, const std::vector<std::string>& overrides,
             std::optional<double> end, bool keep_events) {
  tools::RunOptions options;
  options.scene_path = path;
  options.overrides = overrides;
  options.end_time = end;
  options.keep_events = keep_events;
  tools::RunResult r;
  {
    py::gil_scoped_release release;  // the simulation needs no Python
    r = tools::run_scene(options);
  }
  py::dict out = trace_arrays(r.trace);
  out["summary"] = to_python(tools::summary_json(r));
  // Collisions as one array (t, body_a index, body_b index, px, py, pz): a fine envelope makes
  // hundreds of thousands of them, too many for Python objects one by one.
  py::array_t<double> contacts({static_cast<py::ssize_t>(r.trace.contacts.size()),
                                static_cast<py::ssize_t>(6)});
  auto c = contacts.mutable_unchecked<2>();
  for (std::size_t k = 0; k < r.trace.contacts.size(); ++k) {
    const ContactEvent& e = r.trace.contacts[k];
    const double row[6] = {e.t, static_cast<double>(e.body_a), static_cast<double>(e.body_b),
                           e.p_W.x(), e.p_W.y(), e.p_W.z()};
    for (int j = 0; j < 6; ++j) c(k, j) = row[j];
  }
  out["contacts"] = contacts;
  out["events"] = EventTable(std::move(r.events), r.trace.body_names);
  return out;
}

// A simulation to step: load a scene (with overrides), run to a time, read states, run on.
class PySimulation {
 public:
  PySimulation(const std::string& path, const std::vector<std::string>& overrides) {
    scene_ = std::make_unique<Scene>(load_scene(path, overrides));
    sim_ = std::make_unique<Simulation>(scene_->world, SimulationOptions{});
  }
  double time() const { return sim_->time(); }
  double end_time() const { return scene_->end_time; }
  void run_until(double t) {
    py::gil_scoped_release release;
    sim_->run_until(t, nullptr);
  }
  // One event; returns (kind, time) or None when nothing is left before t_end.
  py::object step(double t_end) {
    const StepResult r = sim_->step(t_end, nullptr);
    if (r.done) return py::none();
    static const char* kinds[] = {"pair_check", "island", "horizon", "sample"};
    const int k = static_cast<int>(r.kind);
    return py::make_tuple(k >= 0 && k < 4 ? kinds[k] : "event", r.t,
                          r.collision ? py::bool_(true) : py::bool_(false));
  }
  py::dict state(const std::string& name) const {
    const BodyId id = scene_->world.find_body(name);
    if (!id.valid()) throw py::key_error("no body named \"" + name + "\" in the scene");
    const BodyState s = sim_->state_at(id, sim_->time());
    py::dict d;
    d["x"] = py::make_tuple(s.x_W.x(), s.x_W.y(), s.x_W.z());
    d["q"] = py::make_tuple(s.q_WM.w(), s.q_WM.x(), s.q_WM.y(), s.q_WM.z());
    d["v"] = py::make_tuple(s.v_W.x(), s.v_W.y(), s.v_W.z());
    d["w"] = py::make_tuple(s.w_W.x(), s.w_W.y(), s.w_W.z());
    return d;
  }
  py::object statistics() const {
    const SimulationStats& s = sim_->stats();
    py::dict d;
    d["events"] = s.events;
    d["collisions"] = s.collisions;
    d["microcollisions"] = s.microcollisions;
    d["samples"] = s.samples;
    return d;
  }

 private:
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<Simulation> sim_;
};

}  // namespace

PYBIND11_MODULE(_palpable, m) {
  m.doc() = "Palpable: impulse-based, event-driven rigid-body simulation (compiled core)";
  m.attr("__version__") = tools::kVersion;
  m.attr("commit") = tools::kGitCommit;
  // The Python process's heap keeps what the simulations free, as the command line's does.
  tools::keep_freed_heap();
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    }
  });
  m.def("run", &run, py::arg("path"), py::arg("overrides") = std::vector<std::string>{},
        py::arg("end") = std::nullopt, py::arg("keep_events") = true,
        "Run a scene file through `palpable run`'s code path; returns t, bodies, states "
        "(samples x bodies x 13), contacts and the summary dict.");
  py::class_<EventTable>(m, "EventTable")
      .def("__len__", &EventTable::size)
      .def("columns", &EventTable::columns, "the events CSV's columns as numpy arrays");
  m.def(
      "impact",
      [](const py::object& spec, bool trajectory) {
        const tools::ImpactSpec s = tools::parse_impact_spec(from_python(spec, "spec"));
        std::vector<ImpulsePathPoint> points;
        py::object out = to_python(tools::resolve_impact(s, trajectory ? &points : nullptr));
        if (trajectory) {
          // u(p_z) along the integration: p_z, p_x, p_y, u_x, u_y, u_z (contact frame), the
          // columns of `palpable impact --trajectory`.
          py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{6}});
          auto m = a.mutable_unchecked<2>();
          for (std::size_t k = 0; k < points.size(); ++k) {
            const auto i = static_cast<py::ssize_t>(k);
            const ImpulsePathPoint& q = points[k];
            const double row[6] = {q.p_c.z(), q.p_c.x(), q.p_c.y(), q.u_c.x(), q.u_c.y(), q.u_c.z()};
            for (int c = 0; c < 6; ++c) m(i, c) = row[c];
          }
          out["trajectory"] = a;
        }
        return out;
      },
      py::arg("spec"), py::arg("trajectory") = false,
      "Resolve one collision; the same spec and result as `palpable impact` (with trajectory, "
      "also u(p_z) as an array: p_z, p_x, p_y, u_x, u_y, u_z).");
  py::class_<PySimulation>(m, "Simulation")
      .def(py::init<const std::string&, const std::vector<std::string>&>(), py::arg("path"),
           py::arg("overrides") = std::vector<std::string>{})
      .def_property_readonly("time", &PySimulation::time)
      .def_property_readonly("end_time", &PySimulation::end_time)
      .def("run_until", &PySimulation::run_until, py::arg("t"))
      .def("step", &PySimulation::step, py::arg("t_end"))
      .def("state", &PySimulation::state, py::arg("body"))
      .def("statistics", &PySimulation::statistics);
}
