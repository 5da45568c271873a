#include <cmam/texture/sat.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

SummedAreaTable::SummedAreaTable(const Image& image, Storage storage)
    : m_w(image.width()),
      m_h(image.height()),
      m_c(image.channels()),
      m_wrap_s(image.wrap_s()),
      m_wrap_t(image.wrap_t()),
      m_storage(storage),
      m_mean(image.mean()) {
    const std::size_t n = static_cast<std::size_t>(m_w + 1) * (m_h + 1) * m_c;
    std::vector<double> s(n, 0.0);
    // S[j+1][i+1] = S[j][i+1] + rowprefix_j(i), accumulated in double.
    for (int j = 0; j < m_h; ++j)
        for (int c = 0; c < m_c; ++c) {
            double row = 0;
            for (int i = 0; i < m_w; ++i) {
                double t = image.texel(i, j)[c];
                if (storage == Storage::MeanOffsetFloat) t -= m_mean[c];
                row += t;
                s[((static_cast<std::size_t>(j) + 1) * (m_w + 1) + i + 1) * m_c + c] =
                    s[(static_cast<std::size_t>(j) * (m_w + 1) + i + 1) * m_c + c] + row;
            }
        }
    if (storage == Storage::Double)
        m_double = std::move(s);
    else
        m_float.assign(s.begin(), s.end());
}

std::size_t SummedAreaTable::memory_bytes() const {
    return m_double.size() * sizeof(double) + m_float.size() * sizeof(float);
}

double SummedAreaTable::entry(int i, int j, int c) const {
    std::size_t k = (static_cast<std::size_t>(j) * (m_w + 1) + i) * m_c + c;
    return m_storage == Storage::Double ? m_double[k] : double(m_float[k]);
}

double SummedAreaTable::table(double x, double y, int c) const {
    // S is bilinear within a cell, so interpolating the lattice values is exact.
    int i = std::clamp(static_cast<int>(std::floor(x)), 0, m_w - 1);
    int j = std::clamp(static_cast<int>(std::floor(y)), 0, m_h - 1);
    double fx = x - i, fy = y - j;
    double a = entry(i, j, c), b = entry(i + 1, j, c), d = entry(i, j + 1, c),
           e = entry(i + 1, j + 1, c);
    return (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * d + fx * e);
}

double SummedAreaTable::extended_x(double x, double y, int c) const {
    const double W = m_w;
    switch (m_wrap_s) {
        case WrapMode::Repeat: {
            double q = std::floor(x / W), r = x - q * W;
            return q * table(W, y, c) + table(r, y, c);
        }
        case WrapMode::Clamp:
            if (x < 0) return x * table(1, y, c);
            if (x > W) return table(W, y, c) + (x - W) * (table(W, y, c) - table(W - 1, y, c));
            return table(x, y, c);
        case WrapMode::Black:
        case WrapMode::Mirror:  // mirror is not offered for SATs; treated as black outside
            return table(std::clamp(x, 0.0, W), y, c);
    }
    return 0;
}

double SummedAreaTable::extended(double x, double y, int c) const {
    const double H = m_h;
    switch (m_wrap_t) {
        case WrapMode::Repeat: {
            double q = std::floor(y / H), r = y - q * H;
            return q * extended_x(x, H, c) + extended_x(x, r, c);
        }
        case WrapMode::Clamp:
            if (y < 0) return y * extended_x(x, 1, c);
            if (y > H)
                return extended_x(x, H, c) +
                       (y - H) * (extended_x(x, H, c) - extended_x(x, H - 1, c));
            return extended_x(x, y, c);
        case WrapMode::Black:
        case WrapMode::Mirror:
            return extended_x(x, std::clamp(y, 0.0, H), c);
    }
    return 0;
}

namespace {

// Corners within 2^30 texels (false for NaN): beyond, sums keep no precision, and a corner
// must never be converted to an integer out of range.
bool corners_in_range(double x0, double y0, double x1, double y1) {
    constexpr double kMax = detail::kMaxTexelCoord;
    return std::abs(x0) < kMax && std::abs(y0) < kMax && std::abs(x1) < kMax && std::abs(y1) < kMax;
}

// The integral of a rectangle whose corners are out of range: the mean times the area (0 if
// that is not finite).
Texel mean_integral(const Texel& mean, int channels, double x0, double y0, double x1, double y1) {
    const double area = std::abs((x1 - x0) * (y1 - y0));
    Texel out{};
    if (std::isfinite(area))
        for (int c = 0; c < channels; ++c) out[c] = static_cast<float>(mean[c] * area);
    return out;
}

// Moves [lo, hi] by whole periods of n so that lo falls in [0, n).
inline void to_base_period(double& lo, double& hi, int n) {
    double shift = std::floor(lo / n) * n;
    lo -= shift;
    hi -= shift;
}

// The table as integral()'s fast paths read it: (W+1)(H+1) entries of C channels, row by row.
struct TableView {
    using Storage = SummedAreaTable::Storage;
    int w, h, c;
    Storage storage;
    const double* d;  // the entries, Storage::Double
    const float* f;   // the entries of T - mean, Storage::MeanOffsetFloat
    const Texel& mean;

