// Ray differentials and ray cones against central finite differences of the actual ray tracer
// (camera, intersection, reflection, refraction), plus the numbers of algorithms.md §12
// (T-RD-1, T-RC-1) and the agreement of cones with differentials.
#include "render/footprint/footprint.h"

#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>

#include "render/footprint/cones.h"
#include "render/footprint/differentials.h"
#include "render/integrator.h"
#include "render/shading.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {
// Pinhole at the origin looking down +z, 512x512, 90 degrees: one pixel = 1/256 on the plane z=1.
std::string camera512(const std::string& world) {
    return "LookAt 0 0 0  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 90 "
           "Film \"image\" \"integer xresolution\" 512 \"integer yresolution\" 512 WorldBegin " +
           world + " WorldEnd";
}
void expect_vec(const Vec3& a, const Vec3& b, double tol, const char* what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}
SurfaceHit hit_at(const Scene& s, float px, float py, Vec3* d) {
    const CameraRay r = s.camera.generate_ray(px, py);
    *d = r.dir;
    const std::optional<SurfaceHit> h = s.intersect(r.org, r.dir, 0, 1e30f);
    EXPECT_TRUE(h.has_value());
    return h.value_or(SurfaceHit{});
}
}  // namespace

// A thin-lens camera's differentials are pbrt-v3's: the offset rays leave the same lens point
// (no origin offset) towards the pinhole's offset rays' points on the plane of focus. On a plane
// facing the camera the lens point then cancels: a hit's dP/dx and dP/dy are the pinhole's at
// every depth (the blur comes from the lens samples, not from wider footprints).
TEST(Differentials, ThinLensOffsetRaysMeetThePinholesOnThePlaneOfFocus) {
    const std::string plane =
        "Shape \"trianglemesh\" \"point3 P\" [-100 -100 Z  100 -100 Z  "
        "100 100 Z  -100 100 Z] \"integer indices\" [0 1 2 0 2 3]";
    for (const char* z : {"10", "25"}) {
        SCOPED_TRACE(z);
        std::string w = plane;
        for (std::size_t k; (k = w.find('Z')) != std::string::npos;) w.replace(k, 1, z);
        std::string text = camera512(w);
        text.replace(text.find("\"float fov\" 90"), 14,
                     "\"float fov\" 90 \"float lensradius\" 0.3 \"float focaldistance\" 10");
        auto s = test::scene_from(text);
        ASSERT_TRUE(s->camera.has_lens());
        FootprintMethods methods;
        methods.add(FootprintMethod::Differentials);
        const FootprintProducers producers(methods, s->camera, 1);
        const float px = 300.5f, py = 200.25f, lu = 0.9f, lv = 0.2f;
        const CameraRay lens = s->camera.generate_ray(px, py, lu, lv);
        RayFootprint r;
        producers.start_lens_ray(r, px, py, lu, lv, lens.dir, 0, 0);
        ASSERT_TRUE(r.diff.valid);
        expect_vec(r.diff.dodx, Vec3(0, 0, 0), 0, "dO/dx");
        expect_vec(r.diff.dody, Vec3(0, 0, 0), 0, "dO/dy");
        // Towards the pinhole's offset ray's point on the plane of focus z = 10.
        const CameraRay px1 = s->camera.generate_ray(px + 1, py);
        const Vec3 focus_x = px1.org + px1.dir * (10 / px1.dir.z);
        expect_vec(r.diff.dddx, normalize(focus_x - lens.org) - lens.dir, 1e-6, "dD/dx");
        const std::optional<SurfaceHit> h = s->intersect(lens.org, lens.dir, 0, 1e30f);
        ASSERT_TRUE(h.has_value());
        const HitFootprint at = producers.at_hit(r, lens.dir, *h);
        Vec3 d;
        const SurfaceHit hp = hit_at(*s, px, py, &d);
        const HitFootprint pin = producers.at_hit(producers.camera_ray(px, py, d, {}, 0, 0), d, hp);
        expect_vec(at.dpdx, pin.dpdx, 2e-4, "dP/dx");
        expect_vec(at.dpdy, pin.dpdy, 2e-4, "dP/dy");
    }
}

TEST(Differentials, TRd1CameraDerivativeAndFrontoParallelTransfer) {
    auto s = test::scene_from(camera512(
        "Shape \"trianglemesh\" \"point3 P\" [-100 -100 10  100 -100 10  100 100 10  -100 100 10] "
        "\"integer indices\" [0 1 2 0 2 3]"));
    RayDifferential rd = camera_differential(s->camera, 384, 256, 1);
    expect_vec(rd.dddx, Vec3(0.00279508f, 0, -0.00139754f), 1e-7, "dD/dx");
    Vec3 d;
    for (auto [px, py] : {std::pair{384.0f, 256.0f}, std::pair{10.5f, 400.25f}}) {
        SurfaceHit h = hit_at(*s, px, py, &d);
        HitDifferential hd = transfer(camera_differential(s->camera, px, py, 1), d, h);
        ASSERT_TRUE(hd.valid);
        expect_vec(hd.dpdx, Vec3(0.0390625f, 0, 0), 1e-6, "dP/dx");
        expect_vec(hd.dpdy, Vec3(0, -0.0390625f, 0), 1e-6, "dP/dy (raster y points down)");
    }
}

// The packet's camera rays, made four at a time (perspective_rays), against
// perspective_direction and camera_differential ray by ray: every component bit for bit, for every
// batch size up to 16 (whole groups of four and the rest), on an oblique camera with a non-square
// film.
TEST(Differentials, CameraRaysMadeTogetherEqualOneByOne) {
    auto s = test::scene_from(
        "LookAt 0.3 1.6 -6  0.5 0.8 4  0.1 1 0 Camera \"perspective\" \"float fov\" 37 "
        "Film \"image\" \"integer xresolution\" 641 \"integer yresolution\" 397 WorldBegin "
        "WorldEnd");
    const CameraSteps steps = camera_steps(s->camera);
    const float scale = 0.25f;
    uint32_t state = 12345;
    auto next = [&state] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    for (int n = 1; n <= CameraRayBatch::kMax; ++n) {
        float fx[CameraRayBatch::kMax], fy[CameraRayBatch::kMax];
        for (int i = 0; i < n; ++i) {
            fx[i] = next() * 641;
            fy[i] = next() * 397;
        }
        CameraRayBatch batch;
        perspective_rays(steps, fx, fy, n, scale, batch);
        for (int i = 0; i < n; ++i) {
            Vec3 dir;
            const float inv_len = perspective_direction(steps, fx[i], fy[i], dir);
            RayDifferential rd;
            camera_differential(steps, dir, inv_len, scale, rd);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(batch.dir[c][i], dir[c]) << "n " << n << " ray " << i;
                EXPECT_EQ(batch.dddx[c][i], rd.dddx[c]) << "n " << n << " ray " << i;
                EXPECT_EQ(batch.dddy[c][i], rd.dddy[c]) << "n " << n << " ray " << i;
            }
        }
    }
}

