// pbrt-v3's bump mapping: the shading normal of a surface displaced along its normal by a float
// texture.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/shading.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// A 2 x 2 quad in z = 0 with (u,v) = ((x+1)/2, (y+1)/2), bumped by d = k u, seen from +z.
std::unique_ptr<Scene> bumped_quad(const std::string& bump) {
    const std::string text = R"(LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "image" "integer xresolution" 8 "integer yresolution" 8
WorldBegin
LightSource "distant" "point from" [0 0 1] "point to" [0 0 0]
Texture "d" "float" "bilerp" "float v00" 0 "float v01" 0 "float v10" 0.3 "float v11" 0.3
Material "matte" )" + bump + R"(
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "float uv" [0 0 1 0 1 1 0 1]
WorldEnd
)";
    return build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
}

}  // namespace

TEST(Bump, ALinearDisplacementTiltsTheNormalByItsSlope) {
    auto s = bumped_quad("\"texture bumpmap\" \"d\"");
    const Material& m = s->materials.back();
    ASSERT_GE(m.bump.node, 0);
    const std::optional<SurfaceHit> hit = s->intersect(Vec3(0.2f, 0.1f, 5), Vec3(0, 0, -1), 0, 100);
    ASSERT_TRUE(hit.has_value());
    const SurfaceHit& h = *hit;
    TexContext ctx;
    ctx.u = h.u;
    ctx.v = h.v;
    ctx.p = h.p;
    // dP/du = (2, 0, 0), dd/du = 0.3: the bumped dP/du is (2, 0, 0.3), dP/dv (0, 2, 0), so the
    // normal is (-0.3, 0, 2) normalised.
    const Vec3 n = bump_normal(*s, m.bump, h, ctx, 0.01f, 0.01f);
    const float len = std::sqrt(0.09f + 4);
    EXPECT_NEAR(n.x, -0.3f / len, 1e-5);
    EXPECT_NEAR(n.y, 0, 1e-6);
    EXPECT_NEAR(n.z, 2 / len, 1e-5);
    // Under a light along +z the matte surface is darker by that cosine.
    const auto flat = bumped_quad("");
    const float lit = trace_radiance(*s, Vec3(0.2f, 0.1f, 5), Vec3(0, 0, -1), 1, nullptr).r;
    const float plain = trace_radiance(*flat, Vec3(0.2f, 0.1f, 5), Vec3(0, 0, -1), 1, nullptr).r;
    EXPECT_NEAR(lit / plain, 2 / len, 1e-4);
}

TEST(Bump, AConstantOrMissingBumpMapLeavesTheShadingAlone) {
    auto s = bumped_quad("\"float bumpmap\" 0.5");
    EXPECT_LT(s->materials.back().bump.node, 0);
    const auto flat = bumped_quad("");
    EXPECT_EQ(trace_radiance(*s, Vec3(0.2f, 0.1f, 5), Vec3(0, 0, -1), 1, nullptr).r,
              trace_radiance(*flat, Vec3(0.2f, 0.1f, 5), Vec3(0, 0, -1), 1, nullptr).r);
}
