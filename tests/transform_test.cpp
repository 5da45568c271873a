// pbrt-v3 transform conventions: Rotate is right-handed about its axis, LookAt yields
// camera_from_world with the camera looking down +z, Transform lists columns.
#include "pbrt/transform.h"

#include <gtest/gtest.h>

#include "expect_throw.h"
#include "pbrt/parser.h"

using namespace cmam::pbrt;

namespace {
void expect_near(const std::array<double, 3>& a, const std::array<double, 3>& b,
                 double eps = 1e-12) {
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], eps) << "component " << i;
}
}  // namespace

TEST(Transform, RotateIsRightHanded) {
    expect_near(rotate(90, 0, 0, 1).apply_point({1, 0, 0}), {0, 1, 0});
    expect_near(rotate(90, 1, 0, 0).apply_point({0, 1, 0}), {0, 0, 1});
    expect_near(rotate(90, 0, 1, 0).apply_point({0, 0, 1}), {1, 0, 0});
    expect_near(rotate(120, 1, 1, 1).apply_point({1, 0, 0}), {0, 1, 0});  // axis is normalised
}

TEST(Transform, LookAtMapsEyeToOriginAndViewToPlusZ) {
    Mat4 cw = look_at({1, 2, 3}, {1, 2, 10}, {0, 1, 0});
    expect_near(cw.apply_point({1, 2, 3}), {0, 0, 0});
    expect_near(cw.apply_point({1, 2, 10}), {0, 0, 7});
    // pbrt-v3 is left-handed: with up = +y and view = +z, camera +x is world +x.
    expect_near(cw.apply_vector({1, 0, 0}), {1, 0, 0});
    expect_near(cw.apply_vector({0, 1, 0}), {0, 1, 0});
    Mat4 turned = look_at({0, 0, 0}, {1, 0, 0}, {0, 1, 0});  // looking down +x
    expect_near(turned.apply_vector({1, 0, 0}), {0, 0, 1});
    expect_near(turned.apply_vector({0, 0, -1}), {1, 0, 0});  // camera right is world -z
}

TEST(Transform, LookAtRejectsDegenerateInput) {
    EXPECT_THROW_MSG(look_at({0, 0, 0}, {0, 0, 0}, {0, 1, 0}), SceneError,
                     "error: LookAt eye and look point coincide");
    EXPECT_THROW_MSG(look_at({0, 0, 0}, {0, 1, 0}, {0, 1, 0}), SceneError,
                     "error: LookAt up vector is parallel to the viewing direction");
    EXPECT_THROW_MSG(look_at({0, 0, 0}, {0, 0, 1}, {0, 0, 0}), SceneError,
                     "error: LookAt up vector has zero length");
    // The directive's error is located at it.
    EXPECT_THROW_MSG(parse_string("Camera \"perspective\"\nLookAt 1 2 3  1 2 3  0 1 0"), SceneError,
                     "<string>:2:1: error: LookAt eye and look point coincide");
}

TEST(Transform, SingularMatricesAndZeroAxesAreErrors) {
    EXPECT_THROW_MSG(scale(1, 0, 1).inverse(), SceneError, "error: singular matrix");
    EXPECT_THROW_MSG(rotate(30, 0, 0, 0), SceneError, "error: rotation axis has zero length");
    EXPECT_THROW_MSG(parse_string("Scale 1 0 1\nCamera \"perspective\"\nWorldBegin WorldEnd"),
                     SceneError, "<string>:2:1: error: the camera transform is singular");
    EXPECT_THROW_MSG(parse_string("Rotate 30 0 0 0"), SceneError,
                     "<string>:1:1: error: Rotate axis has zero length");
}

TEST(Transform, InverseAndHandedness) {
    Mat4 m = translate(1, 2, 3) * rotate(33, 1, 2, 3) * scale(2, 3, 4);
    Mat4 p = m * m.inverse();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(p.m[i][j], i == j ? 1 : 0, 1e-12);
    EXPECT_FALSE(m.swaps_handedness());
    EXPECT_TRUE(scale(-1, 1, 1).swaps_handedness());
}

TEST(Transform, DirectivesComposeLikePbrt) {
    // Translate then Scale: the scale applies first to object points.
    SceneDesc d = parse_string(
        "Camera \"perspective\" WorldBegin Translate 1 0 0 Scale 2 2 2 Shape \"sphere\" "
        "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1 ] Shape \"sphere\" "
        "ConcatTransform [ 2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1 ] Shape \"sphere\" WorldEnd");
    ASSERT_EQ(d.shapes.size(), 3u);
    expect_near(d.shapes[0].world_from_object.apply_point({1, 0, 0}), {3, 0, 0});
    expect_near(d.shapes[1].world_from_object.apply_point({0, 0, 0}), {5, 6, 7});  // columns
    expect_near(d.shapes[2].world_from_object.apply_point({1, 0, 0}), {7, 6, 7});
}

TEST(Transform, CameraCoordinateSystem) {
    SceneDesc d = parse_string(
        "LookAt 0 0 -5  0 0 0  0 1 0 Camera \"perspective\" WorldBegin CoordSysTransform "
        "\"camera\" "
        "Shape \"sphere\" WorldEnd");
    expect_near(d.shapes[0].world_from_object.apply_point({0, 0, 0}), {0, 0, -5}, 1e-12);
}
