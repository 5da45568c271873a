#include <cmam/texture/area.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <thread>

#include "kernels.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cmam::texture {

namespace {
// Row j's prefix sums of (texel - mean) into `out` from entry 1 on (entry 0 stays 0): accumulated
// in double, stored as float. The channel count is a constant, so the sums stay in registers, and
// the row is read a tile row at a time (eight contiguous texels in Image's layout).
template <int NC>
void prefix_row(const Image& image, int j, const double* mean, float* out) {
    const int w = image.width();
    const float* row = image.row(j);
    double acc[NC];
    for (int c = 0; c < NC; ++c) acc[c] = 0;
    for (int i0 = 0; i0 < w; i0 += Image::kTile) {
        const float* t = row + Image::column_offset(i0) * NC;
        float* o = out + static_cast<std::size_t>(i0 + 1) * NC;
        const int n = std::min(Image::kTile, w - i0);
        for (int k = 0; k < n; ++k, t += NC, o += NC)
            for (int c = 0; c < NC; ++c) {
                acc[c] += double(t[c]) - mean[c];
                o[c] = static_cast<float>(acc[c]);
            }
    }
}
}  // namespace

RowPrefixTable::RowPrefixTable(const Image& image, OnDemand)
    : m_w(image.width()),
      m_h(image.height()),
      m_c(image.channels()),
      m_wrap_s(image.wrap_s()),
      m_wrap_t(image.wrap_t()),
      m_mean(image.mean()) {
    const bool margin = m_wrap_s == WrapMode::Repeat && m_wrap_t == WrapMode::Repeat &&
                        std::max(m_w, m_h) <= kMarginMaxSize;
    m_row_len = m_w + 1 + (margin ? kMarginKnots : 0);
    m_rows = m_h + (margin ? kMarginRows : 0);
    // A piece starting in texel k0 reads knots k0 to k0 + 2 (and, three channels to a vector, the
    // next knot's first): a walked edge stays below x = W, or with the margin three knots before
    // the row's end.
    m_walk_w = margin ? double(m_row_len - 3) : double(m_w);
    constexpr int kLineFloats = 64 / sizeof(float);
    int lines = (m_row_len * m_c + kLineFloats - 1) / kLineFloats;
    if (lines % 2 == 0) ++lines;
    m_stride = lines * kLineFloats;
    const std::size_t stride = static_cast<std::size_t>(m_stride);
    m_d = TexelBuffer(stride * static_cast<std::size_t>(m_rows), TexelBuffer::Unfilled{});
    m_source = &image;
    if (!margin) {
        m_band_count = (m_h + kBandRows - 1) / kBandRows;
        m_bands = std::make_unique<std::atomic<uint8_t>[]>(static_cast<std::size_t>(m_band_count));
        return;
    }
    build_rows(0, m_h);
    m_source = nullptr;
    for (int j = m_h; j < m_rows; ++j)  // the margin's rows: row j is row j mod H
        std::copy_n(m_d.data() + stride * static_cast<std::size_t>(j % m_h), stride,
                    m_d.data() + stride * static_cast<std::size_t>(j));
}

RowPrefixTable::RowPrefixTable(const Image& image) : RowPrefixTable(image, OnDemand{}) {
    build_all();
    m_source = nullptr;
    m_bands.reset();
    m_band_count = 0;
}

RowPrefixTable::RowPrefixTable(const RowPrefixTable& other)
    : m_w(other.m_w),
      m_h(other.m_h),
      m_c(other.m_c),
      m_wrap_s(other.m_wrap_s),
      m_wrap_t(other.m_wrap_t),
      m_mean(other.m_mean),
      m_row_len(other.m_row_len),
      m_rows(other.m_rows),
      m_walk_w(other.m_walk_w),
      m_stride(other.m_stride) {
    other.build_all();
    m_d = other.m_d;
}

RowPrefixTable& RowPrefixTable::operator=(const RowPrefixTable& other) {
    if (this != &other) *this = RowPrefixTable(other);
    return *this;
}

// Rows j0 to j1 - 1 from the source image: entry 0 is 0, then the prefix sums, then the
// margin's knots.
void RowPrefixTable::build_rows(int j0, int j1) const {
    const std::size_t stride = static_cast<std::size_t>(m_stride);
    const double mean[4] = {m_mean[0], m_mean[1], m_mean[2], m_mean[3]};
    for (int j = j0; j < j1; ++j) {
        float* row = m_d.data() + stride * static_cast<std::size_t>(j);
        detail::with_channels(m_c, [&]<int NC>() {
            for (int c = 0; c < NC; ++c) row[c] = 0;
            prefix_row<NC>(*m_source, j, mean, row);
            // The margin's knots: R(k) with Repeat's extension, R(q W + r) = q D[W] + D[r].
            for (int k = m_w + 1; k < m_row_len; ++k) {
                double r[NC] = {};  // (knot writes all of them)
                knot<NC>(row, k, r);
                for (int c = 0; c < NC; ++c)
                    row[std::size_t(k) * NC + c] = static_cast<float>(r[c]);
            }
        });
        // The padding: read (times a zero weight) past a row's last knot.
        std::fill(row + std::size_t(m_row_len) * m_c, row + stride, 0.0f);
    }
}

void RowPrefixTable::build_band(int64_t b) const {
    std::atomic<uint8_t>& state = m_bands[static_cast<std::size_t>(b)];
    uint8_t expected = 0;
    if (state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
        const int j0 = static_cast<int>(b) * kBandRows;
        build_rows(j0, std::min(j0 + kBandRows, m_h));
        state.store(2, std::memory_order_release);
        return;
    }
    while (state.load(std::memory_order_acquire) != 2) std::this_thread::yield();
}

inline void RowPrefixTable::ensure_band(int64_t b) const {
    if (m_bands[static_cast<std::size_t>(b)].load(std::memory_order_acquire) != 2) [[unlikely]]
        build_band(b);
}

// A piece in row j reads that row's knots and, at most, the first entry of the row stored
// after it (EdgeWalk::piece), so that row is built too.
void RowPrefixTable::ensure_rows(double y0, double y1) const {
    const int64_t j0 = floor_to_int(y0), j1 = floor_to_int(y1);
    if (j0 >= 0 && j1 < m_h) [[likely]] {
        const int64_t last = std::min<int64_t>(j1 + 1, m_h - 1) / kBandRows;
        for (int64_t b = j0 / kBandRows; b <= last; ++b) ensure_band(b);
        return;
    }
    if (j1 - j0 + 1 >= m_h) {
        build_all();
        return;
    }
    for (int64_t j = j0; j <= j1; ++j) {
        const int64_t jj = wrap_index(j, m_h, m_wrap_t);
        if (jj < 0) continue;  // a Black row: nothing read
        ensure_band(jj / kBandRows);
        if (jj + 1 < m_h) ensure_band((jj + 1) / kBandRows);
    }
}

void RowPrefixTable::build_all() const {
    for (int b = 0; b < m_band_count; ++b) ensure_band(b);
}

std::size_t RowPrefixTable::memory_bytes() const {
    if (!m_bands) return m_d.size() * sizeof(float);
    int rows = 0;
    for (int b = 0; b < m_band_count; ++b)
        if (m_bands[static_cast<std::size_t>(b)].load(std::memory_order_acquire) == 2)
            rows += std::min(kBandRows, m_h - b * kBandRows);
    return static_cast<std::size_t>(rows) * static_cast<std::size_t>(m_stride) * sizeof(float);
}

namespace {

// Room for up to eight values, left uninitialised: an array of Vec2d (whose members have
// initialisers) would be zeroed on every lookup, a measurable part of a small region's cost.
template <class T>
union Uninit8 {
    T v[8];
    Uninit8() {}
};

// The multiple of an axis's period (n texels for repeat, 2n for mirror; none for clamp and black)
// that moves x (|x| < 2^30) into the base period. A power-of-two period (most textures) divides
// by multiplying with 2^-k, which is exact: the same quotient without a division's latency
// ahead of every texel index of the lookup.
double period_shift(double x, int n, WrapMode mode) {
    if (mode != WrapMode::Repeat && mode != WrapMode::Mirror) return 0;
    const uint64_t period = mode == WrapMode::Repeat ? uint64_t(n) : 2 * uint64_t(n);
    double q;
    if ((period & (period - 1)) == 0)
        q = x * std::bit_cast<double>(uint64_t(1023 - std::countr_zero(period)) << 52);
    else
        q = x / double(period);
    return double(floor_to_int(q)) * double(period);
}

// ceil(x) for 0 <= x < 2^62, inline (std::ceil is a library call without SSE4.1, and every edge
// takes one). Only the SSE2 walks use it.
[[maybe_unused]] inline int64_t ceil_nonneg(double x) {
    const auto i = static_cast<int64_t>(x);
    return i + (static_cast<double>(i) < x ? 1 : 0);
}

int64_t floor_div(int64_t a, int64_t b) {  // b > 0
    int64_t q = a / b;
    return q - ((a % b != 0) && (a < 0) ? 1 : 0);
}

// Adds the integral of R over [lo, hi] to `out`, for 0 <= lo <= hi and floor(hi) < W (every
// knot read is in the table): R is linear within each texel, so partial texels at both ends
// take their midpoint value times their length, and whole ones (R(k) + R(k+1)) / 2.
template <int NC>
[[gnu::always_inline]] inline void integral_inside(const float* row, double lo, double hi,
                                                   double* out) {
    const int64_t k0 = static_cast<int64_t>(lo), kend = static_cast<int64_t>(hi);  // floors
    const float* d = row + k0 * NC;
    const double b0 = std::min(hi, double(k0 + 1)), f0 = 0.5 * (lo + b0) - double(k0);
    for (int c = 0; c < NC; ++c) out[c] += (b0 - lo) * (d[c] + f0 * (d[NC + c] - d[c]));
    if (kend == k0) return;
    double mid[NC];
    for (int c = 0; c < NC; ++c) mid[c] = 0;
    for (int64_t k = k0 + 1; k < kend; ++k) {
        const float* e = row + k * NC;
        for (int c = 0; c < NC; ++c) mid[c] += double(e[c]) + e[NC + c];
    }
    const double w1 = hi - double(kend), f1 = 0.5 * w1;
    const float* e = row + kend * NC;
    for (int c = 0; c < NC; ++c) out[c] += 0.5 * mid[c] + w1 * (e[c] + f1 * (e[NC + c] - e[c]));
}

}  // namespace

