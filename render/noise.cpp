#include "render/noise.h"

#include <algorithm>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

#if defined(__SSE2__)
namespace {

// Noise at up to four points at once (n of them; the other lanes repeat the first point), each
// lane taking perlin_noise's operations for its point in the same order, so each value is the
// same bit for bit (test Noise.OctavesFourAtOnceEqualOneByOne). The lattice cells and hashes
// are computed point by point (as vectors, the cells were 3% slower: the points' scalar chains
// overlap); the eight corners' gradients, the fades and the interpolation four points to an
// instruction. One noise alone is a chain of dependent steps (floor, three table
// reads, gradients, three interpolations); the octaves of a sum are independent, and four at
// once share the chain.
void perlin_noise4(const Vec3* p, int n, float* out) {
    alignas(16) float dx[4], dy[4], dz[4];
    alignas(16) int32_t h[8][4];  // corner (k, j, i) = 4k + 2j + i, lane = point
    for (int l = 0; l < 4; ++l) {
        const Vec3& q = p[l < n ? l : 0];
        const float fx = std::floor(q.x), fy = std::floor(q.y), fz = std::floor(q.z);
        dx[l] = q.x - fx;
        dy[l] = q.y - fy;
        dz[l] = q.z - fz;
        const int x = static_cast<int>(static_cast<long long>(fx) & 255),
                  y = static_cast<int>(static_cast<long long>(fy) & 255),
                  z = static_cast<int>(static_cast<long long>(fz) & 255);
        const int px[2] = {perm(x), perm(x + 1)};
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                const int pxy = perm(px[i] + y + j);
                h[2 * j + i][l] = perm(pxy + z) & 15;
                h[4 + 2 * j + i][l] = perm(pxy + z + 1) & 15;
            }
    }
    const __m128 vdx = _mm_load_ps(dx), vdy = _mm_load_ps(dy), vdz = _mm_load_ps(dz);
    const __m128 one_f = _mm_set1_ps(1.0f);
    const __m128 vdx1 = _mm_sub_ps(vdx, one_f), vdy1 = _mm_sub_ps(vdy, one_f),
                 vdz1 = _mm_sub_ps(vdz, one_f);
    const __m128i c4 = _mm_set1_epi32(4), c8 = _mm_set1_epi32(8), c12 = _mm_set1_epi32(12),
                  c13 = _mm_set1_epi32(13), one = _mm_set1_epi32(1), two = _mm_set1_epi32(2);
    const __m128 sign = _mm_castsi128_ps(_mm_set1_epi32(int(0x80000000u)));
    // gradient() of every lane's corner: its hash chooses a of (dx, dy), b of (dy, dz), signs.
    auto grad = [&](int corner, __m128 ddx, __m128 ddy, __m128 ddz) {
        const __m128i hc = _mm_load_si128(reinterpret_cast<const __m128i*>(h[corner]));
        const __m128i e = _mm_or_si128(_mm_cmpeq_epi32(hc, c12), _mm_cmpeq_epi32(hc, c13));
        const __m128 ma = _mm_castsi128_ps(_mm_or_si128(_mm_cmplt_epi32(hc, c8), e)),
                     mb = _mm_castsi128_ps(_mm_or_si128(_mm_cmplt_epi32(hc, c4), e));
        __m128 a = _mm_or_ps(_mm_and_ps(ma, ddx), _mm_andnot_ps(ma, ddy));
        __m128 b = _mm_or_ps(_mm_and_ps(mb, ddy), _mm_andnot_ps(mb, ddz));
        const __m128 na = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(hc, one), one)),
                     nb = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(hc, two), two));
        a = _mm_xor_ps(a, _mm_and_ps(na, sign));
        b = _mm_xor_ps(b, _mm_and_ps(nb, sign));
        return _mm_add_ps(a, b);
    };
    // dx - float(i) is dx itself for i = 0 and dx - 1 for i = 1, as in perlin_noise.
    const __m128 w000 = grad(0, vdx, vdy, vdz), w001 = grad(1, vdx1, vdy, vdz),
                 w010 = grad(2, vdx, vdy1, vdz), w011 = grad(3, vdx1, vdy1, vdz),
                 w100 = grad(4, vdx, vdy, vdz1), w101 = grad(5, vdx1, vdy, vdz1),
                 w110 = grad(6, vdx, vdy1, vdz1), w111 = grad(7, vdx1, vdy1, vdz1);
    auto fade4 = [](__m128 t) {  // t t t (t (t 6 - 15) + 10)
        const __m128 inner =
            _mm_add_ps(_mm_mul_ps(t, _mm_sub_ps(_mm_mul_ps(t, _mm_set1_ps(6)), _mm_set1_ps(15))),
                       _mm_set1_ps(10));
        return _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(t, t), t), inner);
    };
    auto lerp4 = [](__m128 t, __m128 a, __m128 b) {  // a + t (b - a)
        return _mm_add_ps(a, _mm_mul_ps(t, _mm_sub_ps(b, a)));
    };
    const __m128 u = fade4(vdx), v = fade4(vdy), s = fade4(vdz);
    const __m128 y0 = lerp4(v, lerp4(u, w000, w001), lerp4(u, w010, w011));
    const __m128 y1 = lerp4(v, lerp4(u, w100, w101), lerp4(u, w110, w111));
    alignas(16) float r[4];
    _mm_store_ps(r, lerp4(s, y0, y1));
    for (int l = 0; l < n; ++l) out[l] = r[l];
}

}  // namespace
#endif

