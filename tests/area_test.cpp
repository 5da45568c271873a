// The area filter (algorithms.md §5.2): exact integrals over parallelograms and triangles against
// the cell-clipping oracle for every wrap mode, the level rule's error against level-0
// integration, constants, ramps, strata that tile their pixel, and the reconstruction term.
#include <cmam/texture/area.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>
#include <cmam/texture/polygon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

using namespace cmam::texture;

namespace {

std::vector<float> noise(int w, int h, int c, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0, 1);
    std::vector<float> px(std::size_t(w) * h * c);
    for (float& x : px) x = unit(rng);
    return px;
}

Polygon to_polygon(const Vec2d* v, int n) {
    return Polygon(v, v + n);
}

// The parallelogram (cx, cy) ± a/2 ± b/2, corners in order.
void parallelogram(double cx, double cy, Vec2d a, Vec2d b, Vec2d* p) {
    p[0] = {cx - 0.5 * (a.u + b.u), cy - 0.5 * (a.v + b.v)};
    p[1] = {cx + 0.5 * (a.u - b.u), cy + 0.5 * (a.v - b.v)};
    p[2] = {cx + 0.5 * (a.u + b.u), cy + 0.5 * (a.v + b.v)};
    p[3] = {cx - 0.5 * (a.u - b.u), cy - 0.5 * (a.v - b.v)};
}

// A random parallelogram (centre, two sides) in texel space; sides from 0.05 to 20 texels.
void random_parallelogram(std::mt19937& rng, double lo, double hi, Vec2d* p) {
    std::uniform_real_distribution<double> pos(lo, hi), size(-3, 3.2), angle(0, 6.3);
    const double cx = pos(rng), cy = pos(rng);
    const double la = std::exp2(size(rng)), lb = std::exp2(size(rng));
    const double ta = angle(rng), tb = angle(rng);
    parallelogram(cx, cy, {la * std::cos(ta), la * std::sin(ta)},
                  {lb * std::cos(tb), lb * std::sin(tb)}, p);
}

}  // namespace

class AreaWrap : public ::testing::TestWithParam<WrapMode> {};

TEST_P(AreaWrap, RowPrefixIntegralMatchesTheCellOracle) {
    // Parallelograms and triangles inside, across and beyond the edges of a 13x7 three-channel
    // texture: Green's theorem on the row prefixes equals clipping the polygon to every texel.
    const WrapMode w = GetParam();
    Image img(13, 7, 3, noise(13, 7, 3, 3), w, w);
    RowPrefixTable table(img);
    std::mt19937 rng(11);
    for (int k = 0; k < 400; ++k) {
        Vec2d p[4];
        random_parallelogram(rng, -15, 28, p);
        const int n = k % 4 == 3 ? 3 : 4;  // every fourth a triangle
        const Texel got = table.integral(p, n);
        const Texel want = polygon_integral_cells(img, to_polygon(p, n));
        const double area = std::abs(signed_area(to_polygon(p, n)));
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(got[c], want[c], 1e-5 * std::max(1.0, area))
                << to_string(w) << " polygon " << k << " channel " << c;
        // Orientation does not matter.
        const Vec2d r[4] = {p[3], p[2], p[1], p[0]};
        const Vec2d* rp = n == 4 ? r : r + 1;
        EXPECT_NEAR(table.integral(rp, n)[0], got[0], 1e-5 * std::max(1.0, area));
    }
}

TEST(Area, RepeatRegionsAcrossThePeriodsEdgeMatchTheCellOracle) {
    // A repeating texture's edges that leave the table by less than a period are cut at x = W
    // and y = H and walked in parts inside it (algorithms.md §5.2): regions around the corner
    // (W, H) of 1-, 3- and 4-channel textures, and edges exactly on those lines.
    for (const int nc : {1, 3, 4}) {
        Image img(40, 24, nc, noise(40, 24, nc, 7 + nc), WrapMode::Repeat, WrapMode::Repeat);
        RowPrefixTable table(img);
        std::mt19937 rng(29 + nc);
        for (int k = 0; k < 300; ++k) {
            Vec2d p[4];
            random_parallelogram(rng, 18, 46, p);
            const Texel got = table.integral(p, 4);
            const Texel want = polygon_integral_cells(img, to_polygon(p, 4));
            const double area = std::abs(signed_area(to_polygon(p, 4)));
            for (int c = 0; c < nc; ++c)
                ASSERT_NEAR(got[c], want[c], 1e-5 * std::max(1.0, area))
                    << nc << " channels, polygon " << k << " channel " << c;
        }
        // Edges on x = W and y = H, a corner on (W, H), and an edge ending on x = W.
        const Vec2d on_lines[][4] = {{{40, 20}, {52, 20}, {52, 30}, {40, 30}},
                                     {{33.5, 24}, {40, 24}, {40, 31.25}, {33.5, 31.25}},
                                     {{36.25, 17.5}, {40, 24}, {45.5, 30.5}, {41.75, 24}},
                                     {{30, 10}, {40, 23}, {40, 26}, {30, 13}}};
        // Edges through the corner (W, H) give two cuts at about the same point, in either
        // order after rounding: parts a rounding's width long or outside the table.
        std::uniform_real_distribution<double> tiny(-1e-12, 1e-12), slope(0.2, 5), len(1, 12);
        for (int k = 0; k < 200; ++k) {
            const Vec2d c = k % 2 ? Vec2d{40 + tiny(rng), 24 + tiny(rng)} : Vec2d{40, 24};
            const double m = slope(rng), l0 = len(rng), l1 = len(rng), w = len(rng) / 4;
            const Vec2d q[4] = {{c.u - l0, c.v - l0 * m},
                                {c.u + l1, c.v + l1 * m},
                                {c.u + l1 + w, c.v + l1 * m},
                                {c.u - l0 + w, c.v - l0 * m}};
            const Texel got = table.integral(q, 4);
            const Texel want = polygon_integral_cells(img, to_polygon(q, 4));
            const double area = std::abs(signed_area(to_polygon(q, 4)));
            for (int c2 = 0; c2 < nc; ++c2)
                ASSERT_NEAR(got[c2], want[c2], 1e-5 * std::max(1.0, area))
                    << nc << " channels, corner case " << k;
        }
        for (const auto& q : on_lines) {
            const Texel got = table.integral(q, 4);
            const Texel want = polygon_integral_cells(img, to_polygon(q, 4));
            const double area = std::abs(signed_area(to_polygon(q, 4)));
            for (int c = 0; c < nc; ++c)
                EXPECT_NEAR(got[c], want[c], 1e-5 * area) << nc << " channels, channel " << c;
        }
    }
}

