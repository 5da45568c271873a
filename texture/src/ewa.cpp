#include <cmam/texture/ewa.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <array>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "kernels.h"

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

namespace {
// ewa_ellipse, inlined into ewa_level (a lookup's chain of dependent steps is most of its cost
// before the first texel).
[[gnu::always_inline]] inline EwaEllipse ellipse_of(double a_s, double a_t, double b_s,
                                                    double b_t) {
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
}  // namespace

EwaEllipse ewa_ellipse(double a_s, double a_t, double b_s, double b_t) {
    return ellipse_of(a_s, a_t, b_s, b_t);
}

namespace {

int64_t ceil_to_int(double x) {
    return -floor_to_int(-x);
}

// Coordinates and extents are kept below 2^30 texels (ewa_level), so that every conversion to
// an integer is in range.
constexpr double kMaxCoord = detail::kMaxTexelCoord;

// The along-line wrap handled at compile time where it is cheap: Repeat runs through the
// two-period offset table from the wrapped start, Clamp clamps; anything else wraps each texel.
enum class ColumnWrap { Repeat, Clamp, Other };

// The image seen as lines of texels: its rows (along s) or its columns (along t). The ellipse is
// walked line by line with an exact span per line, so the cost has a part per texel and a part
// per line. Walking the direction with fewer lines (along the ellipse's longer extent) visits,
// for a thin ellipse at a random angle, about 40% fewer lines than walking rows only.
// Texel (i along, k across) is data + line[k] + along[i], both offsets from the image's
// two-period tables. Rows and columns are the same code (one instance of the walk, not two).
struct Lines {
    Lines(const Image& img, bool columns)
        : data(img.row(0)),
          along(columns ? img.row_offsets() : img.column_offsets()),
          line(columns ? img.column_offsets() : img.row_offsets()),
          n_along(columns ? img.height() : img.width()),
          n_across(columns ? img.width() : img.height()),
          wrap_along(columns ? img.wrap_t() : img.wrap_s()),
          wrap_across(columns ? img.wrap_s() : img.wrap_t()),
          nc(img.channels()) {}
    const float* data;
    const std::ptrdiff_t *along, *line;
    int64_t n_along, n_across;
    WrapMode wrap_along, wrap_across;
    int nc;
};

// Accumulates weighted texels: with SSE2, three or four channels are one 4-wide multiply-add
// (a 4-float load of a 3-channel texel reads the next texel's first channel, or the buffer's
// slack after the last one, into a lane that is never used). Per lane the arithmetic is the
// scalar w * t + acc, so results do not depend on which path ran.
template <int NC>
struct TexelSum {
#if defined(__SSE2__)
    static constexpr bool kVector = NC == 3 || NC == 4;
#else
    static constexpr bool kVector = false;
#endif
    void add(float w, const float* t, int nc) {
#if defined(__SSE2__)
        if constexpr (kVector) {
            v = _mm_add_ps(v, _mm_mul_ps(_mm_set1_ps(w), _mm_loadu_ps(t)));
            return;
        }
#endif
        for (int c = 0; c < (NC > 0 ? NC : nc); ++c) s[c] += w * t[c];
    }
    void store(float* out, int nc) const {
#if defined(__SSE2__)
        if constexpr (kVector) {
            float tmp[4];
            _mm_storeu_ps(tmp, v);
            for (int c = 0; c < nc; ++c) out[c] = tmp[c];
            return;
        }
#endif
        for (int c = 0; c < nc; ++c) out[c] = s[c];
    }
#if defined(__SSE2__)
    __m128 v = _mm_setzero_ps();
#endif
    float s[4] = {0, 0, 0, 0};
};

// Ellipses spanning at most this many lines (and 4 or 8 texels along them) take a window.
constexpr int64_t kWindowLines = 8;

// A small ellipse, repeat-wrapped both ways: a window of K (4 or 8) texels per line from s_lo
// (wrapped: j0), lines t_lo..t_hi (the first wrapped: jt), without branches. Texels outside the
// ellipse get the table's last entry, 0, and are not counted; as they add exactly zero, the sums
// are those of the exact spans, in the same order. An, Bn, Cn are the coefficients times the
// table size N, as in ewa_accumulate. With SSE2, Q is computed two texels per instruction with
// the scalar expression's operations in its order (so the same values), and the table index is
// converted by an instruction defined for any input (out-of-range gives INT_MIN, masked to the
// last entry): texels near the ellipse's edge, inside or outside at random, cost no mispredicted
// branch.
template <int K, int NC, class L>
void ewa_window(const L& lines, int64_t s_lo, int64_t j0, int64_t t_lo, int64_t t_hi, int64_t jt,
                double s0, double t0, double An, double Bn, double Cn, TexelSum<NC>& acc,
                float& wsum, int64_t& count) {
    const int64_t H = lines.n_across;
    const int nc = NC > 0 ? NC : lines.nc;
    const float* lut = ewa_weight_lut();
    constexpr double N = kEwaLutSize;
    const double xs = double(s_lo);
    // The window's columns from the two-period table (j0 + K - 1 < 2W as W >= K).
    std::ptrdiff_t off[K];
    for (int k = 0; k < K; ++k) off[k] = lines.along[j0 + k];
#if defined(__SSE2__)
    // x and A x^2 per column pair; per line only B y x and C y^2 change.
    __m128d x[K / 2], ax2[K / 2];
    for (int p = 0; p < K / 2; ++p) {
        x[p] =
            _mm_sub_pd(_mm_add_pd(_mm_set1_pd(xs), _mm_setr_pd(2 * p, 2 * p + 1)), _mm_set1_pd(s0));
        ax2[p] = _mm_mul_pd(_mm_mul_pd(_mm_set1_pd(An), x[p]), x[p]);
    }
    const __m128d vn = _mm_set1_pd(N);
    const __m128i last = _mm_set1_epi32(kEwaLutSize - 1);
    __m128i inside = _mm_setzero_si128();  // per lane, minus the number of texels inside
#endif
    for (int64_t it = t_lo; it <= t_hi; ++it) {
        const double y = double(it) - t0, by = Bn * y, cyy = Cn * y * y;
        const float* row = lines.data + lines.line[jt];
        jt = jt + 1 == H ? 0 : jt + 1;
#if defined(__SSE2__)
        const __m128d vby = _mm_set1_pd(by), vcyy = _mm_set1_pd(cyy);
        for (int g = 0; g < K / 4; ++g) {
            const __m128d q0 = _mm_add_pd(_mm_add_pd(ax2[2 * g], _mm_mul_pd(vby, x[2 * g])), vcyy);
            const __m128d q1 =
                _mm_add_pd(_mm_add_pd(ax2[2 * g + 1], _mm_mul_pd(vby, x[2 * g + 1])), vcyy);
            // Four lanes: inside (all ones) or not, and the table index.
            const __m128 in = _mm_shuffle_ps(_mm_castpd_ps(_mm_cmplt_pd(q0, vn)),
                                             _mm_castpd_ps(_mm_cmplt_pd(q1, vn)), 0x88);
            const __m128i m = _mm_castps_si128(in);
            __m128i idx = _mm_unpacklo_epi64(_mm_cvttpd_epi32(q0), _mm_cvttpd_epi32(q1));
            idx = _mm_or_si128(_mm_and_si128(m, idx), _mm_andnot_si128(m, last));
            alignas(16) int32_t ix[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(ix), idx);
            inside = _mm_add_epi32(inside, m);
            for (int k = 0; k < 4; ++k) {
                const float w = lut[ix[k]];
                wsum += w;
                acc.add(w, row + off[4 * g + k], nc);
            }
        }
#else
        for (int k = 0; k < K; ++k) {
            const double x = (xs + k) - s0, q = An * x * x + by * x + cyy;
            const bool in = q < N;
            const float w = lut[in ? static_cast<int64_t>(q) : kEwaLutSize - 1];
            wsum += w;
            count += in;
            acc.add(w, row + off[k], nc);
        }
#endif
    }
#if defined(__SSE2__)
    alignas(16) int32_t n[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(n), inside);
    count -= int64_t(n[0]) + n[1] + n[2] + n[3];
#endif
}

// The ellipse's weighted sum at one level, walked along the lines L. Coordinates are in L's
// terms: s0 along a line, t0 across the lines, and Q = A x^2 + B x y + C y^2 with x along and y
// across; coefficients are normalised (Q < 1 inside). hx and hy are the half-extents along and
// across the lines; 1 / 2A is half_f / a_raw (F / 2 over the unnormalised A), a division only
// the spans need, so the small ellipses' window does not wait for it. NC > 0 fixes the channel
// count at compile time.
template <int NC, ColumnWrap CW, class L>
void ewa_accumulate(const L& lines, double s0, double t0, double A, double B, double C, double hx,
                    double hy, double half_f, double a_raw, float* sum, double* wsum_out,
                    int* count_out) {
    const int64_t W = lines.n_along, H = lines.n_across;
    const std::ptrdiff_t* along = lines.along;
    const int nc = NC > 0 ? NC : lines.nc;
    const float* lut = ewa_weight_lut();
    const double delta = 4 * A * C - B * B;
    // The weight-table index is floor(Q N). Scaling the coefficients by N, a power of two, is
    // exact, so Q N below carries exactly the rounding of Q and the index is the same.
    constexpr double N = kEwaLutSize;
    const double An = A * N, Bn = B * N, Cn = C * N;
    const int64_t t_lo = ceil_to_int(t0 - hy), t_hi = floor_to_int(t0 + hy);
    TexelSum<NC> acc;
    float wsum = 0;
    int64_t count = 0;
    // Lines are done in two passes: first every line's span (independent of one another, so
    // their square roots and conversions overlap), then the texels, line after line. One pass
    // per line would start each line's texels only after its own span's chain of dependent steps.
    struct Span {
        int64_t s_lo, s_hi, jt;
        double by, cyy;
    };
    constexpr int kRows = 32;
    Span spans[kRows];
    // Repeat lines step along with `it` (one division per level, not per line: tiny levels wrap
    // on nearly every line).
    const bool repeat_t = lines.wrap_across == WrapMode::Repeat;
    int64_t jt_next = repeat_t ? wrap_index(t_lo, H, WrapMode::Repeat) : 0;
    // Index i along a line wrapped into [0, W) under Repeat (a mask for power-of-two widths).
    auto repeat_along = [W](int64_t i) {
        return (W & (W - 1)) == 0 ? (i & (W - 1)) : wrap_index(i, W, WrapMode::Repeat);
    };
    if constexpr (CW == ColumnWrap::Repeat) {
        // A small ellipse (the levels of a round footprint, the coarser level of most others):
        // a fixed window of 4 or 8 texels per line instead of the spans.
        const int64_t s_lo = ceil_to_int(s0 - hx), n_s = floor_to_int(s0 + hx) - s_lo + 1;
        const int window = !(repeat_t && t_hi - t_lo < kWindowLines) ? 0
                           : n_s <= 4 && W >= 4                      ? 4
                           : n_s <= 8 && W >= 8                      ? 8
                                                                     : 0;
        if (window != 0) {
            if (window == 4)
                ewa_window<4>(lines, s_lo, repeat_along(s_lo), t_lo, t_hi, jt_next, s0, t0, An, Bn,
                              Cn, acc, wsum, count);
            else
                ewa_window<8>(lines, s_lo, repeat_along(s_lo), t_lo, t_hi, jt_next, s0, t0, An, Bn,
                              Cn, acc, wsum, count);
            acc.store(sum, nc);
            *wsum_out = wsum;
            *count_out = static_cast<int>(count);
            return;
        }
    }
    const double inv2a = half_f / a_raw;
    for (int64_t it0 = t_lo; it0 <= t_hi; it0 += kRows) {
        const int64_t it1 = std::min(t_hi, it0 + kRows - 1);
        int n = 0;
        for (int64_t it = it0; it <= it1; ++it) {
            const int64_t jt = repeat_t ? jt_next : wrap_index(it, H, lines.wrap_across);
            if (repeat_t) jt_next = jt_next + 1 == H ? 0 : jt_next + 1;
            const double y = double(it) - t0;
            // Exact span of this row: A x^2 + (B y) x + (C y^2 - 1) < 0, i.e.
            // |x - xc| < sqrt(disc)/2A.
            const double disc = 4 * A - delta * y * y;
            if (!(disc > 0)) continue;
            const double half = std::sqrt(disc) * inv2a, xc = s0 - B * y * inv2a;
            spans[n++] = {ceil_to_int(xc - half), floor_to_int(xc + half), jt, Bn * y, Cn * y * y};
        }
        for (int k = 0; k < n; ++k) {
            // Plain copies, not a structured binding: the lambda below uses two of them, and
            // Clang before 16 cannot capture structured bindings (a C++20 addition).
            const int64_t s_lo = spans[k].s_lo, s_hi = spans[k].s_hi, jt = spans[k].jt;
            const double by = spans[k].by, cyy = spans[k].cyy;
            if (s_hi < s_lo) continue;
            // Q is evaluated directly per texel, not by forward differences: the weight-table
            // index floor(Q N) must not depend on accumulated rounding (texels exactly on a
            // table step, common on symmetric footprints, would change weight). The span's end
            // texels can still fall just outside (Q >= 1) by rounding; they are skipped and not
            // counted.
            int64_t outside = 0;
            double xi = double(s_lo);
            // One texel of the span; outside a black edge (t null) only the weight counts.
            // Always inlined: GCC otherwise puts it out of line, which takes the address of the
            // sums it captures, and then every texel's additions go through memory (a store and
            // a reload in each sum's chain) and each line builds the closure on the stack.
            auto visit = [&](const float* t, bool black) __attribute__((always_inline)) {
                const double x = xi - s0, q = An * x * x + by * x + cyy;
                xi += 1;
                if (!(q < N)) {
                    ++outside;
                } else {
                    const float w = lut[static_cast<int64_t>(q)];
                    wsum += w;
                    if (!black) acc.add(w, t, nc);
                }
            };
            if (jt < 0) {  // a line outside a black edge
                for (int64_t is = s_lo; is <= s_hi; ++is) visit(nullptr, true);
                count += s_hi - s_lo + 1 - outside;
                continue;
            }
            const float* row = lines.data + lines.line[jt];
            if constexpr (CW == ColumnWrap::Repeat) {
                // Through the two-period table from the wrapped start, in pieces of at most one
                // period (one piece unless the span is longer than the image).
                int64_t j = repeat_along(s_lo);
#if defined(__SSE2__)
                // A span within one period (nearly all): Q of two texels per instruction, with
                // the scalar expression's operations in its order (the same values); a pair
                // inside the ellipse, as nearly all are, adds its two texels in order without a
                // branch each, and a pair with a texel outside (by rounding, at a span's end)
                // takes visit's test texel by texel, so the sums are the scalar loop's.
                if (s_hi - s_lo + 1 <= W) {
                    const std::ptrdiff_t* a = along + j;
                    const int64_t n_span = s_hi - s_lo + 1;
                    const __m128d vs0 = _mm_set1_pd(s0), van = _mm_set1_pd(An),
                                  vby = _mm_set1_pd(by), vcyy = _mm_set1_pd(cyy),
                                  vn = _mm_set1_pd(N), two = _mm_set1_pd(2);
                    __m128d vxi = _mm_setr_pd(xi, xi + 1);
                    int64_t m = 0;
                    for (; m + 2 <= n_span; m += 2) {
                        const __m128d x = _mm_sub_pd(vxi, vs0);
                        vxi = _mm_add_pd(vxi, two);
                        const __m128d q = _mm_add_pd(
                            _mm_add_pd(_mm_mul_pd(_mm_mul_pd(van, x), x), _mm_mul_pd(vby, x)),
                            vcyy);
                        if (_mm_movemask_pd(_mm_cmplt_pd(q, vn)) == 3) {
                            const __m128i idx = _mm_cvttpd_epi32(q);
                            const float w0 = lut[_mm_cvtsi128_si32(idx)],
                                        w1 = lut[_mm_cvtsi128_si32(_mm_srli_si128(idx, 4))];
                            wsum += w0;
                            acc.add(w0, row + a[m], nc);
                            wsum += w1;
                            acc.add(w1, row + a[m + 1], nc);
                        } else {
                            xi = double(s_lo + m);
                            visit(row + a[m], false);
                            visit(row + a[m + 1], false);
                        }
                    }
                    if (m < n_span) {
                        xi = double(s_lo + m);
                        visit(row + a[m], false);
                    }
                    count += n_span - outside;
                    continue;
                }
#endif
                for (int64_t left = s_hi - s_lo + 1; left > 0;) {
                    const int64_t end = j + std::min(left, W);
                    left -= end - j;
                    for (; j < end; ++j) visit(row + along[j], false);
                    j -= W;
                }
            } else {
                for (int64_t is = s_lo; is <= s_hi; ++is) {
                    int64_t col;
                    if constexpr (CW == ColumnWrap::Clamp)
                        col = is < 0 ? 0 : (is >= W ? W - 1 : is);
                    else
                        col = wrap_index(is, W, lines.wrap_along);
                    if (col < 0)  // outside a black edge
                        visit(nullptr, true);
                    else
                        visit(row + along[col], false);
                }
            }
            count += s_hi - s_lo + 1 - outside;
        }
    }
    acc.store(sum, nc);
    *wsum_out = wsum;
    *count_out = static_cast<int>(count);
}

template <int NC, class L>
void ewa_accumulate_wrap(const L& lines, double s0, double t0, double A, double B, double C,
                         double hx, double hy, double half_f, double a_raw, float* sum,
                         double* wsum, int* count) {
    switch (lines.wrap_along) {
        case WrapMode::Repeat:
            return ewa_accumulate<NC, ColumnWrap::Repeat>(lines, s0, t0, A, B, C, hx, hy, half_f,
                                                          a_raw, sum, wsum, count);
        case WrapMode::Clamp:
            return ewa_accumulate<NC, ColumnWrap::Clamp>(lines, s0, t0, A, B, C, hx, hy, half_f,
                                                         a_raw, sum, wsum, count);
        default:
            return ewa_accumulate<NC, ColumnWrap::Other>(lines, s0, t0, A, B, C, hx, hy, half_f,
                                                         a_raw, sum, wsum, count);
    }
}

// Rows when the ellipse is at least as wide as it is tall, columns otherwise (A, C and the
// half-extents trade places).
template <int NC>
void ewa_accumulate_nc(const Image& img, double s0, double t0, const EwaEllipse& e, double A,
                       double B, double C, float* sum, double* wsum, int* count) {
    const bool columns = e.hy > e.hx;
    ewa_accumulate_wrap<NC>(Lines(img, columns), columns ? t0 : s0, columns ? s0 : t0,
                            columns ? C : A, B, columns ? A : C, columns ? e.hy : e.hx,
                            columns ? e.hx : e.hy, 0.5 * e.F, columns ? e.C : e.A, sum, wsum,
                            count);
}

}  // namespace

EwaLevelResult ewa_level(const Image& img, double u, double v, double a_s, double a_t, double b_s,
                         double b_t) {
    const int W = img.width(), H = img.height(), nc = img.channels();
    const bool black = img.wrap_s() == WrapMode::Black || img.wrap_t() == WrapMode::Black;
    if (W == 1 && H == 1 && !black)  // every texel of the ellipse is this one
        return {img.fetch(0, 0), 1};
    const double s0 = u * W - 0.5, t0 = v * H - 0.5;
    const EwaEllipse e = ellipse_of(a_s, a_t, b_s, b_t);
    // Beyond 2^30 texels the texture's mean, as for bilinear lookups: no coordinate outside an
    // integer's range is ever converted to one.
    if (!(std::abs(s0) + e.hx < kMaxCoord && std::abs(t0) + e.hy < kMaxCoord))
        return {img.mean(), 1};
    const double inv_f = 1 / e.F, An = e.A * inv_f, Bn = e.B * inv_f, Cn = e.C * inv_f;
    float sum[4] = {0, 0, 0, 0};
    double wsum = 0;
    int count = 0;
    switch (nc) {
        case 1:
            ewa_accumulate_nc<1>(img, s0, t0, e, An, Bn, Cn, sum, &wsum, &count);
            break;
        case 3:
            ewa_accumulate_nc<3>(img, s0, t0, e, An, Bn, Cn, sum, &wsum, &count);
            break;
        default:
            ewa_accumulate_nc<0>(img, s0, t0, e, An, Bn, Cn, sum, &wsum, &count);
            break;
    }
    EwaLevelResult out;
    out.texels_read = count;
    if (wsum <= 0) {
        out.value = texture::bilinear(img, u, v);
        return out;
    }
    // All four lanes (unused channels' sums are 0, and 1 / wsum is finite: a texel inside weighs
    // at least the table's smallest positive entry), so the loop is one multiply. wsum is a sum
    // of floats kept in float, so the division in float is the double one rounded to float
    // (double's 53 bits are more than twice float's 24 plus two: the rounding twice changes
    // nothing), and quicker.
    const float inv = 1.0f / static_cast<float>(wsum);
    for (int c = 0; c < 4; ++c) out.value[c] = sum[c] * inv;
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
    max_aniso = max_aniso >= 1 ? std::min(max_aniso, kEwaMaxAnisotropy) : 1;
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
    // lambda = max(0, log2 |b|), taken from |b| rounded to single precision, the precision
    // pbrt-v3 and OpenImageIO compute the level of detail in. A minor axis that is a power of
    // two to that precision (a rotated footprint's rounded components leave it within about
    // 1e-7 of one) then gives f = 0 and one level, rather than a second level weighted about
    // 1e-7; lambda moves by at most about 1e-7. Its integer part is the binary exponent, so the
    // first level's texels need not wait for the logarithm; only the blend weight does. (The
    // min keeps the conversion in float's range; any |b| that large gives the coarsest level.)
    const double lod_b = static_cast<float>(std::min(lb, 1e30));
    const int l = lod_b < 1 ? 0 : detail::floor_log2(lod_b);
    if (l >= L - 1) {
        r.value = pyr.level(L - 1).mean();
        r.lambda = L - 1;
        r.texels_read = 1;
        return r;
    }
    const double lambda = lod_b < 1 ? 0 : std::log2(lod_b);
    const double f = std::clamp(lambda - l, 0.0, 1.0);
    r.lambda = std::min(lambda, double(L - 1));
    // Level-0 texels to level-lev texels: multiplications by W_lev / W_0 (the reciprocals do not
    // depend on the lookup, so they are ready before the level is).
    const double inv_w = 1.0 / base.width(), inv_h = 1.0 / base.height();
    auto at_level = [&](int lev) {
        const Image& img = pyr.level(lev);
        const double ks = img.width() * inv_w, kt = img.height() * inv_h;
        const EwaLevelResult e = ewa_level(img, u, v, as * ks, at * kt, bs * ks, bt * kt);
        r.texels_read += e.texels_read;
        return e.value;
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
