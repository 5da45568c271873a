// Pixel reconstruction filters (PixelFilter): pbrt-v3's filter functions and parameters, and a
// filtered film against pbrt-v3's film computed here on its own, sample by sample, for a step
// edge whose radiance is known at every sample; cropped films and any thread count.
#include "render/pixel_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "expect_throw.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

PixelFilter filter_of(const std::string& directive, std::vector<std::string>* warnings = nullptr) {
    const std::string text = directive + " WorldBegin WorldEnd";
    auto s = build_scene(pbrt::parse_string(text, "f.pbrt"), {}, [&](const std::string& w) {
        if (warnings) warnings->push_back(w);
    });
    return s->film.filter;
}

}  // namespace

TEST(PixelFilter, FactorsArePbrtV3Filters) {
    PixelFilter f;
    f.kind = PixelFilter::Kind::Gaussian;  // alpha 2
    EXPECT_NEAR(f.factor(0, 2), 1 - std::exp(-8.0), 1e-6);
    EXPECT_NEAR(f.factor(1, 2), std::exp(-2.0) - std::exp(-8.0), 1e-6);
    EXPECT_EQ(f.factor(2.5f, 2), 0);
    f.kind = PixelFilter::Kind::Triangle;
    EXPECT_NEAR(f.factor(0.5f, 2), 1.5, 1e-6);
    EXPECT_NEAR(f.factor(-1.5f, 2), 0.5, 1e-6);
    EXPECT_EQ(f.factor(3, 2), 0);
    f.kind = PixelFilter::Kind::Mitchell;  // B = C = 1/3, over [-2, 2] stretched to the radius
    EXPECT_NEAR(f.factor(0, 2), 16.0 / 18, 1e-6);
    EXPECT_NEAR(f.factor(1, 2), 1.0 / 18, 1e-6);  // |2x/r| = 1: both pieces agree
    EXPECT_LT(f.factor(1.5f, 2), 0);              // the negative lobe
    EXPECT_NEAR(f.factor(2, 2), 0, 1e-6);
    f.kind = PixelFilter::Kind::Sinc;  // tau 3
    EXPECT_NEAR(f.factor(0, 4), 1, 1e-6);
    const double x = 0.5, pi = std::numbers::pi;
    EXPECT_NEAR(f.factor(0.5f, 4),
                std::sin(pi * x) / (pi * x) * std::sin(pi * x / 3) / (pi * x / 3), 1e-6);
    EXPECT_NEAR(f.factor(1, 4), 0, 1e-6);
    EXPECT_EQ(f.factor(4.5f, 4), 0);
    // The tables hold the factor at each step's midpoint.
    f.kind = PixelFilter::Kind::Gaussian;
    f.rx = 2;
    f.ry = 1;
    f.tabulate();
    EXPECT_FLOAT_EQ(f.table_x[0], f.factor(2.0f / 32, 2));
    EXPECT_FLOAT_EQ(f.table_x[15], f.factor(2 * 15.5f / 16, 2));
    EXPECT_FLOAT_EQ(f.table_y[3], f.factor(3.5f / 16, 1));
}

TEST(PixelFilter, ScenesGivePbrtV3sParametersAndDefaults) {
    using K = PixelFilter::Kind;
    EXPECT_TRUE(filter_of("").own_pixel());  // no PixelFilter: pbrt-v3's box of radius 0.5
    EXPECT_TRUE(filter_of("PixelFilter \"box\"").own_pixel());
    PixelFilter b = filter_of("PixelFilter \"box\" \"float xwidth\" 1");
    EXPECT_FALSE(b.own_pixel());
    EXPECT_EQ(b.rx, 1);
    EXPECT_EQ(b.ry, 0.5f);
    PixelFilter g = filter_of("PixelFilter \"gaussian\"");
    EXPECT_EQ(g.kind, K::Gaussian);
    EXPECT_EQ(g.rx, 2);
    EXPECT_EQ(g.alpha, 2);
    EXPECT_FLOAT_EQ(g.table_x[0], g.factor(1.0f / 16, 2));  // tabulated when the scene is built
    g = filter_of("PixelFilter \"gaussian\" \"float alpha\" 0.5 \"float ywidth\" 3");
    EXPECT_EQ(g.alpha, 0.5f);
    EXPECT_EQ(g.ry, 3);
    PixelFilter s = filter_of("PixelFilter \"sinc\"");
    EXPECT_EQ(s.kind, K::Sinc);
    EXPECT_EQ(s.rx, 4);
    EXPECT_EQ(s.tau, 3);
    PixelFilter m = filter_of("PixelFilter \"mitchell\" \"float B\" 0 \"float C\" 0.5");
    EXPECT_EQ(m.kind, K::Mitchell);
    EXPECT_EQ(m.b, 0);
    EXPECT_EQ(m.c, 0.5f);
    EXPECT_EQ(filter_of("PixelFilter \"triangle\"").kind, K::Triangle);
    // A radius beyond 16 pixels is used as 16, with a warning; one that is not a positive finite
    // number is an error at the parameter.
    std::vector<std::string> warnings;
    EXPECT_EQ(filter_of("PixelFilter \"triangle\" \"float xwidth\" 100", &warnings).rx, 16);
    EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                            [](const std::string& w) {
                                return w.find(
                                           "f.pbrt:1:24: warning: PixelFilter xwidth 100 is "
                                           "rendered as 16 pixels") != std::string::npos;
                            }),
              1);
    EXPECT_THROW_MSG(filter_of("PixelFilter \"gaussian\" \"float ywidth\" -1"), pbrt::SceneError,
                     "f.pbrt:1:24: error: ywidth must be a positive finite number, got -1");
    EXPECT_THROW_MSG(filter_of("PixelFilter \"lanczos\""), pbrt::SceneError,
                     "f.pbrt:1:1: error: unknown PixelFilter \"lanczos\"");
}