// R(k): the row integral from 0 to the integer k (unwrapped), with the wrap modes' extension.
// Inside [0,W] it is the table; Repeat adds whole periods; Mirror's period is 2W with the second
// half read backwards; Clamp continues with the edge texel; Black continues with zero texels,
// i.e. with -mean in the table's offset units.
template <int NC>
void RowPrefixTable::knot(const float* row, int64_t k, double* out) const {
    const int64_t W = m_w;
    if (k >= 0 && k <= W) {
        for (int c = 0; c < NC; ++c) out[c] = row[k * NC + c];
        return;
    }
    switch (m_wrap_s) {
        case WrapMode::Repeat: {
            const int64_t q = floor_div(k, W), r = k - q * W;
            for (int c = 0; c < NC; ++c) out[c] = double(q) * row[W * NC + c] + row[r * NC + c];
            return;
        }
        case WrapMode::Mirror: {
            const int64_t q = floor_div(k, 2 * W), r = k - q * 2 * W;
            for (int c = 0; c < NC; ++c) {
                const double full = row[W * NC + c];
                out[c] = 2 * double(q) * full +
                         (r <= W ? double(row[r * NC + c]) : 2 * full - row[(2 * W - r) * NC + c]);
            }
            return;
        }
        case WrapMode::Clamp:
            for (int c = 0; c < NC; ++c)
                out[c] = k < 0 ? double(k) * (row[NC + c] - row[c])
                               : row[W * NC + c] +
                                     double(k - W) * (row[W * NC + c] - row[(W - 1) * NC + c]);
            return;
        case WrapMode::Black:
            for (int c = 0; c < NC; ++c)
                out[c] =
                    k < 0 ? -m_mean[c] * double(k) : row[W * NC + c] - m_mean[c] * double(k - W);
            return;
    }
}

// Clamp and Black: the integral of R over [a,b] where it lies outside [0,W], in closed form (R
// is linear there), so a region far beyond the texture costs nothing per texel.
template <int NC>
void RowPrefixTable::outside_integral(const float* row, double a, double b, double* out) const {
    const double W = m_w;
    for (int c = 0; c < NC; ++c) out[c] = 0;
    if (a < 0) {  // R(x) = x s on x <= 0
        const double e = std::min(b, 0.0);
        for (int c = 0; c < NC; ++c) {
            const double s =
                m_wrap_s == WrapMode::Clamp ? double(row[NC + c]) - row[c] : -m_mean[c];
            out[c] += s * (e * e - a * a) / 2;
        }
    }
    if (b > W) {  // R(x) = D[W] + (x - W) s on x >= W
        const double e = std::max(a, W);
        for (int c = 0; c < NC; ++c) {
            const double dw = row[m_w * NC + c];
            const double s =
                m_wrap_s == WrapMode::Clamp ? dw - row[(m_w - 1) * NC + c] : -m_mean[c];
            out[c] += dw * (b - e) + s * ((b - W) * (b - W) - (e - W) * (e - W)) / 2;
        }
    }
}

// The integral over a boundary piece within row j, from (x0, y0) to (x1, y1) with h = y1 - y0:
// x is linear in y, so it is h times the mean of R_j over [x0,x1]. R_j is linear within each
// texel: a piece within one texel takes its midpoint value; a longer one sums its texels' exact
// trapezoids, times h / (x1 - x0) (`h_per_x`, the same along the edge).
template <int NC>
void RowPrefixTable::row_piece(int64_t j, double x0, double x1, double h, double h_per_x,
                               double* acc) const {
    const int64_t jj = j >= 0 && j < m_h ? j : wrap_index(j, m_h, m_wrap_t);
    if (jj < 0) {  // Black rows: zero texels, R(x) = -mean x
        for (int c = 0; c < NC; ++c) acc[c] -= h * m_mean[c] * 0.5 * (x0 + x1);
        return;
    }
    const float* row = m_d.data() + static_cast<std::size_t>(jj) * m_stride;
    if (x0 > x1) std::swap(x0, x1);
    const int64_t k0 = floor_to_int(x0);
    double ra[NC], rb[NC];
    if (x1 <= double(k0 + 1)) {  // within one texel: R is linear, its mean the midpoint value
        const double f = 0.5 * (x0 + x1) - double(k0);
        if (k0 >= 0 && k0 < m_w) {
            const float* d = row + k0 * NC;
            for (int c = 0; c < NC; ++c) acc[c] += h * (d[c] + f * (d[NC + c] - d[c]));
            return;
        }
        knot<NC>(row, k0, ra);
        knot<NC>(row, k0 + 1, rb);
        for (int c = 0; c < NC; ++c) acc[c] += h * (ra[c] + f * (rb[c] - ra[c]));
        return;
    }
    double sum[NC];
    for (int c = 0; c < NC; ++c) sum[c] = 0;
    double lo = x0, hi = x1;
    if (m_wrap_s == WrapMode::Clamp || m_wrap_s == WrapMode::Black) {
        if (lo < 0 || hi > m_w) outside_integral<NC>(row, lo, hi, sum);
        lo = std::max(lo, 0.0);
        hi = std::min(hi, double(m_w));
    }
    if (lo < hi) {
        int64_t k = floor_to_int(lo);
        const int64_t kend = floor_to_int(hi);  // the last texel is [kend, hi] (may be empty)
        // First and last texels are partial; those between are whole: (R(k) + R(k+1)) / 2.
        auto partial = [&](int64_t kk, double a, double b, const double* r0, const double* r1) {
            const double f = 0.5 * (a + b) - double(kk);
            for (int c = 0; c < NC; ++c) sum[c] += (b - a) * (r0[c] + f * (r1[c] - r0[c]));
        };
        if (k >= 0 && kend < m_w) {  // inside the table: direct reads
            integral_inside<NC>(row, lo, hi, sum);
        } else if (m_wrap_s == WrapMode::Repeat) {
            // Across a period: R(q W + r) = q D[W] + D[r], stepping r without dividing.
            const int64_t W = m_w;
            int64_t q = floor_div(k, W), r = k - q * W;
            for (int c = 0; c < NC; ++c) ra[c] = double(q) * row[W * NC + c] + row[r * NC + c];
            for (; double(k) < hi; ++k) {
                if (++r > W) {
                    r = 1;
                    ++q;
                }
                for (int c = 0; c < NC; ++c) rb[c] = double(q) * row[W * NC + c] + row[r * NC + c];
                partial(k, std::max(lo, double(k)), std::min(hi, double(k + 1)), ra, rb);
                for (int c = 0; c < NC; ++c) ra[c] = rb[c];
            }
        } else {  // mirror across a period, or an edge: knots with the extension
            knot<NC>(row, k, ra);
            for (; double(k) < hi; ++k) {
                knot<NC>(row, k + 1, rb);
                partial(k, std::max(lo, double(k)), std::min(hi, double(k + 1)), ra, rb);
                for (int c = 0; c < NC; ++c) ra[c] = rb[c];
            }
        }
    }
    for (int c = 0; c < NC; ++c) acc[c] += h_per_x * sum[c];
}

#if defined(__SSE2__)
namespace {
// A knot's channels as one float vector: a 3-channel knot's fourth lane is the next knot's first
// channel, or the table's slack, never used; one or two channels leave the other lanes zero.
template <int NC>
inline __m128 knot4(const float* d) {
    if constexpr (NC == 1) return _mm_load_ss(d);
    if constexpr (NC == 2)
        return _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(d)));
    return _mm_loadu_ps(d);
}

// A piece spanning at most one knot, lane by lane: h m0 + w (m1 - m0), with m0 the mean of knots
// d0, d1 at fraction f0 and m1 that of d1, d2 at f1 (EdgeWalk::piece's short formula).
[[gnu::always_inline]] inline __m128 short_piece(__m128 d0, __m128 d1, __m128 d2, __m128 f0,
                                                 __m128 f1, __m128 h, __m128 w) {
    const __m128 m0 = _mm_add_ps(d0, _mm_mul_ps(f0, _mm_sub_ps(d1, d0)));
    const __m128 m1 = _mm_add_ps(d1, _mm_mul_ps(f1, _mm_sub_ps(d2, d1)));
    return _mm_add_ps(_mm_mul_ps(h, m0), _mm_mul_ps(w, _mm_sub_ps(m1, m0)));
}

// The walk of one edge within the table (p.v < q.v, `sign` its direction), row by row: the
// first row's piece (from p to the next row's line, or to q), whole rows of height one, then the
// last row's piece to q. Each piece adds its height times the mean of R_j over its x-span (the
// midpoint value within one texel; partial end texels and whole ones between otherwise, times
// `h_per_x`), with the channels as one vector: each piece's value in float (the table's
// precision), added to double sums. Every channel count takes this path, so a channel's result
// does not depend on how many there are. `Guard`: the edge may end on the table's right edge
// x = W (a part of an edge split there), where a position rounded to W would read two knots
// past the row; a piece then starts in texel W - 1 at the latest.
//
// A steep edge (|dx/dy| < 0.999: each row's piece spans at most one knot) is walked whole by
// walk_steep, four rows a group with a row per float lane, its first and last rows included.
template <int NC, bool Guard = false>
struct EdgeWalk {
    const float* row;
    std::size_t stride;
    Vec2d p, q;
    double dxdy, h_per_x, sign;
    int64_t j, j_last;
    bool one_row;
    double x, xnext;
    __m128 h_row;
    struct Sum {
        __m128d lo = _mm_setzero_pd(), hi = _mm_setzero_pd();  // channels 0-1, 2-3
    };
    Sum acc;
    int64_t k_last = 0;  // Guard: W - 1