TEST_P(AreaWrap, RowsBuiltOnDemandEqualTheWholeTable) {
    // A table built on demand builds the rows a region reads as it first reads them: each
    // polygon, inside, across and beyond the edges of a 150x70 texture (too large for a margin),
    // on a fresh table of a texture of its own, integrates to the whole table's value bit for
    // bit (a row read before it was built would hold another texture's sums, or nothing).
    const WrapMode w = GetParam();
    const int tw = 150, th = 70;
    // A stored row: W + 1 knots of three floats (1,812 bytes), padded to an odd number of
    // 64-byte lines (29).
    const std::size_t row_bytes = 29 * 64;
    std::mt19937 rng(41);
    for (int k = 0; k < 120; ++k) {
        const Image img(tw, th, 3, noise(tw, th, 3, 100 + k), w, w);
        const RowPrefixTable whole(img), lazy(img, RowPrefixTable::OnDemand{});
        EXPECT_EQ(lazy.memory_bytes(), 0u);
        Vec2d p[4];
        if (k % 3 == 0)
            random_parallelogram(rng, 20, 50, p);  // inside: a few bands
        else
            random_parallelogram(rng, -90, 240, p);
        const int n = k % 4 == 3 ? 3 : 4;
        const Texel got = lazy.integral(p, n), want = whole.integral(p, n);
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(got[c], want[c]) << to_string(w) << " polygon " << k << " channel " << c;
        if (k % 3 == 0) {
            // Sides up to 9.2 texels: at most 14 rows (one more read at its edge), 3 bands.
            EXPECT_GT(lazy.memory_bytes(), 0u);
            EXPECT_LE(lazy.memory_bytes(), 3 * RowPrefixTable::kBandRows * row_bytes);
        }
        if (k % 2) {  // a copy is a whole table
            const RowPrefixTable copy(lazy);
            EXPECT_EQ(copy.memory_bytes(), whole.memory_bytes());
            EXPECT_EQ(copy.integral(p, n)[1], want[1]);
        }
        lazy.build_all();
        EXPECT_EQ(lazy.memory_bytes(), whole.memory_bytes());
        EXPECT_EQ(lazy.memory_bytes(), th * row_bytes);
    }
}

TEST(RowPrefix, RowsAreAnOddNumberOfCacheLinesApart) {
    // A steep edge reads a knot a row down one column: rows about a power of two bytes apart put
    // all those reads in a few sets of the caches.
    for (const int w : {4, 150, 511, 512, 1024})
        for (const int c : {1, 2, 3, 4}) {
            const int h = 3;
            const Image img(w, h, c, noise(w, h, c, 7), WrapMode::Clamp, WrapMode::Clamp);
            const RowPrefixTable table(img);
            const std::size_t row = table.memory_bytes() / h;
            EXPECT_EQ(row * h, table.memory_bytes());
            EXPECT_GE(row, std::size_t(w + 1) * c * sizeof(float)) << w << "x" << c;
            EXPECT_LT(row, std::size_t(w + 1) * c * sizeof(float) + 128) << w << "x" << c;
            EXPECT_EQ(row % 128, 64u) << w << "x" << c;
        }
}

TEST_P(AreaWrap, ConstantTextureStaysConstant) {
    const WrapMode w = GetParam();
    std::vector<float> px(std::size_t(40) * 24 * 3);
    for (std::size_t i = 0; i < px.size(); ++i)
        px[i] = i % 3 == 0 ? 0.25f : (i % 3 == 1 ? 0.5f : 2);
    FilteredTexture t(Image(40, 24, 3, px, w, w));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> pos(0.1, 0.9), size(-9, 2), angle(0, 6.3);
    for (int k = 0; k < 300; ++k) {
        // Black darkens where the region leaves the texture: keep it inside there.
        const double s = std::exp2(size(rng)) * (w == WrapMode::Black ? 0.05 : 1);
        const double th = angle(rng);
        const Footprint fp = Footprint::axes({s * std::cos(th), s * std::sin(th)},
                                             {-0.3 * s * std::sin(th), 0.3 * s * std::cos(th)});
        const Texel x = t.lookup(pos(rng), pos(rng), fp, {FilterKind::Area});
        EXPECT_NEAR(x[0], 0.25, 1e-5) << s;
        EXPECT_NEAR(x[1], 0.5, 1e-5) << s;
        EXPECT_NEAR(x[2], 2.0, 1e-5) << s;
    }
}

