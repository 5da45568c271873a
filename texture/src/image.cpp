#include <cmam/texture/filters.h>
#include <cmam/texture/image.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <utility>

#include "kernels.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace cmam::texture {

std::optional<WrapMode> parse_wrap_mode(std::string_view name) {
    return kWrapModeNames.parse(name);
}

std::string_view to_string(WrapMode mode) {
    return kWrapModeNames.name(mode);
}

float srgb_to_linear(float c) {
    if (c <= 0.04045f) return c / 12.92f;
    return std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float c) {
    if (c <= 0.0031308f) return 12.92f * c;
    return 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

TexelBuffer::TexelBuffer(std::size_t count, Unfilled) : m_size(count) {
    if (count == 0) return;
    constexpr std::size_t kHuge = std::size_t{2} << 20;
    // Four floats of slack after the last texel: a filter may load a 3-channel texel as four
    // floats (the fourth is never used).
    const std::size_t bytes = (count + 4) * sizeof(float);
    const std::size_t align = bytes >= kHuge ? kHuge : 64;
    const std::size_t rounded = (bytes + align - 1) / align * align;
    m_data = static_cast<float*>(std::aligned_alloc(align, rounded));
    if (!m_data) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    // Huge pages for the whole 2 MB regions the buffer fills (advice only: may be ignored). Its
    // tail stays in ordinary pages: a huge page there would be zeroed whole and held for up to
    // 2 MB the buffer never uses.
    if (align == kHuge) madvise(m_data, bytes / kHuge * kHuge, MADV_HUGEPAGE);
#endif
    std::memset(m_data + count, 0, 4 * sizeof(float));
}

TexelBuffer::TexelBuffer(std::size_t count) : TexelBuffer(count, Unfilled{}) {
    if (count == 0) return;
    const std::size_t bytes = count * sizeof(float);
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    // From 64 KB, the pages are made present in one call rather than faulted in one at a time
    // by the zero fill below (a fault per 4 KB page, each costly under virtualisation; kernels
    // before 5.14 refuse the advice, and the fill faults them in as before).
    if (bytes >= (std::size_t{64} << 10)) {
        constexpr std::uintptr_t kPage = 4096;
        const auto start = reinterpret_cast<std::uintptr_t>(m_data);
        const std::uintptr_t lo = (start + kPage - 1) / kPage * kPage,
                             hi = (start + bytes) / kPage * kPage;
        if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_POPULATE_WRITE);
    }
#endif
    std::memset(m_data, 0, bytes);
}

TexelBuffer::TexelBuffer(const TexelBuffer& other) : TexelBuffer(other.m_size) {
    if (m_size) std::memcpy(m_data, other.m_data, m_size * sizeof(float));
}

TexelBuffer::TexelBuffer(TexelBuffer&& other) noexcept
    : m_data(std::exchange(other.m_data, nullptr)), m_size(std::exchange(other.m_size, 0)) {}

TexelBuffer& TexelBuffer::operator=(TexelBuffer other) noexcept {
    std::swap(m_data, other.m_data);
    std::swap(m_size, other.m_size);
    return *this;
}

TexelBuffer::~TexelBuffer() {
    std::free(m_data);
}

namespace {
// `texels` when it holds width*height*channels floats (sizes the constructor accepts).
const std::vector<float>& checked_texels(const std::vector<float>& texels, int width, int height,
                                         int channels) {
    if (width > 0 && height > 0 && channels >= 1 && channels <= 4 &&
        texels.size() != static_cast<std::size_t>(width) * height * channels)
        throw TextureError("texel count does not match width*height*channels");
    return texels;
}
}  // namespace

Image::Image(int width, int height, int channels, const std::vector<float>& texels, WrapMode wrap_s,
             WrapMode wrap_t)
    : Image(
          Rows{}, width, height, channels,
          [&t = checked_texels(texels, width, height, channels), width, channels](int j,
                                                                                  float* row) {
              std::copy_n(&t[static_cast<std::size_t>(j) * width * channels],
                          static_cast<std::size_t>(width) * channels, row);
          },
          wrap_s, wrap_t) {}

Image Image::from_rows(int width, int height, int channels,
                       const std::function<void(int, float*)>& fill, WrapMode wrap_s,
                       WrapMode wrap_t) {
    return Image(Rows{}, width, height, channels, fill, wrap_s, wrap_t);
}

