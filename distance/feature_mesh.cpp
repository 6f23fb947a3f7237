#include "distance/feature_mesh.hpp"

#include "core/check.hpp"

#include <algorithm>
#include <string>

namespace palpable {

namespace {

VoronoiPlane make_plane(const Vec3& normal_M, const Vec3& point_M, Feature neighbor) {
  VoronoiPlane plane;
  plane.normal_M = normal_M;
  plane.offset = normal_M.dot(point_M);
  plane.neighbor = neighbor;
  return plane;
}

}  // namespace

FeatureMesh::FeatureMesh(const ConvexPolyhedron& polyhedron) {
  const std::vector<Vec3>& vertices = polyhedron.vertices();
  const std::vector<HalfEdge>& half_edges = polyhedron.half_edges();
  const std::vector<PolyFace>& faces = polyhedron.faces();
  const int num_v = static_cast<int>(vertices.size());
  const int num_h = static_cast<int>(half_edges.size());
  const int num_f = static_cast<int>(faces.size());
  if (num_v < 4 || num_h < 12 || num_f < 4) {
    throw InputError("polyhedron", "a convex polyhedron needs at least 4 vertices and 4 faces");
  }
  vertices_ = vertices;
  half_edges_.resize(num_h);
  for (int h = 0; h < num_h; ++h) {
    const HalfEdge& e = half_edges[h];
    const bool ok = e.tail >= 0 && e.tail < num_v && e.twin >= 0 && e.twin < num_h &&
                    half_edges[e.twin].twin == h && e.next >= 0 && e.next < num_h && e.face >= 0 &&
                    e.face < num_f && half_edges[e.next].face == e.face;
    if (!ok) {
      throw InputError("polyhedron/half_edges/" + std::to_string(h),
                       "not a closed two-manifold half-edge mesh");
    }
    half_edges_[h] = {e.tail, e.twin, e.next, e.face};
  }
  for (const Vec3& v : vertices_) max_radius_ = std::max(max_radius_, v.norm());

  face_normals_.resize(num_f);
  face_offsets_.resize(num_f);
  face_half_edge_.resize(num_f);
  for (int f = 0; f < num_f; ++f) {
    face_normals_[f] = faces[f].normal_M;
    face_offsets_[f] = faces[f].offset;
    face_half_edge_[f] = faces[f].half_edge;
  }

  // Vertex regions: the planes through the vertex perpendicular to each incident edge (Mirtich
  // 1998, section 3.1): x is in VR(v) across edge h only if (v - x) . u_h >= 0.
  vertex_plane_begin_.assign(num_v + 1, 0);
  for (const Edge& e : half_edges_) ++vertex_plane_begin_[e.tail + 1];
  for (int v = 0; v < num_v; ++v) vertex_plane_begin_[v + 1] += vertex_plane_begin_[v];
  planes_.resize(vertex_plane_begin_[num_v]);
  std::vector<int> fill(vertex_plane_begin_.begin(), vertex_plane_begin_.end() - 1);
  for (int h = 0; h < num_h; ++h) {
    const Vec3 u = (head(h) - tail(h)).normalized();
    planes_[fill[half_edges_[h].tail]++] = make_plane(-u, tail(h), Feature::edge(h));
  }

  // Edge regions: two planes perpendicular to the edge at its ends, and two planes through the
  // edge perpendicular to its two faces.
  edge_plane_base_ = static_cast<int>(planes_.size());
  planes_.reserve(planes_.size() + 4 * num_h);
  for (int h = 0; h < num_h; ++h) {
    const Vec3 u = (head(h) - tail(h)).normalized();
    const Vec3& n_left = face_normals_[half_edges_[h].face];
    const Vec3& n_right = face_normals_[half_edges_[twin(h)].face];
    planes_.push_back(make_plane(u, tail(h), Feature::vertex(tail_vertex(h))));
    planes_.push_back(make_plane(-u, head(h), Feature::vertex(head_vertex(h))));
    planes_.push_back(
        make_plane(u.cross(n_left).normalized(), tail(h), Feature::face(half_edges_[h].face)));
    planes_.push_back(make_plane(n_right.cross(u).normalized(), tail(h),
                                 Feature::face(half_edges_[twin(h)].face)));
  }

  // Face regions: the planes through each boundary edge perpendicular to the face; the face
  // interior lies to the left of its counter-clockwise half-edges, n_f x u_h.
  face_plane_begin_.assign(num_f + 1, 0);
  for (int f = 0; f < num_f; ++f) {
    face_plane_begin_[f] = static_cast<int>(planes_.size());
    int h = face_half_edge_[f];
    int count = 0;
    do {
      const Vec3 u = (head(h) - tail(h)).normalized();
      planes_.push_back(
          make_plane(face_normals_[f].cross(u).normalized(), tail(h), Feature::edge(h)));
      h = half_edges_[h].next;
      if (++count > num_h) {
        throw InputError("polyhedron/faces/" + std::to_string(f), "half-edge cycle does not close");
      }
    } while (h != face_half_edge_[f]);
  }
  face_plane_begin_[num_f] = static_cast<int>(planes_.size());
}

FeatureMesh FeatureMesh::point() {
  FeatureMesh mesh;
  mesh.vertices_.push_back(Vec3::Zero());
  mesh.vertex_plane_begin_ = {0, 0};
  mesh.face_plane_begin_ = {0};
  return mesh;
}

}  // namespace palpable
