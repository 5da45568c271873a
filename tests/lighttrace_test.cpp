// pbrt-v3's "bdpt" (and "mlt") integrator: the path tracer plus light paths from the delta lights
// joined to the camera. A caustic against its closed form (a light seen in a mirror is a second
// light at its mirror image, which only the light paths carry to a diffuse floor), with the
// direct light from the path tracer beside it, through a thin lens and a crop window; refraction
// against SPPM; the same image for any thread count; the path tracer's image wherever no light
// path has a specular first bounce or the camera has no importance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "expect_throw.h"
#include "pbrt/error.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/memory.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

using test::mean_of;
using test::render_text;

// A diffuse floor (albedo 1/2) at y = 0, a light at height 1 above the origin and a mirror
// facing down at height 1.5; a pinhole camera at height 0.5 below the light looks straight down
// at the floor over [0.4, 0.8] x [-0.2, 0.2] (tan of half its field of view 0.4), away from the
// light's shadow in the mirror. The floor's radiance at distance r from the foot of the light is
// 1/(2 pi) (E_direct + E_mirror), E_mirror the irradiance from the light's mirror image at height
// 2. maxdepth 2 leaves out the light bouncing between floor and mirror.
std::string mirror_scene(const std::string& light, int spp, const std::string& camera = "",
                         const std::string& integrator = "bdpt") {
    return R"(LookAt 0.6 0.5 0  0.6 0 0  0 0 1
Camera "perspective" "float fov" 43.602818 )" +
           camera + R"(
Film "image" "integer xresolution" 16 "integer yresolution" 16
Sampler "stratified" "integer xsamples" )" +
           std::to_string(spp) + R"( "integer ysamples" 1 "bool jitter" true
Integrator ")" +
           integrator +
           R"(" "integer maxdepth" 2
)" + test::mirror_world(light);
}

// The floor's closed-form radiance at pixel (x, y)'s centre, the irradiance of a light of
// intensity 1 at height h at distance r being h / (h^2 + r^2)^1.5.
double mirror_radiance(int x, int y, bool direct) {
    const double px = 0.4 + 0.4 * (x + 0.5) / 16, pz = -0.2 + 0.4 * (y + 0.5) / 16;
    const double r2 = px * px + pz * pz;
    auto irradiance = [&](double h) { return h / std::pow(h * h + r2, 1.5); };
    return 0.5 / M_PI * ((direct ? irradiance(1) : 0) + irradiance(2));
}

double mirror_expected(bool direct, int x0 = 0, int x1 = 16, int y0 = 0, int y1 = 16) {
    double sum = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) sum += mirror_radiance(x, y, direct);
    return sum / ((x1 - x0) * (y1 - y0));
}

// A spot light facing the mirror: no light reaches the floor directly (the path tracer's part is
// black), all of it by light paths; its cone's falloff starts 24 degrees out, beyond the 22.3 at
// which the floor seen lies from the mirror image.
const char* kSpotUp = R"(LightSource "spot" "point from" [0 1 0] "point to" [0 2 0] "rgb I" [1 1 1]
  "float coneangle" 25 "float conedeltaangle" 1)";
const char* kPoint = R"(LightSource "point" "point from" [0 1 0] "rgb I" [1 1 1])";

}  // namespace

