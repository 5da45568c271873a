// render — pbrt-v3's hair BSDF (its "hair" material): the scattering model of d'Eon et al. 2011
// and Chiang et al. 2016, with lobes R, TT, TRT and the rest, each a longitudinal term M_p, an
// attenuation A_p and an azimuthal term N_p (algorithms.md §21).
#pragma once

#include <array>
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

/// The hair BSDF at a shading point: what its parameters give every evaluation, made once where
/// the point is shaded (two powers, a sine and an arcsine, which the value, the density and the
/// sampling each took anew): h, the index and the absorption as given, R's longitudinal variance
/// v0 (the other lobes' are v0 / 4, 4 v0 and 4 v0), the azimuthal logistic's scale s, sin and
/// cos of alpha (the scales' tilt) and gamma_o = asin h. (It is part of every Bsdf, so it keeps
/// no more than these.)
struct HairModel {
    static constexpr int kLobes = 4;  // R, TT, TRT, and one for all the longer paths
    float h = 0, eta = 1.55f;
    Rgb sigma_a{};
    float v0 = 0, s = 0, gamma_o = 0, sin_alpha = 0, cos_alpha = 1;
    HairModel() = default;
    explicit HairModel(const HairParams& p);
    /// Lobe k's longitudinal variance.
    float v(int k) const { return k == 0 ? v0 : k == 1 ? 0.25f * v0 : 4 * v0; }
    /// sin and cos of theta_o turned by lobe k's tilt (R by -2 alpha, TT by alpha, TRT by
    /// 4 alpha; the rest not at all), the cosine's sign dropped.
    void tilt(int k, float sin_o, float cos_o, float& sin_ok, float& cos_ok) const;
};

/// What an outgoing direction wo gives every evaluation: its angles (sin theta_o, cos theta_o,
/// phi_o) and the refracted path through the fibre (gamma_t, the lobes' attenuations A_p), made
/// once per direction: a shading point's light samples and its BSDF sample share them.
struct HairOutgoing {
    float sin_o = 0, cos_o = 0, phi_o = 0, gamma_t = 0;
    std::array<Rgb, HairModel::kLobes> a{};
};
HairOutgoing hair_outgoing(const HairModel& m, const Vec3& wo);

/// In the hair's local frame: x along the fibre, z the surface normal (the ray's side of the
/// fibre), for wo as `o` (hair_outgoing). f includes pbrt-v3's 1 / |cos theta_i| (wi.z), so
/// f |wi.z| integrates to the albedo.
Rgb hair_f(const HairModel& m, const HairOutgoing& o, const Vec3& wi);
float hair_pdf(const HairModel& m, const HairOutgoing& o, const Vec3& wi);
/// A direction drawn with density hair_pdf from three uniform numbers, with that density and the
/// value hair_f there: the same numbers as calling the two, from one pass over the lobes (none
/// where wo is along the fibre).
using HairSample = DirectionSample;
std::optional<HairSample> hair_sample_f(const HairModel& m, const HairOutgoing& o, float u0,
                                        float u1, float u2);

/// The same for one call each, the model made from `p` for it.
Rgb hair_f(const HairParams& p, const Vec3& wo, const Vec3& wi);
float hair_pdf(const HairParams& p, const Vec3& wo, const Vec3& wi);
std::optional<Vec3> hair_sample(const HairParams& p, const Vec3& wo, float u0, float u1, float u2);

/// pbrt-v3's absorption of hair from its eumelanin and pheomelanin concentrations, and from the
/// colour it should have after multiple scattering with azimuthal roughness beta_n.
Rgb hair_sigma_a_from_concentration(float eumelanin, float pheomelanin);
Rgb hair_sigma_a_from_reflectance(const Rgb& colour, float beta_n);

}  // namespace cmam::render
