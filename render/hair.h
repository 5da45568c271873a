// render — pbrt-v3's hair BSDF (its "hair" material): the scattering model of d'Eon et al. 2011
// and Chiang et al. 2016, with lobes R, TT, TRT and the rest, each a longitudinal term M_p, an
// attenuation A_p and an azimuthal term N_p (algorithms.md §21).
#pragma once

#include <optional>

#include "render/math.h"

namespace cmam::render {

/// The hair BSDF's parameters at a point: h in [-1, 1] where the ray meets the fibre's width
/// (pbrt-v3's -1 + 2v), the fibre's index of refraction, its absorption per unit length
/// (relative to its radius), the longitudinal and azimuthal roughnesses in [0, 1] and the
/// scales' tilt in degrees.
struct HairParams {
    float h = 0, eta = 1.55f;
    Rgb sigma_a{};
    float beta_m = 0.3f, beta_n = 0.3f, alpha = 2;
};

/// The hair BSDF at a shading point: its parameters and what they alone give every evaluation,
/// made once where the point is shaded (two powers, a sine and an arcsine, which the value, the
/// density and the sampling each took anew): the lobes' longitudinal variances v, the azimuthal
/// logistic's scale s, sin and cos of 2^k alpha (the scales' tilt, doubled per bounce) and
/// gamma_o = asin h.
struct HairModel {
    static constexpr int kLobes = 4;  // R, TT, TRT, and one for all the longer paths
    HairParams p;
    float v[kLobes] = {}, s = 0, sin2k[3] = {}, cos2k[3] = {}, gamma_o = 0;
    HairModel() = default;
    explicit HairModel(const HairParams& params);
    /// sin and cos of theta_o turned by lobe k's tilt (R by -2 alpha, TT by alpha, TRT by
    /// 4 alpha; the rest not at all), the cosine's sign dropped.
    void tilt(int k, float sin_o, float cos_o, float& sin_ok, float& cos_ok) const;
};

/// In the hair's local frame: x along the fibre, z the surface normal (the ray's side of the
/// fibre). f includes pbrt-v3's 1 / |cos theta_i| (wi.z), so f |wi.z| integrates to the albedo.
Rgb hair_f(const HairModel& m, const Vec3& wo, const Vec3& wi);
float hair_pdf(const HairModel& m, const Vec3& wo, const Vec3& wi);
/// A direction drawn with density hair_pdf from three uniform numbers, with that density and the
/// value hair_f there: the same numbers as calling the two, from one pass over the lobes and one
/// refracted path (none where wo is along the fibre).
using HairSample = DirectionSample;
std::optional<HairSample> hair_sample_f(const HairModel& m, const Vec3& wo, float u0, float u1,
                                        float u2);

/// The same for one call each, the model made from `p` for it.
Rgb hair_f(const HairParams& p, const Vec3& wo, const Vec3& wi);
float hair_pdf(const HairParams& p, const Vec3& wo, const Vec3& wi);
std::optional<Vec3> hair_sample(const HairParams& p, const Vec3& wo, float u0, float u1, float u2);

/// pbrt-v3's absorption of hair from its eumelanin and pheomelanin concentrations, and from the
/// colour it should have after multiple scattering with azimuthal roughness beta_n.
Rgb hair_sigma_a_from_concentration(float eumelanin, float pheomelanin);
Rgb hair_sigma_a_from_reflectance(const Rgb& colour, float beta_n);

}  // namespace cmam::render