    // A piece's value (its channels in float lanes) added to a double sum.
    [[gnu::always_inline]] static void add(Sum& sum, __m128 v) {
        sum.lo = _mm_add_pd(sum.lo, _mm_cvtps_pd(v));
        if constexpr (NC > 2) sum.hi = _mm_add_pd(sum.hi, _mm_cvtps_pd(_mm_movehl_ps(v, v)));
    }

    EdgeWalk(const float* table, std::size_t stride_, Vec2d p_, Vec2d q_, double sign_,
             double dxdy_, double h_per_x_, int64_t width = 0)
        : stride(stride_), p(p_), q(q_), dxdy(dxdy_), h_per_x(h_per_x_), sign(sign_) {
        k_last = width - 1;
        j = floor_to_int(p.v);
        j_last = ceil_nonneg(q.v) - 1;  // >= j, as q.v > p.v
        one_row = j == j_last;
        row = table + static_cast<std::size_t>(j) * stride;
        h_row = _mm_set1_ps(static_cast<float>(sign));
        x = p.u;
        xnext = p.u;
    }
    // Whole rows' pieces span |dxdy| texels: at most one knot when |dxdy| < 1 (below one with a
    // margin for the rounding of xnext), and then they take no branch.
    bool steep() const { return std::abs(dxdy) < 0.999; }

    // The piece of the current row from xa to xb, of height h (hv: h as a float vector).
    [[gnu::always_inline]] void piece(double xa, double xb, __m128 hv, Sum& sum_to) {
        const double x0 = std::min(xa, xb), x1 = std::max(xa, xb);
        int64_t k0 = static_cast<int64_t>(x0);  // x0 >= 0: truncation is floor
        if constexpr (Guard) k0 = std::min(k0, k_last);
        const float* d = row + k0 * NC;
        if (x1 <= double(k0 + 2)) {
            // Within texel k0, or into the next one by l1: the span's first part [x0, b0] has
            // mean m0, the rest m1, so the piece is h_per_x ((b0 − x0) m0 + l1 m1) =
            // h m0 + h_per_x l1 (m1 − m0), which is h m0 when l1 = 0 (no branch between the two).
            // Knot k0 + 2 is read even then: at most one past the row, the next row's first
            // entry or the buffer's slack, finite either way.
            const double b0 = std::min(x1, double(k0 + 1)), l1 = x1 - b0;
            const __m128 f0 = _mm_set1_ps(static_cast<float>(0.5 * (x0 + b0) - double(k0))),
                         f1 = _mm_set1_ps(static_cast<float>(0.5 * l1));
            add(sum_to, short_piece(knot4<NC>(d), knot4<NC>(d + NC), knot4<NC>(d + 2 * NC), f0, f1,
                                    hv, _mm_set1_ps(static_cast<float>(h_per_x * l1))));
        } else {  // partial first and last texels, whole ones between
            alignas(16) double sum[4] = {0, 0, 0, 0};
            integral_inside<NC>(row, x0, x1, sum);
            sum_to.lo = _mm_add_pd(sum_to.lo, _mm_mul_pd(_mm_set1_pd(h_per_x), _mm_load_pd(sum)));
            if constexpr (NC > 2)
                sum_to.hi =
                    _mm_add_pd(sum_to.hi, _mm_mul_pd(_mm_set1_pd(h_per_x), _mm_load_pd(sum + 2)));
        }
    }
    // The first row's piece; the walk is then at the first whole row.
    void first() {
        if (one_row) {
            piece(p.u, q.u, _mm_set1_ps(static_cast<float>(sign * (q.v - p.v))), acc);
            return;
        }
        xnext = p.u + (double(j + 1) - p.v) * dxdy;
        piece(x, xnext, _mm_set1_ps(static_cast<float>(sign * (double(j + 1) - p.v))), acc);
        ++j;
        row += stride;
    }
    // One whole row (j < j_last) of a shallow edge.
    void step() {
        x = xnext;
        xnext = p.u + (double(j + 1) - p.v) * dxdy;
        piece(x, xnext, h_row, acc);
        ++j;
        row += stride;
    }
    // A steep edge, all of it (its first and last rows' pieces too), four rows a group, a row a
    // float lane. Row r (from row j) spans [yt, yb] = [max(r, c), min(r + 1, e)], with c and e
    // the edge's ends in rows from j: whole rows have height exactly one, the first and last
    // their partial heights, rows past the last yt = yb = e and height and width zero. Its
    // x-span follows from x = xp + (y - c) dxdy, counted from the edge's leftmost texel kb, in
    // float (an edge of at most kSteepRows rows keeps x under about 2^6, within about 1e-6
    // texel, below the table's own rounding). Every piece spans at most one knot (|dxdy| <
    // 0.999): piece's short formula in float, h m0 + h_per_x l1 (m1 - m0). Row r adds to
    // partial sum r mod 4 (in double), the four added ((0 + 2) + (1 + 3)) at the end: one
    // channel does a group's four rows in the four lanes at once, more channels the rows one
    // after another with the same lane arithmetic, so a channel's value is the same whatever
    // the texture's channel count.
    [[gnu::always_inline]] void walk_steep(double* out) {
        const int64_t kb = static_cast<int64_t>(std::min(p.u, q.u));  // >= 0: the floor
        const int64_t n_rows = j_last - j + 1;
        const float* base = row + kb * NC;  // row j, texel kb
        const __m128 c = _mm_set1_ps(static_cast<float>(p.v - double(j))),
                     e = _mm_set1_ps(static_cast<float>(q.v - double(j))),
                     xp = _mm_set1_ps(static_cast<float>(p.u - double(kb))),
                     d = _mm_set1_ps(static_cast<float>(dxdy)),
                     hpx = _mm_set1_ps(static_cast<float>(h_per_x)),
                     sg = _mm_set1_ps(static_cast<float>(sign)), one = _mm_set1_ps(1),
                     half = _mm_set1_ps(0.5f), four = _mm_set1_ps(4);
        const __m128i k_max = _mm_set1_epi32(static_cast<int32_t>(k_last - kb));
        __m128 r = _mm_setr_ps(0, 1, 2, 3);
        Sum part[4];  // partial sums by row mod 4
        const std::ptrdiff_t row_step = static_cast<std::ptrdiff_t>(stride);
        const float* group_row = base;  // the group's first row, texel kb
        for (int64_t i = 0; i < n_rows; i += 4) {
            const __m128 yt = _mm_min_ps(_mm_max_ps(r, c), e),
                         yb = _mm_min_ps(_mm_max_ps(_mm_add_ps(r, one), c), e);
            r = _mm_add_ps(r, four);
            const __m128 xt = _mm_add_ps(xp, _mm_mul_ps(_mm_sub_ps(yt, c), d)),
                         xb = _mm_add_ps(xp, _mm_mul_ps(_mm_sub_ps(yb, c), d));
            const __m128 x0 = _mm_min_ps(xt, xb), x1 = _mm_max_ps(xt, xb);
            __m128i k0 = _mm_cvttps_epi32(x0);  // x0 >= 0 (or a rounding below): the floor
            if constexpr (Guard) {
                const __m128i over = _mm_cmpgt_epi32(k0, k_max);
                k0 = _mm_or_si128(_mm_and_si128(over, k_max), _mm_andnot_si128(over, k0));
            }
            const __m128 dk = _mm_cvtepi32_ps(k0);
            const __m128 b0 = _mm_min_ps(x1, _mm_add_ps(dk, one)), l1 = _mm_sub_ps(x1, b0);
            const __m128 f0 = _mm_sub_ps(_mm_mul_ps(half, _mm_add_ps(x0, b0)), dk),
                         f1 = _mm_mul_ps(half, l1), w = _mm_mul_ps(hpx, l1),
                         h = _mm_mul_ps(sg, _mm_sub_ps(yb, yt));
            // The lanes' first knots (rows past the last read the last row: they add zero),
            // from the group's first row: the rows' offsets are whole multiples of the stride,
            // the knots' (k0 NC) come from one vector.
            __m128i kn = k0;
            if constexpr (NC == 2) kn = _mm_add_epi32(k0, k0);
            if constexpr (NC == 3) kn = _mm_add_epi32(_mm_add_epi32(k0, k0), k0);
            if constexpr (NC == 4) kn = _mm_slli_epi32(k0, 2);
            alignas(16) int32_t k[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(k), kn);
            const float* at[4];
            if (i + 4 <= n_rows) [[likely]] {
                for (int l = 0; l < 4; ++l) at[l] = group_row + l * row_step + k[l];
            } else {
                for (int l = 0; l < 4; ++l)
                    at[l] = group_row + std::min<int64_t>(l, n_rows - 1 - i) * row_step + k[l];
            }
            group_row += 4 * row_step;
            if constexpr (NC == 1) {
                // Knots k0, k0 + 1 of each row in one load, k0 + 2 in another, transposed.
                auto pair = [](const float* q) {
                    return _mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(q)));
                };
                const __m128 p01 = _mm_unpacklo_ps(pair(at[0]), pair(at[1])),
                             p23 = _mm_unpacklo_ps(pair(at[2]), pair(at[3]));
                const __m128 d0 = _mm_movelh_ps(p01, p23), d1 = _mm_movehl_ps(p23, p01);
                const __m128 d2 =
                    _mm_movelh_ps(_mm_unpacklo_ps(_mm_load_ss(at[0] + 2), _mm_load_ss(at[1] + 2)),
                                  _mm_unpacklo_ps(_mm_load_ss(at[2] + 2), _mm_load_ss(at[3] + 2)));
                const __m128 v = short_piece(d0, d1, d2, f0, f1, h, w);
                part[0].lo = _mm_add_pd(part[0].lo, _mm_cvtps_pd(v));  // rows 0 and 1: lanes
                part[1].lo = _mm_add_pd(part[1].lo, _mm_cvtps_pd(_mm_movehl_ps(v, v)));
            } else {
                alignas(16) float lf0[4], lf1[4], lw[4], lh[4];
                _mm_store_ps(lf0, f0);
                _mm_store_ps(lf1, f1);
                _mm_store_ps(lw, w);
                _mm_store_ps(lh, h);
                const int lanes = static_cast<int>(std::min<int64_t>(4, n_rows - i));
                for (int l = 0; l < lanes; ++l)
                    add(part[l],
                        short_piece(knot4<NC>(at[l]), knot4<NC>(at[l] + NC),
                                    knot4<NC>(at[l] + 2 * NC), _mm_set1_ps(lf0[l]),
                                    _mm_set1_ps(lf1[l]), _mm_set1_ps(lh[l]), _mm_set1_ps(lw[l])));
            }
        }
        alignas(16) double sum[4];
        if constexpr (NC == 1) {
            // part[0].lo holds rows 0 and 1 mod 4 (lanes), part[1].lo rows 2 and 3.
            const __m128d t = _mm_add_pd(part[0].lo, part[1].lo);  // (0 + 2, 1 + 3)
            _mm_store_pd(sum, t);
            out[0] += sum[0] + sum[1];
        } else {
            _mm_store_pd(sum, _mm_add_pd(_mm_add_pd(part[0].lo, part[2].lo),
                                         _mm_add_pd(part[1].lo, part[3].lo)));
            _mm_store_pd(sum + 2, _mm_add_pd(_mm_add_pd(part[0].hi, part[2].hi),
                                             _mm_add_pd(part[1].hi, part[3].hi)));
            for (int cc = 0; cc < NC; ++cc) out[cc] += sum[cc];
        }
    }
    // The last row's piece (none when first() had the whole edge); the sums into `out`.
    void finish(double* out) {
        if (!one_row)
            piece(xnext, q.u, _mm_set1_ps(static_cast<float>(sign * (q.v - double(j)))), acc);
        alignas(16) double sum[4];
        _mm_store_pd(sum, acc.lo);
        _mm_store_pd(sum + 2, acc.hi);
        for (int c = 0; c < NC; ++c) out[c] += sum[c];
    }
    // The most rows walk_steep takes in one frame; a longer steep edge (the level rule's regions
    // have at most 32 rows an edge; other polygons may have more) is walked as parts of this many.
    static constexpr int64_t kSteepRows = 64;
    [[gnu::noinline]] void walk_steep_parts(double* out) const {
        for (int64_t j0 = j; j0 <= j_last; j0 += kSteepRows) {
            const double ya = std::max(p.v, double(j0)),
                         yz = std::min(q.v, double(j0 + kSteepRows));
            const Vec2d a{ya == p.v ? p.u : p.u + (ya - p.v) * dxdy, ya},
                z{yz == q.v ? q.u : p.u + (yz - p.v) * dxdy, yz};
            EdgeWalk(row - j * static_cast<int64_t>(stride), stride, a, z, sign, dxdy, h_per_x,
                     k_last + 1)
                .walk_steep(out);
        }
    }
    void walk(double* out) {
        if (steep()) {
            if (j_last - j < kSteepRows) [[likely]]
                walk_steep(out);
            else
                walk_steep_parts(out);
            return;
        }
        first();
        while (j < j_last) step();
        finish(out);
    }
};

}  // namespace
#endif

