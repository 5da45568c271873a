// pbrt-v3's procedural textures and 2-D mappings at points where their value is known: bilerp,
// uv, dots, 3-D checkerboard, fbm, wrinkled, windy, marble; spherical, cylindrical and planar
// mappings; Perlin noise's lattice zeros; fBm and turbulence, whose octaves are evaluated four at
// a time, against the octaves one by one.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "render/integrator.h"
#include "render/noise.h"
#include "render/shading.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// A scene whose first material's Kd is the spectrum texture "t" declared by `texture`.
std::unique_ptr<Scene> with_texture(const std::string& texture) {
    return test::scene_from("Camera \"perspective\" WorldBegin " + texture +
                            " Material \"matte\" \"texture Kd\" \"t\" Shape \"sphere\" WorldEnd");
}

Rgb at(const Scene& s, float u, float v, Vec3 p = {}) {
    TexContext ctx;
    ctx.u = u;
    ctx.v = v;
    ctx.p = p;
    return eval_texture(s, s.materials[0].kd, ctx);
}

}  // namespace

// fbm and turbulence take their octaves' noise four at a time: each must be what the octaves
// one by one give (pbrt-v3's loops, restated here with the single noise), bit for bit, for
// every number of octaves, at negative and large coordinates (beyond 2^23 and 2^31 too), on
// lattice planes, at -0, and with the faded octave anywhere in a group of four.
namespace {
float octave_count(const Vec3& dpdx, const Vec3& dpdy, int max_octaves) {
    const float len2 = std::max(dot(dpdx, dpdx), dot(dpdy, dpdy));
    if (!(len2 > 0)) return float(max_octaves);
    return std::clamp(-1 - 0.5f * std::log2(len2), 0.0f, float(max_octaves));
}
float smooth(float x) {
    if (x <= 0.3f) return 0;
    if (x >= 0.7f) return 1;
    const float t = (x - 0.3f) / (0.7f - 0.3f);
    return t * t * (3 - 2 * t);
}
float fbm_one_by_one(const Vec3& p, const Vec3& dx, const Vec3& dy, float omega, int octaves) {
    const float n = octave_count(dx, dy, octaves);
    const int whole = static_cast<int>(std::floor(n));
    float sum = 0, frequency = 1, amplitude = 1;
    for (int i = 0; i < whole; ++i) {
        sum += amplitude * perlin_noise(p * frequency);
        frequency *= 1.99f;
        amplitude *= omega;
    }
    return sum + amplitude * smooth(n - float(whole)) * perlin_noise(p * frequency);
}
float turbulence_one_by_one(const Vec3& p, const Vec3& dx, const Vec3& dy, float omega,
                            int octaves) {
    const float n = octave_count(dx, dy, octaves);
    const int whole = static_cast<int>(std::floor(n));
    float sum = 0, frequency = 1, amplitude = 1;
    for (int i = 0; i < whole; ++i) {
        sum += amplitude * std::abs(perlin_noise(p * frequency));
        frequency *= 1.99f;
        amplitude *= omega;
    }
    const float w = smooth(n - float(whole));
    sum += amplitude * (0.2f + w * (std::abs(perlin_noise(p * frequency)) - 0.2f));
    for (int i = whole; i < octaves; ++i) {
        sum += amplitude * 0.2f;
        amplitude *= omega;
    }
    return sum;
}
uint32_t bits(float x) {
    uint32_t u;
    std::memcpy(&u, &x, 4);
    return u;
}
}  // namespace

