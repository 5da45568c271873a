#include "pbrt/transform.h"

#include <cmath>
#include <numbers>

#include "pbrt/error.h"

namespace cmam::pbrt {

Mat4 Mat4::identity() {
    Mat4 r;
    for (int i = 0; i < 4; ++i) r.m[i][i] = 1;
    return r;
}

Mat4 Mat4::operator*(const Mat4& b) const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += m[i][k] * b.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

Mat4 Mat4::transposed() const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
    return r;
}

Mat4 Mat4::inverse() const {
    // Gauss-Jordan elimination with partial pivoting.
    std::array<std::array<double, 8>, 4> a{};
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) a[i][j] = m[i][j];
        a[i][4 + i] = 1;
    }
    for (int col = 0; col < 4; ++col) {
        int piv = col;
        for (int r = col + 1; r < 4; ++r)
            if (std::abs(a[r][col]) > std::abs(a[piv][col])) piv = r;
        if (std::abs(a[piv][col]) < 1e-300) throw SceneError("singular matrix");
        std::swap(a[piv], a[col]);
        double inv = 1.0 / a[col][col];
        for (double& x : a[col]) x *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == col) continue;
            double f = a[r][col];
            if (f == 0) continue;
            for (int c = 0; c < 8; ++c) a[r][c] -= f * a[col][c];
        }
    }
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][4 + j];
    return r;
}

bool Mat4::is_identity() const {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (m[i][j] != (i == j ? 1.0 : 0.0)) return false;
    return true;
}

double Mat4::linear_determinant() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

bool Mat4::swaps_handedness() const {
    return linear_determinant() < 0;
}

std::array<double, 3> Mat4::apply_point(const std::array<double, 3>& p) const {
    std::array<double, 3> r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    double w = m[3][0] * p[0] + m[3][1] * p[1] + m[3][2] * p[2] + m[3][3];
    if (w != 1 && w != 0)
        for (double& x : r) x /= w;
    return r;
}

std::array<double, 3> Mat4::apply_vector(const std::array<double, 3>& v) const {
    std::array<double, 3> r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    return r;
}

Mat4 translate(double x, double y, double z) {
    Mat4 r = Mat4::identity();
    r.m[0][3] = x;
    r.m[1][3] = y;
    r.m[2][3] = z;
    return r;
}

Mat4 scale(double x, double y, double z) {
    Mat4 r = Mat4::identity();
    r.m[0][0] = x;
    r.m[1][1] = y;
    r.m[2][2] = z;
    return r;
}

Mat4 rotate(double degrees, double ax, double ay, double az) {
    double len = std::sqrt(ax * ax + ay * ay + az * az);
    if (len == 0) throw SceneError("rotation axis has zero length");
    ax /= len;
    ay /= len;
    az /= len;
    double th = degrees * std::numbers::pi / 180.0;
    double s = std::sin(th), c = std::cos(th), t = 1 - c;
    Mat4 r = Mat4::identity();
    // Rodrigues' formula for a right-handed rotation about the axis.
    r.m[0][0] = ax * ax * t + c;
    r.m[0][1] = ax * ay * t - az * s;
    r.m[0][2] = ax * az * t + ay * s;
    r.m[1][0] = ax * ay * t + az * s;
    r.m[1][1] = ay * ay * t + c;
    r.m[1][2] = ay * az * t - ax * s;
    r.m[2][0] = ax * az * t - ay * s;
    r.m[2][1] = ay * az * t + ax * s;
    r.m[2][2] = az * az * t + c;
    return r;
}

namespace {
using V3 = std::array<double, 3>;
V3 sub(const V3& a, const V3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
V3 cross(const V3& a, const V3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double length(const V3& a) {
    return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}
V3 normalized(const V3& a) {
    double l = length(a);
    return {a[0] / l, a[1] / l, a[2] / l};
}
}  // namespace

Mat4 look_at(const V3& eye, const V3& look, const V3& up) {
    V3 d = sub(look, eye);
    if (length(d) == 0) throw SceneError("LookAt eye and look point coincide");
    V3 dir = normalized(d);
    if (length(up) == 0) throw SceneError("LookAt up vector has zero length");
    V3 right = cross(normalized(up), dir);
    if (length(right) == 0)
        throw SceneError("LookAt up vector is parallel to the viewing direction");
    right = normalized(right);
    V3 new_up = cross(dir, right);
    // world_from_camera has columns (right, up, dir, eye); LookAt yields its inverse.
    Mat4 wc = Mat4::identity();
    for (int i = 0; i < 3; ++i) {
        wc.m[i][0] = right[i];
        wc.m[i][1] = new_up[i];
        wc.m[i][2] = dir[i];
        wc.m[i][3] = eye[i];
    }
    return wc.inverse();
}

}  // namespace cmam::pbrt
