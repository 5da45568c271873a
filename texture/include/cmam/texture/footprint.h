// cmam::texture — the footprint seam between producers and filters.
// Footprint producers (ray differentials, ray cones, the CMAM) describe a pixel's texture-space
// extent with this value type; filters (MIP, SAT, EWA) consume it. Nothing here knows rays.
#pragma once

#include <array>
#include <cstdint>

namespace cmam::texture {

/// A texture-space vector or point in (u,v) units (not texels).
struct Vec2d {
    double u = 0, v = 0;
};

/// A ray's tag as the CMAM sees it (paper §3.1): the ray ID (scanline or pixel) and the
/// recursion level (0 for primary rays, +1 per specular bounce). `seq` numbers the camera
/// samples of one ID in the order they are traced (algorithms.md §6.3.2), so the CMAM can
/// accept only adjacent samples.
struct RayTag {
    uint32_t id = 0;
    uint32_t level = 0;
    uint32_t seq = 0;
};

/// A texture-space footprint around the lookup point.
/// * `None`: no area information; every filter falls back to bilinear at level 0.
/// * `Axes`: two axis vectors in (u,v) units, read as conjugate semi-diameters of an ellipse
///   (the columns of the Jacobian d(u,v)/d(x,y): one pixel step each).
/// * `Points`: up to three texture-space sample points (the CMAM's cached samples plus the
///   current one, current first); filters build their region from them.
struct Footprint {
    enum class Kind : uint8_t { None, Axes, Points };
    Kind kind = Kind::None;
    Vec2d axis_a{}, axis_b{};
    std::array<Vec2d, 3> points{};
    int point_count = 0;

    static Footprint none() { return {}; }
    static Footprint axes(Vec2d a, Vec2d b) {
        Footprint f;
        f.kind = Kind::Axes;
        f.axis_a = a;
        f.axis_b = b;
        return f;
    }
};

}  // namespace cmam::texture
