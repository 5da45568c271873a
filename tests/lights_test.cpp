// Environment maps and area lights against closed forms: a diffuse plane under a constant map
// reflects Kd L; the map's orientation follows pbrt-v3's (phi / 2 pi, theta / pi) with z up in
// the light's frame; importance sampling is unbiased against a quadrature of the map; square,
// disk and sphere area lights give the irradiance of their form factors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "render/build_scene.h"
#include "render/envmap.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "scene_util.h"
#include "temp_dir.h"

using namespace cmam;
using namespace cmam::render;
namespace fs = std::filesystem;

namespace {

// The maps' folder, removed with them when the test process exits.
const fs::path& temp_dir() {
    static const test::TempDir dir("cmam_lights");
    return dir.path;
}

// Writes a W x H map whose texel (i, j) (j = 0 the file's top row) is f(i, j).
template <class F>
std::string write_map(const std::string& name, int W, int H, F f) {
    std::vector<float> rgb(static_cast<std::size_t>(W) * H * 3);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const Rgb c = f(i, j);
            float* p = &rgb[(static_cast<std::size_t>(j) * W + i) * 3];
            p[0] = c.r;
            p[1] = c.g;
            p[2] = c.b;
        }
    const std::string path = (temp_dir() / name).string();
    write_image(path, W, H, rgb);
    return path;
}

// The red radiance's mean and standard deviation over 4000 seeds along one ray down onto the
// plane of camera_and_plane.
std::pair<double, double> radiance_stats(const Scene& s) {
    double m = 0, m2 = 0;
    const int n = 4000;
    for (int k = 0; k < n; ++k) {
        const double r =
            trace_radiance(s, Vec3(0.3f, 0.2f, 0.5f), Vec3(0, 0, -1), uint64_t(k) + 1, nullptr).r;
        m += r;
        m2 += r * r;
    }
    m /= n;
    return {m, std::sqrt(std::max(0.0, m2 / n - m * m))};
}

std::string camera_and_plane(const std::string& world) {
    // (Whitted: the closed forms below are the lights' direct light.)
    return "LookAt 0 0 10  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 30 "
           "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
           "Integrator \"whitted\" WorldBegin " +
           world +
           " Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5] "
           "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0] "
           "\"integer indices\" [0 1 2 0 2 3] WorldEnd";
}

double mean_red(const Framebuffer& fb) {
    double m = 0;
    for (std::size_t i = 0; i < fb.rgb.size(); i += 3) m += fb.rgb[i];
    return m / double(fb.rgb.size() / 3);
}

// Mean red radiance along a ray over many seeds.
double mean_radiance(const Scene& s, Vec3 org, Vec3 dir, int n) {
    double m = 0;
    for (int k = 0; k < n; ++k)
        m += trace_radiance(s, org, normalize(dir), uint64_t(k) + 1, nullptr).r;
    return m / n;
}

}  // namespace

TEST(EnvironmentMap, ConstantMapLightsADiffusePlaneWithKdTimesL) {
    const std::string map = write_map("const.exr", 16, 8, [](int, int) { return Rgb(0.7f); });
    auto s = test::scene_from(camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" +
                                               map + "\" \"rgb L\" [2 2 2]"),
                              "t.pbrt", 256);
    ASSERT_EQ(s->lights.size(), 1u);
    ASSERT_TRUE(s->lights[0].env);
    Framebuffer fb = render::render(*s, {}, nullptr);
    // 65536 samples of 4 Kd L cos(theta)^+ (uniform over the sphere): sigma 0.0035.
    EXPECT_NEAR(mean_red(fb), 0.5 * 0.7 * 2, 0.012);
}

// An 8-bit light map's values are its bytes over 255, not decoded from sRGB: pbrt-v3 reads the
// maps of its infinite, goniometric and projection lights with ReadImage, which decodes nothing
// (only an image texture has "gamma"). A PNG written from linear 0.2 stores sRGB-encoded bytes
// near 0.48, which the light's map then holds.
TEST(EnvironmentMap, EightBitMapsAreTheirBytesAsPbrtV3ReadsThem) {
    const std::string map = write_map("grey.png", 16, 8, [](int, int) { return Rgb(0.2f); });
    const RawImage raw = read_image(map);
    ASSERT_TRUE(raw.is_8bit);
    const float stored = raw.pixels.at(0);
    ASSERT_NEAR(stored, 0.48f, 0.01f);
    auto s = test::scene_from(
        camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + map + "\""), "t.pbrt",
        1);
    const EnvironmentMap& env = *s->lights.at(0).env;
    for (const Vec3 d : {Vec3(0, 0, 1), Vec3(1, 0.3f, -0.2f), Vec3(-0.5f, -1, 0.1f)})
        EXPECT_NEAR(env.radiance(normalize(d)).g, stored, 1e-6f);
}

