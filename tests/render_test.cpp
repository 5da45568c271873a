// Whole renders: a Lambertian plane under point and distant lights against closed-form pixel
// values; identical images for 1 and 2 threads; the bundled scenes build and render.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>

#include "expect_throw.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/footprint/cmam_caches.h"
#include "render/integrator.h"
#include "render/tracer.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {
// A 40x40 plane z = 0 (normal +z), seen from (0,0,10) looking down -z with a 90 degree fov.
const char* kPlane =
    "LookAt 0 0 10  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 90 "
    "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32 WorldBegin %LIGHTS% "
    "Material \"matte\" \"rgb Kd\" [0.5 0.25 0.8] "
    "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0] "
    "\"integer indices\" [0 1 2 0 2 3] WorldEnd";

std::string plane_with(const std::string& lights) {
    std::string s = kPlane;
    s.replace(s.find("%LIGHTS%"), 8, lights);
    return s;
}
}  // namespace

TEST(Analytic, LambertianPlaneUnderAPointLight) {
    auto s = test::scene_from(
        plane_with("LightSource \"point\" \"point from\" [1 2 3] \"rgb I\" [10 10 10]"), "t.pbrt",
        1);
    RenderOptions o;
    RenderStats st;
    Framebuffer fb = render::render(*s, o, &st);
    ASSERT_EQ(fb.width, 32);
    double worst = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            const CameraRay ray = s->camera.generate_ray(x + 0.5f, y + 0.5f);
            const Vec3 &org = ray.org, &dir = ray.dir;
            Vec3 p = org + dir * (-org.z / dir.z);
            Vec3 d = Vec3(1, 2, 3) - p;
            float d2 = dot(d, d);
            float cosl = d.z / std::sqrt(d2);
            double expected_r = 0.5 / 3.14159265358979 * 10 * cosl / d2;
            double expected_b = 0.8 / 3.14159265358979 * 10 * cosl / d2;
            const float* px = &fb.rgb[(y * 32 + x) * 3];
            worst = std::max({worst, std::abs(px[0] - expected_r) / expected_r,
                              std::abs(px[2] - expected_b) / expected_b});
        }
    EXPECT_LT(worst, 1e-4);
    EXPECT_EQ(st.camera_rays, 32u * 32u);
    EXPECT_EQ(st.shadow_rays, 32u * 32u);
}

TEST(Analytic, LambertianPlaneUnderADistantLightAndUniformSky) {
    // Distant light at 60 degrees from the normal: E = L cos 60. Sky L_sky over the upper
    // hemisphere adds pi * L_sky irradiance (sampled stochastically: compare the image mean).
    auto s = test::scene_from(
        plane_with(
            "LightSource \"distant\" \"point from\" [0 0 0] \"point to\" [0 -0.8660254 -0.5] "
            "\"rgb L\" [3 3 3]"),
        "t.pbrt", 1);
    Framebuffer fb = render::render(*s, {}, nullptr);
    for (std::size_t i = 0; i < fb.rgb.size(); i += 3)
        EXPECT_NEAR(fb.rgb[i], 0.5 / 3.14159265 * 3 * 0.5, 1e-6);

    auto sky = test::scene_from(plane_with("LightSource \"infinite\" \"rgb L\" [0.7 0.7 0.7]"),
                                "t.pbrt", 16);
    Framebuffer fs = render::render(*sky, {}, nullptr);
    double mean = 0;
    for (std::size_t i = 0; i < fs.rgb.size(); i += 3) mean += fs.rgb[i];
    mean /= fs.rgb.size() / 3;
    EXPECT_NEAR(mean, 0.5 * 0.7, 0.004);  // Kd/pi * pi * L
}

TEST(Analytic, UberOpacityPassesTheRestThrough) {
    // An uber of opacity 0.25 (red) to 1 (blue) and no Kd or Ks, in front of a uniform sky of
    // radiance 1, under whitted and path: the sky seen through it, times 1 - opacity.
    for (const char* integrator : {"whitted", "path"}) {
        auto s = test::scene_from(std::string("Integrator \"") + integrator + R"("
LookAt 0 0 -2  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-0.5 0.5 -0.5 0.5]
Film "image" "integer xresolution" 4 "integer yresolution" 4
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "uber" "rgb Kd" [0 0 0] "rgb Ks" [0 0 0] "rgb opacity" [0.25 0.5 1]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 -1 0 1 -1 0 1 1 0 -1 1 0]
WorldEnd
)",
                                  "t.pbrt", 4);
        const Framebuffer fb = render::render(*s, {}, nullptr);
        for (std::size_t i = 0; i < fb.rgb.size(); i += 3) {
            EXPECT_NEAR(fb.rgb[i], 0.75f, 1e-5) << integrator;
            EXPECT_NEAR(fb.rgb[i + 1], 0.5f, 1e-5) << integrator;
            EXPECT_NEAR(fb.rgb[i + 2], 0.0f, 1e-5) << integrator;
        }
    }
}

