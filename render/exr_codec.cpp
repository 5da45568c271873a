// render — OpenEXR files through OpenEXR itself: the header walk that refuses what OpenEXR would
// allocate without bound, the reader, and the in-memory writer.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "render/error.h"
#include "render/image_codecs_detail.h"

namespace cmam::render::codec {

namespace {

// ---- OpenEXR --------------------------------------------------------------------------------

// The channels read: R, G, B (and A) when the file has them; otherwise Y; otherwise the first.
std::vector<std::string> exr_channels(const Imf::ChannelList& list) {
    auto has = [&](const char* n) { return list.findChannel(n) != nullptr; };
    if (has("R") && has("G") && has("B")) {
        std::vector<std::string> names{"R", "G", "B"};
        if (has("A")) names.push_back("A");
        return names;
    }
    if (has("Y")) return {"Y"};
    if (list.begin() != list.end()) return {list.begin().name()};
    throw RenderError("the file has no channels");
}

// The size of a value of one of OpenEXR's fixed-size attribute types; -1 for the others.
int fixed_exr_size(const std::string& type) {
    static const std::pair<const char*, int> kSizes[] = {{"box2i", 16},      {"box2f", 16},
                                                         {"compression", 1}, {"lineOrder", 1},
                                                         {"envmap", 1},      {"deepImageState", 1},
                                                         {"float", 4},       {"int", 4},
                                                         {"double", 8},      {"v2i", 8},
                                                         {"v2f", 8},         {"v2d", 16},
                                                         {"v3i", 12},        {"v3f", 12},
                                                         {"v3d", 24},        {"m33f", 36},
                                                         {"m33d", 72},       {"m44f", 64},
                                                         {"m44d", 128},      {"chromaticities", 32},
                                                         {"tiledesc", 9},    {"rational", 8},
                                                         {"timecode", 8},    {"keycode", 28}};
    for (const auto& [name, bytes] : kSizes)
        if (type == name) return bytes;
    return -1;
}

// Walks the (first) header's attributes before OpenEXR does, so that what OpenEXR would
// allocate from them is bounded first: an attribute claiming more bytes than the file holds is
// refused, the data window must be there, every channel's sampling must be sane, and the data
// window times the number of channels is checked against the size limit.
void precheck_exr(const std::string& path, const SizeCheck& check) {
    std::ifstream in(path, std::ios::binary);
    in.seekg(0, std::ios::end);
    const std::int64_t file_size = in.tellg();
    in.seekg(4);
    std::uint32_t version = 0;
    in.read(reinterpret_cast<char*>(&version), 4);
    const std::size_t max_name = (version & 0x400) ? 255 : 31;  // the "long names" flag
    auto read_string = [&](std::string& out, std::size_t max) {
        out.clear();
        for (char c; in.get(c);) {
            if (c == '\0') return true;
            if (out.size() == max) return false;
            out += c;
        }
        return false;
    };
    auto corrupt = [](const std::string& why) {
        return RenderError("corrupt OpenEXR header" + (why.empty() ? "" : ": " + why));
    };
    std::string name, type;
    bool have_window = false;
    std::int64_t w = 0, h = 0, channels = -1;
    while (in) {
        if (!read_string(name, max_name)) throw corrupt("");
        if (name.empty()) break;  // end of the header
        std::int32_t size = -1;
        if (!read_string(type, max_name) || !in.read(reinterpret_cast<char*>(&size), 4))
            throw corrupt("");
        const std::int64_t at = in.tellg();
        if (size < 0 || at + size > file_size)
            throw corrupt("attribute \"" + name + "\" claims " + std::to_string(size) + " bytes");
        if (name == "dataWindow" && type == "box2i" && size == 16) {
            std::int32_t box[4];
            in.read(reinterpret_cast<char*>(box), 16);
            w = std::int64_t(box[2]) - box[0] + 1;
            h = std::int64_t(box[3]) - box[1] + 1;
            have_window = true;
        } else if (type == "chlist") {
            // name, pixel type (int), pLinear and 3 reserved bytes, x and y sampling (ints).
            // Any attribute of this type is walked: OpenEXR reads each to its terminator.
            // OpenEXR reads the list to its terminator, not to the declared size: so does this
            // walk, which then requires the two to agree.
            std::int64_t count = 0;
            std::string ch;
            while (true) {
                if (!read_string(ch, max_name)) throw corrupt("channel list");
                if (ch.empty()) break;
                std::int32_t f[4];
                if (!in.read(reinterpret_cast<char*>(f), 16)) throw corrupt("channel list");
                if (f[0] < 0 || f[0] > 2 || f[2] < 1 || f[2] > 64 || f[3] < 1 || f[3] > 64)
                    throw corrupt("channel \"" + ch + "\"");
                if (in.tellg() > at + size) throw corrupt("channel list");
                ++count;
            }
            if (in.tellg() != at + size) throw corrupt("channel list");
            if (name == "channels") channels = count;
        } else if (const int fixed = fixed_exr_size(type); fixed >= 0 && size != fixed) {
            // OpenEXR reads a value of a fixed-size type by its type, not by the declared size:
            // a different size would put it elsewhere in the file than this walk.
            throw corrupt("attribute \"" + name + "\" of type " + type + " has " +
                          std::to_string(size) + " bytes");
        } else if (type == "preview") {
            // Width and height, then that many RGBA bytes, which OpenEXR allocates.
            std::uint32_t wh[2] = {0, 0};
            in.read(reinterpret_cast<char*>(wh), 8);
            if (size < 8 || 8 + 4 * std::uint64_t(wh[0]) * wh[1] != std::uint64_t(size))
                throw corrupt("preview image");
        }
        in.seekg(at + size);
    }
    if (!in) throw corrupt("");
    if (!have_window || channels < 0)
        throw corrupt(!have_window ? "no data window" : "no channel list");
    if (w <= 0 || h <= 0 || channels == 0) throw RenderError("empty image");
    if (w > 0x7fffffff || h > 0x7fffffff) throw RenderError("image too large");
    RawImage img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    img.channels = static_cast<int>(std::min<std::int64_t>(channels, 1 << 20));
    check(img);
}

}  // namespace

RawImage decode_exr(const std::string& path, const SizeCheck& check) {
    precheck_exr(path, check);
    try {
        Imf::InputFile in(path.c_str());
        const Imath::Box2i dw = in.header().dataWindow();
        const std::int64_t w = std::int64_t(dw.max.x) - dw.min.x + 1;
        const std::int64_t h = std::int64_t(dw.max.y) - dw.min.y + 1;
        if (w > 0x7fffffff || h > 0x7fffffff) throw RenderError("image too large");
        const std::vector<std::string> names = exr_channels(in.header().channels());
        RawImage img;
        img.width = static_cast<int>(w);
        img.height = static_cast<int>(h);
        img.channels = static_cast<int>(names.size());
        check_size(img, check);
        const std::size_t xs = sizeof(float) * names.size();
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < names.size(); ++c)
            fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.pixels.data() + c, dw, xs,
                                                 xs * static_cast<std::size_t>(w)));
        in.setFrameBuffer(fb);
        in.readPixels(dw.min.y, dw.max.y);
        return img;
    } catch (const RenderError&) {
        throw;
    } catch (const std::exception& e) {
        throw RenderError(e.what());
    }
}

