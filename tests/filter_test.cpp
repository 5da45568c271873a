// The filtering library against algorithms.md §12 (T-SAT, T-MIP, T-EWA, T-CMAM-2 numbers) and
// property tests parametrised over filter x wrap mode.
#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>
#include <cmam/texture/polygon.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

using namespace cmam::texture;

namespace {
Image tex2x2(WrapMode w) {
    return Image(2, 2, 1, {1, 2, 3, 4}, w, w);
}
// T-MIP-1 texture, rows j = 0..3.
Image tmip1(WrapMode w = WrapMode::Repeat) {
    return Image(4, 4, 1, {3, 0, 1, 2, 5, 7, 4, 1, 0, 2, 6, 3, 1, 1, 0, 4}, w, w);
}
// A w x h image of uniform random texels in [0,1), three channels.
Image random_rgb(int w, int h, unsigned seed, WrapMode wrap = WrapMode::Repeat) {
    std::vector<float> px(std::size_t(w) * h * 3);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0, 1);
    for (float& x : px) x = unit(rng);
    return Image(w, h, 3, px, wrap, wrap);
}
double avg(const SummedAreaTable& s, double x0, double x1, double y0, double y1) {
    return s.average(x0, y0, x1, y1)[0];
}
}  // namespace

// ---- summed-area tables -------------------------------------------------------------------
class SatStorage : public ::testing::TestWithParam<SummedAreaTable::Storage> {};

TEST_P(SatStorage, TSat1AveragesInside) {
    SummedAreaTable s(tex2x2(WrapMode::Repeat), GetParam());
    EXPECT_NEAR(avg(s, 0.5, 1.5, 0.5, 1.5), 2.5, 1e-6);
    EXPECT_NEAR(avg(s, 0.25, 1.0, 0, 2), 2.0, 1e-6);
    EXPECT_NEAR(s.integral(0.25, 0, 1.0, 2)[0], 3.0, 1e-6);
    EXPECT_NEAR(avg(s, 0.5, 2, 0, 1), 1.666667, 1e-6);
    EXPECT_NEAR(avg(s, 0.2, 1.2, 0.3, 1.3), 1.8, 1e-6);
    EXPECT_NEAR(avg(s, 1.5, 0.5, 1.5, 0.5), 2.5, 1e-6);  // corners in any order
}

TEST_P(SatStorage, TSat2RepeatWrap) {
    SummedAreaTable s(tex2x2(WrapMode::Repeat), GetParam());
    EXPECT_NEAR(avg(s, 1.5, 2.5, 0, 1), 1.5, 1e-6);
    EXPECT_NEAR(avg(s, -0.5, 0.5, 1, 2), 3.5, 1e-6);
    EXPECT_NEAR(s.integral(1.75, 1.75, 2.25, 2.25)[0], 0.625, 1e-6);
    EXPECT_NEAR(s.integral(0, 0, 4, 2)[0], 20, 1e-5);
    EXPECT_NEAR(s.integral(-3, -1, 5, 3)[0], 80, 1e-5);
    EXPECT_NEAR(avg(s, 1e6 + 0.5, 1e6 + 1.5, -1e6 + 0.5, -1e6 + 1.5), 2.5,
                1e-6);  // far away: no cancellation
}

TEST_P(SatStorage, TSat3UnitBoxEqualsBilinear) {
    Image t = tex2x2(WrapMode::Repeat);
    SummedAreaTable s(t, GetParam());
    for (auto [cs, ct, expected] :
         {std::tuple{1.0, 1.0, 2.5}, {0.7, 1.2, 2.6}, {0.2, 0.3, 1.7}, {1.9, 0.1, 2.4}}) {
        EXPECT_NEAR(avg(s, cs - 0.5, cs + 0.5, ct - 0.5, ct + 0.5), expected, 1e-6);
        EXPECT_NEAR(bilinear(t, cs / 2, ct / 2)[0], expected, 1e-6);
    }
}

TEST_P(SatStorage, TSat4ClampAndBlack) {
    SummedAreaTable c(tex2x2(WrapMode::Clamp), GetParam());
    EXPECT_NEAR(avg(c, 1.5, 3, 0, 1), 2.0, 1e-6);
    EXPECT_NEAR(c.integral(-1, -1, 3, 3)[0], 40, 1e-5);
    SummedAreaTable b(tex2x2(WrapMode::Black), GetParam());
    EXPECT_NEAR(avg(b, 1.5, 3, 0, 1), 0.666667, 1e-6);
}

