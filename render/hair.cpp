#include "render/hair.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "render/shading.h"

namespace cmam::render {

namespace {

constexpr int kPMax = 3;  // lobes R, TT, TRT, and one for all the longer paths

float sqr(float x) {
    return x * x;
}
float safe_sqrt(float x) {
    return std::sqrt(std::max(0.0f, x));
}
float safe_asin(float x) {
    return std::asin(std::clamp(x, -1.0f, 1.0f));
}

// The modified Bessel function I0 by its series (ten terms), and its logarithm (asymptotically
// for large arguments, where the series overflows).
float bessel_i0(float x) {
    float val = 0, x2i = 1;
    double ifact = 1;
    float i4 = 1;
    for (int i = 0; i < 10; ++i) {
        if (i > 1) ifact *= i;
        val += x2i / (i4 * float(ifact * ifact));
        x2i *= x * x;
        i4 *= 4;
    }
    return val;
}
float log_bessel_i0(float x) {
    if (x > 12) return x + 0.5f * (-std::log(2 * kPi) + std::log(1 / x) + 1 / (8 * x));
    return std::log(bessel_i0(x));
}

// The longitudinal scattering function with variance v (d'Eon et al.), in its log form for small
// variances.
float mp(float cos_i, float cos_o, float sin_i, float sin_o, float v) {
    const float a = cos_i * cos_o / v, b = sin_i * sin_o / v;
    return v <= 0.1f ? std::exp(log_bessel_i0(a) - b - 1 / v + 0.6931f + std::log(1 / (2 * v)))
                     : std::exp(-b) * bessel_i0(a) / (std::sinh(1 / v) * 2 * v);
}

// The attenuations of the lobes: Fresnel reflection at the entry (R), transmission in and out
// through the fibre (TT), one internal reflection more (TRT), and the geometric sum of the rest.
std::array<Rgb, kPMax + 1> ap(float cos_o, float eta, float h, const Rgb& t) {
    std::array<Rgb, kPMax + 1> a;
    const float cos_gamma_o = safe_sqrt(1 - h * h);
    const float f = fresnel_dielectric(cos_o * cos_gamma_o, 1, eta);
    a[0] = Rgb(f);
    a[1] = sqr(1 - f) * t;
    a[2] = a[1] * t * f;
    const Rgb tf = t * f;
    auto rest = [](float x) { return x < 1 ? x / (1 - x) : 0.0f; };  // (x = 1: f = 1, none enter)
    a[3] = a[2] * Rgb(rest(tf.r), rest(tf.g), rest(tf.b));
    return a;
}

float phi_of(int p, float gamma_o, float gamma_t) {
    return 2 * p * gamma_t - 2 * gamma_o + p * kPi;
}
float logistic(float x, float s) {
    x = std::abs(x);
    return std::exp(-x / s) / (s * sqr(1 + std::exp(-x / s)));
}
float logistic_cdf(float x, float s) {
    return 1 / (1 + std::exp(-x / s));
}
float trimmed_logistic(float x, float s, float a, float b) {
    return logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s));
}
// The azimuthal term: the trimmed logistic about the lobe's exit angle.
float np(float phi, int p, float s, float gamma_o, float gamma_t) {
    float dphi = phi - phi_of(p, gamma_o, gamma_t);
    while (dphi > kPi) dphi -= 2 * kPi;
    while (dphi < -kPi) dphi += 2 * kPi;
    return trimmed_logistic(dphi, s, -kPi, kPi);
}
float sample_trimmed_logistic(float u, float s, float a, float b) {
    const float k = logistic_cdf(b, s) - logistic_cdf(a, s);
    const float x = -s * std::log(1 / (u * k + logistic_cdf(a, s)) - 1);
    return std::clamp(x, a, b);
}

}  // namespace

HairModel::HairModel(const HairParams& p) : h(p.h), eta(p.eta), sigma_a(p.sigma_a) {
    const float bm = p.beta_m, bn = p.beta_n;
    v0 = sqr(0.726f * bm + 0.812f * sqr(bm) + 3.7f * std::pow(bm, 20.0f));
    s = std::sqrt(kPi / 8) * (0.265f * bn + 1.194f * sqr(bn) + 5.372f * std::pow(bn, 22.0f));
    sin_alpha = std::sin(p.alpha * kPi / 180);
    cos_alpha = safe_sqrt(1 - sqr(sin_alpha));
    gamma_o = safe_asin(p.h);
}

