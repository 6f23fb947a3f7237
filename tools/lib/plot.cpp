#include "tools/lib/plot.hpp"

#include "tools/lib/atomic_file.hpp"

#include "scenarios/reference.hpp"

#include "core/check.hpp"

#include <Eigen/Geometry>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <sstream>

extern char** environ;

namespace palpable::tools {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A temporary directory removed with everything in it when it goes out of scope.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "palpable-plot-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a temporary directory " + pattern);
    }
    path_ = pattern;
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  fs::path path() const { return path_; }

 private:
  fs::path path_;
};

// gnuplot string literal (single quotes; a quote is doubled).
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

std::string body_of(const json& spec) {
  auto it = spec.find("body");
  if (it == spec.end() || !it->is_string()) {
    throw InputError("--param body", "expected the body's name");
  }
  return it->get<std::string>();
}

std::string terminal(int height) {
  return "set terminal pngcairo size 1100," + std::to_string(height) +
         " enhanced font 'DejaVu Sans,11' linewidth 1.5\n";
}

void put(std::ostream& out, double x) {
  out << std::setprecision(12) << x;
}

// Series: positions and velocities of one body against time, two panels.
std::string series_plot(const Trace& trace, const std::string& body_name, const fs::path& dir) {
  std::string name = body_name;
  if (name.empty()) {
    if (trace.body_names.size() != 1) {
      throw InputError("--body", "required: the trace has several bodies");
    }
    name = trace.body_names.front();
  }
  const std::size_t body = trace.body_index(name, "--body");
  std::ofstream data(dir / "data.dat");
  for (std::size_t k = 0; k < trace.times.size(); ++k) {
    const BodyState& s = trace.samples[k][body];
    put(data, trace.times[k]);
    for (double v : {s.x_W.x(), s.x_W.y(), s.x_W.z(), s.v_W.x(), s.v_W.y(), s.v_W.z()}) {
      data << ' ';
      put(data, v);
    }
    data << '\n';
  }
  std::ostringstream gp;
  gp << "set multiplot layout 2,1 title " << quoted("Body \"" + name + "\": centre of mass")
     << "\nset grid\nset key outside right\n"
     << "set title 'Position (world frame)'\nset xlabel 't [s]'\nset ylabel 'position [m]'\n"
     << "plot 'data.dat' u 1:2 w l t 'x', '' u 1:3 w l t 'y', '' u 1:4 w l t 'z'\n"
     << "set title 'Velocity (world frame)'\nset ylabel 'velocity [m/s]'\n"
     << "plot 'data.dat' u 1:5 w l t 'v_x', '' u 1:6 w l t 'v_y', '' u 1:7 w l t 'v_z'\n"
     << "unset multiplot\n";
  return gp.str();
}

// Top view: every body's x-y path (one data block per body), start marked.
std::string top_plot(const Trace& trace, const fs::path& dir) {
  // Bodies that never move (fixed ones, a halfspace's origin) are left out: their "path" is a
  // point that says nothing and may sit far from the action.
  std::vector<std::size_t> moving;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t b = 0; b < trace.body_names.size(); ++b) {
    bool moves = false;
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      moves = moves || trace.samples[k][b].x_W != trace.samples[0][b].x_W;
    }
    if (!moves) continue;
    moving.push_back(b);
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      lo = lo.cwiseMin(trace.samples[k][b].x_W);
      hi = hi.cwiseMax(trace.samples[k][b].x_W);
    }
  }
  if (moving.empty()) throw InputError("trace", "no body moves: nothing to draw in a top view");
  std::ofstream data(dir / "data.dat");
  for (std::size_t i = 0; i < moving.size(); ++i) {
    if (i > 0) data << "\n\n";
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      put(data, trace.samples[k][moving[i]].x_W.x());
      data << ' ';
      put(data, trace.samples[k][moving[i]].x_W.y());
      data << '\n';
    }
  }
  // A true top view has equal axes; a path 5 times longer than wide (a bowling lane) would be a
  // line, so then the axes are scaled apart and the title says so.
  const double width = hi.x() - lo.x(), height = hi.y() - lo.y();
  const bool to_scale = std::max(width, height) <= 5.0 * std::min(width, height);
  std::ostringstream gp;
  gp << "set title "
     << quoted(std::string("Top view: paths of the centres of mass") +
               (to_scale ? "" : " (axes not to scale)"))
     << "\nset grid\n"
     << (to_scale ? "set size ratio -1\n" : "")
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset key outside right\nplot ";
  for (std::size_t i = 0; i < moving.size(); ++i) {
    gp << (i > 0 ? ", " : "") << "'data.dat' index " << i << " w l lc " << i + 1 << " t "
       << quoted(trace.body_names[moving[i]]) << " noenhanced, '' index " << i
       << " every ::0::0 w p pt 7 lc " << i + 1 << " notitle";
  }
  gp << "\n";
  return gp.str();
}

