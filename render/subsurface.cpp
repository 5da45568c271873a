#include "render/subsurface.h"

#include <cmath>

#include "render/medium.h"
#include "render/parallel.h"
#include "render/spline.h"

namespace cmam::render {

namespace {

// The unpolarised reflectance of a dielectric boundary for light arriving at cos theta = c from
// the side of index eta_i (the other's eta_t), in double: fresnel_dielectric's, whose float
// rounding (1e-8 where there is no boundary at all) the Fresnel moments' quadrature would sum.
double dielectric_reflectance(double c, double eta_i, double eta_t) {
    const double sin_t = eta_i / eta_t * std::sqrt(std::max(0.0, 1 - c * c));
    if (sin_t >= 1) return 1;
    const double cos_t = std::sqrt(std::max(0.0, 1 - sin_t * sin_t));
    const double par = (eta_t * c - eta_i * cos_t) / (eta_t * c + eta_i * cos_t);
    const double perp = (eta_i * c - eta_t * cos_t) / (eta_i * c + eta_t * cos_t);
    return 0.5 * (par * par + perp * perp);
}

// pbrt-v3's measured coefficients (mm^-1): absorption, then reduced scattering.
struct Measured {
    const char* name;
    float sigma_a[3], sigma_prime_s[3];
};
constexpr Measured kMeasured[] = {
    // Jensen, Marschner, Levoy and Hanrahan, "A Practical Model for Subsurface Light
    // Transport", SIGGRAPH 2001; Narasimhan, Gupta, Donner, Ramamoorthi, Nayar and Jensen,
    // "Acquiring Scattering Properties of Participating Media by Dilution", SIGGRAPH 2006.
    {"Apple", {0.0030f, 0.0034f, 0.046f}, {2.29f, 2.39f, 1.97f}},
    {"Chicken1", {0.015f, 0.077f, 0.19f}, {0.15f, 0.21f, 0.38f}},
    {"Chicken2", {0.018f, 0.088f, 0.20f}, {0.19f, 0.25f, 0.32f}},
    {"Cream", {0.0002f, 0.0028f, 0.0163f}, {7.38f, 5.47f, 3.15f}},
    {"Ketchup", {0.061f, 0.97f, 1.45f}, {0.18f, 0.07f, 0.03f}},
    {"Marble", {0.0021f, 0.0041f, 0.0071f}, {2.19f, 2.62f, 3.00f}},
    {"Potato", {0.0024f, 0.0090f, 0.12f}, {0.68f, 0.70f, 0.55f}},
    {"Skimmilk", {0.0014f, 0.0025f, 0.0142f}, {0.70f, 1.22f, 1.90f}},
    {"Skin1", {0.032f, 0.17f, 0.48f}, {0.74f, 0.88f, 1.01f}},
    {"Skin2", {0.013f, 0.070f, 0.145f}, {1.09f, 1.59f, 1.79f}},
    {"Spectralon", {0.00f, 0.00f, 0.00f}, {11.6f, 20.4f, 14.9f}},
    {"Wholemilk", {0.0011f, 0.0024f, 0.014f}, {2.55f, 3.21f, 3.77f}},
    {"Lowfat Milk", {0.002875f, 0.00575f, 0.0115f}, {0.89187f, 1.5136f, 2.532f}},
    {"Reduced Milk", {0.0025556f, 0.0051111f, 0.012778f}, {2.4858f, 3.1669f, 4.5214f}},
    {"Regular Milk", {0.0015333f, 0.0046f, 0.019933f}, {4.5513f, 5.8294f, 7.136f}},
    {"Espresso", {4.7984f, 6.5751f, 8.8493f}, {0.72378f, 0.84557f, 1.0247f}},
    {"Mint Mocha Coffee", {3.772f, 5.8228f, 7.82f}, {0.31602f, 0.38538f, 0.48131f}},
    {"Lowfat Soy Milk", {0.0014375f, 0.0071875f, 0.035937f}, {0.30576f, 0.34233f, 0.61664f}},
    {"Regular Soy Milk", {0.0019167f, 0.0095833f, 0.065167f}, {0.59223f, 0.73866f, 1.4693f}},
    {"Lowfat Chocolate Milk", {0.0115f, 0.0368f, 0.1564f}, {0.64925f, 0.83916f, 1.1057f}},
    {"Regular Chocolate Milk", {0.010063f, 0.043125f, 0.14375f}, {1.4585f, 2.1289f, 2.9527f}},
    {"Coke", {0.10014f, 0.16503f, 0.2468f}, {8.9053e-05f, 8.372e-05f, 0.0f}},
    {"Pepsi", {0.091641f, 0.14158f, 0.20729f}, {6.1697e-05f, 4.2564e-05f, 0.0f}},
    {"Sprite", {0.001886f, 0.0018308f, 0.0020025f}, {6.0306e-06f, 6.4139e-06f, 6.5504e-06f}},
    {"Gatorade", {0.024794f, 0.019289f, 0.008878f}, {0.0024574f, 0.003007f, 0.0037325f}},
    {"Chardonnay", {0.010782f, 0.011855f, 0.023997f}, {1.7982e-05f, 1.3758e-05f, 1.2023e-05f}},
    {"White Zinfandel", {0.012072f, 0.016184f, 0.019843f}, {1.7501e-05f, 1.9069e-05f, 1.288e-05f}},
    {"Merlot", {0.11632f, 0.25191f, 0.29434f}, {2.1129e-05f, 0.0f, 0.0f}},
    {"Budweiser Beer", {0.011492f, 0.024911f, 0.057786f}, {2.4356e-05f, 2.4079e-05f, 1.0564e-05f}},
    {"Coors Light Beer", {0.006164f, 0.013984f, 0.034983f}, {5.0922e-05f, 4.301e-05f, 0.0f}},
    {"Clorox", {0.0033542f, 0.014892f, 0.026297f}, {0.0024035f, 0.0031373f, 0.003991f}},
    {"Apple Juice", {0.012957f, 0.023741f, 0.052184f}, {0.00013612f, 0.00015836f, 0.000227f}},
    {"Cranberry Juice", {0.039437f, 0.094223f, 0.12426f}, {0.00010402f, 0.00011646f, 7.8139e-05f}},
    {"Grape Juice", {0.10404f, 0.23958f, 0.29325f}, {5.382e-05f, 0.0f, 0.0f}},
    {"Ruby Grapefruit Juice", {0.085867f, 0.18314f, 0.25262f}, {0.011002f, 0.010927f, 0.011036f}},
    {"White Grapefruit Juice", {0.0138f, 0.018831f, 0.056781f}, {0.22826f, 0.23998f, 0.32748f}},
    {"Shampoo", {0.014107f, 0.045693f, 0.061717f}, {0.0007176f, 0.0008303f, 0.0009016f}},
    {"Strawberry Shampoo", {0.01449f, 0.05796f, 0.075823f}, {0.00015671f, 0.00015947f, 1.518e-05f}},
    {"Head & Shoulders Shampoo",
     {0.084621f, 0.15688f, 0.20365f},
     {0.023805f, 0.028804f, 0.034306f}},
    {"Lemon Tea Powder", {2.4288f, 4.5757f, 7.2127f}, {0.040224f, 0.045264f, 0.051081f}},
    {"Orange Powder", {0.001449f, 0.003441f, 0.007863f}, {0.00015617f, 0.00017482f, 0.0001762f}},
    {"Pink Lemonade Powder",
     {0.001165f, 0.002366f, 0.003195f},
     {0.00012103f, 0.00013073f, 0.00012528f}},
    {"Cappuccino Powder", {35.844f, 49.547f, 61.084f}, {1.8436f, 2.5851f, 2.1662f}},
    {"Salt Powder", {0.28415f, 0.3257f, 0.34148f}, {0.027333f, 0.032451f, 0.031979f}},
    {"Sugar Powder", {0.012638f, 0.031051f, 0.050124f}, {0.00022272f, 0.00025513f, 0.000271f}},
    {"Suisse Mocha Powder", {17.502f, 27.004f, 35.433f}, {2.7979f, 3.5452f, 4.3365f}},
    {"Pacific Ocean Surface Water",
     {0.031845f, 0.031324f, 0.030147f},
     {0.0001764f, 0.00032095f, 0.00019617f}},
};

}  // namespace

double fresnel_moment(int i, double eta) {
    // Below the critical cosine (total internal reflection) the reflectance is 1; above it a
    // midpoint rule over many intervals.
    const double mu_c = eta > 1 ? std::sqrt(1 - 1 / (eta * eta)) : 0.0;
    double sum = std::pow(mu_c, i + 1) / (i + 1);
    constexpr int kSteps = 1 << 14;
    const double h = (1 - mu_c) / kSteps;
    for (int k = 0; k < kSteps; ++k) {
        const double mu = mu_c + (k + 0.5) * h;
        sum += dielectric_reflectance(mu, eta, 1) * std::pow(mu, i) * h;
    }
    return sum;
}

namespace {
float beam_diffusion_ms(float sigma_s, float sigma_a, float g, double fm1, double fm2, float r);
}

float beam_diffusion_ms(float sigma_s, float sigma_a, float g, float eta, float r) {
    return beam_diffusion_ms(sigma_s, sigma_a, g, fresnel_moment(1, eta), fresnel_moment(2, eta),
                             r);
}

namespace {
// The same with the boundary's Fresnel moments given.
float beam_diffusion_ms(float sigma_s, float sigma_a, float g, double fm1, double fm2, float r) {
    constexpr int kSamples = 100;
    // The reduced coefficients, the diffusion coefficient D_g (Grosjean's) and the effective
    // transport coefficient.
    const double sps = double(sigma_s) * (1 - g), spt = double(sigma_a) + sps, rhop = sps / spt;
    const double d_g = (2 * double(sigma_a) + sps) / (3 * spt * spt);
    const double sigma_tr = std::sqrt(std::max(0.0, double(sigma_a) / d_g));
    // The boundary condition: the extrapolated boundary ze, and the weights of fluence and flux.
    const double ze = -2 * d_g * (1 + 3 * fm2) / (1 - 2 * fm1);
    const double c_phi = 0.25 * (1 - 2 * fm1), c_e = 0.5 * (1 - 3 * fm2);
    double ed = 0;
    for (int i = 0; i < kSamples; ++i) {
        // A real source at depth zr (exponentially distributed along the beam), its virtual
        // image at zv mirrored about the extrapolated boundary.
        const double zr = -std::log(1 - (i + 0.5) / kSamples) / spt, zv = -zr + 2 * ze;
        const double dr = std::sqrt(double(r) * r + zr * zr),
                     dv = std::sqrt(double(r) * r + zv * zv);
        const double phi = (std::exp(-sigma_tr * dr) / dr - std::exp(-sigma_tr * dv) / dv) /
                           (4 * std::numbers::pi * d_g);
        const double en = (zr * (1 + sigma_tr * dr) * std::exp(-sigma_tr * dr) / (dr * dr * dr) -
                           zv * (1 + sigma_tr * dv) * std::exp(-sigma_tr * dv) / (dv * dv * dv)) /
                          (4 * std::numbers::pi);
        const double e = phi * c_phi + en * c_e;
        // The share of the source that is multiply scattered.
        const double kappa = 1 - std::exp(-2 * spt * (dr + zr));
        ed += kappa * rhop * rhop * e;
    }
    return static_cast<float>(ed / kSamples);
}
}  // namespace

float beam_diffusion_ss(float sigma_s, float sigma_a, float g, float eta, float r) {
    constexpr int kSamples = 100;
    const double sigma_t = double(sigma_a) + sigma_s, rho = sigma_s / sigma_t;
    // The single scattering reaches the surface at r only from beyond the depth where the exit
    // direction is past the critical angle.
    const double t_crit = r * std::sqrt(std::max(0.0, double(eta) * eta - 1));
    double ess = 0;
    for (int i = 0; i < kSamples; ++i) {
        const double ti = t_crit - std::log(1 - (i + 0.5) / kSamples) / sigma_t;
        const double d = std::sqrt(double(r) * r + ti * ti), cos_o = ti / d;
        ess += rho * std::exp(-sigma_t * (d + t_crit)) / (d * d) *
               hg_phase(static_cast<float>(cos_o), g) *
               (1 - dielectric_reflectance(cos_o, eta, 1)) * std::abs(cos_o);
    }
    return static_cast<float>(ess / kSamples);
}

std::shared_ptr<const BssrdfTable> BssrdfTable::beam_diffusion(float g, float eta, int threads) {
    auto t = std::make_shared<BssrdfTable>();
    constexpr int kRho = 100, kRadius = 64;
    t->g = g;
    t->eta = eta;
    t->rho.resize(kRho);
    t->radius.resize(kRadius);
    // Radii from 0, then 2.5e-3 growing by 1.2 (to about 1.9e2 mean free paths); albedos
    // crowded towards 1, where the profile changes fastest.
    t->radius[1] = 2.5e-3f;
    for (int j = 2; j < kRadius; ++j) t->radius[j] = t->radius[j - 1] * 1.2f;
    for (int i = 0; i < kRho; ++i)
        t->rho[i] =
            static_cast<float>((1 - std::exp(-8.0 * i / (kRho - 1))) / (1 - std::exp(-8.0)));
    t->profile.resize(std::size_t(kRho) * kRadius);
    t->cdf.resize(t->profile.size());
    t->rho_eff.resize(kRho);
    t->exit_norm = static_cast<float>(1 - 2 * fresnel_moment(1, 1 / double(eta)));
    const double fm1 = fresnel_moment(1, eta), fm2 = fresnel_moment(2, eta);
    parallel_range_on(kRho, threads, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
            float* row = &t->profile[std::size_t(i) * kRadius];
            for (int j = 0; j < kRadius; ++j) {
                const float rho = t->rho[i], r = t->radius[j];
                row[j] = 2 * kPi * r *
                         (beam_diffusion_ss(rho, 1 - rho, g, eta, r) +
                          beam_diffusion_ms(rho, 1 - rho, g, fm1, fm2, r));
            }
            t->rho_eff[i] =
                integrate_spline(kRadius, t->radius.data(), row, &t->cdf[std::size_t(i) * kRadius]);
        }
    });
    return t;
}

