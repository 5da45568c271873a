#include <cmam/texture/area.h>
#include <cmam/texture/filter.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

RowPrefixTable::RowPrefixTable(const Image& image)
    : m_w(image.width()),
      m_h(image.height()),
      m_c(image.channels()),
      m_wrap_s(image.wrap_s()),
      m_wrap_t(image.wrap_t()),
      m_mean(image.mean()) {
    const std::size_t stride = static_cast<std::size_t>(m_w + 1) * m_c;
    m_d.assign(stride * static_cast<std::size_t>(m_h), 0.0f);
    for (int j = 0; j < m_h; ++j) {
        float* row = &m_d[stride * static_cast<std::size_t>(j)];
        double acc[4] = {0, 0, 0, 0};  // accumulated in double, stored as float
        for (int i = 0; i < m_w; ++i) {
            const float* t = image.texel(i, j);
            for (int c = 0; c < m_c; ++c) {
                acc[c] += double(t[c]) - m_mean[c];
                row[static_cast<std::size_t>(i + 1) * m_c + c] = static_cast<float>(acc[c]);
            }
        }
    }
}

namespace {

int64_t floor_div(int64_t a, int64_t b) {  // b > 0
    int64_t q = a / b;
    return q - ((a % b != 0) && (a < 0) ? 1 : 0);
}

}  // namespace

// R(k): the row integral from 0 to the integer k (unwrapped), with the wrap modes' extension.
// Inside [0,W] it is the table; Repeat adds whole periods; Mirror's period is 2W with the second
// half read backwards; Clamp continues with the edge texel; Black continues with zero texels,
// i.e. with -mean in the table's offset units.
template <int NC>
void RowPrefixTable::knot(const float* row, int64_t k, double* out) const {
    const int64_t W = m_w;
    if (k >= 0 && k <= W) {
        for (int c = 0; c < NC; ++c) out[c] = row[k * NC + c];
        return;
    }
    switch (m_wrap_s) {
        case WrapMode::Repeat: {
            const int64_t q = floor_div(k, W), r = k - q * W;
            for (int c = 0; c < NC; ++c) out[c] = double(q) * row[W * NC + c] + row[r * NC + c];
            return;
        }
        case WrapMode::Mirror: {
            const int64_t q = floor_div(k, 2 * W), r = k - q * 2 * W;
            for (int c = 0; c < NC; ++c) {
                const double full = row[W * NC + c];
                out[c] = 2 * double(q) * full +
                         (r <= W ? double(row[r * NC + c]) : 2 * full - row[(2 * W - r) * NC + c]);
            }
            return;
        }
        case WrapMode::Clamp:
            for (int c = 0; c < NC; ++c)
                out[c] = k < 0 ? double(k) * (row[NC + c] - row[c])
                               : row[W * NC + c] +
                                     double(k - W) * (row[W * NC + c] - row[(W - 1) * NC + c]);
            return;
        case WrapMode::Black:
            for (int c = 0; c < NC; ++c)
                out[c] = k < 0 ? -m_mean[c] * double(k)
                               : row[W * NC + c] - m_mean[c] * double(k - W);
            return;
    }
}

// Clamp and Black: the integral of R over [a,b] where it lies outside [0,W], in closed form (R
// is linear there), so a region far beyond the texture costs nothing per texel.
template <int NC>
void RowPrefixTable::outside_integral(const float* row, double a, double b, double* out) const {
    const double W = m_w;
    for (int c = 0; c < NC; ++c) out[c] = 0;
    if (a < 0) {  // R(x) = x s on x <= 0
        const double e = std::min(b, 0.0);
        for (int c = 0; c < NC; ++c) {
            const double s = m_wrap_s == WrapMode::Clamp ? double(row[NC + c]) - row[c] : -m_mean[c];
            out[c] += s * (e * e - a * a) / 2;
        }
    }
    if (b > W) {  // R(x) = D[W] + (x - W) s on x >= W
        const double e = std::max(a, W);
        for (int c = 0; c < NC; ++c) {
            const double dw = row[m_w * NC + c];
            const double s = m_wrap_s == WrapMode::Clamp
                                 ? dw - row[(m_w - 1) * NC + c]
                                 : -m_mean[c];
            out[c] += dw * (b - e) + s * ((b - W) * (b - W) - (e - W) * (e - W)) / 2;
        }
    }
}

