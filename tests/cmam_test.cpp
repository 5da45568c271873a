// The CMAM against algorithms.md §12 (T-CMAM-1..3) and the paper's rules: matching on tag and
// level, the cache shift, the three cases per filter, the miss policies and the readings.
#include <cmam/texture/cmam.h>
#include <cmam/texture/filters.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace cmam::texture;

namespace {
constexpr double kPi = 3.14159265358979323846;
Image tmip1() {
    return Image(4, 4, 1, {3, 0, 1, 2, 5, 7, 4, 1, 0, 2, 6, 3, 1, 1, 0, 4});
}
CmamCache::Entry at(double s, double t) {
    return {RayTag{}, s, t, true};
}
double area(const CmamRegion& r) {
    return kPi * std::abs(cross(r.a, r.b));
}
// Singular values of [a b] (the true semi-axes of the conjugate-diameter ellipse).
std::pair<double, double> sigma(Vec2d a, Vec2d b) {
    double A = a.v * a.v + b.v * b.v, C = a.u * a.u + b.u * b.u, B = -2 * (a.u * a.v + b.u * b.v);
    double root = std::sqrt((A - C) * (A - C) + B * B);
    return {std::sqrt((A + C + root) / 2), std::sqrt((A + C - root) / 2)};
}
}  // namespace

TEST(CmamRegion, TCmam1CaseTwoGeometry) {
    CmamCache::Entry cached[2] = {at(12, 10.5), at(10.5, 11.5)};
    CmamOptions o;
    CmamRegion r = cmam_region(10, 10, cached, 2, o);
    EXPECT_NEAR(r.width, 2.5, 1e-12);
    EXPECT_NEAR(std::log2(r.width), 1.321928, 1e-6);
    EXPECT_DOUBLE_EQ(r.a.u, 2);
    EXPECT_DOUBLE_EQ(r.a.v, 0.5);
    EXPECT_DOUBLE_EQ(r.b.u, 0.5);
    EXPECT_DOUBLE_EQ(r.b.v, 1.5);
    EXPECT_FALSE(r.orthogonal_fallback);
    auto [s1, s2] = sigma(r.a, r.b);
    EXPECT_NEAR(s1, 2.309017, 1e-6);
    EXPECT_NEAR(s2, 1.190983, 1e-6);
    EXPECT_NEAR(area(r), 8.639380, 1e-6);
    EXPECT_NEAR(std::log2(length(r.b)), 0.661, 1e-3);
    EXPECT_NEAR(std::log2(s2), 0.252, 1e-3);
    EXPECT_DOUBLE_EQ(r.rect.lo.u, 10);
    EXPECT_DOUBLE_EQ(r.rect.hi.u, 12);
    EXPECT_DOUBLE_EQ(r.rect.lo.v, 10);
    EXPECT_DOUBLE_EQ(r.rect.hi.v, 11.5);
    o.ellipse = CmamEllipse::Orthogonal;
    EXPECT_NEAR(area(cmam_region(10, 10, cached, 2, o)), 10.240339, 1e-6);
    o.ellipse = CmamEllipse::Orthogonalised;
    CmamRegion r3 = cmam_region(10, 10, cached, 2, o);
    EXPECT_NEAR(area(r3), 8.639380, 1e-6);
    EXPECT_NEAR(dot(r3.a, r3.b), 0, 1e-12);
}

TEST(CmamRegion, TCmam1CollinearFallsBackAndKeepsAMinimumExtent) {
    CmamCache::Entry cached[2] = {at(11, 10), at(12, 10)};
    CmamRegion r = cmam_region(10, 10, cached, 2, CmamOptions{});
    EXPECT_NEAR(std::log2(r.width), 1, 1e-12);
    EXPECT_TRUE(r.orthogonal_fallback);
    EXPECT_NEAR(length(r.a), 2, 1e-12);
    EXPECT_NEAR(length(r.b), 1, 1e-12);
    EXPECT_NEAR(dot(r.a, r.b), 0, 1e-12);
    EXPECT_NEAR(r.rect.hi.v - r.rect.lo.v, 1, 1e-12);  // zero height -> 1 texel
    EXPECT_NEAR(r.rect.hi.u - r.rect.lo.u, 2, 1e-12);

    CmamCache::Entry row[2] = {at(9, 10.05), at(8, 10.2)};  // a perspective row
    CmamRegion p = cmam_region(10, 10, row, 2, CmamOptions{});
    EXPECT_TRUE(p.orthogonal_fallback);
    EXPECT_NEAR(sigma(p.a, p.b).second, std::hypot(1.0, 0.05), 1e-9);  // R2: minor = |b|
}

TEST(Cmam, TCmam2CaseOneOnTheMipTexture) {
    FilteredTexture tex(tmip1());
    EXPECT_NEAR(bilinear(tex.image(), 0.8, 0.6)[0], 3.70, 1e-5);
    auto run = [&](CmamOptions o) {
        CmamCache cache;
        RayTag tag{7, 0, 0};
        cmam_lookup(tex, cache, tag, 0.3, 0.6, o);  // cached sample
        tag.seq = 1;
        const CmamResult x = cmam_lookup_with_info(tex, cache, tag, 0.8, 0.6, o);
        EXPECT_EQ(x.region.matches, 1);
        return std::pair{x.value[0], x.region};
    };
    CmamOptions o;
    o.filter = FilterKind::Trilinear;
    auto [tri, rt] = run(o);
    EXPECT_NEAR(rt.width, 2, 1e-12);
    EXPECT_NEAR(tri, 2.77, 1e-5);
    o.filter = FilterKind::Sat;
    auto [sat, rs] = run(o);
    EXPECT_NEAR(rs.rect.lo.u, 1.2, 1e-12);
    EXPECT_NEAR(rs.rect.hi.u, 3.2, 1e-12);
    EXPECT_NEAR(rs.rect.lo.v, 1.9, 1e-12);
    EXPECT_NEAR(rs.rect.hi.v, 2.9, 1e-12);
    EXPECT_NEAR(sat, 4.18, 1e-5);
    o.sat_box = CmamSatBox::Square;
    EXPECT_NEAR(run(o).first, 3.15, 1e-5);
    o.filter = FilterKind::Ewa;
    EXPECT_NEAR(run(o).first, 2.465593, 1e-5);
}

