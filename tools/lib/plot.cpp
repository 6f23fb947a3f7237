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
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <utility>

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

// The bodies that move in the trace (a fixed body's or a halfspace's "path" is a point that says
// nothing and may sit far from the action).
std::vector<std::size_t> moving_bodies(const Trace& trace) {
  std::vector<std::size_t> moving;
  for (std::size_t b = 0; b < trace.body_names.size(); ++b) {
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      if (trace.samples[k][b].x_W != trace.samples[0][b].x_W) {
        moving.push_back(b);
        break;
      }
    }
  }
  if (moving.empty()) throw InputError("trace", "no body moves: nothing to draw");
  return moving;
}

// The outline seen from above (x-y convex hull) of a convex shape at a pose, as a closed polygon.
using Outline = std::vector<Eigen::Vector2d>;
Outline hull_2d(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  Outline h(2 * p.size());
  std::size_t k = 0;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

// Every convex piece of a shape seen from above (halfspaces, the floor, are left out).
void outlines_of(const Shape& shape, const Vec3& x, const Quat& q, std::vector<Outline>& out) {
  if (const Sphere* s = std::get_if<Sphere>(&shape)) {
    Outline circle;
    for (int i = 0; i < 48; ++i) {
      const double phi = 2.0 * kPi * i / 48.0;
      circle.emplace_back(x.x() + s->radius * std::cos(phi), x.y() + s->radius * std::sin(phi));
    }
    out.push_back(circle);
  } else if (const ConvexPolyhedron* p = std::get_if<ConvexPolyhedron>(&shape)) {
    std::vector<Eigen::Vector2d> points;
    for (const Vec3& v : p->vertices()) points.push_back((x + q * v).head<2>());
    out.push_back(hull_2d(points));
  } else if (is_smooth_convex(shape)) {
    // The outline seen from above: the horizontal support points, exact on the silhouette.
    Outline outline;
    for (int i = 0; i < 48; ++i) {
      const double phi = 2.0 * kPi * i / 48.0;
      outline.push_back(support_W(shape, x, q, Vec3(std::cos(phi), std::sin(phi), 0.0)).head<2>());
    }
    out.push_back(hull_2d(outline));
  } else if (const Compound* c = std::get_if<Compound>(&shape)) {
    for (const CompoundPart& part : c->parts) {
      outlines_of(*part.shape, x + q * part.position_M, q * part.orientation_M, out);
    }
  }
}

// Top view: every moving body's x-y path (one data block per body, start marked, one colour each)
// over the fixed bodies seen from above (the scene's shapes at their traced poses).
std::string top_plot(const Trace& trace, const Scene* scene, const fs::path& dir) {
  const std::vector<std::size_t> moving = moving_bodies(trace);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t b : moving) {
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      lo = lo.cwiseMin(trace.samples[k][b].x_W);
      hi = hi.cwiseMax(trace.samples[k][b].x_W);
    }
  }
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
  // The fixed bodies near the paths (within half the paths' extent): their outlines, and the
  // range grown to show them whole.
  std::vector<Outline> fixed;
  std::vector<std::string> fixed_names;
  if (scene != nullptr) {
    const Eigen::Vector2d margin = Eigen::Vector2d::Constant(0.5 * (hi - lo).head<2>().norm());
    const Eigen::Vector2d near_lo = lo.head<2>() - margin, near_hi = hi.head<2>() + margin;
    for (std::size_t b = 0; b < trace.body_names.size(); ++b) {
      const BodyId id = scene->world.find_body(trace.body_names[b]);
      if (!id.valid() || scene->world.bodies[id.index].is_dynamic()) continue;
      std::vector<Outline> pieces;
      outlines_of(*scene->world.bodies[id.index].shape, trace.samples[0][b].x_W,
                  trace.samples[0][b].q_WM, pieces);
      bool shown = false;
      for (const Outline& o : pieces) {
        Eigen::Vector2d olo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
        Eigen::Vector2d ohi = -olo;
        for (const auto& v : o) {
          olo = olo.cwiseMin(v);
          ohi = ohi.cwiseMax(v);
        }
        if (o.size() < 3 || (olo.array() > near_hi.array()).any() ||
            (ohi.array() < near_lo.array()).any()) {
          continue;
        }
        fixed.push_back(o);
        shown = true;
        lo.head<2>() = lo.head<2>().cwiseMin(olo);
        hi.head<2>() = hi.head<2>().cwiseMax(ohi);
      }
      if (shown) fixed_names.push_back(trace.body_names[b]);
    }
  }
  // A true top view has equal axes; a path 5 times longer than wide (a bowling lane) would be a
  // line, so then the axes are scaled apart and the title says so.
  const double width = hi.x() - lo.x(), height = hi.y() - lo.y();
  const bool to_scale = std::max(width, height) <= 5.0 * std::min(width, height);
  // Each axis padded by 3% of its extent (of the larger one when to scale); an axis along which
  // nothing moves gets 5% of the other's (gnuplot refuses an empty range).
  const double span = std::max({width, height, 1e-6});
  auto range = [&](double a, double b) {
    const double extent = std::max(b - a, 0.05 * span);
    const double half = 0.5 * extent + 0.03 * (to_scale ? span : extent);
    std::ostringstream r;
    r << std::setprecision(12) << "[" << 0.5 * (a + b) - half << ":" << 0.5 * (a + b) + half << "]";
    return r.str();
  };
  std::string names;
  for (const std::string& n : fixed_names) names += (names.empty() ? "" : ", ") + n;
  std::ostringstream gp;
  gp << std::setprecision(12) << "set title "
     << quoted(std::string("Top view: paths of the centres of mass") +
               (fixed.empty() ? "" : " over the fixed bodies (grey: " + names + ")") +
               (to_scale ? "" : " (axes not to scale)"))
     << " noenhanced\nset grid\n"
     << (to_scale ? "set size ratio -1\n" : "") << "set xrange " << range(lo.x(), hi.x())
     << "\nset yrange " << range(lo.y(), hi.y()) << "\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset key outside right\n";
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    gp << "set object " << i + 1 << " polygon from ";
    for (std::size_t v = 0; v <= fixed[i].size(); ++v) {
      const auto& p = fixed[i][v % fixed[i].size()];
      gp << (v > 0 ? " to " : "") << p.x() << "," << p.y();
    }
    gp << " fc rgb '#d4d4cc' fs solid 1.0 border lc rgb '#8c8c84' behind\n";
  }
  gp << "plot ";
  if (!fixed.empty()) gp << "NaN w filledcurves fc rgb '#d4d4cc' t 'fixed bodies', ";
  for (std::size_t i = 0; i < moving.size(); ++i) {
    const std::string colour = quoted(palette_colour(i));
    gp << (i > 0 ? ", " : "") << "'data.dat' index " << i << " w l lc rgb " << colour << " t "
       << quoted(trace.body_names[moving[i]]) << " noenhanced, '' index " << i
       << " every ::0::0 w p pt 7 lc rgb " << colour << " notitle";
  }
  gp << "\n";
  return gp.str();
}

