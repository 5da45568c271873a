// pbrt-v3's "mix" material: amount x the first named material + (1 - amount) x the second, per
// channel: their lobes added into one BSDF where they fit one, else in expectation over the
// integrator's choice of one per shading point.
#include <gtest/gtest.h>

#include <algorithm>

#include "render/build_scene.h"
#include "render/integrator.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// A plane lit head-on by a distant light of radiance pi: its radiance is its reflectance. The
// mix of materials a and b (by default two mattes of Kd 0.8 and (0.2, 0.4, 0.2)). Whitted: a
// pick between the two draws independent numbers (path tracing stratifies them per pixel).
std::unique_ptr<Scene> mixed_plane(
    const std::string& amount,
    const std::string& a = "\"string type\" \"matte\" \"rgb Kd\" [0.8 0.8 0.8]",
    const std::string& b = "\"string type\" \"matte\" \"rgb Kd\" [0.2 0.4 0.2]") {
    return test::scene_from(
        "LookAt 0 0 10  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 30 "
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
        "Integrator \"whitted\" WorldBegin "
        "LightSource \"distant\" \"point from\" [0 0 1] \"point to\" [0 0 0] "
        "\"rgb L\" [3.14159265 3.14159265 3.14159265] "
        "MakeNamedMaterial \"a\" " +
            a + " MakeNamedMaterial \"b\" " + b +
            " MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\" "
            "\"string namedmaterial2\" \"b\" " +
            amount +
            " NamedMaterial \"m\" "
            "Shape \"trianglemesh\" \"point3 P\" [-20 -20 0  20 -20 0  20 20 0  -20 20 0] "
            "\"integer indices\" [0 1 2 0 2 3] WorldEnd",
        "t.pbrt", 64);
}

Rgb mean(const Framebuffer& fb) {
    double m[3] = {0, 0, 0};
    for (std::size_t i = 0; i < fb.rgb.size(); ++i) m[i % 3] += fb.rgb[i];
    const double n = double(fb.rgb.size() / 3);
    return Rgb(float(m[0] / n), float(m[1] / n), float(m[2] / n));
}

}  // namespace

TEST(MixMaterial, BlendsItsMaterialsByAmountPerChannel) {
    // amount 0.25: 0.25 a + 0.75 b (16384 samples of a two-valued choice: sigma < 0.003).
    Rgb c = mean(render::render(*mixed_plane("\"rgb amount\" [0.25 0.25 0.25]"), {}, nullptr));
    EXPECT_NEAR(c.r, 0.25f * 0.8f + 0.75f * 0.2f, 0.01f);
    EXPECT_NEAR(c.g, 0.25f * 0.8f + 0.75f * 0.4f, 0.01f);
    // Per channel: red all a, green all b, blue half and half.
    c = mean(render::render(*mixed_plane("\"rgb amount\" [1 0 0.5]"), {}, nullptr));
    EXPECT_NEAR(c.r, 0.8f, 0.02f);
    EXPECT_NEAR(c.g, 0.4f, 0.02f);
    EXPECT_NEAR(c.b, 0.5f * 0.8f + 0.5f * 0.2f, 0.02f);
}

// Lobes that fit one BSDF (here two Lambertian ones) are added, as pbrt-v3 adds them: every
// pixel is the blend, none is one material or the other.
TEST(MixMaterial, LobesThatFitOneBsdfAreAddedAtEveryPixel) {
    const Framebuffer fb = render::render(*mixed_plane("\"rgb amount\" [0.25 0.5 1]"), {}, nullptr);
    const float want[3] = {0.25f * 0.8f + 0.75f * 0.2f, 0.5f * 0.8f + 0.5f * 0.4f, 0.8f};
    ASSERT_FALSE(fb.rgb.empty());
    for (std::size_t i = 0; i < fb.rgb.size(); ++i)
        ASSERT_NEAR(fb.rgb[i], want[i % 3], 1e-4f) << "pixel " << i / 3 << " channel " << i % 3;
}

// Two Oren-Nayar lobes of different sigma do not fit one Bsdf: the second is a layer, and every
// pixel is still the blend. Lit and seen head-on, Oren-Nayar's value is
// Kd (1 - sigma^2 / (2 (sigma^2 + 0.33))) / pi (sigma in radians).
TEST(MixMaterial, LobesOfOneKindWithDifferentParametersAreAddedAtEveryPixel) {
    const auto scene =
        mixed_plane("\"rgb amount\" [0.25 0.25 0.25]",
                    "\"string type\" \"matte\" \"rgb Kd\" [0.8 0.8 0.8] \"float sigma\" 20",
                    "\"string type\" \"matte\" \"rgb Kd\" [0.2 0.4 0.2] \"float sigma\" 40");
    const Framebuffer fb = render::render(*scene, {}, nullptr);
    auto oren_nayar_a = [](double degrees) {
        const double s = degrees * 3.14159265358979 / 180, s2 = s * s;
        return 1 - s2 / (2 * (s2 + 0.33));
    };
    const double want = 0.25 * 0.8 * oren_nayar_a(20) + 0.75 * 0.4 * oren_nayar_a(40);
    ASSERT_FALSE(fb.rgb.empty());
    for (std::size_t i = 1; i < fb.rgb.size(); i += 3)
        ASSERT_NEAR(fb.rgb[i], want, 1e-4) << "pixel " << i / 3;
    // The texture AOV: the blend of the two Kd, the layer's included.
    RenderOptions ro;
    ro.aov = AovKind::Texture;
    const Framebuffer aov = render::render(*scene, ro, nullptr);
    for (std::size_t i = 1; i < aov.rgb.size(); i += 3)
        ASSERT_NEAR(aov.rgb[i], 0.25 * 0.8 + 0.75 * 0.4, 1e-5) << "pixel " << i / 3;
}

// A mix with material "none" (pbrt-v3 has no sum for it) picks one of the two per shading
// point, weighted: "none" passes the ray on (here into the black beyond), so the mean is
// amount x the matte, and each pixel is one or the other.
TEST(MixMaterial, MixesThatCannotBeAddedArePickedAndWeighted) {
    const Framebuffer fb =
        render::render(*mixed_plane("\"rgb amount\" [0.25 0.25 0.25]",
                                    "\"string type\" \"matte\" \"rgb Kd\" [0.8 0.8 0.8]",
                                    "\"string type\" \"none\""),
                       {}, nullptr);
    EXPECT_NEAR(mean(fb).g, 0.25 * 0.8, 0.01);
    std::size_t apart = 0;
    for (std::size_t i = 1; i < fb.rgb.size(); i += 3)
        apart += std::abs(fb.rgb[i] - 0.25 * 0.8) > 0.01;
    EXPECT_GT(apart, fb.rgb.size() / 3 / 4);
}

TEST(MixMaterial, NamesResolveWhereTheMixIsDeclared) {
    std::vector<std::string> warnings;
    pbrt::SceneDesc d = pbrt::parse_string(
        "Camera \"perspective\" WorldBegin "
        "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"later\" "
        "\"string namedmaterial2\" \"later\" "
        "MakeNamedMaterial \"later\" \"string type\" \"mirror\" WorldEnd",
        "t.pbrt");
    EXPECT_EQ(d.materials[0].mix[0], -1);
    auto s = render::build_scene(d, {}, [&](const std::string& w) { warnings.push_back(w); });
    EXPECT_TRUE(std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
        return w.find("named material \"later\" is not defined here") != std::string::npos;
    }));
}
