#include "distance/vclip.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

const char* to_string(ContactStatus status) {
  switch (status) {
    case ContactStatus::kSeparated: return "separated";
    case ContactStatus::kTouching: return "touching";
    case ContactStatus::kPenetrating: return "penetrating";
    case ContactStatus::kFailed: return "failed";
  }
  return "unknown";
}

Vec3 closest_point_segment(const Vec3& p, const Vec3& q, const Vec3& x) {
  const Vec3 d = q - p;
  const double dd = d.squaredNorm();
  if (dd <= 0.0) return p;
  const double s = std::clamp((x - p).dot(d) / dd, 0.0, 1.0);
  return p + s * d;
}

double closest_points_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                      const Vec3& q2, Vec3& c1, Vec3& c2) {
  double s, t;
  return closest_params_segment_segment(p1, q1, p2, q2, s, t, c1, c2);
}

double closest_params_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                      const Vec3& q2, double& s, double& t, Vec3& c1, Vec3& c2) {
  const Vec3 d1 = q1 - p1;
  const Vec3 d2 = q2 - p2;
  const Vec3 r = p1 - p2;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  s = 0.0;
  t = 0.0;
  if (a <= 0.0 && e <= 0.0) {
    c1 = p1;
    c2 = p2;
    return (c1 - c2).squaredNorm();
  }
  if (a <= 0.0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0.0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
  return (c1 - c2).squaredNorm();
}

namespace {

// kZero: the features meet (distance exactly 0) and the walk cannot tell touching from overlap;
// resolved by a local separating-axis test at the end.
enum class Step { kContinue, kDone, kPenetrating, kZero };

// The part [lo, hi] of the edge e(l) = tail + l (head - tail) inside a Voronoi region, with the
// neighbours across the planes that cut it (Mirtich 1998, figure 7, "ClipEdge").
struct Clip {
  double lo = 0.0;
  double hi = 1.0;
  Feature n_lo;
  Feature n_hi;
  bool excluded = false;  // the whole edge is outside the region
  bool simple = false;    // ... and one plane excludes it alone (n_lo == n_hi is that plane's)
};

inline void clip_edge(const Vec3& tail, const Vec3& head, const VoronoiPlane* begin,
                      const VoronoiPlane* end, Clip& c) {
  for (const VoronoiPlane* p = begin; p != end; ++p) {
    const double dt = p->eval(tail);
    const double dh = p->eval(head);
    if (dt < 0.0) {
      if (dh < 0.0) {
        c.n_lo = c.n_hi = p->neighbor;
        c.excluded = c.simple = true;
        return;
      }
      const double l = dt / (dt - dh);
      if (l > c.lo) {
        c.lo = l;
        c.n_lo = p->neighbor;
        if (c.lo > c.hi) {
          c.excluded = true;
          return;
        }
      }
    } else if (dh < 0.0) {
      const double l = dt / (dt - dh);
      if (l < c.hi) {
        c.hi = l;
        c.n_hi = p->neighbor;
        if (c.hi < c.lo) {
          c.excluded = true;
          return;
        }
      }
    }
  }
}

struct Solver {
  const FeatureMesh* mesh[2];
  Mat3 R;   // B -> A rotation
  Vec3 t;   // B -> A translation
  Mat3 Rt;  // A -> B rotation
  Vec3 tt;  // A -> B translation
  Feature f[2];
  Vec3 n_penetration_A = Vec3::UnitX();

  // A point of body `from` (the other body) in the frame of body `frame`.
  Vec3 to(int frame, const Vec3& p) const {
    return frame == 0 ? Vec3(R * p + t) : Vec3(Rt * p + tt);
  }
  Vec3 dir_to(int frame, const Vec3& d) const { return frame == 0 ? Vec3(R * d) : Vec3(Rt * d); }
  Vec3 to_a(int frame, const Vec3& p) const { return frame == 0 ? p : Vec3(R * p + t); }
  Vec3 dir_to_a(int frame, const Vec3& d) const { return frame == 0 ? d : Vec3(R * d); }

  Step vertex_vertex() {
    const FeatureMesh& a = *mesh[0];
    const FeatureMesh& b = *mesh[1];
    const Vec3 vb = to(0, b.vertex(f[1].index));
    for (const VoronoiPlane* p = a.vertex_planes_begin(f[0].index);
         p != a.vertex_planes_end(f[0].index); ++p) {
      if (p->eval(vb) < 0.0) {
        f[0] = p->neighbor;
        return Step::kContinue;
      }
    }
    const Vec3 va = to(1, a.vertex(f[0].index));
    for (const VoronoiPlane* p = b.vertex_planes_begin(f[1].index);
         p != b.vertex_planes_end(f[1].index); ++p) {
      if (p->eval(va) < 0.0) {
        f[1] = p->neighbor;
        return Step::kContinue;
      }
    }
    return Step::kDone;
  }

  Step vertex_edge(int iv, int ie) {
    const FeatureMesh& mv = *mesh[iv];
    const FeatureMesh& me = *mesh[ie];
    const int v = f[iv].index;
    const int h = f[ie].index;
    const Vec3 p = to(ie, mv.vertex(v));
    const VoronoiPlane* planes = me.edge_planes(h);
    for (int k = 0; k < 4; ++k) {
      if (planes[k].eval(p) < 0.0) {
        f[ie] = planes[k].neighbor;
        return Step::kContinue;
      }
    }
    const Vec3 tail = to(iv, me.tail(h));
    const Vec3 head = to(iv, me.head(h));
    Clip c;
    clip_edge(tail, head, mv.vertex_planes_begin(v), mv.vertex_planes_end(v), c);
    if (c.simple) {
      f[iv] = c.n_lo;
      return Step::kContinue;
    }
    const Vec3& V = mv.vertex(v);
    const Vec3 seg = head - tail;
    if (c.n_lo.valid() && (tail + c.lo * seg - V).dot(seg) > 0.0) {
      f[iv] = c.n_lo;
      return Step::kContinue;
    }
    if (c.n_hi.valid() && (tail + c.hi * seg - V).dot(seg) < 0.0) {
      f[iv] = c.n_hi;
      return Step::kContinue;
    }
    if (c.excluded) {
      f[iv] = c.n_lo.valid() ? c.n_lo : c.n_hi;
      return Step::kContinue;
    }
    return Step::kDone;
  }

  Step vertex_face(int iv, int iF) {
    const FeatureMesh& mv = *mesh[iv];
    const FeatureMesh& mf = *mesh[iF];
    const int v = f[iv].index;
    const int face = f[iF].index;
    const Vec3 p = to(iF, mv.vertex(v));
    // V outside the face's side planes: move to the boundary feature of F nearest to V among the
    // edges whose planes it violates — the edge, or its end vertex where the boundary comes
    // closest at a corner (the distance to F is the distance to it: a downward move).
    Feature best;
    double best_d2 = kInfinity;
    for (const VoronoiPlane* q = mf.face_planes_begin(face); q != mf.face_planes_end(face); ++q) {
      if (q->eval(p) < 0.0) {
        const int h = q->neighbor.index;
        const Vec3 d = mf.head(h) - mf.tail(h);
        const double s = std::clamp((p - mf.tail(h)).dot(d) / d.squaredNorm(), 0.0, 1.0);
        const double d2 = (mf.tail(h) + s * d - p).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = s <= 0.0   ? Feature::vertex(mf.tail_vertex(h))
                 : s >= 1.0 ? Feature::vertex(mf.head_vertex(h))
                            : Feature::edge(h);
        }
      }
    }
    if (best.valid()) {
      f[iF] = best;
      return Step::kContinue;
    }
    const double d = mf.face_eval(face, p);
    // An edge of V pointing toward F's plane (from either side) reduces |d|: F is not in VR(V).
    // The slope is computed exactly as the E-F state computes it, d(head) - d(tail) with both
    // ends mapped into F's frame (d(tail) is d), so that the two states agree on its sign: for an
    // edge parallel to F up to rounding, the normal dotted with the edge in V's frame (-7e-18
    // where E-F saw 0) sent V-F to the edge and E-F back to V until the step limit
    // (tests/fuzz/findings/engine_timeout_distance_steps.bin).
    for (const VoronoiPlane* q = mv.vertex_planes_begin(v); q != mv.vertex_planes_end(v); ++q) {
      const double dd = mf.face_eval(face, to(iF, mv.head(q->neighbor.index))) - d;
      if ((d > 0.0 && dd < 0.0) || (d < 0.0 && dd > 0.0)) {
        f[iv] = q->neighbor;
        return Step::kContinue;
      }
    }
    if (d > 0.0) return Step::kDone;
    // Local minimum (Mirtich 1998, section 5.4): V is on or below F's plane and no edge of V
    // leads up. Either some face plane of F's polyhedron has V above it (move there), or V is
    // inside every face plane: penetration (or exactly on the surface: touching).
    int best_face = face;
    double best_eval = d;
    for (int g = 0; g < mf.num_faces(); ++g) {
      const double e = mf.face_eval(g, p);
      if (e > best_eval) {
        best_eval = e;
        best_face = g;
      }
    }
    if (best_eval > 0.0) {
      f[iF] = Feature::face(best_face);
      return Step::kContinue;
    }
    f[iF] = Feature::face(best_face);
    if (best_eval == 0.0) return Step::kZero;
    const Vec3 n = dir_to_a(iF, mf.face_normal(best_face));
    n_penetration_A = iF == 1 ? n : Vec3(-n);
    return Step::kPenetrating;
  }

  // Clips the edge of body `ic` against the Voronoi region of the edge of body `io`.
  Step edge_edge_subtest(int ic, int io) {
    const FeatureMesh& mc = *mesh[ic];
    const FeatureMesh& mo = *mesh[io];
    const int hc = f[ic].index;
    const int ho = f[io].index;
    const Vec3 tail = to(io, mc.tail(hc));
    const Vec3 head = to(io, mc.head(hc));
    const Vec3 seg = head - tail;
    const VoronoiPlane* planes = mo.edge_planes(ho);
    Clip c;
    clip_edge(tail, head, planes, planes + 2, c);
    if (c.simple) {
      f[io] = c.n_lo;
      return Step::kContinue;
    }
    const Clip vertex_clip = c;
    clip_edge(tail, head, planes + 2, planes + 4, c);
    auto vertex_derivative = [&](double l, Feature vertex) {
      return (tail + l * seg - mo.vertex(vertex.index)).dot(seg);
    };
    auto face_derivative = [&](double l, Feature face) {
      // The slope is computed exactly as the E-F state computes it (d(head) - d(tail)), so the
      // two states agree on its sign even for an edge nearly parallel to the face: otherwise
      // rounding can send E-E up to F and E-F back down to the edge forever.
      const double d_tail = mo.face_eval(face.index, tail);
      const double slope = mo.face_eval(face.index, head) - d_tail;
      const double d = d_tail + l * slope;
      return d > 0.0 ? slope : (d < 0.0 ? -slope : 0.0);
    };
    if (c.simple) {
      // Excluded by a face plane alone: first the vertex crossings' derivatives, else the face.
      if (vertex_clip.n_lo.valid() && vertex_derivative(vertex_clip.lo, vertex_clip.n_lo) > 0.0) {
        f[io] = vertex_clip.n_lo;
      } else if (vertex_clip.n_hi.valid() &&
                 vertex_derivative(vertex_clip.hi, vertex_clip.n_hi) < 0.0) {
        f[io] = vertex_clip.n_hi;
      } else {
        f[io] = c.n_lo;
      }
      return Step::kContinue;
    }
    if (c.excluded) {
      if (c.n_lo.kind == FeatureKind::kVertex) {
        f[io] = vertex_derivative(c.lo, c.n_lo) >= 0.0 ? c.n_lo : c.n_hi;
        return Step::kContinue;
      }
      if (c.n_hi.kind == FeatureKind::kVertex) {
        f[io] = vertex_derivative(c.hi, c.n_hi) <= 0.0 ? c.n_hi : c.n_lo;
        return Step::kContinue;
      }
      // The edge passes beneath E through both neighbouring face planes: go to the face whose
      // side the distance decreases toward.
      const double d_tail = mo.face_eval(c.n_lo.index, tail);
      const double d_head = mo.face_eval(c.n_lo.index, head);
      const double d_lo = d_tail + c.lo * (d_head - d_tail);
      if (d_lo > 0.0) {
        f[io] = d_tail < d_head ? c.n_lo : c.n_hi;
      } else {
        f[io] = d_tail > d_head ? c.n_lo : c.n_hi;
      }
      return Step::kContinue;
    }
    if (c.n_lo.valid()) {
      const double dd = c.n_lo.kind == FeatureKind::kVertex ? vertex_derivative(c.lo, c.n_lo)
                                                            : face_derivative(c.lo, c.n_lo);
      if (dd > 0.0) {
        f[io] = c.n_lo;
        return Step::kContinue;
      }
    }
    if (c.n_hi.valid()) {
      const double dd = c.n_hi.kind == FeatureKind::kVertex ? vertex_derivative(c.hi, c.n_hi)
                                                            : face_derivative(c.hi, c.n_hi);
      if (dd < 0.0) {
        f[io] = c.n_hi;
        return Step::kContinue;
      }
    }
    return Step::kDone;
  }

  Step edge_edge() {
    const Step s = edge_edge_subtest(1, 0);
    if (s != Step::kDone) return s;
    return edge_edge_subtest(0, 1);
  }

  Step edge_face(int ie, int iF) {
    const FeatureMesh& me = *mesh[ie];
    const FeatureMesh& mf = *mesh[iF];
    const int h = f[ie].index;
    const int face = f[iF].index;
    const Vec3 tail = to(iF, me.tail(h));
    const Vec3 head = to(iF, me.head(h));
    Clip c;
    clip_edge(tail, head, mf.face_planes_begin(face), mf.face_planes_end(face), c);
    if (c.excluded) {
      // E misses F's region: the closest point of F to E is on F's boundary. Move to the
      // boundary feature nearest to E, an edge or, where the boundary comes closest at a corner,
      // that vertex (same distance: a downward move).
      Feature best;
      double best_d2 = kInfinity;
      for (const VoronoiPlane* q = mf.face_planes_begin(face); q != mf.face_planes_end(face); ++q) {
        const int g = q->neighbor.index;
        Vec3 c1, c2;
        double s_e, s_g;
        const double d2 =
            closest_params_segment_segment(tail, head, mf.tail(g), mf.head(g), s_e, s_g, c1, c2);
        if (d2 < best_d2) {
          best_d2 = d2;
          best = s_g <= 0.0   ? Feature::vertex(mf.tail_vertex(g))
                 : s_g >= 1.0 ? Feature::vertex(mf.head_vertex(g))
                              : Feature::edge(g);
        }
      }
      f[iF] = best;
      return Step::kContinue;
    }
    const double d_tail = mf.face_eval(face, tail);
    const double d_head = mf.face_eval(face, head);
    const double d_lo = c.n_lo.valid() ? d_tail + c.lo * (d_head - d_tail) : d_tail;
    const double d_hi = c.n_hi.valid() ? d_tail + c.hi * (d_head - d_tail) : d_head;
    // The edge pierces F inside F's region: overlap. (Through F's boundary exactly, it may only
    // touch: decided at the end like every zero distance.)
    if ((d_lo < 0.0 && d_hi > 0.0) || (d_lo > 0.0 && d_hi < 0.0)) {
      const Vec3 pierce = tail + (d_tail / (d_tail - d_head)) * (head - tail);
      for (const VoronoiPlane* q = mf.face_planes_begin(face); q != mf.face_planes_end(face); ++q) {
        if (q->eval(pierce) <= 0.0) return Step::kZero;
      }
      const Vec3 n = dir_to_a(iF, mf.face_normal(face));
      n_penetration_A = iF == 1 ? n : Vec3(-n);
      return Step::kPenetrating;
    }
    // E meets F's plane inside F: touching or overlap, decided at the end.
    if (d_lo == 0.0 || d_hi == 0.0) return Step::kZero;
    // Derivative rule: |d| not decreasing from the low end means the closest point is at or
    // before it: the tail vertex, or F's boundary edge across which E left the region.
    if ((d_lo > 0.0 && d_tail <= d_head) || (d_lo < 0.0 && d_tail >= d_head)) {
      if (c.n_lo.valid()) {
        f[iF] = c.n_lo;
      } else {
        f[ie] = Feature::vertex(me.tail_vertex(h));
      }
    } else {
      if (c.n_hi.valid()) {
        f[iF] = c.n_hi;
      } else {
        f[ie] = Feature::vertex(me.head_vertex(h));
      }
    }
    return Step::kContinue;
  }

  // Calls on_face(normal) and on_edge(direction), in A's frame, for every face and edge of body
  // i through the point x_A (within tol).
  template <typename FaceFn, typename EdgeFn>
  void features_through(int i, const Vec3& x_A, double tol, FaceFn&& on_face,
                        EdgeFn&& on_edge) const {
    const FeatureMesh& m = *mesh[i];
    const Vec3 x = i == 0 ? x_A : Vec3(Rt * x_A + tt);
    for (int g = 0; g < m.num_faces(); ++g) {
      if (std::abs(m.face_eval(g, x)) <= tol) on_face(dir_to_a(i, m.face_normal(g)));
    }
    for (int h = 0; h < m.num_half_edges(); ++h) {
      if (h > m.twin(h)) continue;
      if ((closest_point_segment(m.tail(h), m.head(h), x) - x).norm() <= tol) {
        on_edge(dir_to_a(i, Vec3(m.head(h) - m.tail(h))));
      }
    }
  }

  // For features that meet (distance 0) at p_A: is there a plane separating the two interiors?
  // The candidates are the separating-axis theorem's, restricted to the faces and edges through
  // the contact point: face normals of either body and cross products of an edge of each.
  // Returns the separating normal oriented from B to A, or zero if the interiors overlap.
  Vec3 local_separating_axis(const Vec3& p_A) const {
    constexpr int kMaxAxes = 128;
    constexpr int kMaxEdges = 16;
    Vec3 axes[kMaxAxes];
    int count = 0;
    Vec3 edges_a[kMaxEdges];
    int num_edges_a = 0;
    const double tol = 1e-12 * (mesh[0]->max_radius() + mesh[1]->max_radius() + t.norm());
    auto add_axis = [&](const Vec3& n) {
      if (count < kMaxAxes) axes[count++] = n;
    };
    features_through(0, p_A, tol, add_axis, [&](const Vec3& e) {
      if (num_edges_a < kMaxEdges) edges_a[num_edges_a++] = e;
    });
    features_through(1, p_A, tol, add_axis, [&](const Vec3& e) {
      for (int k = 0; k < num_edges_a; ++k) {
        const Vec3 c = edges_a[k].cross(e);
        const double norm = c.norm();
        if (norm > 1e-12 * edges_a[k].norm() * e.norm()) add_axis(c / norm);
      }
    });
    const FeatureMesh& a = *mesh[0];
    const FeatureMesh& b = *mesh[1];
    for (int k = 0; k < count; ++k) {
      const Vec3& L = axes[k];
      const Vec3 L_b = Rt * L;
      const double shift = L.dot(t);
      double max_a = -kInfinity, min_a = kInfinity, max_b = -kInfinity, min_b = kInfinity;
      for (int v = 0; v < a.num_vertices(); ++v) {
        const double x = L.dot(a.vertex(v));
        max_a = std::max(max_a, x);
        min_a = std::min(min_a, x);
      }
      for (int v = 0; v < b.num_vertices(); ++v) {
        const double x = L_b.dot(b.vertex(v)) + shift;
        max_b = std::max(max_b, x);
        min_b = std::min(min_b, x);
      }
      if (max_a <= min_b) return -L;  // A below B along L: n from B to A is -L
      if (max_b <= min_a) return L;
    }
    return Vec3::Zero();
  }

  // Closest points (in A) of the final feature pair.
  void closest_points(Vec3& p_a, Vec3& p_b) const {
    Vec3 pts[2];
    const FeatureKind ka = f[0].kind;
    const FeatureKind kb = f[1].kind;
    auto feature_point = [&](int i) { return to_a(i, mesh[i]->vertex(f[i].index)); };
    if (ka == FeatureKind::kVertex && kb == FeatureKind::kVertex) {
      pts[0] = feature_point(0);
      pts[1] = feature_point(1);
    } else if (ka == FeatureKind::kEdge && kb == FeatureKind::kEdge) {
      closest_points_segment_segment(
          to_a(0, mesh[0]->tail(f[0].index)), to_a(0, mesh[0]->head(f[0].index)),
          to_a(1, mesh[1]->tail(f[1].index)), to_a(1, mesh[1]->head(f[1].index)), pts[0], pts[1]);
    } else if (ka == FeatureKind::kFace || kb == FeatureKind::kFace) {
      const int iF = ka == FeatureKind::kFace ? 0 : 1;
      const int io = 1 - iF;
      const FeatureMesh& mf = *mesh[iF];
      const int face = f[iF].index;
      if (f[io].kind == FeatureKind::kVertex) {
        const Vec3 p = to(iF, mesh[io]->vertex(f[io].index));
        pts[io] = to_a(iF, p);
        pts[iF] = to_a(iF, Vec3(p - mf.face_eval(face, p) * mf.face_normal(face)));
      } else {
        // Edge meeting a face: the crossing of the plane, else the clipped end nearest to it.
        const Vec3 tail = to(iF, mesh[io]->tail(f[io].index));
        const Vec3 head = to(iF, mesh[io]->head(f[io].index));
        Clip c;
        clip_edge(tail, head, mf.face_planes_begin(face), mf.face_planes_end(face), c);
        const Vec3 e_lo = tail + c.lo * (head - tail);
        const Vec3 e_hi = tail + c.hi * (head - tail);
        const double d_lo = mf.face_eval(face, e_lo);
        const double d_hi = mf.face_eval(face, e_hi);
        Vec3 p = std::abs(d_lo) <= std::abs(d_hi) ? e_lo : e_hi;
        if ((d_lo < 0.0 && d_hi > 0.0) || (d_lo > 0.0 && d_hi < 0.0)) {
          p = e_lo + (d_lo / (d_lo - d_hi)) * (e_hi - e_lo);  // where E crosses F's plane
        }
        pts[io] = to_a(iF, p);
        pts[iF] = to_a(iF, Vec3(p - mf.face_eval(face, p) * mf.face_normal(face)));
      }
    } else {
      const int iv = ka == FeatureKind::kVertex ? 0 : 1;
      const int ie = 1 - iv;
      pts[iv] = feature_point(iv);
      pts[ie] = closest_point_segment(to_a(ie, mesh[ie]->tail(f[ie].index)),
                                      to_a(ie, mesh[ie]->head(f[ie].index)), pts[iv]);
    }
    p_a = pts[0];
    p_b = pts[1];
  }

  // The normal that separated features fix by themselves, oriented from B to A (along `diff`,
  // from B's closest point to A's): a face's, or two crossing edges' cross product; zero where
  // only the closest points fix it (a vertex against a vertex or an edge, parallel edges). At a
  // gap of a few ulps of the coordinates diff / |diff| is mostly rounding (an impact applied at
  // the instant of contact, DESIGN.md §8.5); these are not.
  Vec3 feature_normal(const Vec3& diff) const {
    if (f[0].kind == FeatureKind::kFace) return -mesh[0]->face_normal(f[0].index);
    if (f[1].kind == FeatureKind::kFace) return R * mesh[1]->face_normal(f[1].index);
    if (f[0].kind != FeatureKind::kEdge || f[1].kind != FeatureKind::kEdge) return Vec3::Zero();
    const Vec3 ua = mesh[0]->head(f[0].index) - mesh[0]->tail(f[0].index);
    const Vec3 ub = R * (mesh[1]->head(f[1].index) - mesh[1]->tail(f[1].index));
    Vec3 n = ua.cross(ub);
    const double norm = n.norm();
    if (!(norm > 1e-6 * ua.norm() * ub.norm())) return Vec3::Zero();  // (near) parallel
    n /= norm;
    return n.dot(diff) < 0.0 ? Vec3(-n) : n;
  }

  // A normal for features that meet (zero distance), oriented from B to A.
  Vec3 touching_normal() const {
    Vec3 n = Vec3::Zero();
    if (f[0].kind == FeatureKind::kFace) {
      n = -mesh[0]->face_normal(f[0].index);
    } else if (f[1].kind == FeatureKind::kFace) {
      n = R * mesh[1]->face_normal(f[1].index);
    } else if (f[0].kind == FeatureKind::kEdge && f[1].kind == FeatureKind::kEdge) {
      const Vec3 ua = mesh[0]->head(f[0].index) - mesh[0]->tail(f[0].index);
      const Vec3 ub = R * (mesh[1]->head(f[1].index) - mesh[1]->tail(f[1].index));
      n = ua.cross(ub);
    }
    if (n.squaredNorm() == 0.0) n = -t;  // from B's centre of mass toward A's
    if (n.dot(-t) < 0.0) n = -n;
    const double norm = n.norm();
    return norm > 0.0 ? Vec3(n / norm) : Vec3(Vec3::UnitX());
  }
};

bool feature_in_range(const FeatureMesh& m, Feature f) {
  switch (f.kind) {
    case FeatureKind::kVertex: return f.index >= 0 && f.index < m.num_vertices();
    case FeatureKind::kEdge: return f.index >= 0 && f.index < m.num_half_edges();
    case FeatureKind::kFace: return f.index >= 0 && f.index < m.num_faces();
    case FeatureKind::kNone: return false;
  }
  return false;
}

}  // namespace