// The mean of R_j over [x0,x1] (either order): R_j is linear within each texel, so a piece
// within one texel is its midpoint value, and a longer one sums its texels' exact trapezoids.
template <int NC>
void RowPrefixTable::row_mean(int64_t j, double x0, double x1, double* out) const {
    const int64_t jj = wrap_index(j, m_h, m_wrap_t);
    if (jj < 0) {  // Black rows: zero texels, R(x) = -mean x
        for (int c = 0; c < NC; ++c) out[c] = -m_mean[c] * 0.5 * (x0 + x1);
        return;
    }
    const float* row = &m_d[static_cast<std::size_t>(jj) * (m_w + 1) * NC];
    if (x0 > x1) std::swap(x0, x1);
    const int64_t k0 = floor_to_int(x0);
    double ra[NC], rb[NC];
    if (x1 <= double(k0 + 1)) {  // within one texel: R is linear, its mean is its midpoint value
        knot<NC>(row, k0, ra);
        knot<NC>(row, k0 + 1, rb);
        const double f = 0.5 * (x0 + x1) - double(k0);
        for (int c = 0; c < NC; ++c) out[c] = ra[c] + f * (rb[c] - ra[c]);
        return;
    }
    double acc[NC];
    for (int c = 0; c < NC; ++c) acc[c] = 0;
    double lo = x0, hi = x1;
    if (m_wrap_s == WrapMode::Clamp || m_wrap_s == WrapMode::Black) {
        if (lo < 0 || hi > m_w) outside_integral<NC>(row, lo, hi, acc);
        lo = std::max(lo, 0.0);
        hi = std::min(hi, double(m_w));
    }
    if (lo < hi) {
        int64_t k = floor_to_int(lo);
        knot<NC>(row, k, ra);
        if (m_wrap_s == WrapMode::Repeat) {
            // Consecutive knots: R(q W + r) = q D[W] + D[r], stepping r without dividing.
            const int64_t W = m_w;
            int64_t q = floor_div(k, W), r = k - q * W;
            for (; double(k) < hi; ++k) {
                if (++r > W) {
                    r = 1;
                    ++q;
                }
                for (int c = 0; c < NC; ++c) rb[c] = double(q) * row[W * NC + c] + row[r * NC + c];
                const double a = std::max(lo, double(k)), b = std::min(hi, double(k + 1));
                const double f = 0.5 * (a + b) - double(k);
                for (int c = 0; c < NC; ++c) {
                    acc[c] += (b - a) * (ra[c] + f * (rb[c] - ra[c]));
                    ra[c] = rb[c];
                }
            }
        } else {
            for (; double(k) < hi; ++k) {
                knot<NC>(row, k + 1, rb);
                const double a = std::max(lo, double(k)), b = std::min(hi, double(k + 1));
                const double f = 0.5 * (a + b) - double(k);
                for (int c = 0; c < NC; ++c) {
                    acc[c] += (b - a) * (ra[c] + f * (rb[c] - ra[c]));
                    ra[c] = rb[c];
                }
            }
        }
    }
    const double inv = 1 / (x1 - x0);
    for (int c = 0; c < NC; ++c) out[c] = acc[c] * inv;
}

// Green's theorem: the area integral of T is the boundary integral of R(x,y) dy, where R is the
// row integral from 0 to x (algorithms.md §5.2). Each edge is cut where it crosses a texel row;
// on a piece within row j, x is linear in y, so the piece's integral is its height times the
// mean of R_j over the piece's x-span. Clamp and Black rows beyond the texture are one piece.
template <int NC>
void RowPrefixTable::integrate(const Vec2d* v, int n, double* acc) const {
    const bool far_rows = m_wrap_t == WrapMode::Clamp || m_wrap_t == WrapMode::Black;
    for (int e = 0; e < n; ++e) {
        Vec2d p = v[e], q = v[(e + 1) % n];
        if (p.v == q.v) continue;  // no dy: no contribution
        double sign = 1;
        if (p.v > q.v) {
            std::swap(p, q);
            sign = -1;
        }
        const double dxdy = (q.u - p.u) / (q.v - p.v);
        double y = p.v;
        while (y < q.v) {
            const int64_t j = floor_to_int(y);
            double ynext;
            if (far_rows && j < 0)
                ynext = std::min(0.0, q.v);
            else if (far_rows && j >= m_h)
                ynext = q.v;
            else
                ynext = std::min(double(j + 1), q.v);
            const double xa = p.u + (y - p.v) * dxdy, xb = p.u + (ynext - p.v) * dxdy;
            double m[NC];
            row_mean<NC>(j, xa, xb, m);
            const double h = sign * (ynext - y);
            for (int c = 0; c < NC; ++c) acc[c] += h * m[c];
            y = ynext;
        }
    }
}

