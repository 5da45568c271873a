#include "render/tessellate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace cmam::render {

namespace {

// pbrt-v3's hyperboloid: the implicit surface ah (x^2 + y^2) - ch z^2 = 1 whose coefficients its
// constructor fits, in single precision, through p2 and a point beyond p1 on the line (p1 + 2
// (p2 - p1), pushed further while the fit is not finite), clipped to z between p1's and p2's and
// to phi <= phimax, phi measured from the line's point at that height. It is the segment swept
// about z only when the segment's closest approach to the axis is at z = 0; otherwise it is not
// (from (1, 0, 0) to (0, 1, 1) it is a hyperboloid of two sheets, nothing below z = 1/2): the
// shape pbrt-v3 renders, which cmam renders. algorithms.md §15.
struct Hyperboloid {
    double a[3], b[3];  // p1 and p2 (swapped when p2 is at z = 0, as pbrt-v3 does)
    double ah = 0, ch = 0;
    explicit Hyperboloid(const QuadricParams& p) {
        std::copy(p.p1, p.p1 + 3, a);
        std::copy(p.p2, p.p2 + 3, b);
        if (b[2] == 0) std::swap(a, b);
        float pp[3] = {float(a[0]), float(a[1]), float(a[2])};
        const float q[3] = {float(b[0]), float(b[1]), float(b[2])};
        float fa = 0, fc = 0;
        for (int guard = 0; guard < 64; ++guard) {
            for (int k = 0; k < 3; ++k) pp[k] += 2 * (q[k] - float(a[k]));
            const float xy1 = pp[0] * pp[0] + pp[1] * pp[1], xy2 = q[0] * q[0] + q[1] * q[1];
            fa = (1 / xy1 - (pp[2] * pp[2]) / (xy1 * q[2] * q[2])) /
                 (1 - (xy2 * pp[2] * pp[2]) / (xy1 * q[2] * q[2]));
            fc = (fa * xy2 - 1) / (q[2] * q[2]);
            if (std::isfinite(fa) && std::isfinite(fc)) break;
        }
        ah = fa;
        ch = fc;
    }
    // The radius at height z squared ((1 + ch z^2) / ah; negative where there is no surface).
    double r2(double z) const { return (1 + ch * z * z) / ah; }
    // The parts of [z0, z1] where the surface exists (r2 >= 0): at most two intervals.
    std::vector<std::pair<double, double>> spans(double z0, double z1) const {
        std::vector<std::pair<double, double>> out;
        auto add = [&](double lo, double hi) {
            lo = std::max(lo, z0);
            hi = std::min(hi, z1);
            if (lo < hi) out.emplace_back(lo, hi);
        };
        const double inf = std::numeric_limits<double>::infinity();
        if (!(ah != 0) || !std::isfinite(ah) || !std::isfinite(ch)) return out;
        if (ch >= 0) {
            if (ah > 0) add(-inf, inf);  // (ah < 0: nowhere)
            return out;
        }
        const double zc = 1 / std::sqrt(-ch);  // r2 changes sign at |z| = zc
        if (ah > 0) {
            add(-zc, zc);
        } else {
            add(-inf, -zc);
            add(zc, inf);
        }
        return out;
    }
};

}  // namespace

