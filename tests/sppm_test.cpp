// pbrt-v3's "sppm" integrator (stochastic progressive photon mapping): a caustic against its
// closed form (a light seen in a mirror is a second light at its mirror image, which only the
// photons carry to a diffuse floor), the image against the path tracer's on a scene both render,
// the same image for any thread count, and the integrator's parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "expect_throw.h"
#include "pbrt/error.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

using test::mean_of;
using test::render_text;

// A diffuse floor (albedo 1/2) at y = 0, a light at height 1 above the origin and a mirror
// facing down at height 1.5, the floor seen over [0.4, 0.8] x [-0.2, 0.2] by an orthographic
// camera below the light (which it does not see), away from the light's shadow in the mirror:
// the floor's radiance at distance x from the foot of the light is 1/(2 pi) (E_direct +
// E_mirror), where E_mirror is the irradiance from the light's mirror image at height 2.
// maxdepth 2 leaves out the light bouncing between floor and mirror.
std::string mirror_scene(const std::string& light, int side = 16) {
    const std::string n = std::to_string(side);
    return R"(LookAt 0.6 0.5 0  0.6 0 0  0 0 1
Camera "orthographic" "float screenwindow" [-0.2 0.2 -0.2 0.2]
Film "image" "integer xresolution" )" +
           n + R"( "integer yresolution" )" + n + R"(
Integrator "sppm" "integer maxdepth" 2 "integer numiterations" 32
  "integer photonsperiteration" 50000 "float radius" 0.05
)" + test::mirror_world(light);
}

// The closed form's mean over the 16 x 16 pixels: the floor's radiance at each pixel's centre,
// the irradiance of a light of intensity 1 at height h at distance x being h / (h^2 + x^2)^1.5
// (`lambertian`: of a small disc of radiance times area 1 facing the floor, h^2 / (h^2 + x^2)^2).
double mirror_expected(bool direct, bool lambertian = false) {
    auto irradiance = [&](double h, double r2) {
        return lambertian ? h * h / std::pow(h * h + r2, 2) : h / std::pow(h * h + r2, 1.5);
    };
    double sum = 0;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            const double px = 0.4 + 0.4 * (x + 0.5) / 16, pz = -0.2 + 0.4 * (y + 0.5) / 16;
            const double r2 = px * px + pz * pz;
            sum += 0.5 / M_PI * ((direct ? irradiance(1, r2) : 0) + irradiance(2, r2));
        }
    return sum / 256;
}

}  // namespace

