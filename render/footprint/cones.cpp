#include "render/footprint/cones.h"

#include <cmath>

namespace cmam::render {

RayCone camera_cone(const Camera& c, float scale) {
    // One pixel of the shorter axis on the image plane at distance 1.
    float px = (c.screen[1] - c.screen[0]) / c.xres * c.tan_half_fov;
    float py = (c.screen[3] - c.screen[2]) / c.yres * c.tan_half_fov;
    if (c.orthographic) return {std::min(px, py) * scale, 0};  // a cylinder one pixel wide
    return {0, 2 * std::atan(0.5f * std::min(px, py)) * scale};
}

float cone_width_at(const RayCone& cone, float t) {
    return cone.width + 2 * t * std::tan(cone.spread / 2);
}

float surface_curvature(const SurfaceHit& hit) {
    const Primitive& pr = *hit.prim;
    if (pr.kind == Primitive::Kind::Sphere) {
        // 1/r in object space over the scale along the surface (algorithms.md §8): transforms
        // that keep the sphere round (its own and its instance's) scale it by their uniform
        // scales; any other, per hit, by the square root of the ratio of the world and object
        // area elements.
        float k;
        if (pr.uniform_scale > 0 && (!hit.instance || hit.instance->uniform)) {
            k = static_cast<float>(1 / (pr.radius * pr.uniform_scale));
            if (hit.instance) k /= hit.instance->curvature_scale;
        } else {
            const auto [dpdu, dpdv] = hit.partials();
            double s = std::sqrt(
                length(cross(dpdu, dpdv)) /
                (pr.phi_max * std::abs(pr.theta_zmax - pr.theta_zmin) * pr.radius * pr.radius *
                 std::max(1e-12, std::sqrt(1 - std::pow(hit.p_object[2] / pr.radius, 2)))));
            k = static_cast<float>(1 / (pr.radius * s));
        }
        return pr.flip ? -k : k;
    }
    if (pr.kind == Primitive::Kind::Disk || pr.normals.empty()) return 0;
    // Per-triangle: mean of (n_j - n_i).(p_j - p_i) / |p_j - p_i|^2 over the three edges.
    const uint32_t* idx = &pr.indices[3 * hit.triangle];
    float k = 0;
    for (int e = 0; e < 3; ++e) {
        uint32_t i = idx[e], j = idx[(e + 1) % 3];
        Vec3 dp = pr.positions[j] - pr.positions[i];
        Vec3 ni = normalize(pr.normals[i]), nj = normalize(pr.normals[j]);
        k += dot(nj - ni, dp) / dot(dp, dp);
    }
    k /= 3;
    if (hit.instance) k /= hit.instance->curvature_scale;  // measured in the object's space
    return pr.flip ? -k : k;
}

namespace {
float density(const SurfaceHit& hit) {  // sqrt of world area per unit (u,v) area
    const auto [dpdu, dpdv] = hit.partials();
    return std::sqrt(length(cross(dpdu, dpdv)));
}
float clamp_cos(float c) {
    return std::copysign(std::max(std::abs(c), 1e-5f), c);
}
}  // namespace

float cone_uv_width(const RayCone& cone, const Vec3& d, const SurfaceHit& hit) {
    float w = std::abs(cone_width_at(cone, hit.t));
    float dn = std::abs(clamp_cos(dot(d, hit.ng)));
    return w / (dn * density(hit));
}

namespace {
// The anisotropic cone's ellipse on the hit's tangent plane: semi-axes a1 (along the incidence
// plane, elongated by 1 / |d.n|) and a2 (across it).
void cone_ellipse(const RayCone& cone, const Vec3& d, const SurfaceHit& hit, Vec3& a1, Vec3& a2) {
    const Vec3& n = hit.ng;
    float r = 0.5f * std::abs(cone_width_at(cone, hit.t));
    float dn = clamp_cos(dot(n, d));
    Vec3 along = d - dot(n, d) * n;
    if (dot(along, along) < 1e-12f) {  // head-on: a circle of radius r in the tangent plane
        Frame f = Frame::from_z(n);
        a1 = f.s * r;
        a2 = f.t * r;
    } else {
        a1 = normalize(along) * (r / std::abs(dn));  // elongated along the incidence plane
        a2 = normalize(cross(n, a1)) * r;
    }
}
}  // namespace

texture::Footprint cone_uv_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit,
                                Vec3& world_a, Vec3& world_b) {
    Vec3 a1, a2;
    cone_ellipse(cone, d, hit, a1, a2);
    UvDelta g1, g2;
    hit.uv_offsets(a1, a2, g1, g2);
    world_a = a1 * 2.0f;
    world_b = a2 * 2.0f;
    return texture::Footprint::axes({2 * g1.du, 2 * g1.dv}, {2 * g2.du, 2 * g2.dv});
}