TEST(Differentials, UvDerivativesMatchFiniteDifferencesOnATiltedPlaneAndASphere) {
    for (const char* shape :
         {"Translate 0 0 10 Rotate 60 1 0 0 Shape \"trianglemesh\" \"point3 P\" [-8 -8 0  8 -8 0  "
          "8 8 0  -8 8 0] "
          "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 4 0 4 4 0 4]",
          "Translate 0.3 -0.2 4 Rotate 30 1 1 0 Shape \"sphere\" \"float radius\" 1.5"}) {
        auto s = test::scene_from(camera512(shape));
        for (auto [px, py] : {std::pair{300.0f, 200.0f}, std::pair{250.0f, 280.0f}}) {
            Vec3 d;
            SurfaceHit h = hit_at(*s, px, py, &d);
            HitDifferential hd = transfer(camera_differential(s->camera, px, py, 1), d, h);
            ASSERT_TRUE(hd.valid);
            const float e = 0.05f;
            Vec3 dd;
            SurfaceHit xp = hit_at(*s, px + e, py, &dd), xm = hit_at(*s, px - e, py, &dd);
            SurfaceHit yp = hit_at(*s, px, py + e, &dd), ym = hit_at(*s, px, py - e, &dd);
            double tol = 2e-3 * (std::abs(hd.dudx) + std::abs(hd.dvdx) + std::abs(hd.dudy) +
                                 std::abs(hd.dvdy)) +
                         1e-6;
            EXPECT_NEAR(hd.dudx, (xp.u - xm.u) / (2 * e), tol) << shape;
            EXPECT_NEAR(hd.dvdx, (xp.v - xm.v) / (2 * e), tol) << shape;
            EXPECT_NEAR(hd.dudy, (yp.u - ym.u) / (2 * e), tol) << shape;
            EXPECT_NEAR(hd.dvdy, (yp.v - ym.v) / (2 * e), tol) << shape;
            expect_vec(hd.dpdx, (xp.p - xm.p) / (2 * e), 2e-3 * length(hd.dpdx) + 1e-6, "dP/dx");
        }
    }
}

// A textured mesh's triangles carry their (u,v) gradients, made once at commit in double; a hit's
// (u,v) offsets from them equal the barycentric basis's per hit (the path of an untextured mesh)
// to float rounding, on a tilted, irregular mesh with skewed (u,v).
TEST(Differentials, TriangleUvGradientsEqualThePerHitBasis) {
    auto s =
        test::scene_from(camera512("Texture \"checks\" \"spectrum\" \"checkerboard\" "
                                   "Material \"matte\" \"texture Kd\" \"checks\" "
                                   "Translate 0.5 -0.3 9 Rotate 50 1 0.3 0 Shape \"trianglemesh\" "
                                   "\"point3 P\" [-7 -6 0  8 -8 1  6 7 -0.5  -8 6 0.5  0.5 0.2 2] "
                                   "\"integer indices\" [0 1 4 1 2 4 2 3 4 3 0 4] "
                                   "\"point2 uv\" [0 0  5 0.5  4.5 6  -0.5 4  2.2 3.1]"));
    int hits = 0;
    for (float py = 140.5f; py < 400; py += 37)
        for (float px = 120.25f; px < 420; px += 41) {
            const CameraRay r = s->camera.generate_ray(px, py);
            const std::optional<SurfaceHit> h = s->intersect(r.org, r.dir, 0, 1e30f);
            if (!h) continue;
            ++hits;
            ASSERT_FALSE(h->prim->uv_gradients.empty());
            const Vec3& d = r.dir;
            const RayDifferential rd = camera_differential(s->camera, px, py, 1);
            const HitDifferential with = transfer(rd, d, *h);
            Primitive plain = *h->prim;
            plain.uv_gradients.clear();
            SurfaceHit h2 = *h;
            h2.prim = &plain;
            const HitDifferential without = transfer(rd, d, h2);
            ASSERT_TRUE(with.valid && without.valid);
            const double tol = 1e-5 * (std::abs(without.dudx) + std::abs(without.dvdx) +
                                       std::abs(without.dudy) + std::abs(without.dvdy));
            EXPECT_NEAR(with.dudx, without.dudx, tol) << px << " " << py;
            EXPECT_NEAR(with.dvdx, without.dvdx, tol) << px << " " << py;
            EXPECT_NEAR(with.dudy, without.dudy, tol) << px << " " << py;
            EXPECT_NEAR(with.dvdy, without.dvdy, tol) << px << " " << py;
        }
    EXPECT_GT(hits, 20);
}

