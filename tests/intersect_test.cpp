// Sphere, disk, triangle and PLY intersections with pbrt-v3's (u,v) and normal orientation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "render/error.h"
#include "scene_util.h"
#include "temp_dir.h"

using namespace cmam;
using render::SurfaceHit;
using render::Vec3;

namespace {
std::unique_ptr<render::Scene> world(const std::string& body) {
    return test::scene_from("Camera \"perspective\" WorldBegin " + body + " WorldEnd");
}
// The same with its object instances kept as instances (none built in place).
std::unique_ptr<render::Scene> instanced_world(const std::string& body) {
    return test::instanced_scene_from("Camera \"perspective\" WorldBegin " + body + " WorldEnd");
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

// pbrt-v3's triangle takes a given normal's side for the surface's, flipped by ReverseOrientation
// alone: a mirroring transform maps the normal (as a normal) and flips nothing else, whereas a
// mesh without normals, and a quadric, turn with ReverseOrientation xor the mirror.
TEST(Triangle, GivenNormalsFlipForReverseOrientationNotForAMirror) {
    const std::string tri =
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  4 0 0  0 4 0] \"integer indices\" [0 1 2]";
    const std::string up = tri + " \"normal N\" [0 0 1  0 0 1  0 0 1]";
    struct Case {
        const char* prefix;
        const std::string& shape;
        float z;  // the hit's shading normal's z
    };
    // Seen from +z through a mirror in x (Scale -1 1 1), the triangle lies at x <= 0.
    const Case cases[] = {{"", up, 1},
                          {"Scale -1 1 1 ", up, 1},
                          {"ReverseOrientation ", up, -1},
                          {"Scale -1 1 1 ReverseOrientation ", up, -1},
                          {"", tri, 1},
                          {"Scale -1 1 1 ", tri, 1},  // the winding turns, and the flip with it
                          {"ReverseOrientation ", tri, -1},
                          {"Scale -1 1 1 ReverseOrientation ", tri, -1}};
    for (const Case& c : cases) {
        auto s = world(std::string(c.prefix) + c.shape);
        const float x = std::string(c.prefix).find("Scale") != std::string::npos ? -1 : 1;
        SurfaceHit h = hit(*s, Vec3(x, 1, 5), Vec3(0, 0, -1));
        EXPECT_NEAR(h.ns.z, c.z, 1e-6) << c.prefix << c.shape;
        EXPECT_NEAR(h.ng.z, c.z, 1e-6) << c.prefix << c.shape;
    }
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

// Packets of rays (the render loop's camera rays and shadow rays) give what the same rays give
// one by one, through every kind of shape, inside and outside instances (Embree's coherent
// packet traversal of an instanced sphere did not return), and for rays that are not finite.
namespace {
const char* kPacketWorld = R"(
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-4 -4 0 4 -4 0 4 4 0 -4 4 0]
      "point2 uv" [0 0 1 0 1 1 0 1]
  AttributeBegin Translate 0 0 1 Shape "sphere" "float radius" 0.6 AttributeEnd
  AttributeBegin Translate 1.5 0 0.5 Shape "disk" "float radius" 0.5 AttributeEnd
  ObjectBegin "ball" Shape "sphere" "float radius" 0.4 ObjectEnd
  AttributeBegin Translate -1.5 1 0.5 ObjectInstance "ball" AttributeEnd
  AttributeBegin Translate -1.5 -1 0.5 Rotate 30 1 0 0 ObjectInstance "ball" AttributeEnd
)";

// Rays from above towards points around each shape (the sphere, the disk, the two instances,
// the plane) and past the plane's edge, spread by `seed`; ray 5 has a NaN direction.
void packet_rays(Vec3* org, Vec3* dir, int seed) {
    const Vec3 aim[] = {Vec3(0, 0, 1),         Vec3(1.5f, 0, 0.5f), Vec3(-1.5f, 1, 0.5f),
                        Vec3(-1.5f, -1, 0.5f), Vec3(2, 2.5f, 0),    Vec3(5, -5, 0)};
    for (int i = 0; i < render::Scene::kPacketSize; ++i) {
        org[i] = Vec3(0.3f * seed, -0.2f * seed, 6);
        const float a = 0.7f * i + 1.3f * seed, r = 0.12f * ((i + seed) % 5);
        const Vec3 target = aim[(i + seed) % 6] + Vec3(r * std::cos(a), r * std::sin(a), 0);
        dir[i] = render::normalize(target - org[i]);
    }
    dir[5].y = std::numeric_limits<float>::quiet_NaN();
}

void expect_same_hit(const std::optional<SurfaceHit>& a, const std::optional<SurfaceHit>& b,
                     int i) {
    ASSERT_EQ(a.has_value(), b.has_value()) << "ray " << i;
    if (!a) return;
    EXPECT_EQ(a->t, b->t) << "ray " << i;
    EXPECT_EQ(a->prim, b->prim) << "ray " << i;
    EXPECT_EQ(a->instance, b->instance) << "ray " << i;
    EXPECT_EQ(a->object_id, b->object_id) << "ray " << i;
    EXPECT_EQ(a->u, b->u) << "ray " << i;
    EXPECT_EQ(a->v, b->v) << "ray " << i;
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ((&a->p.x)[c], (&b->p.x)[c]) << "ray " << i;
        EXPECT_EQ((&a->ns.x)[c], (&b->ns.x)[c]) << "ray " << i;
        EXPECT_EQ((&a->ng.x)[c], (&b->ng.x)[c]) << "ray " << i;
    }
}
}  // namespace

