#include "render/noise.h"

#include <cstdint>

namespace cmam::render {

namespace {

// Ken Perlin's permutation of 0..255 (his improved noise reference implementation, 2002).
constexpr uint8_t kPerm[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103,
    30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,
    197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174,
    20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146, 158, 231,
    83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143,
    54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196,
    135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124,
    123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,
    182, 189, 28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101,
    155, 167, 43,  172, 9,   129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185,
    112, 104, 218, 246, 97,  228, 251, 34,  242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,
    51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176,
    115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243,
    141, 128, 195, 78,  66,  215, 61,  156, 180};

int perm(int i) {
    return kPerm[i & 255];
}

// The gradient of lattice point (x, y, z), one of 12 edge directions of a cube, dotted with the
// offset (dx, dy, dz) from it.
float gradient(int x, int y, int z, float dx, float dy, float dz) {
    const int h = perm(perm(perm(x) + y) + z) & 15;
    const float a = h < 8 || h == 12 || h == 13 ? dx : dy;
    const float b = h < 4 || h == 12 || h == 13 ? dy : dz;
    return ((h & 1) ? -a : a) + ((h & 2) ? -b : b);
}

// 6t^5 - 15t^4 + 10t^3: the quintic fade with zero first and second derivatives at 0 and 1.
float fade(float t) {
    return t * t * t * (t * (t * 6 - 15) + 10);
}

float lerp(float t, float a, float b) {
    return a + t * (b - a);
}

float smooth_step(float lo, float hi, float x) {
    if (x <= lo) return 0;
    if (x >= hi) return 1;
    const float t = (x - lo) / (hi - lo);
    return t * t * (3 - 2 * t);
}

// How many octaves the footprint resolves: the octave whose wavelength reaches the larger of
// |dP/dx| and |dP/dy| ends the sum (pbrt-v3: -1 - log2(len) / 2 of the squared length).
float octaves_resolved(const Vec3& dpdx, const Vec3& dpdy, int max_octaves) {
    const float len2 = std::max(dot(dpdx, dpdx), dot(dpdy, dpdy));
    if (!(len2 > 0)) return float(max_octaves);
    return std::clamp(-1 - 0.5f * std::log2(len2), 0.0f, float(max_octaves));
}

}  // namespace

float perlin_noise(const Vec3& p) {
    const float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
    const float dx = p.x - fx, dy = p.y - fy, dz = p.z - fz;
    // Lattice coordinates wrap every 256 cells (large coordinates keep their low bits).
    const int x = static_cast<int>(static_cast<long long>(fx) & 255),
              y = static_cast<int>(static_cast<long long>(fy) & 255),
              z = static_cast<int>(static_cast<long long>(fz) & 255);
    float w[2][2][2];
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i)
                w[k][j][i] =
                    gradient(x + i, y + j, z + k, dx - float(i), dy - float(j), dz - float(k));
    const float u = fade(dx), v = fade(dy), s = fade(dz);
    const float y0 = lerp(v, lerp(u, w[0][0][0], w[0][0][1]), lerp(u, w[0][1][0], w[0][1][1]));
    const float y1 = lerp(v, lerp(u, w[1][0][0], w[1][0][1]), lerp(u, w[1][1][0], w[1][1][1]));
    return lerp(s, y0, y1);
}

float fbm(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves) {
    const float n = octaves_resolved(dpdx, dpdy, max_octaves);
    const int whole = static_cast<int>(std::floor(n));
    float sum = 0, frequency = 1, amplitude = 1;
    for (int i = 0; i < whole; ++i) {
        sum += amplitude * perlin_noise(p * frequency);
        frequency *= 1.99f;
        amplitude *= omega;
    }
    sum += amplitude * smooth_step(0.3f, 0.7f, n - float(whole)) * perlin_noise(p * frequency);
    return sum;
}

float turbulence(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves) {
    const float n = octaves_resolved(dpdx, dpdy, max_octaves);
    const int whole = static_cast<int>(std::floor(n));
    float sum = 0, frequency = 1, amplitude = 1;
    for (int i = 0; i < whole; ++i) {
        sum += amplitude * std::abs(perlin_noise(p * frequency));
        frequency *= 1.99f;
        amplitude *= omega;
    }
    sum += amplitude * lerp(smooth_step(0.3f, 0.7f, n - float(whole)), 0.2f,
                            std::abs(perlin_noise(p * frequency)));
    for (int i = whole; i < max_octaves; ++i) {
        sum += amplitude * 0.2f;
        amplitude *= omega;
    }
    return sum;
}

}  // namespace cmam::render