texture::Footprint cone_uv_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit) {
    Vec3 a, b;
    return cone_uv_axes(cone, d, hit, a, b);
}

void cone_world_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit, Vec3& a, Vec3& b) {
    const float w = std::abs(cone_width_at(cone, hit.t)) / std::abs(clamp_cos(dot(d, hit.ng)));
    const Frame f = Frame::from_z(hit.ng);
    a = f.s * w;
    b = f.t * w;
}

RayCone reflect_cone(const RayCone& cone, const Vec3& d, const SurfaceHit& hit) {
    RayCone out;
    out.width = cone_width_at(cone, hit.t);
    float dn = clamp_cos(dot(d, hit.ns));
    float beta = surface_curvature(hit) * out.width / (-dn);
    out.spread = cone.spread + 2 * beta;
    return out;
}

RayCone refract_cone(const RayCone& cone, const Vec3& d, const SurfaceHit& hit, float eta) {
    // Work in the plane spanned by D and N (N against D): 2-D coordinates (tangent, normal).
    const float w = cone_width_at(cone, hit.t);
    const float side = dot(d, hit.ns) < 0 ? 1.0f : -1.0f;
    const Vec3 n = side * hit.ns;
    Vec3 tan3 = d - dot(d, n) * n;
    float tl = length(tan3);
    if (tl < 1e-6f) tan3 = Frame::from_z(n).s, tl = 1;
    tan3 = tan3 / tl;
    const float dx = dot(d, tan3), dy = dot(d, n);  // dy < 0
    const float beta = surface_curvature(hit) * w / (-clamp_cos(dot(d, hit.ns)));
    struct V2 {
        float x, y;
    };
    auto rot = [](V2 v, float a) {
        return V2{v.x * std::cos(a) - v.y * std::sin(a), v.x * std::sin(a) + v.y * std::cos(a)};
    };
    auto refract2 = [&](V2 dir, V2 nrm) {  // nrm against dir
        float c = dir.x * nrm.x + dir.y * nrm.y;
        float k = 1 - eta * eta * (1 - c * c);
        if (k < 0) {  // total internal reflection: leave tangentially
            V2 t{dir.x - c * nrm.x, dir.y - c * nrm.y};
            float l = std::hypot(t.x, t.y);
            return l > 0 ? V2{t.x / l, t.y / l} : V2{nrm.y, -nrm.x};
        }
        float mu = eta * c + std::sqrt(k);
        return V2{eta * dir.x - mu * nrm.x, eta * dir.y - mu * nrm.y};
    };
    V2 dc{dx, dy}, perp{-dy, dx};
    V2 hits[2], dirs[2];
    for (int s = 0; s < 2; ++s) {
        float sg = s == 0 ? 1.0f : -1.0f;
        V2 dir = rot(dc, sg * cone.spread / 2);
        // Start half the cone's initial width off the central ray, t before the hit.
        V2 start{-dc.x * hit.t + sg * perp.x * (cone.width / 2),
                 -dc.y * hit.t + sg * perp.y * (cone.width / 2)};
        if (std::abs(dir.y) < 1e-8f) dir.y = -1e-8f;
        float t = -start.y / dir.y;  // surface line: y = 0
        hits[s] = {start.x + t * dir.x, 0};
        dirs[s] = refract2(dir, rot(V2{0, 1}, -sg * beta / 2));
    }
    V2 tc = refract2(dc, V2{0, 1});
    float tcl = std::hypot(tc.x, tc.y);
    tc = {tc.x / tcl, tc.y / tcl};
    RayCone out;
    // Signed angle from the lower to the upper boundary ray: positive while the cone diverges.
    out.spread = std::atan2(dirs[1].x * dirs[0].y - dirs[1].y * dirs[0].x,
                            dirs[1].x * dirs[0].x + dirs[1].y * dirs[0].y);
    V2 sep{hits[0].x - hits[1].x, hits[0].y - hits[1].y};
    out.width = std::abs(sep.x * -tc.y + sep.y * tc.x) * (w < 0 ? -1.0f : 1.0f);
    return out;
}

}  // namespace cmam::render
