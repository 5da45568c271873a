// render — pbrt-v3's Fourier BSDF (algorithms.md §18, "Fourier BSDFs").
#include "render/fourier.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "render/error.h"
#include "render/spline.h"

namespace cmam::render {

namespace {

// The file's little-endian 32-bit words, read from `p` on.
uint32_t word_at(const unsigned char* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
int32_t int_at(const unsigned char* p) {
    return static_cast<int32_t>(word_at(p));
}
float float_at(const unsigned char* p) {
    const uint32_t w = word_at(p);
    float f;
    std::memcpy(&f, &w, sizeof f);
    return f;
}

// The cosine of the azimuth between a and b (1 where either has none).
float cos_dphi(const Vec3& a, const Vec3& b) {
    const float aa = a.x * a.x + a.y * a.y, bb = b.x * b.x + b.y * b.y;
    if (aa == 0 || bb == 0) return 1;
    return std::clamp((a.x * b.x + a.y * b.y) / std::sqrt(aa * bb), -1.0f, 1.0f);
}

// An elevation's place in the table: the spline's first node and its four weights.
struct Spline {
    int offset;
    float w[4];
};
bool spline_at(const FourierTable& t, float mu, Spline& s) {
    return spline_weights(t.n_mu, t.mu.data(), mu, &s.offset, s.w);
}

// The series for elevations (mu_i, mu_o), placed by si and so: the 4 x 4 nodes' coefficients
// weighted by the two splines' weights, channel c at ak[c * m_max]. Returns the longest series'
// length.
int interpolated_series(const FourierTable& t, const Spline& si, const Spline& so, int channels,
                        std::vector<double>& ak) {
    const int oi = si.offset, oo = so.offset;
    const float *wi = si.w, *wo = so.w;
    ak.assign(static_cast<std::size_t>(t.m_max) * channels, 0.0);
    int longest = 0;
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
            if (wi[a] == 0 || wo[b] == 0) continue;  // (the nodes beyond the table's ends)
            const float w = wi[a] * wo[b];
            int m;
            const float* c = t.series(oi + a, oo + b, &m);
            longest = std::max(longest, m);
            for (int ch = 0; ch < channels; ++ch)
                for (int k = 0; k < m; ++k)
                    ak[static_cast<std::size_t>(ch) * t.m_max + k] += double(w) * c[ch * m + k];
        }
    return longest;
}

// The scratch series of a thread's lookups (m_max x channels, reused).
std::vector<double>& scratch() {
    thread_local std::vector<double> ak;
    return ak;
}

// sum_k ak[start + k] cos(k phi) for k < m, the cosines by Chebyshev's recurrence.
double series_at(const std::vector<double>& ak, std::size_t start, int m, double cos_phi) {
    double value = 0, prev = cos_phi, cur = 1;
    for (int k = 0; k < m; ++k) {
        value += ak[start + k] * cur;
        const double next = 2 * cos_phi * cur - prev;
        prev = cur;
        cur = next;
    }
    return value;
}

// The value from the luminance Y and (three channels) red and blue, scaled by 1 / |mu_i| and,
// across the material, by the squared relative index (radiance).
Rgb fourier_value(const FourierTable& t, const std::vector<double>& ak, int m, double cos_phi,
                  double y, float mu_i, float mu_o) {
    float scale = mu_i != 0 ? 1 / std::abs(mu_i) : 0.0f;
    if (mu_i * mu_o > 0) {
        const float eta = mu_i > 0 ? 1 / t.eta : t.eta;
        scale *= eta * eta;
    }
    if (t.channels == 1) return Rgb(std::max(0.0f, float(y) * scale));
    const double r = series_at(ak, static_cast<std::size_t>(t.m_max), m, cos_phi),
                 b = series_at(ak, 2 * static_cast<std::size_t>(t.m_max), m, cos_phi);
    const double g = 1.39829 * y - 0.100913 * b - 0.297375 * r;  // Y, R and B to G
    return {std::max(0.0f, float(r) * scale), std::max(0.0f, float(g) * scale),
            std::max(0.0f, float(b) * scale)};
}

}  // namespace

FourierTable read_fourier_table(const std::string& path) {
    const std::string subject = "Fourier BSDF file \"" + path + "\": ";
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) throw RenderError(subject + "cannot read it (" + ec.message() + ")");
    if (size > kMaxFourierFileBytes) throw RenderError(subject + "larger than 256 MB");
    std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
        throw RenderError(subject + "cannot read it");
    constexpr std::size_t kHeader = 64;
    static const char kId[8] = {'S', 'C', 'A', 'T', 'F', 'U', 'N', '\x01'};
    if (bytes.size() < kHeader || std::memcmp(bytes.data(), kId, 8) != 0)
        throw RenderError(subject + "not a version 1 \"SCATFUN\" file");
    const unsigned char* h = bytes.data() + 8;
    const int32_t flags = int_at(h), n_mu = int_at(h + 4), n_coeffs = int_at(h + 8),
                  m_max = int_at(h + 12), channels = int_at(h + 16), bases = int_at(h + 20);
    if (flags != 1)
        throw RenderError(subject + "flags " + std::to_string(flags) +
                          ": only a plain BSDF (1) is read, as in pbrt-v3");
    if (channels != 1 && channels != 3)
        throw RenderError(subject + std::to_string(channels) + " channels (1 or 3 are read)");
    if (bases != 1)
        throw RenderError(subject + "a textured table (" + std::to_string(bases) +
                          " bases; pbrt-v3 reads 1)");
    if (n_mu < 2 || n_mu > 4096 || n_coeffs < 0 || m_max < 1 || m_max > (1 << 16))
        throw RenderError(subject + "a table size out of range");
    FourierTable t;
    t.n_mu = n_mu;
    t.m_max = m_max;
    t.channels = channels;
    t.eta = float_at(h + 36);
    if (!(std::isfinite(t.eta) && t.eta > 0))
        throw RenderError(subject + "its relative index is not a positive number");
    const std::size_t pairs = std::size_t(n_mu) * std::size_t(n_mu);
    const std::size_t need =
        kHeader + 4 * (std::size_t(n_mu) + pairs + 2 * pairs + std::size_t(n_coeffs));
    if (bytes.size() < need)
        throw RenderError(subject + "shorter than its header says (" + std::to_string(need) +
                          " bytes)");
    const unsigned char* p = bytes.data() + kHeader;
    auto floats = [&p](std::vector<float>& v, std::size_t n) {
        v.resize(n);
        for (float& x : v) {
            x = float_at(p);
            p += 4;
        }
    };
    floats(t.mu, std::size_t(n_mu));
    for (int k = 0; k + 1 < n_mu; ++k)
        if (!(std::isfinite(t.mu[k]) && t.mu[k] <= t.mu[k + 1]))  // (-0 and 0 both are nodes)
            throw RenderError(subject + "its elevation nodes decrease");
    floats(t.cdf, pairs);
    t.offset.resize(pairs);
    t.m.resize(pairs);
    for (std::size_t k = 0; k < pairs; ++k, p += 8) {
        t.offset[k] = int_at(p);
        t.m[k] = int_at(p + 4);
        const int64_t end = int64_t(t.offset[k]) + int64_t(t.m[k]) * channels;
        if (t.offset[k] < 0 || t.m[k] < 0 || t.m[k] > m_max || end > n_coeffs)
            throw RenderError(subject + "a series outside its coefficients");
    }
    floats(t.a, std::size_t(n_coeffs));
    t.a0.resize(pairs);
    for (std::size_t k = 0; k < pairs; ++k) t.a0[k] = t.m[k] > 0 ? t.a[t.offset[k]] : 0.0f;
    return t;
}

