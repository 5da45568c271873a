#include "render/image_io.h"

#include <OpenImageIO/imageio.h>
#include <cmam/texture/image.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace cmam::render {

namespace fs = std::filesystem;

RawImage read_image(const std::string& path) {
    if (!fs::exists(path)) throw ImageIoError("cannot read image \"" + path + "\": file not found");
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string why = OIIO::geterror();
        throw ImageIoError("cannot read image \"" + path +
                           "\": " + (why.empty() ? "unknown format" : why));
    }
    const OIIO::ImageSpec& spec = in->spec();
    RawImage img;
    img.width = spec.width;
    img.height = spec.height;
    img.channels = spec.nchannels;
    img.is_8bit = spec.format.basetype == OIIO::TypeDesc::UINT8 ||
                  spec.format.basetype == OIIO::TypeDesc::INT8;
    if (img.width <= 0 || img.height <= 0 || img.channels <= 0)
        throw ImageIoError("cannot read image \"" + path + "\": empty image");
    img.pixels.resize(static_cast<std::size_t>(img.width) * img.height * img.channels);
    if (!in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.pixels.data())) {
        std::string why = in->geterror();
        throw ImageIoError("cannot read image \"" + path +
                           "\": " + (why.empty() ? "corrupt data" : why));
    }
    in->close();
    return img;
}

texture::Image load_texture(const std::string& path, bool is_float, std::optional<bool> gamma_opt,
                            float scale, texture::WrapMode wrap, bool* gamma_used) {
    RawImage raw = read_image(path);
    bool gamma = gamma_opt.value_or(raw.is_8bit);
    if (gamma_used) *gamma_used = gamma;
    const int w = raw.width, h = raw.height, nc = raw.channels, out_c = is_float ? 1 : 3;
    std::vector<float> texels(static_cast<std::size_t>(w) * h * out_c);
    for (int y = 0; y < h; ++y) {
        const int j = h - 1 - y;  // flip: v = 0 is the bottom row (pbrt-v3)
        for (int x = 0; x < w; ++x) {
            const float* src = &raw.pixels[(static_cast<std::size_t>(y) * w + x) * nc];
            float rgb[3] = {src[0], nc >= 3 ? src[1] : src[0], nc >= 3 ? src[2] : src[0]};
            float* dst = &texels[(static_cast<std::size_t>(j) * w + x) * out_c];
            if (is_float) {
                float yv = 0.212671f * rgb[0] + 0.715160f * rgb[1] + 0.072169f * rgb[2];
                dst[0] = scale * (gamma ? texture::srgb_to_linear(yv) : yv);
            } else {
                for (int c = 0; c < 3; ++c)
                    dst[c] = scale * (gamma ? texture::srgb_to_linear(rgb[c]) : rgb[c]);
            }
        }
    }
    return texture::Image(w, h, out_c, std::move(texels), wrap, wrap);
}

namespace {

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

void write_pfm(const std::string& path, int w, int h, const std::vector<float>& rgb) {
    std::ofstream out(path, std::ios::binary);
    if (!out) throw ImageIoError("cannot write \"" + path + "\"");
    // Little-endian PFM: negative scale; rows stored bottom to top.
    out << "PF\n" << w << " " << h << "\n-1\n";
    for (int y = h - 1; y >= 0; --y)
        out.write(reinterpret_cast<const char*>(&rgb[static_cast<std::size_t>(y) * w * 3]),
                  static_cast<std::streamsize>(sizeof(float)) * w * 3);
    out.flush();
    if (!out) throw ImageIoError("cannot write \"" + path + "\": write failed");
}

}  // namespace

void write_image(const std::string& path, int w, int h, const std::vector<float>& rgb,
                 const std::vector<std::string>& channel_names) {
    std::string ext = lower_extension(path);
    fs::path target(path);
    fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    if (!fs::is_directory(dir))
        throw ImageIoError("cannot write \"" + path + "\": directory \"" + dir.string() +
                           "\" does not exist");
    // The temporary keeps the extension so format plug-ins that check it are satisfied.
    fs::path tmp =
        dir / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()) + ext);
    try {
        if (ext == ".pfm") {
            write_pfm(tmp.string(), w, h, rgb);
        } else {
            auto out = OIIO::ImageOutput::create(path);
            if (!out)
                throw ImageIoError("cannot write \"" + path + "\": unsupported output format \"" +
                                   ext + "\" (use .exr, .pfm or .png)");
            bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".tif" || ext == ".tiff";
            OIIO::ImageSpec spec(w, h, 3, is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
            std::vector<unsigned char> bytes;
            if (!is_float) {
                spec.attribute("oiio:ColorSpace", "sRGB");
                bytes.resize(rgb.size());
                for (std::size_t i = 0; i < rgb.size(); ++i) {
                    float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
                    float e = texture::linear_to_srgb(v);
                    bytes[i] =
                        static_cast<unsigned char>(std::clamp(e * 255.0f + 0.5f, 0.0f, 255.0f));
                }
            } else {
                spec.attribute("oiio:ColorSpace", "Linear");
                if (channel_names.size() == 3) spec.channelnames = channel_names;
            }
            if (!out->open(tmp.string(), spec))
                throw ImageIoError("cannot write \"" + path + "\": " + out->geterror());
            bool ok = is_float ? out->write_image(OIIO::TypeDesc::FLOAT, rgb.data())
                               : out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
            if (!ok || !out->close())
                throw ImageIoError("cannot write \"" + path + "\": " + out->geterror());
        }
        fs::rename(tmp, target);
    } catch (...) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw;
    }
}

void write_png8(const std::string& path, int w, int h, const std::vector<unsigned char>& rgb) {
    fs::path target(path);
    fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".tmp" +
                                           std::to_string(::getpid()) + ".png");
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw ImageIoError("cannot write \"" + path + "\": no PNG writer");
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    if (!out->open(tmp.string(), spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) ||
        !out->close()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw ImageIoError("cannot write \"" + path + "\": " + out->geterror());
    }
    fs::rename(tmp, target);
}

}  // namespace cmam::render
