// render — ray differentials (Igehy 1999; pbrt's default footprint). algorithms.md §7.
// A ray carries dO/dx, dO/dy, dD/dx, dD/dy (unit D). They are transferred to the hit, turned
// into (u,v) derivatives (the footprint's two axes), and propagated through perfect
// reflection and refraction. Non-finite values or grazing hits drop the differentials.
#pragma once

#include <cmath>

#include "render/scene.h"

namespace cmam::render {

struct RayDifferential {
    bool valid = false;
    Vec3 dodx, dody, dddx, dddy;
};

/// Camera differentials of the unit direction through raster (px, py), scaled by `scale`
/// (pbrt-v3 scales by 1/sqrt(spp)).
RayDifferential camera_differential(const Camera& camera, float px, float py, float scale);

/// The camera's one-pixel steps of the unnormalised ray direction along x and y, in world space:
/// the same for every ray, so a renderer computes them once (camera_differential's result is
/// the same bit for bit). For the perspective camera the unnormalised direction through raster
/// (px, py) is affine in them: corner + px right + py down.
struct CameraSteps {
    Vec3 right, down;
    Vec3 corner;  // the unnormalised direction through raster (0, 0)
};
CameraSteps camera_steps(const Camera& camera);
RayDifferential camera_differential(const Camera& camera, const CameraSteps& steps, float px,
                                    float py, float scale);

/// The unit direction of the perspective camera's ray through raster (px, py) into `dir`, from
/// the affine form corner + px right + py down (three multiply-adds a component and one
/// normalisation, where generate_ray maps the raster position to the screen and through the
/// camera's matrix; its direction to rounding), returning 1/|d| of the unnormalised direction d
/// (the ray's differential needs it). The ray starts at the camera's origin.
inline float perspective_direction(const CameraSteps& s, float px, float py, Vec3& dir) {
    const Vec3 d = s.corner + px * s.right + py * s.down;
    const float inv_len = 1 / std::sqrt(dot(d, d));
    dir.x = d.x * inv_len;
    dir.y = d.y * inv_len;
    dir.z = d.z * inv_len;
    return inv_len;
}

/// Camera differentials of a perspective ray from its unit direction n and 1/|d|
/// (perspective_direction),
/// into `rd`: dn/dx = (right - (n.right) n) / |d|, likewise down, times `scale`;
/// camera_differential's up to rounding, without recomputing the direction.
inline void camera_differential(const CameraSteps& s, const Vec3& n, float inv_len, float scale,
                                RayDifferential& rd) {
    const float k = inv_len * scale;
    rd.valid = true;
    rd.dodx = {};
    rd.dody = {};
    rd.dddx = (s.right - dot(n, s.right) * n) * k;
    rd.dddy = (s.down - dot(n, s.down) * n) * k;
}

/// The perspective camera's rays through raster positions (fx[i], fy[i]), i < n <= 16, and
/// their differentials, computed together: per ray the operations of perspective_direction and
/// of the camera_differential above in their order (the same values bit for bit), with SSE four
/// rays an instruction. A sample's chain of a square root and two divisions is long, and one ray
/// after another left most of it waiting; side by side the rays overlap.
struct CameraRayBatch {
    static constexpr int kMax = 16;
    alignas(16) float dir[3][kMax];   // unit directions, per component
    alignas(16) float dddx[3][kMax];  // dD/dx, dD/dy times the scale
    alignas(16) float dddy[3][kMax];
};
void perspective_rays(const CameraSteps& s, const float* fx, const float* fy, int n, float scale,
                      CameraRayBatch& out);

/// Differential geometry at a hit: dP/dx, dP/dy and the (u,v) derivatives.
struct HitDifferential {
    bool valid = false;
    Vec3 dpdx, dpdy;
    float dudx = 0, dvdx = 0, dudy = 0, dvdy = 0;
};

/// Transfers `ray` (unit direction `d`) to `hit` (plane of the geometric normal). Without `uv`
/// only dP/dx and dP/dy are computed (what reflection and refraction need), the (u,v)
/// derivatives stay zero.
HitDifferential transfer(const RayDifferential& ray, const Vec3& d, const SurfaceHit& hit,
                         bool uv = true);
/// The same written into `h` (a hit footprint's, without a copy).
void transfer(const RayDifferential& ray, const Vec3& d, const SurfaceHit& hit, bool uv,
              HitDifferential& h);

/// Differentials of the perfectly reflected ray wi = -wo + 2 (wo.n) n (n the shading normal).
RayDifferential reflect(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit);
/// Differentials of the refracted ray with relative index eta = n_incident / n_transmitted
/// (total internal reflection falls back to reflection).
RayDifferential refract(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, float eta);
/// The same given the shading normal's derivatives along hd.dpdx and hd.dpdy
/// (hit.normal_offsets), which a hit with both children computes once for the two.
RayDifferential reflect(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, const Vec3& dnx, const Vec3& dny);
RayDifferential refract(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, float eta, const Vec3& dnx, const Vec3& dny);

}  // namespace cmam::render