Rgb fourier_f(const FourierTable& t, const Vec3& wo, const Vec3& wi) {
    const float mu_i = -wi.z, mu_o = wo.z;
    const double cos_phi = cos_dphi(-wi, wo);
    Spline si, so;
    if (!spline_at(t, mu_i, si) || !spline_at(t, mu_o, so)) return {};
    std::vector<double>& ak = scratch();
    const int m = interpolated_series(t, si, so, t.channels, ak);
    const double y = std::max(0.0, series_at(ak, 0, m, cos_phi));
    return fourier_value(t, ak, m, cos_phi, y, mu_i, mu_o);
}

float fourier_pdf(const FourierTable& t, const Vec3& wo, const Vec3& wi) {
    const float mu_i = -wi.z, mu_o = wo.z;
    Spline si, so;
    if (!spline_at(t, mu_i, si) || !spline_at(t, mu_o, so)) return 0;
    std::vector<double>& ak = scratch();
    const int m = interpolated_series(t, si, so, 1, ak);
    // The luminance's integral over the sphere for wo: 2 pi times the spline of a0's integrals.
    double rho = 0;
    for (int o = 0; o < 4; ++o)
        if (so.w[o] != 0)
            rho += so.w[o] * t.cdf[std::size_t(so.offset + o) * t.n_mu + t.n_mu - 1] * (2 * kPi);
    const double y = series_at(ak, 0, m, cos_dphi(-wi, wo));
    return rho > 0 && y > 0 ? float(y / rho) : 0.0f;
}

