// cmam::texture — the footprint seam between producers and filters.
// Footprint producers (ray differentials, ray cones, the CMAM) describe a pixel's texture-space
// extent with this value type; filters (MIP, SAT, EWA) consume it. Nothing here knows rays.
#pragma once

#include <cmam/texture/vec2.h>

#include <array>
#include <cstdint>

namespace cmam::texture {

/// How EWA reads the CMAM's two non-orthogonal vectors (algorithms.md §6.2 item 3): R1
/// conjugate semi-diameters, R2 an orthogonal minor axis of the same length, R3 the minor
/// vector orthogonalised against the major.
enum class CmamEllipse : uint8_t { Conjugate, Orthogonal, Orthogonalised };
/// SAT region for one matching sample: the rectangle spanned by the two samples (paper), or a
/// square of side |p1 - p0| centred on the current sample (algorithms.md §6.4 alternative).
enum class CmamSatBox : uint8_t { Spanned, Square };

/// A texture-space footprint around the lookup point.
/// * `None`: no area information; every filter falls back to bilinear at level 0.
/// * `Axes`: two axis vectors in (u,v) units, the columns of the Jacobian d(u,v)/d(x,y) (one
///   pixel or stratum step each): the pixel's parallelogram c ± a/2 ± b/2, which EWA reads as
///   the conjugate semi-diameters of its ellipse.
/// * `Points`: two or three texture-space sample points, the current one first, then the 1-D
///   CMAM's matching cached samples, most recent first; every filter builds the paper's region
///   for it from them (cmam_region(), algorithms.md §6.1) with the same rules the CMAM uses.
///   One point alone has no region: bilinear at level 0.
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
