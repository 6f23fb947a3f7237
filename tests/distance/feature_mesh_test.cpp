// FeatureMesh: Voronoi planes of a box and a hull; every point outside lies in the Voronoi region
// of a feature that is closest to it.
#include "distance/feature_mesh.hpp"

#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

using namespace palpable;
using namespace palpable::test;

namespace {

bool in_region(const FeatureMesh& m, Feature f, const Vec3& x) {
  const VoronoiPlane* begin = nullptr;
  const VoronoiPlane* end = nullptr;
  switch (f.kind) {
    case FeatureKind::kVertex:
      begin = m.vertex_planes_begin(f.index);
      end = m.vertex_planes_end(f.index);
      break;
    case FeatureKind::kEdge:
      begin = m.edge_planes(f.index);
      end = begin + 4;
      break;
    case FeatureKind::kFace:
      if (m.face_eval(f.index, x) < 0.0) return false;
      begin = m.face_planes_begin(f.index);
      end = m.face_planes_end(f.index);
      break;
    case FeatureKind::kNone: return false;
  }
  for (const VoronoiPlane* p = begin; p != end; ++p) {
    if (p->eval(x) < 0.0) return false;
  }
  return true;
}

double feature_distance(const FeatureMesh& m, Feature f, const Vec3& x) {
  switch (f.kind) {
    case FeatureKind::kVertex: return (m.vertex(f.index) - x).norm();
    case FeatureKind::kEdge:
      return (closest_point_segment(m.tail(f.index), m.head(f.index), x) - x).norm();
    case FeatureKind::kFace: return m.face_eval(f.index, x);
    case FeatureKind::kNone: break;
  }
  return kInfinity;
}

}  // namespace

TEST_CASE("box feature mesh has the expected Voronoi planes", "[distance][feature_mesh]") {
  const FeatureMesh m(ConvexPolyhedron::box(Vec3(0.5, 1.0, 1.5)));
  REQUIRE(m.num_vertices() == 8);
  REQUIRE(m.num_half_edges() == 24);
  REQUIRE(m.num_faces() == 6);
  CHECK(m.max_radius() == Approx(std::sqrt(0.25 + 1.0 + 2.25)));
  for (int v = 0; v < 8; ++v) {
    CHECK(m.vertex_planes_end(v) - m.vertex_planes_begin(v) == 3);
    for (auto p = m.vertex_planes_begin(v); p != m.vertex_planes_end(v); ++p) {
      CHECK(std::abs(p->eval(m.vertex(v))) < 1e-15);
      CHECK(p->neighbor.kind == FeatureKind::kEdge);
      CHECK(m.tail_vertex(p->neighbor.index) == v);
    }
  }
  for (int f = 0; f < 6; ++f) CHECK(m.face_size(f) == 4);
  for (int h = 0; h < 24; ++h) {
    const VoronoiPlane* p = m.edge_planes(h);
    CHECK(p[0].neighbor == Feature::vertex(m.tail_vertex(h)));
    CHECK(p[1].neighbor == Feature::vertex(m.head_vertex(h)));
    CHECK(p[2].neighbor == Feature::face(m.face_of(h)));
    CHECK(p[3].neighbor == Feature::face(m.face_of(m.twin(h))));
    // The edge's own midpoint is inside its region; the face centres are not.
    const Vec3 mid = 0.5 * (m.tail(h) + m.head(h));
    for (int k = 0; k < 4; ++k) CHECK(p[k].eval(mid) > -1e-15);
  }
}

TEST_CASE("points outside lie in the Voronoi region of a closest feature",
          "[distance][feature_mesh]") {
  for (const TestShape& s : {cube(), tetrahedron(), coin(), hull1280()}) {
    const FeatureMesh m(std::get<ConvexPolyhedron>(*s.shape));
    const WorldConvex world = to_world(*s.shape, Pose{});
    std::mt19937_64 rng(77);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    const int samples = s.name == "hull1280" ? 50 : 2000;
    for (int i = 0; i < samples; ++i) {
      const Vec3 x(u(rng), u(rng), u(rng));
      double outside = -kInfinity;
      for (int f = 0; f < m.num_faces(); ++f) outside = std::max(outside, m.face_eval(f, x));
      if (outside <= 0.0) continue;
      const double d_min = point_polyhedron_distance(world, x);
      int containing = 0;
      auto check_feature = [&](Feature f) {
        if (!in_region(m, f, x)) return;
        ++containing;
        INFO(s.name << " sample " << i << " feature " << static_cast<int>(f.kind) << ":"
                    << f.index);
        CHECK(feature_distance(m, f, x) == Approx(d_min).epsilon(1e-12).margin(1e-14));
      };
      for (int v = 0; v < m.num_vertices(); ++v) check_feature(Feature::vertex(v));
      for (int h = 0; h < m.num_half_edges(); ++h) check_feature(Feature::edge(h));
      for (int f = 0; f < m.num_faces(); ++f) check_feature(Feature::face(f));
      CHECK(containing >= 1);
    }
  }
}

TEST_CASE("the point mesh has an unbounded Voronoi region", "[distance][feature_mesh]") {
  const FeatureMesh p = FeatureMesh::point();
  CHECK(p.num_vertices() == 1);
  CHECK(p.num_half_edges() == 0);
  CHECK(p.vertex_planes_begin(0) == p.vertex_planes_end(0));
}