// Both packet widths (Embree's packets of 16, or two of 8), whichever this processor uses.
TEST(Packets, IntersectPacketGivesTheSingleRaysHits) {
    auto s = instanced_world(kPacketWorld);
    constexpr int N = render::Scene::kPacketSize;
    EXPECT_TRUE(s->packet_width() == 8 || s->packet_width() == 16);
    int hits = 0, quadrics = 0, instanced = 0;
    for (int seed = 0; seed < 16; ++seed) {
        s->set_packet_width(seed % 2 == 0 ? 16 : 8);
        Vec3 org[N], dir[N];
        packet_rays(org, dir, seed / 2);
        // A full packet and partial ones; in packets of 8, 11 rays are a packet of 8 and one
        // of 3, 8 rays one full packet, 6 rays one partial packet.
        for (int n : {N, 11, 8, 6}) {
            std::optional<SurfaceHit> packet[N];
            s->intersect_packet(org, dir, n, packet);
            for (int i = 0; i < n; ++i) {
                const auto single =
                    s->intersect(org[i], dir[i], 0, std::numeric_limits<float>::infinity());
                expect_same_hit(packet[i], single, i);
                hits += single.has_value();
                quadrics += single && single->prim->kind != render::Primitive::Kind::Triangles;
                instanced += single && single->instance;
            }
            EXPECT_FALSE(packet[5].has_value());  // the NaN ray
        }
    }
    EXPECT_THROW(s->set_packet_width(4), render::RenderError);
    // The rays reach every kind of shape (else the comparison would prove little).
    EXPECT_GT(hits, 200);
    EXPECT_GT(quadrics, 10);
    EXPECT_GT(instanced, 2);
}

TEST(Packets, OccludedPacketGivesTheSingleRaysAnswers) {
    auto s = instanced_world(kPacketWorld);
    constexpr int N = render::Scene::kPacketSize;
    int blocked = 0, clear = 0;
    for (int seed = 0; seed < 16; ++seed) {
        s->set_packet_width(seed % 2 == 0 ? 16 : 8);  // as above
        Vec3 org[N], dir[N];
        packet_rays(org, dir, seed / 2);
        float tmax[N];
        for (int i = 0; i < N; ++i) tmax[i] = i % 3 == 0 ? 4.5f : 1e30f;  // some stop short
        tmax[7] = std::numeric_limits<float>::quiet_NaN();
        for (int n : {N, 13}) {
            bool occluded[N];
            s->occluded_packet(org, dir, tmax, n, occluded);
            for (int i = 0; i < n; ++i) {
                EXPECT_EQ(occluded[i], s->occluded(org[i], dir[i], 0, tmax[i])) << "ray " << i;
                (occluded[i] ? blocked : clear) += 1;
            }
            EXPECT_TRUE(occluded[5]);  // not finite: occluded, as occluded() has it
            EXPECT_TRUE(occluded[7]);
        }
    }
    EXPECT_GT(blocked, 100);
    EXPECT_GT(clear, 40);
}