TEST_P(SatStorage, RandomRectanglesMatchBruteForce) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> val(0, 1);
    std::vector<float> px(13 * 9);
    for (float& p : px) p = val(rng);
    for (WrapMode w : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black}) {
        Image img(13, 9, 1, px, w, w);
        SummedAreaTable s(img, GetParam());
        std::uniform_int_distribution<int> coord(-20, 30);
        for (int k = 0; k < 200; ++k) {
            int x0 = coord(rng), x1 = coord(rng), y0 = coord(rng), y1 = coord(rng);
            double brute = 0;
            for (int j = std::min(y0, y1); j < std::max(y0, y1); ++j)
                for (int i = std::min(x0, x1); i < std::max(x0, x1); ++i)
                    brute += img.fetch(i, j)[0];
            EXPECT_NEAR(s.integral(x0, y0, x1, y1)[0], brute, 1e-3 * (1 + std::abs(brute)))
                << to_string(w);
        }
    }
}

TEST_P(SatStorage, RealCornersAcrossTheEdgeMatchBruteForceInEveryChannel) {
    // Repeat-wrapped RGB rectangles with real corners, most crossing the texture's edge or wider
    // than it, against the box-reconstructed texture integrated texel by texel.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> val(0, 1);
    std::vector<float> px(13 * 9 * 3);
    for (float& p : px) p = val(rng);
    Image img(13, 9, 3, px, WrapMode::Repeat, WrapMode::Repeat);
    SummedAreaTable s(img, GetParam());
    std::uniform_real_distribution<double> corner(-30, 40);
    for (int k = 0; k < 300; ++k) {
        const double x0 = corner(rng), y0 = corner(rng);
        const double x1 = x0 + std::abs(corner(rng)) / (k % 2 ? 1 : 6),
                     y1 = y0 + std::abs(corner(rng)) / (k % 3 ? 1 : 6);
        double brute[3] = {0, 0, 0};
        for (int j = int(std::floor(y0)); j < std::ceil(y1); ++j)
            for (int i = int(std::floor(x0)); i < std::ceil(x1); ++i) {
                const double a = (std::min(x1, i + 1.0) - std::max(x0, double(i))) *
                                 (std::min(y1, j + 1.0) - std::max(y0, double(j)));
                for (int c = 0; c < 3; ++c) brute[c] += a * img.fetch(i, j)[c];
            }
        const Texel t = s.integral(x0, y0, x1, y1);
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(t[c], brute[c], 1e-4 * (1 + brute[c]))
                << "[" << x0 << ", " << x1 << "] x [" << y0 << ", " << y1 << "] channel " << c;
    }
}

INSTANTIATE_TEST_SUITE_P(Storage, SatStorage,
                         ::testing::Values(SummedAreaTable::Storage::Double,
                                           SummedAreaTable::Storage::MeanOffsetFloat));

TEST(Sat, TSat5PrecisionGate) {
    const int n = 1024;
    std::vector<float> px(n * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            px[j * n + i] = float(((long long)i * i + 3LL * j * j + 5LL * i * j) % 256) / 255.0f;
    Image img(n, n, 1, px);
    SummedAreaTable d(img, SummedAreaTable::Storage::Double),
        f(img, SummedAreaTable::Storage::MeanOffsetFloat);
    EXPECT_EQ(f.memory_bytes(), std::size_t(n + 1) * (n + 1) * 4);  // 4 bytes per channel per entry
    double worst_d = 0, worst_f = 0;
    for (int j = 0; j < n; j += 3)
        for (int i = 0; i < n; i += 3) {
            double truth = px[j * n + i];
            worst_d = std::max(worst_d, std::abs(d.average(i, j, i + 1, j + 1)[0] - truth));
            worst_f = std::max(worst_f, std::abs(f.average(i, j, i + 1, j + 1)[0] - truth));
        }
    EXPECT_LT(worst_d, 1e-6);  // float output rounding only
    EXPECT_LT(worst_f, 1e-4);
    EXPECT_NEAR(d.average(1023, 1023, 1024, 1024)[0], 0.035294, 1e-6);
    EXPECT_NEAR(f.average(1023, 1023, 1024, 1024)[0], 0.035294, 1e-4);
}

// ---- MIP ----------------------------------------------------------------------------------
TEST(Mip, TMip1PyramidAndTrilinear) {
    MipPyramid p(tmip1());
    ASSERT_EQ(p.levels(), 3);
    EXPECT_FLOAT_EQ(p.level(1).texel(0, 0)[0], 3.75f);
    EXPECT_FLOAT_EQ(p.level(1).texel(1, 0)[0], 2.0f);
    EXPECT_FLOAT_EQ(p.level(1).texel(0, 1)[0], 1.0f);
    EXPECT_FLOAT_EQ(p.level(1).texel(1, 1)[0], 3.25f);
    EXPECT_FLOAT_EQ(p.level(2).texel(0, 0)[0], 2.5f);
    EXPECT_NEAR(p.trilinear(0.3, 0.6, 1)[0], 1.90, 1e-5);
    EXPECT_NEAR(p.trilinear(0.3, 0.6, std::sqrt(2.0))[0], 1.915, 1e-5);
    EXPECT_NEAR(p.trilinear(0.3, 0.6, 2)[0], 1.93, 1e-5);
    EXPECT_NEAR(p.trilinear(0.3, 0.6, 2 * std::sqrt(2.0))[0], 2.215, 1e-5);
    EXPECT_NEAR(p.trilinear(0.3, 0.6, 4)[0], 2.5, 1e-5);
    EXPECT_NEAR(p.trilinear(0.9, 0.05, std::pow(2.0, 0.25))[0], 2.57125, 1e-5);
}

TEST(Mip, TMip2RampKeepsTheHalfTexelConvention) {
    std::vector<float> px(16 * 16);
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) px[j * 16 + i] = float(i);
    MipPyramid p(Image(16, 16, 1, px, WrapMode::Clamp, WrapMode::Clamp));
    for (int l = 0; l <= 3; ++l) {
        EXPECT_NEAR(p.bilinear(l, 0.5, 0.5)[0], 7.5, 1e-5) << l;
        EXPECT_NEAR(p.bilinear(l, 0.25, 0.5)[0], 3.5, 1e-5) << l;
    }
    for (double w = 0.5; w < 40; w *= 1.37)
        EXPECT_NEAR(p.trilinear(0.5, 0.5, w)[0], 7.5, 1e-5) << w;
}