TEST(EnvironmentMap, OrientationFollowsPbrtV3) {
    // The file's top half (theta < pi/2: +z in the light's frame) is bright; its left half
    // (phi < pi: +y side) is red, its right half blue.
    const std::string map = write_map("orient.exr", 64, 32, [](int i, int j) {
        const float up = j < 16 ? 1.0f : 0.1f;
        return i < 32 ? Rgb(up, 0, 0) : Rgb(0, 0, up);
    });
    const std::string light = "LightSource \"infinite\" \"string mapname\" \"" + map + "\" ";
    auto s = test::scene_from(camera_and_plane(light), "t.pbrt", 1);
    const EnvironmentMap& env = *s->lights[0].env;
    EXPECT_NEAR(env.radiance(normalize(Vec3(0.1f, 1, 1))).r, 1.0f, 1e-5f);   // up, +y: red
    EXPECT_NEAR(env.radiance(normalize(Vec3(0.1f, -1, 1))).b, 1.0f, 1e-5f);  // up, -y: blue
    EXPECT_NEAR(env.radiance(normalize(Vec3(0.1f, 1, -1))).r, 0.1f, 1e-5f);  // down
    // A camera ray that escapes sees the map: straight up from above the plane.
    EXPECT_NEAR(trace_radiance(*s, Vec3(0, 0, 1), normalize(Vec3(0.1f, 1, 1)), 1, nullptr).r, 1.0f,
                1e-5f);
    // The light's transform orients it: Rotate -90 about x takes its z to world +y.
    auto r = test::scene_from(
        camera_and_plane("AttributeBegin Rotate -90 1 0 0 " + light + "AttributeEnd"), "t.pbrt", 1);
    const EnvironmentMap& er = *r->lights[0].env;
    EXPECT_NEAR(er.radiance(normalize(Vec3(0.1f, 1, -1))).r, 1.0f, 1e-5f);
    EXPECT_NEAR(er.radiance(normalize(Vec3(0.1f, -1, 1))).r + er.radiance(Vec3(0.1f, -1, 1)).b,
                0.1f, 1e-5f);
}

TEST(EnvironmentMap, ImportanceSamplingIsUnbiasedAndItsPdfIsConsistent) {
    // A dim map with a small bright patch and a band: the luminance-sampled estimate of the
    // cosine-weighted integral over the upper hemisphere matches a fine quadrature.
    const std::string map = write_map("sun.exr", 32, 16, [](int i, int j) {
        if (i == 5 && j == 4) return Rgb(200, 150, 100);
        if (j == 10) return Rgb(0, 3, 0);
        return Rgb(0.05f * float((i * 7 + j * 3) % 5));
    });
    auto s = test::scene_from(
        camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + map + "\""), "t.pbrt",
        1);
    const EnvironmentMap& env = *s->lights[0].env;
    const Vec3 n = normalize(Vec3(0.3f, -0.2f, 1));
    double ref = 0;
    const int NT = 1200, NP = 2400;
    for (int a = 0; a < NT; ++a)
        for (int b = 0; b < NP; ++b) {
            const double th = (a + 0.5) * std::numbers::pi / NT,
                         ph = (b + 0.5) * 2 * std::numbers::pi / NP;
            const Vec3 w(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                         float(std::cos(th)));
            ref += env.radiance(w).luminance() * std::max(0.0f, dot(w, n)) * std::sin(th);
        }
    ref *= (std::numbers::pi / NT) * (2 * std::numbers::pi / NP);
    double est = 0;
    const int N = 400000;
    uint64_t x = 12345;
    auto uni = [&x] {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        return float(x >> 40) * 0x1.0p-24f;
    };
    int checked = 0, pdf_mismatches = 0;
    for (int k = 0; k < N; ++k) {
        const auto [L, wi, pdf] = env.sample(uni(), uni());
        if (pdf == 0) continue;
        est += L.luminance() * std::max(0.0f, dot(wi, n)) / pdf;
        if (k % 997 == 0) {  // the sample's radiance and density are those of its direction
            EXPECT_NEAR(L.luminance(), env.radiance(wi).luminance(), 1e-3f * (1 + L.luminance()));
            // (a sample within rounding of a cell's edge may find the neighbour's density)
            pdf_mismatches += std::abs(pdf - env.pdf(wi)) > 2e-3f * pdf;
            ++checked;
        }
    }
    est /= N;
    EXPECT_GT(checked, 100);
    EXPECT_LE(pdf_mismatches, checked / 50);
    EXPECT_NEAR(est, ref, 0.01 * ref);
}

