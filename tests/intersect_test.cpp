// Sphere, disk, triangle and PLY intersections with pbrt-v3's (u,v) and normal orientation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "scene_util.h"
#include "temp_dir.h"

using namespace cmam;
using render::SurfaceHit;
using render::Vec3;

namespace {
std::unique_ptr<render::Scene> world(const std::string& body) {
    return test::scene_from("Camera \"perspective\" WorldBegin " + body + " WorldEnd");
}
SurfaceHit hit(const render::Scene& s, Vec3 o, Vec3 d) {
    const std::optional<SurfaceHit> h = s.intersect(o, render::normalize(d), 0, 1e30f);
    EXPECT_TRUE(h.has_value());
    return h.value_or(SurfaceHit{});
}
}  // namespace

TEST(Sphere, UvParameterization) {
    auto s = world("Shape \"sphere\" \"float radius\" 2");
    SurfaceHit h = hit(*s, Vec3(10, 0, 0), Vec3(-1, 0, 0));  // phi = 0, theta = pi/2
    EXPECT_NEAR(h.t, 8, 1e-5);
    EXPECT_NEAR(h.u, 0, 1e-6);
    EXPECT_NEAR(h.v, 0.5, 1e-6);
    EXPECT_NEAR(h.ng.x, 1, 1e-6);                 // outward
    h = hit(*s, Vec3(0, 10, 0), Vec3(0, -1, 0));  // phi = pi/2
    EXPECT_NEAR(h.u, 0.25, 1e-6);
    h = hit(*s, Vec3(0, 0, 10), Vec3(0, 0, -1));  // north pole: v = 1
    EXPECT_NEAR(h.v, 1, 1e-5);
    h = hit(*s, Vec3(0, 0, -10), Vec3(0, 0, 1));  // south pole: v = 0
    EXPECT_NEAR(h.v, 0, 1e-5);
    h = hit(*s, Vec3(10, 0, std::sqrt(2.0f)), Vec3(-1, 0, 0));  // z = r/sqrt2: theta = 45 deg
    EXPECT_NEAR(h.v, 0.75, 1e-5);
}

TEST(Sphere, PartialSphereSkipsTheCutAndShowsTheInside) {
    auto s = world("Shape \"sphere\" \"float radius\" 1 \"float zmax\" 0.5 \"float phimax\" 180");
    SurfaceHit h = hit(*s, Vec3(0.01f, 0.01f, 5), Vec3(0, 0, -1));
    EXPECT_NEAR(h.t, 6, 1e-3);  // the cap above z = 0.5 is gone: hits the far side
    EXPECT_LT(h.ng.z, -0.99f);  // outward normal of the far side, seen from inside
    const std::optional<SurfaceHit> none = s->intersect(Vec3(0, -5, 0), Vec3(0, 1, 0), 0, 1e30f);
    EXPECT_FALSE(none && none->p.y < 0) << "phi > 180 degrees must not be hit";
}

TEST(Sphere, TransformedAndReversed) {
    auto s = world("Translate 0 0 5 Scale 2 2 2 ReverseOrientation Shape \"sphere\"");
    SurfaceHit h = hit(*s, Vec3(0, 0, 0), Vec3(0, 0, 1));
    EXPECT_NEAR(h.t, 3, 1e-5);
    EXPECT_NEAR(h.p.z, 3, 1e-5);
    EXPECT_NEAR(h.ng.z, 1, 1e-6);  // reversed: points inwards (+z at the near pole)
}

TEST(Disk, UvAndNormal) {
    auto s =
        world("Shape \"disk\" \"float radius\" 2 \"float innerradius\" 1 \"float height\" 0.5");
    SurfaceHit h = hit(*s, Vec3(1.5f, 0, 3), Vec3(0, 0, -1));
    EXPECT_NEAR(h.t, 2.5, 1e-5);
    EXPECT_NEAR(h.u, 0, 1e-6);
    EXPECT_NEAR(h.v, 0.5, 1e-6);  // (radius - r) / (radius - innerradius)
    EXPECT_NEAR(h.ng.z, 1, 1e-6);
    EXPECT_FALSE(s->intersect(Vec3(0.5f, 0, 3), Vec3(0, 0, -1), 0, 1e30f));  // inside the hole
}

TEST(Triangle, BarycentricUvAndDefaultUv) {
    auto s = world(
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  4 0 0  0 4 0] \"integer indices\" [0 1 2] "
        "\"point2 uv\" [0.5 0.5  1 0.5  0.5 1]");
    SurfaceHit h = hit(*s, Vec3(1, 1, 5), Vec3(0, 0, -1));
    EXPECT_NEAR(h.u, 0.5 + 0.25 * 0.5, 1e-6);
    EXPECT_NEAR(h.v, 0.5 + 0.25 * 0.5, 1e-6);
    EXPECT_NEAR(std::abs(h.ng.z), 1, 1e-6);
    EXPECT_NEAR(h.ng.z, 1, 1e-6);  // counter-clockwise seen from +z
    auto d = world(
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  4 0 0  4 4 0] \"integer indices\" [0 1 2]");
    h = hit(*d, Vec3(3, 1, 5), Vec3(0, 0, -1));
    // pbrt-v3 default uv (0,0),(1,0),(1,1): u = b1 + b2, v = b2
    EXPECT_NEAR(h.u, 0.75, 1e-6);
    EXPECT_NEAR(h.v, 0.25, 1e-6);
}

TEST(Triangle, ShadingNormalsOrientTheGeometricNormal) {
    auto s = world(
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  4 0 0  0 4 0] \"integer indices\" [0 1 2] "
        "\"normal N\" [0 0 -1  0 0 -1  0 0 -1]");
    SurfaceHit h = hit(*s, Vec3(1, 1, 5), Vec3(0, 0, -1));
    EXPECT_NEAR(h.ns.z, -1, 1e-6);
    EXPECT_NEAR(h.ng.z, -1, 1e-6);
}

TEST(PlyMesh, IntersectsWithItsUv) {
    const test::TempDir dir("cmam_quad");
    const std::filesystem::path p = dir.path / "quad.ply";
    std::ofstream(p)
        << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
           "property float z\nproperty float s\nproperty float t\nelement face 1\n"
           "property list uchar int vertex_indices\nend_header\n"
           "-1 -1 0 0 0\n1 -1 0 1 0\n1 1 0 1 1\n-1 1 0 0 1\n4 0 1 2 3\n";
    auto s = world("Shape \"plymesh\" \"string filename\" \"" + p.string() + "\"");
    SurfaceHit h = hit(*s, Vec3(0.5f, -0.5f, 2), Vec3(0, 0, -1));
    EXPECT_NEAR(h.u, 0.75, 1e-6);
    EXPECT_NEAR(h.v, 0.25, 1e-6);
    EXPECT_NEAR(h.t, 2, 1e-6);
}

TEST(Occlusion, ShadowRaysRespectTheirInterval) {
    auto s = world("Shape \"sphere\"");
    EXPECT_TRUE(s->occluded(Vec3(0, 0, -5), Vec3(0, 0, 1), 0, 10));
    EXPECT_FALSE(s->occluded(Vec3(0, 0, -5), Vec3(0, 0, 1), 0, 3.9f));
    EXPECT_FALSE(s->occluded(Vec3(0, 0, -5), Vec3(0, 1, 0), 0, 100));
}