TEST(Analytic, SpotLightFalloff) {
    // Spot straight down from (0,0,5): full inside conedelta, zero outside coneangle.
    auto s = test::scene_from(
        plane_with("LightSource \"spot\" \"point from\" [0 0 5] \"point to\" [0 0 0] "
                   "\"float coneangle\" 30 \"float conedelta\" 10 \"rgb I\" [25 25 25]"),
        "t.pbrt", 1);
    Rgb centre = trace_radiance(*s, Vec3(0, 0, 10), Vec3(0, 0, -1), 1, nullptr);
    EXPECT_NEAR(centre.r, 0.5 / 3.14159265 * 25 / 25, 1e-6);
    Rgb outside = trace_radiance(*s, Vec3(4, 0, 10), Vec3(0, 0, -1), 1, nullptr);  // 38.7 degrees
    EXPECT_EQ(outside.r, 0);
    // At 25 degrees (inside the falloff band 20..30): pbrt-v3's smooth step delta^4.
    float x = 5 * std::tan(25 * 3.14159265f / 180);
    Rgb mid = trace_radiance(*s, Vec3(x, 0, 10), Vec3(0, 0, -1), 1, nullptr);
    float c = std::cos(25 * 3.14159265f / 180);
    float delta = (c - std::cos(30 * 3.14159265f / 180)) /
                  (std::cos(20 * 3.14159265f / 180) - std::cos(30 * 3.14159265f / 180));
    float d2 = 25 + x * x;
    EXPECT_NEAR(mid.r, 0.5 / 3.14159265 * 25 * std::pow(delta, 4) * c / d2, 1e-6);
}

TEST(Scenes, PbrtV3LightAndSamplerParametersAreReadOrWarned) {
    // pbrt-v3 names the spot light's falloff "conedeltaangle" (cmam's earlier "conedelta" is
    // still read, with a warning that pbrt-v3 would not); "nsamples" on lights and "pixelsamples"
    // on the stratified sampler are pbrt-v3 parameters cmam has no use for: warnings, not errors.
    const std::string body =
        "LightSource \"spot\" \"point from\" [0 0 5] \"point to\" [0 0 0] "
        "\"float coneangle\" 30 \"float DELTA\" 10 \"rgb I\" [25 25 25] \"integer nsamples\" 4\n";
    for (const char* name : {"conedeltaangle", "conedelta"}) {
        std::string light = body;
        light.replace(light.find("DELTA"), 5, name);
        std::vector<std::string> warnings;
        const std::string text =
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
            "Sampler \"stratified\" \"integer pixelsamples\" 16\nWorldBegin\n" +
            light + "WorldEnd\n";
        auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), {},
                             [&](const std::string& w) { warnings.push_back(w); });
        ASSERT_EQ(s->lights.size(), 1u) << name;
        EXPECT_NEAR(s->lights[0].cos_falloff_start, std::cos(20 * 3.14159265 / 180), 1e-6) << name;
        const bool old_name = std::string(name) == "conedelta";
        ASSERT_EQ(warnings.size(), old_name ? 3u : 2u) << name;
        if (old_name) {
            EXPECT_EQ(warnings[1],
                      "t.pbrt:5:81: warning: light \"spot\": \"conedelta\" is read as the falloff "
                      "(cmam's earlier name for \"conedeltaangle\"); pbrt-v3 does not know it and "
                      "would take the default, 5 degrees");
        }
        EXPECT_EQ(warnings[0],
                  "t.pbrt:3:22: warning: parameter \"pixelsamples\" of Sampler \"stratified\" "
                  "is not supported by cmam; ignored");
        EXPECT_NE(warnings.back().find("parameter \"nsamples\" of light \"spot\" is not supported"),
                  std::string::npos)
            << warnings.back();
    }
}

// The samplers cmam renders as stratified take pbrt-v3's sample counts: "random" 4 per pixel by
// default (the others 16), and Sobol, (0,2)-sequence and maxmindist round a count up to a power
// of two, with a warning, as pbrt-v3 does; the k x k grid is then the nearest square.
TEST(Scenes, SamplerCountsArePbrtV3s) {
    auto grid = [](const std::string& sampler, std::vector<std::string>* warnings = nullptr) {
        auto s = build_scene(
            pbrt::parse_string("Camera \"perspective\"\n" + sampler + "\nWorldBegin\nWorldEnd\n",
                               "t.pbrt"),
            {}, [&](const std::string& w) {
                if (warnings) warnings->push_back(w);
            });
        EXPECT_EQ(s->sampler.xsamples, s->sampler.ysamples);
        return s->sampler.xsamples;
    };
    EXPECT_EQ(grid("Sampler \"random\""), 2);
    EXPECT_EQ(grid("Sampler \"halton\""), 4);
    EXPECT_EQ(grid("Sampler \"sobol\""), 4);
    EXPECT_EQ(grid("Sampler \"halton\" \"integer pixelsamples\" 24"), 5);  // 24: 5x5
    std::vector<std::string> warnings;
    EXPECT_EQ(grid("Sampler \"sobol\" \"integer pixelsamples\" 24", &warnings), 6);  // 32: 6x6
    EXPECT_EQ(std::count(warnings.begin(), warnings.end(),
                         "t.pbrt:2:17: warning: pixelsamples 24 rounded up to a power of two, 32, "
                         "as pbrt-v3's \"sobol\" sampler does"),
              1);
    EXPECT_EQ(grid("Sampler \"02sequence\" \"integer pixelsamples\" 9"), 4);  // 16: 4x4
    EXPECT_EQ(grid("Sampler \"maxmindist\" \"integer pixelsamples\" 16"), 4);
}

TEST(Analytic, FilmScaleMultipliesRadianceNotAovs) {
    // pbrt-v3's Film "scale": the same scene at scale 2.5 is 2.5 times as bright; the texture
    // AOV is unscaled.
    auto with_scale = [](const char* film, AovKind aov) {
        const std::string text =
            std::string("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n") +
            "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8" + film +
            "\nWorldBegin\nLightSource \"distant\" \"rgb L\" [1 1 1] " +
            "\"point from\" [0 0 5] \"point to\" [0 0 0]\n" +
            "Material \"matte\" \"rgb Kd\" [0.5 0.25 0.125]\n" +
            "Shape \"sphere\" \"float radius\" 3\nWorldEnd\n";
        auto s = test::scene_from(text, "t.pbrt", 1);
        RenderOptions o;
        o.aov = aov;
        return render::render(*s, o, nullptr).rgb;
    };
    const auto one = with_scale("", AovKind::None),
               two = with_scale(" \"float scale\" 2.5", AovKind::None);
    double sum = 0;
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_FLOAT_EQ(two[i], 2.5f * one[i]);
        sum += one[i];
    }
    EXPECT_GT(sum, 0);
    EXPECT_EQ(with_scale("", AovKind::Texture),
              with_scale(" \"float scale\" 2.5", AovKind::Texture));
}