TEST(LightPaths, MirroredSpotReachesTheFloorByLightPaths) {
    RenderStats stats;
    const Framebuffer spot = render_text(mirror_scene(kSpotUp, 512), 0, &stats);
    EXPECT_NEAR(mean_of(spot) / mirror_expected(false), 1.0, 0.02);
    // Every third pixel of every third row near its own closed form: the joins land where they
    // should (the halves' ratio below tells a raster mirrored along x apart).
    for (int y = 0; y < 16; y += 3)
        for (int x = 0; x < 16; x += 3)
            EXPECT_NEAR(
                spot.rgb[(static_cast<std::size_t>(y) * 16 + x) * 3] / mirror_radiance(x, y, false),
                1.0, 0.15)
                << x << " " << y;
    // As many light paths as camera samples, each a ray to the mirror and one to the floor or
    // beyond; each join where the camera sees the floor a shadow ray (about 6% of the paths).
    EXPECT_GE(stats.secondary_rays.load(), 2u * 16u * 16u * 512u);
    EXPECT_GT(stats.shadow_rays.load(), 16u * 16u * 512u / 25u);
    EXPECT_LT(stats.shadow_rays.load(), 16u * 16u * 512u / 8u);
    // A camera mirrored left to right (pbrt-v3 scenes' Scale -1 1 1): the same image, mirrored.
    const Framebuffer flipped = render_text("Scale -1 1 1\n" + mirror_scene(kSpotUp, 512));
    for (int y = 0; y < 16; y += 3)
        for (int x = 0; x < 16; x += 3)
            EXPECT_NEAR(flipped.rgb[(static_cast<std::size_t>(y) * 16 + x) * 3] /
                            mirror_radiance(15 - x, y, false),
                        1.0, 0.15)
                << x << " " << y;
    // (Its left half the floor's far side: 0.92 of its right half, 1/0.92 unmirrored.)
    EXPECT_NEAR(mean_of(flipped, 0, 8) / mean_of(flipped, 8, 16),
                mirror_expected(false, 8, 16) / mirror_expected(false, 0, 8), 0.02);
    // A black strip at height 0.25 hides the floor from the camera over columns 0 to 3, where
    // the floor is lit: no join passes through it.
    const Framebuffer hidden = render_text(mirror_scene(std::string(kSpotUp) + R"(
Material "matte" "rgb Kd" [0 0 0]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [0.5 0.25 -1 0.55 0.25 -1 0.55 0.25 1 0.5 0.25 1])",
                                                        64));
    EXPECT_EQ(mean_of(hidden, 0, 4), 0.0);
    EXPECT_GT(mean_of(hidden, 5, 16), 0.5 * mirror_expected(false));
    // The same scene by the path tracer alone: black.
    EXPECT_EQ(mean_of(render_text(mirror_scene(kSpotUp, 4, "", "path"))), 0.0);
}

TEST(LightPaths, PointLightIsDirectByThePathTracerAndMirroredByLightPaths) {
    // The path tracer's light sample gives the direct light, the light paths the mirrored light
    // only: together the whole closed form, neither counted twice (the path tracer alone gives
    // the direct light, 0.74 of it).
    const Framebuffer point = render_text(mirror_scene(kPoint, 1024));
    EXPECT_NEAR(mean_of(point) / mirror_expected(true), 1.0, 0.015);
    const Framebuffer path = render_text(mirror_scene(kPoint, 16, "", "path"));
    EXPECT_NEAR(mean_of(path) / (mirror_expected(true) - mirror_expected(false)), 1.0, 0.01);
    // mlt is the same path space: the same image, at as many samples per pixel.
    std::string mlt = mirror_scene(kPoint, 64, "", "mlt");
    mlt.replace(mlt.find("\"integer maxdepth\""), 0, "\"integer mutationsperpixel\" 64 ");
    auto render_scene = [](const std::unique_ptr<Scene>& scene) {
        return render::render(*scene, RenderOptions{}, nullptr);
    };
    const auto mlt_scene = test::scene_from(mlt),
               bdpt_scene = test::scene_from(mirror_scene(kPoint, 64), "t.pbrt", 64);
    EXPECT_EQ(mlt_scene->sampler.spp(), 64);
    EXPECT_EQ(render_scene(mlt_scene).rgb, render_scene(bdpt_scene).rgb);
}