TEST(Mip, NonPowerOfTwoLevelsPreserveTheMeanAndStayInside) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> val(0, 1);
    for (auto [w, h] : {std::pair{13, 5}, std::pair{7, 1}, std::pair{1, 9}, std::pair{100, 3}}) {
        std::vector<float> px(static_cast<std::size_t>(w) * h);
        for (float& p : px) p = val(rng);
        MipPyramid p(Image(w, h, 1, px, WrapMode::Black, WrapMode::Black));
        double mean = p.level(0).mean()[0];
        for (int l = 0; l < p.levels(); ++l) {
            EXPECT_EQ(p.level(l).width(), std::max(1, w >> l));
            EXPECT_EQ(p.level(l).height(), std::max(1, h >> l));
            EXPECT_NEAR(p.level(l).mean()[0], mean, 1e-5)
                << w << "x" << h << " level " << l;  // no black bleeding
        }
        EXPECT_EQ(p.level(p.levels() - 1).width() * p.level(p.levels() - 1).height(), 1);
    }
}

TEST(Mip, TrilinearAtALevelOfDetailMatchesTheWidth) {
    MipPyramid p(random_rgb(37, 20, 3));
    // Magnification, between levels, exactly on a level, a double's step below and above one
    // (where trilinear takes the level from the exponent and log2 may round up to the next
    // level), and beyond the coarsest level. Both go through trilinear_levels: exactly equal.
    for (double w :
         {0.5, 1.0, 1.7, 2.0, 3.3, 9.0, 31.0, 32.0, 100.0, std::nextafter(2.0, 0.0),
          std::nextafter(8.0, 0.0), std::nextafter(8.0, 9.0), std::nextafter(16.0, 0.0)}) {
        const Texel a = p.trilinear(0.31, 0.77, w), b = p.trilinear_lod(0.31, 0.77, std::log2(w));
        for (int c = 0; c < 3; ++c) EXPECT_EQ(a[c], b[c]) << w;
    }
    EXPECT_NEAR(p.trilinear_lod(0.31, 0.77, 100)[0], p.level(p.levels() - 1).mean()[0], 1e-7);
    EXPECT_NEAR(p.trilinear_lod(0.31, 0.77, -3)[0], p.bilinear(0, 0.31, 0.77)[0], 1e-7);
}

TEST(Mip, TrilinearLookupMatchesThePyramid) {
    // FilteredTexture::lookup takes the level from the squared width's exponent and the blend
    // weight from its logarithm; MipPyramid::trilinear takes both from log2(width).
    FilteredTexture t(random_rgb(64, 48, 5));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0, 1);
    // Widths on and either side of every power of two, and random ones.
    std::vector<double> widths;
    for (int k = 0; k <= 8; ++k)
        for (double d : {-1e-12, 0.0, 1e-12}) widths.push_back(std::ldexp(1.0, k) * (1 + d));
    for (int k = 0; k < 200; ++k) widths.push_back(std::exp2(9 * unit(rng) - 1));
    for (double w : widths) {
        const double u = unit(rng), v = unit(rng);
        const auto [a, info] = t.lookup_with_info(u, v, Footprint::axes({w / 64, 0}, {0, 0.5 / 48}),
                                                  {FilterKind::Trilinear});
        const Texel b = t.pyramid().trilinear(u, v, w);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-6) << "width " << w;
        EXPECT_NEAR(info.lambda, std::clamp(std::log2(w), 0.0, t.pyramid().levels() - 1.0), 1e-12);
        EXPECT_NEAR(t.pyramid().trilinear_lambda(w), info.lambda, 1e-12) << "width " << w;
    }
}