TEST(Cmam, MissPolicies) {
    FilteredTexture tex(tmip1());
    CmamCache cache;
    CmamOptions o;
    EXPECT_FLOAT_EQ(cmam_lookup(tex, cache, {1, 0, 0}, 0.8, 0.6, o)[0], 2.5f);  // average: the mean
    cache.reset();
    o.miss = CmamMiss::Point;
    EXPECT_NEAR(cmam_lookup(tex, cache, {1, 0, 0}, 0.8, 0.6, o)[0], 3.70, 1e-5);
    cache.reset();
    o.filter = FilterKind::Sat;
    o.sat_miss = CmamSatMiss::PaperLiteral;  // average over [0, s] x [0, t] = [0,3.2] x [0,2.4]
    float lit = cmam_lookup(tex, cache, {1, 0, 0}, 0.8, 0.6, o)[0];
    EXPECT_NEAR(lit, tex.sat().average(0, 0, 3.2, 2.4)[0], 1e-6);
}

TEST(Cmam, MatchingShiftsTheCacheAndComparesTagAndLevel) {
    FilteredTexture tex(tmip1());
    CmamOptions o;
    CmamCache c;
    CmamRegion r;
    r = cmam_lookup_with_info(tex, c, {3, 0, 0}, 0.1, 0.1, o).region;
    EXPECT_EQ(r.matches, 0);
    EXPECT_TRUE(c.last.valid);
    EXPECT_FALSE(c.second_last.valid);
    r = cmam_lookup_with_info(tex, c, {3, 0, 1}, 0.2, 0.1, o).region;
    EXPECT_EQ(r.matches, 1);
    EXPECT_DOUBLE_EQ(c.second_last.s, 0.4);
    EXPECT_DOUBLE_EQ(c.last.s, 0.8);
    r = cmam_lookup_with_info(tex, c, {3, 0, 2}, 0.3, 0.1, o).region;
    EXPECT_EQ(r.matches, 2);
    // A reflected ray: another level.
    r = cmam_lookup_with_info(tex, c, {3, 1, 3}, 0.4, 0.1, o).region;
    EXPECT_EQ(r.matches, 0);
    r = cmam_lookup_with_info(tex, c, {4, 1, 4}, 0.5, 0.1, o).region;  // another ID (next scanline)
    EXPECT_EQ(r.matches, 0);
    r = cmam_lookup_with_info(tex, c, {4, 1, 5}, 0.6, 0.1, o).region;
    EXPECT_EQ(r.matches, 1);
}

TEST(Cmam, TCmam3AdjacencyRejectsSamplesAcrossAnOccluder) {
    // Object A at x = 10, object B at x = 11..20, object A again at x = 21 (one scanline).
    FilteredTexture tex(tmip1());
    CmamOptions o;
    CmamCache a;
    CmamRegion r;
    cmam_lookup(tex, a, {5, 0, 10}, 0.10, 0.5, o);
    r = cmam_lookup_with_info(tex, a, {5, 0, 21}, 0.21, 0.5, o).region;
    EXPECT_EQ(r.matches, 0) << "a footprint spanning the occluder";
    o.adjacent_only = false;  // the paper's literal matching would span it
    CmamCache b;
    cmam_lookup(tex, b, {5, 0, 10}, 0.10, 0.5, o);
    r = cmam_lookup_with_info(tex, b, {5, 0, 21}, 0.21, 0.5, o).region;
    EXPECT_EQ(r.matches, 1);
}

TEST(Cmam, ModuleObjectIsTheWholeApi) {
    FilteredTexture tex(Image(8, 8, 3, std::vector<float>(8 * 8 * 3, 0.25f)));
    for (FilterKind k : {FilterKind::Trilinear, FilterKind::Sat, FilterKind::Ewa}) {
        Cmam m(tex, CmamOptions{k});
        for (uint32_t x = 0; x < 20; ++x)
            EXPECT_NEAR(m.lookup({0, 0, x}, 0.05 * x, 0.3 + 0.01 * x)[1], 0.25f, 1e-6);
    }
}

TEST(Cmam, NonFiniteCoordinatesGiveTheMean) {
    FilteredTexture tex(tmip1());
    CmamCache c;
    const CmamResult x = cmam_lookup_with_info(tex, c, {}, std::nan(""), 0.5, CmamOptions{});
    EXPECT_FLOAT_EQ(x.value[0], 2.5f);
    EXPECT_TRUE(x.info.fallback);
    EXPECT_FALSE(c.last.valid);
}