// The axis (0 x, 1 y, 2 z) along which the moving bodies' paths are longest, and whether every
// path stays within 2% of that length of one line along it.
std::pair<int, bool> line_axis(const Trace& trace, const std::vector<std::size_t>& moving) {
  Vec3 reach = Vec3::Zero();  // the longest extent along each axis over the bodies
  Vec3 widest = Vec3::Zero();
  std::vector<Vec3> extents;
  for (std::size_t b : moving) {
    Vec3 lo = trace.samples[0][b].x_W, hi = lo;
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      lo = lo.cwiseMin(trace.samples[k][b].x_W);
      hi = hi.cwiseMax(trace.samples[k][b].x_W);
    }
    extents.push_back(hi - lo);
    reach = reach.cwiseMax(hi - lo);
  }
  int axis = 0;
  reach.maxCoeff(&axis);
  for (const Vec3& e : extents) {
    for (int i = 0; i < 3; ++i) {
      if (i != axis) widest[i] = std::max(widest[i], e[i]);
    }
  }
  return {axis, widest.maxCoeff() <= 0.02 * reach[axis] && reach[axis] > 0.0};
}

// Several bodies' curves against time in panels (one data block per body, columns: t, then the
// panels' values), one colour per body; panels are {title, y label, column}.
std::string panels_plot(const std::string& title, const std::vector<std::string>& names,
                        const std::vector<std::array<std::string, 2>>& panels) {
  std::ostringstream gp;
  gp << "set multiplot layout " << panels.size() << ",1 title " << quoted(title)
     << "\nset grid\nset key outside right\nset xlabel 't [s]'\n";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    gp << "set title " << quoted(panels[p][0]) << "\nset ylabel " << quoted(panels[p][1])
       << "\nplot ";
    for (std::size_t i = 0; i < names.size(); ++i) {
      gp << (i > 0 ? ", " : "") << "'data.dat' index " << i << " u 1:" << p + 2 << " w l lc rgb "
         << quoted(palette_colour(i)) << " t " << quoted(names[i]) << " noenhanced";
    }
    gp << "\n";
  }
  gp << "unset multiplot\n";
  return gp.str();
}