TEST(Mip, TrilinearFromTheSquaredWidthMatchesTheWidth) {
    // trilinear_width2 takes the level from width^2's exponent, with no square root: the same
    // texels and weight as trilinear(width) up to the logarithm's last bit, on and either side
    // of every power of two (where the root can round onto the next level), for magnification
    // (level 0, lambda 0) and for a NaN width (bilinear at level 0, as trilinear()).
    MipPyramid p(random_rgb(50, 37, 9));
    std::vector<double> widths = {0.3, 1.0, std::nextafter(1.0, 2.0), 1e6};
    for (int k = 0; k <= 7; ++k)
        for (double d : {-1e-15, 0.0, 1e-15, 0.37}) widths.push_back(std::ldexp(1.0, k) * (1 + d));
    for (double w : widths) {
        double lambda = -1;
        const Texel a = p.trilinear_width2(0.63, 0.21, w * w, &lambda),
                    b = p.trilinear(0.63, 0.21, w);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-6) << "width " << w;
        EXPECT_NEAR(lambda, p.trilinear_lambda(w), 1e-12) << "width " << w;
    }
    double lambda = -1;
    const Texel n = p.trilinear_width2(0.63, 0.21, std::nan(""), &lambda);
    EXPECT_EQ(n[0], p.bilinear(0, 0.63, 0.21)[0]);
    EXPECT_EQ(lambda, 0);
}

TEST(Mip, TrilinearIsContinuousAtLambdaOneAndLevelMonotonic) {
    MipPyramid p(tmip1());
    double below = p.trilinear(0.3, 0.6, 2 - 1e-9)[0], at = p.trilinear(0.3, 0.6, 2)[0];
    EXPECT_NEAR(below, at, 1e-6);
    FilteredTexture t(tmip1());
    double last = -1;
    for (double w = 0.25; w < 64; w *= 1.1) {
        const double lambda = t.lookup_with_info(0.3, 0.6, Footprint::axes({w / 4, 0}, {0, w / 8}),
                                                 {FilterKind::Trilinear})
                                  .info.lambda;
        EXPECT_GE(lambda, last);
        last = lambda;
    }
}

// ---- EWA ----------------------------------------------------------------------------------
TEST(Ewa, TEwa1Coefficients) {
    EwaEllipse e = ewa_ellipse(2, 0, 0, 1);
    EXPECT_DOUBLE_EQ(e.A, 2);
    EXPECT_DOUBLE_EQ(e.B, 0);
    EXPECT_DOUBLE_EQ(e.C, 5);
    EXPECT_DOUBLE_EQ(e.F, 10);
    EXPECT_NEAR(e.hx, 2.236068, 1e-6);
    EXPECT_NEAR(e.hy, 1.414214, 1e-6);
    e = ewa_ellipse(3, 1, 1, 2);
    EXPECT_DOUBLE_EQ(e.A, 6);
    EXPECT_DOUBLE_EQ(e.B, -10);
    EXPECT_DOUBLE_EQ(e.C, 11);
    EXPECT_DOUBLE_EQ(e.F, 41);
    EXPECT_NEAR(e.hx, 3.316625, 1e-6);
    EXPECT_NEAR(e.hy, 2.449490, 1e-6);
    e = ewa_ellipse(2, 0, 1, 0);  // collinear: no division by zero
    EXPECT_DOUBLE_EQ(e.A, 1);
    EXPECT_DOUBLE_EQ(e.C, 6);
    EXPECT_DOUBLE_EQ(e.F, 6);
    EXPECT_NEAR(e.hx, std::sqrt(6.0), 1e-9);
    EXPECT_NEAR(e.hy, 1, 1e-9);
}

TEST(Ewa, TEwa1LutValues) {
    const float* lut = ewa_weight_lut();
    EXPECT_NEAR(lut[0], 0.8646647, 1e-6);
    EXPECT_NEAR(lut[64], 0.2296588, 1e-6);
    EXPECT_NEAR(lut[127], 0.0, 1e-7);
    for (int i = 1; i < kEwaLutSize; ++i) EXPECT_LE(lut[i], lut[i - 1]);
}

TEST(Ewa, TEwa2FullLookups) {
    std::vector<float> px(64);
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) px[j * 8 + i] = float((5 * i + 3 * j) % 7) / 6.0f;
    MipPyramid p(Image(8, 8, 1, px));
    EXPECT_NEAR(ewa(p, 0.5, 0.5, 2.0 / 8, 0, 0, 1.0 / 8).value[0], 0.583333, 1e-5);
    EXPECT_NEAR(ewa(p, 0.4, 0.55, 3.0 / 8, 1.0 / 8, 1.0 / 8, 2.0 / 8).value[0], 0.499428, 1e-5);
    EXPECT_NEAR(ewa(p, 0.1, 0.9, 1.5 / 8, 1.5 / 8, 0.5 / 8, -0.5 / 8).value[0], 0.520615, 1e-5);
}