// A triangle given the same normal at its three vertices (a flat face with normals, as
// exporters write them) has a constant normal: its offsets are exactly zero, however the normal
// leans from the face's. With normals that vary they are not.
TEST(Differentials, OneNormalAtEveryVertexHasNoNormalOffsets) {
    const std::string mesh =
        "Material \"glass\" Translate 0.5 -0.3 9 Rotate 50 1 0.3 0 Shape \"trianglemesh\" "
        "\"point3 P\" [-7 -6 0  8 -8 1  6 7 -0.5  -8 6 0.5  0.5 0.2 2] "
        "\"integer indices\" [0 1 4 1 2 4 2 3 4 3 0 4] \"normal N\" ";
    auto one = test::scene_from(
        camera512(mesh + "[0.2 -0.1 1  0.2 -0.1 1  0.2 -0.1 1  0.2 -0.1 1  0.2 -0.1 1]"));
    auto varied = test::scene_from(
        camera512(mesh + "[-0.5 -0.4 1  0.6 -0.5 1  0.4 0.7 1  -0.6 0.3 1  0.1 0 1]"));
    int hits = 0;
    for (float py = 140.5f; py < 400; py += 37)
        for (float px = 120.25f; px < 420; px += 41) {
            Vec3 d;
            const CameraRay r = one->camera.generate_ray(px, py);
            if (!one->intersect(r.org, r.dir, 0, 1e30f)) continue;
            ++hits;
            for (const Scene* s : {one.get(), varied.get()}) {
                const SurfaceHit h = hit_at(*s, px, py, &d);
                const HitDifferential hd =
                    transfer(camera_differential(s->camera, px, py, 1), d, h);
                ASSERT_TRUE(hd.valid);
                Vec3 dnx, dny;
                h.normal_offsets(hd.dpdx, hd.dpdy, dnx, dny);
                if (s == one.get()) {
                    EXPECT_EQ(length(dnx), 0.0f) << px << " " << py;
                    EXPECT_EQ(length(dny), 0.0f) << px << " " << py;
                } else {
                    EXPECT_GT(length(dnx), 1e-4f) << px << " " << py;
                    EXPECT_GT(length(dny), 1e-4f) << px << " " << py;
                }
            }
        }
    EXPECT_GT(hits, 20);
}

namespace {
// Direction of the reflected or refracted ray through raster (px, py), as the integrator makes it.
Vec3 secondary(const Scene& s, float px, float py, bool refracted, float eta,
               SurfaceHit* out = nullptr) {
    Vec3 d;
    SurfaceHit h = hit_at(s, px, py, &d);
    if (out) *out = h;
    Vec3 wo = -d, n = h.ns;
    if (!refracted) return -wo + 2 * dot(wo, n) * n;
    const std::optional<Vec3> wt = render::refract(wo, faceforward(n, wo), eta);
    EXPECT_TRUE(wt.has_value());
    return wt.value_or(Vec3{});
}
}  // namespace

TEST(Differentials, ReflectionAndRefractionMatchFiniteDifferencesOnASphere) {
    auto s = test::scene_from(camera512("Translate 0 0 5 Shape \"sphere\""));
    for (bool refracted : {false, true}) {
        const float px = 281.6f, py = 268.8f, eta = 1 / 1.5f;
        SurfaceHit h;
        Vec3 d;
        h = hit_at(*s, px, py, &d);
        RayDifferential cam = camera_differential(s->camera, px, py, 1);
        HitDifferential hd = transfer(cam, d, h);
        RayDifferential out =
            refracted ? render::refract(cam, hd, d, h, eta) : render::reflect(cam, hd, d, h);
        ASSERT_TRUE(out.valid);
        const float e = 0.02f;
        Vec3 fx = (secondary(*s, px + e, py, refracted, eta) -
                   secondary(*s, px - e, py, refracted, eta)) /
                  (2 * e);
        Vec3 fy = (secondary(*s, px, py + e, refracted, eta) -
                   secondary(*s, px, py - e, refracted, eta)) /
                  (2 * e);
        expect_vec(out.dddx, fx, 2e-3 * length(fx) + 2e-6, refracted ? "dT/dx" : "dR/dx");
        expect_vec(out.dddy, fy, 2e-3 * length(fy) + 2e-6, refracted ? "dT/dy" : "dR/dy");
    }
    // T-RD-3: the reflection at d ~ (0.1, 0.05, 1) (raster y grows downwards here, so the
    // doc's y = 268.8 is 243.2 in raster), unit sphere at (0,0,5).
    Vec3 d;
    SurfaceHit h = hit_at(*s, 281.6f, 243.2f, &d);
    expect_vec(h.p, Vec3(0.411194f, 0.205597f, 4.111941f), 2e-5, "P");
    RayDifferential cam = camera_differential(s->camera, 281.6f, 243.2f, 1);
    HitDifferential hd = transfer(cam, d, h);
    expect_vec(hd.dpdx, Vec3(0.0168517f, 0.00039471f, 0.0078941f), 2e-6, "T-RD-3 dP/dx");
    expect_vec(render::reflect(cam, hd, d, h).dddx, Vec3(0.0224455f, -0.0040737f, 0.0330926f), 2e-6,
               "T-RD-3 dR/dx");
    expect_vec(render::refract(cam, hd, d, h, 1 / 1.5f).dddx,
               Vec3(-0.00501599f, -0.00079384f, -0.00047737f), 2e-6, "T-RD-4 dT/dx");
}

TEST(Cones, TRc1AndAgreementWithDifferentialsOnAFrontoParallelPlane) {
    // Plane z = 10 mapping 4 world units to 1 uv; a 1024^2 texture: 10 texels per pixel.
    auto s = test::scene_from(camera512(
        "Shape \"trianglemesh\" \"point3 P\" [-100 -100 10  100 -100 10  100 100 10  -100 100 10] "
        "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 50 0 50 50 0 50]"));
    RayCone c = camera_cone(s->camera, 1);
    EXPECT_NEAR(c.spread, std::atan(1.0 / 256) * 1.0, 1e-7);  // 2 atan(1/512) ~ atan(1/256)
    Vec3 d;
    SurfaceHit h = hit_at(*s, 256, 256, &d);
    EXPECT_NEAR(cone_width_at(c, h.t), 0.0390624, 1e-6);
    float w = cone_uv_width(c, d, h);
    EXPECT_NEAR(std::log2(w * 1024), std::log2(10.0), 1e-4);
    HitDifferential hd = transfer(camera_differential(s->camera, 256, 256, 1), d, h);
    EXPECT_NEAR(w, std::hypot(hd.dudx, hd.dvdx), 1e-4 * w);
    const texture::Footprint ax = cone_uv_axes(c, d, h);
    EXPECT_NEAR(std::hypot(ax.axis_a.u, ax.axis_a.v), w, 1e-3 * w);
    EXPECT_NEAR(std::hypot(ax.axis_b.u, ax.axis_b.v), w, 1e-3 * w);
}

