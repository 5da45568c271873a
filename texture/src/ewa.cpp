#include <cmam/texture/ewa.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace cmam::texture {

const float* ewa_weight_lut() {
    static const std::array<float, kEwaLutSize> lut = [] {
        std::array<float, kEwaLutSize> t{};
        const double alpha = 2;
        for (int i = 0; i < kEwaLutSize; ++i) {
            double r2 = double(i) / (kEwaLutSize - 1);
            t[static_cast<std::size_t>(i)] =
                static_cast<float>(std::exp(-alpha * r2) - std::exp(-alpha));
        }
        return t;
    }();
    return lut.data();
}

EwaEllipse ewa_ellipse(double a_s, double a_t, double b_s, double b_t) {
    EwaEllipse e;
    e.A = a_t * a_t + b_t * b_t + 1;
    e.B = -2 * (a_s * a_t + b_s * b_t);
    e.C = a_s * a_s + b_s * b_s + 1;
    e.F = e.A * e.C - e.B * e.B / 4;
    // Normalised (divided by F) the half-extents are 2 sqrt(C/delta) and 2 sqrt(A/delta) with
    // delta = 4AC - B^2 = 4/F, which is sqrt(C) and sqrt(A) of the unnormalised coefficients.
    e.hx = std::sqrt(e.C);
    e.hy = std::sqrt(e.A);
    return e;
}

namespace {

int64_t ceil_to_int(double x) {
    return -floor_to_int(-x);
}

// Column wrap handled at compile time where it is cheap: Repeat steps the wrapped column along
// with the unwrapped one, Clamp clamps it; anything else wraps each texel.
enum class ColumnWrap { Repeat, Clamp, Other };

// The ellipse's weighted sum at one level. Coefficients are normalised (Q < 1 inside);
// NC > 0 fixes the channel count at compile time.
template <int NC, ColumnWrap CW>
void ewa_accumulate(const Image& img, double s0, double t0, double A, double B, double C, double hy,
                    double inv2a, float* sum, double* wsum_out, int* count_out) {
    const int64_t W = img.width(), H = img.height();
    const int nc = NC > 0 ? NC : img.channels();
    const float* lut = ewa_weight_lut();
    const double delta = 4 * A * C - B * B;
    const int64_t t_lo = ceil_to_int(t0 - hy), t_hi = floor_to_int(t0 + hy);
    float acc[4] = {0, 0, 0, 0};
    float wsum = 0;
    int count = 0;
    // Repeat rows step along with `it` (one division per level, not per row: tiny levels wrap
    // on nearly every row).
    const bool repeat_t = img.wrap_t() == WrapMode::Repeat;
    int64_t jt_next = repeat_t ? wrap_index(t_lo, H, WrapMode::Repeat) : 0;
    for (int64_t it = t_lo; it <= t_hi; ++it) {
        const int64_t jt = repeat_t ? jt_next : wrap_index(it, H, img.wrap_t());
        if (repeat_t) jt_next = jt_next + 1 == H ? 0 : jt_next + 1;
        const double y = double(it) - t0;
        // Exact span of this row: A x^2 + (B y) x + (C y^2 - 1) < 0, i.e. |x - xc| < sqrt(disc)/2A.
        const double disc = 4 * A - delta * y * y;
        if (!(disc > 0)) continue;
        const double half = std::sqrt(disc) * inv2a, xc = s0 - B * y * inv2a;
        const int64_t s_lo = ceil_to_int(xc - half), s_hi = floor_to_int(xc + half);
        const float* row = jt >= 0 ? img.row(static_cast<int>(jt)) : nullptr;
        const double by = B * y, cyy = C * y * y;
        int64_t js = 0;
        if constexpr (CW == ColumnWrap::Repeat)  // a mask for power-of-two widths, no division
            js = (W & (W - 1)) == 0 ? (s_lo & (W - 1)) : wrap_index(s_lo, W, WrapMode::Repeat);
        // Q is evaluated directly per texel (not incrementally): the weight-table index
        // floor(Q * N) must not depend on accumulated rounding.
        double xi = double(s_lo);
        for (int64_t is = s_lo; is <= s_hi; ++is, xi += 1) {
            const double x = xi - s0;
            const double r2 = A * x * x + by * x + cyy;
            int64_t col;
            if constexpr (CW == ColumnWrap::Repeat) {
                col = js;
                js = js + 1 == W ? 0 : js + 1;
            } else if constexpr (CW == ColumnWrap::Clamp) {
                col = is < 0 ? 0 : (is >= W ? W - 1 : is);
            } else {
                col = wrap_index(is, W, img.wrap_s());
            }
            if (!(r2 < 1)) continue;
            const float w = lut[static_cast<int>(r2 * kEwaLutSize)];
            ++count;
            wsum += w;
            if (!row || col < 0) continue;  // outside a black edge: the weight counts, 0 adds
            const float* t = row + Image::column_offset(col) * nc;
            for (int c = 0; c < nc; ++c) acc[c] += w * t[c];
        }
    }
    for (int c = 0; c < nc; ++c) sum[c] = acc[c];
    *wsum_out = wsum;
    *count_out = count;
}

template <int NC>
void ewa_accumulate_nc(const Image& img, double s0, double t0, double A, double B, double C,
                       double hy, double inv2a, float* sum, double* wsum, int* count) {
    switch (img.wrap_s()) {
        case WrapMode::Repeat:
            return ewa_accumulate<NC, ColumnWrap::Repeat>(img, s0, t0, A, B, C, hy, inv2a, sum,
                                                          wsum, count);
        case WrapMode::Clamp:
            return ewa_accumulate<NC, ColumnWrap::Clamp>(img, s0, t0, A, B, C, hy, inv2a, sum, wsum,
                                                         count);
        default:
            return ewa_accumulate<NC, ColumnWrap::Other>(img, s0, t0, A, B, C, hy, inv2a, sum, wsum,
                                                         count);
    }
}

}  // namespace

