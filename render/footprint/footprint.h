// render — the tracer's side of the footprint seam (docs/architecture.md).
// A ray carries one RayFootprint: its ray differential, its ray cone, and what the CMAM reads
// of it (its tag and its path). The integrator hands every event of a ray's life to one
// FootprintProducers object: the camera ray, a hit, a reflection, a refraction, a pass through
// a surface without a material. At a hit the producers turn the ray's state into texture-space
// footprints (texture::Footprint), which the filters consume; producers no texture uses are not
// computed. algorithms.md §7 (differentials), §8 (cones), §6 (the CMAM's tags).
#pragma once

#include <cmam/texture/cmam.h>
#include <cmam/texture/footprint.h>

#include <cstdint>

#include "render/footprint/cones.h"
#include "render/footprint/differentials.h"
#include "render/footprint/method.h"
#include "render/scene.h"

namespace cmam::render {

/// The footprint state a ray carries from event to event.
struct RayFootprint {
    RayDifferential diff;  // valid only when some texture uses ray differentials
    RayCone cone;
    texture::RayTag tag;  // the camera sample's tag; tag.level is the ray's specular depth
    // Which specular bounces led here: 1 for camera rays, then 2p for the reflected and 2p + 1
    // for the refracted child of path p (the CMAM keeps a cache per path).
    uint64_t path = 1;
    // From the camera sample to its stratum's centre, in stratum steps (x, y): the same screen
    // offset at every hit of the path, mapped to (u,v) by that hit's differentials (with ray
    // cones alone, by the camera ray's at its first hit: FootprintProducers' `cone_strata`).
    float to_stratum_x = 0, to_stratum_y = 0;
};

/// A footprint's two axes in (u,v) units, or none (a point sample): what a producer gives at a
/// hit, held compactly (a texture::Footprint also has room for the CMAM's points), since every
/// hit makes one per producer.
struct UvAxes {
    texture::Vec2d a{}, b{};
    bool valid = false;

    texture::Footprint footprint() const {
        return valid ? texture::Footprint::axes(a, b) : texture::Footprint::none();
    }
};

/// An isotropic footprint of width w in (u,v): the axes (w, 0), (0, w).
struct UvWidth {
    float w = 0;
    bool valid = false;

    texture::Footprint footprint() const {
        return valid ? texture::Footprint::axes({w, 0}, {0, w}) : texture::Footprint::none();
    }
};

/// The producers' footprints at one hit, in the surface's (u,v) units.
struct HitFootprint {
    HitDifferential diff;  // as transferred (invalid: no footprint from differentials)
    // The hit's screen derivatives dP/dx, dP/dy when the differentials are valid, zero
    // otherwise: what 3-D textures and the non-uv mappings read.
    Vec3 dpdx{}, dpdy{};
    UvAxes axes;  // ray differentials' Jacobian columns
    // From the hit to its stratum's centre in (u,v): through the differentials at every hit, or
    // through the camera ray's at the first hit for cones (`cone_strata`); zero otherwise.
    texture::Vec2d stratum_offset;
    UvWidth cone;  // isotropic ray cone
    UvAxes cone_aniso;
    // The cones' footprints as world-space vectors in the tangent plane (cone_world_axes), set
    // with `cone` and `cone_aniso` where a texture mapping the hit's point (spherical,
    // cylindrical, planar) reads them: it maps them to its (s,t), as it maps dP/dx and dP/dy for
    // the differentials.
    Vec3 cone_world[2]{}, cone_aniso_world[2]{};
    texture::RayTag tag;  // the ray's tag at this depth
    uint64_t path = 1;
    bool dropped = false;  // the ray carried differentials, but they failed at this hit
    // The shading normal's derivatives along dP/dx and dP/dy, computed by the first child
    // (reflected or refracted) that needs them and kept for the other: a glass hit has both.
    mutable bool dn_ready = false;
    mutable Vec3 dndx, dndy;

    /// The footprint `method` gives here (None for point sampling and for the CMAM, which
    /// builds its own from its cache).
    texture::Footprint of(FootprintMethod method) const;
};

/// The footprint producers of one render: one call per event of a ray.
class FootprintProducers {
  public:
    /// For `methods` over `camera`, `spp` samples per pixel (pbrt-v3 scales a camera sample's
    /// footprint by 1/sqrt(spp)). `cone_strata`: an area-filtered texture reads ray cones, so
    /// camera rays carry their differentials to the first hit, where they map the sample's offset
    /// to its stratum's centre into (u,v) (algorithms.md §5.2, "Cones"); nothing else reads them
    /// unless `methods` has the differentials. `cone_world`: a texture mapping the hit's point
    /// (spherical, cylindrical, planar) reads ray cones, so each hit keeps the cones'
    /// cross-sections as world-space vectors too (HitFootprint::cone_world).
    FootprintProducers(FootprintMethods methods, const Camera& camera, int spp,
                       bool cone_strata = false, bool cone_world = false);

