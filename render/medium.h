// render — participating media, as pbrt-v3's volpath integrator renders them: a homogeneous
// medium and a grid of densities (pbrt-v3's "heterogeneous"), each scattering by the
// Henyey–Greenstein phase function. Distances are sampled and transmittances estimated along a
// ray with unit direction, in world units (docs/algorithms.md §19).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "render/math.h"

namespace cmam::render {

/// pbrt-v3's Henyey–Greenstein phase function for directions wo and wi that both point away
/// from the scattering point (so forward scattering, g > 0, favours wi = -wo): its value, which
/// is also the density hg_sample draws wi with. |g| < 1.
inline float hg_phase(float cos_wo_wi, float g) {
    const float denom = 1 + g * g + 2 * g * cos_wo_wi;
    return (1 - g * g) / (4 * kPi * denom * std::sqrt(std::max(denom, 1e-30f)));
}

/// A direction wi drawn from hg_phase(dot(wo, wi), g) for uniform u1, u2; returns its density.
float hg_sample(const Vec3& wo, float g, float u1, float u2, Vec3& wi);

/// A participating medium. Its coefficients are per unit of world distance, "scale" applied.
struct Medium {
    enum class Type { Homogeneous, Grid };
    Type type = Type::Homogeneous;
    Rgb sigma_a, sigma_s, sigma_t;  // absorption, scattering, their sum
    float g = 0;                    // Henyey–Greenstein asymmetry

    // Grid: nx * ny * nz densities, x fastest, over the unit cube of grid space, which
    // grid_from_world maps the world into; the density at a point is their trilinear
    // interpolation (a sample at each cell's centre, 0 beyond the grid). Its attenuation is
    // sigma_t's first channel times the density (pbrt-v3 requires it equal in every channel).
    int nx = 1, ny = 1, nz = 1;
    std::vector<float> density;
    float grid_sigma_t = 0, inv_max_density = 0;
    std::array<double, 12> grid_from_world{};
    // Majorants: a coarse grid (mx * my * mz cells over the unit cube, x fastest) of the largest
    // density_at within each cell, which tracking steps through (build_majorants; without
    // them, one cell of the largest density).
    int mx = 0, my = 0, mz = 0;
    std::vector<float> majorant;