TEST(Sppm, MirroredLightReachesTheFloorThroughPhotons) {
    // A point light: direct light from the camera paths, the mirrored light from photons (an
    // image without them would be 0.8 of this).
    const Framebuffer point =
        render_text(mirror_scene(R"(LightSource "point" "point from" [0 1 0] "rgb I" [1 1 1])"));
    EXPECT_NEAR(mean_of(point) / mirror_expected(true), 1.0, 0.01);
    // One pixel over the same view: its visible points' grid is a single bucket, where each
    // point's ball spans several cells; it must still take each photon once.
    const Framebuffer one =
        render_text(mirror_scene(R"(LightSource "point" "point from" [0 1 0] "rgb I" [1 1 1])", 1));
    EXPECT_NEAR(mean_of(one) / mirror_expected(true), 1.0, 0.05);
    // A spot light facing the mirror: nothing reaches the floor directly, all of it by photons
    // from the spot's cone (whose falloff ends 40 degrees out: the floor seen is within 6).
    const Framebuffer spot = render_text(mirror_scene(
        R"(LightSource "spot" "point from" [0 1 0] "point to" [0 2 0] "rgb I" [1 1 1]
           "float coneangle" 45 "float conedeltaangle" 5)"));
    EXPECT_NEAR(mean_of(spot) / mirror_expected(false), 1.0, 0.02);
    // Area lights: a small sphere of radiance 1 / (pi r^2) (from afar a point light of intensity
    // 1) and a two-sided disc of radiance times area 1 facing up, lighting the floor with its
    // lower side and the mirror with its upper one (photons leave both sides).
    const Framebuffer sphere = render_text(mirror_scene(
        R"(AttributeBegin Translate 0 1 0 AreaLightSource "diffuse" "rgb L" [127.32395 127.32395 127.32395]
           Shape "sphere" "float radius" 0.05 AttributeEnd)"));
    EXPECT_NEAR(mean_of(sphere) / mirror_expected(true), 1.0, 0.015);
    const Framebuffer disc = render_text(mirror_scene(
        R"(AttributeBegin Translate 0 1 0 Rotate -90 1 0 0
           AreaLightSource "diffuse" "rgb L" [127.32395 127.32395 127.32395] "bool twosided" true
           Shape "disk" "float radius" 0.05 AttributeEnd)"));
    EXPECT_NEAR(mean_of(disc) / mirror_expected(true, true), 1.0, 0.015);
    // Every pixel of the spot's image near its own closed form: the flux lands where it should.
    for (int y = 0; y < 16; y += 5)
        for (int x = 0; x < 16; x += 5) {
            const double px = 0.4 + 0.4 * (x + 0.5) / 16, pz = -0.2 + 0.4 * (y + 0.5) / 16;
            const double expected = 0.5 / M_PI * 2 / std::pow(4 + px * px + pz * pz, 1.5);
            EXPECT_NEAR(spot.rgb[(static_cast<std::size_t>(y) * 16 + x) * 3] / expected, 1.0, 0.1)
                << x << " " << y;
        }
}

namespace {

// Diffuse and glossy surfaces lit directly and indirectly by a distant light, an infinite light
// and a spherical area light: light transport both integrators compute.
std::string gi_scene(const std::string& integrator) {
    return R"(LookAt 0 2 -6  0 0.8 0  0 1 0
Camera "perspective" "float fov" 45
Film "image" "integer xresolution" 32 "integer yresolution" 32
Sampler "stratified" "integer xsamples" 16 "integer ysamples" 16
)" + integrator +
           R"(
WorldBegin
LightSource "distant" "point from" [1 3 -1] "point to" [0 0 0] "rgb L" [1.5 1.5 1.5]
LightSource "infinite" "rgb L" [0.2 0.25 0.3]
AttributeBegin
  Translate -1 2.5 -1
  AreaLightSource "diffuse" "rgb L" [4 3 2]
  Shape "sphere" "float radius" 0.2
AttributeEnd
Material "matte" "rgb Kd" [0.6 0.6 0.6]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-4 0 -4 4 0 -4 4 0 4 -4 0 4]
Material "matte" "rgb Kd" [0.7 0.2 0.2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-4 0 2 4 0 2 4 4 2 -4 4 2]
Material "plastic" "rgb Kd" [0.2 0.5 0.2] "rgb Ks" [0.3 0.3 0.3] "float roughness" 0.05
Translate 0.5 0.7 0
Shape "sphere" "float radius" 0.7
WorldEnd
)";
}

}  // namespace

TEST(Sppm, AgreesWithThePathTracer) {
    const Framebuffer path = render_text(gi_scene(R"(Integrator "path" "integer maxdepth" 4)"));
    RenderStats stats;
    const Framebuffer sppm =
        render_text(gi_scene(R"(Integrator "sppm" "integer maxdepth" 4 "integer numiterations" 64
                    "integer photonsperiteration" 100000 "float radius" 0.2)"),
                    0, &stats);
    EXPECT_NEAR(mean_of(sppm) / mean_of(path), 1.0, 0.01);
    // Each 8 x 8 block (floor, wall, sphere, sky) within 3% (measured: 0.4% RMS).
    for (int by = 0; by < 4; ++by)
        for (int bx = 0; bx < 4; ++bx) {
            const int x0 = bx * 8, y0 = by * 8;
            EXPECT_NEAR(
                mean_of(sppm, x0, x0 + 8, y0, y0 + 8) / mean_of(path, x0, x0 + 8, y0, y0 + 8), 1.0,
                0.03)
                << bx << " " << by;
        }
    // One camera ray per pixel and iteration; the photons' rays counted as secondary rays.
    EXPECT_EQ(stats.camera_rays.load(), 32u * 32u * 64u);
    EXPECT_GT(stats.secondary_rays.load(), 64u * 100000u);
}

TEST(Sppm, SameImageForAnyThreadCount) {
    const std::string text =
        gi_scene(R"(Integrator "sppm" "integer numiterations" 3 "float radius" 0.2
                    "integer photonsperiteration" 20000)");
    const Framebuffer one = render_text(text, 1), two = render_text(text, 2),
                      three = render_text(text, 3);
    EXPECT_EQ(one.rgb, two.rgb);
    EXPECT_EQ(one.rgb, three.rgb);
    EXPECT_GT(mean_of(one), 0.1);
}

