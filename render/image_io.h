// render — image input and output, through each format's own library (image_codecs.h).
// Outputs are encoded in memory, written to a temporary file beside the target with every
// write, the flush to disk and the close checked, and renamed over the target: a full disk is
// an error that leaves the old file, and SIGINT, SIGTERM or SIGHUP during a write remove the
// temporary before taking effect.
#pragma once

#include <cmam/texture/image.h>

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/error.h"
#include "render/huge_pages.h"

namespace cmam::render {

/// Pixels as read from a file: top row first, `channels` floats per pixel, values as stored
/// (8-bit data scaled to [0,1], no colour conversion).
struct RawImage {
    int width = 0, height = 0, channels = 0;
    bool is_8bit = false;      // the file stores 8-bit (or narrower) integers
    HugeVector<float> pixels;  // (a 2048x1024 RGB map: 24 MiB, touched once)
    /// An 8-bit image read with keep_8bit: its samples as stored, `pixels` then empty.
    HugeVector<unsigned char> bytes;
    /// Sample i (of width × height × channels, top row first) in [0,1] for 8-bit data, either way.
    float sample(std::size_t i) const {
        return bytes.empty() ? pixels[i] : bytes[i] * (1.0f / 255.0f);
    }
};

/// Reads an image; throws RenderError naming the file and the reason. An image whose pixels
/// (as 32-bit floats, or bytes when kept) would take more than the image memory limit is
/// refused, with its size, before anything is allocated. With `keep_8bit` an 8-bit file's
/// samples stay bytes (`bytes`, a quarter of the floats' memory); `sample()` reads either.
RawImage read_image(const std::string& path, bool keep_8bit = false);

/// The image memory limit in bytes (default: memory_limit() of memory.h); for tests and
/// fuzzing, which keep hostile sizes small.
void set_image_memory_limit(std::size_t bytes);

/// Reads a texture as pbrt-v3's imagemap does: flipped so that row 0 is v = 0, decoded from
/// sRGB when `gamma` (default: for a PNG or TGA file, as pbrt-v3, and any other file storing
/// 8-bit data), multiplied by `scale`. Float
/// textures (`is_float`) keep one channel, the luminance of the stored RGB (decoded after
/// taking the luminance, as pbrt-v3 does); others keep RGB, grey files replicated to three
/// channels, or with `keep_grey` kept as one (the renderer's spectrum textures: a third of the
/// memory, and every filter gives each channel the same value bit for bit either way).
/// `non_finite`, if given, receives the number of texel values that are not finite (only float
/// files can have them).
texture::Image load_texture(const std::string& path, bool is_float, std::optional<bool> gamma,
                            float scale, texture::WrapMode wrap, bool* gamma_used = nullptr,
                            bool keep_grey = false, std::size_t* non_finite = nullptr);

/// Writes linear RGB `rgb` (top row first, 3 floats per pixel). The format follows the
/// extension: .exr (32-bit float), .pfm (float), .hdr (RGBE), .tif/.tiff (32-bit float), or
/// 8-bit sRGB, clamped: .png, .jpg/.jpeg, .tga, .bmp. Atomic: temp file, then rename.
void write_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                 const std::vector<std::string>& channel_names = {"R", "G", "B"});

/// Writes 8-bit RGB bytes (already display-encoded) as PNG, atomically.
void write_png8(const std::string& path, int width, int height,
                const std::vector<unsigned char>& rgb);

/// For tests: `hook` is called during each write, once its temporary file exists (nullptr:
/// none).
void set_write_test_hook(void (*hook)());

}  // namespace cmam::render