    /// The grid's density at p in grid space.
    float density_at(const Vec3& p) const;
    /// Makes the majorant grid (at most 16 cells a side) from the densities.
    void build_majorants();
};

/// Where a ray scatters in a medium, if it does before tmax, and the weight that sampling gives
/// what lies beyond (pbrt-v3's Medium::Sample: transmittance over its density, times sigma_s
/// at a scattering point).
struct MediumSample {
    Rgb weight{1, 1, 1};
    float t = 0;
    bool scattered = false;
};

namespace media_detail {

// At most this many tentative collisions per tracking call: a grid whose sigma_t times its
// largest density, times the length a ray crosses, is beyond any real scene's (a hostile file)
// would otherwise take that many steps. A ray that reaches the bound is taken as absorbed.
constexpr int kMaxTrackingSteps = 1 << 20;

enum class Tracked { Passed, Stopped, Bound };

// Tentative collisions along og + t dg (grid space; t in world units), t0 <= t < t1, cell by
// cell of m's majorant grid (Amanatides and Woo's traversal): in a cell of majorant rho_max, the
// steps are exponential at the rate sigma_t rho_max, and a step that leaves the cell starts again
// at its boundary at the next cell's rate (the exponential forgets), so cells of no density cost
// nothing. visit(t, rho / rho_max) is called at each and returns true to stop there.
template <class Uniform, class Visit>
Tracked track(const Medium& m, const Vec3& og, const Vec3& dg, float t0, float t1, Uniform& u,
              Visit&& visit) {
    const bool coarse = !m.majorant.empty();
    const int res[3] = {coarse ? m.mx : 1, coarse ? m.my : 1, coarse ? m.mz : 1};
    const Vec3 p0 = og + t0 * dg;
    int cell[3], step[3];
    float next[3], delta[3];
    for (int a = 0; a < 3; ++a) {
        const float x = p0[a] * float(res[a]);
        cell[a] = std::clamp(int(std::floor(std::isfinite(x) ? x : 0.0f)), 0, res[a] - 1);
        if (dg[a] > 0) {
            step[a] = 1;
            next[a] = (float(cell[a] + 1) / float(res[a]) - og[a]) / dg[a];
            delta[a] = 1 / (float(res[a]) * dg[a]);
        } else if (dg[a] < 0) {
            step[a] = -1;
            next[a] = (float(cell[a]) / float(res[a]) - og[a]) / dg[a];
            delta[a] = -1 / (float(res[a]) * dg[a]);
        } else {
            step[a] = 0;
            next[a] = delta[a] = std::numeric_limits<float>::infinity();
        }
    }
    float t = t0;
    int steps = 0;
    while (t < t1) {
        const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
        const float exit = std::max(t, std::min(next[a], t1));  // (rounding at a face: not back)
        const float maj =
            coarse ? m.majorant[(static_cast<std::size_t>(cell[2]) * res[1] + cell[1]) * res[0] +
                                cell[0]]
                   : 1 / m.inv_max_density;
        if (maj > 0) {
            const float rate = maj * m.grid_sigma_t;
            for (;;) {
                if (++steps > kMaxTrackingSteps) return Tracked::Bound;
                const float dt = -std::log(1 - u()) / rate;
                if (!(t + dt < exit)) break;
                t += dt;
                if (visit(t, m.density_at(og + t * dg) / maj)) return Tracked::Stopped;
            }
        }
        t = exit;
        if (!(t < t1)) break;
        cell[a] += step[a];
        if (cell[a] < 0 || cell[a] >= res[a]) break;
        next[a] += delta[a];
        if (++steps > kMaxTrackingSteps) return Tracked::Bound;
    }
    return Tracked::Passed;
}

// The part [t0, t1] of [0, tmax] in which the ray o + t d (grid space) lies in the unit cube;
// false when there is none.
inline bool unit_cube_span(const Vec3& o, const Vec3& d, float tmax, float& t0, float& t1) {
    t0 = 0;
    t1 = tmax;
    for (int a = 0; a < 3; ++a) {
        const float inv = 1 / d[a];
        float n = (0 - o[a]) * inv, f = (1 - o[a]) * inv;
        if (n > f) std::swap(n, f);
        if (std::isnan(n) || std::isnan(f)) {  // parallel to the slab: inside it or never
            if (o[a] < 0 || o[a] > 1) return false;
            continue;
        }
        t0 = std::max(t0, n);
        t1 = std::min(t1, f);
        if (t0 > t1) return false;
    }
    return true;
}

inline Vec3 to_grid_point(const std::array<double, 12>& m, const Vec3& p) {
    return Vec3(float(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]),
                float(m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7]),
                float(m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]));
}
inline Vec3 to_grid_vector(const std::array<double, 12>& m, const Vec3& v) {
    return Vec3(float(m[0] * v.x + m[1] * v.y + m[2] * v.z),
                float(m[4] * v.x + m[5] * v.y + m[6] * v.z),
                float(m[8] * v.x + m[9] * v.y + m[10] * v.z));
}

}  // namespace media_detail