// An edge from p to q (p.v < q.v, `sign` its direction) that lies within the table: cut at every
// row it crosses, each piece adds its height times the mean of R_j over its x-span (the midpoint
// value within one texel; partial end texels and whole ones between otherwise, times
// `h_per_x`).
template <int NC>
[[gnu::always_inline]] inline void RowPrefixTable::edge_inside(Vec2d p, Vec2d q, double sign,
                                                               double dxdy, double h_per_x,
                                                               double* acc) const {
    const std::size_t stride = static_cast<std::size_t>(m_stride);
#if defined(__SSE2__)
    EdgeWalk<NC>(m_d.data(), stride, p, q, sign, dxdy, h_per_x).walk(acc);
#else
    double y = p.v, x = p.u;
    int64_t j = floor_to_int(y);
    const float* row = m_d.data() + static_cast<std::size_t>(j) * stride;
    while (y < q.v) {
        const double ynext = std::min(double(j + 1), q.v);
        const double xnext = ynext == q.v ? q.u : p.u + (ynext - p.v) * dxdy;
        const double h = sign * (ynext - y);
        const double x0 = std::min(x, xnext), x1 = std::max(x, xnext);
        const int64_t k0 = static_cast<int64_t>(x0);  // x0 >= 0: truncation is floor
        const float* d = row + k0 * NC;
        if (x1 <= double(k0 + 2)) {
            // Within texel k0, or into the next one by l1: the span's first part [x0, b0] has
            // mean m0, the rest m1, so the piece is h_per_x ((b0 − x0) m0 + l1 m1) =
            // h m0 + h_per_x l1 (m1 − m0), which is h m0 when l1 = 0 (no branch between the two).
            // Knot k0 + 2 is read even then: at most one past the row, the next row's first
            // entry or the buffer's slack, finite either way.
            const double b0 = std::min(x1, double(k0 + 1)), l1 = x1 - b0;
            const double f0 = 0.5 * (x0 + b0) - double(k0), f1 = 0.5 * l1, w = h_per_x * l1;
            for (int c = 0; c < NC; ++c) {
                const double m0 = d[c] + f0 * (d[NC + c] - d[c]);
                const double m1 = d[NC + c] + f1 * (d[2 * NC + c] - d[NC + c]);
                acc[c] += h * m0 + w * (m1 - m0);
            }
        } else {  // partial first and last texels, whole ones between
            double sum[NC];
            for (int c = 0; c < NC; ++c) sum[c] = 0;
            integral_inside<NC>(row, x0, x1, sum);
            for (int c = 0; c < NC; ++c) acc[c] += h_per_x * sum[c];
        }
        y = ynext;
        x = xnext;
        ++j;
        row += stride;
    }
#endif
}

#if defined(__SSE2__)
// An edge (p.v < q.v) of a region on a texture that repeats, within [0, 2W) x [0, 2H] after the
// region's shift to the base period (most edges that leave the table do so by less than a
// period): cut where it crosses x = W and y = H, each part moved back into the table by whole
// periods and walked like an edge inside it. Rows repeat along t, so a part above H is the same
// rows H lower. Along s, R(x) = D[W] + R(x - W) beyond W, so a part beyond W adds, besides its
// walk, its height in each row times that row's total D[W].
template <int NC>
void RowPrefixTable::edge_split(Vec2d p, Vec2d q, double sign, double dxdy, double h_per_x,
                                double* acc) const {
    const double W = m_w, H = m_h;
    const std::size_t stride = static_cast<std::size_t>(m_stride);
    // The cut points, in order along the edge (t its parameter): exactly on their lines.
    struct Cut {
        double t;
        Vec2d at;
    };
    Cut cuts[4];
    int n = 0;
    cuts[n++] = {0, p};
    if (p.v < H && q.v > H) cuts[n++] = {(H - p.v) / (q.v - p.v), {p.u + (H - p.v) * dxdy, H}};
    if (std::min(p.u, q.u) < W && std::max(p.u, q.u) > W) {
        const double t = (W - p.u) / (q.u - p.u);
        cuts[n++] = {t, {W, p.v + t * (q.v - p.v)}};
        if (n == 3 && cuts[2].t < cuts[1].t) std::swap(cuts[1], cuts[2]);
    }
    cuts[n++] = {1, q};
    for (int k = 0; k + 1 < n; ++k) {
        const Vec2d a = cuts[k].at, b = cuts[k + 1].at;
        if (!(b.v > a.v)) continue;  // no height (or a rounding-sized inversion): nothing
        const double sx = 0.5 * (a.u + b.u) >= W ? W : 0, sy = 0.5 * (a.v + b.v) >= H ? H : 0;
        // Moved into the table. A cut computed on one line lies on the other to within rounding,
        // so when the edge passes (about) through the corner (W, H) a part's end can be a
        // rounding's width outside the table: it is put back on the table's edge.
        const Vec2d a1{std::clamp(a.u - sx, 0.0, W), std::clamp(a.v - sy, 0.0, H)},
            b1{std::clamp(b.u - sx, 0.0, W), std::clamp(b.v - sy, 0.0, H)};
        if (!(b1.v > a1.v)) continue;
        EdgeWalk<NC, true>(m_d.data(), stride, a1, b1, sign, dxdy, h_per_x, m_w).walk(acc);
        if (sx == 0) continue;
        // The row totals D_j[W] times the part's height in each row.
        int64_t j = floor_to_int(a1.v);
        const int64_t j_last = ceil_nonneg(b1.v) - 1;
        const float* total = m_d.data() + static_cast<std::size_t>(j) * stride + m_w * NC;
        double sum[NC];
        for (int c = 0; c < NC; ++c) sum[c] = 0;
        for (; j <= j_last; ++j, total += stride) {
            const double h = std::min(b1.v, double(j + 1)) - std::max(a1.v, double(j));
            for (int c = 0; c < NC; ++c) sum[c] += h * total[c];
        }
        for (int c = 0; c < NC; ++c) acc[c] += sign * sum[c];
    }
}
#endif

