// Image output formats round-trip; writes are atomic (temp file + rename).
#include "render/image_io.h"

#include <cmam/texture/filter.h>
#include <cmam/texture/image.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>

#include "expect_throw.h"

using namespace cmam::render;
namespace texture = cmam::texture;
namespace fs = std::filesystem;

namespace {
// A RawImage's decoded floats as a plain vector, to compare.
std::vector<float> floats(const RawImage& r) {
    return {r.pixels.begin(), r.pixels.end()};
}
struct TempDir {
    fs::path path;
    TempDir() {
        path = fs::temp_directory_path() /
               ("cmam_io_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~TempDir() { fs::remove_all(path); }
    std::size_t entries() const {
        return std::distance(fs::directory_iterator(path), fs::directory_iterator());
    }
};

std::string contents(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Pixels that no format compresses much.
std::vector<float> noise(int w, int h) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<float> v(static_cast<std::size_t>(w) * h * 3);
    for (float& x : v) x = u(rng);
    return v;
}

// While alive, files this process writes are limited to `bytes` (writes past it fail with
// EFBIG, as on a full disk, and SIGXFSZ is ignored).
struct FileSizeLimit {
    rlimit saved{};
    void (*saved_handler)(int);
    explicit FileSizeLimit(rlim_t bytes) {
        saved_handler = std::signal(SIGXFSZ, SIG_IGN);
        getrlimit(RLIMIT_FSIZE, &saved);
        rlimit l = saved;
        l.rlim_cur = bytes;
        setrlimit(RLIMIT_FSIZE, &l);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &saved);
        std::signal(SIGXFSZ, saved_handler);
    }
};

std::vector<float> gradient(int w, int h) {
    std::vector<float> v(static_cast<std::size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) v[(y * w + x) * 3 + c] = (x + 2 * y + 5 * c) / 40.0f;
    return v;
}
}  // namespace

TEST(ImageIo, ExrAndPfmRoundTripExactly) {
    TempDir d;
    auto px = gradient(7, 5);
    for (const char* name : {"a.exr", "a.pfm"}) {
        std::string p = (d.path / name).string();
        write_image(p, 7, 5, px);
        RawImage r = read_image(p);
        ASSERT_EQ(r.width, 7);
        ASSERT_EQ(r.height, 5);
        ASSERT_EQ(r.channels, 3);
        EXPECT_EQ(floats(r), px) << name;  // top row first in both
    }
    EXPECT_EQ(d.entries(), 2u);  // no temporaries left behind
}

// Every output format reads back: float formats within their precision (RGBE: 8-bit mantissa
// with a shared exponent), 8-bit formats as the sRGB bytes written; JPEG, lossy and with its
// colour subsampled, on average within a few levels.
TEST(ImageIo, EveryOutputFormatReadsBack) {
    TempDir d;
    const std::vector<float> px = gradient(7, 5);
    struct Case {
        const char* name;
        bool is_8bit;
        double tolerance;
    };
    for (const Case& c : {Case{"a.exr", false, 0}, Case{"a.pfm", false, 0}, Case{"a.tif", false, 0},
                          Case{"a.hdr", false, 1.0 / 128}, Case{"a.png", true, 0.5 / 255},
                          Case{"a.tga", true, 0.5 / 255}, Case{"a.bmp", true, 0.5 / 255},
                          Case{"a.jpg", true, 3.0 / 255}}) {
        SCOPED_TRACE(c.name);
        const std::string p = (d.path / c.name).string();
        write_image(p, 7, 5, px);
        const RawImage r = read_image(p);
        ASSERT_EQ(r.width, 7);
        ASSERT_EQ(r.height, 5);
        ASSERT_EQ(r.channels, 3);
        EXPECT_EQ(r.is_8bit, c.is_8bit);
        const bool lossy = std::string(c.name) == "a.jpg";
        double worst = 0, sum = 0;
        for (std::size_t i = 0; i < px.size(); ++i) {
            const float want =
                c.is_8bit ? cmam::texture::linear_to_srgb(std::min(px[i], 1.0f)) : px[i];
            const double e = std::abs(r.pixels[i] - want) / std::max(1.0f, want);
            worst = std::max(worst, e);
            sum += e;
        }
        EXPECT_LE(lossy ? sum / px.size() : worst, c.tolerance);
    }
    EXPECT_EQ(d.entries(), 8u);  // no temporaries left behind
}

// Read with keep_8bit, an 8-bit file keeps its samples as bytes (a quarter of the memory, what
// load_texture reads) with exactly the floats of a plain read; other files are read as before.
TEST(ImageIo, EightBitFilesCanKeepTheirBytes) {
    TempDir d;
    std::vector<std::string> paths;
    for (const char* name : {"a.png", "a.tga", "a.bmp", "a.jpg", "a.exr", "a.pfm", "a.hdr"}) {
        paths.push_back((d.path / name).string());
        write_image(paths.back(), 7, 5, gradient(7, 5));
    }
    for (const char* name : {"gray1.png", "gray16.png", "gray_alpha.png", "palette.png", "rgba.png",
                             "gray.jpg", "uint16.tif", "float32.tif"})
        paths.push_back(std::string(CMAM_TEST_DATA_DIR) + "/images/" + name);
    int eight_bit = 0;
    for (const std::string& p : paths) {
        SCOPED_TRACE(p);
        const RawImage plain = read_image(p), kept = read_image(p, true);
        ASSERT_EQ(kept.width, plain.width);
        ASSERT_EQ(kept.channels, plain.channels);
        EXPECT_EQ(kept.is_8bit, plain.is_8bit);
        const std::size_t n = std::size_t(plain.width) * plain.height * plain.channels;
        if (plain.is_8bit) {
            ++eight_bit;
            EXPECT_TRUE(kept.pixels.empty());
            ASSERT_EQ(kept.bytes.size(), n);
        } else {
            EXPECT_TRUE(kept.bytes.empty());
            ASSERT_EQ(kept.pixels.size(), n);
        }
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(kept.sample(i), plain.pixels[i]) << i;
    }
    EXPECT_EQ(eight_bit, 9);
}

// load_texture decodes 8-bit samples through a table of their 256 values: each texel must be
// the sample decoded on its own (sRGB, then the scale), for spectrum and float textures, grey
// and colour files, flipped so that row 0 is the file's bottom row.
TEST(ImageIo, TextureTexelsAreTheirSamplesDecoded) {
    for (const char* name :
         {"gray1.png", "gray.jpg", "gray_alpha.png", "palette.png", "rgba.png", "gray16.png"}) {
        SCOPED_TRACE(name);
        const std::string p = std::string(CMAM_TEST_DATA_DIR) + "/images/" + name;
        const RawImage raw = read_image(p);
        const int nc = raw.channels;
        for (const bool is_float : {false, true})
            for (const bool keep_grey : {false, true}) {
                bool gamma = false;
                const texture::Image t = load_texture(p, is_float, std::nullopt, 0.8f,
                                                      texture::WrapMode::Repeat, &gamma, keep_grey);
                // By default 8-bit files and, as in pbrt-v3, every PNG (gray16.png too).
                EXPECT_EQ(gamma, raw.is_8bit || std::string(name).ends_with(".png"));
                for (int y = 0; y < raw.height; ++y)
                    for (int x = 0; x < raw.width; ++x) {
                        const float* px = &raw.pixels[(std::size_t(y) * raw.width + x) * nc];
                        const float rgb[3] = {px[0], px[nc >= 3 ? 1 : 0], px[nc >= 3 ? 2 : 0]};
                        auto decode = [&](float v) {
                            return 0.8f * (gamma ? texture::srgb_to_linear(v) : v);
                        };
                        const float* got = t.texel(x, raw.height - 1 - y);
                        if (is_float) {
                            ASSERT_EQ(got[0], decode(0.212671f * rgb[0] + 0.715160f * rgb[1] +
                                                     0.072169f * rgb[2]));
                        } else {
                            for (int c = 0; c < t.channels(); ++c)
                                ASSERT_EQ(got[c], decode(rgb[c]));
                        }
                    }
            }
    }
}

// A grey file read as a spectrum texture with keep_grey stays one channel, and every filter
// gives it, bit for bit, the value each channel of the replicated three-channel texture has.
TEST(ImageIo, GreyTexturesCanStayOneChannel) {
    for (const char* name : {"gray1.png", "gray16.png", "gray.jpg"}) {
        SCOPED_TRACE(name);
        const std::string p = std::string(CMAM_TEST_DATA_DIR) + "/images/" + name;
        const texture::FilteredTexture one(
            load_texture(p, false, std::nullopt, 0.7f, texture::WrapMode::Repeat, nullptr, true));
        const texture::FilteredTexture three(
            load_texture(p, false, std::nullopt, 0.7f, texture::WrapMode::Repeat));
        ASSERT_EQ(one.image().channels(), 1);
        ASSERT_EQ(three.image().channels(), 3);
        const texture::Footprint fp = texture::Footprint::axes({0.05, 0.01}, {-0.02, 0.03});
        for (int f = 0; f < texture::kFilterKinds; ++f) {
            const texture::FilterOptions o{static_cast<texture::FilterKind>(f)};
            for (double u : {0.1, 0.37, 0.9}) {
                const texture::Texel a = one.lookup(u, 0.6, fp, o), b = three.lookup(u, 0.6, fp, o);
                for (int c = 0; c < 3; ++c) EXPECT_EQ(a[0], b[c]) << f << " " << u;
            }
        }
    }
    // An RGB file keeps its three channels.
    const std::string rgba = std::string(CMAM_TEST_DATA_DIR) + "/images/rgba.png";
    EXPECT_EQ(load_texture(rgba, false, std::nullopt, 1, texture::WrapMode::Repeat, nullptr, true)
                  .channels(),
              3);
}

namespace {
RawImage read_fixture(const char* name) {
    return read_image(std::string(CMAM_TEST_DATA_DIR) + "/images/" + name);
}
}  // namespace

// Stored layouts other than 8-bit RGB, read as they are stored (tests/data/images/README.md).
TEST(ImageIo, PngLayoutsReadAsStored) {
    const RawImage g16 = read_fixture("gray16.png");
    ASSERT_EQ(g16.channels, 1);
    EXPECT_FALSE(g16.is_8bit);
    EXPECT_EQ(floats(g16), (std::vector<float>{0, 1000 / 65535.0f, 30000 / 65535.0f, 1, 1,
                                               64535 / 65535.0f, 35535 / 65535.0f, 0}));
    const RawImage g1 = read_fixture("gray1.png");
    ASSERT_EQ(g1.channels, 1);
    EXPECT_TRUE(g1.is_8bit);
    EXPECT_EQ(floats(g1), (std::vector<float>{1, 0, 0, 1}));
    // A palette with a transparent entry: RGBA, colours as in the palette.
    const RawImage pal = read_fixture("palette.png");
    ASSERT_EQ(pal.channels, 4);
    EXPECT_EQ(pal.pixels[0], 1);
    EXPECT_EQ(pal.pixels[3], 1);
    EXPECT_EQ(pal.pixels[5], 1);
    EXPECT_EQ(pal.pixels[7], 0);
    EXPECT_FLOAT_EQ(pal.pixels[9], 20 / 255.0f);
    // Alpha is kept apart, as pbrt-v3 reads PNG: colour is not multiplied by it.
    const RawImage rgba = read_fixture("rgba.png");
    ASSERT_EQ(rgba.channels, 4);
    EXPECT_FLOAT_EQ(rgba.pixels[0], 200 / 255.0f);
    EXPECT_EQ(rgba.pixels[3], 0);
    EXPECT_FLOAT_EQ(rgba.pixels[4], 10 / 255.0f);
}

TEST(ImageIo, TiffExrJpegAndPfmFixtures) {
    // 4x2, left to right: x/3 times (1, 0.5, 0.25).
    for (const char* name : {"float32.tif", "uint16.tif", "window.exr"}) {
        SCOPED_TRACE(name);
        const RawImage r = read_fixture(name);
        ASSERT_EQ(r.width, 4);
        ASSERT_EQ(r.height, 2);
        ASSERT_EQ(r.channels, 3);
        EXPECT_FALSE(r.is_8bit);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x)
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(r.pixels[(y * 4 + x) * 3 + c],
                                x / 3.0 *
                                    (c == 0   ? 1
                                     : c == 1 ? 0.5
                                              : 0.25),
                                5e-4);  // half: 11 bits
    }
    const RawImage y = read_fixture("luminance.exr");  // a Y channel only
    ASSERT_EQ(y.channels, 1);
    for (int i = 0; i < 8; ++i) EXPECT_NEAR(y.pixels[i], (i % 4) / 3.0, 1e-3);  // half
    const RawImage j = read_fixture("gray.jpg");  // 8x8 of 0.4, one channel
    ASSERT_EQ(j.channels, 1);
    EXPECT_TRUE(j.is_8bit);
    for (float v : j.pixels) EXPECT_NEAR(v, 0.4, 1.0 / 255);
    // Big-endian with scale 2: values are multiplied by |scale|, as pbrt-v3 reads them.
    const RawImage pfm = read_fixture("scaled_be.pfm");
    EXPECT_EQ(floats(pfm), (std::vector<float>{0.5f, 1, 2, 4, 6, 8}));
}

