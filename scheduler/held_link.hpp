#pragma once
// A held contact's geometry (DESIGN.md §8.1-8.2): the link that holds two bodies in contact
// (HeldLink), made once from the pair's closest features at its collision (make_held_link), and
// what it is at any states of the two bodies. The support owns the contact plane (a face, or a
// halfspace), the mover touches it with a face, an edge, a vertex, a sphere, a round side or a
// curved point; where neither side offers a plane, the two touch at a point between two features
// (a point pair). At given states a link gives its plane, frame and patch (place_link), how high
// what else of the mover lies above the plane (held_feature_height, curved_rise) and which pairs
// of edges it watches (edge_watch_candidates, edge_separation); where a patch leaves the
// support's face it turns its roles round or becomes a point pair (swap_roles, to_point_pair).
// Nothing here reads or changes a simulation's state: the island (scheduler/island.hpp) holds the
// links and chooses when each of these applies, so every rule can be tested on hand-made links.
//
// Frames: a link's points and directions are fixed in the two bodies' modelling frames (_M the
// mover's, _S the support's), so it stays valid as the bodies move; what it gives at given states
// is in the world (_W). Units SI: lengths [m]. A curved or round-sided link points at its body's
// shape (curved_shape, side_shape), which outlives the link.
#include "core/body.hpp"
#include "distance/closest_features.hpp"
#include "distance/feature_mesh.hpp"
#include "impulse/contact_dynamics.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace palpable {

// A held contact, in the bodies' own frames (modelling frames M; S for the support's).
struct HeldLink {
  std::uint32_t pair = 0;  // the pair's slot (PairSet)
  BodyId mover, support;
  int support_piece = 0;  // which piece of a compound support holds it
  // > 0: the mover is rounded by this radius about a core: a sphere centred at its origin (no
  // feature), or a cylinder or capsule lying on its side (its feature is then the core, the
  // piece's axis: the contact line is the axis moved by the radius against the normal).
  double sphere_radius = 0.0;
  // The mover's contact feature: a face (counter-clockwise about the mover's outward normal),
  // an edge (2 points) or a vertex (1); empty for a sphere; the axis of a rounded side.
  std::vector<Vec3> mover_feature_M;
  // The support's face (counter-clockwise about normal_S); empty for a halfspace (unbounded).
  std::vector<Vec3> support_face_S;
  Vec3 normal_S = Vec3::UnitZ();  // the contact plane's outward normal, toward the mover
  Vec3 point_S = Vec3::Zero();    // a point of the plane
  Vec3 t1_S = Vec3::UnitX();      // a tangent fixed in the support: slip directions refer to it
  double gap = 0.0;               // the gap held [m] (the mover's feature above the plane)
  // The mover touches the plane with a point of a curved surface (an ellipsoid, a cylinder's
  // rim, a capsule's end, a loaded ball): found afresh at every state as the support point of
  // this smooth shape (the mover's piece, posed at piece_p_M, piece_R_M in its frame) against the
  // plane's normal; mover_feature_M is empty, sphere_radius 0. The shape is the body's geometry,
  // which outlives the link.
  const Shape* curved_shape = nullptr;
  Vec3 piece_p_M = Vec3::Zero();
  Mat3 piece_R_M = Mat3::Identity();
  // A cylinder's or capsule's curved link: the end held, +1 or -1 along the piece's z (the rim or
  // end cap the point lies on, kept even where the body stands level and rounding would pick the
  // other); 0 for other shapes.
  double curved_end = 0.0;
  // A round side's piece (sphere_radius > 0 about its axis): where the line tips about one of its
  // ends, the link goes on as a curved point of that end (curved_shape).
  const Shape* side_shape = nullptr;
  // Neither side offers a plane (two spheres, a sphere or a vertex on an edge, an edge across an
  // edge): a point contact along the line between the two features' closest points. The
  // support's feature is then in support_face_S (1 point, or 2 for an edge; empty for a sphere of
  // radius support_sphere_radius about its origin), and the normal turns with the features.
  bool point_pair = false;
  double support_sphere_radius = 0.0;
  // A point pair of a sphere and a polyhedron's vertex or edge: that feature's Voronoi planes
  // (V-Clip), in the polyhedron's body frame, >= 0 inside. While the sphere's centre is inside
  // them the feature is the polyhedron's closest to it, so the gap held is the bodies' gap; when
  // it leaves them (a ball pushing a turning pin passes from an edge over a face) the link lets
  // go, and the pair's check finds the feature that touches now. Empty: not watched.
  std::vector<VoronoiPlane> feature_region;
  // An edge of a polyhedron held across an edge of another: feature_region is the mover's
  // edge's Voronoi region (in its frame), watched at the support's closest point, and this the
  // support's edge's (in the support's frame), watched at the mover's. While both closest points
  // stay inside, they are the two convex bodies' closest points (V-Clip's condition), so nothing
  // else of either body can touch the other. Empty otherwise.
  std::vector<VoronoiPlane> support_region;
  // Modes, carried from one plan to the next (see HeldContact).
  bool sticks = true;
  Vec2 slip_dir = Vec2::UnitX();
  bool spin_sticks = true;
  double spin_sign = 1.0;
  bool roll_sticks = true;
  Vec2 roll_dir = Vec2::UnitX();
};

// One side of a link at this instant.
struct LinkSide {
  const Body& body;
  const ShapeGeometry& geometry;
  const BodyState& state;
};

