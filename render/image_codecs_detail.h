// render — what the image codecs' files share (image_codecs.cpp, exr_codec.cpp): the size check
// before pixels are allocated and the OpenEXR reader and writer. Private to image I/O.
#pragma once

#include <string>
#include <vector>

#include "render/image_codecs.h"

namespace cmam::render::codec {

/// Refuses an empty image, asks `check`, then allocates the pixels: as bytes when `keep_8bit`
/// and the image is 8-bit (`is_8bit` set before the call), as floats otherwise.
void check_size(RawImage& img, const SizeCheck& check, bool keep_8bit = false);

/// OpenEXR: the header walked before OpenEXR reads it (sizes and lengths against the limit),
/// then the pixels as float; throws RenderError with the reason.
RawImage decode_exr(const std::string& path, const SizeCheck& check);
/// Float channels `names` (three) of a w x h image, ZIP-compressed, in memory.
std::vector<unsigned char> encode_exr(int w, int h, const float* rgb,
                                      const std::vector<std::string>& names);

}  // namespace cmam::render::codec