// Incline: along-slope position and velocity against a = g (sin θ − μ cos θ) (DESIGN.md §6),
// stopping at t* = v0 / (-a) when decelerating, at rest throughout when it sticks.
std::string incline_plot(const Trace& trace, const json& spec, const fs::path& dir) {
  const std::size_t body = trace.body_index(body_of(spec), "--param body");
  const InclineMotion motion = incline_motion(spec, "--param");
  const double theta = spec["angle_deg"].get<double>() * kPi / 180.0;
  const double mu = spec["friction"].get<double>();
  const double v0 = motion.initial_speed;
  const double a = motion.acceleration;
  const double t_stop = motion.stop_time;
  const Vec3 down = motion.down_slope;
  const double t0 = trace.times.front();
  const Vec3 x0 = trace.samples.front()[body].x_W;
  std::ofstream data(dir / "data.dat");
  for (std::size_t k = 0; k < trace.times.size(); ++k) {
    const double t = trace.times[k] - t0;
    const BodyState& s = trace.samples[k][body];
    for (double v : {trace.times[k], (s.x_W - x0).dot(down), s.v_W.dot(down), motion.distance(t),
                     motion.speed(t)}) {
      put(data, v);
      data << ' ';
    }
    data << '\n';
  }
  std::ostringstream title;
  title << std::setprecision(4) << "Block \"" << body_of(spec) << "\" on a " << theta * 180.0 / kPi
        << "° incline, μ = " << mu << ", v_0 = " << v0 << " m/s: a = g (sin θ − μ cos θ) = " << a
        << " m/s²";
  if (std::isfinite(t_stop)) title << ", stops at t* = " << std::setprecision(5) << t_stop << " s";
  std::ostringstream gp;
  gp << "set multiplot layout 3,1 title " << quoted(title.str()) << "\nset grid\n"
     << "set key bottom right\nset xlabel 't [s]'\n"
     << "set title 'Along-slope position'\nset ylabel 's [m]'\n"
     << "plot 'data.dat' u 1:4 w l lw 3 lc rgb '#a0a0a0' t 'closed form', "
        "'' u 1:2 w l lc rgb '#c00000' t 'simulation'\n"
     << "set title 'Along-slope velocity (sampled: a microcollision steps it by about a_t τ)'\n"
     << "set ylabel 'v [m/s]'\n"
     << "plot 'data.dat' u 1:5 w l lw 3 lc rgb '#a0a0a0' t 'closed form', "
        "'' u 1:3 w l lc rgb '#c00000' t 'simulation'\n"
     << "set title 'Position error: simulation − closed form'\nset ylabel 'Δs [m]'\n"
     << "set format y '%.1e'\n"
     << "plot 'data.dat' u 1:($2-$4) w l lc rgb '#c00000' t 'Δs'\n"
     << "unset multiplot\n";
  return gp.str();
}

