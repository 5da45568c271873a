#include <cmam/texture/filters.h>
#include <cmam/texture/mip.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

namespace {
// Weights of source cells for each output cell along one axis: out k covers [k*N/n, (k+1)*N/n).
struct Span {
    int first;
    std::vector<double> w;
};
std::vector<Span> area_weights(int N, int n) {
    std::vector<Span> spans(static_cast<std::size_t>(n));
    double scale = double(N) / n;
    for (int k = 0; k < n; ++k) {
        double a = k * scale, b = (k + 1) * scale;
        int i0 = static_cast<int>(std::floor(a)), i1 = std::min(N, static_cast<int>(std::ceil(b)));
        Span& s = spans[static_cast<std::size_t>(k)];
        s.first = i0;
        for (int i = i0; i < i1; ++i)
            s.w.push_back((std::min<double>(b, i + 1) - std::max<double>(a, i)) / scale);
    }
    return spans;
}
}  // namespace

namespace {
// Output row k of `w` texels from source rows 2k and 2k + 1. Texels 2i and 2i + 1 are neighbours
// within one tile row (tiles are eight wide), and the channel count is a constant.
template <int C>
void halve_row(const Image& src, int k, int w, float* row) {
    const float *r0 = src.row(2 * k), *r1 = src.row(2 * k + 1);
    for (int i = 0; i < w; ++i) {
        const std::ptrdiff_t at = Image::column_offset(2 * i) * C;
        const float *a = r0 + at, *b = a + C, *c = r1 + at, *d = c + C;
        float* o = row + static_cast<std::size_t>(i) * C;
        for (int ch = 0; ch < C; ++ch) {
            const double top = 0.5 * a[ch] + 0.5 * b[ch], bottom = 0.5 * c[ch] + 0.5 * d[ch];
            o[ch] = static_cast<float>(0.5 * top + 0.5 * bottom);
        }
    }
}

// Halving in both axes, the common case: each output texel is the mean of a 2x2 block, in the
// same operations and order as the general weights below (every weight 1/2), so the same floats
// at a fraction of the cost.
Image halve(const Image& src) {
    const int w = src.width() / 2, C = src.channels();
    // Written row by row into the level: no second copy of it.
    auto fill = [&](int k, float* row) {
        detail::with_channels(C, [&]<int NC>() { halve_row<NC>(src, k, w, row); });
    };
    return Image::from_rows(w, src.height() / 2, C, fill, src.wrap_s(), src.wrap_t());
}
}  // namespace

Image box_downsample(const Image& src, int w, int h) {
    const int W = src.width(), H = src.height(), C = src.channels();
    if (W == 2 * w && H == 2 * h) return halve(src);
    auto xs = area_weights(W, w), ys = area_weights(H, h);
    // Along x first (H rows of w texels), then along y.
    std::vector<double> tmp(static_cast<std::size_t>(w) * H * C, 0.0);
    for (int j = 0; j < H; ++j)
        for (int k = 0; k < w; ++k) {
            const Span& s = xs[static_cast<std::size_t>(k)];
            for (std::size_t q = 0; q < s.w.size(); ++q) {
                const float* t = src.texel(s.first + static_cast<int>(q), j);
                for (int c = 0; c < C; ++c)
                    tmp[(static_cast<std::size_t>(j) * w + k) * C + c] += s.w[q] * t[c];
            }
        }
    std::vector<float> out(static_cast<std::size_t>(w) * h * C);
    for (int k = 0; k < h; ++k) {
        const Span& s = ys[static_cast<std::size_t>(k)];
        for (int i = 0; i < w; ++i)
            for (int c = 0; c < C; ++c) {
                double acc = 0;
                for (std::size_t q = 0; q < s.w.size(); ++q)
                    acc += s.w[q] * tmp[((static_cast<std::size_t>(s.first) + q) * w + i) * C + c];
                out[(static_cast<std::size_t>(k) * w + i) * C + c] = static_cast<float>(acc);
            }
    }
    return Image(w, h, C, std::move(out), src.wrap_s(), src.wrap_t());
}

MipPyramid::MipPyramid(const Image& base)
    : m_owned_base(std::make_unique<Image>(base)), m_base(m_owned_base.get()) {
    build_upper();
}

MipPyramid MipPyramid::over(const Image& base) {
    MipPyramid p;
    p.m_base = &base;
    p.build_upper();
    return p;
}