namespace {

// The noise of octaves 0..count-1 of a sum at p, octave i at frequency 1.99^i (multiplied up
// one octave at a time, as the sums did), handed to each(i, noise) in order; four at a time
// where the vector noise exists.
template <class F>
void octave_noise(const Vec3& p, int count, F&& each) {
    float frequency = 1;
#if defined(__SSE2__)
    for (int i0 = 0; i0 < count; i0 += 4) {
        const int m = std::min(4, count - i0);
        Vec3 q[4];
        for (int k = 0; k < m; ++k) {
            q[k] = p * frequency;
            frequency *= 1.99f;
        }
        float r[4];
        perlin_noise4(q, m, r);
        for (int k = 0; k < m; ++k) each(i0 + k, r[k]);
    }
#else
    for (int i = 0; i < count; ++i) {
        each(i, perlin_noise(p * frequency));
        frequency *= 1.99f;
    }
#endif
}

}  // namespace

float fbm(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves) {
    const float n = octaves_resolved(dpdx, dpdy, max_octaves);
    const int whole = static_cast<int>(std::floor(n));
    // Octaves 0..whole-1 whole, octave `whole` faded in.
    float sum = 0, amplitude = 1;
    octave_noise(p, whole + 1, [&](int i, float noise) {
        if (i < whole) {
            sum += amplitude * noise;
            amplitude *= omega;
        } else {
            sum += amplitude * smooth_step(0.3f, 0.7f, n - float(whole)) * noise;
        }
    });
    return sum;
}

float turbulence(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves) {
    const float n = octaves_resolved(dpdx, dpdy, max_octaves);
    const int whole = static_cast<int>(std::floor(n));
    float sum = 0, amplitude = 1;
    octave_noise(p, whole + 1, [&](int i, float noise) {
        if (i < whole) {
            sum += amplitude * std::abs(noise);
            amplitude *= omega;
        } else {
            sum +=
                amplitude * lerp(smooth_step(0.3f, 0.7f, n - float(whole)), 0.2f, std::abs(noise));
        }
    });
    for (int i = whole; i < max_octaves; ++i) {
        sum += amplitude * 0.2f;
        amplitude *= omega;
    }
    return sum;
}

}  // namespace cmam::render
