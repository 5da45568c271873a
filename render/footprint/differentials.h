// render — ray differentials (Igehy 1999; pbrt's default footprint). algorithms.md §7.
// A ray carries dO/dx, dO/dy, dD/dx, dD/dy (unit D). They are transferred to the hit, turned
// into (u,v) derivatives (the footprint's two axes), and propagated through perfect
// reflection and refraction. Non-finite values or grazing hits drop the differentials.
#pragma once

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
/// the same bit for bit).
struct CameraSteps {
    Vec3 right, down;
};
CameraSteps camera_steps(const Camera& camera);
RayDifferential camera_differential(const Camera& camera, const CameraSteps& steps, float px,
                                    float py, float scale);

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

/// Differentials of the perfectly reflected ray wi = -wo + 2 (wo.n) n (n the shading normal).
RayDifferential reflect(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit);
/// Differentials of the refracted ray with relative index eta = n_incident / n_transmitted
/// (total internal reflection falls back to reflection).
RayDifferential refract(const RayDifferential& ray, const HitDifferential& hd, const Vec3& d,
                        const SurfaceHit& hit, float eta);

}  // namespace cmam::render
