// Image output formats round-trip; writes are atomic (temp file + rename).
#include "render/image_io.h"

#include <cmam/texture/image.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

using namespace cmam::render;
namespace fs = std::filesystem;

namespace {
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
        EXPECT_EQ(r.pixels, px) << name;  // top row first in both
    }
    EXPECT_EQ(d.entries(), 2u);  // no temporaries left behind
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
    EXPECT_THROW(write_image(p, 2, 2, gradient(2, 2)), ImageIoError);
    std::ifstream in(p);
    std::string s((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(s, "old contents");
    EXPECT_EQ(d.entries(), 1u);
    EXPECT_THROW(write_image((d.path / "nodir" / "x.png").string(), 2, 2, gradient(2, 2)),
                 ImageIoError);
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
    } catch (const ImageIoError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("cannot read image \"" + p + "\": ", 0), 0u)
            << e.what();
    }
}