    /// The state of the camera ray through raster position (fx, fy), direction `dir`.
    RayFootprint camera_ray(float fx, float fy, const Vec3& dir, texture::RayTag tag,
                            float to_stratum_x, float to_stratum_y) const;
    /// The same written into `r` (every member but the tag, which is the caller's): a render
    /// loop's slot, without a copy of the state.
    void start_camera_ray(RayFootprint& r, float fx, float fy, const Vec3& dir, float to_stratum_x,
                          float to_stratum_y) const;
    /// The environment camera's: `dirs` from Camera::environment_directions, the ray's and its
    /// neighbours' one pixel right and down (the same state as start_camera_ray's).
    void start_environment_ray(RayFootprint& r, const Vec3 (&dirs)[3], float to_stratum_x,
                               float to_stratum_y) const;
    /// Whether camera rays carry ray differentials (for the differentials, or the cones' strata).
    bool differentials() const { return m_camera_differentials; }
    /// The same for a ray of a camera with a thin lens: from the lens point of sample (lu, lv),
    /// whose differential is pbrt-v3's (the offset rays leave the same lens point towards their
    /// own points on the plane of focus: no origin offset).
    void start_lens_ray(RayFootprint& r, float fx, float fy, float lu, float lv, const Vec3& dir,
                        float to_stratum_x, float to_stratum_y) const;
    /// The same for a ray of a realistic camera (`ray`, from exit-pupil sample (lu, lv)): its
    /// differential is pbrt-v3's, the rays through raster positions 0.05 pixels away along x
    /// and y from the same pupil sample (the other side where one is blocked), their origins'
    /// and directions' differences over 0.05. False where both rays along x or both along y are
    /// blocked: pbrt-v3 then drops the sample (weight 0), whatever the footprints.
    bool start_realistic_ray(RayFootprint& r, float fx, float fy, float lu, float lv,
                             const CameraRay& ray, float to_stratum_x, float to_stratum_y) const;
    /// Whether camera rays can be made together (camera_rays): the perspective pinhole's.
    bool batches_camera_rays() const { return m_batches; }
    /// The perspective camera's rays through (fx[i], fy[i]), i < n <= 16, together
    /// (perspective_rays); start_camera_ray then takes ray i from `batch`.
    void camera_rays(const float* fx, const float* fy, int n, CameraRayBatch& batch) const {
        perspective_rays(m_steps, fx, fy, n, m_scale, batch);
    }
    /// Ray i of `batch` into `org`, `dir` and `r` (every member of r but the tag): the camera's
    /// origin and the single-ray functions' direction and differential (perspective_direction,
    /// camera_differential) for the same raster position, bit for bit.
    void start_camera_ray(RayFootprint& r, Vec3& org, Vec3& dir, const CameraRayBatch& batch, int i,
                          float to_stratum_x, float to_stratum_y) const;
    /// The footprints at `hit` of a ray with state `ray` and unit direction `dir`. Without `uv`
    /// (a hit whose shading reads no texture) only what the ray's children need: dP/dx, dP/dy.
    HitFootprint at_hit(const RayFootprint& ray, const Vec3& dir, const SurfaceHit& hit,
                        bool uv = true) const;
    /// The same written into `f`, a default HitFootprint (a texture context's, without a copy).
    void at_hit(HitFootprint& f, const RayFootprint& ray, const Vec3& dir, const SurfaceHit& hit,
                bool uv) const;
    /// The child ray's state after a perfect reflection at `hit`.
    RayFootprint reflected(const RayFootprint& ray, const HitFootprint& at, const Vec3& dir,
                           const SurfaceHit& hit) const;
    /// The child ray's state after refraction at `hit`, relative index eta = n_i / n_t.
    RayFootprint refracted(const RayFootprint& ray, const HitFootprint& at, const Vec3& dir,
                           const SurfaceHit& hit, float eta) const;
    /// The same written into `child` (a child ray's slot, without a copy of the state).
    void reflected(RayFootprint& child, const RayFootprint& ray, const HitFootprint& at,
                   const Vec3& dir, const SurfaceHit& hit) const;
    void refracted(RayFootprint& child, const RayFootprint& ray, const HitFootprint& at,
                   const Vec3& dir, const SurfaceHit& hit, float eta) const;
    /// The same ray's state after it passes through `hit` (a surface without a material).
    RayFootprint passed_through(const RayFootprint& ray, const HitFootprint& at,
                                const SurfaceHit& hit) const;

    bool uses(FootprintMethod m) const { return m_methods.has(m); }

  private:
    // What every camera ray's state has but its differential: the cone, the path, the offset.
    void start_camera_state(RayFootprint& r, float to_stratum_x, float to_stratum_y) const;

    FootprintMethods m_methods;
    const Camera& m_camera;
    CameraSteps m_steps;    // the camera's one-pixel direction steps
    float m_scale;          // 1/sqrt(spp)
    RayCone m_camera_cone;  // every camera ray's cone
    bool m_differentials, m_cones, m_cones_aniso;
    bool m_cone_strata;           // cones' first hits centred on their strata (constructor)
    bool m_cone_world;            // the cones' world-space cross-sections kept (constructor)
    bool m_camera_differentials;  // m_differentials || m_cone_strata
    bool m_batches;               // batches_camera_rays(), asked of every camera sample
};

}  // namespace cmam::render
