#pragma once
// The Voronoi structure of a convex polyhedron for closest-feature tracking (V-Clip: B. Mirtich,
// "V-Clip: Fast and Robust Polyhedral Collision Detection", ACM TOG 17(3), 1998; MERL TR-97-05,
// section 3). Built once per polyhedron in its modelling frame M and immutable afterwards: the
// shapes it is built from are immutable, so it is cached beside them (ShapeGeometry).
//
// Features are vertices, edges and faces. An edge is named by either of its two half-edges; the
// Voronoi planes of an edge are stored per half-edge (the two half-edges of one edge describe the
// same region). Each Voronoi plane is stored with its sign chosen so that eval(x) >= 0 on the side
// of the plane's owner feature; the plane's neighbour is the feature across it.
#include "core/shape.hpp"
#include "core/types.hpp"

#include <cstdint>
#include <vector>

namespace palpable {

enum class FeatureKind : std::uint8_t { kNone, kVertex, kEdge, kFace };

struct Feature {
  std::int32_t index = -1;
  FeatureKind kind = FeatureKind::kNone;

  static Feature vertex(int i) { return {i, FeatureKind::kVertex}; }
  static Feature edge(int half_edge) { return {half_edge, FeatureKind::kEdge}; }
  static Feature face(int i) { return {i, FeatureKind::kFace}; }
  bool valid() const { return kind != FeatureKind::kNone; }
  friend bool operator==(Feature a, Feature b) { return a.index == b.index && a.kind == b.kind; }
  friend bool operator!=(Feature a, Feature b) { return !(a == b); }
};

// A Voronoi plane in M: eval(x) = normal_M . x - offset, >= 0 on the owner's side.
struct VoronoiPlane {
  Vec3 normal_M = Vec3::Zero();
  double offset = 0.0;
  Feature neighbor;
  double eval(const Vec3& x_M) const { return normal_M.dot(x_M) - offset; }
};

class FeatureMesh {
 public:
  // From a half-edge polyhedron (faces with counter-clockwise half-edges about their outward
  // normals). Throws InputError if the mesh is not a closed two-manifold.
  explicit FeatureMesh(const ConvexPolyhedron& polyhedron);
  // A single vertex at the origin whose Voronoi region is all of space: the centre of a sphere,
  // so that sphere-polyhedron queries run through the same V-Clip states (V-V, V-E, V-F).
  static FeatureMesh point();

  int num_vertices() const { return static_cast<int>(vertices_.size()); }
  int num_half_edges() const { return static_cast<int>(half_edges_.size()); }
  int num_faces() const { return static_cast<int>(face_normals_.size()); }

  const Vec3& vertex(int v) const { return vertices_[v]; }
  int tail_vertex(int h) const { return half_edges_[h].tail; }
  int head_vertex(int h) const { return half_edges_[half_edges_[h].twin].tail; }
  const Vec3& tail(int h) const { return vertices_[half_edges_[h].tail]; }
  const Vec3& head(int h) const { return vertices_[head_vertex(h)]; }
  int twin(int h) const { return half_edges_[h].twin; }
  int next(int h) const { return half_edges_[h].next; }
  int face_of(int h) const { return half_edges_[h].face; }
  int face_half_edge(int f) const { return face_half_edge_[f]; }
  int face_size(int f) const { return face_plane_begin_[f + 1] - face_plane_begin_[f]; }

  const Vec3& face_normal(int f) const { return face_normals_[f]; }
  double face_offset(int f) const { return face_offsets_[f]; }
  double face_eval(int f, const Vec3& x_M) const {
    return face_normals_[f].dot(x_M) - face_offsets_[f];
  }

  // Voronoi planes of a vertex: one per incident edge (neighbour: the edge, as the half-edge
  // leaving the vertex).
  const VoronoiPlane* vertex_planes_begin(int v) const {
    return planes_.data() + vertex_plane_begin_[v];
  }
  const VoronoiPlane* vertex_planes_end(int v) const {
    return planes_.data() + vertex_plane_begin_[v + 1];
  }
  // Voronoi planes of an edge, four per half-edge in this order: tail vertex, head vertex, left
  // face (the half-edge's own face), right face (its twin's face).
  const VoronoiPlane* edge_planes(int h) const { return planes_.data() + edge_plane_base_ + 4 * h; }
  // Voronoi side planes of a face: one per boundary edge (neighbour: the face's own half-edge),
  // in the order of the face's half-edge cycle.
  const VoronoiPlane* face_planes_begin(int f) const {
    return planes_.data() + face_plane_begin_[f];
  }
  const VoronoiPlane* face_planes_end(int f) const {
    return planes_.data() + face_plane_begin_[f + 1];
  }

  // Largest distance from the origin of M to a vertex [m].
  double max_radius() const { return max_radius_; }

 private:
  FeatureMesh() = default;

  struct Edge {
    int tail = -1;
    int twin = -1;
    int next = -1;
    int face = -1;
  };
  std::vector<Vec3> vertices_;
  std::vector<Edge> half_edges_;
  std::vector<Vec3> face_normals_;
  std::vector<double> face_offsets_;
  std::vector<int> face_half_edge_;
  std::vector<VoronoiPlane> planes_;
  std::vector<int> vertex_plane_begin_;  // size num_vertices + 1
  std::vector<int> face_plane_begin_;    // size num_faces + 1
  int edge_plane_base_ = 0;
  double max_radius_ = 0.0;
};

}  // namespace palpable