Texel ewa_level(const Image& img, double u, double v, double a_s, double a_t, double b_s,
                double b_t, int* texels_read) {
    const int W = img.width(), H = img.height(), nc = img.channels();
    const bool black = img.wrap_s() == WrapMode::Black || img.wrap_t() == WrapMode::Black;
    if (W == 1 && H == 1 && !black) {  // every texel of the ellipse is this one
        if (texels_read) *texels_read += 1;
        return img.fetch(0, 0);
    }
    const double s0 = u * W - 0.5, t0 = v * H - 0.5;
    const EwaEllipse e = ewa_ellipse(a_s, a_t, b_s, b_t);
    const double inv_f = 1 / e.F, An = e.A * inv_f, Bn = e.B * inv_f, Cn = e.C * inv_f;
    const double hy = e.hy, inv2a = 0.5 * e.F / e.A;  // 1 / 2An, beside 1/F rather than after it
    float sum[4] = {0, 0, 0, 0};
    double wsum = 0;
    int count = 0;
    switch (nc) {
        case 1:
            ewa_accumulate_nc<1>(img, s0, t0, An, Bn, Cn, hy, inv2a, sum, &wsum, &count);
            break;
        case 3:
            ewa_accumulate_nc<3>(img, s0, t0, An, Bn, Cn, hy, inv2a, sum, &wsum, &count);
            break;
        default:
            ewa_accumulate_nc<0>(img, s0, t0, An, Bn, Cn, hy, inv2a, sum, &wsum, &count);
            break;
    }
    if (texels_read) *texels_read += count;
    Texel out{};
    if (wsum <= 0) return texture::bilinear(img, u, v);
    const float inv = static_cast<float>(1 / wsum);
    for (int c = 0; c < nc; ++c) out[c] = sum[c] * inv;
    return out;
}

EwaResult ewa(const MipPyramid& pyr, double u, double v, double au, double av, double bu, double bv,
              double max_aniso) {
    EwaResult r;
    const Image& base = pyr.level(0);
    const int L = pyr.levels();
    if (!std::isfinite(u) || !std::isfinite(v) || !std::isfinite(au) || !std::isfinite(av) ||
        !std::isfinite(bu) || !std::isfinite(bv)) {
        r.value = base.mean();
        r.lambda = L - 1;
        return r;
    }
    max_aniso = std::max(1.0, max_aniso);
    // Axes in level-0 texels, per axis scaled.
    double as = au * base.width(), at = av * base.height();
    double bs = bu * base.width(), bt = bv * base.height();
    double la = std::sqrt(as * as + at * at), lb = std::sqrt(bs * bs + bt * bt);
    if (la < lb) {
        std::swap(as, bs);
        std::swap(at, bt);
        std::swap(la, lb);
    }
    if (la == 0) {  // no extent at all: point sample
        r.value = pyr.bilinear(0, u, v);
        r.texels_read = 4;
        return r;
    }
    if (lb == 0) {  // degenerate minor axis: perpendicular, |a| / maxAniso long
        double k = la / max_aniso / la;
        bs = -at * k;
        bt = as * k;
        lb = la / max_aniso;
    } else if (lb * max_aniso < la) {  // clamp the anisotropy by widening the minor axis
        double k = la / (lb * max_aniso);
        bs *= k;
        bt *= k;
        lb *= k;
    }
    r.major = la;
    r.minor = lb;
    double lambda = std::max(0.0, std::log2(lb));
    if (lambda >= L - 1) {
        r.value = pyr.level(L - 1).mean();
        r.lambda = L - 1;
        r.texels_read = 1;
        return r;
    }
    int l = static_cast<int>(std::floor(lambda));
    double f = lambda - l;
    r.lambda = lambda;
    auto at_level = [&](int lev) {
        const Image& img = pyr.level(lev);
        double ks = double(img.width()) / base.width(), kt = double(img.height()) / base.height();
        return ewa_level(img, u, v, as * ks, at * kt, bs * ks, bt * kt, &r.texels_read);
    };
    Texel a = at_level(l);
    if (f == 0) {
        r.value = a;
        return r;
    }
    Texel b = at_level(l + 1);  // l + 1 <= L - 1 here
    for (int c = 0; c < 4; ++c) r.value[c] = static_cast<float>((1 - f) * a[c] + f * b[c]);
    return r;
}

}  // namespace cmam::texture