// A batch of samples (drawn together so that their table reads overlap) is each pair's single
// sample, bit for bit: batch sizes below, at and past the batch's 16, u at 0 and just below 1,
// and a black map (nothing to sample).
TEST(EnvironmentMap, BatchedSamplesAreTheSingleSamples) {
    const std::string map = write_map("batch.exr", 48, 24, [](int i, int j) {
        if (i == 30 && j == 7) return Rgb(500, 400, 300);
        return Rgb(0.02f * float((i * 5 + j * 11) % 7), 0.3f, 0.01f * float(j));
    });
    const std::string black = write_map("black.exr", 8, 4, [](int, int) { return Rgb(0); });
    for (const std::string& m : {map, black}) {
        auto s = test::scene_from(
            camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + m + "\""), "t.pbrt",
            1);
        const EnvironmentMap& env = *s->lights[0].env;
        uint64_t x = 99;
        auto uni = [&x] {
            x = x * 6364136223846793005ull + 1442695040888963407ull;
            return float(x >> 40) * 0x1.0p-24f;
        };
        for (int n : {0, 1, 5, 16, 17, 40}) {
            std::vector<float> u1(static_cast<std::size_t>(n)), u2(u1.size());
            for (int i = 0; i < n; ++i) {
                u1[i] = i == 1 ? 0.0f : (i == 2 ? std::nextafter(1.0f, 0.0f) : uni());
                u2[i] = i == 3 ? 0.0f : (i == 4 ? std::nextafter(1.0f, 0.0f) : uni());
            }
            std::vector<EnvironmentMap::Sample> out(u1.size());
            env.sample(u1.data(), u2.data(), n, out.data());
            for (int i = 0; i < n; ++i) {
                const EnvironmentMap::Sample one = env.sample(u1[i], u2[i]);
                EXPECT_EQ(std::memcmp(&one.radiance, &out[i].radiance, sizeof one.radiance), 0);
                EXPECT_EQ(std::memcmp(&one.wi, &out[i].wi, sizeof one.wi), 0);
                EXPECT_EQ(std::memcmp(&one.pdf, &out[i].pdf, sizeof one.pdf), 0);
                // (u2 = 0 is the pole, where no direction is drawn)
                if (m == black || i == 3)
                    EXPECT_EQ(out[i].pdf, 0) << i;
                else
                    EXPECT_GT(out[i].pdf, 0) << i;
            }
        }
    }
}

// pbrt-v3's directlighting takes an environment map's nsamples (drawn in batches): their mean
// is the one-sample estimate's, with 1/sqrt(nsamples) of its spread (20 samples: a batch of 16
// and one of 4).
TEST(EnvironmentMap, NsamplesUnderDirectLightingAveragesThatManySamples) {
    const std::string map = write_map("ns.exr", 32, 16, [](int i, int j) {
        return Rgb(0.2f + float((i * 3 + j * 5) % 4), 1, 1);
    });
    auto scene = [&](const std::string& integrator) {
        std::string text = camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + map +
                                            "\" \"integer nsamples\" 20");
        text.insert(text.find("WorldBegin"), integrator + " ");
        return test::scene_from(text, "t.pbrt", 1);
    };
    const auto direct = scene("Integrator \"directlighting\""),
               whitted = scene("Integrator \"whitted\"");
    EXPECT_EQ(direct->lights[0].samples, 20);
    EXPECT_EQ(whitted->lights[0].samples, 1);
    const auto [m20, s20] = radiance_stats(*direct);
    const auto [m1, s1] = radiance_stats(*whitted);
    EXPECT_NEAR(m20, m1, 4 * s1 / std::sqrt(4000.0));
    EXPECT_GT(s1, 0);
    EXPECT_NEAR(s20 / s1, 1 / std::sqrt(20.0), 0.05);
}

