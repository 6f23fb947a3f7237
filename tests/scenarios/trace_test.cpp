// Trace CSV: the exact header, and a write/read round trip that loses no bits.
#include "scenarios/trace.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <fstream>
#include <random>
#include <sstream>

using palpable::BodyState;
using palpable::Quat;
using palpable::Vec3;

TEST_CASE("trace rows round-trip exactly through CSV", "[scenarios][trace]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<std::string> names{"a", "b"};
  std::string path = "trace_test_roundtrip.csv";
  std::vector<std::vector<BodyState>> written;
  {
    std::ofstream out(path);
    out << palpable::kTraceHeader << "\n";
    for (int k = 0; k < 20; ++k) {
      std::vector<BodyState> states(2);
      for (auto& s : states) {
        s.x_W = Vec3(n(rng), n(rng), n(rng)) * 1e-3;
        s.q_WM = Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
        s.v_W = Vec3(n(rng), n(rng), n(rng));
        s.w_W = Vec3(n(rng), n(rng), n(rng)) * 1e4;
      }
      palpable::write_trace_rows(out, 0.01 * k, names, states);
      written.push_back(states);
    }
  }
  palpable::Trace trace = palpable::read_trace_csv(path);
  std::remove(path.c_str());
  REQUIRE(trace.body_names == names);
  REQUIRE(trace.samples.size() == 20);
  for (int k = 0; k < 20; ++k) {
    CHECK(trace.times[k] == 0.01 * k);
    for (int b = 0; b < 2; ++b) {
      CHECK(trace.samples[k][b].x_W == written[k][b].x_W);
      CHECK(trace.samples[k][b].q_WM.coeffs() == written[k][b].q_WM.coeffs());
      CHECK(trace.samples[k][b].v_W == written[k][b].v_W);
      CHECK(trace.samples[k][b].w_W == written[k][b].w_W);
    }
  }
}

TEST_CASE("malformed traces are rejected naming file and line", "[scenarios][trace]") {
  std::string path = "trace_test_bad.csv";
  {
    std::ofstream out(path);
    out << palpable::kTraceHeader << "\n0,a,1,2,3,1,0,0,0,0,0,0,0,0,x\n";
  }
  CHECK_THROWS_WITH(palpable::read_trace_csv(path), Catch::StartsWith(path + ":2"));
  {
    std::ofstream out(path);
    out << "time,body\n";
  }
  CHECK_THROWS_WITH(palpable::read_trace_csv(path), Catch::StartsWith(path + ":1"));
  std::remove(path.c_str());
}

TEST_CASE("events CSV fills the trace's contacts, bad rows name file and line",
          "[scenarios][trace]") {
  palpable::Trace trace;
  trace.body_names = {"block", "ramp"};
  std::string path = "trace_test_events.csv";
  {
    std::ofstream out(path);
    out << "t,kind,body_a,body_b,px,py,pz,nx,ny,nz,jx,jy,jz,approach_speed,energy_change,"
           "centre_of_pressure\n"
        << "0.25,collision,block,ramp,0.5,-0.125,3e-5,0,0,1,0,0,1,0.1,-0.01,0\n"
        << "0.5,microcollision,ramp,block,0.1,0.2,0.3,0,0,1,0,0,1,0.01,0,1\n"
        << "0.75,hold,block,ramp,0.5,0,0.1,0,0,0,0,0,0,0,0,0\n";
  }
  palpable::read_events_csv(path, trace);
  REQUIRE(trace.contacts.size() == 2);
  CHECK(trace.contacts[0].j_W == Vec3(0, 0, 1));
  CHECK(trace.contacts[0].n_W == Vec3(0, 0, 1));
  CHECK_FALSE(trace.contacts[0].micro);
  CHECK(trace.contacts[1].micro);
  REQUIRE(trace.held.size() == 1);  // a held contact's change of mode, not a contact
  CHECK(trace.held[0].kind == "hold");
  CHECK(trace.held[0].t == 0.75);
  CHECK(trace.held[0].body_b == 1);
  CHECK(trace.contacts[0].t == 0.25);
  CHECK(trace.contacts[0].body_a == 0);
  CHECK(trace.contacts[0].body_b == 1);
  CHECK(trace.contacts[0].p_W == Vec3(0.5, -0.125, 3e-5));
  CHECK(trace.contacts[1].body_a == 1);
  {
    std::ofstream out(path);
    out << "t,kind,body_a,body_b,px,py,pz\n0.1,collision,block,table,0,0,0\n";
  }
  CHECK_THROWS_WITH(palpable::read_events_csv(path, trace),
                    Catch::StartsWith(path + ":2") && Catch::Contains("table"));
  {
    std::ofstream out(path);
    out << "t,kind,body_a,body_b,px,py,pz\n0.1,collision,block,ramp,0,zero,0\n";
  }
  CHECK_THROWS_WITH(palpable::read_events_csv(path, trace), Catch::StartsWith(path + ":2"));
  {
    std::ofstream out(path);
    out << palpable::kTraceHeader << "\n";
  }
  CHECK_THROWS_WITH(palpable::read_events_csv(path, trace), Catch::StartsWith(path + ":1"));
  std::remove(path.c_str());
}

TEST_CASE("a trace holds finite numbers and UTF-8 body names only", "[scenarios][trace][hostile]") {
  const std::string path = "trace_test_hostile.csv";
  const char* rows[] = {
      "0,a,nan,2,3,1,0,0,0,0,0,0,0,0,0\n",       // nan position
      "0,a,1,2,3,1,0,0,0,inf,0,0,0,0,0\n",       // infinite velocity
      "-nan,a,1,2,3,1,0,0,0,0,0,0,0,0,0\n",      // nan time
      "0,\xff\xfe,1,2,3,1,0,0,0,0,0,0,0,0,0\n",  // a name that is not UTF-8
  };
  for (const char* row : rows) {
    CAPTURE(row);
    {
      std::ofstream out(path);
      out << palpable::kTraceHeader << "\n" << row;
    }
    CHECK_THROWS_WITH(palpable::read_trace_csv(path), Catch::StartsWith(path + ":2"));
  }
  std::remove(path.c_str());
}