// Turntable: the ball's path and the circle of radius |v0| / (k Ω / (1 + k)) around
// x0 + axis × v0 / rate (DESIGN.md §6), in the plane of the platter (axis z).
std::string turntable_plot(const Trace& trace, const json& spec, const fs::path& dir) {
  const std::size_t body = trace.body_index(body_of(spec), "--param body");
  const BodyState& first = trace.samples.front()[body];
  const TurntableCircle circle = turntable_circle(spec, "--param", first.x_W, first.v_W);
  if (std::abs(circle.axis.z()) < 1.0 - 1e-12) {
    throw InputError("--param axis", "the turntable plot is a top view: expected axis [0, 0, ±1]");
  }
  const double omega = spec["omega"].get<double>();
  const double rate = circle.rate;
  const Vec3 centre = circle.centre;
  const double radius = circle.radius;
  std::ofstream data(dir / "data.dat");
  for (std::size_t i = 0; i < trace.times.size(); ++i) {
    put(data, trace.samples[i][body].x_W.x());
    data << ' ';
    put(data, trace.samples[i][body].x_W.y());
    data << '\n';
  }
  data << "\n\n";
  for (int i = 0; i <= 720; ++i) {
    const double phi = 2.0 * kPi * i / 720.0;
    put(data, centre.x() + radius * std::cos(phi));
    data << ' ';
    put(data, centre.y() + radius * std::sin(phi));
    data << '\n';
  }
  data << "\n\n";
  put(data, centre.x());
  data << ' ';
  put(data, centre.y());
  data << '\n';
  std::ostringstream title;
  title << std::setprecision(4) << "Ball \"" << body_of(spec) << "\" on a platter at Ω = " << omega
        << " rad/s: circle at kΩ/(1+k) = " << rate << " rad/s, radius " << radius << " m ("
        << trace.times.back() - trace.times.front() << " s)";
  std::ostringstream gp;
  gp << "set title " << quoted(title.str()) << "\nset grid\nset size ratio -1\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset key outside right\n"
     << "plot 'data.dat' index 1 w l lw 4 lc rgb '#a0a0a0' t 'closed-form circle', "
        "'' index 2 w p pt 1 ps 2 lc rgb '#a0a0a0' t 'closed-form centre', "
        "'' index 0 w l lc rgb '#c00000' t 'simulation', "
        "'' index 0 every ::0::0 w p pt 7 lc rgb '#c00000' t 'start'\n";
  return gp.str();
}

// Runs `program script` in `dir`; stderr goes to dir/gnuplot.log. Returns the exit status.
int run_gnuplot(const std::string& program, const fs::path& dir) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log = (dir / "gnuplot.log").string();
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::string script = (dir / "plot.gp").string();
  std::string prog = program;
  char* argv[] = {prog.data(), script.data(), nullptr};
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, program.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot start " + program);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waiting for gnuplot failed");
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

}  // namespace

PlotKind parse_plot_kind(const std::string& text) {
  if (text == "series") return PlotKind::kSeries;
  if (text == "top") return PlotKind::kTop;
  if (text == "incline") return PlotKind::kIncline;
  if (text == "turntable") return PlotKind::kTurntable;
  throw InputError("--kind", "got \"" + text + "\", expected series, top, incline or turntable");
}

std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    return ::access(name.c_str(), X_OK) == 0 ? name : std::string();
  }
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

std::string require_gnuplot(const std::string& name) {
  const std::string program = find_program(name);
  if (program.empty()) {
    throw std::runtime_error("gnuplot not found (looked for \"" + name +
                             "\" on PATH): install the Debian package gnuplot-nox "
                             "(tools/setup does)");
  }
  return program;
}

namespace {
// Writes the script into dir, runs gnuplot on it into a PNG inside dir, and writes that PNG to
// `out_path` through an AtomicFile only when gnuplot succeeded: a regular file is replaced
// atomically, a device or a symlink's target is written through, and nothing is ever left beside
// `out_path` (not even when it names a directory, or on a signal).
void render(const std::string& program, const TempDir& dir, const std::string& script, int height,
            const std::string& out_path) {
  AtomicFile out(out_path);  // opened first: an unwritable path fails before gnuplot runs
  const fs::path temp_png = fs::absolute(dir.path() / "out.png");
  {
    std::ofstream gp(dir.path() / "plot.gp");
    gp << terminal(height) << "set encoding utf8\nset output " << quoted(temp_png.string()) << "\n"
       << "cd " << quoted(dir.path().string()) << "\n"
       << script << "unset output\n";
    if (!gp) throw std::runtime_error("cannot write the gnuplot script in " + dir.path().string());
  }
  const int status = run_gnuplot(program, dir.path());
  std::ifstream log_in(dir.path() / "gnuplot.log");
  std::string messages((std::istreambuf_iterator<char>(log_in)), std::istreambuf_iterator<char>());
  std::error_code ignored;
  if (status != 0 || !fs::exists(temp_png) || fs::file_size(temp_png, ignored) == 0) {
    throw std::runtime_error("gnuplot failed (status " + std::to_string(status) + "): " + messages);
  }
  std::ifstream png(temp_png, std::ios::binary);
  out.stream() << png.rdbuf();
  out.commit();
}

}  // namespace