ShapeMesh tessellate(const std::string& type, const QuadricParams& p, int segments) {
    const double phi_max = std::clamp(p.phimax, 0.0, 360.0) * std::numbers::pi / 180;
    const int nu =
        std::max(2, static_cast<int>(std::ceil(segments * phi_max / (2 * std::numbers::pi))));
    // A cylinder's quads are flat rectangles: one row. The others need rows: the paraboloid
    // curves along v, a hyperboloid's quads are twisted (their diagonal leaves the surface),
    // and a cone's taper skews (u,v) across a long facet.
    const int nv = type == "cylinder" ? 1 : std::max(8, segments / 4);
    const double z0 = std::min(p.zmin, p.zmax), z1 = std::max(p.zmin, p.zmax);
    const bool hyperboloid = type == "hyperboloid";
    const Hyperboloid hyp(p);
    const double* a = hyp.a;
    const double* b = hyp.b;
    // The ranges of v meshed: [0, 1], or a hyperboloid's parts that exist, in v = (z - p1.z) /
    // (p2.z - p1.z) (each meshed from its smaller v, so that rows go the way v does).
    std::vector<std::pair<double, double>> v_spans;
    if (!hyperboloid) {
        v_spans.emplace_back(0, 1);
    } else {
        for (auto [lo, hi] : hyp.spans(std::min(a[2], b[2]), std::max(a[2], b[2]))) {
            const double va = (lo - a[2]) / (b[2] - a[2]), vb = (hi - a[2]) / (b[2] - a[2]);
            v_spans.emplace_back(std::min(va, vb), std::max(va, vb));
        }
    }

    ShapeMesh m;
    for (auto [v_lo, v_hi] : v_spans) {
        const int base = static_cast<int>(m.positions.size() / 3);
        for (int j = 0; j <= nv; ++j)
            for (int i = 0; i <= nu; ++i) {
                const double u = double(i) / nu, phi = u * phi_max;
                const double v = j == nv ? v_hi : v_lo + (v_hi - v_lo) * j / nv;
                const double c = std::cos(phi), s = std::sin(phi);
                double P[3], N[3];
                if (type == "cylinder") {
                    P[0] = p.radius * c, P[1] = p.radius * s, P[2] = z0 + v * (z1 - z0);
                    N[0] = c, N[1] = s, N[2] = 0;
                } else if (type == "cone") {
                    // Radius shrinks linearly to the apex at z = height (v = z / height).
                    const double r = p.radius * (1 - v);
                    P[0] = r * c, P[1] = r * s, P[2] = v * p.height;
                    N[0] = p.height * c, N[1] = p.height * s, N[2] = p.radius;
                } else if (type == "paraboloid") {
                    // x^2 + y^2 = radius^2 z / zmax, v along z from zmin to zmax.
                    const double z = z0 + v * (z1 - z0);
                    const double r = p.radius * std::sqrt(std::max(0.0, z / z1));
                    P[0] = r * c, P[1] = r * s, P[2] = z;
                    N[0] = r * c, N[1] = r * s, N[2] = -p.radius * p.radius / (2 * z1);
                } else {
                    // The surface's circle at the height of the segment's point at v, from
                    // that point's direction on by phi (pbrt-v3's phi).
                    const double q[3] = {(1 - v) * a[0] + v * b[0], (1 - v) * a[1] + v * b[1],
                                         (1 - v) * a[2] + v * b[2]};
                    const double r = std::sqrt(std::max(0.0, hyp.r2(q[2])));
                    const double start = std::atan2(q[1], q[0]);
                    P[0] = r * std::cos(start + phi), P[1] = r * std::sin(start + phi), P[2] = q[2];
                    // pbrt-v3's normal, dP/du x dP/dv: dP/du along (-y, x, 0), dP/dv the
                    // segment's direction turned by phi.
                    const double d[3] = {(b[0] - a[0]) * c - (b[1] - a[1]) * s,
                                         (b[0] - a[0]) * s + (b[1] - a[1]) * c, b[2] - a[2]};
                    const double t[3] = {-P[1], P[0], 0};
                    N[0] = t[1] * d[2] - t[2] * d[1];
                    N[1] = t[2] * d[0] - t[0] * d[2];
                    N[2] = t[0] * d[1] - t[1] * d[0];
                }
                for (int k = 0; k < 3; ++k) {
                    m.positions.push_back(float(P[k]));
                    m.normals.push_back(float(N[k]));
                }
                m.uvs.push_back(float(u));
                m.uvs.push_back(float(v));
            }
        // (u, v), (u+1, v), (u+1, v+1) and (u, v), (u+1, v+1), (u, v+1): facet normals along
        // dP/du x dP/dv, pbrt-v3's orientation of these shapes.
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const int v00 = base + j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1,
                          v11 = v01 + 1;
                m.indices.insert(m.indices.end(), {v00, v10, v11, v00, v11, v01});
            }
    }
    return m;
}

}  // namespace cmam::render
