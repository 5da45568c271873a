// cmam::texture — inner kernels shared by the filters (private header).
// Bilinear taps resolved per axis once (wrap applied to the pair of indices, never per texel),
// so no lookup divides unless its coordinate lies outside the base period; texel addresses come
// from the image's row and column offset tables (two loads each instead of the tile arithmetic).
// With SSE2, a 3- or 4-channel texel is one 4-wide multiply-add per tap, kept in a register from
// the taps to the caller's blend: per lane the arithmetic is the scalar expression's, so results
// do not depend on which path ran.
#pragma once

#include <cmam/texture/image.h>
#include <cmam/texture/vec2.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cmam::texture::detail {

/// Texel coordinates are used up to 2^30 in magnitude: beyond, every filter returns the mean, so
/// no coordinate is ever converted to an integer out of range and no sum loses all precision.
inline constexpr double kMaxTexelCoord = 1073741824.0;

/// Minimum extent of a SAT rectangle (level-0 texels) per axis (algorithms.md §6.4):
/// max(extent, 1 texel, other extent / maxAniso), centred on the original.
inline void sat_min_extent(Box2d& r, double max_aniso) {
    if (!(max_aniso >= 1)) max_aniso = 1;  // below 1 (or NaN) would widen without bound
    const double w = r.hi.u - r.lo.u, h = r.hi.v - r.lo.v;
    const Vec2d half{std::max({w, 1.0, h / max_aniso}) / 2, std::max({h, 1.0, w / max_aniso}) / 2};
    const Vec2d centre = 0.5 * (r.lo + r.hi);
    r = {centre - half, centre + half};
}

/// f.template operator()<NC>() with the channel count `nc` (1 to 4; anything else is taken as 4)
/// a compile-time constant: the per-texel loops of a table, a level or a copy keep their sums in
/// registers and unroll over the channels. `f` is typically a lambda `[&]<int NC>() { ... }`.
template <class F>
[[gnu::always_inline]] inline decltype(auto) with_channels(int nc, F&& f) {
    switch (nc) {
        case 1:
            return f.template operator()<1>();
        case 2:
            return f.template operator()<2>();
        case 3:
            return f.template operator()<3>();
        default:
            return f.template operator()<4>();
    }
}

/// floor(log2(x)) for x >= 1 (infinity included), exactly, from the binary exponent: a level
/// chosen this way does not wait for a logarithm.
inline int floor_log2(double x) {
    static_assert(std::numeric_limits<double>::is_iec559);
    return static_cast<int>((std::bit_cast<uint64_t>(x) >> 52) & 0x7ff) - 1023;
}

/// The two lattice indices around continuous coordinate `s` (already shifted by -1/2) on an
/// axis of n texels, with the wrap applied; -1 marks a Black tap. `f` is the weight of i1.
struct AxisTaps {
    int i0, i1;
    float f;
};

inline AxisTaps axis_taps(double s, int n, WrapMode mode) {
    int64_t k = floor_to_int(s);
    AxisTaps t;
    t.f = static_cast<float>(s - static_cast<double>(k));
    if (k >= 0 && k + 1 < n) {  // the common case: both inside
        t.i0 = static_cast<int>(k);
        t.i1 = t.i0 + 1;
        return t;
    }
    switch (mode) {
        case WrapMode::Repeat: {
            int64_t w = wrap_index(k, n, WrapMode::Repeat);
            t.i0 = static_cast<int>(w);
            t.i1 = w + 1 == n ? 0 : t.i0 + 1;
            return t;
        }
        case WrapMode::Clamp:
            t.i0 = static_cast<int>(k < 0 ? 0 : (k >= n ? n - 1 : k));
            t.i1 = static_cast<int>(k + 1 < 0 ? 0 : (k + 1 >= n ? n - 1 : k + 1));
            return t;
        default:
            t.i0 = static_cast<int>(wrap_index(k, n, mode));
            t.i1 = static_cast<int>(wrap_index(k + 1, n, mode));
            return t;
    }
}

#if defined(__SSE2__)
/// Bilinear interpolation of a 3- or 4-channel image from resolved taps `x`, `y` (none of them
/// Black), as four lanes. A 3-channel texel is loaded as four floats (the next texel's first
/// channel, or the buffer's slack after the last texel), so lane 3 is then meaningless. Weights
/// and sums in bilinear_at's scalar order: w00 a + w10 b + w01 c + w11 d.
inline __m128 bilinear_taps4(const Image& img, const AxisTaps& x, const AxisTaps& y) {
    const float fs = x.f, ft = y.f;
    // (w00, w10, w01, w11) in one multiply.
    const __m128 w =
        _mm_mul_ps(_mm_setr_ps(1 - fs, fs, 1 - fs, fs), _mm_setr_ps(1 - ft, 1 - ft, ft, ft));
    const float* base = img.row(0);
    const std::ptrdiff_t *cols = img.column_offsets(), *rows = img.row_offsets();
    const float *r0 = base + rows[y.i0], *r1 = base + rows[y.i1];
    const std::ptrdiff_t c0 = cols[x.i0], c1 = cols[x.i1];
    __m128 v = _mm_mul_ps(_mm_shuffle_ps(w, w, 0x00), _mm_loadu_ps(r0 + c0));
    v = _mm_add_ps(v, _mm_mul_ps(_mm_shuffle_ps(w, w, 0x55), _mm_loadu_ps(r0 + c1)));
    v = _mm_add_ps(v, _mm_mul_ps(_mm_shuffle_ps(w, w, 0xaa), _mm_loadu_ps(r1 + c0)));
    return _mm_add_ps(v, _mm_mul_ps(_mm_shuffle_ps(w, w, 0xff), _mm_loadu_ps(r1 + c1)));
}