TEST(Ewa, TCmam2CircleOfRadiusTwoTexels) {
    MipPyramid p(tmip1());
    EXPECT_NEAR(ewa(p, 0.8, 0.6, 2.0 / 4, 0, 0, 2.0 / 4).value[0], 2.465593, 1e-5);
}

TEST(Ewa, TMip2RampIsSymmetric) {
    std::vector<float> px(16 * 16);
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) px[j * 16 + i] = float(i);
    MipPyramid p(Image(16, 16, 1, px, WrapMode::Clamp, WrapMode::Clamp));
    for (auto [au, av, bu, bv] :
         {std::tuple{0.1, 0.02, -0.01, 0.05}, {0.05, 0.0, 0.0, 0.05}, {0.2, 0.2, 0.01, -0.01}})
        EXPECT_NEAR(ewa(p, 0.5, 0.5, au, av, bu, bv).value[0], 7.5, 1e-4);
}

TEST(Ewa, LevelIsContinuousAcrossPowersOfTwo) {
    // The level is |b|'s binary exponent and the blend weight log2|b| minus it, with |b| rounded
    // to single precision; either side of a power of two the result must not jump.
    MipPyramid p(random_rgb(128, 128, 9));
    for (int k = 0; k <= 7; ++k)
        for (double d : {-1e-5, -1e-9, 0.0, 1e-9, 1e-5}) {
            // Axes 3|b| and |b| long at 30 degrees, |b| = 2^k (1 + d) level-0 texels.
            auto look = [&](double lb) {
                const double b = lb / 128, c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
                return ewa(p, 0.37, 0.61, 3 * b * c, 3 * b * s, -b * s, b * c);
            };
            const EwaResult r = look(std::ldexp(1.0, k) * (1 + d)), at = look(std::ldexp(1.0, k));
            const double single = static_cast<float>(r.minor);
            EXPECT_EQ(r.lambda, std::clamp(std::log2(single), 0.0, 7.0)) << k << " " << d;
            EXPECT_NEAR(r.lambda, std::clamp(std::log2(r.minor), 0.0, 7.0), 1e-7) << k << " " << d;
            // |b| 1e-5 away moves lambda by 1.4e-5: allow for that much change, and no more than
            // 1e-5 where |b| is the power of two to single precision.
            const double tol = std::abs(d) > 1e-6 ? 1e-4 : 1e-5;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.value[c], at.value[c], tol) << k << " " << d;
        }
}

TEST(Ewa, PowerOfTwoMinorAxisToSinglePrecisionReadsOneLevel) {
    // A rotated footprint's minor axis is a power of two only to within the rounding of its
    // components. When it rounds to one in single precision the lookup reads one level, as an
    // axis-aligned footprint of that size does, instead of a second level weighted about 1e-7.
    MipPyramid p(random_rgb(256, 256, 21));
    int rotated_one_level = 0;
    for (int deg = 1; deg < 90; ++deg)
        for (int aniso : {1, 4}) {
            const double th = deg * M_PI / 180, b = 8.0 / 256, a = b * aniso;
            const float au = float(a * std::cos(th)), av = float(a * std::sin(th)),
                        bu = float(-b * std::sin(th)), bv = float(b * std::cos(th));
            const EwaResult r = ewa(p, 0.41, 0.27, au, av, bu, bv);
            EXPECT_NEAR(r.lambda, 3.0, 2e-7) << deg << " " << aniso;
            if (static_cast<float>(r.minor) != 8.0f) continue;
            EXPECT_EQ(r.lambda, 3.0) << deg << " " << aniso;
            // What the level-3 ellipse alone reads (level 3 is 32 texels wide).
            const EwaLevelResult level3 =
                ewa_level(p.level(3), 0.41, 0.27, au * 32.0, av * 32.0, bu * 32.0, bv * 32.0);
            EXPECT_EQ(r.texels_read, level3.texels_read) << deg << " " << aniso;
            rotated_one_level += r.minor != 8.0;
        }
    // Most rotations leave |b| inexact in double precision but exact in single.
    EXPECT_GT(rotated_one_level, 89) << rotated_one_level;
    EXPECT_EQ(ewa(p, 0.41, 0.27, 8.0 / 256, 0, 0, 8.0 / 256).lambda, 3.0);
}