TEST(Noise, OctavesFourAtOnceEqualOneByOne) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> small(-300.0f, 300.0f), big(-1e6f, 1e6f),
        step(0.0f, 0.3f), omega(0.2f, 0.8f);
    std::uniform_int_distribution<int> lattice(-600, 600), octaves(1, 11);
    int differ = 0, nonzero = 0, n = 0;
    for (int k = 0; k < 40000; ++k) {
        Vec3 p;
        switch (k % 6) {
            case 0:
                p = Vec3(small(rng), small(rng), small(rng));
                break;
            case 1:
                p = Vec3(big(rng), big(rng), small(rng));
                break;
            case 2:
                p = Vec3(float(lattice(rng)), small(rng), small(rng));
                break;
            case 3:
                p = Vec3(small(rng), float(lattice(rng)), float(lattice(rng)));
                break;
            // Beyond 2^23 (integral floats) and 2^31 (past a 32-bit integer), and -0.
            case 4:
                p = Vec3(big(rng) * 1e4f, small(rng) * 3e7f, -0.0f);
                break;
            default:
                p = Vec3(-0.0f, std::nextafter(float(lattice(rng)), 0.0f), small(rng));
                break;
        }
        // Footprints from none (every octave) to wide (none but a faded first one).
        const Vec3 dx = k % 5 == 0 ? Vec3() : Vec3(step(rng), 0, step(rng)),
                   dy = Vec3(0, step(rng), 0);
        const float w = omega(rng);
        const int o = octaves(rng);
        const float f = fbm(p, dx, dy, w, o), t = turbulence(p, dx, dy, w, o);
        differ += bits(f) != bits(fbm_one_by_one(p, dx, dy, w, o));
        differ += bits(t) != bits(turbulence_one_by_one(p, dx, dy, w, o));
        nonzero += f != 0;
        ++n;
    }
    EXPECT_EQ(differ, 0);
    EXPECT_GT(nonzero, n * 3 / 4);
}

TEST(Noise, ZeroOnTheLatticeAndBounded) {
    EXPECT_EQ(perlin_noise(Vec3(0, 0, 0)), 0);
    EXPECT_EQ(perlin_noise(Vec3(3, -7, 12)), 0);
    float lo = 0, hi = 0;
    for (int i = 0; i < 2000; ++i) {
        const float x = perlin_noise(Vec3(i * 0.137f, i * 0.0713f - 5, 2.5f - i * 0.0291f));
        lo = std::min(lo, x);
        hi = std::max(hi, x);
    }
    EXPECT_LT(lo, -0.3f);
    EXPECT_GT(hi, 0.3f);
    EXPECT_GE(lo, -1.1f);
    EXPECT_LE(hi, 1.1f);
    // One octave of fbm is the noise; a footprint wider than the first octave leaves nothing.
    const Vec3 p(0.3f, 1.7f, -2.2f);
    EXPECT_FLOAT_EQ(fbm(p, {}, {}, 0.5f, 1), perlin_noise(p));
    EXPECT_FLOAT_EQ(fbm(p, Vec3(4, 0, 0), Vec3(0, 4, 0), 0.5f, 8), 0);
    // Turbulence counts the octaves it does not resolve at 0.2 each, and (as pbrt-v3 does) the
    // faded-out one at 0.2 too.
    EXPECT_NEAR(turbulence(p, Vec3(4, 0, 0), {}, 0.5f, 3), 0.2f + 0.2f * (1 + 0.5f + 0.25f), 1e-6f);
}

TEST(ProceduralTexture, BilerpAndUvAtKnownCoordinates) {
    auto b = with_texture(
        "Texture \"t\" \"spectrum\" \"bilerp\" \"rgb v00\" [1 0 0] \"rgb v01\" [0 1 0] "
        "\"rgb v10\" [0 0 1] \"rgb v11\" [1 1 1]");
    const Rgb c = at(*b, 0.25f, 0.75f);  // 3/16 v00 + 9/16 v01 + 1/16 v10 + 3/16 v11
    EXPECT_NEAR(c.r, 3 / 16.0f + 3 / 16.0f, 1e-6f);
    EXPECT_NEAR(c.g, 9 / 16.0f + 3 / 16.0f, 1e-6f);
    EXPECT_NEAR(c.b, 1 / 16.0f + 3 / 16.0f, 1e-6f);
    auto uv =
        with_texture("Texture \"t\" \"spectrum\" \"uv\" \"float uscale\" 3 \"float vdelta\" 0.5");
    const Rgb d = at(*uv, 0.5f, 0.25f);  // (frac(1.5), frac(0.75), 0)
    EXPECT_NEAR(d.r, 0.5f, 1e-6f);
    EXPECT_NEAR(d.g, 0.75f, 1e-6f);
    EXPECT_EQ(d.b, 0);
}

