// render — pbrt-v3's subsurface scattering (its "subsurface" and "kdsubsurface" materials,
// algorithms.md §26): the photon beam diffusion profile tabulated over albedo and optical radius,
// the tabulated BSSRDF at a shading point (its radial profile, sampled and with its density),
// the coefficients of a diffuse reflectance, and measured coefficients by name.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/math.h"

namespace cmam::render {

/// The radial profile of a semi-infinite medium of index `eta` and phase asymmetry `g` lit by a
/// beam (photon beam diffusion: its multiple and single scattering), tabulated at unit extinction:
/// 2 pi r R(r) at albedos rho[i] and optical radii radius[j] (pbrt-v3's BSSRDFTable, 100 x 64).
struct BssrdfTable {
    std::vector<float> rho, radius;
    std::vector<float> profile;  // [i * radius.size() + j]
    std::vector<float> cdf;      // each row's running integral over the radii
    std::vector<float> rho_eff;  // each row's integral: the effective albedo
    float g = 0, eta = 1.33f;
    // The exit lobe's normalisation c = 1 - 2 F1, F1 the first Fresnel moment of the boundary
    // seen from outside (fresnel_moment(1, 1 / eta)): its lobe (1 - F(cos)) / (c pi) reflects
    // all that reaches it.
    float exit_norm = 1;
    int radii() const { return static_cast<int>(radius.size()); }

    /// The table for g and eta, computed on `threads` workers (0: all cores).
    static std::shared_ptr<const BssrdfTable> beam_diffusion(float g, float eta, int threads = 0);
};

/// The i-th Fresnel moment of the boundary seen from inside a medium of index eta (its outside of
/// index 1): the integral over mu in [0, 1] of the dielectric reflectance at cos theta = mu times
/// mu^i, by quadrature (pbrt-v3 fits polynomials to it).
double fresnel_moment(int i, double eta);

/// The photon beam diffusion radiant exitance at distance r from a beam entering a medium of
/// scattering and absorption coefficients sigma_s, sigma_a (phase asymmetry g, index eta): its
/// multiple scattering (dipoles along the beam, 100 samples) and its single scattering (100
/// samples along the refracted beam).
float beam_diffusion_ms(float sigma_s, float sigma_a, float g, float eta, float r);
float beam_diffusion_ss(float sigma_s, float sigma_a, float g, float eta, float r);

/// pbrt-v3's TabulatedBSSRDF at a shading point: the table scaled to the point's extinction
/// sigma_t = sigma_a + sigma_s and albedo rho = sigma_s / sigma_t, per channel.
struct Bssrdf {
    Bssrdf(const BssrdfTable& table, const Rgb& sigma_a, const Rgb& sigma_s);
    const BssrdfTable* table;
    float sigma_t[3], rho[3];

    /// The radial profile S_r(r) per channel (0 below; beyond the table 0).
    Rgb sr(float r) const;
    /// A radius drawn from channel ch's profile (its share of the profile up to u), or -1 where
    /// the channel has no extinction.
    float sample_sr(int ch, float u) const;
    /// The density sample_sr draws r with, per unit area of the plane (S_r over its integral).
    float pdf_sr(int ch, float r) const;
    /// The density of a probe point `pi` (normal n_pi) drawn about `po` whose shading frame is
    /// `f`: the projections on the frame's three axes (probabilities 1/4, 1/4, 1/2 for s, t, n),
    /// each channel's radius (1/3 each), times |n_pi| along the axis.
    float pdf_sp(const Frame& f, const Vec3& po, const Vec3& pi, const Vec3& n_pi) const;
};

/// The absorption and scattering coefficients whose profile has the effective albedo kd and mean
/// free path mfp (pbrt-v3's SubsurfaceFromDiffuse), per channel.
void subsurface_from_diffuse(const BssrdfTable& table, const Rgb& kd, const Rgb& mfp, Rgb& sigma_a,
                             Rgb& sigma_s);

/// Measured absorption and reduced scattering coefficients in mm^-1 by name (Jensen et al. 2001,
/// Narasimhan et al. 2006; pbrt-v3's names); false for an unknown name.
bool measured_scattering(const std::string& name, Rgb& sigma_a, Rgb& sigma_prime_s);

}  // namespace cmam::render