Texel RowPrefixTable::integral(const Vec2d* v0, int n) const {
    Texel out{};
    if (n < 3) return out;
    Vec2d v[8];
    n = std::min(n, 8);  // the filters' regions have three or four
    double area2 = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2d a = v0[i], b = v0[(i + 1) % n];
        area2 += a.u * b.v - b.u * a.v;
    }
    const double area = std::abs(area2) / 2;
    constexpr double kMax = detail::kMaxTexelCoord;
    for (int i = 0; i < n; ++i)
        if (!(std::abs(v0[i].u) < kMax && std::abs(v0[i].v) < kMax)) {  // NaN included
            if (std::isfinite(area))
                for (int c = 0; c < m_c; ++c) out[c] = static_cast<float>(m_mean[c] * area);
            return out;
        }
    // Periodic modes: move the polygon to the base period (small knots, no cancellation).
    double sx = 0, sy = 0;
    double xmin = v0[0].u, ymin = v0[0].v;
    for (int i = 1; i < n; ++i) {
        xmin = std::min(xmin, v0[i].u);
        ymin = std::min(ymin, v0[i].v);
    }
    if (m_wrap_s == WrapMode::Repeat) sx = std::floor(xmin / m_w) * m_w;
    if (m_wrap_s == WrapMode::Mirror) sx = std::floor(xmin / (2.0 * m_w)) * 2.0 * m_w;
    if (m_wrap_t == WrapMode::Repeat) sy = std::floor(ymin / m_h) * m_h;
    if (m_wrap_t == WrapMode::Mirror) sy = std::floor(ymin / (2.0 * m_h)) * 2.0 * m_h;
    for (int i = 0; i < n; ++i) v[i] = {v0[i].u - sx, v0[i].v - sy};
    double acc[4] = {0, 0, 0, 0};
    switch (m_c) {
        case 1:
            integrate<1>(v, n, acc);
            break;
        case 2:
            integrate<2>(v, n, acc);
            break;
        case 3:
            integrate<3>(v, n, acc);
            break;
        default:
            integrate<4>(v, n, acc);
            break;
    }
    const double sign = area2 < 0 ? -1 : 1;
    for (int c = 0; c < m_c; ++c) out[c] = static_cast<float>(sign * acc[c] + m_mean[c] * area);
    return out;
}

namespace {

double length(Vec2d a) {
    return std::hypot(a.u, a.v);
}

// The level rule (algorithms.md §5.2) for a region of area `area` (level-0 texels^2) whose
// longest side is `longest` and whose sides are `sides` (level-0 texel vectors, for the
// perimeter on each level).
int area_level(const FilteredTexture& tex, double width, const Vec2d* sides, int n) {
    const MipPyramid& pyr = tex.pyramid();
    const int top = pyr.levels() - 1;
    int l = 0;
    if (width > 2 * kAreaMinWidth) l = std::min(top, detail::floor_log2(width / kAreaMinWidth));
    const double W = tex.image().width(), H = tex.image().height();
    for (; l < top; ++l) {
        const double kx = pyr.level(l).width() / W, ky = pyr.level(l).height() / H;
        double perimeter = 0;
        for (int i = 0; i < n; ++i) perimeter += std::hypot(sides[i].u * kx, sides[i].v * ky);
        if (perimeter <= kAreaMaxPerimeter) break;
    }
    return l;
}

// Every corner within 2^30 texels and a finite, positive area.
bool within_range(const Vec2d* p, int n, double area) {
    constexpr double kMax = detail::kMaxTexelCoord;
    for (int i = 0; i < n; ++i)
        if (!(std::abs(p[i].u) < kMax && std::abs(p[i].v) < kMax)) return false;
    return area > 0 && std::isfinite(area);
}

// Integrates the polygon `p` (level-0 texels) on level l and returns its mean.
AreaResult integrate_on(const FilteredTexture& tex, int l, const Vec2d* p, int n, double area) {
    AreaResult r;
    r.level = l;
    r.area = area;
    const Image& img = tex.image();
    const int top = tex.pyramid().levels() - 1;
    const Image& lev = l > 0 ? tex.pyramid().level(l) : img;
    const double kx = double(lev.width()) / img.width(), ky = double(lev.height()) / img.height();
    if (l == top) {
        // The coarsest level: a periodic texture's integral over a region spanning many periods
        // is its mean (up to the boundary, 1/perimeter of it); a single texel is constant.
        const bool periodic = img.wrap_s() != WrapMode::Clamp && img.wrap_s() != WrapMode::Black &&
                              img.wrap_t() != WrapMode::Clamp && img.wrap_t() != WrapMode::Black;
        double perimeter = 0;
        for (int i = 0; i < n; ++i) {
            const Vec2d a = p[i], b = p[(i + 1) % n];
            perimeter += std::hypot((b.u - a.u) * kx, (b.v - a.v) * ky);
        }
        if ((lev.width() == 1 && lev.height() == 1 && periodic) ||
            (periodic && perimeter > kAreaMaxPerimeter)) {
            r.value = img.mean();
            r.knots = 1;
            return r;
        }
    }
    Vec2d q[8];
    for (int i = 0; i < n; ++i) q[i] = {p[i].u * kx, p[i].v * ky};
    const Texel t = tex.row_prefix(l).integral(q, n);
    const double inv = 1 / (area * kx * ky);
    for (int c = 0; c < img.channels(); ++c) r.value[c] = static_cast<float>(t[c] * inv);
    double perimeter = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2d a = q[i], b = q[(i + 1) % n];
        perimeter += std::abs(b.u - a.u) + std::abs(b.v - a.v);
    }
    r.knots = static_cast<int>(perimeter) + 2 * n;
    return r;
}

}  // namespace