TEST_P(AreaWrap, EachChannelIsItsOwnOneChannelIntegral) {
    // Two, three and four channels walk the boundary with a channel per vector lane, one channel
    // with a row per lane: a channel's integral must still equal, bit for bit, that of a table
    // holding that channel alone. Long regions with steep and shallow edges, inside the table
    // (walked directly), across its edges and beyond; repeating, a 100x60 table has a margin, a
    // 150x70 one none.
    const WrapMode w = GetParam();
    for (const auto& [tw, th] : {std::pair{100, 60}, std::pair{150, 70}}) {
        const std::vector<float> px = noise(tw, th, 4, 23);
        std::vector<RowPrefixTable> single;
        for (int c = 0; c < 4; ++c) {
            std::vector<float> one(std::size_t(tw) * th);
            for (std::size_t i = 0; i < one.size(); ++i) one[i] = px[4 * i + c];
            single.emplace_back(Image(tw, th, 1, one, w, w));
        }
        std::mt19937 rng(29);
        std::uniform_real_distribution<double> pos(-0.2, 1.2), len(0.5, 40), angle(0, 6.3);
        for (int nc : {2, 3, 4}) {
            std::vector<float> many(std::size_t(tw) * th * nc);
            for (std::size_t i = 0; i < std::size_t(tw) * th; ++i)
                for (int c = 0; c < nc; ++c) many[i * nc + c] = px[4 * i + c];
            const RowPrefixTable table(Image(tw, th, nc, many, w, w));
            int steep = 0;
            for (int k = 0; k < 300; ++k) {
                const double cx = pos(rng) * tw, cy = pos(rng) * th, la = len(rng),
                             lb = len(rng) / 8, ta = angle(rng);
                const Vec2d a{la * std::cos(ta), la * std::sin(ta)},
                    b{-lb * std::sin(ta), lb * std::cos(ta)};
                Vec2d p[4];
                parallelogram(cx, cy, a, b, p);
                steep += std::abs(a.u) < std::abs(a.v) && std::abs(a.v) > 4;
                const Texel got = table.integral(p, 4);
                for (int c = 0; c < 4; ++c)
                    ASSERT_EQ(got[c], c < nc ? single[c].integral(p, 4)[0] : 0.0f)
                        << to_string(w) << " " << tw << "x" << th << ", " << nc
                        << " channels, channel " << c << ", region " << k;
            }
            EXPECT_GT(steep, 60);  // long steep edges, walked a row per lane with one channel
        }
    }
}

