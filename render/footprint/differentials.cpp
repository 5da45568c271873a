#include "render/footprint/differentials.h"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

void perspective_rays(const CameraSteps& s, const float* fx, const float* fy, int n, float scale,
                      CameraRayBatch& out) {
    n = std::clamp(n, 0, CameraRayBatch::kMax);
    int i = 0;
#if defined(__SSE2__)
    // Lane by lane: d = (corner + x right) + y down; 1 / sqrt((dx dx + dy dy) + dz dz); the
    // direction d / |d| as d times that; k = inv_len scale; dD/dx = (right - (n . right) n) k.
    const __m128 one = _mm_set1_ps(1), vscale = _mm_set1_ps(scale);
    auto splat = [](const Vec3& v, __m128* o) {
        o[0] = _mm_set1_ps(v.x);
        o[1] = _mm_set1_ps(v.y);
        o[2] = _mm_set1_ps(v.z);
    };
    __m128 corner[3], right[3], down[3];
    splat(s.corner, corner);
    splat(s.right, right);
    splat(s.down, down);
    auto dot4 = [](const __m128* a, const __m128* b) {
        return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1])),
                          _mm_mul_ps(a[2], b[2]));
    };
    for (; i + 4 <= n; i += 4) {
        const __m128 x = _mm_loadu_ps(fx + i), y = _mm_loadu_ps(fy + i);
        __m128 d[3];
        for (int c = 0; c < 3; ++c)
            d[c] =
                _mm_add_ps(_mm_add_ps(corner[c], _mm_mul_ps(x, right[c])), _mm_mul_ps(y, down[c]));
        const __m128 inv_len = _mm_div_ps(one, _mm_sqrt_ps(dot4(d, d)));
        __m128 u[3];
        for (int c = 0; c < 3; ++c) {
            u[c] = _mm_mul_ps(d[c], inv_len);
            _mm_store_ps(out.dir[c] + i, u[c]);
        }
        const __m128 k = _mm_mul_ps(inv_len, vscale);
        const __m128 ur = dot4(u, right), ud = dot4(u, down);
        for (int c = 0; c < 3; ++c) {
            _mm_store_ps(out.dddx[c] + i,
                         _mm_mul_ps(_mm_sub_ps(right[c], _mm_mul_ps(ur, u[c])), k));
            _mm_store_ps(out.dddy[c] + i, _mm_mul_ps(_mm_sub_ps(down[c], _mm_mul_ps(ud, u[c])), k));
        }
    }
#endif
    for (; i < n; ++i) {  // the rest (and without SSE2): the single ray's functions
        Vec3 u;
        const float inv_len = perspective_direction(s, fx[i], fy[i], u);
        RayDifferential rd;
        camera_differential(s, u, inv_len, scale, rd);
        for (int c = 0; c < 3; ++c) {
            out.dir[c][i] = u[c];
            out.dddx[c][i] = rd.dddx[c];
            out.dddy[c][i] = rd.dddy[c];
        }
    }
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