TEST(Cmam, ParseAndPrint) {
    for (auto m : {CmamMiss::Average, CmamMiss::Point}) EXPECT_EQ(parse_cmam_miss(to_string(m)), m);
    for (auto e : {CmamEllipse::Conjugate, CmamEllipse::Orthogonal, CmamEllipse::Orthogonalised})
        EXPECT_EQ(parse_cmam_ellipse(to_string(e)), e);
    for (auto m : {CmamSatMiss::Average, CmamSatMiss::PaperLiteral})
        EXPECT_EQ(parse_cmam_sat_miss(to_string(m)), m);
    EXPECT_FALSE(parse_cmam_miss("blur"));
}

TEST(CmamHull, OnlyTheNewPartOfEachTriangleIsIntegrated) {
    // The 2x2 texture of §12 (repeat); texel space = uv * 2.
    FilteredTexture tex(Image(2, 2, 1, {1, 2, 3, 4}));
    CmamOptions o;
    o.hull = true;
    o.adjacent_only = false;
    CmamCache c;
    RayTag tag{9, 0, 0};
    // Samples (texels): (0,0), (1,0), then (0,1): triangle (0,0),(1,0),(0,1), area 0.5, all new.
    cmam_lookup(tex, c, tag, 0.0, 0.0, o);
    cmam_lookup(tex, c, tag, 0.5, 0.0, o);
    CmamResult x = cmam_lookup_with_info(tex, c, tag, 0.0, 0.5, o);
    EXPECT_NEAR(x.region.hull_new_area, 0.5, 1e-12);
    EXPECT_NEAR(x.value[0], 1.0, 1e-6);  // all inside texel (0,0)
    // Next sample (1,1): triangle (1,1),(0,1),(1,0): new area 0.5, also in texel (0,0).
    x = cmam_lookup_with_info(tex, c, tag, 0.5, 0.5, o);
    EXPECT_NEAR(x.region.hull_new_area, 0.5, 1e-12);
    EXPECT_NEAR(x.value[0], 1.0, 1e-6);
    // A triangle inside the hull [0,1]^2 adds nothing: the running mean comes back.
    cmam_lookup(tex, c, tag, 0.1, 0.1, o);
    x = cmam_lookup_with_info(tex, c, tag, 0.2, 0.1, o);
    EXPECT_NEAR(x.region.hull_new_area, 0.0, 1e-12);
    EXPECT_NEAR(x.value[0], 1.0, 1e-6);
    // A triangle reaching into texel (1,0): only the part outside the hull counts.
    x = cmam_lookup_with_info(tex, c, tag, 1.0, 0.25, o);  // (2, 0.5) with (0.4,0.2),(0.2,0.2)
    EXPECT_GT(x.region.hull_new_area, 0);
    EXPECT_GT(x.value[0], 1.0f);
    // A new ID (the next pixel) starts a new hull.
    tag.id = 10;
    cmam_lookup(tex, c, tag, 0.0, 0.0, o);
    cmam_lookup(tex, c, tag, 0.5, 0.0, o);
    x = cmam_lookup_with_info(tex, c, tag, 0.0, 0.5, o);
    EXPECT_NEAR(x.region.hull_new_area, 0.5, 1e-12);
}

TEST(Cmam2d, RegionUsesTheLeftAndUpperNeighboursAsJacobianColumns) {
    CmamCache::Entry left = at(9, 10), above = at(10.5, 8);
    CmamRegion r = cmam_region_2d(10, 10, &left, above, CmamOptions{});
    EXPECT_TRUE(r.used_above);
    EXPECT_DOUBLE_EQ(r.a.u, -1);
    EXPECT_DOUBLE_EQ(r.a.v, 0);
    EXPECT_DOUBLE_EQ(r.b.u, 0.5);
    EXPECT_DOUBLE_EQ(r.b.v, -2);
    EXPECT_NEAR(r.width, std::hypot(0.5, 2.0), 1e-12);
    // The box around the parallelogram p0 +- (a +- b)/2: half extents 0.75 and 1.
    EXPECT_NEAR(r.rect.lo.u, 9.25, 1e-12);
    EXPECT_NEAR(r.rect.hi.u, 10.75, 1e-12);
    EXPECT_NEAR(r.rect.lo.v, 9, 1e-12);
    EXPECT_NEAR(r.rect.hi.v, 11, 1e-12);
    CmamRegion c = cmam_region_2d(10, 10, nullptr, above, CmamOptions{});  // no left: a circle
    EXPECT_NEAR(length(c.a), length(c.b), 1e-12);
    EXPECT_NEAR(dot(c.a, c.b), 0, 1e-12);
}

TEST(Cmam2d, TheRowBufferFindsTheSampleAboveOfTheSameLevel) {
    FilteredTexture tex(tmip1());
    CmamOptions o;
    o.two_d = true;
    CmamCache c;
    CmamRegion r;
    for (uint32_t x = 0; x < 4; ++x) cmam_lookup(tex, c, {0, 0, x}, 0.1 * x, 0.5, o);  // row 0
    r = cmam_lookup_with_info(tex, c, {1, 0, 0}, 0.0, 0.55, o).region;  // row 1, x = 0
    EXPECT_TRUE(r.used_above);
    EXPECT_EQ(r.matches, 0);  // no left neighbour, but the sample above gives a region
    EXPECT_NEAR(length(r.b), 0.05 * 4, 1e-9);
    r = cmam_lookup_with_info(tex, c, {1, 0, 1}, 0.1, 0.55, o).region;
    EXPECT_TRUE(r.used_above);
    EXPECT_EQ(r.matches, 1);
    r = cmam_lookup_with_info(tex, c, {1, 1, 2}, 0.2, 0.55, o).region;  // a reflected ray: level 1
    EXPECT_FALSE(r.used_above);
    r = cmam_lookup_with_info(tex, c, {3, 0, 2}, 0.2, 0.6, o).region;  // ID 3 after 1: no row above
    EXPECT_FALSE(r.used_above);
}