// pbrt-v3's Film "maxsampleluminance": a sample whose luminance (y of its RGB) is above it is
// scaled down to it, before the film's scale; samples below it are untouched.
TEST(Analytic, FilmMaxSampleLuminanceScalesBrightSamplesDown) {
    auto render_with = [](const std::string& film) {
        const std::string text =
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
            "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8" +
            film +
            "\nIntegrator \"whitted\"\nWorldBegin\n"
            "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [40 20 10]\n"
            "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
            "\"point3 P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] AttributeEnd\nWorldEnd\n";
        return render::render(*test::scene_from(text, "t.pbrt", 1), {}, nullptr).rgb;
    };
    const auto plain = render_with(""), limited = render_with(" \"float maxsampleluminance\" 10"),
               scaled = render_with(" \"float maxsampleluminance\" 10 \"float scale\" 2"),
               above = render_with(" \"float maxsampleluminance\" 30");
    const double y = 0.212671 * 40 + 0.715160 * 20 + 0.072169 * 10;  // 23.53
    ASSERT_EQ(plain.size(), 8u * 8 * 3);
    for (std::size_t p = 0; p < plain.size(); p += 3) {
        EXPECT_FLOAT_EQ(plain[p], 40);
        EXPECT_NEAR(limited[p], 40 * 10 / y, 1e-4);
        EXPECT_NEAR(limited[p + 1], 20 * 10 / y, 1e-4);
        EXPECT_NEAR(limited[p + 2], 10 * 10 / y, 1e-4);
        EXPECT_FLOAT_EQ(scaled[p + 1], 2 * limited[p + 1]);
        EXPECT_EQ(above[p], plain[p]);
    }
    EXPECT_THROW_CONTAINS(render_with(" \"float maxsampleluminance\" -1"), pbrt::SceneError,
                          "t.pbrt:3:62: error: maxsampleluminance must be a positive");
}

// The texture AOV is the Kd of the first non-specular hit: through smooth glass, the surface
// behind it; at rough glass (no specular chain to follow), the glass itself, which has none.
TEST(Analytic, TextureAovStopsAtRoughGlass) {
    auto aov_of = [](const std::string& glass, const std::string& integrator) {
        const std::string text =
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 10\n"
            "Film \"image\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
            "Integrator \"" +
            integrator +
            "\"\nWorldBegin\nLightSource \"distant\" \"rgb L\" [1 1 1]\n"
            "AttributeBegin Material \"matte\" \"rgb Kd\" [0.5 0.25 0.125]\n"
            "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
            "\"point3 P\" [-9 -9 -2  9 -9 -2  9 9 -2  -9 9 -2] AttributeEnd\n"
            "Material \"glass\" " +
            glass + "\nShape \"sphere\" \"float radius\" 2\nWorldEnd\n";
        RenderOptions o;
        o.aov = AovKind::Texture;
        return render::render(*test::scene_from(text, "t.pbrt", 1), o, nullptr).rgb;
    };
    // (Path tracing goes on past the rough glass's hit: the plane behind it would be next.)
    const auto smooth = aov_of("", "whitted"),
               rough = aov_of("\"float uroughness\" 0.2 \"float vroughness\" 0.2", "path");
    ASSERT_EQ(smooth.size(), 4u * 4 * 3);
    for (std::size_t p = 0; p < smooth.size(); p += 3) {
        EXPECT_FLOAT_EQ(smooth[p + 1], 0.25f);  // the plane's Kd, seen through the glass
        EXPECT_FLOAT_EQ(rough[p + 1], 0);       // the rough glass's own (none)
    }
}

TEST(Analytic, ShadowsBlockDirectLight) {
    auto s = test::scene_from(
        plane_with(
            "LightSource \"point\" \"point from\" [0 0 5] \"rgb I\" [10 10 10] "
            "AttributeBegin Translate 0 0 2.5 Shape \"sphere\" \"float radius\" 0.5 AttributeEnd"),
        "t.pbrt", 1);
    Rgb under = trace_radiance(*s, Vec3(0.1f, 0.1f, -1), Vec3(0, 0, 1), 1,
                               nullptr);  // from below: back side
    EXPECT_EQ(under.r, 0);
    Rgb shadowed = trace_radiance(*s, Vec3(0.6f, 0, 10), Vec3(0, 0, -1), 1, nullptr);
    EXPECT_NEAR(shadowed.r, 0.0, 1e-7) << "point (0.6,0,0) is in the sphere's shadow";
    Rgb lit = trace_radiance(*s, Vec3(3, 0, 10), Vec3(0, 0, -1), 1, nullptr);
    EXPECT_GT(lit.r, 0.0f);
}