TEST_P(AreaWrap, SmallRegionsGiveEachChannelItsOneChannelValue) {
    // Under kAreaBlendHi texels the Gauss rules run with a channel per vector lane for two to
    // four channels, and with one of the rule's points per lane for one channel: each channel
    // must still get, bit for bit, what a texture of that channel alone gets. Sides of 0.3 to 6
    // texels (the 3x3, 4x4 and 5x5 rules, their blends, and the 5x5 rule's blend into the region
    // integral), centres inside the texture and beyond its edges.
    const WrapMode w = GetParam();
    const int tw = 24, th = 20;
    const std::vector<float> px = noise(tw, th, 4, 41);
    std::vector<std::unique_ptr<FilteredTexture>> single;
    for (int c = 0; c < 4; ++c) {
        std::vector<float> one(std::size_t(tw) * th);
        for (std::size_t i = 0; i < one.size(); ++i) one[i] = px[4 * i + c];
        single.push_back(std::make_unique<FilteredTexture>(Image(tw, th, 1, one, w, w)));
    }
    std::mt19937 rng(43);
    std::uniform_real_distribution<double> pos(-0.3, 1.3), len(0.3, 6), ratio(0.2, 1),
        angle(0, 6.3);
    for (int nc : {2, 3, 4}) {
        std::vector<float> many(std::size_t(tw) * th * nc);
        for (std::size_t i = 0; i < std::size_t(tw) * th; ++i)
            for (int c = 0; c < nc; ++c) many[i * nc + c] = px[4 * i + c];
        const FilteredTexture t(Image(tw, th, nc, many, w, w));
        for (int k = 0; k < 400; ++k) {
            const double u = pos(rng), v = pos(rng), la = len(rng), lb = la * ratio(rng),
                         ta = angle(rng), tb = ta + 0.3 + angle(rng) / 3;
            const Footprint fp = Footprint::axes({la * std::cos(ta) / tw, la * std::sin(ta) / th},
                                                 {lb * std::cos(tb) / tw, lb * std::sin(tb) / th});
            const Texel got = t.lookup(u, v, fp, {FilterKind::Area});
            for (int c = 0; c < nc; ++c)
                ASSERT_EQ(got[c], single[c]->lookup(u, v, fp, {FilterKind::Area})[0])
                    << to_string(w) << ", " << nc << " channels, channel " << c << ", footprint "
                    << k << " (" << la << " texels)";
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Wraps, AreaWrap,
                         ::testing::Values(WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black,
                                           WrapMode::Mirror),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(Area, LongSteepEdgesMatchTheCellOracle) {
    // Steep edges are walked four rows a group in float positions relative to the edge, at most
    // 64 rows in one frame: longer ones (a polygon given to RowPrefixTable::integral, which the
    // level rule does not bound) in parts. Thin regions 70 to 250 rows tall inside a 1- and a
    // 3-channel table, clamped and repeating (no margin at this size).
    for (const WrapMode w : {WrapMode::Clamp, WrapMode::Repeat}) {
        for (int nc : {1, 3}) {
            const int tw = 160, th = 280;
            Image img(tw, th, nc, noise(tw, th, nc, 31), w, w);
            RowPrefixTable table(img);
            std::mt19937 rng(37);
            std::uniform_real_distribution<double> height(70, 250), lean(-0.9, 0.9), width(0.3, 6);
            for (int k = 0; k < 40; ++k) {
                const double hgt = height(rng), dx = lean(rng) * hgt, wd = width(rng);
                const double x0 = 5 + std::max(0.0, -dx), y0 = 0.5 * (th - hgt) + 0.37 * k;
                const Vec2d p[4] = {
                    {x0, y0}, {x0 + wd, y0}, {x0 + wd + dx, y0 + hgt}, {x0 + dx, y0 + hgt}};
                const Texel got = table.integral(p, 4);
                const Texel want = polygon_integral_cells(img, to_polygon(p, 4));
                const double area = wd * hgt;
                for (int c = 0; c < nc; ++c)
                    ASSERT_NEAR(got[c], want[c], 1e-5 * area)
                        << to_string(w) << ", " << nc << " channels, region " << k;
            }
        }
    }
}

TEST(Area, RegionsBeyondTheRepeatMarginMatchTheCellOracle) {
    // A repeating table of at most RowPrefixTable::kMarginMaxSize texels continues by
    // periodicity for kMarginKnots knots and kMarginRows rows past (W, H): regions leaving the
    // base period by less are walked directly, longer edges are cut at x = W and y = H, as are
    // a larger table's. Long regions around the corner (W, H) of 1- and 3-channel textures, with
    // and without the margin, take every path.
    for (const auto& [w, h] : {std::pair{90, 60}, std::pair{150, 130}})
        for (const int nc : {1, 3}) {
            Image img(w, h, nc, noise(w, h, nc, 17 + nc), WrapMode::Repeat, WrapMode::Repeat);
            RowPrefixTable table(img);
            std::mt19937 rng(41 + nc);
            std::uniform_real_distribution<double> offset(-15, 15), len(15, 60), angle(0, 6.3),
                width(0.5, 6);
            for (int k = 0; k < 120; ++k) {
                const double cx = w + offset(rng), cy = h + offset(rng), l = len(rng),
                             th = angle(rng), wd = width(rng);
                const Vec2d a{l * std::cos(th), l * std::sin(th)},
                    b{-wd * std::sin(th), wd * std::cos(th)};
                Vec2d p[4];
                parallelogram(cx, cy, a, b, p);
                const Texel got = table.integral(p, 4);
                const Texel want = polygon_integral_cells(img, to_polygon(p, 4));
                const double area = std::abs(signed_area(to_polygon(p, 4)));
                for (int c = 0; c < nc; ++c)
                    ASSERT_NEAR(got[c], want[c], 1e-5 * std::max(1.0, area))
                        << w << "x" << h << ", " << nc << " channels, polygon " << k << " channel "
                        << c;
            }
        }
}

TEST(Area, Tpoly1NumbersThroughTheRowPrefixes) {
    // algorithms.md §12 T-POLY-1 on the 2x2 texture [1 2; 3 4].
    Image img(2, 2, 1, {1, 2, 3, 4}, WrapMode::Repeat, WrapMode::Repeat);
    RowPrefixTable table(img);
    const Vec2d tri[3] = {{0, 0}, {2, 0}, {0, 2}};
    EXPECT_NEAR(table.integral(tri, 3)[0], 3.5, 1e-6);
    const Vec2d para[4] = {{0.5, 0.25}, {1.75, 0.75}, {1.25, 1.75}, {0, 1.25}};
    EXPECT_NEAR(table.integral(para, 4)[0], 3.6, 1e-6);
}

TEST(Area, LevelRuleErrorAgainstLevelZeroIsBounded) {
    // White noise is the worst case for integrating on a coarser level: every texel differs.
    // Regions from 1 to 300 texels wide and anisotropy up to 16, integrated by the level rule
    // and exactly on level 0; the difference is stated in algorithms.md §5.2.
    const int n = 512;
    FilteredTexture t(Image(n, n, 1, noise(n, n, 1, 9)));
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> pos(0, 1), size(0, 8.2), aniso(0, 4), angle(0, 6.3);
    double sum2 = 0, worst = 0;
    int coarse = 0, count = 0;
    for (int k = 0; k < 400; ++k) {
        const double minor = std::exp2(size(rng)) / n,
                     major = std::max(minor * std::exp2(aniso(rng)), kAreaBlendHi / n);
        const double th = angle(rng), u = pos(rng), v = pos(rng);
        const Vec2d a{major * std::cos(th), major * std::sin(th)},
            b{-minor * std::sin(th), minor * std::cos(th)};
        const AreaRegion g = area_region(t, u, v, a, b);
        const double exact = t.row_prefix(0).integral(g.corners, 4)[0] / g.area;
        const AreaResult r = area_parallelogram(t, u, v, a, b);
        EXPECT_EQ(r.level, g.level);
        const double e = r.value[0] - exact;
        sum2 += e * e;
        worst = std::max(worst, std::abs(e));
        coarse += r.level > 0;
        ++count;
    }
    const double rms = std::sqrt(sum2 / count);
    RecordProperty("rms_error", std::to_string(rms));
    RecordProperty("max_error", std::to_string(worst));
    std::printf("level rule vs level 0 on white noise: rms %.5f, max %.5f, %d of %d coarser\n", rms,
                worst, coarse, count);
    EXPECT_GT(coarse, count / 2);  // the rule does pick coarser levels
    EXPECT_LT(rms, 0.006);         // measured 0.0034
    EXPECT_LT(worst, 0.04);        // measured 0.020
}

TEST(Area, CostIsBoundedByThePerimeterRule) {
    // However large or anisotropic the region, the boundary walk reads O(kAreaMaxPerimeter),
    // for every pair of wrap modes: with one periodic axis and one not, a region many times the
    // texture once walked every period along the periodic one (the knot count below does not
    // see that walk, the time did: 1.5 s for one fuzzed lookup).
    const WrapMode modes[] = {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black, WrapMode::Mirror};
    for (WrapMode ws : modes)
        for (WrapMode wt : modes) {
            FilteredTexture t(Image(256, 64, 1, noise(256, 64, 1, 2), ws, wt));
            for (double s : {1e-4, 0.01, 0.1, 1.0, 30.0, 3e4})
                for (double aniso : {1.0, 8.0, 64.0, 1e4}) {
                    const AreaResult r = area_parallelogram(t, 0.3, 0.6, {s, 0}, {0, s / aniso});
                    EXPECT_LE(r.knots, 3 * kAreaMaxPerimeter) << s << " aniso " << aniso;
                    const int top = t.pyramid().levels() - 1;
                    if (r.level == top && r.knots > 1) {
                        // Walked on the coarsest level: its perimeter there is within the bound,
                        // or neither axis is periodic (rows and columns outside are closed forms).
                        const double periods = 2 * (s + s / aniso) * t.pyramid().level(top).width();
                        const bool periodic = ws == WrapMode::Repeat || ws == WrapMode::Mirror ||
                                              wt == WrapMode::Repeat || wt == WrapMode::Mirror;
                        EXPECT_FALSE(periodic && periods > 4 * kAreaMaxPerimeter)
                            << s << " aniso " << aniso << " wraps " << int(ws) << int(wt);
                    }
                }
        }
}

TEST(Area, SymmetricRegionOnALinearRampGivesTheCentre) {
    std::vector<float> px(64 * 64);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) px[j * 64 + i] = float(i + 0.5);  // value = s at centres
    FilteredTexture t(Image(64, 64, 1, px, WrapMode::Clamp, WrapMode::Clamp));
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> size(-8, -2.5), angle(0, 6.3);
    for (int k = 0; k < 200; ++k) {
        const double s = std::exp2(size(rng)), th = angle(rng);
        const Footprint fp = Footprint::axes({s * std::cos(th), s * std::sin(th)},
                                             {-0.5 * s * std::sin(th), 0.5 * s * std::cos(th)});
        // The box-reconstructed ramp is a staircase: its mean over the region is the centre up
        // to the part of one step the boundary cuts, a small fraction of the region's width.
        const double tol = std::max(1e-4, 0.02 * s * 64);
        EXPECT_NEAR(t.lookup(0.5, 0.5, fp, {FilterKind::Area})[0], 32.0, tol) << s;
    }
    // A sub-texel region is the bilinear reconstruction, which is the ramp itself.
    EXPECT_NEAR(
        t.lookup(0.3 + 0.1 / 64, 0.5, Footprint::axes({1e-5, 0}, {0, 1e-5}), {FilterKind::Area})[0],
        0.3 * 64 + 0.1, 1e-4);
}

TEST(Area, TinyAxisAlignedRegionIsTheBilinearValue) {
    for (WrapMode w : {WrapMode::Repeat, WrapMode::Clamp, WrapMode::Black, WrapMode::Mirror}) {
        FilteredTexture t(Image(9, 6, 3, noise(9, 6, 3, 8), w, w));
        std::mt19937 rng(4);
        std::uniform_real_distribution<double> pos(-0.2, 1.2);
        for (int k = 0; k < 100; ++k) {
            const double u = pos(rng), v = pos(rng);
            const Texel a = t.lookup(u, v, Footprint::axes({0, 0}, {0, 0}), {FilterKind::Area});
            const Texel b = t.lookup(u, v, Footprint::none(), {FilterKind::Bilinear});
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 2e-5) << to_string(w);
        }
    }
}

TEST(Area, MagnificationIsTheBilinearMeanAndContinuous) {
    // Below kAreaBlendLo the filter is the mean of the bilinear reconstruction: exact within one
    // patch, and the 3x3 and 4x4 Gauss rules are exact for any bilinear function. On a texture that
    // is bilinear everywhere (a product of ramps, clamped) it is the value at the centre plus the
    // mean of the cross term, for footprints within one patch and across several.
    std::vector<float> px(16 * 16);
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) px[j * 16 + i] = float((i + 0.5) * (j + 0.5));
    FilteredTexture ramp(Image(16, 16, 1, px, WrapMode::Clamp, WrapMode::Clamp));
    const double cu = 7.3 / 16, cv = 8.6 / 16;
    for (double s : {0.2, 0.6, 0.9, 1.7, 2.4, 2.6, 3.2, 3.8}) {
        const Footprint fp = Footprint::axes({s / 16, 0.1 * s / 16}, {-0.2 * s / 16, s / 16});
        // The mean of x y over a centrally symmetric region is cx cy + the mean of dx dy.
        const double dxdy = (s * -0.2 * s + 0.1 * s * s) / 12;
        EXPECT_NEAR(ramp.lookup(cu, cv, fp, {FilterKind::Area})[0], 7.3 * 8.6 + dxdy, 1e-4) << s;
    }
    // Continuous through the blend band and at both of its ends, on texel-sized detail.
    FilteredTexture t(Image(64, 64, 1, noise(64, 64, 1, 12)));
    double prev = 0;
    for (int k = 0; k <= 550; ++k) {
        // texels (the longer side is 1.044 times `side`): through [kAreaRule4Lo, kAreaRule4Hi],
        // [kAreaRule5Lo, kAreaRule5Hi] and [kAreaBlendLo, kAreaBlendHi]
        const double side = 0.5 + 0.01 * k;
        const Footprint fp = Footprint::axes({side / 64, 0.3 * side / 64}, {-0.2 / 64, 0.7 / 64});
        const double x = t.lookup(0.41, 0.57, fp, {FilterKind::Area})[0];
        if (k > 0) {
            EXPECT_NEAR(x, prev, 0.01) << side;
        }
        prev = x;
    }
}