/// Bilinear interpolation of a 3- or 4-channel image at lattice coordinates (s, t) (finite, below
/// 2^30 in magnitude), with the wrap applied, as four lanes in `out`; false, leaving `out`
/// alone, when a tap lies outside a Black edge. A tiled texture's coordinates are mostly outside
/// the base period: the wrap is resolved per axis (axis_taps), so they take this path too.
inline bool bilinear_wrapped4(const Image& img, double s, double t, __m128* out) {
    const AxisTaps x = axis_taps(s, img.width(), img.wrap_s());
    const AxisTaps y = axis_taps(t, img.height(), img.wrap_t());
    if ((x.i0 | x.i1 | y.i0 | y.i1) < 0) return false;
    *out = bilinear_taps4(img, x, y);
    return true;
}

/// The lanes of `v` as a Texel of `nc` (3 or 4) channels; unused channels are 0.
inline Texel to_texel(__m128 v, int nc) {
    Texel out;
    _mm_storeu_ps(out.data(), v);
    if (nc == 3) out[3] = 0;
    return out;
}
#endif

/// The four texels of the bilinear patch holding lattice coordinates (s, t) (finite, below 2^30
/// in magnitude), with the wrap applied: t00, t10 (next column), t01 (next row), t11; a tap
/// outside a Black edge is zero. `fs`, `ft` are the position within the patch.
struct BilinearPatch {
    Texel t00{}, t10{}, t01{}, t11{};
    float fs = 0, ft = 0;
    /// bilinear_at's value: the same weights, in the same order.
    Texel value(int nc) const {
        const float w00 = (1 - fs) * (1 - ft), w10 = fs * (1 - ft), w01 = (1 - fs) * ft,
                    w11 = fs * ft;
        Texel out{};
        for (int k = 0; k < nc; ++k)
            out[k] = w00 * t00[k] + w10 * t10[k] + w01 * t01[k] + w11 * t11[k];
        return out;
    }
};

inline BilinearPatch bilinear_patch(const Image& img, double s, double t) {
    const AxisTaps x = axis_taps(s, img.width(), img.wrap_s());
    const AxisTaps y = axis_taps(t, img.height(), img.wrap_t());
    BilinearPatch p;
    p.fs = x.f;
    p.ft = y.f;
    const int nc = img.channels();
    const float* base = img.row(0);
    const std::ptrdiff_t *cols = img.column_offsets(), *rows = img.row_offsets();
    auto get = [&](int i, int j, Texel& out) {
        if (i < 0 || j < 0) return;  // outside a Black edge
        const float* texel = base + rows[j] + cols[i];
        for (int k = 0; k < nc; ++k) out[k] = texel[k];
    };
    get(x.i0, y.i0, p.t00);
    get(x.i1, y.i0, p.t10);
    get(x.i0, y.i1, p.t01);
    get(x.i1, y.i1, p.t11);
    return p;
}

/// Bilinear interpolation at lattice coordinates (s, t) = (u*W - 1/2, v*H - 1/2), which the
/// caller has checked to be finite and below 2^30 in magnitude.
inline Texel bilinear_at(const Image& img, double s, double t) {
    const AxisTaps x = axis_taps(s, img.width(), img.wrap_s());
    const AxisTaps y = axis_taps(t, img.height(), img.wrap_t());
    const int nc = img.channels();
#if defined(__SSE2__)
    if (nc >= 3 && (x.i0 | x.i1 | y.i0 | y.i1) >= 0) return to_texel(bilinear_taps4(img, x, y), nc);
#endif
    const float w00 = (1 - x.f) * (1 - y.f), w10 = x.f * (1 - y.f), w01 = (1 - x.f) * y.f,
                w11 = x.f * y.f;
    Texel out{};
    if ((x.i0 | x.i1 | y.i0 | y.i1) >= 0) {
        const float* base = img.row(0);
        const std::ptrdiff_t *cols = img.column_offsets(), *rows = img.row_offsets();
        const float *r0 = base + rows[y.i0], *r1 = base + rows[y.i1];
        const std::ptrdiff_t c0 = cols[x.i0], c1 = cols[x.i1];
        const float *a = r0 + c0, *b = r0 + c1, *c = r1 + c0, *d = r1 + c1;
        auto blend = [&](int k) { return w00 * a[k] + w10 * b[k] + w01 * c[k] + w11 * d[k]; };
        if (nc == 3) return {blend(0), blend(1), blend(2), 0.0f};
        if (nc == 1) return {blend(0), 0.0f, 0.0f, 0.0f};
        for (int k = 0; k < nc; ++k) out[k] = blend(k);
        return out;
    }
    // Some tap lies outside a Black edge: it contributes zero.
    const int is[2] = {x.i0, x.i1}, js[2] = {y.i0, y.i1};
    const float ws[2][2] = {{w00, w10}, {w01, w11}};
    for (int q = 0; q < 2; ++q)
        for (int p = 0; p < 2; ++p) {
            if (is[p] < 0 || js[q] < 0) continue;
            const float* texel = img.texel(is[p], js[q]);
            for (int k = 0; k < nc; ++k) out[k] += ws[q][p] * texel[k];
        }
    return out;
}

}  // namespace cmam::texture::detail
