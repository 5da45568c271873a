// pbrt-v3's "curve" shape: its segments as pbrt-v3 makes them, hits with pbrt-v3's (u,v),
// widths and normals, instances, shading without self-shadowing, and the builder's errors.
#include <gtest/gtest.h>

#include <cmath>

#include "expect_throw.h"
#include "render/integrator.h"
#include "scene_util.h"

using namespace cmam;
using render::Primitive;
using render::SurfaceHit;
using render::Vec3;

namespace {
std::unique_ptr<render::Scene> world(const std::string& body) {
    return test::scene_from("Camera \"perspective\" WorldBegin " + body + " WorldEnd");
}
std::optional<SurfaceHit> hit_from_above(const render::Scene& s, float x, float y) {
    return s.intersect(Vec3(x, y, 5), Vec3(0, 0, -1), 0, 1e30f);
}
// A straight cubic along x from -2 to 2 (its control points evenly spaced, so u = (x + 2) / 4),
// 0.4 wide at its start and 0.2 at its end.
const std::string kStraight =
    "\"point P\" [-2 0 0  -0.6666667 0 0  0.6666667 0 0  2 0 0] \"float width0\" 0.4 "
    "\"float width1\" 0.2";
std::vector<std::string> build_warnings(const std::string& body) {
    std::vector<std::string> w;
    render::build_scene(
        pbrt::parse_string("Camera \"perspective\" WorldBegin " + body + " WorldEnd", "c.pbrt"), {},
        [&](const std::string& s) { w.push_back(s); });
    return w;
}
}  // namespace

// pbrt-v3's flat curve: u along the curve, v across it (1/2 on the curve, pbrt-v3's side by
// its edge function), the width interpolated from width0 to width1, dP/du the tangent, and the
// normal cross(dP/du, dP/dv) with dP/dv = normalize(d x dP/du) times the width: along the ray.
TEST(Curve, FlatCurveHitsWithPbrtV3sUvWidthAndNormal) {
    auto s = world("Shape \"curve\" " + kStraight);
    for (float x : {-1.5f, 0.0f, 1.0f}) {
        const float u = (x + 2) / 4, w = 0.4f - 0.2f * u;
        for (float y : {0.0f, 0.3f * w, -0.45f * w}) {
            const std::optional<SurfaceHit> h = hit_from_above(*s, x, y);
            ASSERT_TRUE(h) << x << " " << y;
            EXPECT_NEAR(h->t, 5, 1e-3) << x << " " << y;
            EXPECT_NEAR(h->u, u, 2e-3) << x;
            EXPECT_NEAR(h->v, 0.5f - y / w, 2e-3) << x << " " << y;
            EXPECT_NEAR(h->ng.z, -1, 1e-4);
            EXPECT_EQ(h->ns.z, h->ng.z);
            const render::Partials d = h->partials();
            EXPECT_NEAR(d.dpdu.x, 4, 1e-3);
            EXPECT_NEAR(d.dpdv.y, -w, 1e-3);
        }
        EXPECT_FALSE(hit_from_above(*s, x, 0.55f * w)) << x;  // beyond half the width
    }
    // A ray from the other side: the normal turns with it (along the ray again).
    const std::optional<SurfaceHit> below = s->intersect(Vec3(0, 0, -5), Vec3(0, 0, 1), 0, 1e30f);
    ASSERT_TRUE(below);
    EXPECT_NEAR(below->ng.z, 1, 1e-4);
    // ReverseOrientation flips it, as pbrt-v3 flips every shape's.
    auto r = world("ReverseOrientation Shape \"curve\" " + kStraight);
    EXPECT_NEAR(hit_from_above(*r, 0, 0)->ng.z, 1, 1e-4);
}

// pbrt-v3's cylinder curve is the flat one with dP/dv turned about dP/du by -(v - 1/2) 180
// degrees: the normal (0, -sin theta, -cos theta) here, theta = (v - 1/2) pi.
TEST(Curve, CylinderNormalTurnsAcrossTheWidth) {
    auto s = world("Shape \"curve\" \"string type\" \"cylinder\" " + kStraight);
    const float w = 0.3f;  // at x = 0
    for (float y : {0.0f, 0.2f * w, -0.35f * w}) {
        const std::optional<SurfaceHit> h = hit_from_above(*s, 0, y);
        ASSERT_TRUE(h);
        const float theta = (h->v - 0.5f) * 3.14159265f;
        EXPECT_NEAR(h->v, 0.5f - y / w, 2e-3);
        EXPECT_NEAR(h->ng.x, 0, 1e-4);
        EXPECT_NEAR(h->ng.y, -std::sin(theta), 1e-4) << y;
        EXPECT_NEAR(h->ng.z, -std::cos(theta), 1e-4) << y;
    }
}