namespace {

// mu_i drawn from the spline of a0 over mu_i (its integral tabulated in cdf), interpolated in
// mu_o: the spline segment by the interpolated integrals, then t within it by inverting the
// segment's cubic integral (Newton's method, bisection where a step leaves the bracket). `pdf`:
// the density in mu_i. `so` places mu_o.
float sample_elevation(const FourierTable& t, const Spline& so, float u, float* pdf) {
    return sample_spline(t.n_mu, t.mu.data(), t.a0.data(), t.cdf.data(), so.offset, so.w, u,
                         nullptr, pdf);
}

// phi drawn from the series a (its constant term a[0] > 0) on [0, 2 pi): a half chosen by u,
// then phi in [0, pi] by inverting F(phi) = a0 phi + sum_k a_k sin(k phi) / k (Newton's method,
// bisection where a step leaves the bracket), mirrored for the other half. Returns the series'
// value there; `pdf` its density in phi.
double sample_azimuth(const std::vector<double>& a, int m, float u, float* pdf, float* phi_out) {
    const bool flip = u >= 0.5f;
    u = flip ? 1 - 2 * (u - 0.5f) : 2 * u;
    double lo = 0, hi = std::numbers::pi, phi = 0.5 * std::numbers::pi, F = 0, f = 0;
    for (int iter = 0; iter < 100; ++iter) {
        const double c = std::cos(phi), sn = std::sqrt(std::max(0.0, 1 - c * c));
        double cos_prev = c, cos_cur = 1, sin_prev = -sn, sin_cur = 0;
        F = a[0] * phi;
        f = a[0];
        for (int k = 1; k < m; ++k) {
            const double sin_next = 2 * c * sin_cur - sin_prev,
                         cos_next = 2 * c * cos_cur - cos_prev;
            sin_prev = sin_cur;
            sin_cur = sin_next;
            cos_prev = cos_cur;
            cos_cur = cos_next;
            F += a[k] / k * sin_next;
            f += a[k] * cos_next;
        }
        F -= u * a[0] * std::numbers::pi;
        if (F > 0)
            hi = phi;
        else
            lo = phi;
        if (std::abs(F) < 1e-6 || hi - lo < 1e-6) break;
        phi -= F / f;
        if (!(phi > lo && phi < hi)) phi = 0.5 * (lo + hi);
    }
    if (flip) phi = 2 * std::numbers::pi - phi;
    *pdf = float(f / (2 * std::numbers::pi * a[0]));
    *phi_out = float(phi);
    return f;
}

}  // namespace

FourierSample fourier_sample(const FourierTable& t, const Vec3& wo, float u_phi, float u_mu) {
    FourierSample out;
    const float mu_o = wo.z;
    Spline so, si;
    if (!spline_at(t, mu_o, so)) return out;
    float pdf_mu;
    const float mu_i = sample_elevation(t, so, u_mu, &pdf_mu);
    if (!(pdf_mu > 0) || !spline_at(t, mu_i, si)) return out;
    std::vector<double>& ak = scratch();
    const int m = interpolated_series(t, si, so, t.channels, ak);
    if (m <= 0 || !(ak[0] > 0)) return out;
    float pdf_phi, phi;
    const double y = sample_azimuth(ak, m, u_phi, &pdf_phi, &phi);
    // -wi: wo's azimuth turned by phi, at elevation mu_i.
    const float sin2_o = std::max(0.0f, 1 - wo.z * wo.z);
    float norm = std::sqrt(std::max(0.0f, 1 - mu_i * mu_i) / sin2_o);
    if (!std::isfinite(norm)) norm = 0;
    const float s = std::sin(phi), c = std::cos(phi);
    const Vec3 wi = -Vec3(norm * (c * wo.x - s * wo.y), norm * (s * wo.x + c * wo.y), mu_i);
    const float len = length(wi);
    if (!(len > 0)) return out;
    out.wi = wi / len;
    out.pdf = std::max(0.0f, pdf_phi * pdf_mu);
    out.f = fourier_value(t, ak, m, c, std::max(0.0, y), mu_i, mu_o);
    return out;
}

}  // namespace cmam::render
