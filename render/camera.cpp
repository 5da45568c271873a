// render — the camera's primary rays (pbrt-v3's perspective, orthographic and environment
// cameras).
#include <cmath>

#include "render/lens.h"
#include "render/scene.h"

namespace cmam::render {

namespace {
// The environment camera's world direction at polar angle theta and azimuth phi, from their
// sines and cosines.
Vec3 environment_direction(const std::array<float, 12>& m, float sin_theta, float cos_theta,
                           float sin_phi, float cos_phi) {
    const Vec3 d(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi);
    return normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                          m[4] * d.x + m[5] * d.y + m[6] * d.z,
                          m[8] * d.x + m[9] * d.y + m[10] * d.z));
}
}  // namespace

void concentric_disc(float u, float v, float& x, float& y) {
    const float a = 2 * u - 1, b = 2 * v - 1;
    if (a == 0 && b == 0) {
        x = y = 0;
        return;
    }
    float r, theta;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        theta = kPi / 4 * (b / a);
    } else {
        r = b;
        theta = kPi / 2 - kPi / 4 * (a / b);
    }
    x = r * std::cos(theta);
    y = r * std::sin(theta);
}

CameraRay Camera::generate_ray(float px, float py, float lu, float lv) const {
    if (!has_lens()) return generate_ray(px, py);
    if (realistic) {
        // The lens system's ray in camera space, taken to the world (algorithms.md §7.3).
        const auto& m = world_from_camera;
        RealisticLens::Ray r;
        const double w = realistic->generate(px, py, lu, lv, r);
        if (w == 0) return {Vec3(m[3], m[7], m[11]), normalize(Vec3(m[2], m[6], m[10])), 0};
        const Vec3 o(float(r.o.x), float(r.o.y), float(r.o.z)),
            d(float(r.d.x), float(r.d.y), float(r.d.z));
        return {Vec3(m[0] * o.x + m[1] * o.y + m[2] * o.z + m[3],
                     m[4] * o.x + m[5] * o.y + m[6] * o.z + m[7],
                     m[8] * o.x + m[9] * o.y + m[10] * o.z + m[11]),
                normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                               m[4] * d.x + m[5] * d.y + m[6] * d.z,
                               m[8] * d.x + m[9] * d.y + m[10] * d.z)),
                static_cast<float>(w)};
    }
    // In camera space the pinhole ray's direction is d = (sx tan, sy tan, 1): it meets the plane
    // of focus z = focal_distance at focal_distance d; the ray leaves the lens point towards it
    // (algorithms.md §7), along d - lens / focal_distance (the same direction, without the
    // product that overflows for a far plane of focus).
    const auto& m = world_from_camera;
    const float sx = screen[0] + (px / xres) * (screen[1] - screen[0]);
    const float sy = screen[3] - (py / yres) * (screen[3] - screen[2]);
    float lx, ly;
    concentric_disc(lu, lv, lx, ly);
    lx *= lens_radius;
    ly *= lens_radius;
    const Vec3 d(sx * tan_half_fov - lx / focal_distance, sy * tan_half_fov - ly / focal_distance,
                 1);
    return {
        Vec3(m[0] * lx + m[1] * ly + m[3], m[4] * lx + m[5] * ly + m[7],
             m[8] * lx + m[9] * ly + m[11]),
        normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                       m[8] * d.x + m[9] * d.y + m[10] * d.z))};
}

void Camera::environment_directions(float px, float py, Vec3 (&dirs)[3]) const {
    const float theta = kPi * py / yres, phi = 2 * kPi * px / xres;
    const float theta_down = kPi * (py + 1) / yres, phi_right = 2 * kPi * (px + 1) / xres;
    const float st = std::sin(theta), ct = std::cos(theta), sp = std::sin(phi), cp = std::cos(phi);
    const auto& m = world_from_camera;
    dirs[0] = environment_direction(m, st, ct, sp, cp);
    dirs[1] = environment_direction(m, st, ct, std::sin(phi_right), std::cos(phi_right));
    dirs[2] = environment_direction(m, std::sin(theta_down), std::cos(theta_down), sp, cp);
}

CameraRay Camera::generate_ray(float px, float py) const {
    if (realistic) return generate_ray(px, py, 0.5f, 0.5f);
    const auto& m = world_from_camera;
    if (environment) {
        const float theta = kPi * py / yres, phi = 2 * kPi * px / xres;
        return {Vec3(m[3], m[7], m[11]), environment_direction(m, std::sin(theta), std::cos(theta),
                                                               std::sin(phi), std::cos(phi))};
    }
    float sx = screen[0] + (px / xres) * (screen[1] - screen[0]);
    float sy = screen[3] - (py / yres) * (screen[3] - screen[2]);
    if (orthographic) {
        return {Vec3(m[0] * sx + m[1] * sy + m[3], m[4] * sx + m[5] * sy + m[7],
                     m[8] * sx + m[9] * sy + m[11]),
                normalize(Vec3(m[2], m[6], m[10]))};
    }
    Vec3 d(sx * tan_half_fov, sy * tan_half_fov, 1);
    return {Vec3(m[3], m[7], m[11]), normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                                                    m[4] * d.x + m[5] * d.y + m[6] * d.z,
                                                    m[8] * d.x + m[9] * d.y + m[10] * d.z))};
}

}  // namespace cmam::render
