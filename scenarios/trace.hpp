#pragma once
// A sampled trace in memory: every body's state at each output time. Written to and read from
// the trace CSV of DESIGN.md §6 (header t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz, then any
// extra columns, which are ignored when reading).
#include "core/body.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace palpable {

// Where and when a collision touched (from the events CSV or a run in memory).
struct ContactEvent {
  double t = 0.0;
  std::size_t body_a = 0;  // indices into Trace::body_names
  std::size_t body_b = 0;
  Vec3 p_W = Vec3::Zero();
  Vec3 n_W = Vec3::Zero();  // normal from b to a; zero when the events CSV does not carry it
  Vec3 j_W = Vec3::Zero();  // impulse on a; zero when the events CSV does not carry it
  bool micro = false;       // a microcollision (a resting contact's), not a collision
};

// A held contact changing mode under the persistent contact model (hold, slip, stick, rest,
// lift_off, release, ...: the events CSV's other rows), at its exact instant.
struct HeldEvent {
  double t = 0.0;
  std::string kind;
  std::size_t body_a = 0;
  std::size_t body_b = 0;
};

struct Trace {
  std::vector<std::string> body_names;
  std::vector<double> times;
  std::vector<std::vector<BodyState>> samples;  // samples[k][body]
  // Optional: the collisions, in time order. A resting body's sampled position jitters within
  // each microcollision flight; its contact points, all taken at the instant of touching, do not.
  std::vector<ContactEvent> contacts;
  // Optional: the held contacts' changes of mode, in time order (from the events CSV).
  std::vector<HeldEvent> held;

  // Index of a body by name; throws InputError naming `where` if absent.
  std::size_t body_index(const std::string& name, const std::string& where) const;
  // Positions/velocities of one body over time.
  std::vector<BodyState> series(std::size_t body) const;
};

inline constexpr const char* kTraceHeader = "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz";

// Writes the rows of one sample (17 significant digits, round-trip exact), leaving out the bodies
// marked in `skip` (fixed bodies after the first sample: read_trace_csv repeats them).
void write_trace_rows(std::ostream& out, double t, const std::vector<std::string>& names,
                      const std::vector<BodyState>& states,
                      const std::vector<bool>* skip = nullptr);

// Reads a trace CSV; throws InputError naming the file and line for malformed input.
Trace read_trace_csv(const std::string& path);

// Reads an events CSV (header starting "t,kind,body_a,body_b,px,py,pz", then optionally
// "nx,ny,nz,jx,jy,jz", further columns ignored) into trace.contacts, in file order: the collisions
// and microcollisions; a held contact's mode changes (rows of other kinds) go to trace.held. Body
// names must be bodies of the trace. Throws InputError naming the file and line for malformed
// input or an unknown body.
void read_events_csv(const std::string& path, Trace& trace);

}  // namespace palpable
