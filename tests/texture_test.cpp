// Texel fetch, wrap modes, point filters and sRGB decoding (algorithms.md §0, §1, §12 T-COL-1).
#include <cmam/texture/filters.h>
#include <cmam/texture/image.h>
#include <gtest/gtest.h>

#include <limits>
#include <tuple>
#include <vector>

#include "expect_throw.h"

using namespace cmam::texture;

namespace {
// The 2x2 texture of algorithms.md §12: T(0,0)=1, T(1,0)=2, T(0,1)=3, T(1,1)=4.
Image tex2x2(WrapMode w = WrapMode::Repeat) {
    return Image(2, 2, 1, {1, 2, 3, 4}, w, w);
}
}  // namespace

TEST(WrapIndex, AllModes) {
    EXPECT_EQ(wrap_index(-1, 4, WrapMode::Repeat), 3);
    EXPECT_EQ(wrap_index(9, 4, WrapMode::Repeat), 1);
    EXPECT_EQ(wrap_index(-1, 4, WrapMode::Clamp), 0);
    EXPECT_EQ(wrap_index(9, 4, WrapMode::Clamp), 3);
    EXPECT_EQ(wrap_index(-1, 4, WrapMode::Black), -1);
    EXPECT_EQ(wrap_index(4, 4, WrapMode::Mirror), 3);
    EXPECT_EQ(wrap_index(-1, 4, WrapMode::Mirror), 0);
}

TEST(WrapMode, ParseAndPrintRoundTrip) {
    for (WrapMode m : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black, WrapMode::Mirror})
        EXPECT_EQ(parse_wrap_mode(to_string(m)), m);
    EXPECT_FALSE(parse_wrap_mode("periodic"));
}

TEST(Nearest, UsesFloorNotRound) {
    Image t = tex2x2();
    EXPECT_EQ(nearest(t, 0.49, 0.2)[0], 1);  // s = 0.98 -> texel 0
    EXPECT_EQ(nearest(t, 0.51, 0.2)[0], 2);
    EXPECT_EQ(nearest(t, 0.2, 0.7)[0], 3);
}

// T-SAT-3's values are the bilinear lookups at these texel-space centres.
TEST(Bilinear, MatchesUnitBoxAverages) {
    Image t = tex2x2();
    EXPECT_NEAR(bilinear(t, 1.0 / 2, 1.0 / 2)[0], 2.5, 1e-6);
    EXPECT_NEAR(bilinear(t, 0.7 / 2, 1.2 / 2)[0], 2.6, 1e-6);
    EXPECT_NEAR(bilinear(t, 0.2 / 2, 0.3 / 2)[0], 1.7, 1e-6);  // wraps
    EXPECT_NEAR(bilinear(t, 1.9 / 2, 0.1 / 2)[0], 2.4, 1e-6);
}

TEST(Bilinear, TexelCentresReturnTexels) {
    Image t = tex2x2(WrapMode::Clamp);
    EXPECT_FLOAT_EQ(bilinear(t, 0.25, 0.25)[0], 1);
    EXPECT_FLOAT_EQ(bilinear(t, 0.75, 0.75)[0], 4);
}

TEST(Bilinear, BlackWrapFadesToZero) {
    Image t = tex2x2(WrapMode::Black);
    // At s = 0 the lattice point -1 is black: half of texel 0.
    EXPECT_NEAR(bilinear(t, 0.0, 0.25)[0], 0.5, 1e-6);
}

TEST(Bilinear, NonFiniteInputGivesMean) {
    Image t = tex2x2();
    double inf = std::numeric_limits<double>::infinity();
    EXPECT_FLOAT_EQ(bilinear(t, std::nan(""), 0.5)[0], 2.5f);
    EXPECT_FLOAT_EQ(bilinear(t, 0.5, inf)[0], 2.5f);
    EXPECT_FLOAT_EQ(nearest(t, 1e300, 0.5)[0], 2.5f);
}

TEST(Bilinear, ConstantTextureAnyWhere) {
    Image t(3, 5, 3, std::vector<float>(45, 0.25f));
    for (double u : {-7.3, 0.0, 0.5, 12.9})
        for (double v : {-2.2, 0.1, 0.99, 100.5}) EXPECT_FLOAT_EQ(bilinear(t, u, v)[1], 0.25f);
}

TEST(Srgb, DecodeReferenceValues) {
    EXPECT_NEAR(srgb_to_linear(128.0f / 255), 0.215861, 1e-6);  // T-COL-1
    EXPECT_NEAR(linear_to_srgb(0.5f), 0.735357, 1e-6);
    for (float x : {0.0f, 0.01f, 0.3f, 0.9f, 1.0f})
        EXPECT_NEAR(linear_to_srgb(srgb_to_linear(x)), x, 1e-6);
}

TEST(Image, RejectsBadSizes) {
    EXPECT_THROW_CONTAINS(Image(0, 2, 1, {}), TextureError, "image size must be positive");
    EXPECT_THROW_CONTAINS(Image(2, 2, 1, {1, 2, 3}), TextureError,
                          "texel count does not match width*height*channels");
    EXPECT_THROW_CONTAINS(Image(1, 1, 5, std::vector<float>(5)), TextureError,
                          "image must have 1 to 4 channels");
}

// Texels are stored in 8x8 tiles; sizes that are not multiples of 8 pad the last tiles.
TEST(Image, TiledStorageKeepsEveryTexel) {
    for (auto [w, h, c] : {std::tuple{1, 1, 1}, {13, 5, 3}, {8, 8, 4}, {17, 23, 2}, {64, 9, 1}}) {
        std::vector<float> px(static_cast<std::size_t>(w) * h * c);
        for (std::size_t k = 0; k < px.size(); ++k) px[k] = static_cast<float>(k);
        Image img(w, h, c, px);
        EXPECT_EQ(img.row_major(), px) << w << "x" << h << "x" << c;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                EXPECT_EQ(img.texel(i, j), img.row(j) + Image::column_offset(i) * c);
                EXPECT_EQ(img.texel(i, j)[0], px[(static_cast<std::size_t>(j) * w + i) * c]);
            }
        Image copy = img;  // deep copy
        EXPECT_EQ(copy.row_major(), px);
        EXPECT_NE(copy.texel(0, 0), img.texel(0, 0));
    }
}