TEST(Cmam2d, RowBuffersHoldTheRowsOwnSamplesOnly) {
    // A strip of the image far from its left edge: sequence numbers from 1000 on. The rows keep
    // those samples only (not every number below them), and still find the samples above; a
    // sample left of its row's first (not a left-to-right scan) extends the row to the left.
    FilteredTexture tex(tmip1());
    CmamOptions o;
    o.two_d = true;
    CmamCache c;
    for (uint32_t row = 0; row < 3; ++row)
        for (uint32_t x = 1000; x < 1010; ++x) {
            const CmamRegion r =
                cmam_lookup_with_info(tex, c, {row, 0, x}, 0.01 * x, 0.5 + 0.05 * row, o).region;
            EXPECT_EQ(r.used_above, row > 0) << row << " " << x;
            EXPECT_LE(c.row_current.size(), 10u);
            EXPECT_LE(c.row_previous.size(), 10u);
        }
    // Row 3: 1003 first, then 998 to its left (row 2 has no 998: nothing above it).
    EXPECT_TRUE(cmam_lookup_with_info(tex, c, {3, 0, 1003}, 10.03, 0.65, o).region.used_above);
    EXPECT_FALSE(cmam_lookup_with_info(tex, c, {3, 0, 998}, 9.98, 0.65, o).region.used_above);
    EXPECT_EQ(c.row_current.size(), 6u);  // 998 to 1003
    // Row 4 finds both above: 998 (the extension) and 1003.
    EXPECT_TRUE(cmam_lookup_with_info(tex, c, {4, 0, 998}, 9.98, 0.7, o).region.used_above);
    EXPECT_TRUE(cmam_lookup_with_info(tex, c, {4, 0, 1003}, 10.03, 0.7, o).region.used_above);
    EXPECT_FALSE(cmam_lookup_with_info(tex, c, {4, 0, 1001}, 10.01, 0.7, o).region.used_above);
}

// The CMAM as a footprint producer for textures that are not images: the same cache steps as a
// lookup, positions in (u,v), the region as axes.
TEST(Cmam, FootprintForTexturesThatAreNotImages) {
    CmamOptions o;
    CmamCache c;
    Vec2d off{7, 7};
    // 1-D: a miss, then the circle of radius |p1 - p0| to the most recent match.
    EXPECT_EQ(cmam_footprint(c, {0, 0, 0}, 0.10, 0.5, o, &off).kind, Footprint::Kind::None);
    EXPECT_EQ(off.u, 0);
    cmam_footprint(c, {0, 0, 1}, 0.13, 0.5, o, &off);
    const Footprint f = cmam_footprint(c, {0, 0, 2}, 0.17, 0.5, o, &off);
    ASSERT_EQ(f.kind, Footprint::Kind::Axes);
    EXPECT_NEAR(f.axis_a.u, 0.04, 1e-12);
    EXPECT_NEAR(f.axis_b.v, 0.04, 1e-12);
    EXPECT_EQ(f.axis_a.v, 0);
    // Not adjacent (sequence number 4 after 2): a miss.
    EXPECT_EQ(cmam_footprint(c, {0, 0, 4}, 0.25, 0.5, o, &off).kind, Footprint::Kind::None);
    // 2-D with positioned tags: the Jacobian and the stratum's centre, as cmam_region_2d gives
    // for the same cache entries (an affine mapping u = 0.01 x + 0.002 y, v = 0.03 y).
    o.two_d = true;
    CmamCache c2;
    auto tag = [](uint32_t row, uint32_t seq, double x, double y) {
        RayTag t{row, 0, seq};
        t.positioned = true;
        t.x = x;
        t.y = y;
        return t;
    };
    const double jit[2][3][2] = {{{0.3, 0.6}, {1.7, 0.2}, {2.4, 0.9}},
                                 {{0.8, 1.1}, {1.2, 1.7}, {2.6, 1.4}}};
    Footprint g;
    for (uint32_t row = 0; row < 2; ++row)
        for (uint32_t k = 0; k < 3; ++k) {
            const double x = jit[row][k][0], y = jit[row][k][1];
            g = cmam_footprint(c2, tag(row, k, x, y), 0.01 * x + 0.002 * y, 0.03 * y, o, &off);
        }
    ASSERT_EQ(g.kind, Footprint::Kind::Axes);
    EXPECT_NEAR(g.axis_a.u, 0.01, 1e-12);
    EXPECT_NEAR(g.axis_a.v, 0, 1e-12);
    EXPECT_NEAR(g.axis_b.u, 0.002, 1e-12);
    EXPECT_NEAR(g.axis_b.v, 0.03, 1e-12);
    // The last sample (2.6, 1.4) moved to its stratum's centre (2.5, 1.5).
    EXPECT_NEAR(off.u, 0.01 * -0.1 + 0.002 * 0.1, 1e-12);
    EXPECT_NEAR(off.v, 0.03 * 0.1, 1e-12);
}