TEST(Determinism, OneAndTwoThreadsGiveIdenticalImages) {
    std::string scenes = CMAM_SCENES_DIR;
    pbrt::SceneDesc d = pbrt::parse_file(scenes + "/demo.pbrt");
    BuildOptions bo;
    bo.spp_override = 4;
    auto s = build_scene(d, bo, {});
    s->film.x0 = 200;
    s->film.x1 = 360;
    s->film.y0 = 150;
    s->film.y1 = 270;  // a crop keeps the test quick
    RenderOptions one, two;
    one.threads = 1;
    two.threads = 2;
    Framebuffer a = render::render(*s, one, nullptr), b = render::render(*s, two, nullptr);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
    double sum = 0;
    for (float v : a.rgb) sum += v;
    EXPECT_GT(sum / a.rgb.size(), 0.05);  // not black
}

TEST(Determinism, AreaTablesBuiltOnDemandGiveIdenticalImages) {
    // The area filter's row prefix tables are built a band at a time by whichever worker first
    // reads it (the demo's 512x512 textures): one and two threads, each on a scene of its own
    // whose tables start empty, give the same image.
    std::string scenes = CMAM_SCENES_DIR;
    pbrt::SceneDesc d = pbrt::parse_file(scenes + "/demo.pbrt");
    BuildOptions bo;
    bo.spp_override = 4;
    bo.filter = texture::FilterKind::Area;
    Framebuffer fb[2];
    for (int threads : {1, 2}) {
        auto s = build_scene(d, bo, {});
        s->film.x0 = 120;
        s->film.x1 = 440;
        s->film.y0 = 170;
        s->film.y1 = 300;  // the floor and the astronaut
        RenderOptions ro;
        ro.threads = threads;
        fb[threads - 1] = render::render(*s, ro, nullptr);
        std::size_t built = 0;
        for (const auto& [key, tex] : s->images) built += tex->row_prefix_bytes();
        EXPECT_GT(built, 0u);
    }
    ASSERT_EQ(fb[0].rgb.size(), fb[1].rgb.size());
    EXPECT_EQ(0, std::memcmp(fb[0].rgb.data(), fb[1].rgb.data(), fb[0].rgb.size() * sizeof(float)));
}

TEST(Determinism, AGeneratorsKthNumberIsTheOneItDrawsKth) {
    // The film computes sample k's jitter as the pixel generator's numbers 2k and 2k + 1
    // (Rng::float_at) rather than drawing the pixel's numbers in sequence: the two must agree
    // for every k, or a jittered image would not be the one the sequence gives.
    for (uint64_t seed : {uint64_t(0), uint64_t(1), mix_seed(123, 0x5eed), ~uint64_t(0)}) {
        Rng rng(seed);
        for (uint64_t k = 0; k < 2 * 64 * 4; ++k) {
            const float drawn = rng.next_float();
            ASSERT_EQ(drawn, Rng::float_at(seed, k)) << "seed " << seed << " k " << k;
            ASSERT_GE(drawn, 0.0f);
            ASSERT_LT(drawn, 1.0f);
        }
    }
}

TEST(Scenes, EveryBundledSceneBuilds) {
    int n = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(CMAM_SCENES_DIR)) {
        if (e.path().extension() != ".pbrt") continue;
        SCOPED_TRACE(e.path().string());
        std::vector<std::string> warnings;
        pbrt::SceneDesc d = pbrt::parse_file(e.path().string(),
                                             [&](const std::string& w) { warnings.push_back(w); });
        auto s = build_scene(d, {}, [&](const std::string& w) { warnings.push_back(w); });
        EXPECT_FALSE(s->primitives.empty());
        EXPECT_TRUE(warnings.empty()) << warnings.front();
        ++n;
    }
    EXPECT_GE(n, 3);
}

namespace {
// A scene rendered with the given samples per pixel, footprint source, filter (none: the
// scene's) and 1-D or 2-D CMAM, its film cut to rows [y0, y1) when y1 > 0.
std::vector<float> render_desc(const pbrt::SceneDesc& d, int spp, FootprintMethod lod,
                               std::optional<texture::FilterKind> filter, bool two_d, int y0 = 0,
                               int y1 = 0) {
    BuildOptions bo;
    bo.spp_override = spp;
    bo.lod = lod;
    bo.filter = filter;
    bo.cmam.two_d = two_d;
    auto s = build_scene(d, bo, {});
    if (y1 > 0) {
        s->film.y0 = y0;
        s->film.y1 = y1;
    }
    return render::render(*s, {}, nullptr).rgb;
}
// Rows 100..180 of the paper's scene 1 (the floor from just below the horizon), rendered with
// the given footprint source, filter and samples per pixel.
std::vector<float> scene1_floor(int spp, FootprintMethod lod, texture::FilterKind filter,
                                bool two_d = false) {
    static const pbrt::SceneDesc d =
        pbrt::parse_file(std::string(CMAM_SCENES_DIR) + "/paper/scene1.pbrt");
    return render_desc(d, spp, lod, filter, two_d, 100, 180);
}
double rmse(const std::vector<float>& a, const std::vector<float>& b) {
    double se = 0;
    for (std::size_t i = 0; i < a.size(); ++i) se += (a[i] - b[i]) * double(a[i] - b[i]);
    return std::sqrt(se / a.size());
}
}  // namespace

TEST(Cmam, IdenticalImagesForOneAndTwoThreadsWithEitherTagPolicy) {
    std::string scenes = CMAM_SCENES_DIR;
    pbrt::SceneDesc d = pbrt::parse_file(scenes + "/demo.pbrt");
    for (TagPolicy tags : {TagPolicy::Scanline, TagPolicy::Pixel})
        for (auto filter :
             {texture::FilterKind::Trilinear, texture::FilterKind::Sat, texture::FilterKind::Ewa}) {
            BuildOptions bo;
            bo.spp_override = tags == TagPolicy::Pixel ? 4 : 1;
            bo.lod = FootprintMethod::Cmam;
            bo.filter = filter;
            bo.tags = tags;
            auto s = build_scene(d, bo, {});
            s->film.x0 = 100;
            s->film.x1 = 540;
            s->film.y0 = 200;
            s->film.y1 = 260;
            RenderOptions one, two;
            one.threads = 1;
            two.threads = 2;
            Framebuffer a = render::render(*s, one, nullptr), b = render::render(*s, two, nullptr);
            EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)))
                << to_string(tags) << " " << texture::to_string(filter);
        }
}