VClipResult vclip(const FeatureMesh& a, const FeatureMesh& b, const Mat3& R_AB, const Vec3& t_AB,
                  FeaturePair& cache, int max_steps) {
  Solver s;
  s.mesh[0] = &a;
  s.mesh[1] = &b;
  s.R = R_AB;
  s.t = t_AB;
  s.Rt = R_AB.transpose();
  s.tt = -(s.Rt * t_AB);
  s.f[0] = feature_in_range(a, cache.a) ? cache.a : Feature::vertex(0);
  s.f[1] = feature_in_range(b, cache.b) ? cache.b : Feature::vertex(0);
  if (s.f[0].kind == FeatureKind::kFace && s.f[1].kind == FeatureKind::kFace) {
    s.f[0] = Feature::vertex(a.tail_vertex(a.face_half_edge(s.f[0].index)));
  }

  VClipResult result;
  Step step = Step::kContinue;
  int steps = 0;
  constexpr auto V = FeatureKind::kVertex;
  constexpr auto E = FeatureKind::kEdge;
  constexpr auto F = FeatureKind::kFace;
  while (true) {
    const FeatureKind ka = s.f[0].kind;
    const FeatureKind kb = s.f[1].kind;
    if (ka == V && kb == V) {
      step = s.vertex_vertex();
    } else if (ka == V && kb == E) {
      step = s.vertex_edge(0, 1);
    } else if (ka == E && kb == V) {
      step = s.vertex_edge(1, 0);
    } else if (ka == V && kb == F) {
      step = s.vertex_face(0, 1);
    } else if (ka == F && kb == V) {
      step = s.vertex_face(1, 0);
    } else if (ka == E && kb == E) {
      step = s.edge_edge();
    } else if (ka == E && kb == F) {
      step = s.edge_face(0, 1);
    } else {
      step = s.edge_face(1, 0);
    }
    if (step != Step::kContinue) break;
    if (++steps >= max_steps) break;
  }
  result.steps = steps;
  result.features = {s.f[0], s.f[1]};
  cache = result.features;
  s.closest_points(result.p_a_A, result.p_b_A);
  if (step == Step::kContinue) {
    result.status = ContactStatus::kFailed;
    result.distance = 0.0;
    return result;
  }
  const Vec3 diff = result.p_a_A - result.p_b_A;
  result.distance = diff.norm();
  if (step == Step::kDone && result.distance > 0.0) {
    result.status = ContactStatus::kSeparated;
    const Vec3 n = s.feature_normal(diff);
    result.n_A = n.squaredNorm() > 0.0 ? n : Vec3(diff / result.distance);
    return result;
  }
  result.distance = 0.0;
  if (step == Step::kPenetrating) {
    result.status = ContactStatus::kPenetrating;
    result.n_A = s.n_penetration_A;
    return result;
  }
  // The features meet: touching if a plane separates the interiors, else overlap.
  const Vec3 axis = s.local_separating_axis(result.p_a_A);
  if (axis.squaredNorm() > 0.0) {
    result.status = ContactStatus::kTouching;
    result.n_A = axis;
  } else {
    result.status = ContactStatus::kPenetrating;
    result.n_A = s.touching_normal();
  }
  return result;
}

}  // namespace palpable
