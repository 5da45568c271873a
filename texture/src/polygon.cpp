#include <cmam/texture/polygon.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

double signed_area(const Polygon& p) {
    double a = 0;
    for (std::size_t i = 0, n = p.size(); i < n; ++i) {
        a += cross(p[i], p[(i + 1) % n]);
    }
    return a / 2;
}

namespace {
// Positive when p lies on the left of the directed line a -> b.
double side(Vec2d a, Vec2d b, Vec2d p) {
    return cross(b - a, p - a);
}
}  // namespace

Polygon clip_left(const Polygon& p, Vec2d a, Vec2d b) {
    Polygon out;
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec2d &cur = p[i], &nxt = p[(i + 1) % n];
        double sc = side(a, b, cur), sn = side(a, b, nxt);
        if (sc >= 0) out.push_back(cur);
        if ((sc >= 0) != (sn >= 0)) {
            double t = sc / (sc - sn);
            out.push_back(cur + t * (nxt - cur));
        }
    }
    return out;
}

std::vector<Polygon> difference(const Polygon& t, const Polygon& h) {
    std::vector<Polygon> pieces;
    Polygon rest = t;
    if (signed_area(rest) < 0) std::reverse(rest.begin(), rest.end());
    if (h.size() < 3) return {rest};  // no hull yet: all of t is new
    constexpr double kTiny = 1e-12;
    for (std::size_t k = 0, n = h.size(); k < n && rest.size() >= 3; ++k) {
        const Vec2d a = h[k], b = h[(k + 1) % n];
        // The part outside edge k is new; the remainder continues inside it.
        Polygon outside = clip_left(rest, b, a);
        if (outside.size() >= 3 && std::abs(signed_area(outside)) > kTiny)
            pieces.push_back(std::move(outside));
        rest = clip_left(rest, a, b);
        if (rest.size() < 3 || std::abs(signed_area(rest)) <= kTiny) break;
    }
    return pieces;
}

Polygon convex_hull(std::vector<Vec2d> pts) {
    std::sort(pts.begin(), pts.end(),
              [](Vec2d a, Vec2d b) { return a.u < b.u || (a.u == b.u && a.v < b.v); });
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
    if (pts.size() < 3) return pts;
    Polygon h(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {  // lower hull
        while (k >= 2 && side(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
        h[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, lo = k + 1; i-- > 0;) {  // upper hull
        while (k >= lo && side(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
        h[k++] = pts[i];
    }
    h.resize(k - 1);
    return h;
}

Texel polygon_integral(const SummedAreaTable& sat, const Polygon& poly) {
    Texel out{};
    const int nc = sat.channels();
    constexpr double kMax = detail::kMaxTexelCoord;  // as for every filter
    for (const Vec2d& p : poly)
        if (!(std::abs(p.u) < kMax && std::abs(p.v) < kMax)) {  // NaN included
            const double area = std::abs(signed_area(poly));
            if (std::isfinite(area))
                for (int c = 0; c < nc; ++c) out[c] = static_cast<float>(sat.mean()[c] * area);
            return out;
        }
    double acc[4] = {0, 0, 0, 0};
    const double sign = signed_area(poly) < 0 ? -1 : 1;
    std::vector<double> ts;
    for (std::size_t e = 0, n = poly.size(); e < n; ++e) {
        const Vec2d a = poly[e], b = poly[(e + 1) % n];
        const double dx = b.u - a.u, dy = b.v - a.v;
        if (dy == 0) continue;  // contributes nothing to the integral of F dy
        // Split the edge where it crosses texel rows and columns.
        ts.assign({0.0, 1.0});
        for (double y = std::floor(std::min(a.v, b.v)) + 1; y < std::max(a.v, b.v); y += 1)
            ts.push_back((y - a.v) / dy);
        if (dx != 0)
            for (double x = std::floor(std::min(a.u, b.u)) + 1; x < std::max(a.u, b.u); x += 1)
                ts.push_back((x - a.u) / dx);
        std::sort(ts.begin(), ts.end());
        for (std::size_t k = 0; k + 1 < ts.size(); ++k) {
            const double t0 = ts[k], t1 = ts[k + 1];
            if (t1 <= t0) continue;
            const double ym = a.v + 0.5 * (t0 + t1) * dy;
            const auto row = static_cast<int64_t>(std::floor(ym));
            const double x0 = a.u + t0 * dx, x1 = a.u + t1 * dx;
            // F(x, y) = integral of row `row` from 0 to x: linear in x within the cell.
            for (int c = 0; c < nc; ++c)
                acc[c] += 0.5 * (sat.row_integral(x0, row, c) + sat.row_integral(x1, row, c)) *
                          (t1 - t0) * dy;
        }
    }
    for (int c = 0; c < nc; ++c) out[c] = static_cast<float>(sign * acc[c]);
    return out;
}

Texel polygon_integral_cells(const Image& img, const Polygon& poly0) {
    Polygon poly = poly0;
    if (signed_area(poly) < 0) std::reverse(poly.begin(), poly.end());
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (Vec2d p : poly) {
        x0 = std::min(x0, p.u);
        x1 = std::max(x1, p.u);
        y0 = std::min(y0, p.v);
        y1 = std::max(y1, p.v);
    }
    double acc[4] = {0, 0, 0, 0};
    for (auto j = static_cast<int64_t>(std::floor(y0)); j < y1; ++j)
        for (auto i = static_cast<int64_t>(std::floor(x0)); i < x1; ++i) {
            Polygon c = poly;
            const double fi = double(i), fj = double(j);
            c = clip_left(c, {fi, fj}, {fi + 1, fj});
            c = clip_left(c, {fi + 1, fj}, {fi + 1, fj + 1});
            c = clip_left(c, {fi + 1, fj + 1}, {fi, fj + 1});
            c = clip_left(c, {fi, fj + 1}, {fi, fj});
            if (c.size() < 3) continue;
            double a = signed_area(c);
            Texel t = img.fetch(i, j);
            for (int k = 0; k < img.channels(); ++k) acc[k] += a * t[k];
        }
    Texel out{};
    for (int k = 0; k < img.channels(); ++k) out[k] = static_cast<float>(acc[k]);
    return out;
}

}  // namespace cmam::texture
