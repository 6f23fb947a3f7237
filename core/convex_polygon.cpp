#include "core/convex_polygon.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

std::vector<Vec2> tidy(const std::vector<Vec2>& in, double tol) {
  std::vector<Vec2> out;
  for (const Vec2& p : in) {
    if (out.empty() || (p - out.back()).norm() > tol) out.push_back(p);
  }
  while (out.size() > 1 && (out.front() - out.back()).norm() <= tol) out.pop_back();
  if (out.size() >= 3) {
    double area = 0.0;
    for (std::size_t i = 0; i < out.size(); ++i) area += cross2(out[i], out[(i + 1) % out.size()]);
    if (area < 0.0) std::reverse(out.begin(), out.end());
    if (std::abs(area) <= tol * tol) {
      // Collinear points: keep the two extremes.
      std::size_t i0 = 0, i1 = 0;
      const Vec2 dir = out[1] - out[0];
      for (std::size_t i = 0; i < out.size(); ++i) {
        if (out[i].dot(dir) < out[i0].dot(dir)) i0 = i;
        if (out[i].dot(dir) > out[i1].dot(dir)) i1 = i;
      }
      out = {out[i0], out[i1]};
    }
  }
  return out;
}

std::vector<Vec2> intersect(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.size() == 1) return a;
  if (b.size() == 1) return b;
  if (a.size() == 2 && b.size() == 2) {
    const Vec2 dir = (a[1] - a[0]).normalized();
    const double a0 = a[0].dot(dir), a1 = a[1].dot(dir);
    const double lo = std::max(std::min(a0, a1), std::min(b[0].dot(dir), b[1].dot(dir)));
    const double hi = std::min(std::max(a0, a1), std::max(b[0].dot(dir), b[1].dot(dir)));
    if (lo > hi) return {};
    auto at = [&](double s) { return Vec2(a[0] + ((s - a0) / (a1 - a0)) * (a[1] - a[0])); };
    return {at(lo), at(hi)};
  }
  // Clip the smaller-dimensional set (or a) against each edge of the polygon.
  const std::vector<Vec2>& poly = a.size() == 2 ? b : (b.size() == 2 ? a : b);
  std::vector<Vec2> subject = a.size() == 2 ? a : (b.size() == 2 ? b : a);
  const bool segment = subject.size() == 2;
  for (std::size_t i = 0; i < poly.size() && !subject.empty(); ++i) {
    const Vec2& e0 = poly[i];
    const Vec2 e = poly[(i + 1) % poly.size()] - e0;
    std::vector<Vec2> out;
    const std::size_t count = segment ? 1 : subject.size();
    for (std::size_t k = 0; k < count; ++k) {
      const Vec2& p = subject[k];
      const Vec2& q = subject[(k + 1) % subject.size()];
      const double sp = cross2(e, p - e0);
      const double sq = cross2(e, q - e0);
      if (sp >= 0.0) out.push_back(p);
      if ((sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0))
        out.push_back(p + (sp / (sp - sq)) * (q - p));
      if (segment && sq >= 0.0) out.push_back(q);
    }
    subject = out;
  }
  return subject;
}

Vec2 centroid(const std::vector<Vec2>& set) {
  if (set.empty()) return Vec2::Zero();
  if (set.size() < 3) return 0.5 * (set.front() + set.back());
  // Area centroid over the fan from the first vertex.
  double area = 0.0;
  Vec2 sum = Vec2::Zero();
  for (std::size_t i = 1; i + 1 < set.size(); ++i) {
    const double a = cross2(set[i] - set[0], set[i + 1] - set[0]);
    area += a;
    sum += a * (set[0] + set[i] + set[i + 1]) / 3.0;
  }
  return area != 0.0 ? Vec2(sum / area) : Vec2(set[0]);
}

}  // namespace palpable