TEST(Cmam, ReducesTheErrorOfARecedingTexturedPlane) {
    // The paper's scene 1 at low resolution: CMAM-filtered 1-spp renders are closer to a
    // supersampled point-sampled reference than the 1-spp point-sampled render.
    using texture::FilterKind;
    auto ref = scene1_floor(64, FootprintMethod::None, FilterKind::Bilinear);
    double off = rmse(ref, scene1_floor(1, FootprintMethod::None, FilterKind::Bilinear));
    double tri = rmse(ref, scene1_floor(1, FootprintMethod::Cmam, FilterKind::Trilinear));
    double ewa = rmse(ref, scene1_floor(1, FootprintMethod::Cmam, FilterKind::Ewa));
    EXPECT_LT(tri, 0.75 * off) << tri << " vs " << off;
    EXPECT_LT(ewa, 0.75 * off) << ewa << " vs " << off;
}

TEST(Cmam, TwoDimensionalCmamFixesTheCollinearSatBoxes) {
    // At 1 spp with scanline tags the paper's cached samples lie along the row, so the SAT box
    // is one texel tall; the 2-D CMAM adds the pixel above and filters vertically too.
    using texture::FilterKind;
    auto ref = scene1_floor(64, FootprintMethod::None, FilterKind::Bilinear);
    double one_d = rmse(ref, scene1_floor(1, FootprintMethod::Cmam, FilterKind::Sat));
    double two_d = rmse(ref, scene1_floor(1, FootprintMethod::Cmam, FilterKind::Sat, true));
    EXPECT_LT(two_d, 0.8 * one_d) << two_d << " vs " << one_d;
}

TEST(Cmam, ScanlineTagsFollowSampleRowsSoErrorFallsWithSamples) {
    // With several samples per pixel, a scanline is a row of sample strata: the 2-D CMAM's
    // vectors are then one stratum long and its footprint shrinks with the sample spacing, as
    // ray differentials scaled by 1/sqrt(spp) do. (Tagging whole pixel rows made the vector to
    // the sample above a full pixel long at any spp, and the error stayed where 1 spp left it.)
    using texture::FilterKind;
    auto ref = scene1_floor(64, FootprintMethod::None, FilterKind::Bilinear);
    for (auto f : {FilterKind::Trilinear, FilterKind::Ewa}) {
        double one = rmse(ref, scene1_floor(1, FootprintMethod::Cmam, f, true));
        double sixteen = rmse(ref, scene1_floor(16, FootprintMethod::Cmam, f, true));
        // (Measured 0.70 and 0.74 of the 1-spp error, since every row has its row above at 1
        // spp too; whole-pixel-row tags gave about 1.)
        EXPECT_LT(sixteen, 0.8 * one) << texture::to_string(f) << ": " << sixteen << " vs " << one;
    }
}

TEST(Area, ConesIntegrateTheirStrataAtSeveralSamples) {
    // At 4 jittered samples a pixel the area filter's parallelogram is a stratum's; with ray
    // cones it is centred on the stratum's centre through the camera ray's differential at the
    // first hit, so the strata tile the pixel as with differentials. Centred on the samples
    // instead (cones carry no screen Jacobian) they overlap and leave gaps. Measured: 0.0040
    // against cones-aniso+ewa's 0.0084 and differentials+area's 0.0031; centred on the samples
    // 0.0098.
    // The reference: 64 strata a pixel, each integrated over its own parallelogram, i.e. the
    // box-filtered pixel (a point-sampled one at 64 spp is too noisy to tell these apart).
    using texture::FilterKind;
    auto ref = scene1_floor(64, FootprintMethod::Differentials, FilterKind::Area);
    const double ewa = rmse(ref, scene1_floor(4, FootprintMethod::ConesAniso, FilterKind::Ewa));
    const double area = rmse(ref, scene1_floor(4, FootprintMethod::ConesAniso, FilterKind::Area));
    const double diff =
        rmse(ref, scene1_floor(4, FootprintMethod::Differentials, FilterKind::Area));
    EXPECT_LT(area, 0.6 * ewa) << area << " vs " << ewa << " (differentials: " << diff << ")";
    EXPECT_LT(area, 1.5 * diff) << area << " vs " << diff;
}

namespace {
// A closed-form checkerboard (60 x 60 cells) on a floor receding from the camera, lit from above.
pbrt::SceneDesc receding_checkerboard() {
    const std::string text =
        "LookAt 0 1 -3  0 0.2 6  0 1 0 Camera \"perspective\" \"float fov\" 40 "
        "Film \"image\" \"integer xresolution\" 96 \"integer yresolution\" 64 "
        "WorldBegin LightSource \"distant\" \"point from\" [0 1 0] \"point to\" [0 0 0] "
        "Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 60 \"float vscale\" 60 "
        "\"rgb tex1\" [1 1 1] \"rgb tex2\" [0 0 0] Material \"matte\" \"texture Kd\" \"c\" "
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
        "\"point3 P\" [-20 0 -5  20 0 -5  20 0 35  -20 0 35] \"point2 uv\" [0 0 1 0 1 1 0 1] "
        "WorldEnd";
    return pbrt::parse_string(text, "checks.pbrt");
}
}  // namespace

