// fuzz — image loading on arbitrary bytes: render::load_texture (and so render::read_image)
// returns a texture or throws RenderError. The input's last byte picks the file's extension
// (the reader is chosen by the file's first bytes; the extension matters only for TGA) and
// whether the texture is read as float or RGB; the rest is the file.
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <string>

#include "fuzz/fuzz_util.h"
#include "render/image_io.h"

namespace {

// The formats cmam reads (README.md).
const char* const kExtensions[] = {".png", ".exr", ".tga", ".bmp", ".ppm", ".pfm",
                                   ".hdr", ".tif", ".jpg", ".gif", ".psd", ".pic"};
constexpr std::size_t kCount = std::size(kExtensions);

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // Images claiming more pixels than this are refused before anything is allocated. 4 MB of
    // samples (1.4 million RGB pixels of an 8-bit file) keep every input's decoding, a pow a
    // pixel for a float texture of an RGB file, within the 10-second timeout under ASan: a
    // 5-million-pixel file took longer there (0.1 s in a release build), a timeout that found
    // nothing but the image's size.
    cmam::render::set_image_memory_limit(std::size_t(4) << 20);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static std::string paths[kCount];
    const uint8_t select = data[size - 1];
    std::string& path = paths[select % kCount];
    if (path.empty()) path = cmam::fuzz::scratch_path(kExtensions[select % kCount]);
    cmam::fuzz::write_file(path, data, size - 1);
    try {
        const bool is_float = (select / kCount) & 1;
        cmam::render::load_texture(path, is_float, std::nullopt, 1.0f,
                                   cmam::texture::WrapMode::Repeat);
    } catch (const cmam::render::RenderError&) {
    }
    return 0;
}