// A ribbon is oriented by its normals: seen along them it is as wide as its width, seen
// edge-on it is not there; its normal is the given one (interpolated spherically, as pbrt-v3
// does, between the ends'), flipped to cross(dP/du, dP/dv).
TEST(Curve, RibbonFacesItsNormals) {
    auto s = world("Shape \"curve\" \"string type\" \"ribbon\" \"normal N\" [0 0 1  0 0 1] " +
                   kStraight);
    const std::optional<SurfaceHit> h = hit_from_above(*s, 0, 0.1f);
    ASSERT_TRUE(h);
    EXPECT_NEAR(std::abs(h->ng.z), 1, 1e-4);
    EXPECT_NEAR(h->v, 0.5f - 0.1f / 0.3f, 2e-3);    // v as a flat curve's
    EXPECT_NEAR(h->partials().dpdv.y, 0.3f, 1e-4);  // normalize(n x dP/du) w: +y
    EXPECT_FALSE(s->intersect(Vec3(0, 5, 0.01f), Vec3(0, -1, 0), 0, 1e30f));  // edge-on
    EXPECT_TRUE(s->intersect(Vec3(0, 5, 5), Vec3(0, -1, -1), 0, 1e30f));      // at 45 degrees
    // Normals turning from +z to +y along the curve: halfway the ribbon faces (0, 1, 1).
    const Vec3 mid = render::curve_normal(Vec3(0, 0, 1), Vec3(0, 1, 0), 0.5f);
    EXPECT_NEAR(mid.y, std::sqrt(0.5f), 1e-6);
    EXPECT_NEAR(mid.z, std::sqrt(0.5f), 1e-6);
    auto t = world("Shape \"curve\" \"string type\" \"ribbon\" \"normal N\" [0 0 1  0 1 0] " +
                   kStraight);
    const std::optional<SurfaceHit> m = t->intersect(Vec3(0, 5, 5), Vec3(0, -1, -1), 0, 1e30f);
    ASSERT_TRUE(m);
    EXPECT_NEAR(std::abs(m->ng.y), std::sqrt(0.5f), 1e-3);
    EXPECT_NEAR(std::abs(m->ng.z), std::sqrt(0.5f), 1e-3);
}

// Degree 2 and B-spline curves become cubic Bezier segments as pbrt-v3 makes them: a degree-2
// Bezier raised to degree 3, a uniform cubic B-spline's segment from (p0 + 4 p1 + p2) / 6 to
// (p1 + 4 p2 + p3) / 6; widths go from width0 to width1 over the whole curve, and the
// transform scales them.
TEST(Curve, SegmentsArePbrtV3sCubicBezierSegments) {
    auto pts = [](const render::Scene& s) { return s.primitives.at(0)->curve_points; };
    auto q = world(
        "Shape \"curve\" \"integer degree\" 2 \"point P\" [0 0 0  3 0 0  3 3 0  3 6 0  "
        "0 6 0] \"float width0\" 1 \"float width1\" 0.5");
    ASSERT_EQ(q->primitives.at(0)->curve_first.size(), 2u);
    const auto a = pts(*q);
    EXPECT_FLOAT_EQ(a[1][0], 2);  // (0,0,0) + 2/3 ((3,0,0) - (0,0,0))
    EXPECT_FLOAT_EQ(a[2][0], 3);
    EXPECT_FLOAT_EQ(a[2][1], 1);       // (3,0,0) + 1/3 ((3,3,0) - (3,0,0))
    EXPECT_FLOAT_EQ(a[4][1], 3);       // the second segment starts where the first ends
    EXPECT_FLOAT_EQ(a[0][3], 0.5f);    // radius: half of width0 at the start,
    EXPECT_FLOAT_EQ(a[3][3], 0.375f);  // half of 0.75 at the middle of the curve,
    EXPECT_FLOAT_EQ(a[7][3], 0.25f);   // half of width1 at the end
    auto b = world(
        "Shape \"curve\" \"string basis\" \"bspline\" \"point P\" [0 0 0  6 0 0  6 6 0  "
        "0 6 0  0 12 0]");
    ASSERT_EQ(b->primitives.at(0)->curve_first.size(), 2u);
    const auto c = pts(*b);
    EXPECT_FLOAT_EQ(c[0][0], 5);  // (0 + 24 + 6) / 6
    EXPECT_FLOAT_EQ(c[0][1], 1);
    EXPECT_FLOAT_EQ(c[3][0], 5);  // (6 + 24 + 0) / 6
    EXPECT_FLOAT_EQ(c[3][1], 5);
    EXPECT_FLOAT_EQ(c[4][0], c[3][0]);
    auto scaled = world("Scale 2 2 2 Shape \"curve\" " + kStraight);
    EXPECT_NEAR(scaled->primitives.at(0)->curve_widths[0][0], 0.8f, 1e-6);
    EXPECT_TRUE(hit_from_above(*scaled, 0, 0.25f));  // 0.6 wide there
}