TEST(Cones, AnisotropicAxesFollowDifferentialsOnATiltedPlane) {
    // T-RD-2 / T-RC-1: plane through (0,0,10), normal (0, -sin60, -cos60), uv = 1/4 per unit.
    auto s = test::scene_from(
        camera512("Translate 0 0 10 Rotate -60 1 0 0 Shape \"trianglemesh\" \"point3 P\" [-40 -40 "
                  "0  40 -40 0  40 40 0  -40 40 0] "
                  "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 20 0 20 20 0 20]"));
    Vec3 d;
    SurfaceHit h = hit_at(*s, 300, 312, &d);
    HitDifferential hd = transfer(camera_differential(s->camera, 300, 312, 1), d, h);
    const texture::Footprint ax = cone_uv_axes(camera_cone(s->camera, 1), d, h);
    const double la = std::hypot(ax.axis_a.u, ax.axis_a.v),
                 lb = std::hypot(ax.axis_b.u, ax.axis_b.v);
    double cone_major = std::max(la, lb) * 1024;
    double cone_minor = std::min(la, lb) * 1024;
    double diff_x = std::hypot(hd.dudx, hd.dvdx) * 1024,
           diff_y = std::hypot(hd.dudy, hd.dvdy) * 1024;
    double diff_major = std::max(diff_x, diff_y), diff_minor = std::min(diff_x, diff_y);
    EXPECT_NEAR(cone_major / diff_major, 1.0, 0.1) << cone_major << " vs " << diff_major;
    EXPECT_NEAR(cone_minor / diff_minor, 1.0, 0.1) << cone_minor << " vs " << diff_minor;
    float iso = cone_uv_width(camera_cone(s->camera, 1), d, h) * 1024;
    EXPECT_NEAR(std::log2(iso), std::log2(diff_major), 0.3);  // T-RC-1: within about 0.3 levels
}

TEST(Cones, ReflectionOffAConvexMirrorSpreadsTheCone) {
    auto s = test::scene_from(camera512("Translate 0 0 5 Shape \"sphere\""));
    Vec3 d;
    SurfaceHit h = hit_at(*s, 270, 250, &d);
    EXPECT_NEAR(surface_curvature(h), 1.0, 1e-4);
    RayCone c = camera_cone(s->camera, 1);
    RayCone r = reflect_cone(c, d, h);
    EXPECT_GT(r.spread, c.spread);
    EXPECT_NEAR(r.width, cone_width_at(c, h.t), 1e-7);
    RayCone t = refract_cone(c, d, h, 1 / 1.5f);
    EXPECT_TRUE(std::isfinite(t.spread) && std::isfinite(t.width));
    EXPECT_GT(std::abs(t.width), 0);
}

// A sphere that its transform keeps round has curvature 1 / (radius x scale) everywhere (near
// the pole facing the camera too), and in an instance over the instance's scale as well; a
// squashed one takes the general path.
TEST(Cones, ARoundSphereHasOneCurvatureEverywhere) {
    auto s = test::scene_from(
        camera512("Translate 0 0 5 Scale 2 2 2 Shape \"sphere\" \"float radius\" 0.5"));
    EXPECT_DOUBLE_EQ(s->primitives[0]->uniform_scale, 2);
    for (auto [px, py] : {std::pair{256.3f, 256.2f}, std::pair{270.0f, 250.0f},
                          std::pair{290.0f, 270.0f}, std::pair{256.0f, 300.0f}}) {
        Vec3 d;
        const SurfaceHit h = hit_at(*s, px, py, &d);
        EXPECT_NEAR(surface_curvature(h), 1.0, 1e-6) << px << ", " << py;
    }
    auto inst = test::instanced_scene_from(
        camera512("ObjectBegin \"b\" Scale 2 2 2 Shape \"sphere\" \"float radius\" 0.5 ObjectEnd "
                  "Translate 0 0 5 Scale 0.75 0.75 0.75 ObjectInstance \"b\""));
    Vec3 d;
    SurfaceHit h = hit_at(*inst, 262, 251, &d);
    ASSERT_NE(h.instance, nullptr);
    EXPECT_NEAR(surface_curvature(h), 1 / 0.75, 1e-5);
    auto squashed = test::scene_from(camera512("Translate 0 0 5 Scale 1 1 2 Shape \"sphere\""));
    EXPECT_EQ(squashed->primitives[0]->uniform_scale, 0);
    h = hit_at(*squashed, 270, 250, &d);
    const float k = surface_curvature(h);
    // An ellipsoid of radii 1, 1 and 2: its curvatures lie between 1/4 and 2.
    EXPECT_TRUE(std::isfinite(k) && k > 0.25f && k < 2) << k;
    // A round sphere squashed by its instance's transform is that ellipsoid too.
    auto squashed_instance =
        test::instanced_scene_from(camera512("ObjectBegin \"b\" Shape \"sphere\" ObjectEnd "
                                             "Translate 0 0 5 Scale 1 1 2 ObjectInstance \"b\""));
    h = hit_at(*squashed_instance, 270, 250, &d);
    ASSERT_NE(h.instance, nullptr);
    EXPECT_FALSE(h.instance->uniform);
    EXPECT_NEAR(surface_curvature(h), k, 1e-4 * k);
}

