// render — Perlin's improved gradient noise and the sums of octaves pbrt-v3's procedural
// textures are made of (fbm, wrinkled, windy, marble, dots). algorithms.md §14.
#pragma once

#include "render/math.h"

namespace cmam::render {

/// Perlin's improved noise at p: zero at every integer lattice point, about [-1, 1] between.
float perlin_noise(const Vec3& p);

/// Fractional Brownian motion: octaves of noise, each at 1.99 times the frequency and omega
/// times the amplitude of the last. dP/dx and dP/dy bound the octaves to those the footprint
/// resolves (zero: all of them), the last one faded in, as pbrt-v3 does.
float fbm(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves);

/// As fbm() with the absolute value of each octave (pbrt-v3's Turbulence); the octaves the
/// footprint does not resolve count as 0.2 each (about their mean), and so does the one faded
/// out, on top of its faded part, as in pbrt-v3.
float turbulence(const Vec3& p, const Vec3& dpdx, const Vec3& dpdy, float omega, int max_octaves);

}  // namespace cmam::render
