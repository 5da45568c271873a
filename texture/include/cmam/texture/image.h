// cmam::texture — texel storage, wrap modes and colour decoding.
// The filtering library's base: an image of linear float texels addressed in the
// renderer's (u,v) convention (v = 0 is the bottom row, as in pbrt-v3). Standard library only.
// Implements algorithms.md §0 (conventions) and §1 (texel fetch).
#pragma once

#include <cmam/texture/names.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace cmam::texture {

/// The one exception type of the filtering library: every error it reports is a TextureError
/// with a fixed message. (Running out of memory is std::bad_alloc, as for any allocation.)
class TextureError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// How texel indices outside [0,n) are mapped (algorithms.md §0).
enum class WrapMode : uint8_t { Repeat, Clamp, Black, Mirror };

inline constexpr NameTable kWrapModeNames{
    Named<WrapMode>{WrapMode::Repeat, "repeat"}, Named{WrapMode::Clamp, "clamp"},
    Named{WrapMode::Black, "black"}, Named{WrapMode::Mirror, "mirror"}};

/// kWrapModeNames.parse; nullopt for an unknown name.
std::optional<WrapMode> parse_wrap_mode(std::string_view name);
std::string_view to_string(WrapMode mode);

/// sRGB transfer functions (IEC 61966-2-1), applied per channel to values in [0,1].
float srgb_to_linear(float encoded);
float linear_to_srgb(float linear);

/// Up to four channel values; unused channels are 0.
using Texel = std::array<float, 4>;

/// Float storage aligned to a cache line; large buffers are aligned to 2 MiB and, on Linux,
/// advised to use transparent huge pages (a filter's reads jump between distant rows).
class TexelBuffer {
  public:
    TexelBuffer() = default;
    explicit TexelBuffer(std::size_t count);  // zero-filled
    /// Not filled: the contents are indeterminate (the slack after them is zero), and the
    /// pages are made present only as they are first written. For tables filled in parts, on
    /// demand.
    struct Unfilled {};
    TexelBuffer(std::size_t count, Unfilled);
    TexelBuffer(const TexelBuffer& other);
    TexelBuffer(TexelBuffer&& other) noexcept;
    TexelBuffer& operator=(TexelBuffer other) noexcept;
    ~TexelBuffer();

    float* data() { return m_data; }
    const float* data() const { return m_data; }
    std::size_t size() const { return m_size; }

  private:
    float* m_data = nullptr;
    std::size_t m_size = 0;
};

/// An image of linear float texels with per-axis wrap modes.
/// Texel (i,j) covers the cell [i,i+1)x[j,j+1) of continuous texel space (s,t) = (u*W, v*H);
/// row j = 0 is v = 0, i.e. the bottom of the picture.
/// Texels are stored in 8x8 tiles (each tile row-major, tiles row-major), so that a filter
/// footprint spanning several rows touches few cache lines and pages; within a tile row,
/// texels i..i|7 are contiguous.
class Image {
  public:
    static constexpr int kTileLog2 = 3;
    static constexpr int kTile = 1 << kTileLog2;

    Image() = default;
    /// `texels` holds width*height*channels floats, row-major from row j = 0 (v = 0).
    Image(int width, int height, int channels, const std::vector<float>& texels,
          WrapMode wrap_s = WrapMode::Repeat, WrapMode wrap_t = WrapMode::Repeat);
    /// The same, row by row: `fill(j, row)` writes row j's width*channels floats (j = 0 first).
    /// No copy of the whole image is needed besides the image itself.
    static Image from_rows(int width, int height, int channels,
                           const std::function<void(int, float*)>& fill,
                           WrapMode wrap_s = WrapMode::Repeat, WrapMode wrap_t = WrapMode::Repeat);

    int width() const { return m_width; }
    int height() const { return m_height; }
    int channels() const { return m_channels; }
    WrapMode wrap_s() const { return m_wrap_s; }
    WrapMode wrap_t() const { return m_wrap_t; }
    std::size_t memory_bytes() const {
        return m_texels.size() * sizeof(float) +
               (m_column_offsets.size() + m_row_offsets.size()) * sizeof(std::ptrdiff_t);
    }