TEST(Ewa, DegenerateMinorAxisStillFiltersAndCostIsBounded) {
    std::vector<float> px(256 * 256);
    for (int j = 0; j < 256; ++j)
        for (int i = 0; i < 256; ++i) px[j * 256 + i] = float((i + j) % 2);  // fine checker
    MipPyramid p(Image(256, 256, 1, px));
    EwaResult r = ewa(p, 0.5, 0.5, 64.0 / 256, 0, 0, 0);  // a line, 64 texels long
    EXPECT_NEAR(r.value[0], 0.5, 0.05) << "filters across the line instead of point sampling";
    EXPECT_GT(r.minor, 0);
    int small = ewa(p, 0.3, 0.3, 2.0 / 256, 0.5 / 256, 0, 0.5 / 256, 8).texels_read;
    int large = ewa(p, 0.3, 0.3, 2000.0 / 256, 500.0 / 256, 0, 250.0 / 256, 8).texels_read;
    EXPECT_LT(large, 4 * std::max(small, 40)) << small << " vs " << large;
}

// One EWA level straight from algorithms.md §4.3: every lattice point of the bounding box, Q
// evaluated directly, texels fetched through Image::fetch. The library walks exact spans along
// rows or columns through offset tables instead; both must weigh the same texels.
Texel bounding_box_ewa(const Image& img, double u, double v, double as, double at, double bs,
                       double bt, int* count) {
    const EwaEllipse e = ewa_ellipse(as, at, bs, bt);
    const double A = e.A / e.F, B = e.B / e.F, C = e.C / e.F;
    const double s0 = u * img.width() - 0.5, t0 = v * img.height() - 0.5;
    const float* lut = ewa_weight_lut();
    double sum[4] = {0, 0, 0, 0}, wsum = 0;
    for (int64_t it = int64_t(std::ceil(t0 - e.hy)); it <= int64_t(std::floor(t0 + e.hy)); ++it)
        for (int64_t is = int64_t(std::ceil(s0 - e.hx)); is <= int64_t(std::floor(s0 + e.hx));
             ++is) {
            const double x = is - s0, y = it - t0, q = A * x * x + B * x * y + C * y * y;
            if (!(q < 1)) continue;
            const double w = lut[std::min(int(q * kEwaLutSize), kEwaLutSize - 1)];
            const Texel t = img.fetch(is, it);
            for (int c = 0; c < 4; ++c) sum[c] += w * t[c];
            wsum += w;
            ++*count;
        }
    Texel out{};
    for (int c = 0; c < 4; ++c) out[c] = float(sum[c] / wsum);
    return out;
}

class EwaWrap : public ::testing::TestWithParam<WrapMode> {};