TEST(Area, SmallRegionsAreCloseToTheBilinearMean) {
    // Footprints of 0.5 to 2.5, 2.5 to 4.5 and 4.5 to 5.5 texels on texel-sized detail (white
    // noise in [0,1], the worst case) against the bilinear reconstruction's mean over the
    // parallelogram by a 64x64-point midpoint rule. The 3x3 Gauss rule gives an RMS error of
    // 0.0044 on the first set, where the 2x2 rule blended into the region integral from one texel
    // on gave 0.012; the 4x4 and 5x5 rules give 0.0048 on the second, where the 4x4 rule and its
    // blend into the region integral from 4 texels gave 0.0063 and the region integral alone
    // 0.0089; the 5x5 rule and its blend into the region integral give 0.0076 on the third, where
    // the region integral gave 0.0106 (algorithms.md §5.2).
    const int n = 32;
    const Image img(n, n, 1, noise(n, n, 1, 21));
    FilteredTexture t(img);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0, 1);
    for (const auto& [lo, hi, bound] :
         {std::tuple{0.5, 2.5, 0.007}, std::tuple{2.5, 4.5, 0.0055}, std::tuple{4.5, 5.5, 0.009}}) {
        double se = 0;
        const int count = 200;
        for (int k = 0; k < count; ++k) {
            const double major = lo + (hi - lo) * unit(rng),
                         minor = major * (0.25 + 0.75 * unit(rng));
            const double th = 6.283 * unit(rng), th2 = th + 0.4 + 1.2 * unit(rng);
            const Vec2d a{major * std::cos(th) / n, major * std::sin(th) / n};
            const Vec2d b{minor * std::cos(th2) / n, minor * std::sin(th2) / n};
            const double u = unit(rng), v = unit(rng);
            double exact = 0;
            const int m = 64;
            for (int i = 0; i < m; ++i)
                for (int j = 0; j < m; ++j) {
                    const double fa = (i + 0.5) / m - 0.5, fb = (j + 0.5) / m - 0.5;
                    exact += bilinear(img, u + fa * a.u + fb * b.u, v + fa * a.v + fb * b.v)[0];
                }
            exact /= m * m;
            const double got = t.lookup(u, v, Footprint::axes(a, b), {FilterKind::Area})[0];
            se += (got - exact) * (got - exact);
        }
        std::printf("%.1f-%.1f texels: rms %.5f\n", lo, hi, std::sqrt(se / count));
        EXPECT_LT(std::sqrt(se / count), bound) << lo << "-" << hi;
    }
}

