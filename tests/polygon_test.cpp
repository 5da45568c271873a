// Polygon clipping, difference and hull, and exact polygon integrals (algorithms.md §5, §12
// T-POLY-1 and T-POLY-2), Green's theorem against the cell-clipping oracle.
#include <cmam/texture/polygon.h>
#include <gtest/gtest.h>

#include <random>

using namespace cmam::texture;

namespace {
Image tex2x2(WrapMode w = WrapMode::Repeat) {
    return Image(2, 2, 1, {1, 2, 3, 4}, w, w);
}
double total_area(const std::vector<Polygon>& ps) {
    double a = 0;
    for (const auto& p : ps) a += signed_area(p);
    return a;
}
}  // namespace

class PolyStorage : public ::testing::TestWithParam<SummedAreaTable::Storage> {};

TEST_P(PolyStorage, TPoly1Integrals) {
    Image img = tex2x2();
    SummedAreaTable sat(img, GetParam());
    Polygon tri = {{0, 0}, {2, 0}, {0, 2}};
    EXPECT_NEAR(signed_area(tri), 2, 1e-12);
    EXPECT_NEAR(polygon_integral(sat, tri)[0], 3.5, 1e-5);
    EXPECT_NEAR(polygon_integral_cells(img, tri)[0], 3.5, 1e-6);  // float result
    Polygon para = {{0.5, 0.25}, {1.75, 0.75}, {1.25, 1.75}, {0, 1.25}};
    EXPECT_NEAR(signed_area(para), 1.5, 1e-12);
    EXPECT_NEAR(polygon_integral(sat, para)[0], 3.6, 1e-5);
    EXPECT_NEAR(polygon_integral_cells(img, para)[0], 3.6, 1e-6);
    Polygon cw(para.rbegin(), para.rend());  // orientation does not matter
    EXPECT_NEAR(polygon_integral(sat, cw)[0], 3.6, 1e-5);
}

TEST_P(PolyStorage, GreenMatchesTheCellOracleOnRandomTrianglesAndWraps) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> val(0, 1);
    std::uniform_real_distribution<double> pos(-6, 12);
    std::vector<float> px(7 * 5);
    for (float& p : px) p = val(rng);
    for (WrapMode w : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black}) {
        Image img(7, 5, 1, px, w, w);
        SummedAreaTable sat(img, GetParam());
        for (int k = 0; k < 100; ++k) {
            Polygon t = {{pos(rng), pos(rng)}, {pos(rng), pos(rng)}, {pos(rng), pos(rng)}};
            EXPECT_NEAR(polygon_integral(sat, t)[0], polygon_integral_cells(img, t)[0], 2e-3)
                << to_string(w);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Storage, PolyStorage,
                         ::testing::Values(SummedAreaTable::Storage::Double,
                                           SummedAreaTable::Storage::MeanOffsetFloat));

TEST(Polygon, TPoly2Difference) {
    Image img = tex2x2();
    SummedAreaTable sat(img, SummedAreaTable::Storage::Double);
    Polygon square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    auto pieces = difference({{0, 0}, {2, 0}, {0, 2}}, square);
    EXPECT_EQ(pieces.size(), 2u);
    EXPECT_NEAR(total_area(pieces), 1, 1e-12);
    double integral = 0;
    for (const auto& p : pieces) integral += polygon_integral(sat, p)[0];
    EXPECT_NEAR(integral, 2.5, 1e-9);
    EXPECT_TRUE(difference({{0.2, 0.2}, {0.8, 0.2}, {0.2, 0.8}}, square).empty());
    auto all = difference({{3, 3}, {4, 3}, {3, 4}}, square);  // disjoint: all of it is new
    EXPECT_NEAR(total_area(all), 0.5, 1e-12);
    EXPECT_NEAR(total_area(difference({{0, 0}, {2, 0}, {0, 2}}, {})), 2, 1e-12);
}

TEST(Polygon, HullIsCounterClockwiseAndDropsInteriorPoints) {
    Polygon h = convex_hull({{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 0}});
    EXPECT_EQ(h.size(), 4u);
    EXPECT_NEAR(signed_area(h), 4, 1e-12);
}