// Green's theorem: the area integral of T is the boundary integral of R(x,y) dy, where R is the
// row integral from 0 to x (algorithms.md §5.2). Each edge is cut where it crosses a texel row;
// on a piece within row j, x is linear in y, so the piece's integral is its height times the
// mean of R_j over the piece's x-span. Clamp and Black rows beyond the texture are one piece.
template <int NC>
void RowPrefixTable::integrate(const Vec2d* v, int n, double* acc) const {
    // Every edge's slopes first: their divisions do not depend on each other and overlap.
    struct Edge {
        Vec2d p, q;  // p.v < q.v
        double sign, dxdy, h_per_x;
    };
    Uninit8<Edge> buf;
    Edge* edges = buf.v;
    int m = 0;
    for (int e = 0; e < n; ++e) {
        Vec2d p = v[e], q = v[e + 1 < n ? e + 1 : 0];
        if (p.v == q.v) continue;  // no dy: no contribution
        double sign = 1;
        if (p.v > q.v) {
            std::swap(p, q);
            sign = -1;
        }
        const double dxdy = (q.u - p.u) / (q.v - p.v);
        const double h_per_x = q.u != p.u ? sign * std::abs((q.v - p.v) / (q.u - p.u)) : 0;
        edges[m++] = {p, q, sign, dxdy, h_per_x};
    }
    const bool far_rows = m_wrap_t == WrapMode::Clamp || m_wrap_t == WrapMode::Black;
#if defined(__SSE2__)
    // How far beyond the table an edge may reach and still be cut into parts inside it: a
    // period along a repeating axis, none along the others.
    const double split_u = m_wrap_s == WrapMode::Repeat ? 2.0 * m_w : m_w,
                 split_v = m_wrap_t == WrapMode::Repeat ? 2.0 * m_h : m_h;
#endif
    for (int e = 0; e < m; ++e) {
        const Edge& E = edges[e];
        const Vec2d p = E.p, q = E.q;
        const double u_lo = std::min(p.u, q.u), u_hi = std::max(p.u, q.u);
        if (p.v >= 0 && q.v <= m_rows && u_lo >= 0 && u_hi < m_walk_w) [[likely]] {
            // The common case, the edge within the table (its margin included): rows and knots
            // read directly.
            edge_inside<NC>(p, q, E.sign, E.dxdy, E.h_per_x, acc);
            continue;
        }
#if defined(__SSE2__)
        if (p.v >= 0 && q.v <= split_v && u_lo >= 0 && u_hi < split_u) {
            edge_split<NC>(p, q, E.sign, E.dxdy, E.h_per_x, acc);
            continue;
        }
#endif
        double y = p.v, x = p.u;
        while (y < q.v) {
            const int64_t j = floor_to_int(y);
            double ynext;
            if (far_rows && j < 0)
                ynext = std::min(0.0, q.v);
            else if (far_rows && j >= m_h)
                ynext = q.v;
            else
                ynext = std::min(double(j + 1), q.v);
            const double xnext = ynext == q.v ? q.u : p.u + (ynext - p.v) * E.dxdy;
            row_piece<NC>(j, x, xnext, E.sign * (ynext - y), E.h_per_x, acc);
            y = ynext;
            x = xnext;
        }
    }
}

Texel RowPrefixTable::integral(const Vec2d* v0, int n) const {
    Texel out{};
    if (n < 3) return out;
    n = std::min(n, 8);  // the filters' regions have three or four
    double area2 = 0;
    for (int i = 0; i < n; ++i) {
        area2 += cross(v0[i], v0[(i + 1) % n]);
    }
    const double area = std::abs(area2) / 2;
    constexpr double kMax = detail::kMaxTexelCoord;
    for (int i = 0; i < n; ++i)
        if (!(std::abs(v0[i].u) < kMax && std::abs(v0[i].v) < kMax)) {  // NaN included
            if (std::isfinite(area))
                for (int c = 0; c < m_c; ++c) out[c] = static_cast<float>(m_mean[c] * area);
            return out;
        }
    return integral_in_range(v0, n, area2);
}

Texel RowPrefixTable::integral_in_range(const Vec2d* v0, int n, double area2) const {
    Texel out{};
    Uninit8<Vec2d> buf;
    Vec2d* v = buf.v;
    n = std::min(n, 8);
    const double area = std::abs(area2) / 2;
    // Periodic modes: move the polygon to the base period (small knots, no cancellation).
    double xmin = v0[0].u, ymin = v0[0].v, ymax = v0[0].v;
    for (int i = 1; i < n; ++i) {
        xmin = std::min(xmin, v0[i].u);
        ymin = std::min(ymin, v0[i].v);
        ymax = std::max(ymax, v0[i].v);
    }
    const double sx = period_shift(xmin, m_w, m_wrap_s), sy = period_shift(ymin, m_h, m_wrap_t);
    for (int i = 0; i < n; ++i) v[i] = {v0[i].u - sx, v0[i].v - sy};
    if (m_bands) ensure_rows(ymin - sy, ymax - sy);
    double acc[4] = {0, 0, 0, 0};
    detail::with_channels(m_c, [&]<int NC>() { integrate<NC>(v, n, acc); });
    const double sign = area2 < 0 ? -1 : 1;
    for (int c = 0; c < m_c; ++c) out[c] = static_cast<float>(sign * acc[c] + m_mean[c] * area);
    return out;
}

namespace {

// The level rule (algorithms.md §5.2) for a region `width` level-0 texels wide (its area over
// its longest side) with perimeter `perimeter` there: the coarsest level where it is still
// kAreaMinWidth texels wide, or coarser until the perimeter is at most kAreaMaxPerimeter (on a
// level w x h of a W x H texture, at most max(w/W, h/H) times the level-0 perimeter).
double level_scale(const MipPyramid& pyr, int l, double W, double H) {
    return std::max(pyr.level(l).width() / W, pyr.level(l).height() / H);
}

int area_level(const FilteredTexture& tex, double width, double perimeter) {
    const MipPyramid& pyr = tex.pyramid();
    const int top = pyr.levels() - 1;
    int l = 0;
    if (width > 2 * kAreaMinWidth) l = std::min(top, detail::floor_log2(width / kAreaMinWidth));
    if (perimeter <= kAreaMaxPerimeter) return l;  // no level is larger than level 0
    const double W = tex.image().width(), H = tex.image().height();
    while (l < top && perimeter * level_scale(pyr, l, W, H) > kAreaMaxPerimeter) ++l;
    return l;
}

// Every corner within 2^30 texels and a finite, positive area.
bool within_range(const Vec2d* p, int n, double area) {
    constexpr double kMax = detail::kMaxTexelCoord;
    for (int i = 0; i < n; ++i)
        if (!(std::abs(p[i].u) < kMax && std::abs(p[i].v) < kMax)) return false;
    return area > 0 && std::isfinite(area);
}

// Integrates the polygon `p` (level-0 texels, signed area `area2` / 2, perimeter `perimeter`)
// on level l and returns its mean.
AreaResult integrate_on(const FilteredTexture& tex, int l, const Vec2d* p, int n, double area2,
                        double perimeter) {
    AreaResult r;
    r.level = l;
    r.area = std::abs(area2) / 2;
    const Image& img = tex.image();
    const MipPyramid& pyr = tex.pyramid();
    const Image& lev = l > 0 ? pyr.level(l) : img;
    const double kx = double(lev.width()) / img.width(), ky = double(lev.height()) / img.height();
    const double perimeter_l = perimeter * std::max(kx, ky);
    if (l == pyr.levels() - 1) [[unlikely]] {
        // The coarsest level: a periodic texture's integral over a region spanning many periods
        // is its mean (up to the boundary, 1/perimeter of it); a single texel is constant. With
        // one periodic axis and one clamped or black (the library allows it; a scene's "wrap"
        // sets both) the walk along the periodic axis is not bounded by the level rule (a fuzzed
        // region thousands of periods long took 1.5 s): beyond kAreaMaxPerimeter the mean too, an
        // approximation for such a region.
        auto periodic = [](WrapMode m) { return m == WrapMode::Repeat || m == WrapMode::Mirror; };
        const bool ps = periodic(img.wrap_s()), pt = periodic(img.wrap_t());
        if ((ps && pt && lev.width() == 1 && lev.height() == 1) ||
            ((ps || pt) && perimeter_l > kAreaMaxPerimeter)) {
            r.value = img.mean();
            r.knots = 1;
            return r;
        }
    }
    Uninit8<Vec2d> buf;
    Vec2d* q = buf.v;
    for (int i = 0; i < n; ++i) q[i] = {p[i].u * kx, p[i].v * ky};
    const Texel t = tex.row_prefix(l).integral_in_range(q, n, area2 * kx * ky);
    const double inv = 1 / (r.area * kx * ky);
    for (int c = 0; c < img.channels(); ++c) r.value[c] = static_cast<float>(t[c] * inv);
    // About the rows and columns the walk crosses. With neither axis periodic the parts beyond
    // the edges are closed forms (and rows beyond them one piece each): at most the level's own.
    const bool any_periodic = img.wrap_s() == WrapMode::Repeat ||
                              img.wrap_s() == WrapMode::Mirror ||
                              img.wrap_t() == WrapMode::Repeat || img.wrap_t() == WrapMode::Mirror;
    const double walked =
        any_periodic ? perimeter_l : std::min(perimeter_l, 2.0 * (lev.width() + lev.height()));
    r.knots = static_cast<int>(1.5 * walked) + 2 * n;
    return r;
}

// Gauss–Legendre product rules on the parallelogram's own coordinates: nodes on [-1/2, 1/2] and
// their weights, per coordinate.
template <int N>
struct GaussRule;
template <>
struct GaussRule<3> {
    static constexpr double x[3] = {-0.38729833462074170, 0, 0.38729833462074170};  // sqrt(3/5)/2
    static constexpr float w[3] = {5.0f / 18, 8.0f / 18, 5.0f / 18};
};
template <>
struct GaussRule<4> {
    static constexpr double x[4] = {-0.43056815579702629, -0.16999052179242813, 0.16999052179242813,
                                    0.43056815579702629};
    static constexpr float w[4] = {0.17392742256872693f, 0.32607257743127307f, 0.32607257743127307f,
                                   0.17392742256872693f};
};

template <>
struct GaussRule<5> {
    static constexpr double x[5] = {-0.45308992296933200, -0.26923465505284155, 0,
                                    0.26923465505284155, 0.45308992296933200};
    static constexpr float w[5] = {0.11846344252809454f, 0.23931433524968326f, 0.28444444444444444f,
                                   0.23931433524968326f, 0.11846344252809454f};
};

// The rules for a region whose longer side is `major` level-0 texels: the 3x3 rule up to
// kAreaRule4Lo, the 4x4 one from kAreaRule4Hi to kAreaRule5Lo, the 5x5 one from kAreaRule5Hi,
// each blended linearly into the next between (continuous in the size): rule `lo`, and the next
// one with weight w when w > 0.
struct RuleMix {
    int lo;
    double w;
    int largest() const { return w > 0 ? lo + 1 : lo; }
};
RuleMix rule_mix(double major) {
    if (major >= kAreaRule5Hi) return {5, 0};
    if (major > kAreaRule5Lo) return {4, (major - kAreaRule5Lo) / (kAreaRule5Hi - kAreaRule5Lo)};
    if (major >= kAreaRule4Hi) return {4, 0};
    if (major > kAreaRule4Lo) return {3, (major - kAreaRule4Lo) / (kAreaRule4Hi - kAreaRule4Lo)};
    return {3, 0};
}

#if defined(__SSE2__)
// A block of texels around the region, read once (wrapped per row and column). Texels of two to
// four channels are four lanes each (a 3-channel texel's fourth lane is the next float, unused;
// two channels leave the other lanes zero), so those channel counts have the same lane
// arithmetic; one channel is a float each (rule_sum_1).
template <int NC>
struct BlockTexel {
    using type = __m128;
};
template <>
struct BlockTexel<1> {
    using type = float;
};
template <int NC>
struct TexelBlock {
    static constexpr int kMax = 12;
    using Texel = typename BlockTexel<NC>::type;
    Texel t[kMax][kMax];
    int64_t k0, j0;  // texel indices of t[0][0], before wrapping
    int nx, ny;      // texels read per row, rows read
};

// One texel into the block's form; a texel outside a Black edge is zero.
template <int NC>
[[gnu::always_inline]] inline typename TexelBlock<NC>::Texel block_texel(const float* d) {
    if constexpr (NC == 1)
        return *d;
    else
        return knot4<NC>(d);
}

// The block holding every point within es texels of the centre s along s and et along t (with
// the texel after each, for the bilinear blend); false when it would not fit. NC: the image's
// channels (a texel is one load of that width).
template <int NC>
bool read_block(const Image& img, double s, double t, double es, double et, TexelBlock<NC>& b) {
    constexpr int kMax = TexelBlock<NC>::kMax;
    b.k0 = floor_to_int(s - es);
    b.j0 = floor_to_int(t - et);
    const int nx = static_cast<int>(floor_to_int(s + es) - b.k0) + 2,
              ny = static_cast<int>(floor_to_int(t + et) - b.j0) + 2;
    if (nx > kMax || ny > kMax) return false;
    b.nx = nx;
    b.ny = ny;
    // Each axis's offsets: a Repeat axis whose start lies less than a period before the base
    // period (the centre is in it: gauss_mean) reads at most a period of consecutive entries of
    // the image's two-period offset table in place, without wrapping; otherwise each index is
    // wrapped into `buf`, -1 outside a Black edge.
    auto offsets = [](int64_t k0, int n, int64_t size, WrapMode mode, const std::ptrdiff_t* table,
                      std::ptrdiff_t* buf) -> const std::ptrdiff_t* {
        if (mode == WrapMode::Repeat && n <= size && k0 >= -size && k0 < size)
            return table + (k0 < 0 ? k0 + size : k0);
        for (int i = 0; i < n; ++i) {
            const int64_t c = wrap_index(k0 + i, size, mode);
            buf[i] = c < 0 ? -1 : table[c];
        }
        return buf;
    };
    std::ptrdiff_t col_buf[kMax], row_buf[kMax];
    const std::ptrdiff_t* col =
        offsets(b.k0, nx, img.width(), img.wrap_s(), img.column_offsets(), col_buf);
    const std::ptrdiff_t* row =
        offsets(b.j0, ny, img.height(), img.wrap_t(), img.row_offsets(), row_buf);
    const float* base = img.row(0);
    if (img.wrap_s() != WrapMode::Black && img.wrap_t() != WrapMode::Black) {
        for (int jj = 0; jj < ny; ++jj)
            for (int i = 0; i < nx; ++i) b.t[jj][i] = block_texel<NC>(base + row[jj] + col[i]);
        return true;
    }
    for (int jj = 0; jj < ny; ++jj)
        for (int i = 0; i < nx; ++i)
            b.t[jj][i] = row[jj] < 0 || col[i] < 0 ? typename TexelBlock<NC>::Texel{}
                                                   : block_texel<NC>(base + row[jj] + col[i]);
    return true;
}

// The rule's points relative to the block, and per group of four points the taps' index in the
// block and the four bilinear weights of each (rule_sum and rule_sum_1). A point's position is
// (rs + xa as) + xb bs along s (likewise along t), in float, with xa and xb its nodes; the
// groups are the points in order (a along, then b), four at a time, the last one padded with
// points at the block's origin of weight 0.
template <int N>
struct RulePoints {
    static constexpr int kPoints = N * N, kGroups = (kPoints + 3) / 4;
    // The nodes and weights of each point, padded to whole groups.
    struct Table {
        alignas(16) float xa[kGroups * 4], xb[kGroups * 4], w[kGroups * 4];
    };
    static constexpr Table kTable = [] {
        using R = GaussRule<N>;
        Table t{};
        for (int k = 0; k < kPoints; ++k) {
            t.xa[k] = static_cast<float>(R::x[k % N]);
            t.xb[k] = static_cast<float>(R::x[k / N]);
            t.w[k] = R::w[k % N] * R::w[k / N];
        }
        return t;
    }();
    __m128 rs, rt, as, at, bs, bt;

