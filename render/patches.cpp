#include "render/patches.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "pbrt/error.h"

namespace cmam::render {

namespace {
// The triangles of an nx x ny grid of vertices (x fastest), pbrt-v3's: each cell (i, j) as
// (i,j), (i+1,j), (i+1,j+1) and (i,j), (i+1,j+1), (i,j+1).
void grid_triangles(int nx, int ny, std::vector<int>& indices) {
    indices.reserve(static_cast<std::size_t>(nx - 1) * static_cast<std::size_t>(ny - 1) * 6);
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const int a = j * nx + i, b = a + 1, c = a + nx + 1, d = a + nx;
            indices.insert(indices.end(), {a, b, c, a, c, d});
        }
}
}  // namespace

ShapeMesh heightfield_mesh(int nu, int nv, const std::vector<double>& z) {
    ShapeMesh m;
    const std::size_t n = static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
    m.positions.reserve(3 * n);
    m.uvs.reserve(2 * n);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            // In single precision, as pbrt-v3 divides: x and y are the vertex's (u,v) too.
            const float x = float(i) / float(nu - 1), y = float(j) / float(nv - 1);
            m.positions.insert(m.positions.end(),
                               {x, y, static_cast<float>(z[static_cast<std::size_t>(j) * nu + i])});
            m.uvs.insert(m.uvs.end(), {x, y});
        }
    grid_triangles(nu, nv, m.indices);
    return m;
}

namespace {

using H = std::array<double, 4>;  // a homogeneous point (x w, y w, z w, w)

H lerp(double a, const H& p, const H& q) {  // (1 - a) p + a q
    return {p[0] + a * (q[0] - p[0]), p[1] + a * (q[1] - p[1]), p[2] + a * (q[2] - p[2]),
            p[3] + a * (q[3] - p[3])};
}

// The knot span [t_k, t_(k+1)] that evaluates parameter t: the first non-empty span from
// k = order - 1 whose end is at or beyond t (at a knot, the span that ends there, as pbrt-v3
// takes it: the derivative there is the one from below).
int span_of(const std::vector<double>& knots, int order, int n, double t) {
    int k = order - 1;
    while (k < n - 1 && (t > knots[k + 1] || !(knots[k] < knots[k + 1]))) ++k;
    return k;
}

// A B-spline curve of `order` through the homogeneous points q(0) ... q(n - 1) at t, with its
// derivative: de Boor's algorithm on the order points that span k weighs; after all but the last
// round the two points left give the derivative, (order - 1) (d1 - d0) / (t_(k+1) - t_k).
template <class Q>
void de_boor(const std::vector<double>& knots, int order, int n, double t, Q q, H& value,
             H& derivative) {
    const int p = order - 1, k = span_of(knots, order, n, t);
    H d[32];                    // orders are at most 32 (nurbs_patch_error)
    derivative = {0, 0, 0, 0};  // (set below: orders are at least 2)
    for (int j = 0; j <= p; ++j) d[j] = q(k - p + j);
    for (int r = 1; r <= p; ++r) {
        if (r == p) {
            const double s = p / (knots[k + 1] - knots[k]);
            for (int c = 0; c < 4; ++c) derivative[c] = s * (d[p][c] - d[p - 1][c]);
        }
        for (int j = p; j >= r; --j) {
            const double lo = knots[k - p + j], hi = knots[k + 1 + j - r];
            d[j] = lerp((t - lo) / (hi - lo), d[j - 1], d[j]);
        }
    }
    value = d[p];
}

}  // namespace

std::optional<NurbsPatchError> nurbs_patch_error(const NurbsPatch& p) {
    using E = std::optional<NurbsPatchError>;
    auto axis = [&](const std::string& a, int n, int order, const std::vector<double>& knots,
                    double t0, double t1) -> E {
        const std::string count = "n" + a, ord = a + "order", kn = a + "knots";
        if (n < 1)
            return NurbsPatchError{count, count + " must be at least 1, got " + std::to_string(n)};
        if (order < 2 || order > 32)
            return NurbsPatchError{ord,
                                   ord + " must be from 2 to 32, got " + std::to_string(order)};
        if (order > n)
            return NurbsPatchError{ord, ord + " " + std::to_string(order) +
                                            " needs at least as many control points along " + a +
                                            ", got " + count + " " + std::to_string(n)};
        if (knots.size() != static_cast<std::size_t>(n + order))
            return NurbsPatchError{kn, kn + " has " + std::to_string(knots.size()) + " values; " +
                                           count + " " + std::to_string(n) + " and " + ord + " " +
                                           std::to_string(order) + " take " +
                                           std::to_string(n + order)};
        for (std::size_t i = 0; i < knots.size(); ++i) {
            if (!std::isfinite(knots[i])) return NurbsPatchError{kn, kn + " must be finite"};
            if (i > 0 && knots[i] < knots[i - 1])
                return NurbsPatchError{kn, kn + " must not decrease"};
        }
        const double lo = knots[static_cast<std::size_t>(order - 1)],
                     hi = knots[static_cast<std::size_t>(n)];
        if (!(lo < hi))
            return NurbsPatchError{kn, kn + " give the surface no extent along " + a + " (knots " +
                                           std::to_string(order - 1) + " and " + std::to_string(n) +
                                           " are equal)"};
        const std::string names[2] = {a + "0", a + "1"};
        const double ts[2] = {t0, t1};
        for (int k = 0; k < 2; ++k)
            if (!(ts[k] >= lo && ts[k] <= hi))
                return NurbsPatchError{names[k], names[k] + " must be within the knots' range [" +
                                                     pbrt::number_text(lo) + ", " +
                                                     pbrt::number_text(hi) + "], got " +
                                                     pbrt::number_text(ts[k])};
        return std::nullopt;
    };
    if (E e = axis("u", p.nu, p.uorder, p.uknots, p.u0, p.u1)) return e;
    if (E e = axis("v", p.nv, p.vorder, p.vknots, p.v0, p.v1)) return e;
    if (p.cp.size() != static_cast<std::size_t>(p.nu) * static_cast<std::size_t>(p.nv))
        return NurbsPatchError{"P", std::to_string(p.cp.size()) + " control points; nu x nv = " +
                                        std::to_string(p.nu * p.nv)};
    for (const H& c : p.cp)
        for (double x : c)
            if (!std::isfinite(x))
                return NurbsPatchError{"P", "control points must be finite numbers"};
    return std::nullopt;
}