    // From an entry to the one above it: (W+1)C.
    std::size_t row() const { return static_cast<std::size_t>(w + 1) * c; }
    // Channel c's integral from the sum of its entries, `area` the rectangle's.
    float value(double v, int c, double area) const {
        if (storage == Storage::MeanOffsetFloat) v += mean[c] * area;
        return static_cast<float>(v);
    }
};

// A corner inside the table, signed as it enters the rectangle's sum.
struct InsideCorner {
    std::size_t k;  // entry index of the cell's lower corner (channel 0)
    double w[4];    // weights of (i,j), (i+1,j), (i,j+1), (i+1,j+1)
    double sign;
};

inline InsideCorner inside_corner(const TableView& t, double x, double y, double sign) {
    int i = std::min(static_cast<int>(x), t.w - 1), j = std::min(static_cast<int>(y), t.h - 1);
    double fx = x - i, fy = y - j;
    return InsideCorner{(static_cast<std::size_t>(j) * (t.w + 1) + i) * t.c,
                        {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy},
                        sign};
}

// Inside the table (the common case after the repeat shift): the four corners' bilinear weights
// are shared by all channels.
inline Texel inside_integral(const TableView& t, double x0, double y0, double x1, double y1,
                             double area) {
    const InsideCorner cs[4] = {inside_corner(t, x1, y1, 1), inside_corner(t, x0, y1, -1),
                                inside_corner(t, x1, y0, -1), inside_corner(t, x0, y0, 1)};
    const std::size_t row = t.row();
    Texel out{};
    for (int c = 0; c < t.c; ++c) {
        double v = 0;
        for (const InsideCorner& k : cs) {
            const std::size_t b = k.k + c;
            double e00, e10, e01, e11;
            if (t.storage == TableView::Storage::Double) {
                e00 = t.d[b], e10 = t.d[b + t.c], e01 = t.d[b + row], e11 = t.d[b + row + t.c];
            } else {
                e00 = t.f[b], e10 = t.f[b + t.c], e01 = t.f[b + row], e11 = t.f[b + row + t.c];
            }
            v += k.sign * (k.w[0] * e00 + k.w[1] * e10 + k.w[2] * e01 + k.w[3] * e11);
        }
        out[c] = t.value(v, c, area);
    }
    return out;
}

// A corner of a rectangle repeated both ways: its quotients, remainders' fractions and entries.
struct RepeatCorner {
    double qx, qy, fx, fy, sign;
    std::size_t k, kw, kh;  // entries (i,j), (W,j) and (i,H), channel 0
};

inline RepeatCorner repeat_corner(const TableView& t, double x, double y, double sign) {
    const double qx = std::floor(x / t.w), rx = x - qx * t.w;
    const double qy = std::floor(y / t.h), ry = y - qy * t.h;
    const int i = std::clamp(static_cast<int>(std::floor(rx)), 0, t.w - 1);
    const int j = std::clamp(static_cast<int>(std::floor(ry)), 0, t.h - 1);
    const std::size_t ci = static_cast<std::size_t>(i) * t.c;
    return RepeatCorner{qx,
                        qy,
                        rx - i,
                        ry - j,
                        sign,
                        j * t.row() + ci,
                        j * t.row() + static_cast<std::size_t>(t.w) * t.c,
                        static_cast<std::size_t>(t.h) * t.row() + ci};
}

// Repeat both ways (rectangles across the texture's edge, as every rectangle wider than the
// texture is): extended() with each corner's quotients, remainders and bilinear weights computed
// once for all channels instead of once per channel, and the table's far column and row read
// directly (table() reaches them with weights 0 and 1, which add exactly nothing): the same
// values.
//   S_p(x,y) = qy (qx S(W,H) + S(rx,H)) + (qx S(W,ry) + S(rx,ry))
// `e` is t.d or t.f: each storage has a loop of its own.
template <class Entry>
inline Texel repeat_integral(const TableView& t, const Entry* e, double x0, double y0, double x1,
                             double y1, double area) {
    const RepeatCorner cs[4] = {repeat_corner(t, x1, y1, 1), repeat_corner(t, x0, y1, -1),
                                repeat_corner(t, x1, y0, -1), repeat_corner(t, x0, y0, 1)};
    const std::size_t row = t.row();
    const std::size_t last =
        static_cast<std::size_t>(t.h) * row + static_cast<std::size_t>(t.w) * t.c;
    Texel out{};
    for (int c = 0; c < t.c; ++c) {
        const double total = e[last + c];  // S(W,H)
        double v = 0;
        for (const RepeatCorner& k : cs) {
            const double fx = k.fx, fy = k.fy;
            const std::size_t b = k.k + c;
            const double col = (1 - fy) * e[k.kw + c] + fy * e[k.kw + row + c];
            const double top = (1 - fx) * e[k.kh + c] + fx * e[k.kh + t.c + c];
            const double in = (1 - fy) * ((1 - fx) * e[b] + fx * e[b + t.c]) +
                              fy * ((1 - fx) * e[b + row] + fx * e[b + row + t.c]);
            v += k.sign * (k.qy * (k.qx * total + top) + (k.qx * col + in));
        }
        out[c] = t.value(v, c, area);
    }
    return out;
}

}  // namespace