TEST(ProceduralTexture, MappingsFollowPbrtV3) {
    // Spherical: (theta / pi, phi / 2 pi) of the texture-space direction.
    auto sph = with_texture("Texture \"t\" \"spectrum\" \"uv\" \"string mapping\" \"spherical\"");
    Rgb c = at(*sph, 0, 0, Vec3(0, 2, 0));
    EXPECT_NEAR(c.r, 0.5f, 1e-6f);
    EXPECT_NEAR(c.g, 0.25f, 1e-6f);
    // The texture's transform moves the centre: at (0, 0, 3) + (1, 0, 0) the direction is +x.
    auto moved = with_texture(
        "TransformBegin Translate 0 0 3 Texture \"t\" \"spectrum\" \"uv\" \"string mapping\" "
        "\"spherical\" TransformEnd");
    c = at(*moved, 0, 0, Vec3(1, 0, 3));
    EXPECT_NEAR(c.r, 0.5f, 1e-6f);
    EXPECT_NEAR(c.g, 0.0f, 1e-6f);
    // Cylindrical: ((pi + atan2(y, x)) / 2 pi, z of the unit direction).
    auto cyl = with_texture("Texture \"t\" \"spectrum\" \"uv\" \"string mapping\" \"cylindrical\"");
    c = at(*cyl, 0, 0, Vec3(0, 1, 0.3f));
    EXPECT_NEAR(c.r, 0.75f, 1e-6f);
    EXPECT_NEAR(c.g, 0.3f / std::sqrt(1.09f), 1e-6f);
    // Planar: offsets plus projections of the world point.
    auto pl = with_texture(
        "Texture \"t\" \"spectrum\" \"uv\" \"string mapping\" \"planar\" \"vector3 v1\" [0 0 1] "
        "\"vector3 v2\" [0.5 0 0] \"float udelta\" 0.25");
    c = at(*pl, 0, 0, Vec3(0.5f, 7, 2.125f));
    EXPECT_NEAR(c.r, 0.375f, 1e-6f);  // frac(0.25 + 2.125)
    EXPECT_NEAR(c.g, 0.25f, 1e-6f);
}

TEST(ProceduralTexture, CheckerboardIn3DAndDots) {
    auto cb = with_texture(
        "Texture \"t\" \"spectrum\" \"checkerboard\" \"integer dimension\" 3 \"rgb tex1\" [1 1 1] "
        "\"rgb tex2\" [0 0 0]");
    EXPECT_EQ(at(*cb, 0, 0, Vec3(0.5f, 0.5f, 0.5f)).r, 1);
    EXPECT_EQ(at(*cb, 0, 0, Vec3(1.5f, 0.5f, 0.5f)).r, 0);
    EXPECT_EQ(at(*cb, 0, 0, Vec3(-0.5f, 0.5f, 0.5f)).r, 0);
    EXPECT_EQ(at(*cb, 0, 0, Vec3(-0.5f, -0.5f, 0.5f)).r, 1);
    // Dots of radius 0.35 in about half the cells: about pi 0.35^2 / 2 of the plane. They show
    // "outside" and the rest "inside", as pbrt-v3 renders them (its constructor takes the two in
    // the other order).
    auto dots = with_texture(
        "Texture \"t\" \"spectrum\" \"dots\" \"rgb inside\" [1 1 1] \"rgb outside\" [0 0 0]");
    int in_dots = 0, n = 0;
    for (int j = 0; j < 200; ++j)
        for (int i = 0; i < 200; ++i, ++n)
            in_dots += at(*dots, i * 0.1f + 0.05f, j * 0.1f + 0.05f).r == 0;
    EXPECT_GT(in_dots, n / 10);
    EXPECT_LT(in_dots, n * 3 / 10);
}

TEST(ProceduralTexture, NoiseTexturesAreFiniteAndVary) {
    for (const char* cls : {"fbm", "wrinkled", "windy", "marble"}) {
        SCOPED_TRACE(cls);
        auto s = with_texture(std::string("Texture \"t\" \"spectrum\" \"") + cls + "\"");
        EXPECT_TRUE(s->footprint_methods.has(
            FootprintMethod::Differentials));  // their octaves follow the footprint
        float lo = 1e9f, hi = -1e9f;
        for (int i = 0; i < 500; ++i) {
            const Rgb c = at(*s, 0, 0, Vec3(i * 0.0371f, 0.2f + i * 0.0113f, -i * 0.023f));
            ASSERT_TRUE(std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b));
            lo = std::min(lo, c.g);
            hi = std::max(hi, c.g);
        }
        EXPECT_GT(hi - lo, 0.01f);
    }
    // fbm's value is the sum of its octaves.
    auto f = with_texture(
        "Texture \"t\" \"spectrum\" \"fbm\" \"integer octaves\" 2 \"float roughness\" 0.25");
    const Vec3 p(0.3f, 1.7f, -2.2f);
    EXPECT_NEAR(at(*f, 0, 0, p).r, perlin_noise(p) + 0.25f * perlin_noise(p * 1.99f), 1e-6f);
}