namespace {

// The spot's caustic on a checkered floor (Kd 0.1 and 0.9 in checks of 0.1, four pixels wide,
// aligned with the pixels), seen through a thin lens of radius 0.05 focused at 0.25, halfway to
// the floor: a circle of confusion of two pixels' radius on the floor.
std::string defocused_checks(int spp) {
    std::string text =
        mirror_scene(kSpotUp, spp, R"("float lensradius" 0.05 "float focaldistance" 0.25)");
    const std::string floor = R"(Material "matte" "rgb Kd" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-10 0 -10 10 0 -10 10 0 10 -10 0 10])";
    text.replace(text.find(floor), floor.size(),
                 R"(Texture "checks" "spectrum" "checkerboard" "float uscale" 200 "float vscale" 200
  "rgb tex1" [0.9 0.9 0.9] "rgb tex2" [0.1 0.1 0.1] "string aamode" "none"
Material "matte" "texture Kd" "checks"
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-10 0 -10 10 0 -10 10 0 10 -10 0 10]
  "float uv" [0 0 1 0 1 1 0 1])");
    return text;
}

// The pixel (x, y) of defocused_checks by quadrature: the floor's radiance averaged over the
// pixel's area and the lens's disc (or at the lens's centre: the pinhole's sharp image). Camera
// x is world x, camera y world z; the ray from lens point l through the point of focus f meets
// the floor, 0.5 below the lens, at l + (f - l) 0.5 / 0.25.
double defocused_pixel(int x, int y, bool lens) {
    const int n = 8, m = lens ? 24 : 1;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double sx = -1 + 2 * (x + (i + 0.5) / n) / 16,
                         sy = 1 - 2 * (y + (j + 0.5) / n) / 16;
            const double fx = 0.25 * 0.4 * sx, fy = 0.25 * 0.4 * sy;
            for (int a = 0; a < m; ++a)
                for (int b = 0; b < m; ++b) {
                    // The lens's disc by its polar grid, equal areas per cell.
                    const double r = 0.05 * std::sqrt((a + 0.5) / m),
                                 phi = 2 * M_PI * (b + 0.5) / m;
                    const double lx = lens ? r * std::cos(phi) : 0,
                                 ly = lens ? r * std::sin(phi) : 0;
                    const double wx = 0.6 + lx + (fx - lx) * 2, wz = ly + (fy - ly) * 2;
                    const double u = (wx + 10) / 20 * 200, v = (wz + 10) / 20 * 200;
                    const double kd =
                        (static_cast<long>(std::floor(u)) + static_cast<long>(std::floor(v))) % 2 ==
                                0
                            ? 0.9
                            : 0.1;
                    sum += kd / M_PI * 2 / std::pow(4 + wx * wx + wz * wz, 1.5);
                }
        }
    return sum / (n * n * m * m);
}

}  // namespace

TEST(LightPaths, ThinLensAndCropWindow) {
    // A thin lens out of focus: each join draws a lens point, its importance over the point's
    // density, in the pixel where the ray from that point through the floor meets the plane of
    // focus. The image's blocks of 4 x 4 pixels (one check each in a sharp image) against the
    // quadrature (measured: within 2.5%); a pinhole's sharp image is 44% to 73% away from it in
    // every block.
    const Framebuffer lens = render_text(defocused_checks(4096));
    for (int by = 0; by < 4; ++by)
        for (int bx = 0; bx < 4; ++bx) {
            double blurred = 0, sharp = 0;
            for (int y = 4 * by; y < 4 * by + 4; ++y)
                for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                    blurred += defocused_pixel(x, y, true);
                    sharp += defocused_pixel(x, y, false);
                }
            EXPECT_GT(std::abs(sharp / blurred - 1), 0.3) << bx << " " << by;
            EXPECT_NEAR(mean_of(lens, 4 * bx, 4 * bx + 4, 4 * by, 4 * by + 4) / (blurred / 16), 1.0,
                        0.06)
                << bx << " " << by;
        }
    // A crop window: its pixels still the floor's radiance (fewer light paths, each weighed by
    // the whole film's area over the cropped one's).
    const std::string cropped =
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
        "\"float cropwindow\" [0.25 0.75 0.5 1]";
    std::string text = mirror_scene(kSpotUp, 1024);
    const std::size_t at = text.find("Film");
    text.replace(at, text.find('\n', at) - at, cropped);
    const Framebuffer crop = render_text(text);
    ASSERT_EQ(crop.width, 8);
    ASSERT_EQ(crop.height, 8);
    EXPECT_NEAR(mean_of(crop) / mirror_expected(false, 4, 12, 8, 16), 1.0, 0.025);
}