namespace {

// Two step edges: rays through the film at raster x in [kLeft, kEdge) meet a black quad, the
// others see a constant infinite light of radiance 1. An orthographic camera along +z whose
// screen window makes screen x = raster x - 10 on a 20 x 6 film; 4 x 4 samples per pixel without
// jitter. The left edge lies in the film's first pixel, so that pixel's value depends on the
// samples beyond the film.
constexpr double kLeft = 0.4, kEdge = 10.3;

std::string edge_scene(const std::string& filter, const std::string& film_extra = "") {
    return "Camera \"orthographic\" \"float screenwindow\" [-10 10 -3 3] "
           "Film \"image\" \"integer xresolution\" 20 \"integer yresolution\" 6 " +
           film_extra +
           " Sampler \"stratified\" \"integer xsamples\" 4 \"integer ysamples\" 4 "
           "\"bool jitter\" \"false\" " +
           filter +
           " WorldBegin LightSource \"infinite\" \"rgb L\" [1 1 1] "
           "Material \"matte\" \"rgb Kd\" [0 0 0] "
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
           "\"point3 P\" [-9.6 -100 5  0.3 -100 5  0.3 100 5  -9.6 100 5] WorldEnd";
}

// pbrt-v3's film for the step edge, column by column (the scene does not change along y, so the
// y weights cancel in each pixel's ratio): each sample of every pixel within the filter's reach,
// pixels beyond the film or the crop included, adds its table weight to the pixels [x0, x1).
std::vector<double> expected_columns(const PixelFilter& f, int x0, int x1) {
    constexpr int N = PixelFilter::kTableSize;
    std::vector<double> sum(static_cast<std::size_t>(x1 - x0)), wsum(sum.size());
    const int first = x0 + static_cast<int>(std::floor(0.5f - f.rx)),
              last = x1 + static_cast<int>(std::ceil(f.rx - 0.5f));
    for (int px = first; px < last; ++px)
        for (int sx = 0; sx < 4; ++sx) {
            const float fx = px + (sx + 0.5f) / 4, d = fx - 0.5f;
            const double radiance = fx >= kLeft && fx < kEdge ? 0 : 1;
            for (int x = std::max(x0, int(std::ceil(d - f.rx)));
                 x < std::min(x1, int(std::floor(d + f.rx)) + 1); ++x) {
                const float t = std::abs((float(x) - d) * (1 / f.rx) * N);
                const int i = std::min(static_cast<int>(std::floor(t)), N - 1);
                const double w = f.factor((i + 0.5f) * f.rx / N, f.rx);
                sum[static_cast<std::size_t>(x - x0)] += w * radiance;
                wsum[static_cast<std::size_t>(x - x0)] += w;
            }
        }
    for (std::size_t k = 0; k < sum.size(); ++k) sum[k] = std::max(0.0, sum[k] / wsum[k]);
    return sum;
}

}  // namespace