// One data block per body: t, then `columns` of its state, per sample. Returns the bodies' names.
std::vector<std::string> write_body_blocks(
    const Trace& trace, const std::vector<std::size_t>& bodies, const fs::path& dir,
    const std::function<std::vector<double>(const BodyState&)>& columns) {
  std::ofstream data(dir / "data.dat");
  std::vector<std::string> names;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (i > 0) data << "\n\n";
    names.push_back(trace.body_names[bodies[i]]);
    for (std::size_t k = 0; k < trace.times.size(); ++k) {
      put(data, trace.times[k]);
      for (double v : columns(trace.samples[k][bodies[i]])) {
        data << ' ';
        put(data, v);
      }
      data << '\n';
    }
  }
  return names;
}

// Line: bodies moving along one axis (a chain of balls): the momentum passing along shows as
// each body's position and velocity against time.
std::string line_plot(const Trace& trace, const fs::path& dir) {
  const std::vector<std::size_t> moving = moving_bodies(trace);
  const int axis = line_axis(trace, moving).first;
  const char* name = axis == 0 ? "x" : axis == 1 ? "y" : "z";
  const std::vector<std::string> names =
      write_body_blocks(trace, moving, dir, [axis](const BodyState& s) {
        return std::vector<double>{s.x_W[axis], s.v_W[axis]};
      });
  return panels_plot(names.size() == 1
                         ? std::string("Position and velocity along ") + name
                         : std::string("Bodies on a line: position and velocity along ") + name +
                               " (the momentum passing from body to body)",
                     names,
                     {{{std::string("Position ") + name, std::string(name) + " [m]"}},
                      {{std::string("Velocity v_") + name, std::string("v_") + name + " [m/s]"}}});
}

