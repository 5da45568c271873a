#include <cmam/texture/filters.h>
#include <cmam/texture/image.h>

#include <algorithm>

namespace cmam::texture {

std::optional<WrapMode> parse_wrap_mode(std::string_view name) {
    if (name == "repeat") return WrapMode::Repeat;
    if (name == "clamp") return WrapMode::Clamp;
    if (name == "black") return WrapMode::Black;
    if (name == "mirror") return WrapMode::Mirror;
    return std::nullopt;
}

std::string_view to_string(WrapMode mode) {
    switch (mode) {
        case WrapMode::Repeat:
            return "repeat";
        case WrapMode::Clamp:
            return "clamp";
        case WrapMode::Black:
            return "black";
        case WrapMode::Mirror:
            return "mirror";
    }
    return "?";
}

float srgb_to_linear(float c) {
    if (c <= 0.04045f) return c / 12.92f;
    return std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float c) {
    if (c <= 0.0031308f) return 12.92f * c;
    return 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

Image::Image(int width, int height, int channels, std::vector<float> texels, WrapMode wrap_s,
             WrapMode wrap_t)
    : m_width(width),
      m_height(height),
      m_channels(channels),
      m_wrap_s(wrap_s),
      m_wrap_t(wrap_t),
      m_texels(std::move(texels)) {
    if (width <= 0 || height <= 0) throw TextureError("image size must be positive");
    if (channels < 1 || channels > 4) throw TextureError("image must have 1 to 4 channels");
    if (m_texels.size() != static_cast<std::size_t>(width) * height * channels)
        throw TextureError("texel count does not match width*height*channels");
    std::array<double, 4> sum{};
    for (std::size_t k = 0; k < m_texels.size(); ++k) sum[k % channels] += m_texels[k];
    double n = static_cast<double>(width) * height;
    for (int c = 0; c < channels; ++c) m_mean[c] = static_cast<float>(sum[c] / n);
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
constexpr double kMaxCoord = 1073741824.0;  // 2^30

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
    int64_t i0 = floor_to_int(s), j0 = floor_to_int(t);
    float fs = static_cast<float>(s - static_cast<double>(i0)),
          ft = static_cast<float>(t - static_cast<double>(j0));
    // Tiled textures: move the lattice cell into the base period so the fast path applies.
    if (image.wrap_s() == WrapMode::Repeat) i0 = wrap_index(i0, image.width(), WrapMode::Repeat);
    if (image.wrap_t() == WrapMode::Repeat) j0 = wrap_index(j0, image.height(), WrapMode::Repeat);
    int nc = image.channels();
    Texel out{};
    // Fast path: all four texels inside the image.
    if (i0 >= 0 && j0 >= 0 && i0 + 1 < image.width() && j0 + 1 < image.height()) {
        const float* a = image.texel(static_cast<int>(i0), static_cast<int>(j0));
        const float* c = a + static_cast<std::ptrdiff_t>(image.width()) * nc;
        const float w00 = (1 - fs) * (1 - ft), w10 = fs * (1 - ft), w01 = (1 - fs) * ft,
                    w11 = fs * ft;
        auto blend = [&](int k) {
            return w00 * a[k] + w10 * a[nc + k] + w01 * c[k] + w11 * c[nc + k];
        };
        if (nc == 3) return {blend(0), blend(1), blend(2), 0.0f};
        if (nc == 1) return {blend(0), 0.0f, 0.0f, 0.0f};
        for (int k = 0; k < nc; ++k) out[k] = blend(k);
        return out;
    }
    Texel a = image.fetch(i0, j0), b = image.fetch(i0 + 1, j0);
    Texel c = image.fetch(i0, j0 + 1), d = image.fetch(i0 + 1, j0 + 1);
    for (int k = 0; k < nc; ++k)
        out[k] = (1 - ft) * ((1 - fs) * a[k] + fs * b[k]) + ft * ((1 - fs) * c[k] + fs * d[k]);
    return out;
}

}  // namespace cmam::texture