TEST(LightPaths, SameImageForAnyThreadCount) {
    const std::string text = mirror_scene(kPoint, 64);
    const Framebuffer one = render_text(text, 1), two = render_text(text, 2),
                      three = render_text(text, 3);
    EXPECT_EQ(one.rgb, two.rgb);
    EXPECT_EQ(one.rgb, three.rgb);
    EXPECT_GT(mean_of(one), 0.01);
}

TEST(LightPaths, MltSamplesPerPixelAreItsMutationsPerPixel) {
    // pbrt-v3's mlt takes no Sampler: mutationsperpixel (default 100) sets the samples, rounded
    // to a square; --spp wins; a count under 1 is a located error.
    std::vector<std::string> warnings;
    auto build = [&](const std::string& integrator, int spp = 0) {
        warnings.clear();
        BuildOptions o;
        o.spp_override = spp;
        return build_scene(
            pbrt::parse_string("Sampler \"halton\" \"integer pixelsamples\" 4\n" + integrator +
                                   "\nCamera \"perspective\" WorldBegin WorldEnd",
                               "m.pbrt"),
            o, [&](const std::string& w) { warnings.push_back(w); });
    };
    EXPECT_EQ(build("Integrator \"mlt\"")->sampler.spp(), 100);
    EXPECT_EQ(build("Integrator \"mlt\" \"integer mutationsperpixel\" 1000")->sampler.spp(), 1024);
    EXPECT_EQ(build("Integrator \"mlt\" \"integer mutationsperpixel\" 1000", 16)->sampler.spp(),
              16);
    EXPECT_EQ(build("Integrator \"bdpt\"")->sampler.spp(), 4);  // bdpt takes its Sampler's
    // The sampler's warning says where the count comes from; Metropolis's parameters unused.
    build("Integrator \"mlt\" \"float sigma\" 0.02");
    ASSERT_EQ(warnings.size(), 3u);
    EXPECT_NE(warnings[0].find("as many as the mlt integrator's mutationsperpixel"),
              std::string::npos)
        << warnings[0];
    EXPECT_NE(warnings[2].find("sigma"), std::string::npos) << warnings[2];
    EXPECT_THROW_MSG(build("Integrator \"mlt\" \"integer mutationsperpixel\" 0"), pbrt::SceneError,
                     "m.pbrt:2:18: error: mutationsperpixel must be at least 1, got 0");
}

TEST(LightPaths, ProgressCoversTheFilmThenTheLightPaths) {
    // The film's rows are the first half of the progress, the light paths the second; on one
    // thread every report is at or past the one before, and the last is the whole.
    auto scene = test::scene_from(mirror_scene(kPoint, 64));
    RenderOptions o;
    o.threads = 1;
    std::vector<double> fractions;
    o.progress = [&](int done, int total) { fractions.push_back(double(done) / total); };
    render::render(*scene, o, nullptr);
    ASSERT_FALSE(fractions.empty());
    for (std::size_t i = 1; i < fractions.size(); ++i)
        EXPECT_GE(fractions[i], fractions[i - 1]) << i;
    EXPECT_EQ(fractions.back(), 1.0);
    EXPECT_EQ(std::count(fractions.begin(), fractions.end(), 0.5), 1);  // the film's last row
}

