#include <cmam/texture/polygon.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

double signed_area(const Polygon& p) {
    double a = 0;
    for (std::size_t i = 0, n = p.size(); i < n; ++i) {
        const P2 &u = p[i], &v = p[(i + 1) % n];
        a += u.x * v.y - v.x * u.y;
    }
    return a / 2;
}

namespace {
double side(P2 a, P2 b, P2 p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}
}  // namespace

Polygon clip_left(const Polygon& p, P2 a, P2 b) {
    Polygon out;
    const std::size_t n = p.size();
    for (std::size_t i = 0; i < n; ++i) {
        const P2 &cur = p[i], &nxt = p[(i + 1) % n];
        double sc = side(a, b, cur), sn = side(a, b, nxt);
        if (sc >= 0) out.push_back(cur);
        if ((sc >= 0) != (sn >= 0)) {
            double t = sc / (sc - sn);
            out.push_back({cur.x + t * (nxt.x - cur.x), cur.y + t * (nxt.y - cur.y)});
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
        P2 a = h[k], b = h[(k + 1) % n];
        // The part outside edge k is new; the remainder continues inside it.
        Polygon outside = clip_left(rest, b, a);
        if (outside.size() >= 3 && std::abs(signed_area(outside)) > kTiny)
            pieces.push_back(std::move(outside));
        rest = clip_left(rest, a, b);
        if (rest.size() < 3 || std::abs(signed_area(rest)) <= kTiny) break;
    }
    return pieces;
}

Polygon convex_hull(std::vector<P2> pts) {
    std::sort(pts.begin(), pts.end(),
              [](P2 a, P2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    pts.erase(
        std::unique(pts.begin(), pts.end(), [](P2 a, P2 b) { return a.x == b.x && a.y == b.y; }),
        pts.end());
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
    for (const P2& p : poly)
        if (!(std::abs(p.x) < kMax && std::abs(p.y) < kMax)) {  // NaN included
            const double area = std::abs(signed_area(poly));
            if (std::isfinite(area))
                for (int c = 0; c < nc; ++c) out[c] = static_cast<float>(sat.mean()[c] * area);
            return out;
        }
    double acc[4] = {0, 0, 0, 0};
    const double sign = signed_area(poly) < 0 ? -1 : 1;
    std::vector<double> ts;
    for (std::size_t e = 0, n = poly.size(); e < n; ++e) {
        const P2 a = poly[e], b = poly[(e + 1) % n];
        const double dx = b.x - a.x, dy = b.y - a.y;
        if (dy == 0) continue;  // contributes nothing to the integral of F dy
        // Split the edge where it crosses texel rows and columns.
        ts.assign({0.0, 1.0});
        for (double y = std::floor(std::min(a.y, b.y)) + 1; y < std::max(a.y, b.y); y += 1)
            ts.push_back((y - a.y) / dy);
        if (dx != 0)
            for (double x = std::floor(std::min(a.x, b.x)) + 1; x < std::max(a.x, b.x); x += 1)
                ts.push_back((x - a.x) / dx);
        std::sort(ts.begin(), ts.end());
        for (std::size_t k = 0; k + 1 < ts.size(); ++k) {
            const double t0 = ts[k], t1 = ts[k + 1];
            if (t1 <= t0) continue;
            const double ym = a.y + 0.5 * (t0 + t1) * dy;
            const auto row = static_cast<int64_t>(std::floor(ym));
            const double x0 = a.x + t0 * dx, x1 = a.x + t1 * dx;
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
    for (P2 p : poly) {
        x0 = std::min(x0, p.x);
        x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y);
        y1 = std::max(y1, p.y);
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
