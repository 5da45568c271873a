// render — 3x4 affine transforms applied to points, vectors and normals, in double (quadrics'
// object_from_world / world_from_object) and in float (instances), and the derivative of a
// normalised normal. Shared by the intersection code and the surface differentials.
#pragma once

#include <array>
#include <cmath>

#include "render/math.h"

namespace cmam::render::xform {

using D3 = std::array<double, 3>;

inline D3 xform_point(const std::array<double, 12>& m, const D3& p) {
    return {m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3],
            m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7],
            m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11]};
}
inline D3 xform_vector(const std::array<double, 12>& m, const D3& v) {
    return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[4] * v[0] + m[5] * v[1] + m[6] * v[2],
            m[8] * v[0] + m[9] * v[1] + m[10] * v[2]};
}
// Normals transform with the inverse transpose: n_world = (object_from_world)^T n_obj.
inline D3 xform_normal(const std::array<double, 12>& object_from_world, const D3& n) {
    const auto& m = object_from_world;
    return {m[0] * n[0] + m[4] * n[1] + m[8] * n[2], m[1] * n[0] + m[5] * n[1] + m[9] * n[2],
            m[2] * n[0] + m[6] * n[1] + m[10] * n[2]};
}
inline Vec3 to_vec(const D3& d) {
    return Vec3(float(d[0]), float(d[1]), float(d[2]));
}

// d(n/|n|) = ((n.n) dn - (n.dn) n) / |n|^3 for an unnormalised normal n.
inline Vec3 unit_derivative(const Vec3& n, const Vec3& dn) {
    float nn = dot(n, n);
    return (nn * dn - dot(n, dn) * n) / (nn * std::sqrt(nn));
}

// A 3x4 row-major affine transform applied to a point, a vector, or (as its inverse transpose,
// given the inverse) a normal.
inline Vec3 apply_point(const std::array<float, 12>& m, const Vec3& p) {
    return Vec3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
                m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}
inline Vec3 apply_vector(const std::array<float, 12>& m, const Vec3& v) {
    return Vec3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                m[8] * v.x + m[9] * v.y + m[10] * v.z);
}
inline Vec3 apply_transpose(const std::array<float, 12>& m, const Vec3& n) {
    return Vec3(m[0] * n.x + m[4] * n.y + m[8] * n.z, m[1] * n.x + m[5] * n.y + m[9] * n.z,
                m[2] * n.x + m[6] * n.y + m[10] * n.z);
}

}  // namespace cmam::render::xform