Bssrdf::Bssrdf(const BssrdfTable& t, const Rgb& sigma_a, const Rgb& sigma_s) : table(&t) {
    const float a[3] = {sigma_a.r, sigma_a.g, sigma_a.b}, s[3] = {sigma_s.r, sigma_s.g, sigma_s.b};
    for (int c = 0; c < 3; ++c) {
        sigma_t[c] = a[c] + s[c];
        rho[c] = sigma_t[c] != 0 ? s[c] / sigma_t[c] : 0.0f;
    }
}

namespace {
// The profile interpolated at albedo rho and optical radius r (2 pi r R(r)), and the effective
// albedo there (rho_eff, when asked); false outside the table.
bool profile_at(const BssrdfTable& t, float rho, float r, float& value, float* rho_eff) {
    int ro, rr;
    float wr[4], wd[4];
    if (!spline_weights(static_cast<int>(t.rho.size()), t.rho.data(), rho, &ro, wr) ||
        !spline_weights(t.radii(), t.radius.data(), r, &rr, wd))
        return false;
    value = 0;
    if (rho_eff) *rho_eff = 0;
    for (int i = 0; i < 4; ++i) {
        if (wr[i] == 0) continue;
        if (rho_eff) *rho_eff += t.rho_eff[std::size_t(ro + i)] * wr[i];
        for (int j = 0; j < 4; ++j)
            if (wd[j] != 0)
                value += wr[i] * wd[j] * t.profile[std::size_t(ro + i) * t.radii() + (rr + j)];
    }
    return true;
}
}  // namespace

