// render — pbrt-v3's "fourier" material: a measured or layered isotropic BSDF tabulated in a
// spline × Fourier basis (Jakob et al. 2014, "A Comprehensive Framework for Rendering Layered
// Materials"), read from the `.bsdf` files its layer designer writes (algorithms.md §18,
// "Fourier BSDFs").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/math.h"

namespace cmam::render {

/// A tabulated BSDF. Directions are in the shading frame; mu is the cosine of an elevation. For
/// each pair of elevation nodes (mu_i for -wi, mu_o for wo) the table holds the coefficients of a
/// cosine series in the azimuth difference phi: f |mu_i| = sum_k a_k cos(k phi), one series per
/// channel (the luminance Y, then red and blue for three channels).
struct FourierTable {
    int n_mu = 0;                // elevation nodes
    int m_max = 0;               // the longest series
    int channels = 0;            // 1 or 3
    float eta = 1;               // relative index through the material (bottom over top)
    std::vector<float> mu;       // n_mu cosines from -1 to 1, not decreasing (-0 and 0 may both be)
    std::vector<float> cdf;      // [o * n_mu + i]: integral of a0 over mu_i up to node i
    std::vector<float> a0;       // [o * n_mu + i]: the luminance series' constant term
    std::vector<int> offset, m;  // [o * n_mu + i]: where a series starts in `a`, its length
    std::vector<float> a;        // every series, channel after channel

    /// Coefficients of node pair (i, o) and their count per channel.
    const float* series(int i, int o, int* count) const {
        const std::size_t k = static_cast<std::size_t>(o) * n_mu + i;
        *count = m[k];
        return a.data() + offset[k];
    }
};

/// Largest `.bsdf` file read (the ones published are under 1 MB).
constexpr std::uintmax_t kMaxFourierFileBytes = std::uintmax_t(256) << 20;

/// Reads a `.bsdf` file (the "SCATFUN" format, version 1: little-endian 32-bit integers and
/// floats). Throws RenderError naming `path` with the reason: the file missing or unreadable,
/// another format or version, textured or harmonic-extrapolated tables and channel counts other
/// than 1 and 3 (which pbrt-v3 does not render either), or offsets and lengths outside the data.
FourierTable read_fourier_table(const std::string& path);

/// The BSDF value for wo and wi in the shading frame (radiance transport).
Rgb fourier_f(const FourierTable& t, const Vec3& wo, const Vec3& wi);

/// The density fourier_pdf reports for wi: the luminance series over its integral.
float fourier_pdf(const FourierTable& t, const Vec3& wo, const Vec3& wi);

/// A direction drawn from the luminance: mu_i by inverting the spline of a0 over mu_i, then phi
/// by inverting the series' integral. `pdf` is the density it was drawn with (0: none drawn),
/// `f` the value there.
using FourierSample = DirectionSample;
FourierSample fourier_sample(const FourierTable& t, const Vec3& wo, float u_phi, float u_mu);

}  // namespace cmam::render