TEST_P(EwaWrap, LevelMatchesABoundingBoxScan) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    // Sizes include odd ones and images narrower than the ellipse (spans longer than a period).
    for (auto [w, h] : {std::pair{37, 20}, {5, 3}, {16, 16}, {1, 9}}) {
        const Image img = random_rgb(w, h, unsigned(w * 100 + h), GetParam());
        for (int k = 0; k < 300; ++k) {
            // Axes in level texels, any orientation, 0.2 to 24 texels long, so that the walk
            // runs along rows for some ellipses and along columns for others.
            const double th = 2 * M_PI * unit(rng), la = 0.2 + 24 * unit(rng) * unit(rng);
            const double lb = la * (0.05 + 0.95 * unit(rng));
            const double as = la * std::cos(th), at = la * std::sin(th);
            const double bs = -lb * std::sin(th), bt = lb * std::cos(th);
            const double u = 3 * unit(rng) - 1, v = 3 * unit(rng) - 1;
            int ref_n = 0;
            const auto [ours, ours_n] = ewa_level(img, u, v, as, at, bs, bt);
            const Texel ref = bounding_box_ewa(img, u, v, as, at, bs, bt, &ref_n);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(ours[c], ref[c], 1e-5 * (1 + std::abs(ref[c])))
                    << w << "x" << h << " footprint " << k << " channel " << c;
            // Texels whose Q rounds to either side of 1 may be counted by one and not the other.
            EXPECT_NEAR(ours_n, ref_n, 2) << w << "x" << h << " footprint " << k;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Wraps, EwaWrap,
                         ::testing::Values(WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black,
                                           WrapMode::Mirror),
                         [](const auto& info) { return std::string(to_string(info.param)); });

// ---- properties over filter x wrap --------------------------------------------------------
class FilterWrap : public ::testing::TestWithParam<std::tuple<FilterKind, WrapMode>> {};

TEST_P(FilterWrap, ConstantTextureGivesTheConstant) {
    auto [kind, wrap] = GetParam();
    FilteredTexture t(Image(17, 11, 3, std::vector<float>(17 * 11 * 3, 0.375f), wrap, wrap));
    for (Footprint fp : {Footprint::none(), Footprint::axes({0.01, 0}, {0, 0.02}),
                         Footprint::axes({0.3, 0.1}, {-0.05, 0.2}), Footprint::axes({3, 0}, {0, 3}),
                         Footprint::axes({0.2, 0}, {0, 0})})
        for (double u : {0.01, 0.5, 0.93})
            for (double v : {0.02, 0.5, 0.97}) {
                Texel x = t.lookup(u, v, fp, {kind, 8});
                if (wrap == WrapMode::Black) {
                    EXPECT_LE(x[1], 0.375f + 1e-5f);  // may fade to black near the border
                    EXPECT_GE(x[1], -1e-5f);
                } else {
                    EXPECT_NEAR(x[1], 0.375f, 1e-5f) << to_string(kind) << " " << u << "," << v;
                }
            }
}

TEST_P(FilterWrap, NonFiniteInputsReturnTheMean) {
    auto [kind, wrap] = GetParam();
    FilteredTexture t(tmip1(wrap));
    double nan = std::nan("");
    double inf = std::numeric_limits<double>::infinity();
    const LookupResult r = t.lookup_with_info(nan, 0.5, Footprint::none(), {kind});
    EXPECT_FLOAT_EQ(r.value[0], 2.5f);
    EXPECT_TRUE(r.info.fallback);
    EXPECT_FLOAT_EQ(t.lookup(0.5, 0.5, Footprint::axes({inf, 0}, {0, 0.1}), {kind})[0], 2.5f);
    EXPECT_FLOAT_EQ(t.lookup(0.5, 0.5, Footprint::axes({0.1, nan}, {0, 0.1}), {kind})[0], 2.5f);
    EXPECT_TRUE(std::isfinite(
        t.lookup(1e300, -1e300, Footprint::axes({1e300, 0}, {0, 1e-300}), {kind})[0]));
    // Finite but far beyond any texel index: the mean, with no out-of-range conversion (the
    // asan preset traps float-cast-overflow).
    for (double far : {1e300, -1e18, 4e9})
        EXPECT_FLOAT_EQ(t.lookup(far, 0.5, Footprint::axes({0.01, 0}, {0, 0.02}), {kind})[0], 2.5f)
            << far;
}

TEST_P(FilterWrap, ChannelsAreFilteredIndependentlyAndExactly) {
    // Three- and four-channel texels are filtered four lanes at a time where possible (and one
    // channel at a time elsewhere): each channel must equal, bit for bit, the same lookup on a
    // one-channel texture holding that channel alone. Footprints from magnified to a few times
    // the texture, at points inside, near the edges and beyond them.
    auto [kind, wrap] = GetParam();
    const int w = 23, h = 14;
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> unit(0, 1);
    std::vector<float> px(std::size_t(w) * h * 4);
    for (float& x : px) x = unit(rng);
    std::vector<std::unique_ptr<FilteredTexture>> single;
    for (int c = 0; c < 4; ++c) {
        std::vector<float> one(std::size_t(w) * h);
        for (std::size_t i = 0; i < one.size(); ++i) one[i] = px[4 * i + c];
        single.push_back(std::make_unique<FilteredTexture>(Image(w, h, 1, one, wrap, wrap)));
    }
    for (int nc : {3, 4}) {
        std::vector<float> many(std::size_t(w) * h * nc);
        for (std::size_t i = 0; i < std::size_t(w) * h; ++i)
            for (int c = 0; c < nc; ++c) many[i * nc + c] = px[4 * i + c];
        FilteredTexture t(Image(w, h, nc, many, wrap, wrap));
        std::uniform_real_distribution<double> pos(-0.3, 1.3), size(-7, 1), angle(0, 6.3);
        for (int k = 0; k < 300; ++k) {
            const double u = pos(rng), v = pos(rng), a = std::exp2(size(rng)),
                         b = a * std::exp2(-3 * unit(rng)), th = angle(rng);
            const Footprint fp = Footprint::axes({a * std::cos(th), a * std::sin(th)},
                                                 {-b * std::sin(th), b * std::cos(th)});
            const Texel x = t.lookup(u, v, fp, {kind, 8});
            for (int c = 0; c < 4; ++c) {
                const float expect = c < nc ? single[c]->lookup(u, v, fp, {kind, 8})[0] : 0.0f;
                EXPECT_EQ(x[c], expect)
                    << nc << " channels, channel " << c << " at " << u << "," << v << " size " << a;
            }
        }
    }
}

TEST(Filter, SymmetricFootprintOnALinearRampGivesTheCentre) {
    // Clamp keeps the ramp linear at the border; nearest is not a symmetric filter.
    std::vector<float> px(64 * 64);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) px[j * 64 + i] = float(i + 0.5);  // value = s at texel centres
    FilteredTexture t(Image(64, 64, 1, px, WrapMode::Clamp, WrapMode::Clamp));
    for (FilterKind kind : {FilterKind::Bilinear, FilterKind::Trilinear, FilterKind::Sat,
                            FilterKind::Ewa, FilterKind::Area}) {
        Texel x = t.lookup(0.5, 0.5, Footprint::axes({4.0 / 64, 1.0 / 64}, {-1.0 / 64, 3.0 / 64}),
                           {kind});
        EXPECT_NEAR(x[0], 32.0, 1e-3) << to_string(kind);
    }
}