namespace {
// One row of `width` texels from `src` (row-major) into its tiles from `dst` (the row's texel
// 0), adding each texel to `sum` in order: eight texels of a tile row are contiguous, and the
// channel count is a constant, so the sums stay in registers.
template <int NC>
void tile_row(const float* src, float* dst, int width, double* sum) {
    double s[NC];
    for (int c = 0; c < NC; ++c) s[c] = sum[c];
    for (int i0 = 0; i0 < width; i0 += Image::kTile) {
        float* d = dst + Image::column_offset(i0) * NC;
        const int n = std::min(Image::kTile, width - i0);
        for (int k = 0; k < n; ++k, src += NC, d += NC)
            for (int c = 0; c < NC; ++c) {
                d[c] = src[c];
                s[c] += src[c];
            }
    }
    for (int c = 0; c < NC; ++c) sum[c] = s[c];
}
}  // namespace

Image::Image(Rows, int width, int height, int channels,
             const std::function<void(int, float*)>& fill, WrapMode wrap_s, WrapMode wrap_t)
    : m_width(width), m_height(height), m_channels(channels), m_wrap_s(wrap_s), m_wrap_t(wrap_t) {
    if (width <= 0 || height <= 0) throw TextureError("image size must be positive");
    if (channels < 1 || channels > 4) throw TextureError("image must have 1 to 4 channels");
    m_tiles_x = static_cast<std::size_t>((width + kTile - 1) >> kTileLog2);
    const std::size_t tiles_y = static_cast<std::size_t>((height + kTile - 1) >> kTileLog2);
    m_texels = TexelBuffer(m_tiles_x * tiles_y * kTile * kTile * channels);
    m_column_offsets.resize(2 * static_cast<std::size_t>(width));
    for (std::size_t k = 0; k < m_column_offsets.size(); ++k)
        m_column_offsets[k] = column_offset(static_cast<int64_t>(k % width)) * channels;
    m_row_offsets.resize(2 * static_cast<std::size_t>(height));
    for (std::size_t k = 0; k < m_row_offsets.size(); ++k)
        m_row_offsets[k] = row_offset(static_cast<int64_t>(k % height)) * channels;
    double sum[4] = {0, 0, 0, 0};
    std::vector<float> row(static_cast<std::size_t>(width) * channels);
    for (int j = 0; j < height; ++j) {
        fill(j, row.data());
        float* dst = m_texels.data() + row_offset(j) * channels;
        detail::with_channels(channels,
                              [&]<int NC>() { tile_row<NC>(row.data(), dst, width, sum); });
    }
    double n = static_cast<double>(width) * height;
    for (int c = 0; c < channels; ++c) m_mean[c] = static_cast<float>(sum[c] / n);
}

std::vector<float> Image::row_major() const {
    std::vector<float> out(static_cast<std::size_t>(m_width) * m_height * m_channels);
    for (int j = 0; j < m_height; ++j)
        for (int i = 0; i < m_width; ++i)
            std::copy_n(texel(i, j), m_channels,
                        &out[(static_cast<std::size_t>(j) * m_width + i) * m_channels]);
    return out;
}

Texel Image::fetch(int64_t i, int64_t j) const {
    int64_t wi = wrap_index(i, m_width, m_wrap_s);
    int64_t wj = wrap_index(j, m_height, m_wrap_t);
    Texel out{};
    if (wi < 0 || wj < 0) return out;
    const float* t = texel(static_cast<int>(wi), static_cast<int>(wj));
    for (int c = 0; c < m_channels; ++c) out[c] = t[c];
    return out;
}

namespace {
// Coordinates beyond this magnitude (or non-finite) cannot be floored to an integer safely.
constexpr double kMaxCoord = detail::kMaxTexelCoord;

bool usable(double x) {
    return std::isfinite(x) && std::abs(x) < kMaxCoord;
}
}  // namespace

Texel nearest(const Image& image, double u, double v) {
    double s = u * image.width(), t = v * image.height();
    if (!usable(s) || !usable(t)) return image.mean();
    return image.fetch(floor_to_int(s), floor_to_int(t));
}

Texel bilinear(const Image& image, double u, double v) {
    double s = u * image.width() - 0.5, t = v * image.height() - 0.5;
    if (!usable(s) || !usable(t)) return image.mean();
    return detail::bilinear_at(image, s, t);
}

}  // namespace cmam::texture