NurbsPoint nurbs_evaluate(const NurbsPatch& p, double u, double v) {
    // Along v through each of the u span's columns, then along u through those (and through
    // their v derivatives, which gives the surface's): S = Σ_i N_i(u) C_i(v), S_v = Σ_i N_i(u)
    // C_i'(v), all homogeneous; then the quotient rule.
    const int ku = span_of(p.uknots, p.uorder, p.nu, u), first = ku - (p.uorder - 1);
    H col[32], col_dv[32];
    for (int i = 0; i < p.uorder; ++i) {
        const int ci = first + i;
        de_boor(
            p.vknots, p.vorder, p.nv, v,
            [&](int j) { return p.cp[static_cast<std::size_t>(j) * p.nu + ci]; }, col[i],
            col_dv[i]);
    }
    // The u curves run through the span's columns only: indices shifted by `first`.
    H s, s_u, s_v, unused;
    de_boor(
        p.uknots, p.uorder, p.nu, u, [&](int i) { return col[i - first]; }, s, s_u);
    de_boor(
        p.uknots, p.uorder, p.nu, u, [&](int i) { return col_dv[i - first]; }, s_v, unused);
    NurbsPoint out;
    for (int c = 0; c < 3; ++c) {
        out.p[c] = s[c] / s[3];
        out.dpdu[c] = (s_u[c] - out.p[c] * s_u[3]) / s[3];
        out.dpdv[c] = (s_v[c] - out.p[c] * s_v[3]) / s[3];
    }
    return out;
}

namespace {
std::array<double, 3> unit_cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    const std::array<double, 3> n = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                     a[0] * b[1] - a[1] * b[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0 && std::isfinite(len))) return {0, 0, 0};
    return {n[0] / len, n[1] / len, n[2] / len};
}
}  // namespace

ShapeMesh nurbs_mesh(const NurbsPatch& p, int dice) {
    ShapeMesh m;
    const std::size_t n = static_cast<std::size_t>(dice) * static_cast<std::size_t>(dice);
    m.positions.reserve(3 * n);
    m.normals.reserve(3 * n);
    m.uvs.reserve(2 * n);
    auto at = [&](int i, double t0, double t1) { return t0 + (t1 - t0) * double(i) / (dice - 1); };
    for (int j = 0; j < dice; ++j)
        for (int i = 0; i < dice; ++i) {
            const double u = at(i, p.u0, p.u1), v = at(j, p.v0, p.v1);
            const NurbsPoint e = nurbs_evaluate(p, u, v);
            std::array<double, 3> nrm = unit_cross(e.dpdu, e.dpdv);
            if (nrm == std::array<double, 3>{0, 0, 0}) {
                // A pole (a row of coincident control points) or a crease: dP/du x dP/dv
                // vanishes, and pbrt-v3's normal there is not a number (its facets around the
                // vertex fall back to their own normals). The normal a thousandth of the range
                // inside, towards the patch's middle; none if that too vanishes (the facets'
                // normals then, as pbrt-v3's).
                const double du = 1e-3 * (p.u1 - p.u0) * (2 * i < dice - 1 ? 1 : -1),
                             dv = 1e-3 * (p.v1 - p.v0) * (2 * j < dice - 1 ? 1 : -1);
                const NurbsPoint in = nurbs_evaluate(p, u + du, v + dv);
                nrm = unit_cross(in.dpdu, in.dpdv);
            }
            for (int c = 0; c < 3; ++c) {
                m.positions.push_back(static_cast<float>(e.p[c]));
                m.normals.push_back(static_cast<float>(nrm[c]));
            }
            m.uvs.insert(m.uvs.end(), {static_cast<float>(u), static_cast<float>(v)});
        }
    grid_triangles(dice, dice, m.indices);
    return m;
}

}  // namespace cmam::render