TEST(ImageIo, PngIsSrgbEncodedAndClamped) {
    TempDir d;
    std::vector<float> px = {0.0f, 0.5f, 2.0f, 0.214041f, -1.0f, 1.0f};
    std::string p = (d.path / "b.png").string();
    write_image(p, 2, 1, px);
    RawImage r = read_image(p);
    EXPECT_TRUE(r.is_8bit);
    EXPECT_FLOAT_EQ(r.pixels[0], 0);
    EXPECT_NEAR(r.pixels[1], cmam::texture::linear_to_srgb(0.5f), 0.5 / 255);
    EXPECT_FLOAT_EQ(r.pixels[2], 1);  // clamped
    EXPECT_NEAR(r.pixels[3], 0.5, 0.5 / 255);
    EXPECT_FLOAT_EQ(r.pixels[4], 0);
}

TEST(ImageIo, FailedWriteLeavesTheOldFileAndNoTemporary) {
    TempDir d;
    std::string p = (d.path / "keep.xyz").string();
    std::ofstream(p) << "old contents";
    EXPECT_THROW_MSG(
        write_image(p, 2, 2, gradient(2, 2)), RenderError,
        "cannot write \"" + p + "\": unsupported output format \".xyz\" (use .exr, .pfm or .png)");
    std::ifstream in(p);
    std::string s((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(s, "old contents");
    EXPECT_EQ(d.entries(), 1u);
    const std::string nodir = (d.path / "nodir").string();
    EXPECT_THROW_MSG(
        write_image(nodir + "/x.png", 2, 2, gradient(2, 2)), RenderError,
        "cannot write \"" + nodir + "/x.png\": directory \"" + nodir + "\" does not exist");
}

TEST(ImageIo, OverwriteReplacesWholeFile) {
    TempDir d;
    std::string p = (d.path / "c.exr").string();
    write_image(p, 4, 4, gradient(4, 4));
    write_image(p, 2, 3, gradient(2, 3));
    RawImage r = read_image(p);
    EXPECT_EQ(r.width, 2);
    EXPECT_EQ(r.height, 3);
    EXPECT_EQ(d.entries(), 1u);
}

TEST(ImageIo, UnreadableImagesNameFileAndReason) {
    TempDir d;
    std::string p = (d.path / "bad.png").string();
    std::ofstream(p) << "not a png";
    try {
        read_image(p);
        FAIL();
    } catch (const RenderError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("cannot read image \"" + p + "\": ", 0), 0u)
            << e.what();
    }
}

// Files that are not regular are refused (a FIFO blocked the reader forever), and so are binary
// PNM and uncompressed TGA files shorter than their headers say (stb_image reads the missing
// pixels as zeros: they loaded as black images). Whole files of both formats still read.
TEST(ImageIo, FifosAndTruncatedPnmAndTgaFilesAreErrors) {
    TempDir d;
    const std::string fifo = (d.path / "fifo.png").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_THROW_MSG(read_image(fifo), RenderError,
                     "cannot read image \"" + fifo + "\": it is not a regular file");
    auto write = [&](const std::string& name, const std::string& bytes) {
        const std::string p = (d.path / name).string();
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    };
    const std::string pixels(4 * 3 * 3, '\x80');  // 4x3 RGB
    const std::string ppm = "P6\n# a comment\n4 3\n255\n";
    EXPECT_EQ(read_image(write("whole.ppm", ppm + pixels)).width, 4);
    const std::string cut = write("cut.ppm", ppm + pixels.substr(0, 20));
    EXPECT_THROW_MSG(read_image(cut), RenderError,
                     "cannot read image \"" + cut +
                         "\": truncated: " + std::to_string(ppm.size() + 20) +
                         " bytes, the header needs " + std::to_string(ppm.size() + 36));
    std::string tga(18, '\0');
    tga[2] = 2;   // uncompressed true colour
    tga[12] = 4;  // width 4
    tga[14] = 3;  // height 3
    tga[16] = 24;
    EXPECT_EQ(read_image(write("whole.tga", tga + pixels)).height, 3);
    const std::string cut_tga = write("cut.tga", tga + pixels.substr(0, 5));
    EXPECT_THROW_MSG(
        read_image(cut_tga), RenderError,
        "cannot read image \"" + cut_tga + "\": truncated: 23 bytes, the header needs 54");
}

// A header claiming more pixels than the image memory limit is refused, naming the file and the
// size, before the pixels are allocated (a PPM claiming 65535^2 once ended in std::bad_alloc).
TEST(ImageIo, ImagesOverTheMemoryLimitAreRefusedBeforeReading) {
    TempDir d;
    const std::string p = (d.path / "huge.ppm").string();
    std::ofstream(p, std::ios::binary) << "P6\n65535 65535\n255\n" << std::string(12, '\x7f');
    set_image_memory_limit(std::size_t(1) << 30);
    try {
        read_image(p);
        FAIL();
    } catch (const RenderError& e) {
        EXPECT_NE(std::string(e.what()).find("\"" + p +
                                             "\": 65535x65535 with 3 channels needs "
                                             "49150 MB, over the limit of 1024 MB"),
                  std::string::npos)
            << e.what();
    }
    const std::string small = (d.path / "small.exr").string();
    write_image(small, 4, 4, gradient(4, 4));
    set_image_memory_limit(4 * 4 * 3 * sizeof(float) - 1);
    EXPECT_THROW_MSG(read_image(small), RenderError,
                     "cannot read image \"" + small +
                         "\": 4x4 with 3 channels needs 0 MB, over the limit of 0 MB");
    set_image_memory_limit(4 * 4 * 3 * sizeof(float));
    EXPECT_EQ(read_image(small).width, 4);
    set_image_memory_limit(std::size_t(1) << 40);
}

// A write that fails part way (here past a file size limit, as on a full disk) is an error
// naming the file and the reason, for every format: the old file stays and no temporary is
// left. PNG once reported success and replaced the old file with a cut one.
TEST(ImageIo, WriteThatRunsOutOfSpaceFailsAndKeepsTheOldFile) {
    TempDir d;
    for (const char* name : {"full.png", "full.exr", "full.pfm"}) {
        SCOPED_TRACE(name);
        const std::string p = (d.path / name).string();
        write_image(p, 4, 4, gradient(4, 4));
        const std::string old = contents(p);
        try {
            FileSizeLimit limit(old.size() + 512);
            write_image(p, 128, 128, noise(128, 128));
            ADD_FAILURE() << "no error reported";
        } catch (const RenderError& e) {
            EXPECT_EQ(std::string(e.what()), "cannot write \"" + p + "\": File too large");
        }
        EXPECT_EQ(contents(p), old);
    }
    EXPECT_EQ(d.entries(), 3u);
}

namespace {
volatile std::sig_atomic_t g_signal_seen = 0;
extern "C" void note_signal(int sig) {
    g_signal_seen = sig;
}
}  // namespace

// SIGINT or SIGTERM while the temporary exists removes it before the signal takes effect: with
// the default action the process ends by the signal; with a handler of the program's own, the
// handler runs and the write is an error. The old file stays either way.
TEST(ImageIo, SignalDuringAWriteRemovesTheTemporary) {
    TempDir d;
    const std::string p = (d.path / "sig.png").string();
    write_image(p, 4, 4, gradient(4, 4));
    const std::string old = contents(p);
    set_write_test_hook([] { std::raise(SIGTERM); });
    EXPECT_EXIT(write_image(p, 8, 8, gradient(8, 8)), ::testing::KilledBySignal(SIGTERM), "");
    EXPECT_EQ(contents(p), old);
    EXPECT_EQ(d.entries(), 1u);

    set_write_test_hook([] { std::raise(SIGINT); });
    void (*saved)(int) = std::signal(SIGINT, note_signal);
    EXPECT_THROW_MSG(write_image(p, 8, 8, gradient(8, 8)), RenderError,
                     "cannot write \"" + p + "\": interrupted by a signal");
    std::signal(SIGINT, saved);
    set_write_test_hook(nullptr);
    EXPECT_EQ(g_signal_seen, SIGINT);
    EXPECT_EQ(contents(p), old);
    EXPECT_EQ(d.entries(), 1u);
}
