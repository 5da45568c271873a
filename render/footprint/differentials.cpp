#include "render/footprint/differentials.h"

#include <cmath>

namespace cmam::render {

namespace {
Vec3 world_vector(const Camera& c, const Vec3& v) {
    const auto& m = c.world_from_camera;
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
}
}  // namespace

CameraSteps camera_steps(const Camera& c) {
    return {world_vector(c, Vec3((c.screen[1] - c.screen[0]) / c.xres * c.tan_half_fov, 0, 0)),
            world_vector(c, Vec3(0, -(c.screen[3] - c.screen[2]) / c.yres * c.tan_half_fov, 0)),
            world_vector(c, Vec3(c.screen[0] * c.tan_half_fov, c.screen[3] * c.tan_half_fov, 1))};
}

RayDifferential camera_differential(const Camera& c, float px, float py, float scale) {
    return camera_differential(c, camera_steps(c), px, py, scale);
}

RayDifferential camera_differential(const Camera& c, const CameraSteps& steps, float px, float py,
                                    float scale) {
    // Unnormalised direction d(x,y) = V + x R + y U in world space; R, U are one-pixel steps.
    const float sx = c.screen[0] + (px / c.xres) * (c.screen[1] - c.screen[0]);
    const float sy = c.screen[3] - (py / c.yres) * (c.screen[3] - c.screen[2]);
    Vec3 d = world_vector(c, Vec3(sx * c.tan_half_fov, sy * c.tan_half_fov, 1));
    const Vec3 &r = steps.right, &u = steps.down;
    RayDifferential rd;
    rd.valid = true;
    if (c.orthographic) {  // parallel rays: the origin moves one pixel, the direction not at all
        rd.dodx = r * scale;
        rd.dody = u * scale;
        return rd;
    }
    const float dd = dot(d, d), k = 1 / (dd * std::sqrt(dd));
    rd.dddx = (dd * r - dot(d, r) * d) * (k * scale);
    rd.dddy = (dd * u - dot(d, u) * d) * (k * scale);
    return rd;
}

HitDifferential transfer(const RayDifferential& ray, const Vec3& d, const SurfaceHit& hit,
                         bool uv) {
    HitDifferential h;
    transfer(ray, d, hit, uv, h);
    return h;
}

void transfer(const RayDifferential& ray, const Vec3& d, const SurfaceHit& hit, bool uv,
              HitDifferential& h) {
    h = {};
    if (!ray.valid) return;
    const Vec3& n = hit.ng;
    const float dn = dot(d, n);
    if (std::abs(dn) < 1e-6f) return;  // grazing: the plane of the hit gives no footprint
    const float t = hit.t;
    Vec3 ox = ray.dodx + t * ray.dddx, oy = ray.dody + t * ray.dddy;
    h.dpdx = ox + (-dot(ox, n) / dn) * d;
    h.dpdy = oy + (-dot(oy, n) / dn) * d;
    if (!uv) {
        h.valid = finite(h.dpdx) && finite(h.dpdy);
        return;
    }
    UvDelta x, y;
    hit.uv_offsets(h.dpdx, h.dpdy, x, y);
    h.dudx = x.du;
    h.dvdx = x.dv;
    h.dudy = y.du;
    h.dvdy = y.dv;
    h.valid = finite(h.dpdx) && finite(h.dpdy) && std::isfinite(h.dudx) && std::isfinite(h.dvdx) &&
              std::isfinite(h.dudy) && std::isfinite(h.dvdy);
}

RayDifferential reflect(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit) {
    if (!ray.valid || !hd.valid) return {};
    Vec3 dnx, dny;
    hit.normal_offsets(hd.dpdx, hd.dpdy, dnx, dny);
    return reflect(ray, hd, d, hit, dnx, dny);
}

RayDifferential reflect(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, const Vec3& dnx, const Vec3& dny) {
    RayDifferential out;
    if (!ray.valid || !hd.valid) return out;
    const Vec3& n = hit.ns;
    const float dn = dot(d, n);
    auto one = [&](const Vec3& dnrm, const Vec3& dd) {
        float ddn = dot(dd, n) + dot(d, dnrm);
        return dd - 2 * (dn * dnrm + ddn * n);
    };
    out.dodx = hd.dpdx;
    out.dody = hd.dpdy;
    out.dddx = one(dnx, ray.dddx);
    out.dddy = one(dny, ray.dddy);
    out.valid = finite(out.dddx) && finite(out.dddy);
    return out;
}

RayDifferential refract(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, float eta) {
    if (!ray.valid || !hd.valid) return {};
    Vec3 dnx, dny;
    hit.normal_offsets(hd.dpdx, hd.dpdy, dnx, dny);
    return refract(ray, hd, d, hit, eta, dnx, dny);
}

RayDifferential refract(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, float eta, const Vec3& dnx, const Vec3& dny) {
    RayDifferential out;
    if (!ray.valid || !hd.valid) return out;
    // N oriented against D (D.N < 0), as is its derivative.
    const float side = dot(d, hit.ns) < 0 ? 1.0f : -1.0f;
    const Vec3 n = side * hit.ns;
    const float dn = dot(d, n);
    const float k = 1 - eta * eta * (1 - dn * dn);
    if (k < 0) return reflect(ray, hd, d, hit, dnx, dny);  // total internal reflection
    const float tn = -std::sqrt(k);                        // T.N
    const float mu = eta * dn - tn;
    auto one = [&](const Vec3& dn_hit, const Vec3& dd) {
        Vec3 dnrm = side * dn_hit;
        float ddn = dot(dd, n) + dot(d, dnrm);
        float dmu = (eta - eta * eta * dn / tn) * ddn;
        return eta * dd - (mu * dnrm + dmu * n);
    };
    out.dodx = hd.dpdx;
    out.dody = hd.dpdy;
    out.dddx = one(dnx, ray.dddx);
    out.dddy = one(dny, ray.dddy);
    out.valid = finite(out.dddx) && finite(out.dddy);
    return out;
}

}  // namespace cmam::render