TEST(Cmam, FarOrNonNumericSamplesGiveTheMeanAndAreNotCached) {
    // A position beyond 2^30 texels gets the mean, as in every filter, and is not cached, so
    // the next sample's region never spans to it; a maximum anisotropy below 1 (or NaN) is 1.
    FilteredTexture tex(tmip1());
    for (FilterKind f : {FilterKind::Trilinear, FilterKind::Sat, FilterKind::Ewa})
        for (double aniso : {8.0, std::nan(""), 1e-300}) {
            CmamOptions o;
            o.filter = f;
            o.max_aniso = aniso;
            o.hull = f == FilterKind::Sat;
            CmamCache c;
            const CmamResult far = cmam_lookup_with_info(tex, c, {2, 0, 0}, 1e12, 0.5, o);
            EXPECT_TRUE(far.info.fallback);
            EXPECT_FLOAT_EQ(far.value[0], tex.image().mean()[0]);
            EXPECT_FALSE(c.last.valid);
            EXPECT_EQ(cmam_lookup_with_info(tex, c, {2, 0, 1}, 0.25, 0.5, o).region.matches, 0);
            const CmamResult near = cmam_lookup_with_info(tex, c, {2, 0, 2}, 0.3, 0.5, o);
            EXPECT_EQ(near.region.matches, 1);
            EXPECT_TRUE(std::isfinite(near.value[0]));
            EXPECT_GE(near.value[0], 0.0f);
            EXPECT_LE(near.value[0], 7.0f);
        }
}