void plot_trace(const PlotOptions& options) {
  if (options.out_path.empty()) throw InputError("--out", "required: the PNG to write");
  json spec;
  if (options.kind == PlotKind::kIncline || options.kind == PlotKind::kTurntable) {
    spec = reference_spec(options.reference);
    const std::string expected = options.kind == PlotKind::kIncline ? "incline" : "turntable";
    if (spec["type"] != expected) {
      throw InputError("--reference", "got " + spec["type"].dump() + ", expected \"" + expected +
                                          "\" for --kind " + expected);
    }
    validate_reference(spec, options.reference.scene_path.empty()
                                 ? std::string("--param")
                                 : options.reference.scene_path + ":/reference");
  }
  Trace trace = read_trace_csv(options.trace_path);
  const std::string program = require_gnuplot(options.gnuplot);
  TempDir dir;
  std::string script;
  switch (options.kind) {
    case PlotKind::kSeries: script = series_plot(trace, options.body, dir.path()); break;
    case PlotKind::kTop: script = top_plot(trace, dir.path()); break;
    case PlotKind::kIncline: script = incline_plot(trace, spec, dir.path()); break;
    case PlotKind::kTurntable: script = turntable_plot(trace, spec, dir.path()); break;
  }
  render(program, dir, script, options.kind == PlotKind::kIncline ? 1100 : 800, options.out_path);
}

std::vector<std::size_t> pareto_front(const std::vector<ParetoPoint>& points) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isfinite(points[i].cpu_s) && std::isfinite(points[i].error)) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (points[a].cpu_s != points[b].cpu_s) return points[a].cpu_s < points[b].cpu_s;
    return points[a].error < points[b].error;
  });
  std::vector<std::size_t> front;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i : order) {
    if (points[i].error < best) {
      front.push_back(i);
      best = points[i].error;
    }
  }
  return front;
}

void plot_pareto(const std::vector<ParetoPoint>& points, const std::string& title,
                 const std::string& out_path, const std::string& gnuplot) {
  if (out_path.empty()) throw InputError("--plot", "expected the PNG to write");
  // Logarithmic axes: an error of exactly 0 is drawn at the floor below the smallest non-zero
  // error (and said so in the key); non-finite points are left out.
  double smallest = std::numeric_limits<double>::infinity();
  for (const ParetoPoint& p : points) {
    if (p.error > 0.0 && std::isfinite(p.error)) smallest = std::min(smallest, p.error);
  }
  const double floor = std::isfinite(smallest) ? smallest / 10.0 : 1e-16;
  std::vector<ParetoPoint> drawn;
  std::size_t zeros = 0, skipped = 0;
  for (const ParetoPoint& p : points) {
    if (!std::isfinite(p.error) || !(p.cpu_s > 0.0) || !std::isfinite(p.cpu_s)) {
      ++skipped;
      continue;
    }
    ParetoPoint q = p;
    if (q.error == 0.0) {
      q.error = floor;
      ++zeros;
    }
    drawn.push_back(q);
  }
  if (drawn.empty()) {
    throw std::runtime_error("nothing to plot: no combination has a finite error and CPU time");
  }
  const std::string program = require_gnuplot(gnuplot);
  TempDir dir;
  {
    std::ofstream data(dir.path() / "data.dat");
    data << "# cpu_s error label\n";
    for (const ParetoPoint& p : drawn) {
      put(data, p.cpu_s);
      data << ' ';
      put(data, std::abs(p.error));
      data << " \"" << p.label << "\"\n";
    }
    data << "\n\n";
    for (std::size_t i : pareto_front(drawn)) {
      put(data, drawn[i].cpu_s);
      data << ' ';
      put(data, std::abs(drawn[i].error));
      data << '\n';
    }
    if (!data) throw std::runtime_error("cannot write the plot data in " + dir.path().string());
  }
  std::ostringstream gp;
  std::string note;
  if (zeros > 0) note += ", " + std::to_string(zeros) + " zero errors drawn at the floor";
  if (skipped > 0) note += ", " + std::to_string(skipped) + " without a finite error left out";
  gp << "set title " << quoted(title + note) << " noenhanced\n"
     << "set logscale xy\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
     << "set xlabel 'CPU time per run [s]'\nset ylabel 'relative error'\n"
     << "set grid xtics ytics mxtics mytics lc rgb '#e0e0e0'\nset key top right\n"
     << "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n"
     << "plot 'data.dat' index 1 w steps lw 2 lc rgb '#c00000' t 'Pareto front', "
        "'' index 0 u 1:2 w p pt 7 ps 1.2 lc rgb '#0060c0' t 'combination', "
        "'' index 0 u 1:2:3 w labels offset 0.8,0.6 font ',8' noenhanced notitle\n";
  render(program, dir, gp.str(), 800, out_path);
}

}  // namespace palpable::tools