TEST(ProceduralTexture, MarbleAtTheOriginFollowsPbrtV3sSpline) {
    // At the origin every octave of noise is zero, so t = 0.5: the segment index clamps to 1
    // and the spline is evaluated at 2 over greys 1..4 (pbrt-v3's marble).
    auto m = with_texture("Texture \"t\" \"spectrum\" \"marble\"");
    const Rgb c = at(*m, 0, 0, Vec3(0, 0, 0));
    const float g[4] = {0.58f, 0.58f, 0.5f, 0.6f};  // red channel of colours 1..4
    const float t = 2;
    auto mix = [t](float a, float b) { return (1 - t) * a + t * b; };
    const float s0 = mix(mix(g[0], g[1]), mix(g[1], g[2])),
                s1 = mix(mix(g[1], g[2]), mix(g[2], g[3]));
    EXPECT_NEAR(c.r, 1.5f * mix(s0, s1), 1e-5f);
}

TEST(ProceduralTexture, UnknownMappingIsALocatedError) {
    try {
        with_texture("Texture \"t\" \"spectrum\" \"uv\" \"string mapping\" \"cubic\"");
        FAIL() << "no error";
    } catch (const pbrt::SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("unknown texture mapping \"cubic\""),
                  std::string::npos)
            << e.what();
    }
}

TEST(AlphaMask, CutOutsFollowTheMaskForCameraAndShadowRays) {
    // A unit square at z = 1 (uv = xy) over a big plane at z = 0, lit from straight above.
    auto scene = [](const std::string& mask) {
        return test::scene_from(
            "Camera \"perspective\" WorldBegin LightSource \"distant\" \"point from\" [0 0 1] "
            "\"point to\" [0 0 0] Texture \"checks\" \"float\" \"checkerboard\" \"float uscale\" 2 "
            "\"float vscale\" 2 \"float tex1\" 1 \"float tex2\" 0 "
            "Shape \"trianglemesh\" \"point3 P\" [0 0 1  1 0 1  1 1 1  0 1 1] \"point2 uv\" "
            "[0 0 1 0 1 1 0 1] \"integer indices\" [0 1 2 0 2 3] " +
            mask +
            " Shape \"trianglemesh\" \"point3 P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "
            "\"integer indices\" [0 1 2 0 2 3] WorldEnd");
    };
    auto hit_z = [](const Scene& s, float x, float y) {
        const std::optional<SurfaceHit> h = s.intersect(Vec3(x, y, 5), Vec3(0, 0, -1), 0, 100);
        EXPECT_TRUE(h.has_value());
        return h ? h->p.z : 0.0f;
    };
    auto none = scene("\"float alpha\" 0");
    EXPECT_NEAR(hit_z(*none, 0.3f, 0.3f), 0, 1e-5f);  // not there
    auto checks = scene("\"texture alpha\" \"checks\"");
    EXPECT_NEAR(hit_z(*checks, 0.25f, 0.25f), 1, 1e-5f);  // cell (0,0): 1, present
    EXPECT_NEAR(hit_z(*checks, 0.75f, 0.25f), 0, 1e-5f);  // cell (1,0): 0, cut out
    EXPECT_FALSE(checks->occluded(Vec3(0.75f, 0.25f, 0.5f), Vec3(0, 0, 1), 0, 10));
    EXPECT_TRUE(checks->occluded(Vec3(0.25f, 0.25f, 0.5f), Vec3(0, 0, 1), 0, 10));
    // shadowalpha: seen by camera rays, not by shadow rays.
    auto ghost = scene("\"float shadowalpha\" 0");
    EXPECT_NEAR(hit_z(*ghost, 0.3f, 0.3f), 1, 1e-5f);
    EXPECT_FALSE(ghost->occluded(Vec3(0.3f, 0.3f, 0.5f), Vec3(0, 0, 1), 0, 10));
    // The plane under a square that is not there is lit: Kd / pi * E with E = 1.
    EXPECT_NEAR(trace_radiance(*none, Vec3(0.3f, 0.3f, 5), Vec3(0, 0, -1), 1, nullptr).r,
                0.5f / kPi * 1, 1e-5f);
}