// A curve in an object is hit through each instance as the same curve placed in the world.
TEST(Curve, InstancesHitAsFlattenedCurves) {
    // (A ribbon's width is checked during traversal, in the instance's space.)
    for (const std::string type : {"\"string type\" \"cylinder\" ",
                                   "\"string type\" \"ribbon\" \"normal N\" [0 0.3 1  0.3 0 1] "}) {
        auto flat = world("Translate 1 2 0 Rotate 30 0 0 1 Shape \"curve\" " + type + kStraight);
        auto inst = world("ObjectBegin \"c\" Shape \"curve\" " + type + kStraight +
                          " ObjectEnd AttributeBegin Translate 1 2 0 Rotate 30 0 0 1 "
                          "ObjectInstance \"c\" AttributeEnd");
        int hits = 0;
        for (float x = 0; x < 2; x += 0.1f)
            for (float y = 1.5f; y < 3; y += 0.01f) {
                const std::optional<SurfaceHit> a = hit_from_above(*flat, x, y),
                                                b = hit_from_above(*inst, x, y);
                ASSERT_EQ(a.has_value(), b.has_value()) << type << x << " " << y;
                if (!a) continue;
                ++hits;
                EXPECT_NEAR(a->t, b->t, 1e-4);
                EXPECT_NEAR(a->u, b->u, 1e-4);
                EXPECT_NEAR(a->v, b->v, 1e-3);
                EXPECT_NEAR(dot(a->ng, b->ng), 1, 1e-4);
                EXPECT_NEAR(a->offset, b->offset, 1e-4);
            }
        EXPECT_GT(hits, 100) << type;
    }
}