TEST(Area, GaussRuleReadsTheRightTexelsAtTheBlocksEdges) {
    // A rule's outermost points lie exactly on the extent of the block of texels it reads.
    // Footprints are placed so that extent falls on a texel centre, give or take a few units in
    // the last place: a point rounded onto the block's far edge must still take that texel. On
    // alternating columns and rows (every neighbour differs by 1) a wrong tap is off by a
    // point's weight (0.077 or more for the 3x3 rule, 0.014 for the 5x5 one), far beyond the
    // tolerance; the rule itself is compared, point by point in double. The 3x3 rule (sides of
    // 1.2 to 2.2 texels) and the 5x5 one (3.8 to 4.8).
    const int n = 16;
    std::vector<float> px(std::size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) px[std::size_t(j) * n + i] = float((i + j) % 2);
    const Image img(n, n, 1, px);
    FilteredTexture t(img);
    struct Rule {
        std::vector<double> node, weight;
        double side;  // the shortest side tried
    };
    const double x3 = 0.38729833462074170, x5a = 0.45308992296933200, x5b = 0.26923465505284155;
    const Rule rules[] = {{{-x3, 0, x3}, {5.0 / 18, 8.0 / 18, 5.0 / 18}, 1.2},
                          {{-x5a, -x5b, 0, x5b, x5a},
                           {0.11846344252809454, 0.23931433524968326, 0.28444444444444444,
                            0.23931433524968326, 0.11846344252809454},
                           3.8}};
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> cell(2, n - 5), ulps(-4, 4);
    std::uniform_real_distribution<double> unit(0, 1);
    double worst = 0;
    for (const Rule& r : rules) {
        const double outer = r.node.back();
        for (int k = 0; k < 2000; ++k) {
            // Texel-space centre s (lattice: texel centres at integers), sides of `side` to
            // side + 1 texels along s and side to side + 0.5 along t, so that
            // s + outer (|a_s| + |b_s|) is the integer `edge`.
            const double la = r.side + unit(rng), lb = r.side + 0.5 * unit(rng);
            const double edge = cell(rng) + 2, s = edge - outer * la;
            double t0 = cell(rng) + unit(rng);
            if (k % 2) t0 = cell(rng) + 2 - outer * lb;  // the far row edge too
            double u = (s + 0.5) / n, v = (t0 + 0.5) / n;
            for (int i = ulps(rng); i != 0; i += i > 0 ? -1 : 1)
                u = std::nextafter(u, i > 0 ? 1.0 : 0.0);
            const Vec2d a{la / n, 0}, b{0, lb / n};
            double want = 0;
            for (std::size_t ib = 0; ib < r.node.size(); ++ib)
                for (std::size_t ia = 0; ia < r.node.size(); ++ia)
                    want += r.weight[ia] * r.weight[ib] *
                            bilinear(img, u + r.node[ia] * a.u, v + r.node[ib] * b.v)[0];
            const double got = t.lookup(u, v, Footprint::axes(a, b), {FilterKind::Area})[0];
            worst = std::max(worst, std::abs(got - want));
            ASSERT_NEAR(got, want, 1e-4) << r.node.size() << "x" << r.node.size()
                                         << " rule, footprint " << k << " at " << u << "," << v;
        }
    }
    RecordProperty("max_error", std::to_string(worst));
}

