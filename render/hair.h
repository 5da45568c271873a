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

/// In the hair's local frame: x along the fibre, z the surface normal (the ray's side of the
/// fibre). f includes pbrt-v3's 1 / |cos theta_i| (wi.z), so f |wi.z| integrates to the albedo.
Rgb hair_f(const HairParams& p, const Vec3& wo, const Vec3& wi);
float hair_pdf(const HairParams& p, const Vec3& wo, const Vec3& wi);
/// A direction drawn with density hair_pdf from three uniform numbers (none where wo is along
/// the fibre).
std::optional<Vec3> hair_sample(const HairParams& p, const Vec3& wo, float u0, float u1, float u2);

/// pbrt-v3's absorption of hair from its eumelanin and pheomelanin concentrations, and from the
/// colour it should have after multiple scattering with azimuthal roughness beta_n.
Rgb hair_sigma_a_from_concentration(float eumelanin, float pheomelanin);
Rgb hair_sigma_a_from_reflectance(const Rgb& colour, float beta_n);

}  // namespace cmam::render