// The producers run only for the methods a scene uses, and each event hands on the state a
// child ray needs: its own differential and cone, the level one deeper, the path extended.
TEST(FootprintProducers, RunOnlyTheMethodsUsedAndCarryTagAndPath) {
    auto s = test::scene_from(
        camera512("Shape \"sphere\" \"float radius\" 1000 Translate 0 0 10 Shape \"trianglemesh\" "
                  "\"point3 P\" [-100 -100 0  100 -100 0  100 100 0  -100 100 0] "
                  "\"integer indices\" [0 1 2 0 2 3]"));
    Vec3 d;
    const SurfaceHit h = hit_at(*s, 300, 200, &d);
    texture::RayTag tag;
    tag.id = 7;
    tag.seq = 3;
    for (FootprintMethod m : {FootprintMethod::None, FootprintMethod::Differentials,
                              FootprintMethod::Cones, FootprintMethod::ConesAniso}) {
        SCOPED_TRACE(std::string(to_string(m)));
        FootprintMethods methods;
        methods.add(m);
        const FootprintProducers producers(methods, s->camera, 4);
        const RayFootprint camera = producers.camera_ray(300, 200, d, tag, 0.25f, -0.5f);
        EXPECT_EQ(camera.diff.valid, m == FootprintMethod::Differentials);
        EXPECT_FLOAT_EQ(camera.cone.spread, camera_cone(s->camera, 0.5f).spread);
        const HitFootprint at = producers.at_hit(camera, d, h);
        using Kind = texture::Footprint::Kind;
        EXPECT_EQ(at.axes.valid, m == FootprintMethod::Differentials);
        EXPECT_EQ(at.cone_aniso.valid, m == FootprintMethod::ConesAniso);
        EXPECT_EQ(at.of(m).kind == Kind::Axes, m != FootprintMethod::None);
        EXPECT_EQ(at.of(FootprintMethod::Cmam).kind, Kind::None);
        EXPECT_EQ(at.tag.id, 7u);
        if (m == FootprintMethod::Differentials) {
            // The stratum offset is the screen offset (0.25, -0.5) mapped by the Jacobian.
            const HitDifferential& hd = at.diff;
            EXPECT_NEAR(at.stratum_offset.u, hd.dudx * 0.25 - hd.dudy * 0.5, 1e-9);
            EXPECT_NEAR(at.stratum_offset.v, hd.dvdx * 0.25 - hd.dvdy * 0.5, 1e-9);
            EXPECT_NE(dot(at.dpdx, at.dpdx), 0);
        } else
            EXPECT_EQ(dot(at.dpdx, at.dpdx), 0);

        const RayFootprint refl = producers.reflected(camera, at, d, h);
        const RayFootprint refr = producers.refracted(camera, at, d, h, 1 / 1.5f);
        const RayFootprint through = producers.passed_through(camera, at, h);
        EXPECT_EQ(refl.path, 2u);
        EXPECT_EQ(refr.path, 3u);
        EXPECT_EQ(through.path, 1u);
        EXPECT_EQ(producers.reflected(refr, at, d, h).path, 6u);
        EXPECT_EQ(refl.tag.level, 1u);
        EXPECT_EQ(refr.tag.level, 1u);
        EXPECT_EQ(through.tag.level, 0u);
        EXPECT_EQ(refl.tag.seq, 3u);
        EXPECT_FLOAT_EQ(refl.to_stratum_y, -0.5f);
        EXPECT_EQ(refl.diff.valid, m == FootprintMethod::Differentials);
        const bool cones = m == FootprintMethod::Cones || m == FootprintMethod::ConesAniso;
        EXPECT_EQ(refl.cone.width != 0, cones);  // the cone's width at the hit, carried on
        EXPECT_FLOAT_EQ(through.cone.width, cone_width_at(camera.cone, h.t));
    }
}

// With `cone_strata` (an area-filtered texture reads cones), a camera ray's first hit maps its
// offset to the stratum's centre into (u,v) as the differentials do there, and only there: the
// cone itself, the hit's own differential and every child are as without it.
TEST(FootprintProducers, ConeStrataCentreTheFirstHitOnly) {
    auto s = test::scene_from(
        camera512("Translate 0 0 10 Rotate 50 1 0 0 Shape \"trianglemesh\" "
                  "\"point3 P\" [-100 -100 0  100 -100 0  100 100 0  -100 100 0] "
                  "\"point2 uv\" [0 0 1 0 1 1 0 1] \"integer indices\" [0 1 2 0 2 3]"));
    Vec3 d;
    const SurfaceHit h = hit_at(*s, 300, 200, &d);
    FootprintMethods diff_only, aniso;
    diff_only.add(FootprintMethod::Differentials);
    aniso.add(FootprintMethod::ConesAniso);
    const FootprintProducers differentials(diff_only, s->camera, 4), plain(aniso, s->camera, 4),
        strata(aniso, s->camera, 4, true);
    EXPECT_FALSE(plain.differentials());
    EXPECT_TRUE(strata.differentials());
    const texture::RayTag tag;
    const RayFootprint cd = differentials.camera_ray(300, 200, d, tag, 0.25f, -0.5f),
                       cp = plain.camera_ray(300, 200, d, tag, 0.25f, -0.5f),
                       cs = strata.camera_ray(300, 200, d, tag, 0.25f, -0.5f);
    EXPECT_FALSE(cp.diff.valid);
    ASSERT_TRUE(cs.diff.valid);
    const HitFootprint ad = differentials.at_hit(cd, d, h), ap = plain.at_hit(cp, d, h),
                       as = strata.at_hit(cs, d, h);
    // The same transfer as the differentials' own: the same offset, bit for bit, and not zero.
    EXPECT_EQ(as.stratum_offset.u, ad.stratum_offset.u);
    EXPECT_EQ(as.stratum_offset.v, ad.stratum_offset.v);
    EXPECT_NE(as.stratum_offset.u * as.stratum_offset.u + as.stratum_offset.v * as.stratum_offset.v,
              0);
    EXPECT_EQ(ap.stratum_offset.u, 0);
    EXPECT_EQ(ap.stratum_offset.v, 0);
    // Nothing else changes: the cone's axes, no differential or dP/dx at the hit.
    EXPECT_EQ(as.cone_aniso.a.u, ap.cone_aniso.a.u);
    EXPECT_EQ(as.cone_aniso.b.v, ap.cone_aniso.b.v);
    EXPECT_FALSE(as.diff.valid);
    EXPECT_FALSE(as.axes.valid);
    EXPECT_EQ(dot(as.dpdx, as.dpdx), 0);
    // A child carries no differential, so its hit has no offset; nor does a hit without (u,v).
    const RayFootprint refl = strata.reflected(cs, as, d, h);
    EXPECT_FALSE(refl.diff.valid);
    const HitFootprint next = strata.at_hit(refl, d, h);
    EXPECT_EQ(next.stratum_offset.u, 0);
    EXPECT_EQ(next.stratum_offset.v, 0);
    EXPECT_EQ(strata.at_hit(cs, d, h, false).stratum_offset.u, 0);
    EXPECT_FALSE(strata.passed_through(cs, as, h).diff.valid);
    // Without cones the flag does nothing.
    const FootprintProducers none_strata(diff_only, s->camera, 4, true);
    EXPECT_EQ(none_strata.at_hit(cd, d, h).stratum_offset.u, ad.stratum_offset.u);
}