// The link of a pair to be held, from the query at its collision: which body owns the plane (a
// face or a halfspace facing the other body), and the other's contact feature; where neither side
// offers a plane, the two features of a point contact. nullopt for two parallel edges without a
// plane (held by neither rule: they stay collisions), and for a curved surface touching along a
// point or a line against anything but a plane (a smooth shape other than a cylinder's flat cap,
// a loaded ball): it stays a train of microcollisions. A curved point on a plane is held with
// the point found afresh from the shape (curved_shape); a cylinder's or capsule's side lying on a
// plane is held like a sphere about its axis (sphere_radius). `envelope` [m]: a rim within the
// landing level of its cap or its other rim is not held (see Island's landing events).
std::optional<HeldLink> make_held_link(std::uint32_t pair, BodyId a, BodyId b,
                                       const LinkSide& side_a, const LinkSide& side_b,
                                       const DistanceResult& closest,
                                       const ContactGeometry& geometry, double envelope);

// The plane and the patch of a link at the given states, in the world: the reference point c (the
// patch's centroid, on the mover's feature), the frame, and the patch (the mover's feature
// intersected with the support's face, projected on the plane). Empty `polygon` and kPoint for a
// single point. Returns false if the patch vanished (the mover left the support's face).
bool place_link(const HeldLink& link, const BodyState& mover, const BodyState& support,
                HeldContact& out);

// How far a polyhedral mover's held feature (mover_feature_M) is above the link's plane at the
// given states: its lowest point [m]; +inf for a link without one (a sphere, a curved point).
double held_feature_height(const HeldLink& link, const BodyState& mover, const BodyState& support);

// How far above a curved link's touching point the mover's next part lies, from the direction d
// of -n in the piece's frame: for a cylinder on a rim, its rim's far side (2 r |d_xy|: it lands on
// its cap) or its other rim (2 h |d_z|: on its side); for a capsule on one end, the other end
// (2 h |d_z|). Infinite for shapes with nothing else that can touch (an ellipsoid, a ball).
// `end`: the end held (HeldLink::curved_end); the other end's rise is negative where it lies
// lower than the held one.
double curved_rise(const Shape& shape, const Vec3& d, double end);

// The rise below which that next part has landed: half the held point's height, at least a
// quarter envelope (as for a polyhedron's other vertices).
double landing_level(double held_height, double envelope);

// A support's edge watched against one of a held mover's edges (Island::integrate's landing
// event): their half-edges in the two pieces' meshes, their common normal when they were chosen
// (in the world, pointing out of the support), and the threshold their separation along it must
// stay above (edge_watch_candidates: the separation).
struct EdgeWatch {
  int support_edge, mover_edge;
  Vec3 axis_W;
  double threshold;
};

// The pairs of edges a held link watches besides its vertices, each with its present separation:
// an edge of the support and an edge of the mover (not one whose both ends are `held_vertex`,
// the feature held, whose leaving the patch the tip event watches) whose lines pass within
// `envelope` of each other at points inside both edges, at least 1e-3 rad from parallel, and
// whose common normal lies in both edges' normal cones (a Minkowski face: along it, the
// separation of the two edges is the two pieces' separation near there, negative where they
// cross). These are the crossings that no vertex watch sees: neither body's vertex enters the
// other. Both pieces are posed in the world (rotation and origin of the piece's frame).
std::vector<EdgeWatch> edge_watch_candidates(const ShapeGeometry::Piece& mover, const Mat3& R_mover,
                                             const Vec3& origin_mover,
                                             const std::vector<bool>& held_vertex,
                                             const ShapeGeometry::Piece& support,
                                             const Mat3& R_support, const Vec3& origin_support,
                                             double envelope);

// The separation of a watched pair of edges along their common normal now, oriented as the
// watch's axis (out of the support: negative where they cross; the cross product of the edges
// reverses where they turn through parallel, the axis does not); +inf where the normal has
// turned more than 60 degrees from the axis, or the edges are parallel (not the configuration
// chosen: the faces' and vertices' watches cover it). Both meshes posed in the world.
double edge_separation(const FeatureMesh& support, const Mat3& R_support,
                       const Vec3& origin_support, const FeatureMesh& mover, const Mat3& R_mover,
                       const Vec3& origin_mover, const EdgeWatch& watch);

// The edge of a link's support face (support_face_S, in the world at `support`) on which all
// `points` lie, measured within the link's plane (along its normal), to 1e-9 of the face's size;
// -1 if none (or the support offers no face). A reduced patch on such an edge tips the mover over
// the support's edge: the link's roles turn round.
int support_edge_under(const HeldLink& link, const BodyState& support,
                       const std::vector<Vec3>& points);

// The link seen the other way round: the old mover's face becomes the plane, the support's edge
// `edge` the feature on it (a block sliding over the edge of a table, which it then tips over).
// False if the mover offers no face.
bool swap_roles(HeldLink& link, int edge, const BodyState& mover, const BodyState& support);

// A plane link whose sphere rolled or slid off the support's face: the same contact, now between
// the sphere and the face's boundary edge nearest to it (a ball going over a table's edge). False
// for any other mover (a polyhedron's vertex or edge on an edge is not held: see point_pair_link)
// and for an unbounded support (nothing to leave).
bool to_point_pair(HeldLink& link, const BodyState& mover, const BodyState& support);

}  // namespace palpable