TEST(Cmam, FiltersClosedFormCheckerboardsToo) {
    // A receding closed-form checkerboard: with --lod cmam it was point-sampled (the CMAM's
    // caches filled only for image textures); now its own cache gives the closed form a region.
    // Measured against 64 point samples a pixel, at 1 spp: 2-D CMAM 0.037, 1-D 0.038, point
    // sampling 0.066 (as the CMAM was), ray differentials 0.035.
    const pbrt::SceneDesc d = receding_checkerboard();
    auto render_with = [&](int spp, FootprintMethod lod, bool two_d) {
        return render_desc(d, spp, lod, std::nullopt, two_d);
    };
    const auto ref = render_with(64, FootprintMethod::None, false);
    const double none = rmse(ref, render_with(1, FootprintMethod::None, false));
    const double one_d = rmse(ref, render_with(1, FootprintMethod::Cmam, false));
    const double two_d = rmse(ref, render_with(1, FootprintMethod::Cmam, true));
    EXPECT_LT(two_d, 0.7 * none) << two_d << " vs " << none;
    EXPECT_LT(one_d, 0.7 * none) << one_d << " vs " << none;
}

TEST(Area, ClosedFormCheckerboardsTakeTheExactParallelogram) {
    // --filter area integrates a closed-form checkerboard over each sample's own parallelogram
    // (algorithms.md §5.4) instead of pbrt-v3's box, twice as wide as the pixel: against 256
    // point samples a pixel, at 1 and 4 spp, ray differentials and the 2-D CMAM. Measured, RMSE
    // at 1 spp: the box 0.0348, exact 0.0104, the 2-D CMAM 0.0124; at 4 spp 0.0189, 0.0025 and
    // 0.0042.
    const pbrt::SceneDesc d = receding_checkerboard();
    const auto ref = render_desc(d, 256, FootprintMethod::None, std::nullopt, false);
    for (int spp : {1, 4}) {
        const double box = rmse(ref, render_desc(d, spp, FootprintMethod::Differentials,
                                                 texture::FilterKind::Ewa, false)),
                     exact = rmse(ref, render_desc(d, spp, FootprintMethod::Differentials,
                                                   texture::FilterKind::Area, false)),
                     cmam2d = rmse(ref, render_desc(d, spp, FootprintMethod::Cmam,
                                                    texture::FilterKind::Area, true));
        EXPECT_LT(exact, 0.5 * box) << spp << ": " << exact << " vs " << box;
        EXPECT_LT(cmam2d, 0.7 * box) << spp << ": " << cmam2d << " vs " << box;
    }
}

TEST(Scenes, MaxAnisotropyAboveTheLimitIsClampedWithALocatedWarning) {
    const std::string text =
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
        "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"textures/bricks.png\"\n"
        "  \"float maxanisotropy\" 1000\n"
        "Material \"matte\" \"texture Kd\" \"t\"\nShape \"sphere\"\nWorldEnd\n";
    const std::string file = std::string(CMAM_SCENES_DIR) + "/aniso.pbrt";
    std::vector<std::string> warnings;
    auto s = build_scene(pbrt::parse_string(text, file), {},
                         [&](const std::string& w) { warnings.push_back(w); });
    std::erase_if(warnings, [](const std::string& w) {  // keep this test's warning only
        return w.find("maxanisotropy") == std::string::npos;
    });
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], file +
                               ":5:3: warning: maxanisotropy 1000 is above cmam's limit of 256, "
                               "which is used instead");
}

TEST(Scenes, NonFiniteTextureCoordinatesGiveTheMeanAndAreCounted) {
    // uscale inf makes every s infinite: each lookup (differentials with EWA, and the CMAM) must
    // return the texture's mean, never NaN, and --stats must count them. With a finite uscale
    // none is counted.
    auto plane = [](const char* uscale, const char* lod) {
        return std::string(
                   "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\n"
                   "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
                   "WorldBegin\nLightSource \"distant\" \"point from\" [0 0 5] \"point to\" [0 0 "
                   "0]\n"
                   "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" "
                   "\"textures/bricks.png\" \"float uscale\" ") +
               uscale + " \"string lod\" \"" + lod +
               "\"\nMaterial \"matte\" \"texture Kd\" \"t\"\n"
               "Shape \"trianglemesh\" \"point3 P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0] "
               "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\nWorldEnd\n";
    };
    const std::string file = std::string(CMAM_SCENES_DIR) + "/nonfinite.pbrt";
    for (const char* lod : {"differentials", "cmam"}) {
        for (const char* uscale : {"inf", "4"}) {
            render::BuildOptions bo;
            bo.spp_override = 1;
            auto s = build_scene(pbrt::parse_string(plane(uscale, lod), file), bo, {});
            RenderStats st;
            Framebuffer fb = render::render(*s, {}, &st);
            uint64_t lookups = st.lookups_point_sampled;
            for (auto& n : st.lookups_by_filter) lookups += n;
            EXPECT_EQ(lookups, 16u * 16u) << lod << " " << uscale;
            EXPECT_EQ(st.lookups_non_finite, std::string(uscale) == "inf" ? lookups : 0u)
                << lod << " " << uscale;
            for (float v : fb.rgb) ASSERT_TRUE(std::isfinite(v)) << lod << " " << uscale;
        }
    }
}

