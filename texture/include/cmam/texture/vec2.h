// cmam::texture — the library's one 2-D vector type and its axis-aligned boxes.
#pragma once

#include <cmath>

namespace cmam::texture {

/// A 2-D vector or point. In a footprint it is in (u,v) units; in the CMAM's regions and the
/// polygons it is in texels, (s,t) = (u*W, v*H): each declaration says which.
struct Vec2d {
    double u = 0, v = 0;
    bool operator==(const Vec2d&) const = default;
};

constexpr Vec2d operator+(Vec2d a, Vec2d b) {
    return {a.u + b.u, a.v + b.v};
}
constexpr Vec2d operator-(Vec2d a, Vec2d b) {
    return {a.u - b.u, a.v - b.v};
}
constexpr Vec2d operator*(double k, Vec2d a) {
    return {k * a.u, k * a.v};
}
constexpr Vec2d operator/(Vec2d a, double k) {
    return {a.u / k, a.v / k};
}
constexpr double dot(Vec2d a, Vec2d b) {
    return a.u * b.u + a.v * b.v;
}
/// a.u b.v - a.v b.u: twice the signed area of the triangle (0, a, b), positive when b lies
/// counter-clockwise of a.
constexpr double cross(Vec2d a, Vec2d b) {
    return a.u * b.v - a.v * b.u;
}
inline double length(Vec2d a) {
    return std::sqrt(dot(a, a));
}

/// An axis-aligned rectangle [lo.u, hi.u] x [lo.v, hi.v].
struct Box2d {
    Vec2d lo, hi;
};

}  // namespace cmam::texture