TEST(EnvironmentMap, EscapingRaysFilterTheMapOverTheirDifferentials) {
    // A checker of single texels: a point lookup at a texel's centre gives 0 or 1, a lookup over
    // a footprint of about 8 x 8 texels its mean.
    const std::string map =
        write_map("checker.exr", 256, 128, [](int i, int j) { return Rgb(float((i + j) % 2)); });
    auto s = test::scene_from(
        camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + map + "\""), "t.pbrt",
        1);
    ASSERT_TRUE(s->lights[0].env_footprint);
    EXPECT_TRUE(s->footprint_methods.has(FootprintMethod::Differentials));
    const EnvironmentMap& env = *s->lights[0].env;
    // phi at the centre of texel column 10, theta at the centre of row 64.
    const float phi = 2 * kPi * 10.5f / 256, theta = kPi * 64.5f / 128;
    const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    const float point = env.radiance(d).r;
    EXPECT_TRUE(std::abs(point) < 1e-4f || std::abs(point - 1) < 1e-4f) << point;
    const Vec3 dx = 0.2f * Vec3(-std::sin(phi), std::cos(phi), 0), dy(0, 0, -0.2f);
    EXPECT_NEAR(env.radiance(d, &dx, &dy).r, 0.5f, 0.05f);
    // --lod other than differentials point-samples the map, as pbrt-v3 does.
    BuildOptions o;
    o.lod = FootprintMethod::None;
    auto p = render::build_scene(
        pbrt::parse_string(
            camera_and_plane("LightSource \"infinite\" \"string mapname\" \"" + map + "\""),
            "t.pbrt"),
        o, {});
    EXPECT_FALSE(p->lights[0].env_footprint);
}