INSTANTIATE_TEST_SUITE_P(
    All, FilterWrap,
    ::testing::Combine(::testing::Values(FilterKind::Nearest, FilterKind::Bilinear,
                                         FilterKind::Trilinear, FilterKind::Sat, FilterKind::Ewa,
                                         FilterKind::Area),
                       ::testing::Values(WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black)),
    [](const auto& info) {
        return std::string(to_string(std::get<0>(info.param))) + "_" +
               std::string(to_string(std::get<1>(info.param)));
    });

TEST(Filter, ParseAndPrintRoundTrip) {
    for (int k = 0; k < kFilterKinds; ++k)
        EXPECT_EQ(parse_filter(to_string(FilterKind(k))), FilterKind(k));
    EXPECT_FALSE(parse_filter("gaussian"));
}

TEST(Colour, TCol1MinifiedSrgbCheckerIsLinearHalf) {
    std::vector<float> px(64 * 64);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) px[j * 64 + i] = srgb_to_linear(((i + j) % 2) ? 1.0f : 0.0f);
    FilteredTexture t(Image(64, 64, 1, px));
    float lin = t.lookup(0.5, 0.5, Footprint::axes({0.5, 0}, {0, 0.5}), {FilterKind::Trilinear})[0];
    EXPECT_NEAR(lin, 0.5, 1e-6);
    EXPECT_NEAR(linear_to_srgb(lin), 0.735357, 1e-5);
}

TEST(Filter, PbrtTrilinearWidthUsesTheLargestComponent) {
    FilteredTexture t(tmip1());
    Footprint fp = Footprint::axes({1.0 / 4, 1.0 / 4}, {0, 0.5 / 4});  // (1,1) and (0,0.5) texels
    const LookupInfo gl = t.lookup_with_info(0.3, 0.6, fp, {FilterKind::Trilinear, 8, false}).info;
    const LookupInfo pbrt = t.lookup_with_info(0.3, 0.6, fp, {FilterKind::Trilinear, 8, true}).info;
    EXPECT_NEAR(gl.width, std::sqrt(2.0), 1e-12);
    EXPECT_NEAR(pbrt.width, 1.0, 1e-12);
}

TEST(Ewa, MaximumAnisotropyIsCappedSoCostStaysBounded) {
    // A footprint a million times longer than wide: with the maximum anisotropy unbounded it
    // would read about a million texels per line; it reads what the cap allows, and exactly
    // what a request at the cap reads.
    MipPyramid p(random_rgb(256, 256, 5));
    const double th = 0.3, a = 4096.0 / 256, b = a / 1e6;
    auto look = [&](double max_aniso) {
        return ewa(p, 0.4, 0.6, a * std::cos(th), a * std::sin(th), -b * std::sin(th),
                   b * std::cos(th), max_aniso);
    };
    const EwaResult capped = look(kEwaMaxAnisotropy);
    for (double m : {1e6, 1e300, std::numeric_limits<double>::infinity()}) {
        const EwaResult r = look(m);
        EXPECT_EQ(r.texels_read, capped.texels_read) << m;
        EXPECT_EQ(r.minor, capped.minor) << m;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(r.value[c], capped.value[c]) << m;
    }
    EXPECT_LT(capped.texels_read, 4000);
    EXPECT_EQ(look(std::nan("")).minor, look(1).minor);  // NaN is 1, as below 1
}

TEST(Sat, CornersBeyondRangeOrNotNumbersGiveTheMean) {
    const Image img = random_rgb(16, 8, 3);
    for (WrapMode w : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black}) {
        const Image wrapped(16, 8, 3, img.row_major(), w, w);
        const SummedAreaTable sat(wrapped);
        const double nan = std::nan("");
        for (const auto& r : std::vector<std::array<double, 4>>{
                 {0, 0, 3e9, 2}, {-5e12, 1, 2, 3}, {nan, 0, 1, 1}, {0, 0, 1, -INFINITY}}) {
            const Texel avg = sat.average(r[0], r[1], r[2], r[3]);
            for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(avg[c], wrapped.mean()[c]);
        }
        const Texel big = sat.integral(0, 0, 3e9, 2);
        EXPECT_NEAR(big[0], wrapped.mean()[0] * 6e9, 1e3);
        EXPECT_EQ(sat.integral(nan, 0, 1, 1)[0], 0.0f);
        const Texel poly = polygon_integral(sat, {{0, 0}, {4e9, 0}, {0, 1}});
        EXPECT_NEAR(poly[1], wrapped.mean()[1] * 2e9, 1e3);
    }
}