// Without lookup counting (RenderOptions::count_lookups off, what `cmam render` does without
// --stats) the image is the same and only the rays are counted.
TEST(Render, LookupCountingChangesNothingButTheCounts) {
    const std::string scene = std::string(CMAM_SCENES_DIR) + "/demo.pbrt";
    for (const char* lod : {"differentials", "cmam"}) {
        render::BuildOptions bo;
        bo.spp_override = 1;
        bo.lod = render::parse_footprint_method(lod);
        auto s = build_scene(pbrt::parse_file(scene), bo, {});
        RenderOptions counted, uncounted;
        uncounted.count_lookups = false;
        RenderStats st_counted, st_uncounted;
        const Framebuffer a = render::render(*s, counted, &st_counted);
        const Framebuffer b = render::render(*s, uncounted, &st_uncounted);
        EXPECT_EQ(a.rgb, b.rgb) << lod;
        EXPECT_EQ(st_counted.total_rays(), st_uncounted.total_rays()) << lod;
        uint64_t counted_lookups = 0, uncounted_lookups = 0;
        for (auto& n : st_counted.lookups_by_filter) counted_lookups += n;
        for (auto& n : st_uncounted.lookups_by_filter) uncounted_lookups += n;
        EXPECT_GT(counted_lookups, 0u) << lod;
        EXPECT_EQ(uncounted_lookups, 0u) << lod;
    }
}

TEST(Cmam, TwoDimensionalCmamHasTheRowAboveOnEveryRowButTheFirst) {
    // A textured plane fills the frame: with the image traced in strips, top to bottom, every
    // 2-D CMAM lookup has its sample above except those of the image's first row of strata,
    // for any thread count, with the same image. 1024 pixels are 16 strips: one thread traces
    // each strip whole, two cut each into two segments of rows, the second starting from the
    // row above traced into its caches.
    const std::string text = test::cmam_plane(1024, 40);
    const pbrt::SceneDesc d = pbrt::parse_string(text, "plane.pbrt");
    for (int spp : {1, 4}) {
        BuildOptions bo;
        bo.spp_override = spp;
        bo.cmam.two_d = true;
        auto s = build_scene(d, bo, {});
        RenderOptions one, two;
        one.threads = 1;
        two.threads = 2;
        RenderStats st1, st2;
        Framebuffer a = render::render(*s, one, &st1), b = render::render(*s, two, &st2);
        EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
        const uint64_t first_row = 1024 * static_cast<uint64_t>(s->sampler.xsamples);
        EXPECT_EQ(st1.cmam_2d_without_above.load(), first_row) << spp << " spp";
        EXPECT_EQ(st2.cmam_2d_without_above.load(), first_row) << spp << " spp";
        EXPECT_EQ(st1.lookups_by_filter[static_cast<int>(texture::FilterKind::Area)].load(),
                  1024u * 40u * spp);
    }
}

// trace_packet shades each sample's hits in trace_one's order, only intersecting the samples'
// rays in packets (their paths in lock step) and tracing every hit's shadow rays towards delta
// lights in packets: the radiance is trace_one's bit for bit. The scenes have both children at
// every glass hit, so the samples' trees differ in shape, mirrors, an infinite light (random
// numbers at every lit hit) and textures filtered by each footprint method, the CMAM's caches
// included (each sees a path's samples in order: taking the paths in another order changes
// paper scene 4's CMAM image).
namespace {
// Packets of 16 samples along rows y0, y0 + dy, ... < y1, starting at the columns `x0`, against
// the same samples traced one by one; the CMAM's caches go on along each row in both. Returns
// how many samples spawned more than two reflected or transmitted rays.
int expect_packets_match_single_rays(const Scene& s, std::initializer_list<int> x0, int y0, int y1,
                                     int dy) {
    const FootprintProducers producers(s.footprint_methods, s.camera, 1);
    constexpr int N = Scene::kPacketSize;
    int deep = 0;
    PacketScratch scratch;
    for (int py = y0; py < y1; py += dy) {
        CmamRowState packet_caches, one_caches;
        for (int x : x0) {
            // Sixteen samples along a row, as the film would give them (tags in sequence).
            CameraPath paths[N];
            for (int k = 0; k < N; ++k) {
                const float fx = x + k + 0.37f, fy = py + 0.61f;
                const CameraRay ray = s.camera.generate_ray(fx, fy);
                const Vec3 &o = ray.org, &d = ray.dir;
                texture::RayTag tag;
                tag.id = static_cast<uint32_t>(py);
                tag.seq = static_cast<uint32_t>(x + k);
                paths[k].ray = {o, d, producers.camera_ray(fx, fy, d, tag, 0.13f, -0.21f)};
                paths[k].seed = mix_seed(static_cast<uint64_t>(py), static_cast<uint64_t>(x + k));
            }
            Rgb packet[N];
            trace_packet(s, producers, paths, N, &packet_caches, scratch, packet);
            for (int k = 0; k < N; ++k) {
                RayCounts counts;
                const Rgb one =
                    trace_one(s, producers, paths[k].ray.org, paths[k].ray.dir, paths[k].ray.fp,
                              paths[k].seed, &counts, &one_caches, nullptr);
                deep += counts.secondary > 2;
                EXPECT_EQ(std::memcmp(&one, &packet[k], sizeof(Rgb)), 0)
                    << "row " << py << " sample " << x + k << ": " << one.r << " vs "
                    << packet[k].r;
            }
        }
    }
    return deep;
}

// A scene from pbrt text, read as if from a file beside the bundled scenes (textures/...).
std::unique_ptr<Scene> scene_beside_textures(const std::string& text) {
    return build_scene(pbrt::parse_string(text, std::string(CMAM_SCENES_DIR) + "/p.pbrt"), {}, {});
}
}  // namespace

