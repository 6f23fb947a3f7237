#include "scenarios/trace.hpp"

#include "core/check.hpp"
#include "scenarios/json_reader.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>

namespace palpable {

std::size_t Trace::body_index(const std::string& name, const std::string& where) const {
  for (std::size_t i = 0; i < body_names.size(); ++i) {
    if (body_names[i] == name) return i;
  }
  std::string known;
  for (const auto& n : body_names) known += (known.empty() ? "" : ", ") + n;
  throw InputError(where, "no body \"" + name + "\" in the trace (bodies: " + known + ")");
}

std::vector<BodyState> Trace::series(std::size_t body) const {
  std::vector<BodyState> out;
  out.reserve(samples.size());
  for (const auto& s : samples) out.push_back(s[body]);
  return out;
}

namespace {
// A CSV field for an error message: at most 40 bytes, and valid UTF-8 or replaced by "?".
std::string describe_field(const std::string& field) {
  std::string text = field.size() > 40 ? field.substr(0, 37) + "..." : field;
  return is_valid_utf8(text) ? text : "?";
}

void put(std::ostream& out, double x) {
  char buffer[32];
  auto result = std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::general, 17);
  out.write(buffer, result.ptr - buffer);
}
}  // namespace

void write_trace_rows(std::ostream& out, double t, const std::vector<std::string>& names,
                      const std::vector<BodyState>& states, const std::vector<bool>* skip) {
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (skip && (*skip)[i]) continue;
    const BodyState& s = states[i];
    put(out, t);
    out << ',' << names[i];
    const double values[] = {s.x_W.x(),  s.x_W.y(),  s.x_W.z(), s.q_WM.w(), s.q_WM.x(),
                             s.q_WM.y(), s.q_WM.z(), s.v_W.x(), s.v_W.y(),  s.v_W.z(),
                             s.w_W.x(),  s.w_W.y(),  s.w_W.z()};
    for (double v : values) {
      out << ',';
      put(out, v);
    }
    out << '\n';
  }
}

namespace {
// A directory opens as an empty stream: say what it is rather than that its header is wrong.
void refuse_directory(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "is a directory, not a file");
}
}  // namespace

Trace read_trace_csv(const std::string& path) {
  refuse_directory(path);
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open trace file");
  std::string line;
  if (!std::getline(in, line) || line.rfind(kTraceHeader, 0) != 0) {
    throw InputError(path + ":1",
                     std::string("expected the trace header \"") + kTraceHeader + "\"");
  }
  Trace trace;
  std::map<std::string, std::size_t> index;
  std::size_t line_number = 1;
  double current_t = std::nan("");
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (fields.size() < 15) {
      throw InputError(path + ":" + std::to_string(line_number), "expected at least 15 columns");
    }
    double v[14];
    for (int k = 0; k < 14; ++k) {
      const std::string& f = fields[k == 0 ? 0 : k + 1];
      auto result = std::from_chars(f.data(), f.data() + f.size(), v[k]);
      // from_chars reads "nan" and "inf": a trace holds finite numbers only.
      if (result.ec != std::errc() || result.ptr != f.data() + f.size() || !std::isfinite(v[k])) {
        throw InputError(path + ":" + std::to_string(line_number),
                         "not a finite number: \"" + describe_field(f) + "\"");
      }
    }
    const std::string& name = fields[1];
    if (name.empty() || !is_valid_utf8(name)) {
      throw InputError(path + ":" + std::to_string(line_number),
                       "a body name is non-empty UTF-8 text");
    }
    if (trace.times.empty() || v[0] != current_t) {
      if (!trace.times.empty() && !(v[0] > current_t)) {
        throw InputError(path + ":" + std::to_string(line_number), "time runs backwards");
      }
      current_t = v[0];
      trace.times.push_back(current_t);
      // A body a sample leaves out (a fixed body, written in the first sample only) keeps its
      // state from the sample before.
      if (trace.samples.empty()) {
        trace.samples.emplace_back(trace.body_names.size());
      } else {
        trace.samples.push_back(trace.samples.back());
        for (BodyState& s : trace.samples.back()) s.t = current_t;
      }
    }
    auto it = index.find(name);
    if (it == index.end()) {
      if (trace.times.size() > 1) {
        throw InputError(path + ":" + std::to_string(line_number),
                         "body \"" + name + "\" first appears after the first sample");
      }
      it = index.emplace(name, trace.body_names.size()).first;
      trace.body_names.push_back(name);
      trace.samples.back().emplace_back();
    }
    BodyState& s = trace.samples.back()[it->second];
    s.t = v[0];
    s.x_W = Vec3(v[1], v[2], v[3]);
    s.q_WM = Quat(v[4], v[5], v[6], v[7]);
    s.v_W = Vec3(v[8], v[9], v[10]);
    s.w_W = Vec3(v[11], v[12], v[13]);
  }
  if (trace.times.empty()) throw InputError(path, "the trace has no samples");
  return trace;
}

void read_events_csv(const std::string& path, Trace& trace) {
  static constexpr const char* kEventsHeader = "t,kind,body_a,body_b,px,py,pz";
  static constexpr const char* kImpulseHeader = "t,kind,body_a,body_b,px,py,pz,nx,ny,nz,jx,jy,jz";
  refuse_directory(path);
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open events file");
  std::string line;
  if (!std::getline(in, line) || line.rfind(kEventsHeader, 0) != 0) {
    throw InputError(path + ":1",
                     std::string("expected the events header \"") + kEventsHeader + ",...\"");
  }
  const bool impulses = line.rfind(kImpulseHeader, 0) == 0;
  const std::size_t numbers = impulses ? 10 : 4;  // t, p, then n and j
  std::vector<ContactEvent> contacts;
  std::vector<HeldEvent> held;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_number);
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (fields.size() < numbers + 3) {
      throw InputError(where, "expected at least " + std::to_string(numbers + 3) + " columns");
    }
    double v[10];
    for (std::size_t k = 0; k < numbers; ++k) {
      const std::string& f = fields[k == 0 ? 0 : k + 3];
      auto result = std::from_chars(f.data(), f.data() + f.size(), v[k]);
      if (result.ec != std::errc() || result.ptr != f.data() + f.size() || !std::isfinite(v[k])) {
        throw InputError(where, "not a finite number: \"" + describe_field(f) + "\"");
      }
    }
    const std::size_t a = trace.body_index(fields[2], where + " body_a");
    const std::size_t b = trace.body_index(fields[3], where + " body_b");
    // Only collisions touch: the rows of held contacts changing mode (hold, stick, ...) do not.
    if (fields[1] != "collision" && fields[1] != "microcollision") {
      if (!held.empty() && v[0] < held.back().t) throw InputError(where, "time runs backwards");
      held.push_back(HeldEvent{v[0], fields[1], a, b});
      continue;
    }
    ContactEvent c;
    c.t = v[0];
    c.body_a = a;
    c.body_b = b;
    c.p_W = Vec3(v[1], v[2], v[3]);
    if (impulses) {
      c.n_W = Vec3(v[4], v[5], v[6]);
      c.j_W = Vec3(v[7], v[8], v[9]);
    }
    c.micro = fields[1] == "microcollision";
    if (!contacts.empty() && c.t < contacts.back().t)
      throw InputError(where, "time runs backwards");
    contacts.push_back(c);
  }
  trace.contacts = std::move(contacts);
  trace.held = std::move(held);
}

}  // namespace palpable