// Tumble: bodies that bounce, turn over and spin down (coins): height of the centre of mass,
// tilt (angle between the body's z axis, a coin's axis, and the world's: 0° one face up, 180°
// the other) and angular speed against time.
std::string tumble_plot(const Trace& trace, const fs::path& dir) {
  const std::vector<std::string> names =
      write_body_blocks(trace, moving_bodies(trace), dir, [](const BodyState& s) {
        const double cos_tilt = std::clamp((s.q_WM * Vec3::UnitZ()).z(), -1.0, 1.0);
        return std::vector<double>{s.x_W.z(), std::acos(cos_tilt) * 180.0 / kPi, s.w_W.norm()};
      });
  return panels_plot(
      "Tumbling bodies: height, tilt and spin against time", names,
      {{{"Height of the centre of mass", "z [m]"}},
       {{"Tilt: angle of the body's z axis from the vertical (0° and 180°: flat)", "tilt [°]"}},
       {{"Angular speed", "|ω| [rad/s]"}}});
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
// The circle comes from the ball's launch state in the scene when there is one (else from the
// trace's first sample); a second panel shows the distance from the circle against time.
std::string turntable_plot(const Trace& trace, const json& spec, const Scene* scene,
                           const fs::path& dir) {
  const std::size_t body = trace.body_index(body_of(spec), "--param body");
  BodyState launch = trace.samples.front()[body];
  std::string from = "the trace's first sample";
  if (scene != nullptr && scene->world.find_body(body_of(spec)).valid()) {
    launch = scene->world.bodies[scene->world.find_body(body_of(spec)).index].state;
    from = "the scene's launch state";
  }
  const TurntableCircle circle = turntable_circle(spec, "--param", launch.x_W, launch.v_W);
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
  data << "\n\n\n";
  for (std::size_t i = 0; i < trace.times.size(); ++i) {
    const Vec3 off = trace.samples[i][body].x_W - centre;
    put(data, trace.times[i]);
    data << ' ';
    put(data, (off - off.dot(circle.axis) * circle.axis).norm() - radius);
    data << '\n';
  }
  std::ostringstream title;
  title << std::setprecision(4) << "Ball \"" << body_of(spec) << "\" on a platter at Ω = " << omega
        << " rad/s: circle at kΩ/(1+k) = " << rate << " rad/s, radius " << radius << " m ("
        << trace.times.back() - trace.times.front() << " s)";
  std::ostringstream gp;
  gp << "set multiplot title " << quoted(title.str()) << "\n"
     << "set size 1,0.68\nset origin 0,0.28\nset title "
     << quoted("Path seen from above; circle from " + from) << "\nset grid\nset size ratio -1\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset key outside right\n"
     << "plot 'data.dat' index 1 w l lw 4 lc rgb '#a0a0a0' t 'closed-form circle', "
        "'' index 2 w p pt 1 ps 2 lc rgb '#a0a0a0' t 'closed-form centre', "
        "'' index 0 w l lc rgb '#c00000' t 'simulation', "
        "'' index 0 every ::0::0 w p pt 7 lc rgb '#c00000' t 'start'\n"
     << "set size ratio 0\nset size 1,0.28\nset origin 0,0\n"
     << "set title 'Residual: distance of the ball from the closed-form circle'\n"
     << "set xlabel 't [s]'\nset ylabel 'Δr [m]'\nset format y '%.1e'\n"
     << "plot 'data.dat' index 3 u 1:2 w l lc rgb '#c00000' t 'Δr'\nunset multiplot\n";
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
  if (text == "line") return PlotKind::kLine;
  if (text == "tumble") return PlotKind::kTumble;
  if (text == "auto") return PlotKind::kAuto;
  throw InputError(
      "--kind",
      "got \"" + text + "\", expected series, top, incline, turntable, line, tumble or auto");
}

PlotKind choose_plot_kind(const Trace& trace, const Scene* scene) {
  if (scene != nullptr && !scene->plot.empty()) return parse_plot_kind(scene->plot);
  if (scene != nullptr && scene->reference.is_object()) {
    const std::string type = scene->reference.value("type", "");
    if (type == "incline") return PlotKind::kIncline;
    if (type == "turntable") return PlotKind::kTurntable;
  }
  return line_axis(trace, moving_bodies(trace)).second ? PlotKind::kLine : PlotKind::kTop;
}

std::string palette_colour(std::size_t i) {
  // Hue steps of the golden angle never repeat; lightness cycles through three levels so that
  // colours close in hue (8 and 13 steps apart) still differ.
  const double h = std::fmod(static_cast<double>(i) * 0.6180339887498949, 1.0) * 6.0;
  const double s = 0.85, l = (i % 3 == 0) ? 0.40 : (i % 3 == 1) ? 0.55 : 0.30;
  const double c = (1.0 - std::abs(2.0 * l - 1.0)) * s;
  const double x = c * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0));
  const double m = l - c / 2.0;
  double rgb[3] = {0, 0, 0};
  const int sector = static_cast<int>(h);
  const int order[6][3] = {{0, 1, 2}, {1, 0, 2}, {1, 2, 0}, {2, 1, 0}, {2, 0, 1}, {0, 2, 1}};
  rgb[order[sector][0]] = c;  // the largest component
  rgb[order[sector][1]] = x;
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x",
                static_cast<int>(std::lround(255 * (rgb[0] + m))),
                static_cast<int>(std::lround(255 * (rgb[1] + m))),
                static_cast<int>(std::lround(255 * (rgb[2] + m))));
  return text;
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
  // The scene: --scene, else the one the reference comes from.
  const std::string scene_path =
      options.scene_path.empty() ? options.reference.scene_path : options.scene_path;
  std::unique_ptr<Scene> scene;
  if (!scene_path.empty()) scene = std::make_unique<Scene>(load_scene(scene_path));
  Trace trace = read_trace_csv(options.trace_path);
  const PlotKind kind =
      options.kind == PlotKind::kAuto ? choose_plot_kind(trace, scene.get()) : options.kind;
  ReferenceOptions reference = options.reference;
  if ((kind == PlotKind::kIncline || kind == PlotKind::kTurntable) && reference.type.empty() &&
      reference.scene_path.empty()) {
    reference.scene_path = scene_path;  // --scene's reference
  }
  json spec;
  if (kind == PlotKind::kIncline || kind == PlotKind::kTurntable) {
    spec = reference_spec(reference);
    const std::string expected = kind == PlotKind::kIncline ? "incline" : "turntable";
    if (spec["type"] != expected) {
      throw InputError("--reference", "got " + spec["type"].dump() + ", expected \"" + expected +
                                          "\" for --kind " + expected);
    }
    validate_reference(spec, reference.scene_path.empty() ? std::string("--param")
                                                          : reference.scene_path + ":/reference");
  }
  const std::string program = require_gnuplot(options.gnuplot);
  TempDir dir;
  std::string script;
  switch (kind) {
    case PlotKind::kSeries: script = series_plot(trace, options.body, dir.path()); break;
    case PlotKind::kTop: script = top_plot(trace, scene.get(), dir.path()); break;
    case PlotKind::kIncline: script = incline_plot(trace, spec, dir.path()); break;
    case PlotKind::kTurntable: script = turntable_plot(trace, spec, scene.get(), dir.path()); break;
    case PlotKind::kLine: script = line_plot(trace, dir.path()); break;
    case PlotKind::kTumble: script = tumble_plot(trace, dir.path()); break;
    case PlotKind::kAuto: PALPABLE_CHECK(false, "auto is resolved above");
  }
  const bool tall =
      kind == PlotKind::kIncline || kind == PlotKind::kTumble || kind == PlotKind::kTurntable;
  render(program, dir, script, tall ? 1100 : 800, options.out_path);
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

