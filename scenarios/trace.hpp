#pragma once
// A sampled trace in memory: every body's state at each output time. Written to and read from
// the trace CSV of DESIGN.md §6 (header t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz, then any
// extra columns, which are ignored when reading).
#include "core/body.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace palpable {

struct Trace {
  std::vector<std::string> body_names;
  std::vector<double> times;
  std::vector<std::vector<BodyState>> samples;  // samples[k][body]

  // Index of a body by name; throws InputError naming `where` if absent.
  std::size_t body_index(const std::string& name, const std::string& where) const;
  // Positions/velocities of one body over time.
  std::vector<BodyState> series(std::size_t body) const;
};

inline constexpr const char* kTraceHeader = "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz";

// Writes the rows of one sample (17 significant digits, round-trip exact).
void write_trace_rows(std::ostream& out, double t, const std::vector<std::string>& names,
                      const std::vector<BodyState>& states);

// Reads a trace CSV; throws InputError naming the file and line for malformed input.
Trace read_trace_csv(const std::string& path);

}  // namespace palpable