/// Samples where the ray o + t d (d a unit vector) scatters in m before tmax (which may be
/// infinite), drawing uniform numbers from u(): a homogeneous medium picks a channel and an
/// exponential distance in it (the density is the channels' mean), by sigma_t as pbrt-v3 or, in
/// a medium that absorbs more than it scatters, by sigma_s; a grid tracks by its largest
/// density (delta tracking).
template <class Uniform>
MediumSample sample_medium(const Medium& m, const Vec3& o, const Vec3& d, float tmax, Uniform&& u) {
    MediumSample s;
    if (m.type == Medium::Type::Homogeneous) {
        // pbrt-v3 draws the distance by sigma_t, so a ray ends (weight 0) where it samples
        // absorption. Where absorption dominates (coloured liquids and glass), drawing it by
        // sigma_s lets the ray pass weighted by its transmittance instead: the same
        // expectation, without the noise of absorption, and exact where nothing scatters
        // (docs/algorithms.md §19). Where scattering dominates, pbrt-v3's is the less noisy.
        const Rgb& k =
            m.sigma_s.r + m.sigma_s.g + m.sigma_s.b < m.sigma_a.r + m.sigma_a.g + m.sigma_a.b
                ? m.sigma_s
                : m.sigma_t;
        const float u0 = u(), u1 = u();
        const int c = std::min(int(u0 * 3), 2);
        const float kc = c == 0 ? k.r : c == 1 ? k.g : k.b;
        const float dist = kc > 0 ? -std::log(1 - u1) / kc : std::numeric_limits<float>::infinity();
        const float t = std::min(dist, tmax);
        s.scattered = t < tmax;
        // (t at most the largest float: an infinite distance gives 0 where a coefficient is
        // positive, and 1, not NaN, where it is 0.)
        const float tt = std::min(t, std::numeric_limits<float>::max());
        auto decay = [tt](const Rgb& k) {
            return Rgb(std::exp(-k.r * tt), std::exp(-k.g * tt), std::exp(-k.b * tt));
        };
        const Rgb tr = decay(m.sigma_t), e = decay(k);
        // The density of t (scattered) or the probability of passing, over the channels.
        const Rgb dens = s.scattered ? k * e : e;
        float pdf = (dens.r + dens.g + dens.b) / 3;
        if (pdf == 0) pdf = 1;
        s.weight = s.scattered ? tr * m.sigma_s / pdf : tr / pdf;
        s.t = t;
        return s;
    }
    if (!(m.grid_sigma_t > 0 && m.inv_max_density > 0)) return s;
    const Vec3 og = media_detail::to_grid_point(m.grid_from_world, o),
               dg = media_detail::to_grid_vector(m.grid_from_world, d);
    float t0, t1;
    if (!media_detail::unit_cube_span(og, dg, tmax, t0, t1)) return s;
    const media_detail::Tracked r =
        media_detail::track(m, og, dg, t0, t1, u, [&](float t, float ratio) {
            if (!(ratio > u())) return false;  // a null collision
            s.t = t;
            return true;
        });
    if (r == media_detail::Tracked::Bound) {
        s.weight = Rgb();
    } else if (r == media_detail::Tracked::Stopped) {
        s.scattered = true;
        s.weight = m.sigma_s / m.grid_sigma_t;
    }
    return s;
}

/// The transmittance of m along o + t d, 0 <= t < tmax (d a unit vector): exact in a
/// homogeneous medium, estimated without bias in a grid (ratio tracking, with Russian roulette
/// once it falls below 0.1, as pbrt-v3).
template <class Uniform>
Rgb medium_transmittance(const Medium& m, const Vec3& o, const Vec3& d, float tmax, Uniform&& u) {
    if (m.type == Medium::Type::Homogeneous) {
        const float tt = std::min(tmax, std::numeric_limits<float>::max());
        return Rgb(std::exp(-m.sigma_t.r * tt), std::exp(-m.sigma_t.g * tt),
                   std::exp(-m.sigma_t.b * tt));
    }
    if (!(m.grid_sigma_t > 0 && m.inv_max_density > 0)) return Rgb(1);
    const Vec3 og = media_detail::to_grid_point(m.grid_from_world, o),
               dg = media_detail::to_grid_vector(m.grid_from_world, d);
    float t0, t1;
    if (!media_detail::unit_cube_span(og, dg, tmax, t0, t1)) return Rgb(1);
    float tr = 1;
    bool zero = false;
    const media_detail::Tracked r =
        media_detail::track(m, og, dg, t0, t1, u, [&](float, float ratio) {
            tr *= 1 - std::clamp(ratio, 0.0f, 1.0f);
            if (tr < 0.1f) {
                const float q = std::max(0.05f, 1 - tr);
                if (u() < q) {
                    zero = true;
                    return true;
                }
                tr /= 1 - q;
            }
            return false;
        });
    if (r == media_detail::Tracked::Bound || zero) return Rgb();
    return Rgb(tr);
}

}  // namespace cmam::render
