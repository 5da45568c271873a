// render — what the shading code asks of a surface: its partial derivatives, the (u,v) and
// normal changes of an offset along it (through instance transforms), points sampled on it for
// area lights, and alpha cut-outs.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "render/scene.h"
#include "render/shading.h"
#include "render/transform3x4.h"

namespace cmam::render {

using namespace xform;

namespace {
// A quadric's world-space area element from `cw`, the object-space one (dP/du1 x dP/du2 of
// sample_area's parameters) transformed as a normal (M^-T): |det(M)| |cw|; 0 when not finite.
double area_element_of(const Primitive& pr, const D3& cw) {
    const auto& m = pr.world_from_object;
    const double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                       m[2] * (m[4] * m[9] - m[5] * m[8]);
    const double e = std::abs(det) * std::sqrt(cw[0] * cw[0] + cw[1] * cw[1] + cw[2] * cw[2]);
    return e > 0 && std::isfinite(e) ? e : 0.0;
}

// The cone of directions a round sphere of radius R subtends from a point outside it: the
// direction to its centre, the distance to it (and its square), and 1 - cos of the half-angle,
// written sin^2 / (1 + cos) to keep its precision for small, distant spheres. Nothing from
// inside or on the sphere.
struct SphereCone {
    Vec3 to_c;
    float d2, dc, one_minus_cos_max;
};
std::optional<SphereCone> sphere_cone(const Vec3& centre, float R, const Vec3& ref) {
    if (!(R > 0)) return std::nullopt;
    const Vec3 to_c = centre - ref;
    const float d2 = dot(to_c, to_c);
    if (!(d2 > R * R * 1.0001f)) return std::nullopt;
    const float sin2_max = R * R / d2, cos_max = std::sqrt(std::max(0.0f, 1 - sin2_max));
    return SphereCone{to_c, d2, std::sqrt(d2), sin2_max / (1 + cos_max)};
}
}  // namespace

SurfaceSample Primitive::sample_area(float u1, float u2) const {
    SurfaceSample out;
    if (kind == Kind::Curves) return out;  // (curves do not emit: Builder::emit_area_light)
    if (kind == Kind::Triangles) {
        // A triangle by area (area_cdf), then a point uniform in it; u1 is reused within the
        // chosen triangle's span.
        const double total = area_cdf.empty() ? 0 : area_cdf.back();
        if (!(total > 0)) return out;
        const double x = double(u1) * total;
        const auto it = std::upper_bound(area_cdf.begin(), area_cdf.end(), x);
        const std::size_t ntri = area_cdf.size() - 1;
        const std::size_t t = std::min(ntri - 1, static_cast<std::size_t>(std::max<std::ptrdiff_t>(
                                                     0, (it - area_cdf.begin()) - 1)));
        const double span = area_cdf[t + 1] - area_cdf[t];
        const float r = span > 0 ? float(std::clamp((x - area_cdf[t]) / span, 0.0, 1.0)) : 0.5f;
        const float su = std::sqrt(r), b0 = 1 - su, b1 = u2 * su, b2 = 1 - b0 - b1;
        const uint32_t i0 = indices[3 * t], i1 = indices[3 * t + 1], i2 = indices[3 * t + 2];
        const Vec3 &p0 = positions[i0], &p1 = positions[i1], &p2 = positions[i2];
        out.p = b0 * p0 + b1 * p1 + b2 * p2;
        Vec3 ng = normalize(cross(p0 - p2, p1 - p2));
        if (flip) ng = -ng;
        if (!normals.empty()) {  // oriented as intersect() orients hits
            const Vec3 ns = b0 * normals[i0] + b1 * normals[i1] + b2 * normals[i2];
            if (length(ns) > 0) ng = faceforward(ng, flip ? -ns : ns);
        }
        out.n = ng;
        out.pdf = float(1 / total);
        return out;
    }
    // Quadrics: (u1,u2) map to a point uniform by object-space area (Archimedes' z for the
    // sphere, r^2 for the disk, phi for both). The world-space area element is |dP/du1 x
    // dP/du2| after the transform, det(M) M^-T applied to the object-space one, so the density
    // is exact under any transform.
    const double phi = double(u2) * phi_max;
    D3 po, cross_obj;
    if (kind == Kind::Sphere) {
        const double z = zmin + double(u1) * (zmax - zmin);
        const double rho = std::sqrt(std::max(0.0, radius * radius - z * z));
        po = {rho * std::cos(phi), rho * std::sin(phi), z};
        const double k = (zmax - zmin) * phi_max;
        cross_obj = {k * po[0], k * po[1], k * po[2]};  // outwards, |.| = k * radius
    } else {
        const double r2 = inner_radius * inner_radius +
                          double(u1) * (radius * radius - inner_radius * inner_radius);
        const double rho = std::sqrt(r2);
        po = {rho * std::cos(phi), rho * std::sin(phi), height};
        cross_obj = {0, 0, 0.5 * (radius * radius - inner_radius * inner_radius) * phi_max};
    }
    const D3 cw = xform_normal(object_from_world, cross_obj);
    const double area_element = area_element_of(*this, cw);
    if (!(area_element > 0)) return out;
    out.p = to_vec(xform_point(world_from_object, po));
    Vec3 nw = normalize(to_vec(cw));
    out.n = flip ? -nw : nw;
    out.pdf = float(1 / area_element);
    return out;
}

bool Primitive::cut_out(uint32_t tri, float b1, float b2, bool shadow) const {
    const uint32_t i0 = indices[3 * tri], i1 = indices[3 * tri + 1], i2 = indices[3 * tri + 2];
    const float b0 = 1 - b1 - b2;
    TexContext ctx;  // a point lookup: no footprint
    if (!uvs.empty()) {
        ctx.u = b0 * uvs[i0][0] + b1 * uvs[i1][0] + b2 * uvs[i2][0];
        ctx.v = b0 * uvs[i0][1] + b1 * uvs[i1][1] + b2 * uvs[i2][1];
    } else {
        ctx.u = b1 + b2;
        ctx.v = b2;
    }
    ctx.p = b0 * positions[i0] + b1 * positions[i1] + b2 * positions[i2];
    ctx.object = id;
    ctx.u_periodic = u_periodic;
    ctx.v_periodic = v_periodic;
    if (eval_texture(*scene, alpha, ctx).r == 0) return true;
    return shadow && eval_texture(*scene, shadow_alpha, ctx).r == 0;
}

float Primitive::area_pdf(const Vec3& p) const {
    if (kind == Kind::Curves) return 0;
    if (kind == Kind::Triangles) {
        const double total = area_cdf.empty() ? 0 : area_cdf.back();
        return total > 0 ? float(1 / total) : 0.0f;
    }
    // sample_area's area element at the object-space point of p (on the surface).
    const D3 po = xform_point(object_from_world, {p.x, p.y, p.z});
    D3 cross_obj;
    if (kind == Kind::Sphere) {
        const double k = (zmax - zmin) * phi_max;
        cross_obj = {k * po[0], k * po[1], k * po[2]};
    } else {
        cross_obj = {0, 0, 0.5 * (radius * radius - inner_radius * inner_radius) * phi_max};
    }
    const double area_element = area_element_of(*this, xform_normal(object_from_world, cross_obj));
    return area_element > 0 ? float(1 / area_element) : 0.0f;
}

std::optional<float> Primitive::cone_pdf(const Vec3& ref) const {
    const std::optional<SphereCone> c = sphere_cone(sphere_center, sphere_radius, ref);
    if (!c) return std::nullopt;
    return 1 / (2 * kPi * c->one_minus_cos_max);  // uniform in the cone
}

std::optional<SurfaceSample> Primitive::sample_cone(const Vec3& ref, float u1, float u2) const {
    const std::optional<SphereCone> c = sphere_cone(sphere_center, sphere_radius, ref);
    if (!c) return std::nullopt;
    const float R = sphere_radius, d2 = c->d2, dc = c->dc, one_minus_cos_max = c->one_minus_cos_max;
    const Vec3& to_c = c->to_c;
    const float cos_t = 1 - u1 * one_minus_cos_max;
    const float sin2_t = std::max(0.0f, u1 * one_minus_cos_max * (1 + cos_t));
    const float phi = 2 * kPi * u2;
    const Frame f = Frame::from_z(to_c / dc);
    const Vec3 wi = f.to_world(
        Vec3(std::sqrt(sin2_t) * std::cos(phi), std::sqrt(sin2_t) * std::sin(phi), cos_t));
    // The nearer intersection along wi: t = d cos - sqrt(R^2 - d^2 sin^2).
    const float t = dc * cos_t - std::sqrt(std::max(0.0f, R * R - d2 * sin2_t));
    SurfaceSample out;
    out.p = ref + wi * t;
    const Vec3 n = normalize(out.p - sphere_center);
    out.n = flip ? -n : n;
    out.pdf = 1 / (2 * kPi * one_minus_cos_max);
    return out;
}

Partials SurfaceHit::local_partials() const {
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Curves) return curve_partials;
    if (pr.kind == Primitive::Kind::Triangles) {
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        std::array<float, 2> uv0{0, 0}, uv1{1, 0}, uv2{1, 1};
        if (!pr.uvs.empty()) {
            uv0 = pr.uvs[i0];
            uv1 = pr.uvs[i1];
            uv2 = pr.uvs[i2];
        }
        Vec3 dp02 = pr.positions[i0] - pr.positions[i2], dp12 = pr.positions[i1] - pr.positions[i2];
        float du02 = uv0[0] - uv2[0], dv02 = uv0[1] - uv2[1], du12 = uv1[0] - uv2[0],
              dv12 = uv1[1] - uv2[1];
        float det = du02 * dv12 - dv02 * du12;
        if (std::abs(det) < 1e-12f) {  // degenerate uv: any frame of the plane
            Frame f = Frame::from_z(normalize(cross(dp02, dp12)));
            return {f.s, f.t};
        }
        float inv = 1 / det;
        return {(dv12 * dp02 - dv02 * dp12) * inv, (du02 * dp12 - du12 * dp02) * inv};
    }
    const D3& p = p_object;
    D3 du, dv;
    if (pr.kind == Primitive::Kind::Sphere) {
        double r = pr.radius;
        double zr = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        double cos_phi = zr > 0 ? p[0] / zr : 1, sin_phi = zr > 0 ? p[1] / zr : 0;
        // sin(theta) for cos(theta) = z / r, without the angle (pbrt-v3 takes acos, then sin).
        const double cos_theta = std::clamp(p[2] / r, -1.0, 1.0);
        const double sin_theta = std::sqrt(1 - cos_theta * cos_theta);
        double dtheta = pr.theta_zmax - pr.theta_zmin;
        du = {-pr.phi_max * p[1], pr.phi_max * p[0], 0};
        dv = {dtheta * p[2] * cos_phi, dtheta * p[2] * sin_phi, -dtheta * r * sin_theta};
    } else {
        double r_hit = std::sqrt(p[0] * p[0] + p[1] * p[1]);
        du = {-pr.phi_max * p[1], pr.phi_max * p[0], 0};
        double k = r_hit > 0 ? (pr.inner_radius - pr.radius) / r_hit : 0;
        dv = {p[0] * k, p[1] * k, 0};
    }
    return {to_vec(xform_vector(pr.world_from_object, du)),
            to_vec(xform_vector(pr.world_from_object, dv))};
}