// Rays leaving a curve start off it by twice its width (pbrt-v3's error bound): a flat curve's
// pieces turn to face every ray, and a shadow ray starting on the curve would meet it again.
// pbrt-v3's bent curve of its figure 3.18, matte, lit by a distant light: wherever a camera ray
// meets it, the light reaches it unshadowed (nothing else is there), Kd / pi * L * |cos| with
// the hit's normal. (Without the offset, 12 to 19 of the 266 hits are shadowed from two of the
// directions.)
TEST(Curve, ShadowRaysLeaveTheCurve) {
    // (A light at grazing angles would let one bend shadow another: these do not.)
    const Vec3 froms[] = {Vec3(-2, 1, -4), Vec3(3, -1, -1), Vec3(0, 2, 1)};
    for (const Vec3& from : froms)
        for (const char* type : {"flat", "cylinder"}) {
            auto s = test::scene_from(
                "Integrator \"whitted\" Camera \"perspective\" WorldBegin LightSource \"distant\" "
                "\"point from\" [" +
                std::to_string(from.x) + " " + std::to_string(from.y) + " " +
                std::to_string(from.z) +
                "] \"point to\" [0 0 0] \"rgb L\" [1 1 1] Material \"matte\" \"rgb Kd\" [0.5 0.5 "
                "0.5] Rotate 45 0 0 1 Shape \"curve\" \"point P\" [-2 -1 -1  2 2 0  -2 -2 0  2 1 "
                "-1] "
                "\"float width0\" 0.35 \"float width1\" 0.15 \"string type\" \"" +
                type + "\" WorldEnd");
            const Vec3 to_light = render::normalize(from);
            int hits = 0, wrong = 0;
            for (int i = 0; i < 60; ++i)
                for (int j = 0; j < 60; ++j) {
                    const Vec3 org(-2 + 4 * (i + 0.5f) / 60, -2 + 4 * (j + 0.5f) / 60, -10);
                    const std::optional<SurfaceHit> h = s->intersect(org, Vec3(0, 0, 1), 0, 1e30f);
                    if (!h) continue;
                    ++hits;
                    // (No light where the normal puts the viewer and the light on its two sides:
                    // the BSDF's reflection test, pbrt-v3's, takes the geometric normal, which a
                    // cylinder curve turns across its width.)
                    const bool reflect =
                        render::dot(to_light, h->ng) * render::dot(Vec3(0, 0, -1), h->ng) > 0;
                    const float expected =
                        reflect ? 0.5f / 3.14159265f * std::abs(render::dot(h->ns, to_light))
                                : 0.0f;
                    const float got = render::trace_radiance(*s, org, Vec3(0, 0, 1), 1, nullptr).r;
                    if (std::abs(got - expected) > 1e-3f + 1e-3f * expected) ++wrong;
                }
            EXPECT_GT(hits, 100) << type;
            EXPECT_EQ(wrong, 0) << type << " " << from.x << " " << from.y << " " << from.z << ": "
                                << wrong << " of " << hits << " hits";
        }
}

TEST(Curve, BadCurvesAreLocatedErrorsAndUnknownTypesCylinders) {
    auto error = [](const std::string& params) {
        return test::thrown_text<pbrt::SceneError>([&] { world("\nShape \"curve\" " + params); });
    };
    EXPECT_EQ(error("\"point P\" [0 0 0  1 0 0  2 0 0  3 0 0  4 0 0]"),
              "t.pbrt:2:15: error: 5 control points: a degree 3 Bezier curve takes 4 + n * 3 of "
              "them");
    EXPECT_EQ(error("\"integer degree\" 4 \"point P\" [0 0 0  1 0 0  2 0 0  3 0 0  4 0 0]"),
              "t.pbrt:2:15: error: curve degree must be 2 or 3, got 4");
    EXPECT_EQ(error("\"string basis\" \"hermite\" \"point P\" [0 0 0  1 0 0  2 0 0  3 0 0]"),
              "t.pbrt:2:15: error: curve basis must be \"bezier\" or \"bspline\", got \"hermite\"");
    EXPECT_EQ(error("\"string type\" \"ribbon\" \"point P\" [0 0 0  1 0 0  2 0 0  3 0 0]"),
              "t.pbrt:2:1: error: a \"ribbon\" curve needs normals \"N\" at its segments' ends");
    EXPECT_EQ(error("\"string type\" \"ribbon\" \"normal N\" [0 0 1] \"point P\" [0 0 0  1 0 0  2 "
                    "0 0  3 0 0]"),
              "t.pbrt:2:38: error: 1 normals: a ribbon curve of 1 segments takes 2, one at each "
              "segment's ends");
    EXPECT_EQ(error("\"float width\" -1 \"point P\" [0 0 0  1 0 0  2 0 0  3 0 0]"),
              "t.pbrt:2:1: error: curve widths must not be negative");
    const auto w = build_warnings(
        "LightSource \"point\" Shape \"curve\" \"string type\" \"round\" " + kStraight);
    ASSERT_EQ(w.size(), 1u) << w[0] << (w.size() > 1 ? w[1] : "");
    EXPECT_NE(w[0].find("unknown curve type \"round\""), std::string::npos) << w[0];
    EXPECT_NE(w[0].find("\"cylinder\" is used"), std::string::npos) << w[0];
    const auto a = build_warnings(
        "LightSource \"point\" AreaLightSource \"diffuse\" Shape \"curve\" " + kStraight);
    ASSERT_EQ(a.size(), 1u);
    EXPECT_NE(a[0].find("does not emit"), std::string::npos) << a[0];
}