    RulePoints(int64_t k0, int64_t j0, double s, double t, double as_, double at_, double bs_,
               double bt_)
        : rs(_mm_set1_ps(static_cast<float>(s - double(k0)))),
          rt(_mm_set1_ps(static_cast<float>(t - double(j0)))),
          as(_mm_set1_ps(static_cast<float>(as_))),
          at(_mm_set1_ps(static_cast<float>(at_))),
          bs(_mm_set1_ps(static_cast<float>(bs_))),
          bt(_mm_set1_ps(static_cast<float>(bt_))) {}

    // Group g's four points: each one's tap (row j times kMax plus column i of its first texel)
    // and its texels' weights w00 (i, j), w10 (i + 1, j), w01 (i, j + 1), w11 (i + 1, j + 1).
    // Tap indices are clamped into the block: rounding can put a point on the block's far edge
    // (the points' extent along each axis is the block's own).
    void group(int g, int nx, int ny, int32_t* tap, __m128* w4) const {
        const __m128i hi_s = _mm_set1_epi32(nx - 2), hi_t = _mm_set1_epi32(ny - 2),
                      zero = _mm_setzero_si128();
        const __m128 one = _mm_set1_ps(1);
        const __m128 xa = _mm_load_ps(kTable.xa + 4 * g), xb = _mm_load_ps(kTable.xb + 4 * g);
        const __m128 vs = _mm_add_ps(_mm_add_ps(rs, _mm_mul_ps(xa, as)), _mm_mul_ps(xb, bs)),
                     vt = _mm_add_ps(_mm_add_ps(rt, _mm_mul_ps(xa, at)), _mm_mul_ps(xb, bt));
        // Truncation is the floor here (positions are at least about -1e-6). The fractions are
        // taken from the clamped taps, so a point rounded onto the block's far edge still gets
        // that edge's texel (weight 1 on the tap's second texel).
        const __m128i ii = _mm_cvttps_epi32(vs), jj = _mm_cvttps_epi32(vt);
        // (SSE2 has no 32-bit min and max; the 16-bit ones are exact for these small non-negative
        // indices, whose upper halves are zero.)
        const __m128i ic = _mm_max_epi16(_mm_min_epi16(ii, hi_s), zero),
                      jc = _mm_max_epi16(_mm_min_epi16(jj, hi_t), zero);
        const __m128 fs = _mm_sub_ps(vs, _mm_cvtepi32_ps(ic)),
                     ft = _mm_sub_ps(vt, _mm_cvtepi32_ps(jc));
        static_assert(TexelBlock<1>::kMax == 12 && TexelBlock<4>::kMax == 12);
        const __m128i idx = _mm_add_epi32(
            _mm_add_epi32(_mm_slli_epi32(jc, 3), _mm_slli_epi32(jc, 2)), ic);  // j kMax + i
        _mm_store_si128(reinterpret_cast<__m128i*>(tap), idx);
        const __m128 w = _mm_load_ps(kTable.w + 4 * g), gs = _mm_sub_ps(one, fs),
                     gt = _mm_sub_ps(one, ft);
        const __m128 w0 = _mm_mul_ps(w, gt), w1 = _mm_mul_ps(w, ft);
        w4[0] = _mm_mul_ps(w0, gs);
        w4[1] = _mm_mul_ps(w0, fs);
        w4[2] = _mm_mul_ps(w1, gs);
        w4[3] = _mm_mul_ps(w1, fs);
    }
};

// The N x N rule's weighted sum of the bilinear reconstruction at c + fa a + fb b, from the block.
// The points' positions, taps and weights are computed four at a time, in float relative to the
// block (a few texels, so float keeps about 1e-6 texel); each point then adds its four texels,
// weighted, to the sum in one vector, point after point: the same operations for every channel.
template <int N, int NC>
__m128 rule_sum(const TexelBlock<NC>& b, double s, double t, double as, double at, double bs,
                double bt) {
    const RulePoints<N> pts(b.k0, b.j0, s, t, as, at, bs, bt);
    constexpr int kMax = TexelBlock<NC>::kMax;
    __m128 total = _mm_setzero_ps();
    for (int g = 0; g < pts.kGroups; ++g) {
        alignas(16) int32_t tap[4];
        __m128 w4[4];
        pts.group(g, b.nx, b.ny, tap, w4);
        alignas(16) float w00[4], w10[4], w01[4], w11[4];
        _mm_store_ps(w00, w4[0]);
        _mm_store_ps(w10, w4[1]);
        _mm_store_ps(w01, w4[2]);
        _mm_store_ps(w11, w4[3]);
        for (int k = 0; k < 4 && 4 * g + k < pts.kPoints; ++k) {
            const __m128* r = &b.t[0][0] + tap[k];
            const __m128 v =
                _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(w00[k]), r[0]),
                                                 _mm_mul_ps(_mm_set1_ps(w10[k]), r[1])),
                                      _mm_mul_ps(_mm_set1_ps(w01[k]), r[kMax])),
                           _mm_mul_ps(_mm_set1_ps(w11[k]), r[kMax + 1]));
            total = _mm_add_ps(total, v);
        }
    }
    return total;
}