TEST(PixelFilter, FilteredFilmIsPbrtV3sWeightedMeanOfTheSamplesInReach) {
    for (const std::string filter :
         {"PixelFilter \"gaussian\"", "PixelFilter \"mitchell\"", "PixelFilter \"sinc\"",
          "PixelFilter \"triangle\" \"float xwidth\" 1.5", "PixelFilter \"box\" \"float xwidth\" 1",
          "PixelFilter \"box\""}) {
        SCOPED_TRACE(filter);
        auto s = test::scene_from(edge_scene(filter));
        const Framebuffer fb = render::render(*s, {}, nullptr);
        const std::vector<double> want = expected_columns(s->film.filter, 0, 20);
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 20; ++x)
                EXPECT_NEAR(fb.rgb[(static_cast<std::size_t>(y) * 20 + x) * 3], want[x], 1e-5)
                    << x << " " << y;
        if (!s->film.filter.own_pixel()) {
            // The filter reaches across the edge: no longer a step (a blur, or the ringing of
            // mitchell's and sinc's negative lobes).
            EXPECT_TRUE(want[9] != 0 || want[11] != 1) << want[9] << " " << want[11];
        } else {
            EXPECT_EQ(want[0], 0.5);
            EXPECT_EQ(want[9], 0);
            EXPECT_EQ(want[10], 0.75);
            EXPECT_EQ(want[11], 1);
        }
    }
}

TEST(PixelFilter, WithoutTheFilterEachSampleCountsForItsOwnPixel) {
    // RenderOptions::pixel_filter false (cmam eval's box-filtered pixels): the box's image.
    auto s = test::scene_from(edge_scene("PixelFilter \"gaussian\""));
    RenderOptions o;
    o.pixel_filter = false;
    const Framebuffer fb = render::render(*s, o, nullptr);
    EXPECT_EQ(fb.rgb[0], 0.5f);
    EXPECT_EQ(fb.rgb[9 * 3], 0.0f);
    EXPECT_EQ(fb.rgb[10 * 3], 0.75f);
    EXPECT_EQ(fb.rgb[11 * 3], 1.0f);
}

TEST(PixelFilter, CroppedFilmTakesTheSamplesBeyondTheCrop) {
    // Columns [10, 15) of the same film, the edge in the first: the pixels at the crop's edges
    // take the samples of the pixels beyond it, as the whole film's pixels do.
    auto s = test::scene_from(
        edge_scene("PixelFilter \"gaussian\"", "\"float cropwindow\" [0.5 0.75 0 1]"));
    ASSERT_EQ(s->film.x0, 10);
    const Framebuffer fb = render::render(*s, {}, nullptr);
    ASSERT_EQ(fb.width, 5);
    const std::vector<double> want = expected_columns(s->film.filter, 10, 15);
    for (int x = 0; x < 5; ++x) EXPECT_NEAR(fb.rgb[static_cast<std::size_t>(x) * 3], want[x], 1e-5);
    // pbrt-v3's crop edges are ceilings in single precision: 200 x 0.6f is above 120.
    auto c = test::scene_from(
        "Film \"image\" \"integer xresolution\" 10 \"integer yresolution\" 200 "
        "\"float cropwindow\" [0 1 0.1 0.6] WorldBegin WorldEnd");
    EXPECT_EQ(c->film.y0, 20);
    EXPECT_EQ(c->film.y1, 121);
}

TEST(PixelFilter, FilteredImagesAreTheSameForAnyThreadCount) {
    // A textured plane under a point light, the rows' blocks and the CMAM's strips.
    const std::string scene =
        "LookAt 0 1 -4  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 60 "
        "Film \"image\" \"integer xresolution\" 48 \"integer yresolution\" 40 "
        "Sampler \"stratified\" \"integer xsamples\" 2 \"integer ysamples\" 2 "
        "PixelFilter \"gaussian\" WorldBegin "
        "LightSource \"point\" \"point from\" [0 3 0] \"rgb I\" [5 5 5] "
        "Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 20 \"float vscale\" 20 "
        "Material \"matte\" \"texture Kd\" \"c\" "
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
        "\"point3 P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5] \"point2 uv\" [0 0 1 0 1 1 0 1] WorldEnd";
    for (const char* lod : {"differentials", "cmam2d"}) {
        SCOPED_TRACE(lod);
        BuildOptions bo;
        if (std::string(lod) == "cmam2d") {
            bo.lod = FootprintMethod::Cmam;
            bo.cmam.two_d = true;
        }
        auto s = build_scene(pbrt::parse_string(scene, "t.pbrt"), bo, {});
        RenderOptions one, two;
        one.threads = 1;
        two.threads = 2;
        const Framebuffer a = render::render(*s, one, nullptr),
                          b = render::render(*s, two, nullptr);
        ASSERT_EQ(a.rgb.size(), b.rgb.size());
        EXPECT_EQ(a.rgb, b.rgb);
    }
}
