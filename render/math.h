// render — small vector, colour and frame types for the tracer (float, like pbrt-v3).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cmam::render {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kInvPi = 1.0f / kPi;

/// A point or vector in double precision, for what is computed once per scene (subdivision,
/// lens systems) where float's rounding would accumulate.
struct Vec3d {
    double x = 0, y = 0, z = 0;
};
inline Vec3d operator+(Vec3d a, Vec3d b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3d operator-(Vec3d a, Vec3d b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3d operator*(double s, Vec3d a) {
    return {s * a.x, s * a.y, s * a.z};
}
inline Vec3d cross(Vec3d a, Vec3d b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(Vec3d a, Vec3d b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

struct Vec3 {
    float x = 0, y = 0, z = 0;
    Vec3() = default;
    constexpr Vec3(float a, float b, float c) : x(a), y(b), z(c) {}
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    Vec3& operator+=(const Vec3& o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
};
inline Vec3 operator*(float s, const Vec3& v) {
    return v * s;
}
inline float dot(const Vec3& a, const Vec3& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline float absdot(const Vec3& a, const Vec3& b) {
    return std::abs(dot(a, b));
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline bool finite(const Vec3& v) {
    // x * 0 is 0 for a finite x and NaN for an infinite or NaN one, and a NaN in the sum makes it
    // unequal to itself: one test without a branch per component.
    const float z = (v.x * 0.0f + v.y * 0.0f) + v.z * 0.0f;
    return z == z;
}
inline float length(const Vec3& v) {
    return std::sqrt(dot(v, v));
}
inline Vec3 normalize(const Vec3& v) {
    return v / length(v);
}
inline Vec3 faceforward(const Vec3& n, const Vec3& v) {
    return dot(n, v) < 0 ? -n : n;
}
inline float max_abs(const Vec3& v) {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

/// Linear RGB radiance or reflectance (pbrt-v3's RGBSpectrum).
struct Rgb {
    float r = 0, g = 0, b = 0;
    Rgb() = default;
    constexpr Rgb(float a, float b_, float c) : r(a), g(b_), b(c) {}
    constexpr explicit Rgb(float v) : r(v), g(v), b(v) {}
    Rgb operator+(const Rgb& o) const { return {r + o.r, g + o.g, b + o.b}; }
    Rgb operator-(const Rgb& o) const { return {r - o.r, g - o.g, b - o.b}; }
    Rgb operator*(const Rgb& o) const { return {r * o.r, g * o.g, b * o.b}; }
    Rgb operator*(float s) const { return {r * s, g * s, b * s}; }
    Rgb operator/(float s) const { return {r / s, g / s, b / s}; }
    Rgb& operator+=(const Rgb& o) {
        r += o.r;
        g += o.g;
        b += o.b;
        return *this;
    }
    bool is_black() const { return r == 0 && g == 0 && b == 0; }
    float luminance() const { return 0.212671f * r + 0.715160f * g + 0.072169f * b; }
};
inline Rgb operator*(float s, const Rgb& c) {
    return c * s;
}

/// Whether every channel of c is finite.
inline bool finite(const Rgb& c) {
    return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b);
}

/// c with its negative channels made 0 (pbrt-v3's Spectrum::Clamp).
inline Rgb clamp0(const Rgb& c) {
    return {std::max(0.0f, c.r), std::max(0.0f, c.g), std::max(0.0f, c.b)};
}

/// Orthonormal frame with z along a given normal (for BSDF-local directions).
struct Frame {
    Vec3 s, t, n;
    static Frame from_z(const Vec3& n) {
        // Duff et al. 2017 branchless basis.
        float sign = std::copysign(1.0f, n.z);
        float a = -1.0f / (sign + n.z);
        float b = n.x * n.y * a;
        return {Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x),
                Vec3(b, sign + n.y * n.y * a, -n.y), n};
    }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

/// A direction drawn from a scattering function (a BSDF or one of its lobes): the direction,
/// the function's value there and the density it was drawn with (0: nothing drawn).
/// A direction about +z from two uniform numbers in [0,1): cosine-weighted (density cos / pi),
/// or with `uniform` uniform over the hemisphere (density 1 / 2 pi). z >= 0.
inline Vec3 hemisphere_direction(float u1, float u2, bool uniform = false) {
    const float phi = 2 * kPi * u2;
    const float z = uniform ? u1 : std::sqrt(std::max(0.0f, 1 - u1));
    const float r = uniform ? std::sqrt(std::max(0.0f, 1 - z * z)) : std::sqrt(u1);
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// A direction uniform over the unit sphere from uniform u1, u2 (density 1 / 4 pi).
inline Vec3 sphere_direction(float u1, float u2) {
    const float z = 1 - 2 * u1, r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Shirley and Chiu's concentric map of [0,1)^2 onto the unit disc (pbrt-v3's
/// ConcentricSampleDisk): squares' rings onto circles, so strata stay compact.
void concentric_disc(float u, float v, float& x, float& y);

struct DirectionSample {
    Vec3 wi;
    Rgb f;
    float pdf = 0;
};

}  // namespace cmam::render