void HairModel::tilt(int k, float sin_o, float cos_o, float& sin_ok, float& cos_ok) const {
    // sin and cos of 2^i alpha, doubled from alpha's.
    float sin2k[3], cos2k[3];
    sin2k[0] = sin_alpha;
    cos2k[0] = cos_alpha;
    for (int i = 1; i < 3; ++i) {
        sin2k[i] = 2 * cos2k[i - 1] * sin2k[i - 1];
        cos2k[i] = sqr(cos2k[i - 1]) - sqr(sin2k[i - 1]);
    }
    if (k == 0) {
        sin_ok = sin_o * cos2k[1] - cos_o * sin2k[1];
        cos_ok = cos_o * cos2k[1] + sin_o * sin2k[1];
    } else if (k == 1) {
        sin_ok = sin_o * cos2k[0] + cos_o * sin2k[0];
        cos_ok = cos_o * cos2k[0] - sin_o * sin2k[0];
    } else if (k == 2) {
        sin_ok = sin_o * cos2k[2] + cos_o * sin2k[2];
        cos_ok = cos_o * cos2k[2] - sin_o * sin2k[2];
    } else {
        sin_ok = sin_o;
        cos_ok = cos_o;
    }
    cos_ok = std::abs(cos_ok);
}

namespace {

static_assert(HairModel::kLobes == kPMax + 1);

// The refracted path through the fibre into `o`: gamma_t, its angle in the fibre's
// cross-section (sin gamma_t = h / eta', Bravais' index eta' = sqrt(eta^2 - sin^2 theta_o) /
// cos theta_o), and the lobes' attenuations A_p, with T the transmittance along the path, kept
// finite for an index below 1 (no refraction at grazing angles).
void refract(const HairModel& p, HairOutgoing& o) {
    const float sin_o = o.sin_o, cos_o = o.cos_o;
    const float sin_t = sin_o / p.eta, cos_t = safe_sqrt(1 - sqr(sin_t));
    const float etap = safe_sqrt(p.eta * p.eta - sqr(sin_o)) / cos_o;
    const float sin_gt = std::clamp(p.h / std::max(etap, 1e-6f), -1.0f, 1.0f);
    const float cos_gt = safe_sqrt(1 - sqr(sin_gt));
    const float len = 2 * cos_gt / std::max(cos_t, 1e-6f);
    const Rgb t(std::exp(-p.sigma_a.r * len), std::exp(-p.sigma_a.g * len),
                std::exp(-p.sigma_a.b * len));
    o.gamma_t = std::asin(sin_gt);
    o.a = ap(cos_o, p.eta, p.h, t);
}

// The lobes' shares of the sampling, by their attenuations' luminance.
std::array<float, kPMax + 1> shares(const std::array<Rgb, kPMax + 1>& a) {
    std::array<float, kPMax + 1> pdf;
    float sum = 0;
    for (const Rgb& c : a) sum += c.luminance();
    for (int i = 0; i <= kPMax; ++i) pdf[i] = a[i].luminance() / sum;
    return pdf;
}

// The value (without its 1 / |cos theta_i|) and the density at wi: each lobe's M_p N_p weighted
// by its attenuation and by its share. Either output may be null.
void lobes_at(const HairModel& m, const HairOutgoing& o, const Vec3& wi, Rgb* value,
              float* density) {
    const float sin_i = wi.x, cos_i = safe_sqrt(1 - sqr(sin_i));
    const float phi = std::atan2(wi.z, wi.y) - o.phi_o;
    std::array<float, kPMax + 1> share{};
    if (density) share = shares(o.a);
    Rgb sum{};
    float pdf = 0;
    for (int k = 0; k < kPMax; ++k) {
        float sin_ok, cos_ok;
        m.tilt(k, o.sin_o, o.cos_o, sin_ok, cos_ok);
        const float mk = mp(cos_i, cos_ok, sin_i, sin_ok, m.v(k));
        const float nk = np(phi, k, m.s, m.gamma_o, o.gamma_t);
        sum += mk * nk * o.a[k];
        pdf += mk * share[k] * nk;
    }
    const float rest = mp(cos_i, o.cos_o, sin_i, o.sin_o, m.v(kPMax));
    sum += rest / (2 * kPi) * o.a[kPMax];
    pdf += rest * share[kPMax] / (2 * kPi);
    if (value) *value = std::abs(wi.z) > 0 ? sum / std::abs(wi.z) : sum;
    if (density) *density = pdf;
}

}  // namespace