void MipPyramid::build_upper() {
    const int W = m_base->width(), H = m_base->height();
    const int L = 1 + static_cast<int>(std::floor(std::log2(std::max(W, H))));
    m_upper.reserve(static_cast<std::size_t>(L - 1));
    for (int l = 1; l < L; ++l) {
        const int w = std::max(1, W >> l), h = std::max(1, H >> l);
        m_upper.push_back(box_downsample(level(l - 1), w, h));
    }
}

std::size_t MipPyramid::memory_bytes() const {
    std::size_t n = m_owned_base ? m_owned_base->memory_bytes() : 0;
    for (const Image& i : m_upper) n += i.memory_bytes();
    return n;
}

Texel MipPyramid::bilinear(int l, double u, double v) const {
    return texture::bilinear(level(l), u, v);
}

Texel MipPyramid::trilinear(double u, double v, double width) const {
    // Magnification (or NaN width): level 0, no logarithm needed.
    if (!(width > 1)) return bilinear(0, u, v);
    // The level is the width's binary exponent, so the texel reads need not wait for the
    // logarithm; only the blend weight does (FilteredTexture::lookup does the same with the
    // squared width's).
    const int l = detail::floor_log2(width);
    const double lambda = std::log2(width);
    return trilinear_levels(u, v, l, static_cast<float>(std::clamp(lambda - l, 0.0, 1.0)));
}

Texel MipPyramid::trilinear_width2(double u, double v, double width2, double* lambda_out) const {
    if (lambda_out) *lambda_out = 0;
    if (!(width2 > 1)) return bilinear(0, u, v);  // magnification (or NaN)
    // With width2 = m 2^e (1 <= m < 2), lambda = (e + log2 m) / 2 lies in
    // [floor(e/2), floor(e/2) + 1): the level is floor(e/2).
    const int l = detail::floor_log2(width2) >> 1;
    const double lambda = 0.5 * std::log2(width2);
    if (lambda_out) *lambda_out = std::min(lambda, double(levels() - 1));
    return trilinear_levels(u, v, l, static_cast<float>(std::clamp(lambda - l, 0.0, 1.0)));
}

double MipPyramid::trilinear_lambda(double width) const {
    return width > 1 ? std::min(std::log2(width), double(levels() - 1)) : 0;
}

Texel MipPyramid::trilinear_lod(double u, double v, double lambda) const {
    const int L = levels();
    if (!(lambda > 0)) return bilinear(0, u, v);
    if (lambda >= L - 1) return level(L - 1).mean();
    const int l = static_cast<int>(lambda);  // lambda > 0 here
    return trilinear_levels(u, v, l, static_cast<float>(lambda - l));
}

// Flattened: both levels' bilinear reads inline (two calls, each returning its texel through
// memory, were a fifth of a MIP lookup's instructions).
[[gnu::flatten]] Texel MipPyramid::trilinear_levels(double u, double v, int l, float f) const {
    if (l >= levels() - 1) return level(levels() - 1).mean();
    const Image &fine = level(l), &coarse = level(l + 1);
    const double s = u * fine.width() - 0.5, t = v * fine.height() - 0.5;
    // The coarser level's coordinates are smaller, so one range check covers both.
    if (!(std::abs(s) < detail::kMaxTexelCoord && std::abs(t) < detail::kMaxTexelCoord))
        return fine.mean();
    const double sc = u * coarse.width() - 0.5, tc = v * coarse.height() - 0.5;
#if defined(__SSE2__)
    // Both levels' texels stay in registers through the blend.
    if (fine.channels() >= 3) {
        __m128 a, b;
        if (detail::bilinear_wrapped4(fine, s, t, &a) &&
            detail::bilinear_wrapped4(coarse, sc, tc, &b))
            return detail::to_texel(
                _mm_add_ps(_mm_mul_ps(_mm_set1_ps(1 - f), a), _mm_mul_ps(_mm_set1_ps(f), b)),
                fine.channels());
    }
#endif
    const Texel a = detail::bilinear_at(fine, s, t);
    const Texel b = detail::bilinear_at(coarse, sc, tc);
    Texel out{};
    for (int c = 0; c < 4; ++c) out[c] = (1 - f) * a[c] + f * b[c];
    return out;
}

}  // namespace cmam::texture
