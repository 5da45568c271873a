// Camera rays follow pbrt-v3's perspective camera: fov spans the shorter axis, raster y down.
#include <gtest/gtest.h>

#include "scene_util.h"

using namespace cmam;
using render::Vec3;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;
void expect_dir(const Vec3& d, Vec3 e, float eps = 1e-6f) {
    e = render::normalize(e);
    EXPECT_NEAR(d.x, e.x, eps);
    EXPECT_NEAR(d.y, e.y, eps);
    EXPECT_NEAR(d.z, e.z, eps);
}
}  // namespace

TEST(Camera, CentreAndEdgesOfASquareImage) {
    auto s = test::scene_from(
        "LookAt 0 0 0  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 90 "
        "Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 100 WorldBegin "
        "WorldEnd");
    Vec3 d = s->camera.generate_ray(50, 50).dir;
    expect_dir(d, Vec3(0, 0, 1));
    d = s->camera.generate_ray(0, 50).dir;  // left edge: 45 degrees to the left (-x)
    expect_dir(d, Vec3(-1, 0, 1));
    d = s->camera.generate_ray(50, 0).dir;  // top row looks up
    expect_dir(d, Vec3(0, 1, 1));
}

TEST(Camera, FovSpansTheShorterAxis) {
    for (auto [xr, yr] : {std::pair{200, 100}, std::pair{100, 200}}) {
        auto s = test::scene_from(
            "Camera \"perspective\" \"float fov\" 60 Film \"image\" \"integer xresolution\" " +
            std::to_string(xr) + " \"integer yresolution\" " + std::to_string(yr) +
            " WorldBegin WorldEnd");
        Vec3 d;
        float t = float(std::tan(30 * kDeg));
        if (xr > yr) {
            d = s->camera.generate_ray(float(xr) / 2, 0).dir;
            expect_dir(d, Vec3(0, t, 1));
            d = s->camera.generate_ray(float(xr), float(yr) / 2).dir;
            expect_dir(d, Vec3(2 * t, 0, 1));
        } else {
            d = s->camera.generate_ray(0, float(yr) / 2).dir;
            expect_dir(d, Vec3(-t, 0, 1));
            d = s->camera.generate_ray(float(xr) / 2, 0).dir;
            expect_dir(d, Vec3(0, 2 * t, 1));
        }
    }
}

TEST(Camera, LookAtPlacesTheCamera) {
    auto s = test::scene_from(
        "LookAt 1 2 3  1 2 -7  0 1 0 Camera \"perspective\" Film \"image\" \"integer xresolution\" "
        "10 "
        "\"integer yresolution\" 10 WorldBegin WorldEnd");
    auto [o, d] = s->camera.generate_ray(5, 5);
    EXPECT_NEAR(o.x, 1, 1e-6);
    EXPECT_NEAR(o.y, 2, 1e-6);
    EXPECT_NEAR(o.z, 3, 1e-6);
    expect_dir(d, Vec3(0, 0, -1));
    d = s->camera.generate_ray(0, 5).dir;  // looking down -z with +y up: screen left is world +x
    EXPECT_GT(d.x, 0.5f);
}

TEST(Camera, ScreenWindowAndCrop) {
    auto s = test::scene_from(
        "Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [0 1 0 1] "
        "Film \"image\" \"integer xresolution\" 10 \"integer yresolution\" 10 \"float cropwindow\" "
        "[0.5 1 0 0.25] "
        "WorldBegin WorldEnd");
    Vec3 d = s->camera.generate_ray(0, 10).dir;  // bottom-left of the window is screen (0,0)
    expect_dir(d, Vec3(0, 0, 1));
    EXPECT_EQ(s->film.x0, 5);
    EXPECT_EQ(s->film.x1, 10);
    EXPECT_EQ(s->film.y0, 0);
    EXPECT_EQ(s->film.y1, 3);
}