Texel SummedAreaTable::integral(double x0, double y0, double x1, double y1) const {
    if (!corners_in_range(x0, y0, x1, y1)) return mean_integral(m_mean, m_c, x0, y0, x1, y1);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    // Translate repeat-wrapped rectangles to the base period: small quotients, no cancellation.
    if (m_wrap_s == WrapMode::Repeat) to_base_period(x0, x1, m_w);
    if (m_wrap_t == WrapMode::Repeat) to_base_period(y0, y1, m_h);
    const double area = (x1 - x0) * (y1 - y0);
    const TableView t{m_w, m_h, m_c, m_storage, m_double.data(), m_float.data(), m_mean};
    if (x0 >= 0 && y0 >= 0 && x1 <= m_w && y1 <= m_h)
        return inside_integral(t, x0, y0, x1, y1, area);
    if (m_wrap_s == WrapMode::Repeat && m_wrap_t == WrapMode::Repeat)
        return m_storage == Storage::Double
                   ? repeat_integral(t, m_double.data(), x0, y0, x1, y1, area)
                   : repeat_integral(t, m_float.data(), x0, y0, x1, y1, area);
    Texel out{};
    for (int c = 0; c < m_c; ++c) {
        double v =
            extended(x1, y1, c) - extended(x0, y1, c) - extended(x1, y0, c) + extended(x0, y0, c);
        out[c] = t.value(v, c, area);
    }
    // Black outside: the mean offset must not add texture outside the image.
    if (m_storage == Storage::MeanOffsetFloat &&
        ((m_wrap_s != WrapMode::Repeat && m_wrap_s != WrapMode::Clamp) ||
         (m_wrap_t != WrapMode::Repeat && m_wrap_t != WrapMode::Clamp))) {
        double cx0 = m_wrap_s == WrapMode::Black ? std::clamp(x0, 0.0, double(m_w)) : x0;
        double cx1 = m_wrap_s == WrapMode::Black ? std::clamp(x1, 0.0, double(m_w)) : x1;
        double cy0 = m_wrap_t == WrapMode::Black ? std::clamp(y0, 0.0, double(m_h)) : y0;
        double cy1 = m_wrap_t == WrapMode::Black ? std::clamp(y1, 0.0, double(m_h)) : y1;
        double inside = (cx1 - cx0) * (cy1 - cy0);
        for (int c = 0; c < m_c; ++c)
            out[c] = static_cast<float>(out[c] - m_mean[c] * (area - inside));
    }
    return out;
}

double SummedAreaTable::row_integral(double x, int64_t j, int c) const {
    // Rows outside a black border are empty; a clamped row repeats the edge row.
    if (j < 0 || j >= m_h) {
        if (m_wrap_t == WrapMode::Black || m_wrap_t == WrapMode::Mirror) return 0;
        j = m_wrap_t == WrapMode::Repeat ? ((j % m_h) + m_h) % m_h : (j < 0 ? 0 : m_h - 1);
    }
    const double y = double(j);
    double v = extended_x(x, y + 1, c) - extended_x(x, y, c);
    if (m_storage == Storage::MeanOffsetFloat) {
        double xm = x;  // the mean counts only where the row has texels
        if (m_wrap_s == WrapMode::Black || m_wrap_s == WrapMode::Mirror)
            xm = std::clamp(x, 0.0, double(m_w));
        v += m_mean[c] * xm;
    }
    return v;
}

Texel SummedAreaTable::average(double x0, double y0, double x1, double y1) const {
    if (!corners_in_range(x0, y0, x1, y1)) return m_mean;
    double area = std::abs((x1 - x0) * (y1 - y0));
    if (!(area >= 1e-12)) {
        double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
        Texel t = integral(std::floor(cx), std::floor(cy), std::floor(cx) + 1, std::floor(cy) + 1);
        return t;
    }
    Texel t = integral(x0, y0, x1, y1);
    for (float& v : t) v = static_cast<float>(v / area);
    return t;
}

}  // namespace cmam::texture
