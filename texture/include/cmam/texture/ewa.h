// cmam::texture — elliptical weighted average filtering (Greene & Heckbert 1986) on a MIP
// pyramid. algorithms.md §4: the two axes are conjugate semi-diameters (Jacobian columns); a
// unit-variance reconstruction term (+1) keeps the ellipse at least one texel wide; the minor
// axis is lengthened to bound the anisotropy, a degenerate minor axis is replaced by a
// perpendicular one, the level comes from the minor axis and two levels are blended; each row
// visits only the texels inside the ellipse. Cost is bounded by maxAniso, not by the size.
#pragma once

#include <cmam/texture/mip.h>

namespace cmam::texture {

/// Gaussian weights indexed by r^2 in [0,1): LUT[i] = exp(-2 i/(N-1)) - exp(-2), N = 128.
inline constexpr int kEwaLutSize = 128;
const float* ewa_weight_lut();

struct EwaResult {
    Texel value{};
    double lambda = 0;            // fractional MIP level used
    int texels_read = 0;          // texels inside the ellipse(s) that were weighted
    double major = 0, minor = 0;  // semi-axes used, level-0 texels (after clamping)
};

/// The largest maximum anisotropy EWA applies: the cost of a lookup grows with it (about 2.2
/// maxAniso texels per line of the finer level), so larger requests, which no display needs
/// (GPUs stop at 16), are clamped to it rather than allowed to read millions of texels.
inline constexpr double kEwaMaxAnisotropy = 256;

/// EWA lookup at (u,v) with axes `a`, `b` in uv units. `max_aniso` is clamped to
/// [1, kEwaMaxAnisotropy] (NaN gives 1).
EwaResult ewa(const MipPyramid& pyramid, double u, double v, double au, double av, double bu,
              double bv, double max_aniso = 8);

/// The ellipse of axes a, b (level texels) with the +1 reconstruction term: implicit
/// coefficients before normalisation (A x^2 + B x y + C y^2 = F) and the bounding half-extents.
struct EwaEllipse {
    double A = 0, B = 0, C = 0, F = 0;
    double hx = 0, hy = 0;
};
EwaEllipse ewa_ellipse(double a_s, double a_t, double b_s, double b_t);

/// One EWA evaluation on one level, with axes in that level's texels (exposed for tests): the
/// value and the texels weighted.
struct EwaLevelResult {
    Texel value{};
    int texels_read = 0;
};
EwaLevelResult ewa_level(const Image& level, double u, double v, double a_s, double a_t, double b_s,
                         double b_t);

}  // namespace cmam::texture