Rgb Bssrdf::sr(float r) const {
    float out[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
        const float r_optical = r * sigma_t[c];
        float v;
        if (!profile_at(*table, rho[c], r_optical, v, nullptr)) continue;
        // The table holds 2 pi r R(r) at unit extinction: R itself, scaled to sigma_t.
        if (r_optical != 0) v /= 2 * kPi * r_optical;
        out[c] = std::max(0.0f, v * sigma_t[c] * sigma_t[c]);
    }
    return {out[0], out[1], out[2]};
}

float Bssrdf::sample_sr(int ch, float u) const {
    if (!(sigma_t[ch] > 0)) return -1;
    int offset;
    float w[4], pdf;
    if (!spline_weights(static_cast<int>(table->rho.size()), table->rho.data(), rho[ch], &offset,
                        w))
        return -1;
    return sample_spline(table->radii(), table->radius.data(), table->profile.data(),
                         table->cdf.data(), offset, w, u, nullptr, &pdf) /
           sigma_t[ch];
}

float Bssrdf::pdf_sr(int ch, float r) const {
    const float r_optical = r * sigma_t[ch];
    float v, rho_eff;
    if (!profile_at(*table, rho[ch], r_optical, v, &rho_eff) || !(rho_eff > 0)) return 0;
    if (r_optical != 0) v /= 2 * kPi * r_optical;
    return std::max(0.0f, v * sigma_t[ch] * sigma_t[ch] / rho_eff);
}

