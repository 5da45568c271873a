// render — the image formats cmam reads and writes, each through its own library: libpng,
// libjpeg-turbo, libtiff and OpenEXR, stb_image for TGA, BMP, HDR, GIF, PSD and binary PNM, and
// PFM directly. Used only by image_io.cpp, which names the file in errors and writes atomically.
#pragma once

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/image_io.h"

namespace cmam::render::codec {

// The codecs throw RenderError with the reason alone (without the file's name); image_io.cpp
// adds the name.

/// Called with the image's size and channels (pixels still empty) before the pixels are
/// allocated; throws RenderError to refuse the image.
using SizeCheck = std::function<void(const RawImage&)>;

/// Decodes the file, choosing the format by its first bytes (by the extension only for TGA,
/// which has no signature). With `keep_8bit`, an 8-bit file's samples stay bytes
/// (RawImage::bytes). Throws RenderError.
RawImage decode(const std::string& path, const SizeCheck& check, bool keep_8bit = false);

/// The file name's extension in lower case, with the dot (".png"); "" if none.
std::string lower_extension(const std::string& path);

/// The output formats, by lower-case extension with the dot.
enum class Output { Exr, Pfm, Png, Jpeg, Tga, Bmp, Hdr, Tiff, Unsupported };
Output output_format(const std::string& ext);
/// Whether the format stores floats (written linear) rather than 8-bit sRGB.
bool stores_float(Output format);

/// Encodes `w`×`h` pixels, top row first, into the bytes of a file. 8-bit formats take 3
/// bytes per pixel, float formats 3 floats; EXR names its channels `names` (3 of them). TIFF
/// is not encoded in memory: write_tiff writes the file itself.
std::vector<unsigned char> encode_8bit(Output format, int w, int h, const unsigned char* rgb);
std::vector<unsigned char> encode_float(Output format, int w, int h, const float* rgb,
                                        const std::vector<std::string>& names);
void write_tiff(const std::string& path, int w, int h, const float* rgb);

}  // namespace cmam::render::codec