AreaRegion area_region(const FilteredTexture& tex, double u, double v, Vec2d a, Vec2d b) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    Vec2d A{a.u * W, a.v * H}, B{b.u * W, b.v * H};  // level-0 texels
    double la = length(A), lb = length(B);
    if (la < lb) {
        std::swap(A, B);
        std::swap(la, lb);
    }
    // Degenerate axes: zero sides become the axis-aligned unit square below; collinear ones
    // keep the major side, with the perpendicular side of the area they span (about 0).
    if (la == 0) {
        A = {0, 0};
        B = {0, 0};
    } else {
        const double cross = A.u * B.v - A.v * B.u;
        if (!(std::abs(cross) > 1e-6 * la * lb)) {
            const double h = std::abs(cross) / la;
            B = {-A.v / la * h, A.u / la * h};
            lb = h;
        }
    }
    // The bilinear reconstruction term: each side to sqrt(|side|^2 + 1) texels.
    if (la > 0) {
        const double g = std::sqrt(1 + 1 / (la * la));
        A = {A.u * g, A.v * g};
    } else {
        A = {1, 0};
    }
    if (lb > 0) {
        const double g = std::sqrt(1 + 1 / (lb * lb));
        B = {B.u * g, B.v * g};
    } else {
        const double l = length(A);
        B = {-A.v / l, A.u / l};
    }
    la = length(A);
    lb = length(B);
    AreaRegion r;
    r.area = std::abs(A.u * B.v - A.v * B.u);
    const double cs = u * W, ct = v * H;
    r.corners[0] = {cs - 0.5 * (A.u + B.u), ct - 0.5 * (A.v + B.v)};
    r.corners[1] = {cs + 0.5 * (A.u - B.u), ct + 0.5 * (A.v - B.v)};
    r.corners[2] = {cs + 0.5 * (A.u + B.u), ct + 0.5 * (A.v + B.v)};
    r.corners[3] = {cs - 0.5 * (A.u - B.u), ct - 0.5 * (A.v - B.v)};
    r.major = std::max(la, lb);
    r.minor = std::min(la, lb);
    const Vec2d sides[4] = {A, B, A, B};
    r.level = area_level(tex, r.area / r.major, sides, 4);
    return r;
}

AreaResult area_parallelogram(const FilteredTexture& tex, double u, double v, Vec2d a, Vec2d b) {
    if (!(std::isfinite(u) && std::isfinite(v) && std::isfinite(a.u) && std::isfinite(a.v) &&
          std::isfinite(b.u) && std::isfinite(b.v))) {
        AreaResult r;  // as every filter: the texture's mean
        r.value = tex.image().mean();
        r.knots = 1;
        return r;
    }
    const AreaRegion g = area_region(tex, u, v, a, b);
    if (!within_range(g.corners, 4, g.area)) {
        AreaResult r;  // beyond 2^30 texels no sum keeps any precision: the mean, as every filter
        r.value = tex.image().mean();
        r.knots = 1;
        return r;
    }
    AreaResult r = integrate_on(tex, g.level, g.corners, 4, g.area);
    r.major = g.major;
    r.minor = g.minor;
    return r;
}

AreaResult area_polygon(const FilteredTexture& tex, const Vec2d* uv, int n) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    n = std::min(n, 8);
    Vec2d p[8], sides[8];
    for (int i = 0; i < n; ++i) p[i] = {uv[i].u * W, uv[i].v * H};
    double area2 = 0, longest = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2d a = p[i], b = p[(i + 1) % n];
        area2 += a.u * b.v - b.u * a.v;
        sides[i] = {b.u - a.u, b.v - a.v};
        longest = std::max(longest, length(sides[i]));
    }
    const double area = std::abs(area2) / 2;
    // Width: the height over the longest side (twice the area over it for a triangle).
    const double width = longest > 0 ? (n == 3 ? 2 : 1) * area / longest : 0;
    if (!within_range(p, n, area)) {
        AreaResult r;
        r.value = img.mean();
        r.knots = 1;
        return r;
    }
    return integrate_on(tex, area_level(tex, width, sides, n), p, n, area);
}

}  // namespace cmam::texture