    /// Texel (i,j) without wrapping; precondition 0 <= i < width, 0 <= j < height.
    const float* texel(int i, int j) const { return row(j) + column_offset(i) * m_channels; }
    /// Row j's texel 0; texel (i,j) is row(j) + column_offset(i) * channels().
    const float* row(int j) const { return m_texels.data() + row_offset(j) * m_channels; }
    /// Offset of row j from row 0, in texels: texel (i,j) is texel (0,0) + row_offset(j) +
    /// column_offset(i). Rows 8 apart are tile_row_offset() apart.
    std::ptrdiff_t row_offset(int64_t j) const {
        return (j >> kTileLog2) * tile_row_offset() + ((j & (kTile - 1)) << kTileLog2);
    }
    std::ptrdiff_t tile_row_offset() const {
        return static_cast<std::ptrdiff_t>(m_tiles_x) << (2 * kTileLog2);
    }
    /// Offset of column i within a row, in texels.
    static std::ptrdiff_t column_offset(int64_t i) {
        return static_cast<std::ptrdiff_t>(((i >> kTileLog2) << (2 * kTileLog2)) +
                                           (i & (kTile - 1)));
    }

    /// Tables of the offsets above times channels(), in floats: texel (i,j) is
    /// row(0) + row_offsets()[j] + column_offsets()[i]. Each holds two periods (entry n + k
    /// equals entry k), so n consecutive Repeat-wrapped indices from any start in [0,n) are read
    /// without wrapping.
    const std::ptrdiff_t* column_offsets() const { return m_column_offsets.data(); }
    const std::ptrdiff_t* row_offsets() const { return m_row_offsets.data(); }

    /// The texels in row-major order from row j = 0 (what the constructor took).
    std::vector<float> row_major() const;

    /// Texel (i,j) with the wrap modes applied; Black outside gives zeros (algorithms.md §1).
    Texel fetch(int64_t i, int64_t j) const;

    /// Mean of all texels per channel (the value returned for non-finite inputs).
    const Texel& mean() const { return m_mean; }

  private:
    struct Rows {};  // selects the row-filling constructor
    Image(Rows, int width, int height, int channels, const std::function<void(int, float*)>& fill,
          WrapMode wrap_s, WrapMode wrap_t);

    int m_width = 0, m_height = 0, m_channels = 0;
    std::size_t m_tiles_x = 0;
    WrapMode m_wrap_s = WrapMode::Repeat, m_wrap_t = WrapMode::Repeat;
    TexelBuffer m_texels;
    std::vector<std::ptrdiff_t> m_column_offsets, m_row_offsets;
    Texel m_mean{};
};

/// floor() for |x| < 2^62 without a libm call (baseline x86-64 has no rounding instruction).
/// Truncation is the floor of a non-negative x, as most texel coordinates are: a predicted
/// branch then spares the index the conversion back and the comparison (about 10 cycles on the
/// way to a lookup's first texel).
inline int64_t floor_to_int(double x) {
    auto i = static_cast<int64_t>(x);
    if (x >= 0) [[likely]]
        return i;
    return i - (static_cast<double>(i) > x ? 1 : 0);
}

/// Maps index i into [0,n) for the given wrap mode; returns -1 for Black outside.
inline int64_t wrap_index(int64_t i, int64_t n, WrapMode mode) {
    if (i >= 0 && i < n) return i;
    switch (mode) {
        case WrapMode::Repeat: {
            // A mask for power-of-two sizes (two's complement: exact for negative i too), else
            // one division (a 64-bit one costs tens of cycles; a texture coordinate far off the
            // base period, as on any tiled texture, takes this path on every lookup).
            if ((n & (n - 1)) == 0) return i & (n - 1);
            const int64_t r = i % n;
            return r < 0 ? r + n : r;
        }
        case WrapMode::Clamp:
            return i < 0 ? 0 : n - 1;
        case WrapMode::Black:
            return -1;
        case WrapMode::Mirror: {
            const int64_t period = 2 * n;
            int64_t k = i % period;
            if (k < 0) k += period;
            return k < n ? k : period - 1 - k;
        }
    }
    return -1;
}

}  // namespace cmam::texture