TEST(Area, StrataTileTheirPixel) {
    // At n x n samples a pixel's strata are the parallelograms of its Jacobian columns / n, at
    // the strata's centres: their exact integrals add up to the pixel's, and the filter's means
    // (each on its own level, with the reconstruction term) average to the pixel's mean.
    const int size = 256;
    FilteredTexture t(Image(size, size, 1, noise(size, size, 1, 6)));
    const RowPrefixTable& table = t.row_prefix(0);
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> pos(0, 1), side(8, 60), angle(0, 6.3);
    for (int n : {2, 4}) {
        for (int k = 0; k < 20; ++k) {
            const double u = pos(rng), v = pos(rng), la = side(rng), lb = side(rng) * 0.5;
            const double th = angle(rng), tb = th + 1.2;
            const Vec2d a{la * std::cos(th) / size, la * std::sin(th) / size},
                b{lb * std::cos(tb) / size, lb * std::sin(tb) / size};
            auto corners = [&](double cu, double cv, Vec2d x, Vec2d y, Vec2d* p) {
                const double cs = cu * size, ct = cv * size;
                const Vec2d X{x.u * size, x.v * size}, Y{y.u * size, y.v * size};
                p[0] = {cs - 0.5 * (X.u + Y.u), ct - 0.5 * (X.v + Y.v)};
                p[1] = {cs + 0.5 * (X.u - Y.u), ct + 0.5 * (X.v - Y.v)};
                p[2] = {cs + 0.5 * (X.u + Y.u), ct + 0.5 * (X.v + Y.v)};
                p[3] = {cs - 0.5 * (X.u - Y.u), ct - 0.5 * (X.v - Y.v)};
            };
            Vec2d pix[4];
            corners(u, v, a, b, pix);
            const double whole = table.integral(pix, 4)[0];
            const double pixel_mean = t.lookup(u, v, Footprint::axes(a, b), {FilterKind::Area})[0];
            double parts = 0, strata_mean = 0;
            const Vec2d sa{a.u / n, a.v / n}, sb{b.u / n, b.v / n};
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const double fi = (i + 0.5) / n - 0.5, fj = (j + 0.5) / n - 0.5;
                    const double cu = u + fi * a.u + fj * b.u, cv = v + fi * a.v + fj * b.v;
                    Vec2d p[4];
                    corners(cu, cv, sa, sb, p);
                    parts += table.integral(p, 4)[0];
                    strata_mean += t.lookup(cu, cv, Footprint::axes(sa, sb), {FilterKind::Area})[0];
                }
            EXPECT_NEAR(parts, whole, 1e-4 * std::abs(whole));
            // Each mean is within the level rule's error of its level-0 integral (see above).
            EXPECT_NEAR(strata_mean / (n * n), pixel_mean, 0.03) << n << " x " << n;
        }
    }
}

TEST(Area, CollinearAndNonFiniteFootprints) {
    FilteredTexture t(Image(32, 32, 1, noise(32, 32, 1, 1)));
    // Collinear axes: a strip one texel wide along the major axis, not a sliver of no area.
    const AreaRegion g = area_region(t, 0.5, 0.5, {0.25, 0.125}, {-0.5, -0.25});
    EXPECT_NEAR(g.minor, 1.0, 1e-9);
    EXPECT_NEAR(g.major, std::sqrt(0.5 * 0.5 * 32 * 32 + 0.25 * 0.25 * 32 * 32 + 1), 1e-9);
    const Texel x =
        t.lookup(0.5, 0.5, Footprint::axes({0.25, 0.125}, {-0.5, -0.25}), {FilterKind::Area});
    EXPECT_TRUE(std::isfinite(x[0]));
    const LookupResult m =
        t.lookup_with_info(0.5, 0.5, Footprint::axes({NAN, 0}, {0, 0.1}), {FilterKind::Area});
    EXPECT_TRUE(m.info.fallback);
    EXPECT_EQ(m.value[0], t.image().mean()[0]);
    EXPECT_EQ(area_parallelogram(t, 0.5, INFINITY, {0.1, 0}, {0, 0.1}).value[0],
              t.image().mean()[0]);
}

