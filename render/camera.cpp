// render — the camera's primary rays (pbrt-v3's perspective, orthographic and environment
// cameras).
#include <cmath>

#include "render/scene.h"

namespace cmam::render {

CameraRay Camera::generate_ray(float px, float py) const {
    const auto& m = world_from_camera;
    if (environment) {
        const float theta = kPi * py / yres, phi = 2 * kPi * px / xres;
        const Vec3 d(std::sin(theta) * std::cos(phi), std::cos(theta),
                     std::sin(theta) * std::sin(phi));
        return {Vec3(m[3], m[7], m[11]), normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                                                        m[4] * d.x + m[5] * d.y + m[6] * d.z,
                                                        m[8] * d.x + m[9] * d.y + m[10] * d.z))};
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