namespace {
// Barycentric differentials of triangle `tri`: (db1, db2) = (l1 . dp / l1 . e1, l2 . dp / l2 .
// e2) for a world offset dp in its plane.
struct BarycentricBasis {
    Vec3 l1, l2;
    float d1, d2;
    BarycentricBasis(const Primitive& pr, uint32_t tri) {
        const Vec3& p0 = pr.positions[pr.indices[3 * tri]];
        const Vec3 e1 = pr.positions[pr.indices[3 * tri + 1]] - p0,
                   e2 = pr.positions[pr.indices[3 * tri + 2]] - p0;
        const Vec3 n = cross(e1, e2);
        l1 = cross(e2, n);
        l2 = cross(e1, n);
        d1 = dot(l1, e1);
        d2 = dot(l2, e2);
    }
    std::pair<float, float> operator()(const Vec3& dp) const {
        return {dot(l1, dp) / d1, dot(l2, dp) / d2};
    }
};
}  // namespace

void Primitive::make_uv_gradients() {
    uv_gradients.clear();
    if (kind != Kind::Triangles) return;
    const std::size_t n = indices.size() / 3;
    uv_gradients.resize(n);
    using D = std::array<double, 3>;
    auto d3 = [](const Vec3& v) { return D{v.x, v.y, v.z}; };
    auto sub = [](const D& a, const D& b) { return D{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
    auto crs = [](const D& a, const D& b) {
        return D{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    auto dt = [](const D& a, const D& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    for (std::size_t t = 0; t < n; ++t) {
        const uint32_t i0 = indices[3 * t], i1 = indices[3 * t + 1], i2 = indices[3 * t + 2];
        // dB1 = L1 . dP / (L1 . E1) and dB2 = L2 . dP / (L2 . E2), with L1 = E2 x N, L2 = E1 x N
        // (N = E1 x E2); (u,v) interpolates linearly in B1, B2.
        const D p0 = d3(positions[i0]), e1 = sub(d3(positions[i1]), p0),
                e2 = sub(d3(positions[i2]), p0);
        const D nrm = crs(e1, e2), l1 = crs(e2, nrm), l2 = crs(e1, nrm);
        const double d1 = dt(l1, e1), d2 = dt(l2, e2);
        std::array<float, 2> uv0{0, 0}, uv1{1, 0}, uv2{1, 1};
        if (!uvs.empty()) {
            uv0 = uvs[i0];
            uv1 = uvs[i1];
            uv2 = uvs[i2];
        }
        for (int c = 0; c < 2; ++c) {
            // A degenerate triangle (d1 or d2 zero) gives non-finite gradients, and its hits no
            // footprint, as the per-hit division did.
            const double k1 = (double(uv1[c]) - uv0[c]) / d1, k2 = (double(uv2[c]) - uv0[c]) / d2;
            uv_gradients[t][c] = Vec3(static_cast<float>(k1 * l1[0] + k2 * l2[0]),
                                      static_cast<float>(k1 * l1[1] + k2 * l2[1]),
                                      static_cast<float>(k1 * l1[2] + k2 * l2[2]));
        }
    }
}

void Primitive::make_uv_charts() {
    uv_charts.clear();
    if (kind != Kind::Triangles) return;
    const std::size_t n = indices.size() / 3;
    // Vertices by position, bit for bit (-0 is 0): split vertices (for their normals or their
    // (u,v)) are one point of the surface.
    struct Point {
        std::array<uint32_t, 3> bits;
        bool operator==(const Point&) const = default;
    };
    struct PointHash {
        std::size_t operator()(const Point& p) const {
            uint64_t h = 0x9e3779b97f4a7c15ull;
            for (uint32_t b : p.bits) h = (h ^ b) * 0x100000001b3ull;
            return static_cast<std::size_t>(h ^ (h >> 29));
        }
    };
    auto bits = [](float f) { return std::bit_cast<uint32_t>(f + 0.0f); };
    std::unordered_map<Point, uint32_t, PointHash> point_ids;
    point_ids.reserve(positions.size());
    std::vector<uint32_t> point_of(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const Vec3& p = positions[i];
        point_of[i] = point_ids
                          .try_emplace(Point{{bits(p.x), bits(p.y), bits(p.z)}},
                                       static_cast<uint32_t>(point_ids.size()))
                          .first->second;
    }
    // A point whose vertices carry three (u,v) or more, all with one u or all with one v, is
    // singular (a pole, where u is any longitude at one v): its (u,v) says nothing about
    // continuity. (Three (u,v) that differ in both, a cube's corner between three faces'
    // charts, are an ordinary point.)
    std::vector<uint8_t> singular(point_ids.size(), 0);
    if (!uvs.empty()) {
        std::vector<std::array<float, 2>> uv1(point_ids.size()), uv2(point_ids.size());
        std::vector<uint8_t> count(point_ids.size(), 0);  // distinct (u,v) seen, at most 3
        std::vector<uint8_t> same(point_ids.size(), 3);   // bit 0: all one u, bit 1: one v
        for (std::size_t i = 0; i < positions.size(); ++i) {
            const uint32_t p = point_of[i];
            const std::array<float, 2>& uv = uvs[i];
            if (count[p] == 0) {
                uv1[p] = uv;
                count[p] = 1;
                continue;
            }
            same[p] &= (uv[0] == uv1[p][0] ? 1 : 0) | (uv[1] == uv1[p][1] ? 2 : 0);
            if (count[p] == 1 && uv != uv1[p]) {
                uv2[p] = uv;
                count[p] = 2;
            } else if (count[p] == 2 && uv != uv1[p] && uv != uv2[p]) {
                count[p] = 3;
            }
        }
        for (std::size_t p = 0; p < singular.size(); ++p)
            singular[p] = count[p] == 3 && same[p] != 0;
    }
    // A corner's (u,v): the vertex's, or without (u,v) the triangle's own (0,0), (1,0), (1,1).
    auto uv_at = [&](std::size_t t, int k) -> std::array<float, 2> {
        static constexpr std::array<float, 2> kDefault[3] = {{0, 0}, {1, 0}, {1, 1}};
        return uvs.empty() ? kDefault[k] : uvs[indices[3 * t + k]];
    };
    // Triangles joined through the edges they share with the same (u,v) at both ends, or at
    // one end with the other singular (union-find with path halving); any other edge they
    // share is a seam (a cube's edge between two faces' charts, both its ends singular, too).
    std::vector<uint32_t> parent(n);
    for (std::size_t t = 0; t < n; ++t) parent[t] = static_cast<uint32_t>(t);
    auto find = [&](uint32_t t) {
        while (parent[t] != t) t = parent[t] = parent[parent[t]];
        return t;
    };
    struct Seam {
        uint32_t t1, t2;
        uint32_t point[2];          // the edge's ends
        std::array<float, 2> d[2];  // (u,v) on t2's side minus t1's, at the edge's two ends
    };
    std::vector<Seam> seams;
    struct Side {
        uint32_t t;
        int k0, k1;  // the triangle's corners at the key's lower and higher point
    };
    std::unordered_map<uint64_t, Side> edges;
    edges.reserve(3 * n);
    for (std::size_t t = 0; t < n; ++t) {
        const uint32_t p0 = point_of[indices[3 * t]], p1 = point_of[indices[3 * t + 1]],
                       p2 = point_of[indices[3 * t + 2]];
        if (p0 == p1 || p1 == p2 || p2 == p0) continue;  // no area (a pole's row): never hit
        for (int k = 0; k < 3; ++k) {
            const int k2 = (k + 1) % 3;
            uint32_t a = point_of[indices[3 * t + k]], b = point_of[indices[3 * t + k2]];
            Side side{static_cast<uint32_t>(t), k, k2};
            if (a > b) {
                std::swap(a, b);
                std::swap(side.k0, side.k1);
            }
            const auto [it, added] = edges.try_emplace((uint64_t(a) << 32) | b, side);
            if (added) continue;
            const Side& o = it->second;
            const auto o0 = uv_at(o.t, o.k0), o1 = uv_at(o.t, o.k1), s0 = uv_at(t, side.k0),
                       s1 = uv_at(t, side.k1);
            if ((singular[a] || o0 == s0) && (singular[b] || o1 == s1) && (o0 == s0 || o1 == s1))
                parent[find(static_cast<uint32_t>(t))] = find(o.t);
            else
                seams.push_back({o.t,
                                 static_cast<uint32_t>(t),
                                 {a, b},
                                 {{s0[0] - o0[0], s0[1] - o0[1]}, {s1[0] - o1[0], s1[1] - o1[1]}}});
        }
    }
    // Charts numbered in the order of their first triangle (each root's number kept at the
    // root's index).
    std::vector<uint32_t> chart(n), number(n, UINT32_MAX);
    uint32_t charts = 0;
    for (std::size_t t = 0; t < n; ++t) {
        uint32_t& k = number[find(static_cast<uint32_t>(t))];
        if (k == UINT32_MAX) k = charts++;
        chart[t] = k;
    }
    // A chart that meets itself: where every such seam moves (u,v) by the same whole units at
    // its regular ends (a cylinder's or a sphere's unwrapping, u round the axis; a torus's, u
    // and v), the coordinates that move are periodic with period 1, and the CMAM takes
    // neighbours across them the short way round, as on a closed quadric. Any other seam
    // inside a chart leaves the mesh as it is.
    bool whole = !uvs.empty(), moves[2] = {false, false};  // without (u,v), no period
    for (const Seam& sm : seams) {
        if (chart[sm.t1] != chart[sm.t2]) continue;
        for (int e = 0; e < 2; ++e) {
            if (singular[sm.point[e]]) continue;
            const std::array<float, 2>& d = sm.d[e];
            for (int c = 0; c < 2; ++c) {
                const float r = std::round(d[c]);
                whole = whole && std::abs(d[c] - r) <= 1e-4f;
                moves[c] = moves[c] || r != 0;
            }
            whole = whole && (std::round(d[0]) != 0 || std::round(d[1]) != 0);
        }
        // One translation along the whole edge: the same at both ends (a cube's faces mapped
        // each onto the whole texture differ by whole units at the corners, by other amounts
        // between them).
        if (!singular[sm.point[0]] && !singular[sm.point[1]])
            for (int c = 0; c < 2; ++c) whole = whole && std::abs(sm.d[0][c] - sm.d[1][c]) <= 1e-4f;
    }
    if (whole) {
        u_periodic = u_periodic || moves[0];
        v_periodic = v_periodic || moves[1];
    }
    if (charts > 1) uv_charts = std::move(chart);
}

template <std::size_t N>
std::array<UvDelta, N> SurfaceHit::local_uv_offsets(const std::array<Vec3, N>& dp) const {
    std::array<UvDelta, N> out{};
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Triangles && !pr.uv_gradients.empty()) {
        const std::array<Vec3, 2>& g = pr.uv_gradients[triangle];
        for (std::size_t k = 0; k < N; ++k) out[k] = gradient_uv_offset(g, dp[k]);
        return out;
    }
    if (pr.kind == Primitive::Kind::Triangles) {
        // Barycentric differentials: dB_k = L_k . dP, then (u,v) interpolates linearly.
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        const BarycentricBasis basis(pr, triangle);
        std::array<float, 2> uv0{0, 0}, uv1{1, 0}, uv2{1, 1};
        if (!pr.uvs.empty()) {
            uv0 = pr.uvs[i0];
            uv1 = pr.uvs[i1];
            uv2 = pr.uvs[i2];
        }
        for (std::size_t k = 0; k < N; ++k) {
            const auto [db1, db2] = basis(dp[k]);
            out[k] = {db1 * (uv1[0] - uv0[0]) + db2 * (uv2[0] - uv0[0]),
                      db1 * (uv1[1] - uv0[1]) + db2 * (uv2[1] - uv0[1])};
        }
        return out;
    }
    // Least squares: [dpdu dpdv] (du dv)^T = dP.
    const auto [a, b] = local_partials();
    double aa = dot(a, a), ab = dot(a, b), bb = dot(b, b);
    double det = aa * bb - ab * ab;
    if (!(std::abs(det) > 0) || !std::isfinite(det)) return out;
    for (std::size_t k = 0; k < N; ++k) {
        double ad = dot(a, dp[k]), bd = dot(b, dp[k]);
        out[k] = {static_cast<float>((bb * ad - ab * bd) / det),
                  static_cast<float>((aa * bd - ab * ad) / det)};
    }
    return out;
}

template <std::size_t N>
std::array<Vec3, N> SurfaceHit::local_normal_offsets(const std::array<Vec3, N>& dp) const {
    std::array<Vec3, N> out{};
    const Primitive& pr = *prim;
    if (pr.kind == Primitive::Kind::Triangles) {
        if (pr.normals.empty()) return out;  // flat: the normal is constant
        uint32_t i0 = pr.indices[3 * triangle], i1 = pr.indices[3 * triangle + 1],
                 i2 = pr.indices[3 * triangle + 2];
        const Vec3 &n0 = pr.normals[i0], &n1 = pr.normals[i1], &n2 = pr.normals[i2];
        // The same normal at the three vertices (a flat face given normals, as exporters write
        // them): the normal is constant over the triangle, and its offsets zero.
        auto same = [](const Vec3& a, const Vec3& b) {
            return a.x == b.x && a.y == b.y && a.z == b.z;
        };
        if (same(n0, n1) && same(n0, n2)) return out;
        const BarycentricBasis basis(pr, triangle);
        float b0 = 1 - b1 - b2;
        Vec3 ni = b0 * n0 + b1 * n1 + b2 * n2;
        for (std::size_t k = 0; k < N; ++k) {
            const auto [db1, db2] = basis(dp[k]);
            Vec3 dn = (-db1 - db2) * n0 + db1 * n1 + db2 * n2;
            Vec3 d = unit_derivative(ni, dn);
            out[k] = pr.flip ? -d : d;
        }
        return out;
    }
    // A disk's normal is constant, and pbrt-v3 gives a curve's none (its dn/du, dn/dv are 0).
    if (pr.kind == Primitive::Kind::Disk || pr.kind == Primitive::Kind::Curves) return out;
    // Sphere: n_obj = p_obj, so dn_obj = dp_obj; normals map with (object_from_world)^T.
    Vec3 n = to_vec(xform_normal(pr.object_from_world, p_object));
    for (std::size_t k = 0; k < N; ++k) {
        D3 dpo = xform_vector(pr.object_from_world, {dp[k].x, dp[k].y, dp[k].z});
        Vec3 dn = to_vec(xform_normal(pr.object_from_world, dpo));
        Vec3 d = unit_derivative(n, dn);
        out[k] = pr.flip ? -d : d;
    }
    return out;
}

UvDelta SurfaceHit::local_uv_offset(const Vec3& dp) const {
    return local_uv_offsets<1>({dp})[0];
}

Vec3 SurfaceHit::local_normal_offset(const Vec3& dp) const {
    return local_normal_offsets<1>({dp})[0];
}

Partials SurfaceHit::partials() const {
    const Partials local = local_partials();
    if (!instance) return local;
    return {instance->to_world_vector(local.dpdu), instance->to_world_vector(local.dpdv)};
}

UvDelta SurfaceHit::uv_offset(const Vec3& dp) const {
    return local_uv_offset(instance ? instance->to_object_vector(dp) : dp);
}

std::array<UvDelta, 2> SurfaceHit::uv_offsets(const Vec3& dp1, const Vec3& dp2) const {
    if (!instance) return local_uv_offsets<2>({dp1, dp2});
    return local_uv_offsets<2>({instance->to_object_vector(dp1), instance->to_object_vector(dp2)});
}

std::array<Vec3, 2> SurfaceHit::normal_offsets(const Vec3& dp1, const Vec3& dp2) const {
    std::array<Vec3, 2> out;
    normal_offsets(dp1, dp2, out[0], out[1]);
    return out;
}

void SurfaceHit::general_uv_offsets(const Vec3& dp1, const Vec3& dp2, UvDelta& o1,
                                    UvDelta& o2) const {
    const std::array<UvDelta, 2> d = uv_offsets(dp1, dp2);
    o1.du = d[0].du;
    o1.dv = d[0].dv;
    o2.du = d[1].du;
    o2.dv = d[1].dv;
}

void SurfaceHit::normal_offsets(const Vec3& dp1, const Vec3& dp2, Vec3& o1, Vec3& o2) const {
    if (!instance) {
        const std::array<Vec3, 2> dn = local_normal_offsets<2>({dp1, dp2});
        o1 = dn[0];
        o2 = dn[1];
        return;
    }
    const std::array<Vec3, 2> dn =
        local_normal_offsets<2>({instance->to_object_vector(dp1), instance->to_object_vector(dp2)});
    const Vec3 n = instance->to_world_normal(ns_object);
    o1 = unit_derivative(n, instance->to_world_normal(dn[0]));
    o2 = unit_derivative(n, instance->to_world_normal(dn[1]));
}

Vec3 SurfaceHit::normal_offset(const Vec3& dp) const {
    if (!instance) return local_normal_offset(dp);
    // The world normal is normalize(M^-T n_object): its change follows from the object one's.
    const Vec3 dn = local_normal_offset(instance->to_object_vector(dp));
    return unit_derivative(instance->to_world_normal(ns_object), instance->to_world_normal(dn));
}

Vec3 Instance::to_world_point(const Vec3& p) const {
    return apply_point(world_from_object, p);
}
Vec3 Instance::to_world_vector(const Vec3& v) const {
    return apply_vector(world_from_object, v);
}
Vec3 Instance::to_world_normal(const Vec3& n) const {
    return apply_transpose(object_from_world, n);
}
Vec3 Instance::to_object_point(const Vec3& p) const {
    return apply_point(object_from_world, p);
}
Vec3 Instance::to_object_vector(const Vec3& v) const {
    return apply_vector(object_from_world, v);
}

}  // namespace cmam::render