float Bssrdf::pdf_sp(const Frame& f, const Vec3& po, const Vec3& pi, const Vec3& n_pi) const {
    const Vec3 d = po - pi;
    const Vec3 dl(dot(f.s, d), dot(f.t, d), dot(f.n, d));
    const float nl[3] = {dot(f.s, n_pi), dot(f.t, n_pi), dot(f.n, n_pi)};
    const float r_proj[3] = {std::sqrt(dl.y * dl.y + dl.z * dl.z),
                             std::sqrt(dl.z * dl.z + dl.x * dl.x),
                             std::sqrt(dl.x * dl.x + dl.y * dl.y)};
    constexpr float kAxis[3] = {0.25f, 0.25f, 0.5f};
    float pdf = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (int ch = 0; ch < 3; ++ch)
            pdf += pdf_sr(ch, r_proj[axis]) * std::abs(nl[axis]) * kAxis[axis] / 3;
    return pdf;
}

void subsurface_from_diffuse(const BssrdfTable& t, const Rgb& kd, const Rgb& mfp, Rgb& sigma_a,
                             Rgb& sigma_s) {
    const float k[3] = {kd.r, kd.g, kd.b}, m[3] = {mfp.r, mfp.g, mfp.b};
    float a[3], s[3];
    for (int c = 0; c < 3; ++c) {
        const float rho =
            invert_spline(static_cast<int>(t.rho.size()), t.rho.data(), t.rho_eff.data(), k[c]);
        s[c] = rho / m[c];
        a[c] = (1 - rho) / m[c];
    }
    sigma_a = Rgb(a[0], a[1], a[2]);
    sigma_s = Rgb(s[0], s[1], s[2]);
}

bool measured_scattering(const std::string& name, Rgb& sigma_a, Rgb& sigma_prime_s) {
    for (const Measured& m : kMeasured)
        if (name == m.name) {
            sigma_a = Rgb(m.sigma_a[0], m.sigma_a[1], m.sigma_a[2]);
            sigma_prime_s = Rgb(m.sigma_prime_s[0], m.sigma_prime_s[1], m.sigma_prime_s[2]);
            return true;
        }
    return false;
}

}  // namespace cmam::render