TEST(EnvironmentMap, MissingMapIsALocatedError) {
    try {
        test::scene_from(
            camera_and_plane("LightSource \"infinite\" \"string mapname\" \"no_such_map.exr\""));
        FAIL() << "no error";
    } catch (const pbrt::SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("t.pbrt:1:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("no_such_map.exr"), std::string::npos) << e.what();
    }
}

namespace {
// Irradiance at the foot of the normal from a uniform emitter of radiance L covering the
// rectangle [0,X] x [0,Y] in a parallel plane at height h (form factor of a point to a
// rectangle with a corner above it).
double rect_irradiance(double L, double X, double Y, double h) {
    const double x = X / h, y = Y / h;
    const double f = (x / std::sqrt(1 + x * x)) * std::atan(y / std::sqrt(1 + x * x)) +
                     (y / std::sqrt(1 + y * y)) * std::atan(x / std::sqrt(1 + y * y));
    return L * f / 2;  // pi L F with F = f / (2 pi)
}
}  // namespace

// A constant infinite light on a matte plane whose given normals lean 60 degrees from its face:
// the radiance is Kd / pi L times the integral of |wi . ns| over the face's hemisphere (the BSDF
// reflects on the geometric side, the cosine is the shading normal's), and no sample exceeds
// Kd / pi L 4 pi, the bound of the light's sampling at this angle between the normals (half the
// samples uniform; cosine-weighted about the geometric normal alone, |wi . ns| / cos grows
// without bound at its horizon).
TEST(InfiniteLight, TiltedShadingNormalsAreSampledWithBoundedWeights) {
    const double beta = 60 * std::numbers::pi / 180;
    const float nx = float(std::sin(beta)), nz = float(std::cos(beta));
    const std::string n = std::to_string(nx) + " 0 " + std::to_string(nz) + " ";
    auto s = test::scene_from(
        "LookAt 0 0 10  0 0 0  0 1 0 Camera \"perspective\" Integrator \"whitted\" WorldBegin "
        "LightSource \"infinite\" \"rgb L\" [2 2 2] Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5] "
        "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0] "
        "\"integer indices\" [0 1 2 0 2 3] \"normal N\" [" +
            n + n + n + n + "] WorldEnd",
        "t.pbrt", 1);
    // The integral by quadrature over the upper hemisphere (theta, phi midpoints).
    double integral = 0;
    const int nt = 400, np = 800;
    for (int i = 0; i < nt; ++i)
        for (int j = 0; j < np; ++j) {
            const double t = (i + 0.5) * std::numbers::pi / 2 / nt,
                         p = (j + 0.5) * 2 * std::numbers::pi / np;
            const double c =
                std::abs(std::sin(t) * std::cos(p) * std::sin(beta) + std::cos(t) * std::cos(beta));
            integral += c * std::sin(t) * (std::numbers::pi / 2 / nt) * (2 * std::numbers::pi / np);
        }
    const double expected = 0.5 / std::numbers::pi * 2 * integral;
    double sum = 0, sum2 = 0, largest = 0;
    const int samples = 40000;
    for (int k = 0; k < samples; ++k) {
        const double v = trace_radiance(*s, Vec3(0.3f, -0.2f, 4), normalize(Vec3(-0.1f, 0.05f, -1)),
                                        uint64_t(k) + 1, nullptr)
                             .r;
        sum += v;
        sum2 += v * v;
        largest = std::max(largest, v);
    }
    const double mean = sum / samples, sd = std::sqrt(sum2 / samples - mean * mean);
    EXPECT_NEAR(mean, expected, 4 * sd / std::sqrt(double(samples)) + 1e-4 * expected);
    EXPECT_LE(largest, 0.5 / std::numbers::pi * 2 * 4 * std::numbers::pi * (1 + 1e-5));
}

TEST(AreaLight, SquareLightGivesTheFormFactorIrradiance) {
    // A 0.6 x 0.6 square at height 1, facing down, L = 5; the plane's radiance at the origin is
    // Kd / pi * E.
    const std::string light =
        "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [5 5 5] "
        "Shape \"trianglemesh\" \"point3 P\" [-0.3 -0.3 1  -0.3 0.3 1  0.3 0.3 1  0.3 -0.3 1] "
        "\"integer indices\" [0 1 2 0 2 3] AttributeEnd";
    auto s = test::scene_from(camera_and_plane(light), "t.pbrt", 1);
    ASSERT_EQ(s->lights.size(), 1u);
    const double E = 4 * rect_irradiance(5, 0.3, 0.3, 1);
    const double got = mean_radiance(*s, Vec3(0, -0.4f, 0.4f), Vec3(0, 0.4f, -0.4f), 20000);
    EXPECT_NEAR(got, 0.5 / std::numbers::pi * E, 0.003 * 0.5 / std::numbers::pi * E);
    // Its emitting side (the normal of P0 P1 P2 points down) shows L; the other side nothing.
    EXPECT_FLOAT_EQ(trace_radiance(*s, Vec3(0.1f, 0, 0.5f), Vec3(0, 0, 1), 1, nullptr).r, 5);
    EXPECT_FLOAT_EQ(trace_radiance(*s, Vec3(0.1f, 0, 2), Vec3(0, 0, -1), 1, nullptr).r, 0);
}

TEST(AreaLight, TwoSidedEmitsOnBothSidesAndReverseOrientationFlips) {
    auto mk = [](const std::string& pre, const std::string& params) {
        return test::scene_from(camera_and_plane(
            "AttributeBegin " + pre + " AreaLightSource \"diffuse\" \"rgb L\" [5 5 5] " + params +
            " Shape \"trianglemesh\" \"point3 P\" [-0.3 -0.3 1  -0.3 0.3 1  0.3 0.3 1  0.3 -0.3 "
            "1] \"integer indices\" [0 1 2 0 2 3] AttributeEnd"));
    };
    auto two = mk("", "\"bool twosided\" true");
    EXPECT_FLOAT_EQ(trace_radiance(*two, Vec3(0.1f, 0, 2), Vec3(0, 0, -1), 1, nullptr).r, 5);
    auto rev = mk("ReverseOrientation", "");
    EXPECT_FLOAT_EQ(trace_radiance(*rev, Vec3(0.1f, 0, 2), Vec3(0, 0, -1), 1, nullptr).r, 5);
    EXPECT_FLOAT_EQ(trace_radiance(*rev, Vec3(0.1f, 0, 0.5f), Vec3(0, 0, 1), 1, nullptr).r, 0);
}

TEST(AreaLight, DiskAndSphereLightsUnderTransforms) {
    // A disk of radius 0.25 scaled by 2 (radius 0.5 in the world) at height 1, facing down:
    // E = pi L R^2 / (h^2 + R^2).
    auto disk = test::scene_from(camera_and_plane(
        "AttributeBegin Translate 0 0 1 Scale 2 2 2 ReverseOrientation "
        "AreaLightSource \"diffuse\" \"rgb L\" [3 3 3] Shape \"disk\" \"float radius\" 0.25 "
        "AttributeEnd"));
    const double Ed = std::numbers::pi * 3 * 0.25 / (1 + 0.25);
    EXPECT_NEAR(mean_radiance(*disk, Vec3(0, -0.4f, 0.4f), Vec3(0, 0.4f, -0.4f), 20000),
                0.5 / std::numbers::pi * Ed, 0.005 * 0.5 / std::numbers::pi * Ed);
    // A sphere of radius 0.25 scaled by 2, centred 2 above: E = pi L (r / d)^2. A round sphere
    // is sampled in the cone it subtends (almost no variance); the same sphere cut at its poles
    // by zmin and zmax = +-0.2499 is sampled by area (half the samples on its far side).
    auto sphere = test::scene_from(camera_and_plane(
        "AttributeBegin Translate 0 0 2 Scale 2 2 2 AreaLightSource \"diffuse\" \"rgb L\" "
        "[4 4 4] Shape \"sphere\" \"float radius\" 0.25 AttributeEnd"));
    EXPECT_FLOAT_EQ(sphere->primitives[0]->sphere_radius, 0.5f);
    const double Es = std::numbers::pi * 4 * 0.0625;
    EXPECT_NEAR(mean_radiance(*sphere, Vec3(0, -0.4f, 0.4f), Vec3(0, 0.4f, -0.4f), 2000),
                0.5 / std::numbers::pi * Es, 0.001 * 0.5 / std::numbers::pi * Es);
    auto cut = test::scene_from(camera_and_plane(
        "AttributeBegin Translate 0 0 2 Scale 2 2 2 AreaLightSource \"diffuse\" \"rgb L\" "
        "[4 4 4] Shape \"sphere\" \"float radius\" 0.25 \"float zmin\" -0.2499 "
        "\"float zmax\" 0.2499 AttributeEnd"));
    EXPECT_EQ(cut->primitives[0]->sphere_radius, 0);
    EXPECT_NEAR(mean_radiance(*cut, Vec3(0, -0.4f, 0.4f), Vec3(0, 0.4f, -0.4f), 40000),
                0.5 / std::numbers::pi * Es, 0.01 * 0.5 / std::numbers::pi * Es);
}

TEST(AreaLight, InstancedShapesDoNotEmitWithAWarning) {
    std::vector<std::string> warnings;
    pbrt::SceneDesc d = pbrt::parse_string(
        camera_and_plane("AreaLightSource \"diffuse\" ObjectBegin \"o\" Shape \"sphere\" "
                         "ObjectEnd ObjectInstance \"o\""),
        "t.pbrt", [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_FALSE(warnings.empty());
    EXPECT_NE(warnings[0].find("object"), std::string::npos) << warnings[0];
}

TEST(AreaLight, ImagesWithTheNewLightsMaterialsAndTexturesAreTheSameForAnyThreadCount) {
    const std::string map = write_map("det.exr", 16, 8, [](int i, int j) {
        return Rgb(float(i % 3) * 0.3f, float(j % 2), 0.5f);
    });
    auto s = test::scene_from(
        "LookAt 0 -4 3  0 0 0  0 0 1 Camera \"perspective\" \"float fov\" 50 "
        "Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 24 WorldBegin "
        "LightSource \"infinite\" \"string mapname\" \"" +
            map +
            "\" AttributeBegin Translate 0 0 2 AreaLightSource \"diffuse\" \"rgb L\" [3 3 3] "
            "Shape \"sphere\" \"float radius\" 0.3 AttributeEnd "
            "Texture \"n\" \"spectrum\" \"fbm\" "
            "MakeNamedMaterial \"a\" \"string type\" \"matte\" \"texture Kd\" \"n\" "
            "MakeNamedMaterial \"b\" \"string type\" \"mirror\" "
            "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\" "
            "\"string namedmaterial2\" \"b\" NamedMaterial \"m\" "
            "Shape \"trianglemesh\" \"point3 P\" [-5 -5 0  5 -5 0  5 5 0  -5 5 0] "
            "\"integer indices\" [0 1 2 0 2 3] Shape \"cylinder\" \"float radius\" 0.5 WorldEnd",
        "t.pbrt", 4);
    RenderOptions one, two;
    one.threads = 1;
    two.threads = 2;
    const Framebuffer a = render::render(*s, one, nullptr), b = render::render(*s, two, nullptr);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
    double sum = 0;
    for (float x : a.rgb) sum += x;
    EXPECT_GT(sum, 0);
}

TEST(EnvironmentCamera, LatLongDirectionsAsPbrtV3) {
    // Identity camera transform: theta from camera +y (the top row), phi from +x towards +z.
    auto s = test::scene_from(
        "Camera \"environment\" Film \"image\" \"integer xresolution\" 40 "
        "\"integer yresolution\" 20 WorldBegin LightSource \"infinite\" Shape \"sphere\" "
        "\"float radius\" 5 WorldEnd",
        "t.pbrt", 1);
    ASSERT_TRUE(s->camera.environment);
    Vec3 d = s->camera.generate_ray(0, 10).dir;  // theta = pi/2, phi = 0
    EXPECT_NEAR(d.x, 1, 1e-5f);
    d = s->camera.generate_ray(10, 10).dir;  // phi = pi/2: +z
    EXPECT_NEAR(d.z, 1, 1e-5f);
    d = s->camera.generate_ray(7, 0).dir;  // the top row looks along +y
    EXPECT_NEAR(d.y, 1, 1e-5f);
    // Rendering from inside a sphere: every pixel sees it, lit by the sky.
    const Framebuffer fb = render::render(*s, {}, nullptr);
    for (std::size_t i = 0; i < fb.rgb.size(); ++i) ASSERT_TRUE(std::isfinite(fb.rgb[i]));
}

TEST(LightImage, GoniometricAndProjectionFollowPbrtV3) {
    // Goniometric: the file's top rows are the light's +y (pbrt-v3 swaps y and z, then theta).
    const std::string gmap =
        write_map("gonio.exr", 16, 8, [](int, int j) { return Rgb(j < 4 ? 1.0f : 0.0f); });
    auto g = test::scene_from(camera_and_plane(
        "AttributeBegin Translate 0 0 5 LightSource \"goniometric\" \"rgb I\" [2 2 2] "
        "\"string mapname\" \"" +
        gmap + "\" AttributeEnd"));
    const Light& gl = g->lights[0];
    ASSERT_TRUE(gl.image);
    EXPECT_EQ(gl.position.z, 5);
    // theta = pi/4 from +y reads between rows 1 and 2, 3 pi/4 between rows 5 and 6.
    EXPECT_NEAR(gl.image->scale(normalize(Vec3(1, 1, 0))).r, 1, 1e-6f);
    EXPECT_NEAR(gl.image->scale(normalize(Vec3(0, -1, 1))).r, 0, 1e-6f);
    // Projection: the image on the screen of a pinhole along +z, x in [-aspect, aspect].
    const std::string pmap = write_map(
        "proj.exr", 2, 1, [](int i, int) { return i == 0 ? Rgb(1, 0, 0) : Rgb(0, 0, 1); });
    auto p = test::scene_from(camera_and_plane(
        "LightSource \"projection\" \"float fov\" 90 \"string mapname\" \"" + pmap + "\""));
    const LightImage& pi = *p->lights[0].image;
    EXPECT_NEAR(pi.scale(normalize(Vec3(-1, 0, 1))).r, 1, 1e-6f);   // left texel's centre: red
    EXPECT_NEAR(pi.scale(normalize(Vec3(1, 0, 1))).b, 1, 1e-6f);    // right one's: blue
    EXPECT_TRUE(pi.scale(Vec3(0, 0, -1)).is_black());               // behind
    EXPECT_TRUE(pi.scale(normalize(Vec3(3, 0, 1))).is_black());     // beside the screen
    EXPECT_TRUE(pi.scale(normalize(Vec3(0, 1.5f, 1))).is_black());  // above it
}

// Under pbrt-v3's directlighting integrator (strategy "all"), an area light takes its nsamples
// shadow rays per shading point, averaged: the same mean, a quarter of the noise at 16; under
// whitted (or strategy "one") nsamples is not read, as in pbrt-v3.
TEST(AreaLight, NsamplesUnderDirectLightingAveragesThatManyShadowRays) {
    auto scene = [](const std::string& integrator) {
        const std::string light =
            "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [5 5 5] \"integer nsamples\" 16 "
            "Shape \"trianglemesh\" \"point3 P\" [-2 -2 1  -2 2 1  2 2 1  2 -2 1] "
            "\"integer indices\" [0 1 2 0 2 3] AttributeEnd";
        std::string text = camera_and_plane(light);
        text.insert(text.find("WorldBegin"), integrator + " ");
        return test::scene_from(text, "t.pbrt", 1);
    };
    const auto direct = scene("Integrator \"directlighting\""),
               whitted = scene("Integrator \"whitted\""),
               one = scene("Integrator \"directlighting\" \"string strategy\" \"one\"");
    EXPECT_EQ(direct->lights[0].samples, 16);
    EXPECT_EQ(whitted->lights[0].samples, 1);
    EXPECT_EQ(one->lights[0].samples, 1);
    // pbrt-v3's area and infinite lights read "samples" first, then "nsamples".
    for (const char* light : {"AreaLightSource \"diffuse\"", "LightSource \"infinite\""}) {
        SCOPED_TRACE(light);
        auto samples = [&](const std::string& params) {
            std::string text = camera_and_plane(
                "AttributeBegin " + std::string(light) + " " + params +
                " Shape \"trianglemesh\" \"point3 P\" [-2 -2 1  -2 2 1  2 2 1  2 -2 1] "
                "\"integer indices\" [0 1 2 0 2 3] AttributeEnd");
            text.insert(text.find("WorldBegin"), "Integrator \"directlighting\" ");
            return test::scene_from(text, "t.pbrt", 1)->lights.at(0).samples;
        };
        EXPECT_EQ(samples("\"integer samples\" 4"), 4);
        EXPECT_EQ(samples("\"integer samples\" 4 \"integer nsamples\" 8"), 4);
        EXPECT_EQ(samples("\"integer nsamples\" 8"), 8);
        EXPECT_EQ(samples(""), 1);
        // Under the other integrators pbrt-v3 reads it too and takes one sample: no warning.
        std::vector<std::string> warnings;
        std::string text = camera_and_plane(
            "AttributeBegin " + std::string(light) +
            " \"integer nsamples\" 8 Shape \"trianglemesh\" \"point3 P\" [-2 -2 1  -2 2 1  2 2 1  "
            "2 -2 1] \"integer indices\" [0 1 2 0 2 3] AttributeEnd");
        text.insert(text.find("WorldBegin"), "Integrator \"path\" ");
        auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), {},
                             [&](const std::string& w) { warnings.push_back(w); });
        EXPECT_EQ(s->lights.at(0).samples, 1);
        for (const std::string& w : warnings) EXPECT_EQ(w.find("nsamples"), std::string::npos) << w;
    }
    const auto [m16, s16] = radiance_stats(*direct);
    const auto [m1, s1] = radiance_stats(*whitted);
    EXPECT_NEAR(m16, m1, 4 * s1 / std::sqrt(4000.0));
    EXPECT_GT(s1, 0);
    EXPECT_NEAR(s16 / s1, 0.25, 0.05);
}

// A piecewise-constant distribution's sample finds its cell from a guide table and a short walk:
// the cell must be the one a binary search over the CDF finds (the last cell whose CDF start is
// at or below u), for every u at, just below and just above each CDF value, and on a fine grid,
// on distributions with zero-weight cells, one dominant cell, and sizes that do not divide the
// guide's stride. The CDF is restated here as the constructor's documented sums.
TEST(EnvironmentMap, DistributionSamplingFindsTheBinarySearchesCell) {
    auto check = [](const std::vector<float>& w) {
        const Distribution1D d(w);
        const std::size_t n = w.size();
        std::vector<double> sums(n + 1, 0.0);
        for (std::size_t i = 0; i < n; ++i)
            sums[i + 1] = sums[i] + double(std::max(0.0f, w[i])) / double(n);
        std::vector<float> cdf(n + 1);
        for (std::size_t i = 0; i <= n; ++i)
            cdf[i] = float(sums[n] > 0 ? sums[i] / sums[n] : double(i) / double(n));
        cdf[n] = 1;
        auto expected = [&](float u) {
            const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
            return std::clamp(static_cast<int>(it - cdf.begin()) - 1, 0, static_cast<int>(n) - 1);
        };
        std::vector<float> us;
        for (float c : cdf)
            for (float u : {c, std::nextafter(c, 0.0f), std::nextafter(c, 1.0f)})
                if (u >= 0 && u < 1) us.push_back(u);
        for (int i = 0; i < 4096; ++i) us.push_back((i + 0.37f) / 4096);
        us.push_back(0x1.fffffep-1f);
        int wrong = 0;
        for (float u : us) wrong += d.sample(u).cell != expected(u);
        EXPECT_EQ(wrong, 0) << "n = " << n;
    };
    check({1});
    check({0, 3});
    check({2, 0, 0, 5, 1});
    std::vector<float> peaked(1000, 0.01f);
    peaked[613] = 5000;
    for (int i = 100; i < 180; ++i) peaked[static_cast<std::size_t>(i)] = 0;
    check(peaked);
    std::vector<float> ramp(1023);
    for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = float(i % 17) * float(i % 5);
    check(ramp);
    check(std::vector<float>(7, 0));  // no weight: uniform
}