TEST(Packets, TracePacketGivesTraceOnesRadianceBitForBit) {
    for (const char* lod : {"differentials", "cmam", "cones-aniso"}) {
        SCOPED_TRACE(lod);
        const std::string text =
            std::string(
                "LookAt 0 1.5 -5  0 0.8 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
                "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 48\n"
                "Integrator \"whitted\" \"integer maxdepth\" 5\nWorldBegin\n"
                "LightSource \"point\" \"point from\" [2 3 -2] \"rgb I\" [6 6 6]\n"
                "LightSource \"distant\" \"point from\" [-3 6 -4] \"point to\" [0 0 0]\n"
                "LightSource \"infinite\" \"rgb L\" [0.3 0.3 0.4]\n"
                "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" "
                "\"textures/bricks.png\" \"float uscale\" 8 \"float vscale\" 8 "
                "\"string lod\" \"") +
            lod +
            "\"\nMaterial \"matte\" \"texture Kd\" \"t\"\n"
            "Shape \"trianglemesh\" \"point3 P\" [-20 0 -20  20 0 -20  20 0 20  -20 0 20] "
            "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n"
            "AttributeBegin Material \"glass\" Translate 0.5 0.8 0 Shape \"sphere\" \"float "
            "radius\" 0.8 AttributeEnd\n"
            "AttributeBegin Material \"mirror\" Translate -1.2 0.6 1 Shape \"sphere\" \"float "
            "radius\" 0.6 AttributeEnd\n"
            "AttributeBegin Material \"plastic\" \"texture Kd\" \"t\" Translate 1.8 0.5 1.5 "
            "Shape \"sphere\" \"float radius\" 0.5 AttributeEnd\nWorldEnd\n";
        // Some samples went through the glass (children of children).
        EXPECT_GT(
            expect_packets_match_single_rays(*scene_beside_textures(text), {8, 24, 40}, 4, 48, 3),
            0);
    }
    // Glass in glass to depth 14: a packet's trees outgrow what it keeps deferred, and the rest
    // is traced to the end at once.
    for (const char* lod : {"differentials", "cmam"}) {
        SCOPED_TRACE(std::string("deep glass, ") + lod);
        const std::string text =
            std::string(
                "LookAt 0 0 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n"
                "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32\n"
                "Integrator \"whitted\" \"integer maxdepth\" 14\nWorldBegin\n"
                "LightSource \"point\" \"point from\" [2 3 -3] \"rgb I\" [10 10 10]\n"
                "LightSource \"infinite\" \"rgb L\" [0.3 0.3 0.4]\n"
                "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" "
                "\"textures/bricks.png\" \"string lod\" \"") +
            lod +
            "\"\nAttributeBegin Material \"glass\" Shape \"sphere\" \"float radius\" 1 "
            "AttributeEnd\nAttributeBegin Material \"glass\" Shape \"sphere\" \"float radius\" "
            "0.6 AttributeEnd\nAttributeBegin Material \"matte\" \"texture Kd\" \"t\" "
            "Translate 0 0 3 Shape \"sphere\" \"float radius\" 1.5 AttributeEnd\nWorldEnd\n";
        EXPECT_GT(expect_packets_match_single_rays(*scene_beside_textures(text), {8}, 14, 18, 2),
                  0);
    }
    // Paper scene 4's two glass spheres, whose samples' trees differ most, through the CMAM.
    for (FootprintMethod lod : {FootprintMethod::Cmam, FootprintMethod::Differentials}) {
        SCOPED_TRACE(std::string(to_string(lod)));
        BuildOptions bo;
        bo.lod = lod;
        auto s = build_scene(pbrt::parse_file(std::string(CMAM_SCENES_DIR) + "/paper/scene4.pbrt"),
                             bo, {});
        EXPECT_GT(expect_packets_match_single_rays(*s, {96, 112, 128, 240, 256}, 100, 220, 7), 0);
    }
}

// Camera rays that leave the scene take trace_packet's short way (what escapes, set without a
// tracer): trace_one's radiance bit for bit with no infinite light, a constant one and an
// environment map filtered over the rays' differentials. The rows compared hold both rays that
// leave and rays that hit (the floor, and a mirror whose reflections leave through li).
TEST(Packets, CameraRaysThatLeaveTheSceneGiveTraceOnesRadiance) {
    for (const char* light :
         {"", "LightSource \"infinite\" \"rgb L\" [0.3 0.3 0.4]\n",
          "LightSource \"infinite\" \"string mapname\" \"textures/grass.png\"\n"}) {
        SCOPED_TRACE(light);
        const std::string text =
            std::string(
                "LookAt 0 1 -5  0 1.2 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
                "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 48\n"
                "Integrator \"whitted\" \"integer maxdepth\" 5\nWorldBegin\n"
                "LightSource \"distant\" \"point from\" [-3 6 -4] \"point to\" [0 0 0]\n") +
            light +
            "Material \"matte\"\nShape \"trianglemesh\" \"point3 P\" [-4 0 -4  4 0 -4  4 0 4  -4 0 "
            "4] \"integer indices\" [0 1 2 0 2 3]\n"
            "AttributeBegin Material \"mirror\" Translate 0 1 0 Shape \"sphere\" \"float "
            "radius\" 0.7 AttributeEnd\nWorldEnd\n";
        const auto s = scene_beside_textures(text);
        int leave = 0, hit = 0;
        for (int py = 4; py < 48; py += 6)
            for (int px = 8; px < 56; ++px) {
                const CameraRay r = s->camera.generate_ray(px + 0.37f, py + 0.61f);
                ++(s->intersect(r.org, r.dir, 0, std::numeric_limits<float>::infinity(), false)
                       ? hit
                       : leave);
            }
        EXPECT_GT(leave, 0);
        EXPECT_GT(hit, 0);
        expect_packets_match_single_rays(*s, {8, 24, 40}, 4, 48, 6);
    }
}
