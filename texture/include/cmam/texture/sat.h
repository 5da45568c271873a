// cmam::texture — summed-area tables (Crow 1984): exact box filter of any axis-aligned
// rectangle in O(1).
// algorithms.md §3: exclusive (W+1)x(H+1) prefix table; bilinear evaluation of the table is
// exact for real-valued corners; repeat by periodic extension (no splitting), clamp by linear
// extension, black by clamping the corners and dividing by the unclamped area. Precision §3.4:
// sums are accumulated in double and stored either as double or offset by the mean as float.
#pragma once

#include <cmam/texture/image.h>

#include <vector>

namespace cmam::texture {

class SummedAreaTable {
  public:
    enum class Storage : uint8_t {
        Double,           // 8 B per channel per entry; worst single-texel error ~1e-10
        MeanOffsetFloat,  // 4 B per channel per entry: the SAT of (T - mean); error < 1e-4
    };

    SummedAreaTable() = default;
    explicit SummedAreaTable(const Image& image, Storage storage = Storage::MeanOffsetFloat);

    int width() const { return m_w; }
    int height() const { return m_h; }
    int channels() const { return m_c; }
    Storage storage() const { return m_storage; }
    std::size_t memory_bytes() const;

    /// The image's mean texel.
    const Texel& mean() const { return m_mean; }
    /// Integral of the box-reconstructed texture over [x0,x1]x[y0,y1] in level-0 texel space
    /// (corners in any order), per channel, with the image's wrap modes. A corner beyond 2^30
    /// texels or not a number gives the mean times the area (0 if that is not finite): no sum
    /// keeps any precision there.
    Texel integral(double x0, double y0, double x1, double y1) const;
    /// Integral over row `j` (cells j <= t < j+1) from s = 0 to s = x, with the wrap modes:
    /// the row prefix that polygon integration needs (Green's theorem).
    double row_integral(double x, int64_t j, int c) const;
    /// Box average over the rectangle. A rectangle of area below 1e-12 texel^2 returns the
    /// bilinear-free point value of the cell containing its centre; a corner beyond 2^30 texels
    /// or not a number returns the mean.
    Texel average(double x0, double y0, double x1, double y1) const;

  private:
    int m_w = 0, m_h = 0, m_c = 0;
    WrapMode m_wrap_s{}, m_wrap_t{};
    Storage m_storage = Storage::Double;
    std::vector<double> m_double;  // (W+1)(H+1)C entries
    std::vector<float> m_float;    // idem, of T - mean
    Texel m_mean{};

    double entry(int i, int j, int c) const;        // S[j][i] (exclusive), 0 <= i <= W, 0 <= j <= H
    double table(double x, double y, int c) const;  // bilinear evaluation, x in [0,W], y in [0,H]
    double extended(double x, double y, int c) const;  // with the wrap modes' extension
    double extended_x(double x, double y, int c) const;
};

}  // namespace cmam::texture
