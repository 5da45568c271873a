// cmam::texture — texel storage, wrap modes and colour decoding.
// The filtering library's base: an image of linear float texels addressed in the
// renderer's (u,v) convention (v = 0 is the bottom row, as in pbrt-v3). Standard library only.
// Implements algorithms.md §0 (conventions) and §1 (texel fetch).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace cmam::texture {

/// The one exception type of the filtering library.
class TextureError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// How texel indices outside [0,n) are mapped (algorithms.md §0).
enum class WrapMode : uint8_t { Repeat, Clamp, Black, Mirror };

/// Parses "repeat", "clamp", "black" or "mirror"; nullopt otherwise.
std::optional<WrapMode> parse_wrap_mode(std::string_view name);
std::string_view to_string(WrapMode mode);

/// sRGB transfer functions (IEC 61966-2-1), applied per channel to values in [0,1].
float srgb_to_linear(float encoded);
float linear_to_srgb(float linear);

/// Up to four channel values; unused channels are 0.
using Texel = std::array<float, 4>;

/// An image of linear float texels with per-axis wrap modes.
/// Texel (i,j) covers the cell [i,i+1)x[j,j+1) of continuous texel space (s,t) = (u*W, v*H);
/// row j = 0 is v = 0, i.e. the bottom of the picture.
class Image {
  public:
    Image() = default;
    /// `texels` holds width*height*channels floats, row-major from row j = 0 (v = 0).
    Image(int width, int height, int channels, std::vector<float> texels,
          WrapMode wrap_s = WrapMode::Repeat, WrapMode wrap_t = WrapMode::Repeat);

    int width() const { return m_width; }
    int height() const { return m_height; }
    int channels() const { return m_channels; }
    WrapMode wrap_s() const { return m_wrap_s; }
    WrapMode wrap_t() const { return m_wrap_t; }
    const std::vector<float>& data() const { return m_texels; }
    std::size_t memory_bytes() const { return m_texels.size() * sizeof(float); }

    /// Texel (i,j) without wrapping; precondition 0 <= i < width, 0 <= j < height.
    const float* texel(int i, int j) const {
        return &m_texels[(static_cast<std::size_t>(j) * m_width + i) * m_channels];
    }

    /// Texel (i,j) with the wrap modes applied; Black outside gives zeros (algorithms.md §1).
    Texel fetch(int64_t i, int64_t j) const;

    /// Mean of all texels per channel (the value returned for non-finite inputs).
    const Texel& mean() const { return m_mean; }

  private:
    int m_width = 0, m_height = 0, m_channels = 0;
    WrapMode m_wrap_s = WrapMode::Repeat, m_wrap_t = WrapMode::Repeat;
    std::vector<float> m_texels;
    Texel m_mean{};
};

/// floor() for |x| < 2^62 without a libm call (baseline x86-64 has no rounding instruction).
inline int64_t floor_to_int(double x) {
    auto i = static_cast<int64_t>(x);
    return i - (static_cast<double>(i) > x ? 1 : 0);
}

/// Maps index i into [0,n) for the given wrap mode; returns -1 for Black outside.
inline int64_t wrap_index(int64_t i, int64_t n, WrapMode mode) {
    if (i >= 0 && i < n) return i;
    switch (mode) {
        case WrapMode::Repeat:
            return ((i % n) + n) % n;
        case WrapMode::Clamp:
            return i < 0 ? 0 : n - 1;
        case WrapMode::Black:
            return -1;
        case WrapMode::Mirror: {
            int64_t period = 2 * n;
            int64_t k = ((i % period) + period) % period;
            return k < n ? k : period - 1 - k;
        }
    }
    return -1;
}

}  // namespace cmam::texture
