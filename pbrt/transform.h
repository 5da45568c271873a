// pbrt — 4x4 affine/projective matrices with pbrt-v3's transform conventions.
// Points are column vectors: p' = M p. Composition a * b applies b first. Rotate, LookAt and
// Perspective follow pbrt-v3 (left-handed camera space looking down +z).
#pragma once

#include <array>

namespace cmam::pbrt {

struct Mat4 {
    std::array<std::array<double, 4>, 4> m{};

    static Mat4 identity();
    Mat4 operator*(const Mat4& b) const;
    Mat4 transposed() const;
    /// Inverse; throws SceneError (not tied to a location) when singular.
    Mat4 inverse() const;
    bool is_identity() const;
    /// The determinant of the upper 3x3 (the linear part).
    double linear_determinant() const;
    /// True when the upper 3x3 has a negative determinant (mirrors handedness).
    bool swaps_handedness() const;

    std::array<double, 3> apply_point(const std::array<double, 3>& p) const;
    std::array<double, 3> apply_vector(const std::array<double, 3>& v) const;
};

Mat4 translate(double x, double y, double z);
Mat4 scale(double x, double y, double z);
/// Rotation by `degrees` about `axis` (normalised here; SceneError when it has zero length).
Mat4 rotate(double degrees, double ax, double ay, double az);
/// pbrt-v3 LookAt: returns camera_from_world. Throws SceneError (not tied to a location) for
/// degenerate input.
Mat4 look_at(const std::array<double, 3>& eye, const std::array<double, 3>& look,
             const std::array<double, 3>& up);

}  // namespace cmam::pbrt