// rule_sum for one channel: a group's four points are the four lanes. Each point's value is
// rule_sum's lane 0 (the same products and sums in the same order) and the values are added to
// the sum point after point, so the result is rule_sum's bit for bit (in lane 0; the others are
// 0), with a quarter of the arithmetic and the texels gathered in pairs.
template <int N>
__m128 rule_sum_1(const TexelBlock<1>& b, double s, double t, double as, double at, double bs,
                  double bt) {
    const RulePoints<N> pts(b.k0, b.j0, s, t, as, at, bs, bt);
    constexpr int kMax = TexelBlock<1>::kMax;
    const float* block = &b.t[0][0];
    // Texels i and i + 1 of a row, as lanes 0 and 1 (or 2 and 3) of a vector.
    auto lo = [](__m128 v, const float* p) {
        return _mm_loadl_pi(v, reinterpret_cast<const __m64*>(p));
    };
    auto hi = [](__m128 v, const float* p) {
        return _mm_loadh_pi(v, reinterpret_cast<const __m64*>(p));
    };
    float total = 0;
    for (int g = 0; g < pts.kGroups; ++g) {
        alignas(16) int32_t tap[4];
        __m128 w4[4];
        pts.group(g, b.nx, b.ny, tap, w4);
        const float *p0 = block + tap[0], *p1 = block + tap[1], *p2 = block + tap[2],
                    *p3 = block + tap[3];
        const __m128 z = _mm_setzero_ps();
        // Rows j (t00 t10 per point) and j + 1 (t01 t11), two points a vector, then split into
        // one vector per texel of the tap.
        const __m128 a01 = hi(lo(z, p0), p1), a23 = hi(lo(z, p2), p3);
        const __m128 b01 = hi(lo(z, p0 + kMax), p1 + kMax), b23 = hi(lo(z, p2 + kMax), p3 + kMax);
        const __m128 t00 = _mm_shuffle_ps(a01, a23, _MM_SHUFFLE(2, 0, 2, 0)),
                     t10 = _mm_shuffle_ps(a01, a23, _MM_SHUFFLE(3, 1, 3, 1)),
                     t01 = _mm_shuffle_ps(b01, b23, _MM_SHUFFLE(2, 0, 2, 0)),
                     t11 = _mm_shuffle_ps(b01, b23, _MM_SHUFFLE(3, 1, 3, 1));
        const __m128 v =
            _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(w4[0], t00), _mm_mul_ps(w4[1], t10)),
                                  _mm_mul_ps(w4[2], t01)),
                       _mm_mul_ps(w4[3], t11));
        alignas(16) float vk[4];
        _mm_store_ps(vk, v);
        for (int k = 0; k < 4 && 4 * g + k < pts.kPoints; ++k) total += vk[k];
    }
    return _mm_set_ss(total);
}

// The rules of `mix` (one, or two blended) from a block around the region; false when it would
// not fit in one.
template <int NC>
[[gnu::noinline]] bool block_rules(const Image& img, double s, double t, double as, double at,
                                   double bs, double bt, RuleMix mix, int* texels, Texel& out) {
    const int largest = mix.largest();
    const double reach = largest == 3   ? GaussRule<3>::x[2]
                         : largest == 4 ? GaussRule<4>::x[3]
                                        : GaussRule<5>::x[4];
    TexelBlock<NC> block;
    if (!read_block<NC>(img, s, t, reach * (std::abs(as) + std::abs(bs)),
                        reach * (std::abs(at) + std::abs(bt)), block))
        return false;
    *texels = block.nx * block.ny;
    auto rule = [&]<int N>() {
        if constexpr (NC == 1)
            return rule_sum_1<N>(block, s, t, as, at, bs, bt);
        else
            return rule_sum<N, NC>(block, s, t, as, at, bs, bt);
    };
    // One call of each rule (a blend's two are the lone rules' calls).
    const bool blend = mix.w > 0;
    const __m128 z = _mm_setzero_ps();
    const __m128 r3 = mix.lo == 3 ? rule.template operator()<3>() : z,
                 r4 = mix.lo == 4 || (mix.lo == 3 && blend) ? rule.template operator()<4>() : z,
                 r5 = mix.lo == 5 || (mix.lo == 4 && blend) ? rule.template operator()<5>() : z;
    const __m128 lo = mix.lo == 3 ? r3 : mix.lo == 4 ? r4 : r5, hi = mix.lo == 3 ? r4 : r5;
    const __m128 sum = !blend
                           ? lo
                           : _mm_add_ps(_mm_mul_ps(_mm_set1_ps(static_cast<float>(1 - mix.w)), lo),
                                        _mm_mul_ps(_mm_set1_ps(static_cast<float>(mix.w)), hi));
    _mm_storeu_ps(out.data(), sum);
    if constexpr (NC == 3) out[3] = 0;
    return true;
}
#endif

// The same rule point by point (any block size; also the path without SSE2).
template <int N>
[[gnu::cold]] Texel rule_points(const Image& img, double s, double t, double as, double at,
                                double bs, double bt) {
    using R = GaussRule<N>;
    Texel out{};
    for (int ib = 0; ib < N; ++ib)
        for (int ia = 0; ia < N; ++ia) {
            const Texel p = detail::bilinear_at(img, s + R::x[ia] * as + R::x[ib] * bs,
                                                t + R::x[ia] * at + R::x[ib] * bt);
            const float wq = R::w[ia] * R::w[ib];
            for (int c = 0; c < 4; ++c) out[c] += wq * p[c];
        }
    return out;
}

// The mean of the bilinear reconstruction over the parallelogram c ± a/2 ± b/2 (uv units), whose
// longer side is `major` level-0 texels (under kAreaBlendHi). When the parallelogram lies within
// one bilinear patch it is exact in closed form: B there is B(c) plus the twist d = t00 − t10 −
// t01 + t11 times the product of the offsets from c, whose mean over the parallelogram is
// (a_s a_t + b_s b_t) / 12, so one patch read does. Otherwise a Gauss–Legendre product rule in the
// parallelogram's coordinates, 3x3, 4x4 or 5x5 points by size (rule_mix), which is exact within
// one patch too, so the cases agree where the choice changes. `texels` receives the number of
// texels read.
Texel gauss_mean(const Image& img, double u, double v, Vec2d a, Vec2d b, double major,
                 int* texels) {
    const double W = img.width(), H = img.height();
    double s = u * W - 0.5, t = v * H - 0.5;
    const double as = a.u * W, at = a.v * H, bs = b.u * W, bt = b.v * H;
    const double ds = 0.5 * (std::abs(as) + std::abs(bs)), dt = 0.5 * (std::abs(at) + std::abs(bt));
    constexpr double kMax = detail::kMaxTexelCoord;
    *texels = 1;
    if (!(std::abs(s) + ds < kMax && std::abs(t) + dt < kMax)) [[unlikely]]
        return img.mean();  // as bilinear()
    // A periodic axis: move the centre to the base period (exactly: an integer multiple of the
    // period is subtracted), so the texels' indices need no division to wrap.
    s -= period_shift(s, img.width(), img.wrap_s());
    t -= period_shift(t, img.height(), img.wrap_t());
    const int64_t k = floor_to_int(s - ds), j = floor_to_int(t - dt);
    if (floor_to_int(s + ds) == k && floor_to_int(t + dt) == j) {
        *texels = 4;
        const detail::BilinearPatch p = detail::bilinear_patch(img, s, t);
        Texel out = p.value(img.channels());
        const float twist = static_cast<float>((as * at + bs * bt) / 12);
        for (int c = 0; c < img.channels(); ++c)
            out[c] += twist * (p.t00[c] - p.t10[c] - p.t01[c] + p.t11[c]);
        return out;
    }
    const RuleMix mix = rule_mix(major);
#if defined(__SSE2__)
    // The points lie within a block of at most 12x12 texels: per axis they span twice the outer
    // node (0.906 for the 5x5 rule) times the two sides' extents, under 9.97 texels while the
    // longer side is under kAreaBlendHi = 5.5.
    static_assert(kAreaBlendHi <= 5.5 && TexelBlock<1>::kMax >= 12);
    {
        Texel out;
        const bool fits = detail::with_channels(img.channels(), [&]<int NC>() {
            return block_rules<NC>(img, s, t, as, at, bs, bt, mix, texels, out);
        });
        if (fits) [[likely]]
            return out;
    }
#endif
    auto points = [&](int n) {
        *texels += 4 * n * n;
        return n == 3   ? rule_points<3>(img, s, t, as, at, bs, bt)
               : n == 4 ? rule_points<4>(img, s, t, as, at, bs, bt)
                        : rule_points<5>(img, s, t, as, at, bs, bt);
    };
    *texels = 0;
    Texel out{};
    const Texel lo = points(mix.lo);
    for (int c = 0; c < 4; ++c) out[c] += static_cast<float>(1 - mix.w) * lo[c];
    if (mix.w > 0) {
        const Texel hi = points(mix.lo + 1);
        for (int c = 0; c < 4; ++c) out[c] += static_cast<float>(mix.w) * hi[c];
    }
    return out;
}