TEST(Area, LargeTablesBuildOnlyTheRowsTheirRegionsRead) {
    // Lookups in one corner of a 512x512 texture (regions 8 to 40 texels long, 0.3 as wide:
    // walked, not the Gauss rule's) build a few bands of the levels they walk, not the levels'
    // tables, and give the values of a texture whose tables were built whole.
    const std::vector<float> px = noise(512, 512, 1, 9);
    FilteredTexture lazy(Image(512, 512, 1, px)), whole(Image(512, 512, 1, px));
    for (int l = 0; l < whole.pyramid().levels(); ++l) whole.row_prefix(l).build_all();
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> pos(0.1, 0.15), side(8.0 / 512, 40.0 / 512),
        angle(0, 6.3);
    for (int k = 0; k < 200; ++k) {
        const double u = pos(rng), v = pos(rng), la = side(rng), ta = angle(rng);
        const Footprint fp = Footprint::axes({la * std::cos(ta), la * std::sin(ta)},
                                             {-0.3 * la * std::sin(ta), 0.3 * la * std::cos(ta)});
        const LookupResult a = lazy.lookup_with_info(u, v, fp, {FilterKind::Area}),
                           b = whole.lookup_with_info(u, v, fp, {FilterKind::Area});
        ASSERT_EQ(a.value[0], b.value[0]) << "lookup " << k;
    }
    EXPECT_GT(lazy.row_prefix_bytes(), 0u);
    EXPECT_LT(lazy.row_prefix_bytes() * 4, whole.row_prefix_bytes());
}

TEST(Area, TablesAreBuiltLazilyAndCounted) {
    FilteredTexture t(Image(64, 32, 3, noise(64, 32, 3, 2)));
    EXPECT_EQ(t.row_prefix_bytes(), 0u);
    const std::size_t before = t.memory_bytes();
    t.lookup(0.5, 0.5, Footprint::axes({0.001, 0}, {0, 0.001}), {FilterKind::Area});
    EXPECT_EQ(t.row_prefix_bytes(), 0u);  // magnified: the Gauss rule reads the texels
    t.lookup(0.5, 0.5, Footprint::axes({0.1, 0}, {0, 0.1}), {FilterKind::Area});
    // Level 0 only: 65 knots a row and 32 rows, and as the texture repeats, the margin's knots
    // and rows; a row padded to an odd number of 64-byte lines (101 knots of 12 bytes: 19).
    static_assert(RowPrefixTable::kMarginKnots == 36);
    EXPECT_EQ(t.row_prefix_bytes(), std::size_t(19 * 64) * (32 + RowPrefixTable::kMarginRows));
    EXPECT_GE(t.memory_bytes(), before + t.row_prefix_bytes());
}

// A checkerboard's odd-cell share of a parallelogram (closed-form checkerboards under the area
// filter) against the cell-clipping oracle on a 2x2 repeat-wrapped image of the same pattern:
// small regions within one or two cells, large and thin ones (diagonal strips along cells of
// one colour), both orientations, centres far from the origin; degenerate regions give their
// centre's cell.
TEST(Area, CheckerShareMatchesTheCellOracle) {
    const std::vector<float> px = {0, 1, 1, 0};  // texel (i, j) = (i + j) & 1
    const Image img(2, 2, 1, px, WrapMode::Repeat, WrapMode::Repeat);
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> unit(0, 1);
    int checked = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const double size = std::pow(10.0, -3 + 4.5 * unit(rng));  // 0.001 to 30 cells
        const double angle = 6.283185307179586 * unit(rng), thin = trial % 3 == 0 ? 0.01 : 1;
        const double la = size * (0.2 + unit(rng)), lb = thin * size * (0.2 + unit(rng));
        const double skew = 1.5 * (unit(rng) - 0.5);
        const Vec2d a{la * std::cos(angle), la * std::sin(angle)},
            b{lb * std::cos(angle + 1.5707963 + skew), lb * std::sin(angle + 1.5707963 + skew)};
        const double far = trial % 4 == 0 ? 1e4 : 1;
        const Vec2d c{far * 20 * (unit(rng) - 0.5), far * 20 * (unit(rng) - 0.5)};
        const double share = checker_odd_share(c, a, b);
        // The oracle on the same region moved by whole periods near the origin (its cells are
        // clipped in texel space, exact within rounding there).
        const Vec2d c0{c.u - 2 * std::floor(c.u / 2), c.v - 2 * std::floor(c.v / 2)};
        Vec2d p[4];
        parallelogram(c0.u, c0.v, a, b, p);
        const double area = std::abs(cross(a, b));
        const double want = polygon_integral_cells(img, to_polygon(p, 4))[0] / area;
        ASSERT_NEAR(share, want, 1e-7 + 1e-9 * size * size / area)
            << "trial " << trial << " size " << size << " c " << c.u << "," << c.v;
        ++checked;
    }
    EXPECT_EQ(checked, 3000);
    // A thin strip along the diagonal through the cells' corners stays on one colour but for
    // the corners' triangles (their share goes with the width), where a box would give 1/2.
    EXPECT_LT(checker_odd_share({10.5, 10.5}, {20, 20}, {0.001, -0.001}), 1e-3);
    EXPECT_GT(checker_odd_share({10.5, 11.5}, {20, 20}, {0.001, -0.001}), 1 - 1e-3);
    // A whole 2x2 block, and no area at all.
    EXPECT_NEAR(checker_odd_share({3, 5}, {2, 0}, {0, 2}), 0.5, 1e-12);
    EXPECT_EQ(checker_odd_share({0.5, 1.5}, {0, 0}, {0, 0}), 1);
    EXPECT_EQ(checker_odd_share({0.5, 0.5}, {1, 1}, {2, 2}), 0);  // collinear sides
    EXPECT_EQ(checker_odd_share({NAN, 0}, {1, 0}, {0, 1}), -1);
    EXPECT_EQ(checker_odd_share({0, 0}, {5000, 0}, {0, 5000}), -1);  // beyond kCheckerMaxLines
}