TEST(Cmam, PointsFootprintIsTheRenderersRouteForEveryFilter) {
    // `cmam lookup --points` hands the filters a Points footprint; the renderer's CMAM hands
    // them its matching cached samples. Both go through FilteredTexture::lookup and
    // cmam_region(): the same value, bit for bit, for every filter, with one and two matches.
    std::vector<float> px(37 * 23 * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float((i * 7919) % 101) / 100;
    FilteredTexture t(Image(37, 23, 3, px));
    const Vec2d pts[][3] = {{{0.4, 0.5}, {0.39, 0.5}, {0.38, 0.501}},  // a row: nearly collinear
                            {{0.4, 0.5}, {0.37, 0.49}, {0.41, 0.45}},  // a triangle with area
                            {{0.1, 0.9}, {0.05, 0.93}, {0.0, 0.96}}};  // collinear
    for (FilterKind kind :
         {FilterKind::Trilinear, FilterKind::Sat, FilterKind::Ewa, FilterKind::Area})
        for (const auto& p : pts)
            for (int n : {2, 3}) {
                Footprint fp;
                fp.kind = Footprint::Kind::Points;
                fp.point_count = n;
                for (int k = 0; k < n; ++k) fp.points[k] = p[k];
                const Texel direct = t.lookup(p[0].u, p[0].v, fp, {kind, 8});
                CmamCache cache;
                CmamOptions o;
                o.filter = kind;
                for (int k = n - 1; k >= 1; --k)  // oldest first, adjacent sequence numbers
                    cmam_lookup(t, cache, RayTag{0, 0, uint32_t(n - 1 - k)}, p[k].u, p[k].v, o);
                const Texel via_cmam =
                    cmam_lookup(t, cache, RayTag{0, 0, uint32_t(n - 1)}, p[0].u, p[0].v, o);
                for (int c = 0; c < 3; ++c)
                    EXPECT_EQ(direct[c], via_cmam[c]) << to_string(kind) << " " << n << " points";
            }
}

namespace {
// A cached sample with a positioned tag at (x, y) on the image plane (strata), at the texel
// coordinates (s, t) = map(x, y).
template <class Map>
CmamCache::Entry positioned_sample(const Map& map, double x, double y) {
    auto [s, t] = map(x, y);
    CmamCache::Entry e{RayTag{}, s, t, true};
    e.tag.positioned = true;
    e.tag.x = x;
    e.tag.y = y;
    return e;
}
}  // namespace

TEST(Cmam2d, PositionedTagsSolveTheJacobianWhateverTheJitter) {
    // An affine mapping s = 3x + y + 5, t = -x + 2y + 7 (texels per stratum), samples jittered
    // within their strata: the solved axes are the Jacobian columns and the region is centred on
    // the stratum's centre.
    auto map = [](double x, double y) { return std::pair{3 * x + y + 5, -x + 2 * y + 7}; };
    auto entry = [&](double x, double y) { return positioned_sample(map, x, y); };
    const CmamCache::Entry cur = entry(10.8, 20.15), left = entry(9.1, 20.7),
                           above = entry(10.35, 19.9);
    const CmamRegion r = cmam_region_2d(cur.s, cur.t, &left, above, CmamOptions{}, cur.tag);
    EXPECT_NEAR(r.a.u, 3, 1e-5);
    EXPECT_NEAR(r.a.v, -1, 1e-5);
    EXPECT_NEAR(r.b.u, 1, 1e-5);
    EXPECT_NEAR(r.b.v, 2, 1e-5);
    auto [cs, ct] = map(10.5, 20.5);  // the stratum's centre
    EXPECT_NEAR(cur.s + r.offset.u, cs, 1e-5);
    EXPECT_NEAR(cur.t + r.offset.v, ct, 1e-5);
    // Without positions: the plain neighbour vectors, no move.
    const CmamRegion plain = cmam_region_2d(cur.s, cur.t, &left, above, CmamOptions{});
    EXPECT_NEAR(plain.a.u, left.s - cur.s, 1e-12);
    EXPECT_EQ(plain.offset.u, 0);
    // With the row above's samples either side of the one above, the least-squares fit over
    // the four is exact for the affine mapping too.
    const CmamCache::Entry above_left = entry(9.6, 19.3), above_right = entry(11.9, 19.8);
    const CmamRegion fit = cmam_region_2d(cur.s, cur.t, &left, above, CmamOptions{}, cur.tag,
                                          &above_left, &above_right);
    EXPECT_NEAR(fit.a.u, 3, 1e-9);
    EXPECT_NEAR(fit.a.v, -1, 1e-9);
    EXPECT_NEAR(fit.b.u, 1, 1e-9);
    EXPECT_NEAR(fit.b.v, 2, 1e-9);
    EXPECT_NEAR(cur.s + fit.offset.u, cs, 1e-9);
    EXPECT_NEAR(cur.t + fit.offset.v, ct, 1e-9);
}

TEST(Cmam2d, JitteredNeighboursNearlyInLineAreFittedOverFour) {
    // A mapping that is not affine (a receding plane's t grows as 1/(c - y)); the left and above
    // neighbours jittered nearly in line with the current sample (their offsets' determinant
    // -0.257, just beyond the two-neighbour solve's 1/4): that solve amplifies the curvature
    // into the Jacobian, the fit over four neighbours does not (measured: 2.91 and 0.28 off the
    // exact Jacobian at the stratum's centre; over 18,000 random jitters the RMS is 0.64 and
    // 0.51, the rest being the curvature between the samples and the centre).
    auto map = [](double x, double y) { return std::pair{2 * x / (30 - y), 400 / (30 - y)}; };
    auto entry = [&](double x, double y) { return positioned_sample(map, x, y); };
    const CmamCache::Entry cur = entry(10.01, 20.02), left = entry(9.54, 20.98),
                           above = entry(10.64, 19.28), above_left = entry(9.36, 19.96),
                           above_right = entry(11.21, 19.90);
    // The exact Jacobian at (10.5, 20.5): ds/dx = 2/(30-y), ds/dy = 2x/(30-y)^2, dt/dx = 0,
    // dt/dy = 400/(30-y)^2.
    const double k = 30 - 20.5;
    const double jxs = 2 / k, jys = 2 * 10.5 / (k * k), jyt = 400 / (k * k);
    auto error = [&](const CmamRegion& r) {
        return std::hypot(r.a.u - jxs, r.a.v) + std::hypot(r.b.u - jys, r.b.v - jyt);
    };
    const CmamRegion two = cmam_region_2d(cur.s, cur.t, &left, above, CmamOptions{}, cur.tag);
    const CmamRegion four = cmam_region_2d(cur.s, cur.t, &left, above, CmamOptions{}, cur.tag,
                                           &above_left, &above_right);
    EXPECT_LT(error(four), 0.25 * error(two)) << error(four) << " vs " << error(two);
    // On a regular grid (no jitter) the two-neighbour backward differences are kept: the
    // columns are one stratum's steps, the negated vectors to the neighbours.
    const CmamCache::Entry g = entry(10.5, 20.5), gl = entry(9.5, 20.5), ga = entry(10.5, 19.5),
                           gal = entry(9.5, 19.5), gar = entry(11.5, 19.5);
    const CmamRegion grid = cmam_region_2d(g.s, g.t, &gl, ga, CmamOptions{}, g.tag, &gal, &gar);
    const CmamRegion grid2 = cmam_region_2d(g.s, g.t, &gl, ga, CmamOptions{}, g.tag);
    EXPECT_EQ(grid.a.u, grid2.a.u);
    EXPECT_EQ(grid.a.v, grid2.a.v);
    EXPECT_EQ(grid.b.u, grid2.b.u);
    EXPECT_EQ(grid.b.v, grid2.b.v);
    EXPECT_EQ(grid.a.u, g.s - gl.s);
}

// An angular coordinate (a spherical or cylindrical mapping's longitude) jumps from 1 to 0 at
// its seam. With it declared periodic, the samples on either side are neighbours one step
// apart: two rows of the 2-D CMAM crossing the seam at different columns give the regions and
// values of the same rows unwrapped (u continuing past 1 on a repeating texture), in u for
// periodic_u and in v for periodic_v. Without it the region spans the whole texture.
TEST(Cmam, SamplesOfAnotherPatchAreNotNeighbours) {
    // A tag's patch (a mesh's (u,v) chart) parts samples as the ID and level do: a sample
    // after a step onto another patch matches nothing (the paper's miss: the texture's mean),
    // the next one on that patch matches only it, and the 2-D CMAM takes no sample above from
    // another patch.
    FilteredTexture tex(tmip1());
    CmamOptions o;
    o.filter = FilterKind::Ewa;
    auto tag = [](uint32_t id, uint32_t seq, uint32_t patch) {
        RayTag t{id, 0, seq};
        t.patch = patch;
        return t;
    };
    CmamCache c;
    cmam_lookup(tex, c, tag(0, 0, 0), 0.30, 0.4, o);
    EXPECT_EQ(cmam_lookup_with_info(tex, c, tag(0, 1, 0), 0.31, 0.4, o).region.matches, 1);
    EXPECT_EQ(cmam_lookup_with_info(tex, c, tag(0, 2, 0), 0.32, 0.4, o).region.matches, 2);
    const CmamResult jump = cmam_lookup_with_info(tex, c, tag(0, 3, 1), 0.80, 0.4, o);
    EXPECT_EQ(jump.region.matches, 0);
    EXPECT_EQ(jump.value[0], tex.image().mean()[0]);
    EXPECT_EQ(cmam_lookup_with_info(tex, c, tag(0, 4, 1), 0.81, 0.4, o).region.matches, 1);
    EXPECT_EQ(cmam_lookup_with_info(tex, c, tag(0, 5, 1), 0.82, 0.4, o).region.matches, 2);
    // 2-D: row 1's third sample lies on patch 1 under row 0's patch-0 samples.
    o.two_d = true;
    for (const uint32_t patch : {0u, 1u}) {
        CmamCache rows;
        for (uint32_t k = 0; k < 4; ++k)
            cmam_lookup(tex, rows, tag(0, k, 0), 0.3 + 0.01 * k, 0.4, o);
        cmam_lookup(tex, rows, tag(1, 0, 0), 0.3, 0.41, o);
        cmam_lookup(tex, rows, tag(1, 1, 0), 0.31, 0.41, o);
        const CmamResult r = cmam_lookup_with_info(tex, rows, tag(1, 2, patch), 0.32, 0.41, o);
        EXPECT_EQ(r.region.used_above, patch == 0) << patch;
    }
}

TEST(Cmam2d, NeighboursAcrossAPeriodicSeamAreTakenTheShortWay) {
    // Period 1 (a mapping's longitude) and 3 (a closed quadric's u under uscale 3): rows of
    // samples across the seam, wrapped into one period, give the regions and values of the same
    // rows unwrapped.
    FilteredTexture tex(tmip1());
    for (const double period : {1.0, 3.0})
        for (const bool along_v : {false, true}) {
            SCOPED_TRACE(along_v ? "periodic_v" : "periodic_u");
            SCOPED_TRACE(period);
            CmamOptions o;
            o.two_d = true;
            o.filter = FilterKind::Area;
            CmamOptions periodic = o;
            (along_v ? periodic.periodic_v : periodic.periodic_u) = true;
            (along_v ? periodic.period_v : periodic.period_u) = period;
            CmamCache wrapped, unwrapped;
            CmamResult w, uw;
            // Row 0 crosses the seam after its third sample, row 1 after its second.
            const double row_u[2][5] = {{0.88, 0.93, 0.98, 1.03, 1.08},
                                        {0.90, 0.95, 1.00, 1.05, 1.10}};
            for (uint32_t row = 0; row < 2; ++row)
                for (uint32_t k = 0; k < 5; ++k) {
                    const double u = (row_u[row][k] + 0.001 * row) * period, a = 0.4 + 0.03 * row;
                    const double seam = u >= period ? u - period : u;
                    auto look = [&](CmamCache& c, double x, const CmamOptions& opts) {
                        return along_v ? cmam_lookup_with_info(tex, c, {row, 0, k}, a, x, opts)
                                       : cmam_lookup_with_info(tex, c, {row, 0, k}, x, a, opts);
                    };
                    w = look(wrapped, seam, periodic);
                    uw = look(unwrapped, u, o);
                    if (row == 0 && k == 0) continue;
                    EXPECT_NEAR(w.region.a.u, uw.region.a.u, 1e-9) << row << " " << k;
                    EXPECT_NEAR(w.region.a.v, uw.region.a.v, 1e-9) << row << " " << k;
                    EXPECT_NEAR(w.region.b.u, uw.region.b.u, 1e-9) << row << " " << k;
                    EXPECT_NEAR(w.region.b.v, uw.region.b.v, 1e-9) << row << " " << k;
                    EXPECT_NEAR(w.value[0], uw.value[0], 1e-5) << row << " " << k;
                }
            // The last sample of row 1: its left neighbour (1.05) is past the seam as it is, but
            // the sample above (1.08, as 0.08) is too, and the one before it in row 0 (1.03) as
            // well; the plain CMAM sees the step from 0.99 to 0.01 in row 0 as a whole period.
            EXPECT_LT(std::max(length(w.region.a), length(w.region.b)), period);
            CmamCache seam_row;
            const double before = 0.98 * period, after = 0.03 * period;
            cmam_lookup(tex, seam_row, {0, 0, 0}, along_v ? 0.4 : before, along_v ? before : 0.4,
                        o);
            const CmamResult across = cmam_lookup_with_info(
                tex, seam_row, {0, 0, 1}, along_v ? 0.4 : after, along_v ? after : 0.4, o);
            EXPECT_GT(std::max(length(across.region.a), length(across.region.b)), 3.0 * period);
            // Steps of more than half a unit but less than half the period do not cross the
            // seam: they stay as they are.
            CmamCache wide_p, wide;
            for (uint32_t k = 0; k < 4; ++k) {
                const double x = (0.1 + 0.25 * k) * period;
                const CmamResult a = cmam_lookup_with_info(tex, wide_p, {0, 0, k},
                                                           along_v ? 0.4 : x, along_v ? x : 0.4,
                                                           periodic),
                                 b = cmam_lookup_with_info(tex, wide, {0, 0, k}, along_v ? 0.4 : x,
                                                           along_v ? x : 0.4, o);
                EXPECT_NEAR(length(a.region.a), length(b.region.a), 1e-9) << k;
                EXPECT_NEAR(a.value[0], b.value[0], 1e-6) << k;
            }
        }
}

namespace {
// A w x h RGB texture of scrambled values in [0, 1].
Image scrambled_rgb(int w, int h) {
    std::vector<float> px(std::size_t(w) * h * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float((i * 7919) % 103) / 102;
    return Image(w, h, 3, px);
}
constexpr FilterKind kEveryFilter[] = {FilterKind::Trilinear, FilterKind::Sat, FilterKind::Ewa,
                                       FilterKind::Area, FilterKind::Bilinear};
}  // namespace

TEST(Cmam, PlainLookupIsTheRecordedOnesValueAndCacheStep) {
    // cmam_lookup takes a shorter way than cmam_lookup_with_info where no region is asked for
    // (the 1-D CMAM without hull weighting): the two must give the same value, bit for bit, and
    // leave the cache the same, over matches and misses (a new ID, a gap in the sequence, another
    // level or patch), both miss policies, every filter, periodic coordinates across their seam,
    // and samples beyond the texture's range.
    const FilteredTexture t(scrambled_rgb(29, 17));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0, 1);
    int compared = 0, matched = 0;
    for (FilterKind kind : kEveryFilter)
        for (CmamMiss miss : {CmamMiss::Average, CmamMiss::Point})
            for (int periodic : {0, 1, 2}) {
                CmamOptions o;
                o.filter = kind;
                o.miss = miss;
                o.periodic_u = periodic == 1;
                o.periodic_v = periodic == 2;
                o.period_u = 3;  // a closed quadric's u under uscale 3
                CmamCache plain, recorded;
                RayTag tag{};
                // Along the row, across it; along is u, or v when v is the periodic one.
                const double period = periodic == 1 ? o.period_u : o.period_v;
                double along = 0.2, across = 0.7;
                for (int k = 0; k < 400; ++k) {
                    // Mostly steps along a row, now and then a new ID, a skipped sample, another
                    // level or patch, or a sample far outside the texture.
                    const double r = unit(rng);
                    ++tag.seq;
                    if (r < 0.05) {
                        ++tag.id;
                    } else if (r < 0.08) {
                        ++tag.seq;
                    } else if (r < 0.11) {
                        tag.level ^= 1;
                    } else if (r < 0.13) {
                        tag.patch ^= 1;
                    }
                    along += 0.01 + 0.03 * unit(rng);
                    across += 0.01 * (unit(rng) - 0.5);
                    if (periodic != 0 && along >= period) along -= period;  // across the seam
                    const bool far = r > 0.99;
                    const double su = far             ? 1e12
                                      : periodic == 2 ? across
                                                      : along,
                                 vv = far             ? -3e11
                                      : periodic == 2 ? along
                                                      : across;
                    const Texel a = cmam_lookup(t, plain, tag, su, vv, o);
                    const CmamResult b = cmam_lookup_with_info(t, recorded, tag, su, vv, o);
                    for (int c = 0; c < 3; ++c)
                        ASSERT_EQ(a[c], b.value[c])
                            << to_string(kind) << " periodic " << periodic << " sample " << k;
                    matched += b.region.matches > 0;
                    ++compared;
                    for (const auto* e : {&plain.last, &plain.second_last}) {
                        const CmamCache::Entry& f =
                            e == &plain.last ? recorded.last : recorded.second_last;
                        ASSERT_EQ(e->valid, f.valid) << k;
                        ASSERT_EQ(e->s, f.s) << k;
                        ASSERT_EQ(e->t, f.t) << k;
                        ASSERT_EQ(e->u, f.u) << k;
                        ASSERT_EQ(e->v, f.v) << k;
                        ASSERT_EQ(e->tag.seq, f.tag.seq) << k;
                    }
                }
            }
    // Most samples matched a cached one (the filters ran), and some did not (the misses).
    EXPECT_GT(matched, compared / 2);
    EXPECT_LT(matched, compared);
}

TEST(Cmam2d, PlainLookupIsTheRecordedOnesValue) {
    // The 2-D CMAM's plain lookup builds only the region's axes and centre (what the filter
    // reads), the recorded one the whole region: the same value, bit for bit, for every filter,
    // with tags that carry positions (jittered or on the strata's grid) and tags that do not,
    // over rows whose samples have a sample above, and across a periodic seam.
    const FilteredTexture t(scrambled_rgb(31, 19));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0, 1);
    int with_above = 0;
    for (FilterKind kind : kEveryFilter)
        for (int tags : {0, 1, 2})  // unpositioned, positioned and jittered, positioned on a grid
            for (bool periodic : {false, true}) {
                CmamOptions o;
                o.two_d = true;
                o.filter = kind;
                o.periodic_u = periodic;
                CmamCache plain, recorded;
                for (uint32_t row = 0; row < 12; ++row)
                    for (uint32_t k = 0; k < 14; ++k) {
                        RayTag tag{row, 0, k};
                        const double jx = tags == 1 ? unit(rng) : 0.5,
                                     jy = tags == 1 ? unit(rng) : 0.5;
                        if (tags != 0) {
                            tag.positioned = true;
                            tag.x = k + jx;
                            tag.y = row + jy;
                        }
                        // A receding, slightly rotated plane, crossing u = 1 along each row.
                        double u = 0.8 + (k + jx) * (0.03 + 0.002 * row) + 0.004 * (row + jy);
                        const double v = 0.3 + (row + jy) * 0.025 + 0.003 * (k + jx);
                        if (periodic && u >= 1) u -= 1;
                        const Texel a = cmam_lookup(t, plain, tag, u, v, o);
                        const CmamResult b = cmam_lookup_with_info(t, recorded, tag, u, v, o);
                        for (int c = 0; c < 3; ++c)
                            ASSERT_EQ(a[c], b.value[c]) << to_string(kind) << " tags " << tags
                                                        << " row " << row << " sample " << k;
                        with_above += b.region.used_above;
                    }
            }
    EXPECT_GT(with_above, 5 * 3 * 2 * 11 * 14 / 2);  // most samples had one above
}