// area_region with the sides' components apart: with Vec2d arguments the compiler built (a.u W,
// a.v H) as one vector from the arguments stored to memory, and that 16-byte load of two 8-byte
// stores waited for both (store forwarding fails), at the head of every walked lookup.
[[gnu::noinline]] AreaRegion region_of(const FilteredTexture& tex, double u, double v, double au,
                                       double av, double bu, double bv) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    Vec2d A{au * W, av * H}, B{bu * W, bv * H};  // level-0 texels
    double la2 = dot(A, A), lb2 = dot(B, B);
    if (la2 < lb2) {
        std::swap(A, B);
        std::swap(la2, lb2);
    }
    // Degenerate axes: zero sides become the axis-aligned unit square below; collinear ones
    // keep the major side, with the perpendicular side of the area they span (about 0).
    if (la2 == 0) {
        A = {0, 0};
        B = {0, 0};
    } else {
        const double ab = cross(A, B);
        if (!(ab * ab > 1e-12 * la2 * lb2)) {
            const double k = std::abs(ab) / la2;  // the side |ab| / |A| along A's normal
            B = {-A.v * k, A.u * k};
            lb2 = dot(B, B);
        }
    }
    // The bilinear reconstruction term: each side to sqrt(|side|^2 + 1) texels. The four square
    // roots do not depend on each other.
    const double la = std::sqrt(la2), lb = std::sqrt(lb2);
    const double ga = std::sqrt(la2 + 1), gb = std::sqrt(lb2 + 1);
    if (la > 0)
        A = (ga / la) * A;
    else
        A = {1, 0};
    if (lb > 0)
        B = (gb / lb) * B;
    else
        B = {-A.v / ga, A.u / ga};
    AreaRegion r;
    r.area2 = 2 * cross(A, B);
    r.area = std::abs(r.area2) / 2;
    const double cs = u * W, ct = v * H;
    r.corners[0] = {cs - 0.5 * (A.u + B.u), ct - 0.5 * (A.v + B.v)};
    r.corners[1] = {cs + 0.5 * (A.u - B.u), ct + 0.5 * (A.v - B.v)};
    r.corners[2] = {cs + 0.5 * (A.u + B.u), ct + 0.5 * (A.v + B.v)};
    r.corners[3] = {cs - 0.5 * (A.u - B.u), ct - 0.5 * (A.v - B.v)};
    r.major = std::max(ga, gb);
    r.minor = std::min(ga, gb);
    r.perimeter = 2 * (ga + gb);
    r.level = area_level(tex, r.area / r.major, r.perimeter);
    return r;
}
}  // namespace

AreaRegion area_region(const FilteredTexture& tex, double u, double v, Vec2d a, Vec2d b) {
    return region_of(tex, u, v, a.u, a.v, b.u, b.v);
}

AreaResult area_parallelogram(const FilteredTexture& tex, double u, double v, Vec2d a, Vec2d b) {
    if (!(std::isfinite(u) && std::isfinite(v) && std::isfinite(a.u) && std::isfinite(a.v) &&
          std::isfinite(b.u) && std::isfinite(b.v))) [[unlikely]] {
        AreaResult r;  // as every filter: the texture's mean
        r.value = tex.image().mean();
        r.knots = 1;
        return r;
    }
    // Small regions: the mean of the bilinear reconstruction over the parallelogram, exact
    // within one bilinear patch, by a Gauss rule otherwise; from kAreaBlendLo to
    // kAreaBlendHi texels (the longer side) it is blended into the region's integral, beyond it
    // is the integral alone. algorithms.md §5.2.
    const double W = tex.image().width(), H = tex.image().height();
    const double la2 = (a.u * a.u) * (W * W) + (a.v * a.v) * (H * H),
                 lb2 = (b.u * b.u) * (W * W) + (b.v * b.v) * (H * H);
    const double major = std::sqrt(std::max(la2, lb2));
    Texel gauss{};
    double w_gauss = 0;
    int gauss_texels = 0;
    if (major < kAreaBlendHi) {
        gauss = gauss_mean(tex.image(), u, v, a, b, major, &gauss_texels);
        w_gauss = std::clamp((kAreaBlendHi - major) / (kAreaBlendHi - kAreaBlendLo), 0.0, 1.0);
        if (w_gauss == 1) {
            AreaResult r;
            r.value = gauss;
            r.knots = gauss_texels;
            r.major = major;
            r.minor = std::sqrt(std::min(la2, lb2));
            r.area = std::abs(cross(a, b)) * W * H;
            return r;
        }
    }
    const AreaRegion g = region_of(tex, u, v, a.u, a.v, b.u, b.v);
    if (!within_range(g.corners, 4, g.area)) [[unlikely]] {
        AreaResult r;  // beyond 2^30 texels no sum keeps any precision: the mean, as every filter
        r.value = tex.image().mean();
        r.knots = 1;
        return r;
    }
    AreaResult r = integrate_on(tex, g.level, g.corners, 4, g.area2, g.perimeter);
    r.major = g.major;
    r.minor = g.minor;
    if (w_gauss > 0) {
        for (int c = 0; c < 4; ++c)
            r.value[c] = static_cast<float>(w_gauss * gauss[c] + (1 - w_gauss) * r.value[c]);
        r.knots += gauss_texels;
    }
    return r;
}

AreaResult area_polygon(const FilteredTexture& tex, const Vec2d* uv, int n) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    n = std::min(n, 8);
    Uninit8<Vec2d> buf;
    Vec2d* p = buf.v;
    for (int i = 0; i < n; ++i) p[i] = {uv[i].u * W, uv[i].v * H};
    double area2 = 0, longest = 0, perimeter = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2d a = p[i], b = p[(i + 1) % n];
        area2 += cross(a, b);
        const double side = length(b - a);
        longest = std::max(longest, side);
        perimeter += side;
    }
    const double area = std::abs(area2) / 2;
    // Width: the height over the longest side (twice the area over it for a triangle).
    const double width = longest > 0 ? (n == 3 ? 2 : 1) * area / longest : 0;
    if (!within_range(p, n, area)) {
        AreaResult r;
        r.value = img.mean();
        r.knots = 1;
        return r;
    }
    return integrate_on(tex, area_level(tex, width, perimeter), p, n, area2, perimeter);
}

namespace {
// The checkerboard's odd-cell indicator integrated along a row from 0 to x: B(x) in even rows
// (x - B(x) in odd ones), with B(x + 2) = B(x) + 1 and B = max(r - 1, 0) for r = x - 2k in
// [0, 2). Its own integral from 0 to x is C(x) = k (k - 1) + k / 2 + k r + max(r - 1, 0)^2 / 2
// (the whole periods before 2k each add 2m + 1/2). Both hold for negative x.
double checker_b(double x) {
    const double k = std::floor(x / 2), r = x - 2 * k;
    return k + std::max(r - 1, 0.0);
}
double checker_c(double x) {
    const double k = std::floor(x / 2), r = x - 2 * k, e = std::max(r - 1, 0.0);
    return k * (k - 1) + k / 2 + k * r + e * e / 2;
}
// The mean over [x0, x1] of row j's integral R: exact, R being linear within a cell (the
// midpoint's value) and C its integral.
double checker_row_mean(int64_t j, double x0, double x1) {
    const bool odd = (j & 1) != 0;
    double b;
    if (std::floor(x0) == std::floor(x1))
        b = checker_b(0.5 * (x0 + x1));
    else
        b = (checker_c(x1) - checker_c(x0)) / (x1 - x0);
    return odd ? 0.5 * (x0 + x1) - b : b;
}
}  // namespace

double checker_odd_share(Vec2d c, Vec2d a, Vec2d b) {
    if (!(std::isfinite(c.u) && std::isfinite(c.v) && std::isfinite(a.u) && std::isfinite(a.v) &&
          std::isfinite(b.u) && std::isfinite(b.v)))
        return -1;
    const double extent_u = std::abs(a.u) + std::abs(b.u), extent_v = std::abs(a.v) + std::abs(b.v);
    if (!(extent_u < 1e15 && extent_v < 1e15 && std::abs(c.u) < 1e15 && std::abs(c.v) < 1e15))
        return -1;
    // The pattern repeats every two cells both ways: the centre is moved into [0, 2)^2 exactly.
    c.u -= 2 * std::floor(c.u / 2);
    c.v -= 2 * std::floor(c.v / 2);
    const double area2 = 2 * cross(a, b);
    const double scale = std::max(dot(a, a), dot(b, b));
    if (!(std::abs(area2) > 1e-12 * scale))  // a segment or a point (scale 0): c's cell
        return static_cast<double>(
            (static_cast<int64_t>(std::floor(c.u)) + static_cast<int64_t>(std::floor(c.v))) & 1);
    Vec2d p[4] = {c - 0.5 * a - 0.5 * b, c + 0.5 * a - 0.5 * b, c + 0.5 * a + 0.5 * b,
                  c - 0.5 * a + 0.5 * b};
    // Rows are the lines of constant t; with fewer columns, s and t trade places (the pattern is
    // symmetric in them; the polygon's orientation and so its signed area change together).
    const int64_t rows = static_cast<int64_t>(std::ceil(c.v + 0.5 * extent_v) -
                                              std::floor(c.v - 0.5 * extent_v)),
                  columns = static_cast<int64_t>(std::ceil(c.u + 0.5 * extent_u) -
                                                 std::floor(c.u - 0.5 * extent_u));
    double signed_area2 = area2;
    if (columns < rows) {
        for (Vec2d& q : p) std::swap(q.u, q.v);
        signed_area2 = -signed_area2;
    }
    if (std::min(rows, columns) > kCheckerMaxLines) return -1;
    // Green's theorem: the integral over the region is the boundary integral of R(s, t) dt.
    // Each edge is cut at every row line it crosses; along a piece s is linear in t, so the
    // piece adds its height times the mean of its row's R over its s-span.
    double sum = 0;
    for (int e = 0; e < 4; ++e) {
        const Vec2d from = p[e], to = p[(e + 1) % 4];
        if (from.v == to.v) continue;
        const double dir = to.v > from.v ? 1 : -1;
        const Vec2d lo = dir > 0 ? from : to, hi = dir > 0 ? to : from;
        const double dsdt = (hi.u - lo.u) / (hi.v - lo.v);
        double t = lo.v, s = lo.u;
        for (int64_t j = static_cast<int64_t>(std::floor(lo.v)); t < hi.v; ++j) {
            const double t_next = std::min(double(j + 1), hi.v);
            const double s_next = t_next == hi.v ? hi.u : lo.u + (t_next - lo.v) * dsdt;
            sum +=
                dir * (t_next - t) * checker_row_mean(j, std::min(s, s_next), std::max(s, s_next));
            t = t_next;
            s = s_next;
        }
    }
    return std::clamp(sum / (0.5 * signed_area2), 0.0, 1.0);
}

}  // namespace cmam::texture