TEST(Checkerboard, ClosedFormAveragesUnderALargeFootprint) {
    auto s = test::scene_from(
        "Camera \"perspective\" WorldBegin Texture \"c\" \"spectrum\" \"checkerboard\" "
        "\"rgb tex1\" [1 1 1] \"rgb tex2\" [0 0 0] \"float uscale\" 8 \"float vscale\" 8 Material "
        "\"matte\" "
        "\"texture Kd\" \"c\" Shape \"sphere\" WorldEnd");
    TexInput in{0, {}};
    TexContext ctx;
    ctx.u = 0.3f;
    ctx.v = 0.3f;
    EXPECT_EQ(eval_texture(*s, in, ctx).r,
              1.0f);  // no footprint: point sample of check (2,2): tex1
    ctx.footprints.axes = {{0.5, 0}, {0, 0.5}, true};  // 4 checks wide
    EXPECT_NEAR(eval_texture(*s, in, ctx).r, 0.5, 1e-6);
    ctx.footprints.axes = {{0.001, 0}, {0, 0.001}, true};  // inside one check
    EXPECT_EQ(eval_texture(*s, in, ctx).r, 1.0f);
}

namespace {
// The plane z = 10 of camera512, 200 units square with (u,v) 0..50, matte, under a distant
// light, its Kd the image texture "b" (brick.png, 512^2) with the imagemap parameters `params`.
std::unique_ptr<Scene> textured_plane(const std::string& params) {
    const std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/brick.png";
    return test::scene_from(
        camera512("Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + tex + "\" " +
                  params +
                  " Material \"matte\" \"texture Kd\" \"b\" LightSource \"distant\" "
                  "Shape \"trianglemesh\" \"point3 P\" [-100 -100 10  100 -100 10  100 100 10  "
                  "-100 100 10] "
                  "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 50 0 50 50 0 50]"),
        "t.pbrt", 1);
}
// The footprint AOV of pixels 250-261 x 250-251.
Framebuffer footprint_aov(Scene& s) {
    s.film.x0 = 250;
    s.film.x1 = 262;
    s.film.y0 = 250;
    s.film.y1 = 252;
    RenderOptions o;
    o.aov = AovKind::Footprint;
    return render::render(s, o, nullptr);
}
}  // namespace

TEST(Aov, FootprintAndTextureOfAFrontoParallelPlane) {
    // 512x512 pixels, plane z = 10: one pixel covers 0.0390625 world units = 5 texels of a
    // 512^2 texture that spans 4 units.
    auto s = textured_plane("");
    Framebuffer fp = footprint_aov(*s);
    ASSERT_EQ(fp.channel_names, (std::vector<std::string>{"major", "minor", "lambda"}));
    for (std::size_t p = 0; p < fp.rgb.size() / 3; ++p) {
        EXPECT_NEAR(fp.rgb[3 * p], 5.0, 0.01);
        EXPECT_NEAR(fp.rgb[3 * p + 1], 5.0, 0.01);
        EXPECT_NEAR(fp.rgb[3 * p + 2], std::log2(5.0), 0.01);  // EWA: level of the minor axis
    }
    RenderOptions o;
    o.aov = AovKind::Texture;
    Framebuffer tx = render::render(*s, o, nullptr);
    Framebuffer lit = render::render(*s, {}, nullptr);
    // Unlit: the lit value is Kd/pi * L * cos = Kd/pi here (distant light along +z, L = 1).
    for (std::size_t i = 0; i < tx.rgb.size(); ++i)
        EXPECT_NEAR(lit.rgb[i], tx.rgb[i] / 3.14159265f, 1e-5);
}

namespace {
// The largest region the CMAM builds (the footprint AOV's major axis, texels) on pixels
// 241-271 x 251-253 of camera512's `world` at 1 spp (rows with a row above, each pixel with one
// to its left), under the 1-D or the 2-D CMAM: a vertical seam through the image's centre
// crosses them.
double largest_region_across_seam(const std::string& world, bool two_d) {
    const pbrt::SceneDesc d = pbrt::parse_string(camera512(world), "t.pbrt");
    BuildOptions bo;
    bo.spp_override = 1;
    bo.cmam.two_d = two_d;
    auto s = build_scene(d, bo, {});
    s->film.x0 = 240;
    s->film.x1 = 272;
    s->film.y0 = 250;
    s->film.y1 = 254;
    RenderOptions o;
    o.aov = AovKind::Footprint;
    const Framebuffer fp = render::render(*s, o, nullptr);
    const int w = s->film.x1 - s->film.x0;
    double largest = 0;
    for (int y = 1; y < s->film.y1 - s->film.y0; ++y)
        for (int x = 1; x < w; ++x) largest = std::max<double>(largest, fp.rgb[3 * (y * w + x)]);
    return largest;
}
}  // namespace

TEST(Aov, TheCmamTakesAClosedQuadricsSeamTheShortWay) {
    // A whole sphere's u is a longitude. Seen with its seam (u = 0 and 1) facing the camera, a
    // vertical line through the image's centre, the CMAM's neighbours across it are a small step
    // apart the short way round, not a whole texture apart: the regions it builds (the footprint
    // AOV) along rows crossing the seam stay as small as their neighbours', under the 1-D and
    // the 2-D CMAM and at any uscale (the period in s). Without the wrap they span the texture.
    const std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/brick.png";
    for (const bool two_d : {false, true})
        for (const char* uscale : {"1", "3"}) {
            SCOPED_TRACE(two_d ? "2-D" : "1-D");
            SCOPED_TRACE(uscale);
            const double largest = largest_region_across_seam(
                "Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + tex +
                    "\" \"string lod\" \"cmam\" \"float uscale\" " + uscale +
                    " Material \"matte\" \"texture Kd\" \"b\" LightSource \"distant\" "
                    "AttributeBegin Translate 0 0 5 Rotate 90 0 1 0 Rotate -90 1 0 0 "
                    "Shape \"sphere\" \"float radius\" 2 AttributeEnd",
                two_d);
            // About one texel a pixel at uscale 1 (the sphere's 12.6 units of longitude over 512
            // texels, seen 3 units away at 512 pixels for 90 degrees), three at uscale 3.
            EXPECT_GT(largest, 0.5);
            EXPECT_LT(largest, 8.0);
        }
}