HairOutgoing hair_outgoing(const HairModel& m, const Vec3& wo) {
    HairOutgoing o;
    o.sin_o = wo.x;
    o.cos_o = safe_sqrt(1 - sqr(o.sin_o));
    o.phi_o = std::atan2(wo.z, wo.y);
    refract(m, o);
    return o;
}

Rgb hair_f(const HairModel& m, const HairOutgoing& o, const Vec3& wi) {
    Rgb f;
    lobes_at(m, o, wi, &f, nullptr);
    return f;
}

float hair_pdf(const HairModel& m, const HairOutgoing& o, const Vec3& wi) {
    float pdf;
    lobes_at(m, o, wi, nullptr, &pdf);
    return pdf;
}

std::optional<HairSample> hair_sample_f(const HairModel& m, const HairOutgoing& o, float u0,
                                        float u1, float u2) {
    if (!(o.cos_o > 0)) return std::nullopt;
    // The lobe by its share; what is left of u0 within it draws the azimuth.
    const std::array<float, kPMax + 1> share = shares(o.a);
    int k = 0;
    for (; k < kPMax; ++k) {
        if (u0 < share[k]) break;
        u0 -= share[k];
    }
    const float u_phi = share[k] > 0 ? std::clamp(u0 / share[k], 0.0f, 0x1.fffffep-1f) : 0.5f;
    float sin_ok, cos_ok;
    m.tilt(k, o.sin_o, o.cos_o, sin_ok, cos_ok);
    // The longitudinal angle from M_p's sampling (d'Eon et al.).
    u1 = std::max(u1, 1e-5f);
    const float cos_theta = 1 + m.v(k) * std::log(u1 + (1 - u1) * std::exp(-2 / m.v(k)));
    const float sin_theta = safe_sqrt(1 - sqr(cos_theta));
    const float cos_phi = std::cos(2 * kPi * u2);
    const float sin_i = -cos_theta * sin_ok + sin_theta * cos_phi * cos_ok;
    const float cos_i = safe_sqrt(1 - sqr(sin_i));
    const float dphi =
        k < kPMax ? phi_of(k, m.gamma_o, o.gamma_t) + sample_trimmed_logistic(u_phi, m.s, -kPi, kPi)
                  : 2 * kPi * u_phi;
    const float phi_i = o.phi_o + dphi;
    HairSample out;
    out.wi = Vec3(sin_i, cos_i * std::cos(phi_i), cos_i * std::sin(phi_i));
    if (!finite(out.wi)) return std::nullopt;
    lobes_at(m, o, out.wi, &out.f, &out.pdf);
    return out;
}

Rgb hair_f(const HairParams& p, const Vec3& wo, const Vec3& wi) {
    const HairModel m(p);
    return hair_f(m, hair_outgoing(m, wo), wi);
}

float hair_pdf(const HairParams& p, const Vec3& wo, const Vec3& wi) {
    const HairModel m(p);
    return hair_pdf(m, hair_outgoing(m, wo), wi);
}

std::optional<Vec3> hair_sample(const HairParams& p, const Vec3& wo, float u0, float u1, float u2) {
    const HairModel m(p);
    const std::optional<HairSample> s = hair_sample_f(m, hair_outgoing(m, wo), u0, u1, u2);
    if (!s) return std::nullopt;
    return s->wi;
}

Rgb hair_sigma_a_from_concentration(float eumelanin, float pheomelanin) {
    const Rgb eu(0.419f, 0.697f, 1.37f), pheo(0.187f, 0.4f, 1.05f);
    return eumelanin * eu + pheomelanin * pheo;
}

Rgb hair_sigma_a_from_reflectance(const Rgb& c, float bn) {
    const float k = 5.969f - 0.215f * bn + 2.532f * sqr(bn) - 10.73f * std::pow(bn, 3.0f) +
                    5.574f * std::pow(bn, 4.0f) + 0.245f * std::pow(bn, 5.0f);
    auto one = [k](float x) { return sqr(std::log(x) / k); };
    return {one(c.r), one(c.g), one(c.b)};
}

}  // namespace cmam::render