TEST(Sppm, TwoDimensionalCmamHasTheRowAboveOnEveryRowButTheFirst) {
    // A textured plane filling the frame, its texture filtered by the 2-D CMAM: each block of
    // rows traces the row above into its caches first, so that only the image's first row lacks
    // its row above, in every iteration, for any thread count.
    const std::string text = test::cmam_plane(
        64, 40, "Integrator \"sppm\" \"integer numiterations\" 2 \"float radius\" 0.1\n");
    BuildOptions bo;
    bo.cmam.two_d = true;
    auto s = build_scene(pbrt::parse_string(text, "plane.pbrt"), bo, {});
    RenderOptions one, two;
    one.threads = 1;
    two.threads = 2;
    RenderStats st1, st2;
    const Framebuffer a = render::render(*s, one, &st1), b = render::render(*s, two, &st2);
    EXPECT_EQ(a.rgb, b.rgb);
    EXPECT_EQ(st1.cmam_2d_without_above.load(), 64u * 2u);
    EXPECT_EQ(st2.cmam_2d_without_above.load(), 64u * 2u);
    // (Each pixel's one lookup an iteration counted; the primed rows' are not.)
    EXPECT_EQ(st1.lookups_by_filter[static_cast<int>(texture::FilterKind::Area)].load(),
              64u * 40u * 2u);
}

TEST(Sppm, Parameters) {
    std::vector<std::string> warnings;
    auto build = [&](const std::string& integrator, int spp = 0) {
        warnings.clear();
        pbrt::SceneDesc d = pbrt::parse_string(
            integrator + "\nCamera \"perspective\" WorldBegin WorldEnd", "s.pbrt");
        BuildOptions o;
        o.spp_override = spp;
        return build_scene(d, o, [&](const std::string& w) { warnings.push_back(w); });
    };
    // pbrt-v3's defaults: 64 iterations, a photon per pixel, radius 1; no warning.
    auto s = build(R"(Integrator "sppm" "integer maxdepth" 3 "integer imagewritefrequency" 4)");
    EXPECT_TRUE(s->sppm.on);
    EXPECT_EQ(s->sppm.iterations, 64);
    EXPECT_EQ(s->sppm.photons, 0);
    EXPECT_EQ(s->sppm.radius, 1.0f);
    EXPECT_EQ(s->max_depth, 3);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    // "iterations" is numiterations' other name, and wins.
    s = build(R"(Integrator "sppm" "integer numiterations" 5 "integer iterations" 7
                 "integer photonsperiteration" 1000 "float radius" 0.5)");
    EXPECT_EQ(s->sppm.iterations, 7);
    EXPECT_TRUE(warnings.empty()) << warnings.front();  // (numiterations is read too)
    EXPECT_EQ(s->sppm.photons, 1000);
    EXPECT_EQ(s->sppm.radius, 0.5f);
    // A negative photon count is pbrt-v3's default (a photon per pixel).
    EXPECT_EQ(build(R"(Integrator "sppm" "integer photonsperiteration" -5)")->sppm.photons, 0);
    // --spp sets the iterations, rounded to a square as the samplers' counts are.
    EXPECT_EQ(build(R"(Integrator "sppm")", 16)->sppm.iterations, 16);
    EXPECT_EQ(build(R"(Integrator "sppm")", 10)->sppm.iterations, 9);
    // Unknown parameters are warned about, as pbrt-v3 reports them unused.
    build(R"(Integrator "sppm" "float rrthreshold" 0.5)");
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("rrthreshold"), std::string::npos) << warnings[0];
    // No iteration, or a radius that is not positive: located errors.
    EXPECT_THROW_MSG(build("Integrator \"sppm\" \"integer numiterations\" 0"), pbrt::SceneError,
                     "s.pbrt:1:19: error: numiterations must be at least 1, got 0");
    EXPECT_THROW_MSG(build("Integrator \"sppm\" \"integer iterations\" -2"), pbrt::SceneError,
                     "s.pbrt:1:19: error: iterations must be at least 1, got -2");
    EXPECT_THROW_MSG(build("Integrator \"sppm\" \"float radius\" 0"), pbrt::SceneError,
                     "s.pbrt:1:19: error: radius must be positive, got 0");
}
