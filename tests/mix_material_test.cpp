// pbrt-v3's "mix" material: amount x the first named material + (1 - amount) x the second, per
// channel, in expectation over the integrator's choice of one per shading point.
#include <gtest/gtest.h>

#include <algorithm>

#include "render/build_scene.h"
#include "render/integrator.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// A plane lit head-on by a distant light of radiance pi: its radiance is its reflectance.
std::unique_ptr<Scene> mixed_plane(const std::string& amount) {
    return test::scene_from(
        "LookAt 0 0 10  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 30 "
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 WorldBegin "
        "LightSource \"distant\" \"point from\" [0 0 1] \"point to\" [0 0 0] "
        "\"rgb L\" [3.14159265 3.14159265 3.14159265] "
        "MakeNamedMaterial \"a\" \"string type\" \"matte\" \"rgb Kd\" [0.8 0.8 0.8] "
        "MakeNamedMaterial \"b\" \"string type\" \"matte\" \"rgb Kd\" [0.2 0.4 0.2] "
        "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string namedmaterial1\" \"a\" "
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
