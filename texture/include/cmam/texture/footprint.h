// cmam::texture — the footprint seam between producers and filters.
// Footprint producers (ray differentials, ray cones, the CMAM) describe a pixel's texture-space
// extent with this value type; filters (MIP, SAT, EWA) consume it. Nothing here knows rays.
#pragma once

#include <cstdint>

namespace cmam::texture {

/// A texture-space vector or point in (u,v) units (not texels).
struct Vec2d {
    double u = 0, v = 0;
};

/// A ray's tag as the CMAM sees it (paper §3.1): the ray ID (scanline or pixel) and the
/// recursion level (0 for primary rays, +1 per specular bounce).
struct RayTag {
    uint32_t id = 0;
    uint32_t level = 0;
};

/// A texture-space footprint. `None` means "no area information": filters fall back to a
/// bilinear lookup at level 0 (point sampling). `Axes` gives two axis vectors in (u,v) units,
/// read as conjugate semi-diameters of an ellipse (the columns of the Jacobian d(u,v)/d(x,y)).
struct Footprint {
    enum class Kind : uint8_t { None, Axes };
    Kind kind = Kind::None;
    Vec2d axis_a{}, axis_b{};

    static Footprint none() { return {}; }
    static Footprint axes(Vec2d a, Vec2d b) { return {Kind::Axes, a, b}; }
};

}  // namespace cmam::texture
