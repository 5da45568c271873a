// render — ray cones (Akenine-Moller et al. 2019, 2021; Boksansky et al. 2021), the real-time
// footprint. algorithms.md §8. A ray carries a signed width and spread angle; at a hit the cone
// gives an isotropic footprint (a MIP level) or, anisotropically, two axis vectors for EWA.
// Surface curvature widens reflected cones; refraction follows the cone's boundary rays.
#pragma once

#include <cmam/texture/footprint.h>

#include "render/scene.h"

namespace cmam::render {

struct RayCone {
    float width = 0;   // signed; negative past a focus
    float spread = 0;  // signed full cone angle (radians)
};

/// Pixel spread angle of the camera (square pixels of the shorter axis), scaled by `scale`.
RayCone camera_cone(const Camera& camera, float scale);

/// Width of `cone` after travelling `t` (exact form w + 2 t tan(spread/2)).
float cone_width_at(const RayCone& cone, float t);

/// Signed curvature of the surface at `hit` (1/r for spheres; per-triangle from vertex normals).
float surface_curvature(const SurfaceHit& hit);

/// Isotropic footprint radius in (u,v) units at the hit: |w| / (|d.n| sqrt|dP/du x dP/dv|).
float cone_uv_width(const RayCone& cone, const Vec3& d, const SurfaceHit& hit);
/// Anisotropic footprint axes (2 g1, 2 g2) in (u,v) units (JCGT 2021, with its factor 2).
texture::Footprint cone_uv_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit);
/// The same, and the ellipse's diameters 2 a1, 2 a2 themselves (world-space vectors in the
/// tangent plane, whose (u,v) images the axes are) in `world_a`, `world_b`: what a texture
/// mapping the hit's point rather than its (u,v) (spherical, cylindrical, planar) maps.
texture::Footprint cone_uv_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit,
                                Vec3& world_a, Vec3& world_b);
/// The isotropic cone's footprint for those mappings: two orthogonal tangents |w| / |d.n| long,
/// the world extent cone_uv_width measures in (u,v).
void cone_world_axes(const RayCone& cone, const Vec3& d, const SurfaceHit& hit, Vec3& a, Vec3& b);

/// Cone after a perfect reflection at `hit` (width kept, spread + 2 beta).
RayCone reflect_cone(const RayCone& cone, const Vec3& d, const SurfaceHit& hit);
/// Cone after refraction into the medium with relative index eta = n_i / n_t (RTG II ch. 10:
/// refract the boundary rays against normals tilted by the surface spread).
RayCone refract_cone(const RayCone& cone, const Vec3& d, const SurfaceHit& hit, float eta);

}  // namespace cmam::render
