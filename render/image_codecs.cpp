#include "render/image_codecs.h"

#include <jpeglib.h>
#include <png.h>
#include <stb_image.h>
#include <stb_image_write.h>
#include <tiffio.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>

#include "render/image_codecs_detail.h"

// Each C library reports errors its own way; the decoders turn every one into a RenderError.
// libpng and libjpeg leave a failed call by longjmp: the functions that call them keep their
// state in heap objects owned by a guard declared before setjmp, so nothing whose destructor
// matters is skipped and nothing read after the jump lives in a register.

namespace cmam::render::codec {

// Multiplied in double: a header's width × height × channels may exceed 64 bits.
void check_size(RawImage& img, const SizeCheck& check, bool keep_8bit) {
    if (img.width <= 0 || img.height <= 0 || img.channels <= 0) throw RenderError("empty image");
    check(img);
    const std::size_t n = static_cast<std::size_t>(img.width) * img.height * img.channels;
    if (keep_8bit && img.is_8bit)
        img.bytes.resize(n);
    else
        img.pixels.resize(n);
}

namespace {

namespace fs = std::filesystem;

// Sample i of an 8-bit image: the byte itself where the image keeps its bytes, else as a float.
void put_8bit(RawImage& img, std::size_t i, unsigned char v) {
    if (!img.bytes.empty())
        img.bytes[i] = v;
    else
        img.pixels[i] = v * (1.0f / 255.0f);
}

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_for_reading(const std::string& path) {
    File f(std::fopen(path.c_str(), "rb"));
    if (!f) throw RenderError(std::strerror(errno));
    return f;
}

// ---- PNG (libpng) ---------------------------------------------------------------------------

struct PngMessage {
    char text[256] = "corrupt PNG data";
};

extern "C" void png_error_to_jump(png_structp png, png_const_charp message) {
    auto* m = static_cast<PngMessage*>(png_get_error_ptr(png));
    std::snprintf(m->text, sizeof(m->text), "%s", message);
    png_longjmp(png, 1);
}
extern "C" void png_ignore_warning(png_structp, png_const_charp) {}

struct PngReadState {
    PngMessage message;
    png_structp png = nullptr;
    png_infop info = nullptr;
    std::vector<unsigned char> bytes;
    std::vector<png_bytep> rows;
    ~PngReadState() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

RawImage decode_png(const std::string& path, const SizeCheck& check, bool keep_8bit) {
    File f = open_for_reading(path);
    const auto s = std::make_unique<PngReadState>();
    const auto img = std::make_unique<RawImage>();
    s->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &s->message, png_error_to_jump,
                                    png_ignore_warning);
    if (!s->png || !(s->info = png_create_info_struct(s->png))) throw RenderError("out of memory");
    if (setjmp(png_jmpbuf(s->png))) throw RenderError(s->message.text);
    png_init_io(s->png, f.get());
    // Ancillary chunks other than transparency are not used: skipped unread, so that a text or
    // profile chunk whose length claims a gigabyte allocates nothing (libpng would allocate it).
    static const png_byte kSkipped[] =
        "bKGD\0cHRM\0eXIf\0gAMA\0hIST\0iCCP\0iTXt\0oFFs\0pCAL\0"
        "pHYs\0sBIT\0sCAL\0sPLT\0sRGB\0tEXt\0tIME\0zTXt";
    png_set_keep_unknown_chunks(s->png, PNG_HANDLE_CHUNK_NEVER, kSkipped,
                                static_cast<int>(sizeof(kSkipped) / 5));
    png_read_info(s->png, s->info);
    const int color = png_get_color_type(s->png, s->info);
    if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(s->png);
    if (color == PNG_COLOR_TYPE_GRAY && png_get_bit_depth(s->png, s->info) < 8)
        png_set_expand_gray_1_2_4_to_8(s->png);
    if (png_get_valid(s->png, s->info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(s->png);
    if (png_get_bit_depth(s->png, s->info) == 16 && std::endian::native == std::endian::little)
        png_set_swap(s->png);
    png_set_interlace_handling(s->png);
    png_read_update_info(s->png, s->info);
    const bool wide = png_get_bit_depth(s->png, s->info) == 16;
    img->width = static_cast<int>(png_get_image_width(s->png, s->info));
    img->height = static_cast<int>(png_get_image_height(s->png, s->info));
    img->channels = png_get_channels(s->png, s->info);
    img->is_8bit = !wide;
    check_size(*img, check, keep_8bit);
    const std::size_t row = png_get_rowbytes(s->png, s->info);
    // Bytes kept: libpng writes the rows straight into them (8-bit rows are width × channels
    // bytes), with no second copy of the image.
    const bool direct = !img->bytes.empty() && row * img->height == img->bytes.size();
    if (!direct) s->bytes.resize(row * img->height);
    unsigned char* data = direct ? img->bytes.data() : s->bytes.data();
    s->rows.resize(img->height);
    for (int y = 0; y < img->height; ++y) s->rows[y] = data + row * y;
    png_read_image(s->png, s->rows.data());
    if (direct) return std::move(*img);
    const std::size_t n = static_cast<std::size_t>(img->width) * img->height * img->channels;
    if (wide) {
        for (std::size_t i = 0; i < n; ++i) {
            std::uint16_t v;
            std::memcpy(&v, &s->bytes[2 * i], 2);
            img->pixels[i] = v * (1.0f / 65535.0f);
        }
    } else {
        for (std::size_t i = 0; i < n; ++i) put_8bit(*img, i, s->bytes[i]);
    }
    return std::move(*img);
}

struct PngWriteState {
    PngMessage message;
    png_structp png = nullptr;
    png_infop info = nullptr;
    std::vector<unsigned char> out;
    ~PngWriteState() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

extern "C" void png_append(png_structp png, png_bytep data, png_size_t n) {
    auto* out = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
    out->insert(out->end(), data, data + n);
}
extern "C" void png_no_flush(png_structp) {}

std::vector<unsigned char> encode_png(int w, int h, const unsigned char* rgb) {
    const auto s = std::make_unique<PngWriteState>();
    s->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &s->message, png_error_to_jump,
                                     png_ignore_warning);
    if (!s->png || !(s->info = png_create_info_struct(s->png))) throw RenderError("out of memory");
    if (setjmp(png_jmpbuf(s->png))) throw RenderError(s->message.text);
    png_set_write_fn(s->png, &s->out, png_append, png_no_flush);
    // The Sub filter on every row and zlib level 3: the demo's 640x400 render is written in about
    // a third of the time libpng's defaults take (every filter tried per row, level 6), and the
    // bundled scenes' renders come out 4-13% smaller (docs/performance.md, "Writing images").
    png_set_filter(s->png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_level(s->png, 3);
    png_set_IHDR(s->png, s->info, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(s->png, s->info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(s->png, s->info);
    for (int y = 0; y < h; ++y) png_write_row(s->png, rgb + static_cast<std::size_t>(y) * w * 3);
    png_write_end(s->png, nullptr);
    return std::move(s->out);
}

// ---- JPEG (libjpeg-turbo) -------------------------------------------------------------------

struct JpegError {
    jpeg_error_mgr mgr;
    std::jmp_buf jump;
    char text[JMSG_LENGTH_MAX] = "corrupt JPEG data";
};

extern "C" void jpeg_error_to_jump(j_common_ptr cinfo) {
    auto* e = reinterpret_cast<JpegError*>(cinfo->err);
    (*cinfo->err->format_message)(cinfo, e->text);
    std::longjmp(e->jump, 1);
}
extern "C" void jpeg_ignore_message(j_common_ptr) {}

JpegError* install_jpeg_errors(JpegError& e) {
    jpeg_std_error(&e.mgr);
    e.mgr.error_exit = jpeg_error_to_jump;
    e.mgr.output_message = jpeg_ignore_message;  // corrupt-data warnings: the data is still read
    return &e;
}

struct JpegReadState {
    JpegError error;
    jpeg_decompress_struct cinfo{};
    bool created = false;
    std::vector<unsigned char> row;
    ~JpegReadState() {
        if (created) jpeg_destroy_decompress(&cinfo);
    }
};

RawImage decode_jpeg(const std::string& path, const SizeCheck& check, bool keep_8bit) {
    File f = open_for_reading(path);
    const auto s = std::make_unique<JpegReadState>();
    const auto img = std::make_unique<RawImage>();
    s->cinfo.err = &install_jpeg_errors(s->error)->mgr;
    if (setjmp(s->error.jump)) throw RenderError(s->error.text);
    jpeg_create_decompress(&s->cinfo);
    s->created = true;
    jpeg_stdio_src(&s->cinfo, f.get());
    jpeg_read_header(&s->cinfo, TRUE);
    if (s->cinfo.jpeg_color_space == JCS_CMYK || s->cinfo.jpeg_color_space == JCS_YCCK)
        throw RenderError("CMYK JPEG images are not supported (convert it to RGB)");
    s->cinfo.out_color_space = s->cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
    jpeg_calc_output_dimensions(&s->cinfo);
    img->width = static_cast<int>(s->cinfo.output_width);
    img->height = static_cast<int>(s->cinfo.output_height);
    img->channels = s->cinfo.output_components;
    img->is_8bit = true;
    check_size(*img, check, keep_8bit);
    jpeg_start_decompress(&s->cinfo);
    const std::size_t row = static_cast<std::size_t>(img->width) * img->channels;
    s->row.resize(row);
    while (s->cinfo.output_scanline < s->cinfo.output_height) {
        const std::size_t y = s->cinfo.output_scanline;
        JSAMPROW p = s->row.data();
        jpeg_read_scanlines(&s->cinfo, &p, 1);
        for (std::size_t i = 0; i < row; ++i) put_8bit(*img, y * row + i, s->row[i]);
    }
    jpeg_finish_decompress(&s->cinfo);
    return std::move(*img);
}

struct JpegWriteState {
    JpegError error;
    jpeg_compress_struct cinfo{};
    bool created = false;
    unsigned char* buffer = nullptr;
    unsigned long size = 0;
    ~JpegWriteState() {
        if (created) jpeg_destroy_compress(&cinfo);
        std::free(buffer);
    }
};

std::vector<unsigned char> encode_jpeg(int w, int h, const unsigned char* rgb) {
    const auto s = std::make_unique<JpegWriteState>();
    s->cinfo.err = &install_jpeg_errors(s->error)->mgr;
    if (setjmp(s->error.jump)) throw RenderError(s->error.text);
    jpeg_create_compress(&s->cinfo);
    s->created = true;
    jpeg_mem_dest(&s->cinfo, &s->buffer, &s->size);
    s->cinfo.image_width = static_cast<JDIMENSION>(w);
    s->cinfo.image_height = static_cast<JDIMENSION>(h);
    s->cinfo.input_components = 3;
    s->cinfo.in_color_space = JCS_RGB;
    jpeg_set_defaults(&s->cinfo);
    jpeg_set_quality(&s->cinfo, 95, TRUE);
    jpeg_start_compress(&s->cinfo, TRUE);
    while (s->cinfo.next_scanline < s->cinfo.image_height) {
        JSAMPROW p = const_cast<unsigned char*>(rgb) +
                     static_cast<std::size_t>(s->cinfo.next_scanline) * w * 3;
        jpeg_write_scanlines(&s->cinfo, &p, 1);
    }
    jpeg_finish_compress(&s->cinfo);
    return std::vector<unsigned char>(s->buffer, s->buffer + s->size);
}

// ---- TIFF (libtiff) -------------------------------------------------------------------------

// libtiff reports through process-wide handlers: they keep the last message of this thread.
thread_local char t_tiff_message[512];

extern "C" void tiff_error_message(const char* module, const char* format, va_list args) {
    std::vsnprintf(t_tiff_message, sizeof(t_tiff_message), format, args);
}

void install_tiff_handlers() {
    static std::once_flag once;
    std::call_once(once, [] {
        TIFFSetErrorHandler(tiff_error_message);
        TIFFSetWarningHandler(nullptr);
    });
}

struct TiffCloser {
    void operator()(TIFF* t) const { TIFFClose(t); }
};
using Tiff = std::unique_ptr<TIFF, TiffCloser>;

[[noreturn]] void tiff_fail(const char* fallback) {
    throw RenderError(t_tiff_message[0] ? t_tiff_message : fallback);
}

RawImage decode_tiff(const std::string& path, const SizeCheck& check, bool keep_8bit) {
    install_tiff_handlers();
    t_tiff_message[0] = '\0';
    Tiff t(TIFFOpen(path.c_str(), "r"));
    if (!t) tiff_fail("not a TIFF file");
    std::uint32_t w = 0, h = 0;
    std::uint16_t spp = 1, bits = 8, format = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG;
    TIFFGetField(t.get(), TIFFTAG_IMAGEWIDTH, &w);
    TIFFGetField(t.get(), TIFFTAG_IMAGELENGTH, &h);
    TIFFGetFieldDefaulted(t.get(), TIFFTAG_SAMPLESPERPIXEL, &spp);
    TIFFGetFieldDefaulted(t.get(), TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(t.get(), TIFFTAG_SAMPLEFORMAT, &format);
    TIFFGetFieldDefaulted(t.get(), TIFFTAG_PLANARCONFIG, &planar);
    if (w > 0x7fffffffu || h > 0x7fffffffu) throw RenderError("image too large");
    RawImage img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    // 32-bit float and 16-bit integer samples, stored by scanline with interleaved channels,
    // are read as they are; everything else through libtiff's 8-bit RGBA conversion.
    const bool direct = planar == PLANARCONFIG_CONTIG && !TIFFIsTiled(t.get()) && spp <= 4 &&
                        ((format == SAMPLEFORMAT_IEEEFP && bits == 32) ||
                         (format == SAMPLEFORMAT_UINT && bits == 16));
    if (direct) {
        img.channels = spp;
        img.is_8bit = false;
        check_size(img, check);
        std::vector<unsigned char> row(static_cast<std::size_t>(TIFFScanlineSize(t.get())));
        const std::size_t n = static_cast<std::size_t>(w) * spp;
        if (row.size() < n * (bits / 8)) throw RenderError("inconsistent scanline size");
        for (std::uint32_t y = 0; y < h; ++y) {
            if (TIFFReadScanline(t.get(), row.data(), y, 0) < 0) tiff_fail("corrupt TIFF data");
            float* dst = &img.pixels[y * n];
            for (std::size_t i = 0; i < n; ++i) {
                if (bits == 32) {
                    std::memcpy(&dst[i], &row[4 * i], 4);
                } else {
                    std::uint16_t v;
                    std::memcpy(&v, &row[2 * i], 2);
                    dst[i] = v * (1.0f / 65535.0f);
                }
            }
        }
        return img;
    }
    char why[1024] = "";
    if (!TIFFRGBAImageOK(t.get(), why)) throw RenderError(why[0] ? why : "unsupported TIFF layout");
    img.channels = spp == 2 || spp >= 4 ? 4 : 3;
    img.is_8bit = true;
    check_size(img, check, keep_8bit);
    std::vector<std::uint32_t> raster(static_cast<std::size_t>(w) * h);
    if (!TIFFReadRGBAImageOriented(t.get(), w, h, raster.data(), ORIENTATION_TOPLEFT, 0))
        tiff_fail("corrupt TIFF data");
    for (std::size_t i = 0; i < raster.size(); ++i) {
        const std::uint32_t p = raster[i];
        const std::size_t k = i * img.channels;
        put_8bit(img, k, static_cast<unsigned char>(TIFFGetR(p)));
        put_8bit(img, k + 1, static_cast<unsigned char>(TIFFGetG(p)));
        put_8bit(img, k + 2, static_cast<unsigned char>(TIFFGetB(p)));
        if (img.channels == 4) put_8bit(img, k + 3, static_cast<unsigned char>(TIFFGetA(p)));
    }
    return img;
}

// ---- PFM ------------------------------------------------------------------------------------

// "PF" (RGB) or "Pf" (grey), width, height and scale (negative: little-endian) separated by
// white space, one white-space byte, then float rows from the bottom up. Values are multiplied
// by |scale| when it is not 1, as pbrt-v3 reads them.
RawImage decode_pfm(const std::string& path, const SizeCheck& check) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw RenderError(std::strerror(errno));
    std::string magic;
    long long w = 0, h = 0;
    double scale = 0;
    if (!(in >> magic >> w >> h >> scale) || (magic != "PF" && magic != "Pf"))
        throw RenderError("malformed PFM header");
    if (!std::isspace(in.get())) throw RenderError("malformed PFM header");
    if (w <= 0 || h <= 0 || w > 0x7fffffff || h > 0x7fffffff || !(scale == scale) || scale == 0)
        throw RenderError("malformed PFM header");
    RawImage img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    img.channels = magic == "PF" ? 3 : 1;
    check_size(img, check);
    const std::size_t row = static_cast<std::size_t>(w) * img.channels;
    const bool swap = (scale < 0) != (std::endian::native == std::endian::little);
    for (long long y = h - 1; y >= 0; --y) {
        float* dst = &img.pixels[static_cast<std::size_t>(y) * row];
        if (!in.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(row * 4)))
            throw RenderError("truncated PFM data");
        if (swap)
            for (std::size_t i = 0; i < row; ++i) {
                std::uint32_t v;
                std::memcpy(&v, &dst[i], 4);
                v = __builtin_bswap32(v);
                std::memcpy(&dst[i], &v, 4);
            }
        if (std::abs(scale) != 1)
            for (std::size_t i = 0; i < row; ++i) dst[i] *= static_cast<float>(std::abs(scale));
    }
    return img;
}

std::vector<unsigned char> encode_pfm(int w, int h, const float* rgb) {
    const std::string header = "PF\n" + std::to_string(w) + " " + std::to_string(h) +
                               (std::endian::native == std::endian::little ? "\n-1\n" : "\n1\n");
    std::vector<unsigned char> bytes(header.begin(), header.end());
    const std::size_t row = sizeof(float) * static_cast<std::size_t>(w) * 3;
    bytes.reserve(header.size() + row * h);
    for (int y = h - 1; y >= 0; --y) {
        const auto* p =
            reinterpret_cast<const unsigned char*>(rgb + static_cast<std::size_t>(y) * w * 3);
        bytes.insert(bytes.end(), p, p + row);
    }
    return bytes;
}

// ---- stb_image: TGA, BMP, HDR, GIF, PSD, PIC, binary PNM ------------------------------------

struct StbFree {
    void operator()(void* p) const { stbi_image_free(p); }
};

// The bytes a binary PNM (P5, P6) or an uncompressed TGA (types 1-3) must hold, from its
// header; 0 for other files, whose size the header does not give. stb_image reads missing pixel
// data of these two as zeros, so a truncated file would load as a black image.
std::uintmax_t expected_size(const std::string& path, bool is_tga) {
    File f = open_for_reading(path);
    unsigned char h[18] = {};
    const std::size_t n = std::fread(h, 1, sizeof(h), f.get());
    if (n >= 2 && h[0] == 'P' && (h[1] == '5' || h[1] == '6')) {
        // "P6", then width, height and maxval as decimal numbers separated by whitespace and
        // comments, then one whitespace byte before the samples.
        std::rewind(f.get());
        std::fgetc(f.get());
        std::fgetc(f.get());
        std::uintmax_t v[3] = {0, 0, 0};
        for (auto& x : v) {
            int c = std::fgetc(f.get());
            while (c != EOF && (std::isspace(c) || c == '#')) {
                if (c == '#')
                    while (c != EOF && c != '\n') c = std::fgetc(f.get());
                c = std::fgetc(f.get());
            }
            if (c == EOF || !std::isdigit(c)) return 0;  // stb reports a bad header itself
            for (; c != EOF && std::isdigit(c) && x < (std::uintmax_t(1) << 40);
                 c = std::fgetc(f.get()))
                x = x * 10 + std::uintmax_t(c - '0');
            if (c == EOF) return 0;
        }
        const long header = std::ftell(f.get());
        if (header < 0) return 0;
        const std::uintmax_t channels = h[1] == '6' ? 3 : 1, bytes = v[2] > 255 ? 2 : 1;
        return std::uintmax_t(header) + v[0] * v[1] * channels * bytes;
    }
    if (is_tga && n == 18 && h[2] >= 1 && h[2] <= 3) {  // uncompressed: no RLE packets
        const std::uintmax_t id = h[0], map_entries = h[5] | (h[6] << 8), map_bits = h[7];
        const std::uintmax_t w = h[12] | (h[13] << 8), ht = h[14] | (h[15] << 8), bits = h[16];
        const std::uintmax_t map = h[1] ? map_entries * ((map_bits + 7) / 8) : 0;
        return 18 + id + map + w * ht * ((bits + 7) / 8);
    }
    return 0;
}

RawImage decode_stb(const std::string& path, const SizeCheck& check, bool is_tga, bool keep_8bit) {
    RawImage img;
    if (!stbi_info(path.c_str(), &img.width, &img.height, &img.channels))
        throw RenderError(is_tga ? std::string("corrupt TGA data (") + stbi_failure_reason() + ")"
                                 : std::string("unknown image format"));
    const bool hdr = stbi_is_hdr(path.c_str());
    const bool wide = !hdr && stbi_is_16_bit(path.c_str());
    img.is_8bit = !hdr && !wide;
    check_size(img, check, keep_8bit);
    if (const std::uintmax_t need = expected_size(path, is_tga)) {
        std::error_code ec;
        const std::uintmax_t have = fs::file_size(path, ec);
        if (!ec && have < need)
            throw RenderError("truncated: " + std::to_string(have) + " bytes, the header needs " +
                              std::to_string(need));
    }
    int w = 0, h = 0, c = 0;
    const std::size_t n = static_cast<std::size_t>(img.width) * img.height * img.channels;
    auto fail = [] {
        return RenderError(std::string("corrupt data (") + stbi_failure_reason() + ")");
    };
    if (hdr) {
        std::unique_ptr<float, StbFree> p(stbi_loadf(path.c_str(), &w, &h, &c, img.channels));
        if (!p) throw fail();
        std::copy(p.get(), p.get() + n, img.pixels.begin());
    } else if (wide) {
        std::unique_ptr<std::uint16_t, StbFree> p(
            stbi_load_16(path.c_str(), &w, &h, &c, img.channels));
        if (!p) throw fail();
        for (std::size_t i = 0; i < n; ++i) img.pixels[i] = p.get()[i] * (1.0f / 65535.0f);
    } else {
        std::unique_ptr<unsigned char, StbFree> p(
            stbi_load(path.c_str(), &w, &h, &c, img.channels));
        if (!p) throw fail();
        for (std::size_t i = 0; i < n; ++i) put_8bit(img, i, p.get()[i]);
    }
    if (w != img.width || h != img.height) throw RenderError("inconsistent image size");
    return img;
}

extern "C" void stb_append(void* context, void* data, int n) {
    auto* out = static_cast<std::vector<unsigned char>*>(context);
    const auto* p = static_cast<const unsigned char*>(data);
    out->insert(out->end(), p, p + n);
}

bool starts_with(const unsigned char* head, std::size_t n, const char* magic, std::size_t m) {
    return n >= m && std::memcmp(head, magic, m) == 0;
}

}  // namespace

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

RawImage decode(const std::string& path, const SizeCheck& check, bool keep_8bit) {
    unsigned char head[8] = {};
    std::size_t n = 0;
    {
        File f = open_for_reading(path);
        n = std::fread(head, 1, sizeof(head), f.get());
        if (std::ferror(f.get())) throw RenderError(std::strerror(errno));
    }
    if (n == 0) throw RenderError("empty file");
    if (starts_with(head, n, "\x89PNG\r\n\x1a\n", 8)) return decode_png(path, check, keep_8bit);
    if (starts_with(head, n, "\xff\xd8\xff", 3)) return decode_jpeg(path, check, keep_8bit);
    if (starts_with(head, n, "\x76\x2f\x31\x01", 4)) return decode_exr(path, check);
    if (starts_with(head, n, "II*\0", 4) || starts_with(head, n, "MM\0*", 4) ||
        starts_with(head, n, "II+\0", 4) || starts_with(head, n, "MM\0+", 4))
        return decode_tiff(path, check, keep_8bit);
    if (n >= 3 && head[0] == 'P' && (head[1] == 'F' || head[1] == 'f') && std::isspace(head[2]))
        return decode_pfm(path, check);
    return decode_stb(path, check, lower_extension(path) == ".tga", keep_8bit);
}

Output output_format(const std::string& ext) {
    if (ext == ".exr") return Output::Exr;
    if (ext == ".pfm") return Output::Pfm;
    if (ext == ".png") return Output::Png;
    if (ext == ".jpg" || ext == ".jpeg") return Output::Jpeg;
    if (ext == ".tga") return Output::Tga;
    if (ext == ".bmp") return Output::Bmp;
    if (ext == ".hdr") return Output::Hdr;
    if (ext == ".tif" || ext == ".tiff") return Output::Tiff;
    return Output::Unsupported;
}

bool stores_float(Output format) {
    return format == Output::Exr || format == Output::Pfm || format == Output::Hdr ||
           format == Output::Tiff;
}

std::vector<unsigned char> encode_8bit(Output format, int w, int h, const unsigned char* rgb) {
    std::vector<unsigned char> out;
    int ok = 1;
    switch (format) {
        case Output::Png:
            return encode_png(w, h, rgb);
        case Output::Jpeg:
            return encode_jpeg(w, h, rgb);
        case Output::Tga:
            ok = stbi_write_tga_to_func(stb_append, &out, w, h, 3, rgb);
            break;
        case Output::Bmp:
            ok = stbi_write_bmp_to_func(stb_append, &out, w, h, 3, rgb);
            break;
        default:
            throw RenderError("not an 8-bit format");
    }
    if (!ok) throw RenderError("the image could not be encoded");
    return out;
}

std::vector<unsigned char> encode_float(Output format, int w, int h, const float* rgb,
                                        const std::vector<std::string>& names) {
    if (format == Output::Exr) return encode_exr(w, h, rgb, names);
    if (format == Output::Pfm) return encode_pfm(w, h, rgb);
    if (format != Output::Hdr) throw RenderError("not a float format encoded in memory");
    std::vector<unsigned char> out;
    if (!stbi_write_hdr_to_func(stb_append, &out, w, h, 3, rgb))
        throw RenderError("the image could not be encoded");
    return out;
}

void write_tiff(const std::string& path, int w, int h, const float* rgb) {
    install_tiff_handlers();
    t_tiff_message[0] = '\0';
    Tiff t(TIFFOpen(path.c_str(), "w"));
    if (!t) tiff_fail(std::strerror(errno));
    TIFFSetField(t.get(), TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(w));
    TIFFSetField(t.get(), TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(h));
    TIFFSetField(t.get(), TIFFTAG_SAMPLESPERPIXEL, 3);
    TIFFSetField(t.get(), TIFFTAG_BITSPERSAMPLE, 32);
    TIFFSetField(t.get(), TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
    TIFFSetField(t.get(), TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB);
    TIFFSetField(t.get(), TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(t.get(), TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
    TIFFSetField(t.get(), TIFFTAG_ROWSPERSTRIP, TIFFDefaultStripSize(t.get(), 0));
    std::vector<float> row(static_cast<std::size_t>(w) * 3);
    for (int y = 0; y < h; ++y) {
        std::copy_n(rgb + static_cast<std::size_t>(y) * w * 3, row.size(), row.begin());
        if (TIFFWriteScanline(t.get(), row.data(), static_cast<std::uint32_t>(y), 0) < 0)
            tiff_fail("write failed");
    }
    if (!TIFFFlush(t.get())) tiff_fail(std::strerror(errno ? errno : ENOSPC));
}

}  // namespace cmam::render::codec