std::vector<LabelPlace> place_labels(const std::vector<ParetoPoint>& points, double x_lo,
                                     double x_hi, double y_lo, double y_hi) {
  constexpr double kWidth = 900.0, kHeight = 650.0, kChar = 5.5, kLine = 11.0, kDot = 5.0;
  struct Box {
    double l, b, r, t;  // pixels
  };
  std::vector<Box> taken;
  std::vector<std::array<double, 2>> at;
  for (const ParetoPoint& p : points) {
    const double x = (std::log10(p.cpu_s) - x_lo) / (x_hi - x_lo) * kWidth;
    const double y = (std::log10(std::abs(p.error)) - y_lo) / (y_hi - y_lo) * kHeight;
    at.push_back({x, y});
    taken.push_back({x - kDot, y - kDot, x + kDot, y + kDot});
  }
  std::vector<std::size_t> order = pareto_front(points);
  std::vector<bool> queued(points.size(), false);
  for (std::size_t i : order) queued[i] = true;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!queued[i]) order.push_back(i);
  }
  std::vector<LabelPlace> places(points.size());
  for (std::size_t i : order) {
    const double w = kChar * static_cast<double>(points[i].label.size()), h = kLine;
    const double x = at[i][0], y = at[i][1];
    // Right above, right below, left above, left below, above, below, then further out.
    const std::vector<std::array<double, 2>> candidates = {
        {x + 7, y + 2},         {x + 7, y - h - 2},
        {x - 7 - w, y + 2},     {x - 7 - w, y - h - 2},
        {x - w / 2, y + 7},     {x - w / 2, y - h - 7},
        {x + 7, y + h + 4},     {x + 7, y - 2 * h - 4},
        {x - 7 - w, y + h + 4}, {x - 7 - w, y - 2 * h - 4}};
    for (const auto& c : candidates) {
      const Box box{c[0], c[1], c[0] + w, c[1] + h};
      if (box.l < 0 || box.b < 0 || box.r > kWidth || box.t > kHeight) continue;
      const bool free = std::none_of(taken.begin(), taken.end(), [&](const Box& o) {
        return box.l < o.r && o.l < box.r && box.b < o.t && o.b < box.t;
      });
      if (!free) continue;
      taken.push_back(box);
      // gnuplot anchors a left-justified label at its left end, vertically centred.
      places[i] = {true,
                   c[0] / kWidth,
                   (c[1] + h / 2) / kHeight,
                   {box.l / kWidth, box.b / kHeight, box.r / kWidth, box.t / kHeight}};
      break;
    }
  }
  return places;
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
  // Fixed logarithmic ranges, so that a label's place can be worked out here in graph units.
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  for (const ParetoPoint& p : drawn) {
    x_lo = std::min(x_lo, std::log10(p.cpu_s));
    x_hi = std::max(x_hi, std::log10(p.cpu_s));
    y_lo = std::min(y_lo, std::log10(std::abs(p.error)));
    y_hi = std::max(y_hi, std::log10(std::abs(p.error)));
  }
  const double x_span = std::max(x_hi - x_lo, 0.2), y_span = std::max(y_hi - y_lo, 0.2);
  x_lo -= 0.06 * x_span;
  x_hi += 0.12 * x_span;
  y_lo -= 0.06 * y_span;
  y_hi += 0.08 * y_span;
  const std::vector<LabelPlace> places = place_labels(drawn, x_lo, x_hi, y_lo, y_hi);
  std::size_t left_out = 0;
  std::ostringstream gp;
  gp << std::setprecision(12);
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    if (!places[i].shown) {
      ++left_out;
      continue;
    }
    gp << "set label " << i + 1 << " " << quoted(drawn[i].label) << " at graph " << places[i].x
       << "," << places[i].y << " left font ',8' noenhanced front\n";
  }
  std::string note;
  if (zeros > 0) note += ", " + std::to_string(zeros) + " zero errors drawn at the floor";
  if (skipped > 0) note += ", " + std::to_string(skipped) + " without a finite error left out";
  if (left_out > 0) {
    note += ", " + std::to_string(left_out) + " labels left out where they would overlap";
  }
  gp << "set title " << quoted(title + note) << " noenhanced\n"
     << "set logscale xy\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
     << "set xrange [" << std::pow(10.0, x_lo) << ":" << std::pow(10.0, x_hi) << "]\n"
     << "set yrange [" << std::pow(10.0, y_lo) << ":" << std::pow(10.0, y_hi) << "]\n"
     << "set xlabel 'CPU time per run [s]'\nset ylabel 'relative error'\n"
     << "set grid xtics ytics mxtics mytics lc rgb '#e0e0e0'\nset key top right\n"
     << "plot 'data.dat' index 1 w steps lw 2 lc rgb '#c00000' t 'Pareto front', "
        "'' index 0 u 1:2 w p pt 7 ps 1.2 lc rgb '#0060c0' t 'combination'\n";
  render(program, dir, gp.str(), 800, out_path);
}

}  // namespace palpable::tools