namespace {
// A band of `columns` quads round the y axis (radius 2, centre z = 5, y from -3 to 3) in the
// world of camera512, column i from longitude 2 pi i / columns (0: the point nearest the
// camera), its (u,v) i / columns and 0..1: the last column's far edge has the first one's
// positions with u = 1, so the band's unwrapping meets itself at the front, a seam down the
// image's centre. `offset` moves the second half of the band's (u,v) by that much, a chart of
// its own (its vertices at the half-way line doubled); 0 leaves one chart. `v_round` swaps u
// and v (v round the axis). As a trianglemesh.
std::string band(int columns, float offset, bool v_round = false) {
    std::string p, uv, idx;
    auto num = [](double x) { return std::to_string(x) + " "; };
    int vertex = 0;
    auto island = [&](int first, int last, float du) {
        const int base = vertex;
        for (int i = first; i <= last; ++i)
            for (int j = 0; j < 2; ++j) {
                const double phi = 2 * 3.14159265358979 * (i % columns) / columns;
                p += num(2 * std::sin(phi)) + num(j ? 3.0 : -3.0) + num(5 - 2 * std::cos(phi));
                const double round = double(i) / columns + du;
                uv += v_round ? num(j) + num(round) : num(round) + num(j);
                ++vertex;
            }
        for (int i = 0; i < last - first; ++i) {
            const int a = base + 2 * i;
            for (int k : {a, a + 2, a + 1, a + 1, a + 2, a + 3}) idx += std::to_string(k) + " ";
        }
    };
    if (offset == 0) {
        island(0, columns, 0);
    } else {
        island(0, columns / 2, 0);
        island(columns / 2, columns, offset);
    }
    return "Shape \"trianglemesh\" \"point3 P\" [" + p + "] \"point2 uv\" [" + uv +
           "] \"integer indices\" [" + idx + "]";
}
}  // namespace

TEST(UvCharts, AMeshsChartsAndItsPeriodicU) {
    const std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/brick.png";
    auto scene = [&](const std::string& shape) {
        const pbrt::SceneDesc d = pbrt::parse_string(
            camera512("Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + tex +
                      "\" \"string lod\" \"cmam\" Material \"matte\" \"texture Kd\" \"b\" " +
                      shape),
            "t.pbrt");
        BuildOptions bo;
        bo.spp_override = 1;
        return build_scene(d, bo, {});
    };
    // One chart meeting itself where u moves by 1: periodic, no chart numbers needed.
    {
        auto s = scene(band(16, 0));
        const Primitive& pr = *s->primitives[0];
        EXPECT_TRUE(pr.u_periodic);
        EXPECT_FALSE(pr.v_periodic);
        EXPECT_TRUE(pr.uv_charts.empty());
    }
    // A grid of nu x nv quads, point (i, j) at `at(i, j)` with (u,v) `uv_of(i, j)`, or
    // (i / nu, j / nv) when uv_of is nullptr, as a trianglemesh: the last column's and row's
    // points are where `at` puts them.
    auto grid = [](int nu, int nv, auto at, auto uv_of) {
        std::string p, uv, idx;
        auto num = [](double x) { return std::to_string(x) + " "; };
        for (int j = 0; j <= nv; ++j)
            for (int i = 0; i <= nu; ++i) {
                const Vec3 x = at(i, j);
                std::array<double, 2> t{double(i) / nu, double(j) / nv};
                if constexpr (!std::is_null_pointer_v<decltype(uv_of)>) t = uv_of(i, j);
                p += num(x.x) + num(x.y) + num(x.z);
                uv += num(t[0]) + num(t[1]);
            }
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const int a = j * (nu + 1) + i, c = a + nu + 1;
                for (int k : {a, c, a + 1, a + 1, c, c + 1}) idx += std::to_string(k) + " ";
            }
        return "Shape \"trianglemesh\" \"point3 P\" [" + p + "] \"point2 uv\" [" + uv +
               "] \"integer indices\" [" + idx + "]";
    };
    const double pi = 3.14159265358979;
    // A UV sphere's: its seam from pole to pole moves u by 1; at each pole every column has a
    // vertex of its own u (a singular point, no evidence), and the triangles of the poles' rows
    // (two corners at the pole) have no area.
    {
        auto s = scene(grid(
            8, 4,
            [&](int i, int j) {
                const double th = pi * j / 4, ph = 2 * pi * (i % 8) / 8;
                return Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                            5 + std::cos(th));
            },
            nullptr));
        const Primitive& pr = *s->primitives[0];
        EXPECT_TRUE(pr.u_periodic);
        EXPECT_FALSE(pr.v_periodic);
        EXPECT_TRUE(pr.uv_charts.empty());
    }
    // A torus's: u round the axis and v round the tube, each seam moving one of them by 1 (the
    // point where the two seams cross has four (u,v), differing in u and in v: not a pole).
    {
        auto s = scene(grid(
            8, 6,
            [&](int i, int j) {
                const double ph = 2 * pi * (i % 8) / 8, th = 2 * pi * (j % 6) / 6,
                             r = 2 + 0.5 * std::cos(th);
                return Vec3(r * std::cos(ph), 0.5 * std::sin(th), 8 + r * std::sin(ph));
            },
            nullptr));
        const Primitive& pr = *s->primitives[0];
        EXPECT_TRUE(pr.u_periodic);
        EXPECT_TRUE(pr.v_periodic);
        EXPECT_TRUE(pr.uv_charts.empty());
    }
    // A cube with each face mapped onto the whole texture: its charts meet where (u,v) jump
    // by whole units at the corners but by other amounts between them, no period; the corners
    // carry three (u,v) differing in u and in v, ordinary points, not poles.
    {
        std::string p, uv, idx;
        const int faces[6][9] = {{-1, -1, -1, 2, 0, 0, 0, 2, 0}, {-1, -1, 1, 2, 0, 0, 0, 2, 0},
                                 {-1, -1, -1, 0, 2, 0, 0, 0, 2}, {1, -1, -1, 0, 2, 0, 0, 0, 2},
                                 {-1, -1, -1, 2, 0, 0, 0, 0, 2}, {-1, 1, -1, 2, 0, 0, 0, 0, 2}};
        for (int f = 0; f < 6; ++f) {
            const int* o = faces[f];
            for (int c = 0; c < 4; ++c) {
                const int a = c == 1 || c == 2, b = c >= 2;
                for (int k = 0; k < 3; ++k)
                    p +=
                        std::to_string(o[k] + a * o[3 + k] + b * o[6 + k] + (k == 2 ? 8 : 0)) + " ";
                uv += std::to_string(a) + " " + std::to_string(b) + " ";
            }
            for (int k : {0, 1, 2, 0, 2, 3}) idx += std::to_string(4 * f + k) + " ";
        }
        auto s = scene("Shape \"trianglemesh\" \"point3 P\" [" + p + "] \"point2 uv\" [" + uv +
                       "] \"integer indices\" [" + idx + "]");
        // The faces z-, x- and y- (triangles 0-1, 4-5, 8-9) meet with the same (u,v) at both
        // ends of two of their edges, and z+, x+, y+ likewise; every other edge is a seam, and
        // the one inside each chart (z- with x-, z+ with x+) matches at one end only.
        const Primitive& pr = *s->primitives[0];
        EXPECT_FALSE(pr.u_periodic);
        EXPECT_FALSE(pr.v_periodic);
        ASSERT_EQ(pr.uv_charts.size(), 12u);
        for (int f = 0; f < 6; ++f)
            for (int k = 0; k < 2; ++k)
                EXPECT_EQ(pr.uv_charts[2 * f + k], f % 2 == 0 ? 0u : 1u) << f << " " << k;
    }
    // A band whose (u,v) round the axis come back moved by (1, 0) at its foot and (1, 1) at its
    // top: whole units at both ends of the seam but no one translation, no period.
    {
        // The last column's top vertex at v = 2 instead of 1.
        const std::string text = grid(
            8, 1,
            [&](int i, int j) {
                const double ph = 2 * pi * (i % 8) / 8;
                return Vec3(2 * std::sin(ph), j ? 3.0 : -3.0, 5 - 2 * std::cos(ph));
            },
            [](int i, int j) {
                return std::array<double, 2>{i / 8.0, i == 8 && j == 1 ? 2.0 : j};
            });
        auto s = scene(text);
        const Primitive& pr = *s->primitives[0];
        EXPECT_TRUE(pr.uv_charts.empty());
        EXPECT_FALSE(pr.u_periodic);
        EXPECT_FALSE(pr.v_periodic);
    }
    // Two charts: each triangle's, the first half's 0 and the second's 1; the seams between
    // them are no period.
    {
        auto s = scene(band(16, 0.37f));
        const Primitive& pr = *s->primitives[0];
        EXPECT_FALSE(pr.u_periodic);
        ASSERT_EQ(pr.uv_charts.size(), pr.indices.size() / 3);
        for (std::size_t t = 0; t < pr.uv_charts.size(); ++t)
            EXPECT_EQ(pr.uv_charts[t], t < pr.uv_charts.size() / 2 ? 0u : 1u) << t;
    }
    // A quad whose vertices are doubled with the same positions and (u,v) (split for their
    // normals) is one chart; with another (u,v) on one side, two; neither is periodic.
    for (const bool split_uv : {false, true}) {
        auto s = scene(
            std::string("Shape \"trianglemesh\" \"point3 P\" [-1 -1 4  1 -1 4  1 1 4  -1 -1 4  1 "
                        "1 4  -1 1 4] \"point2 uv\" [0 0 1 0 1 1 0 0 ") +
            (split_uv ? "0.5 1" : "1 1") +
            " 0 1] \"normal N\" [0 0 -1 0 0 -1 0 0 -1 0 0.1 -1 0 0.1 -1 0 0.1 -1] "
            "\"integer indices\" [0 1 2 3 4 5]");
        const Primitive& pr = *s->primitives[0];
        EXPECT_FALSE(pr.u_periodic);
        EXPECT_EQ(pr.uv_charts.size(), split_uv ? 2u : 0u);
    }
    // Without the CMAM nothing is made.
    {
        const pbrt::SceneDesc d = pbrt::parse_string(
            camera512("Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + tex +
                      "\" Material \"matte\" \"texture Kd\" \"b\" " + band(16, 0.37f)),
            "t.pbrt");
        auto s = build_scene(d, {}, {});
        EXPECT_TRUE(s->primitives[0]->uv_charts.empty());
        EXPECT_FALSE(s->primitives[0]->u_periodic);
    }
}