// A quadric's (u,v) left for later and then computed equal the ones computed at once.
TEST(Packets, QuadricUvOnDemandEqualsUvAtOnce) {
    auto s = instanced_world(kPacketWorld);
    int quadrics = 0;
    for (int seed = 0; seed < 8; ++seed) {
        Vec3 org[render::Scene::kPacketSize], dir[render::Scene::kPacketSize];
        packet_rays(org, dir, seed);
        for (int i = 0; i < render::Scene::kPacketSize; ++i) {
            const auto now = s->intersect(org[i], dir[i], 0, 1e30f);
            auto later = s->intersect(org[i], dir[i], 0, 1e30f, false);
            ASSERT_EQ(now.has_value(), later.has_value());
            if (!now) continue;
            const bool quadric = now->prim->kind != render::Primitive::Kind::Triangles;
            EXPECT_EQ(later->uv_pending, quadric);
            quadrics += quadric;
            later->ensure_uv();
            EXPECT_FALSE(later->uv_pending);
            expect_same_hit(later, now, i);
        }
    }
    EXPECT_GT(quadrics, 10);
}

// A scene's only quadric carries a second Embree primitive, a point at the centre of its box
// (so that Embree tests the box); rays through that point, one by one and in packets, find what
// the quadric alone gives: nothing through an annulus's hole, the near side of a sphere.
TEST(LoneQuadric, TheBoxsCentreHoldsNothingButTheShape) {
    constexpr int N = render::Scene::kPacketSize;
    auto annulus =
        world("Shape \"disk\" \"float radius\" 2 \"float innerradius\" 1 \"float height\" 0.5");
    auto ball = world("Translate 0 0 3 Shape \"sphere\" \"float radius\" 0.5");
    Vec3 org[N], dir[N];
    float tmax[N];
    for (int i = 0; i < N; ++i) {  // from around the centre's normal, all through the centre
        org[i] = Vec3(0.2f * (i % 4) - 0.3f, 0.2f * (i / 4) - 0.3f, 8);
        dir[i] = render::normalize(Vec3(0, 0, 0.5f) - org[i]);
        tmax[i] = 1e30f;
    }
    std::optional<SurfaceHit> hits[N];
    bool occluded[N];
    annulus->intersect_packet(org, dir, N, hits);
    annulus->occluded_packet(org, dir, tmax, N, occluded);
    for (int i = 0; i < N; ++i) {
        EXPECT_FALSE(hits[i].has_value()) << "ray " << i;
        EXPECT_FALSE(occluded[i]) << "ray " << i;
        EXPECT_FALSE(annulus->intersect(org[i], dir[i], 0, 1e30f)) << "ray " << i;
        EXPECT_FALSE(annulus->occluded(org[i], dir[i], 0, 1e30f)) << "ray " << i;
    }
    for (int i = 0; i < N; ++i) dir[i] = render::normalize(Vec3(0, 0, 3) - org[i]);
    ball->intersect_packet(org, dir, N, hits);
    for (int i = 0; i < N; ++i) {
        ASSERT_TRUE(hits[i].has_value()) << "ray " << i;
        EXPECT_EQ(hits[i]->prim->kind, render::Primitive::Kind::Sphere);
        EXPECT_NEAR(hits[i]->t, length(Vec3(0, 0, 3) - org[i]) - 0.5f, 1e-4) << "ray " << i;
        EXPECT_NEAR(length(hits[i]->p - (Vec3(0, 0, 3) - 0.5f * dir[i])), 0, 1e-4) << "ray " << i;
    }
}
