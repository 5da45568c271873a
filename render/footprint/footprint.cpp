#include "render/footprint/footprint.h"

#include <algorithm>
#include <cmath>

namespace cmam::render {

namespace {

// The environment camera's ray differential: the rays one pixel right and down, differenced
// (pbrt-v3's default for cameras without a closed form), scaled by `scale`.
RayDifferential environment_differential(const Camera& c, float px, float py, const Vec3& dir,
                                         float scale) {
    RayDifferential rd;
    rd.valid = true;
    rd.dddx = (c.generate_ray(px + 1, py).dir - dir) * scale;
    rd.dddy = (c.generate_ray(px, py + 1).dir - dir) * scale;
    return rd;
}

// Every camera ray's cone: the environment camera's pixel spans 2 pi / xres by pi / yres
// radians; the other cameras' as camera_cone says.
RayCone camera_ray_cone(const Camera& c, float scale) {
    if (c.environment) return RayCone{0, std::min(2 * kPi / c.xres, kPi / c.yres) * scale};
    return camera_cone(c, scale);
}

// The ray's offset to its stratum's centre (screen, in stratum steps) mapped into (u,v) by a
// hit's differential.
texture::Vec2d to_stratum(const HitDifferential& hd, const RayFootprint& ray) {
    return {hd.dudx * ray.to_stratum_x + hd.dudy * ray.to_stratum_y,
            hd.dvdx * ray.to_stratum_x + hd.dvdy * ray.to_stratum_y};
}

}  // namespace

texture::Footprint HitFootprint::of(FootprintMethod method) const {
    switch (method) {
        case FootprintMethod::Differentials:
            return axes.footprint();
        case FootprintMethod::Cones:
            return cone.footprint();
        case FootprintMethod::ConesAniso:
            return cone_aniso.footprint();
        case FootprintMethod::None:
        case FootprintMethod::Cmam:
            break;
    }
    return texture::Footprint::none();
}

FootprintProducers::FootprintProducers(FootprintMethods methods, const Camera& camera, int spp,
                                       bool cone_strata, bool cone_world)
    : m_methods(methods),
      m_camera(camera),
      m_steps(camera_steps(camera)),
      m_scale(1 / std::sqrt(float(spp))),
      m_camera_cone(camera_ray_cone(camera, m_scale)),
      m_differentials(methods.has(FootprintMethod::Differentials)),
      m_cones(methods.has(FootprintMethod::Cones) || methods.has(FootprintMethod::ConesAniso)),
      m_cones_aniso(methods.has(FootprintMethod::ConesAniso)),
      m_cone_strata(cone_strata && m_cones),
      m_cone_world(cone_world && m_cones),
      m_camera_differentials(m_differentials || m_cone_strata),
      m_batches(!camera.orthographic && !camera.environment && !camera.has_lens()) {}

RayFootprint FootprintProducers::camera_ray(float fx, float fy, const Vec3& dir,
                                            texture::RayTag tag, float to_stratum_x,
                                            float to_stratum_y) const {
    RayFootprint r;
    start_camera_ray(r, fx, fy, dir, to_stratum_x, to_stratum_y);
    r.tag = tag;
    return r;
}

void FootprintProducers::start_camera_state(RayFootprint& r, float to_stratum_x,
                                            float to_stratum_y) const {
    r.cone = m_camera_cone;
    r.path = 1;
    r.to_stratum_x = to_stratum_x;
    r.to_stratum_y = to_stratum_y;
}

void FootprintProducers::start_camera_ray(RayFootprint& r, float fx, float fy, const Vec3& dir,
                                          float to_stratum_x, float to_stratum_y) const {
    if (!m_camera_differentials)
        r.diff = {};
    else if (m_camera.environment)
        r.diff = environment_differential(m_camera, fx, fy, dir, m_scale);
    else
        r.diff = camera_differential(m_camera, m_steps, fx, fy, m_scale);
    start_camera_state(r, to_stratum_x, to_stratum_y);
}

void FootprintProducers::start_lens_ray(RayFootprint& r, float fx, float fy, float lu, float lv,
                                        const Vec3& dir, float to_stratum_x,
                                        float to_stratum_y) const {
    r.diff = {};
    if (m_camera_differentials) {
        r.diff.valid = true;
        r.diff.dddx = (m_camera.generate_ray(fx + 1, fy, lu, lv).dir - dir) * m_scale;
        r.diff.dddy = (m_camera.generate_ray(fx, fy + 1, lu, lv).dir - dir) * m_scale;
    }
    start_camera_state(r, to_stratum_x, to_stratum_y);
}

bool FootprintProducers::start_realistic_ray(RayFootprint& r, float fx, float fy, float lu,
                                             float lv, const CameraRay& ray, float to_stratum_x,
                                             float to_stratum_y) const {
    r.diff = {};
    Vec3 d_o[2], d_d[2];
    for (int axis = 0; axis < 2; ++axis) {
        bool found = false;
        for (const float eps : {0.05f, -0.05f}) {
            const CameraRay s = m_camera.generate_ray(fx + (axis == 0 ? eps : 0),
                                                      fy + (axis == 1 ? eps : 0), lu, lv);
            if (s.weight == 0) continue;
            d_o[axis] = (s.org - ray.org) / eps;
            d_d[axis] = (s.dir - ray.dir) / eps;
            found = true;
            break;
        }
        if (!found) return false;
    }
    if (m_camera_differentials) {
        r.diff.valid = true;
        r.diff.dodx = d_o[0] * m_scale;
        r.diff.dody = d_o[1] * m_scale;
        r.diff.dddx = d_d[0] * m_scale;
        r.diff.dddy = d_d[1] * m_scale;
    }
    start_camera_state(r, to_stratum_x, to_stratum_y);
    return true;
}

void FootprintProducers::start_environment_ray(RayFootprint& r, const Vec3 (&dirs)[3],
                                               float to_stratum_x, float to_stratum_y) const {
    r.diff = {};
    if (m_camera_differentials) {
        r.diff.valid = true;
        r.diff.dddx = (dirs[1] - dirs[0]) * m_scale;
        r.diff.dddy = (dirs[2] - dirs[0]) * m_scale;
    }
    start_camera_state(r, to_stratum_x, to_stratum_y);
}

void FootprintProducers::start_camera_ray(RayFootprint& r, Vec3& org, Vec3& dir,
                                          const CameraRayBatch& batch, int i, float to_stratum_x,
                                          float to_stratum_y) const {
    const auto& m = m_camera.world_from_camera;
    org = {m[3], m[7], m[11]};
    dir = {batch.dir[0][i], batch.dir[1][i], batch.dir[2][i]};
    if (m_camera_differentials) {
        r.diff.valid = true;
        r.diff.dodx = {};
        r.diff.dody = {};
        r.diff.dddx = {batch.dddx[0][i], batch.dddx[1][i], batch.dddx[2][i]};
        r.diff.dddy = {batch.dddy[0][i], batch.dddy[1][i], batch.dddy[2][i]};
    } else {
        r.diff = {};
    }
    start_camera_state(r, to_stratum_x, to_stratum_y);
}

HitFootprint FootprintProducers::at_hit(const RayFootprint& ray, const Vec3& dir,
                                        const SurfaceHit& hit, bool uv) const {
    HitFootprint f;
    at_hit(f, ray, dir, hit, uv);
    return f;
}

void FootprintProducers::at_hit(HitFootprint& f, const RayFootprint& ray, const Vec3& dir,
                                const SurfaceHit& hit, bool uv) const {
    f.tag = ray.tag;
    f.path = ray.path;
    if (m_differentials) {
        transfer(ray.diff, dir, hit, uv, f.diff);
        const HitDifferential& hd = f.diff;
        if (hd.valid) {
            f.dpdx = hd.dpdx;
            f.dpdy = hd.dpdy;
            if (uv) {
                f.axes = {{hd.dudx, hd.dvdx}, {hd.dudy, hd.dvdy}, true};
                f.stratum_offset = to_stratum(hd, ray);
            }
        } else
            f.dropped = ray.diff.valid;
    } else if (m_cone_strata && uv && ray.diff.valid) {
        // Only a camera ray carries a differential here (children, and rays passed through a
        // surface without a material, get none): the stratum's centre through it, for the cones'
        // area filter. The hit's own differential, dP/dx, dP/dy and axes stay unset, as for
        // cones alone, so nothing else (a bump map's step, a pass-through) reads it.
        HitDifferential hd;
        transfer(ray.diff, dir, hit, true, hd);
        if (hd.valid) f.stratum_offset = to_stratum(hd, ray);
    }
    if (!uv) return;
    if (m_cones) {
        const float w = cone_uv_width(ray.cone, dir, hit);
        f.cone = {w, true};
        if (m_cone_world) cone_world_axes(ray.cone, dir, hit, f.cone_world[0], f.cone_world[1]);
    }
    if (m_cones_aniso) {
        const texture::Footprint ax =
            m_cone_world
                ? cone_uv_axes(ray.cone, dir, hit, f.cone_aniso_world[0], f.cone_aniso_world[1])
                : cone_uv_axes(ray.cone, dir, hit);
        f.cone_aniso = {ax.axis_a, ax.axis_b, ax.kind == texture::Footprint::Kind::Axes};
    }
}

namespace {
// The hit's normal derivatives, computed on first use (see HitFootprint::dn_ready).
void ensure_normal_derivatives(const HitFootprint& at, const SurfaceHit& hit) {
    if (at.dn_ready) return;
    hit.normal_offsets(at.diff.dpdx, at.diff.dpdy, at.dndx, at.dndy);
    at.dn_ready = true;
}

// A child's state but for its differential and cone, written into `c`.
void start_child(RayFootprint& c, const RayFootprint& ray, uint64_t path) {
    c.tag = ray.tag;
    ++c.tag.level;
    c.path = path;
    c.to_stratum_x = ray.to_stratum_x;
    c.to_stratum_y = ray.to_stratum_y;
}
}  // namespace

RayFootprint FootprintProducers::reflected(const RayFootprint& ray, const HitFootprint& at,
                                           const Vec3& dir, const SurfaceHit& hit) const {
    RayFootprint c;
    reflected(c, ray, at, dir, hit);
    return c;
}

RayFootprint FootprintProducers::refracted(const RayFootprint& ray, const HitFootprint& at,
                                           const Vec3& dir, const SurfaceHit& hit,
                                           float eta) const {
    RayFootprint c;
    refracted(c, ray, at, dir, hit, eta);
    return c;
}

void FootprintProducers::reflected(RayFootprint& c, const RayFootprint& ray, const HitFootprint& at,
                                   const Vec3& dir, const SurfaceHit& hit) const {
    start_child(c, ray, ray.path * 2);
    c.diff = {};
    if (m_differentials && ray.diff.valid && at.diff.valid) {
        ensure_normal_derivatives(at, hit);
        c.diff = reflect(ray.diff, at.diff, dir, hit, at.dndx, at.dndy);
    }
    c.cone = m_cones ? reflect_cone(ray.cone, dir, hit) : RayCone{};
}

void FootprintProducers::refracted(RayFootprint& c, const RayFootprint& ray, const HitFootprint& at,
                                   const Vec3& dir, const SurfaceHit& hit, float eta) const {
    start_child(c, ray, ray.path * 2 + 1);
    c.diff = {};
    if (m_differentials && ray.diff.valid && at.diff.valid) {
        ensure_normal_derivatives(at, hit);
        c.diff = refract(ray.diff, at.diff, dir, hit, eta, at.dndx, at.dndy);
    }
    c.cone = m_cones ? refract_cone(ray.cone, dir, hit, eta) : RayCone{};
}

RayFootprint FootprintProducers::passed_through(const RayFootprint& ray, const HitFootprint& at,
                                                const SurfaceHit& hit) const {
    RayFootprint r = ray;
    r.diff.dodx = at.diff.dpdx;
    r.diff.dody = at.diff.dpdy;
    r.diff.valid = at.diff.valid;
    r.cone.width = cone_width_at(ray.cone, hit.t);
    return r;
}

}  // namespace cmam::render