namespace {

// An OpenEXR output stream into memory.
class MemoryStream : public Imf::OStream {
  public:
    MemoryStream() : Imf::OStream("memory") {}
    void write(const char c[], int n) override {
        if (m_pos + n > m_bytes.size()) m_bytes.resize(m_pos + n);
        std::memcpy(m_bytes.data() + m_pos, c, static_cast<std::size_t>(n));
        m_pos += static_cast<std::size_t>(n);
    }
    std::uint64_t tellp() override { return m_pos; }
    void seekp(std::uint64_t pos) override { m_pos = pos; }
    std::vector<unsigned char> take() { return std::move(m_bytes); }

  private:
    std::vector<unsigned char> m_bytes;
    std::size_t m_pos = 0;
};

}  // namespace

std::vector<unsigned char> encode_exr(int w, int h, const float* rgb,
                                      const std::vector<std::string>& names) {
    try {
        MemoryStream stream;
        {
            Imf::Header header(w, h);
            // zlib's level 3, as for PNGs, in place of OpenEXR's 6: a render's floats hardly
            // compress further at 6 (0.1% smaller files) for 11% more CPU time in writing. ZIP,
            // 16 scanlines a block, not ZIPS: zlib sets up 260 KB of buffers per block, which
            // glibc may hand back to the system and fault in again each time (docs/performance.md).
            header.compression() = Imf::ZIP_COMPRESSION;
            header.zipCompressionLevel() = 3;
            for (const std::string& n : names)
                header.channels().insert(n, Imf::Channel(Imf::FLOAT));
            Imf::OutputFile out(stream, header);
            Imf::FrameBuffer fb;
            const std::size_t xs = 3 * sizeof(float);
            for (std::size_t c = 0; c < 3; ++c)
                fb.insert(names[c],
                          Imf::Slice(Imf::FLOAT,
                                     const_cast<char*>(reinterpret_cast<const char*>(rgb + c)), xs,
                                     xs * static_cast<std::size_t>(w)));
            out.setFrameBuffer(fb);
            out.writePixels(h);
        }
        return stream.take();
    } catch (const std::exception& e) {
        throw RenderError(e.what());
    }
}

}  // namespace cmam::render::codec