TEST(Aov, TheCmamTakesNoNeighbourAcrossAMeshsSeam) {
    // A mesh band's (u,v) seam down the image's centre: where the band's one chart meets itself
    // (u, or v if v goes round, moves by 1) the CMAM takes its neighbours the short way round,
    // where two charts meet it takes none from the other chart; either way the regions along
    // rows crossing the seam (the footprint AOV) stay as small as their neighbours', under the
    // 1-D and the 2-D CMAM. Without either, the region across the seam spans a whole texture.
    const std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/brick.png";
    for (const bool two_d : {false, true})
        for (const float offset : {0.0f, 0.37f, -1.0f}) {  // -1: one chart, v round the axis
            SCOPED_TRACE(two_d ? "2-D" : "1-D");
            SCOPED_TRACE(offset);
            const double largest = largest_region_across_seam(
                "Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + tex +
                    "\" \"string lod\" \"cmam\" Material \"matte\" \"texture Kd\" \"b\" "
                    "LightSource \"distant\" " +
                    band(64, std::max(offset, 0.0f), offset < 0),
                two_d);
            // About a texel a pixel: the band's 12.6 units round over 512 texels, seen 3 units
            // away at 512 pixels for 90 degrees.
            EXPECT_GT(largest, 0.5);
            EXPECT_LT(largest, 8.0);
        }
}

// A texture that maps the hit's point (here planar, 8 world units to one repeat) is looked up
// over the image of the world-space footprint, and the footprint AOV reports that, for every
// source with one: ray differentials (dP/dx, dP/dy) and ray cones (their cross-section on the
// tangent plane). One pixel is 0.0390625 units on the plane z = 10, 2.5 texels of the
// 512^2 texture under the mapping, where the surface's own (u,v) would give 5.
TEST(Aov, MappedTexturesReportTheFootprintTheirLookupUses) {
    for (const char* lod : {"differentials", "cones", "cones-aniso"}) {
        SCOPED_TRACE(lod);
        auto s = textured_plane(
            "\"string mapping\" \"planar\" \"vector3 v1\" [0.125 0 0] \"vector3 v2\" [0 0.125 0] "
            "\"string lod\" \"" +
            std::string(lod) + "\"");
        const Framebuffer fp = footprint_aov(*s);
        for (std::size_t p = 0; p < fp.rgb.size() / 3; ++p) {
            EXPECT_NEAR(fp.rgb[3 * p], 2.5, 0.01);
            EXPECT_NEAR(fp.rgb[3 * p + 1], 2.5, 0.01);
        }
    }
}