TEST(LightPaths, OnlyWhereAPathTracerCannotReach) {
    auto same_as_path = [](const std::string& bdpt) {
        std::string path = bdpt;
        path.replace(path.find("\"bdpt\""), 6, "\"path\"");
        EXPECT_EQ(render_text(bdpt).rgb, render_text(path).rgb);
    };
    // No delta light: no light path.
    same_as_path(mirror_scene(R"(AttributeBegin Translate 0 1 0
        AreaLightSource "diffuse" "rgb L" [20 20 20] Shape "sphere" "float radius" 0.05
        AttributeEnd)",
                              16));
    // No specular surface: every light path ends at its first bounce.
    std::string matte = mirror_scene(kPoint, 16);
    const std::string mirror = "\"mirror\" \"rgb Kr\" [1 1 1]";
    matte.replace(matte.find(mirror), mirror.size(), "\"matte\"");
    same_as_path(matte);
    // A camera without importance (orthographic): none either, with a warning that says so.
    std::string ortho = mirror_scene(kPoint, 16);
    const std::string perspective = "Camera \"perspective\" \"float fov\" 43.602818";
    ortho.replace(ortho.find(perspective), perspective.size(),
                  "Camera \"orthographic\" \"float screenwindow\" [-0.2 0.2 -0.2 0.2]");
    same_as_path(ortho);
    std::vector<std::string> warnings;
    const auto ortho_scene = build_scene(pbrt::parse_string(ortho, "o.pbrt"), {},
                                         [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("light paths join only a perspective camera"), std::string::npos)
        << warnings[0];
    // A camera mirrored (pbrt-v3 scenes' Scale -1 1 1) has importance, a scaled one not.
    EXPECT_TRUE(test::scene_from("Scale -1 1 1\n" + mirror_scene(kPoint, 4))->light_tracing);
    EXPECT_FALSE(test::scene_from("Scale 2 2 2\n" + mirror_scene(kPoint, 4))->light_tracing);
    // The memory a render needs: the light paths' sums (a double per channel and pixel) beside
    // the image, where they are traced.
    EXPECT_EQ(render_memory_need(*test::scene_from(mirror_scene(kPoint, 4))).film,
              16u * 16u * 3u * (sizeof(float) + sizeof(double)));
    EXPECT_EQ(render_memory_need(*ortho_scene).film, 16u * 16u * 3u * sizeof(float));
}

TEST(LightPaths, RefractedCausticAgreesWithSppm) {
    // A spot light above a glass sphere that focuses it onto a diffuse floor: the caustic by
    // light paths (refraction carrying importance) against SPPM's photons, two estimates of the
    // same light. The camera sees the floor from one side, not through the sphere (SPPM's
    // photons reach what a camera sees through glass, light paths joined to it do not).
    auto scene = [](const std::string& integrator, const std::string& sampler) {
        return R"(LookAt 2 1.5 0  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "image" "integer xresolution" 16 "integer yresolution" 16
)" + sampler + "\n" +
               integrator + R"(
WorldBegin
LightSource "spot" "point from" [0 4 0] "point to" [0 0 0] "rgb I" [10 10 10]
  "float coneangle" 12 "float conedeltaangle" 1
Material "matte" "rgb Kd" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-10 0 -10 10 0 -10 10 0 10 -10 0 10]
Material "glass" "float index" 1.5
AttributeBegin Translate 0 1.6 0 Shape "sphere" "float radius" 0.5 AttributeEnd
WorldEnd
)";
    };
    const Framebuffer bdpt = render_text(scene(R"(Integrator "bdpt" "integer maxdepth" 5)",
                                               R"(Sampler "stratified" "integer xsamples" 16
                                                  "integer ysamples" 16)"));
    const Framebuffer sppm =
        render_text(scene(R"(Integrator "sppm" "integer maxdepth" 5 "integer numiterations" 16
                            "integer photonsperiteration" 100000 "float radius" 0.05)",
                          ""));
    EXPECT_GT(mean_of(bdpt), 0.0);
    EXPECT_NEAR(mean_of(bdpt) / mean_of(sppm), 1.0, 0.03);
}
