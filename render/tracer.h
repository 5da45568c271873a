// render — what the integrator (integrator.cpp) and the film's render loop (film.cpp) share:
// the per-sample random numbers, the per-row counts, the AOV sample, and tracing camera rays,
// one or a packet at a time. Private to the tracer.
#pragma once

#include <algorithm>
#include <cstdint>
#include <forward_list>
#include <functional>
#include <optional>
#include <vector>

#include "render/footprint/footprint.h"
#include "render/integrator.h"
#include "render/shading.h"

namespace cmam::render {

/// Small counter-based generator (SplitMix64): reproducible streams per pixel sample.
class Rng {
  public:
    explicit Rng(uint64_t seed) : m_state(seed) {}
    uint64_t next_u64() { return mix(m_state += kStep); }
    float next_float() { return to_float(next_u64()); }
    /// The float the k-th next_float() (k = 0, 1, ...) of a generator seeded with `seed` returns,
    /// without drawing the ones before it (the state advances by a constant step).
    static float float_at(uint64_t seed, uint64_t k) {
        return to_float(mix(seed + (k + 1) * kStep));
    }

  private:
    static constexpr uint64_t kStep = 0x9E3779B97F4A7C15ull;
    static uint64_t mix(uint64_t z) {
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    static float to_float(uint64_t x) {
        return std::min(float(x >> 40) * 0x1.0p-24f, 0x1.fffffep-1f);
    }
    uint64_t m_state;
};

/// Ray counts of one row, added to the shared totals once per row (no per-ray atomics).
struct RayCounts {
    uint64_t camera = 0, secondary = 0, shadow = 0;
    LookupCounts lookups;
    uint64_t dropped_differentials = 0;
    uint64_t non_finite_samples = 0;  // samples whose radiance was NaN or infinite
    bool count_lookups = true;        // whether texture lookups are counted (RenderOptions)

    void add_to(RenderStats* stats) const {
        if (!stats) return;
        stats->camera_rays += camera;
        stats->secondary_rays += secondary;
        stats->shadow_rays += shadow;
        for (int k = 0; k < texture::kFilterKinds; ++k)
            stats->lookups_by_filter[k] += lookups.by_filter[k];
        stats->lookups_point_sampled += lookups.point_sampled;
        stats->lookups_non_finite += lookups.non_finite;
        stats->cmam_2d_without_above += lookups.cmam_2d_without_above;
        stats->dropped_differentials += dropped_differentials;
        stats->non_finite_samples += non_finite_samples;
    }
};

/// The AOV sample of one camera ray: three values, recorded at the first non-specular hit.
struct Aov {
    AovKind kind = AovKind::None;
    bool recorded = false;
    float v[3] = {0, 0, 0};
};

inline uint64_t mix_seed(uint64_t a, uint64_t b) {
    uint64_t z = a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull;
    z = (z ^ (z >> 33)) * 0xff51afd7ed558ccdull;
    z = (z ^ (z >> 33)) * 0xc4ceb9fe1a85ec53ull;
    return z ^ (z >> 33);
}

/// A permutation of [0, n) chosen by `key`: a four-round Feistel network on 2h bits (2^2h the
/// power of four at or above n; each round a bijection there, whatever its round function, here
/// mix_seed), repeated until the value falls below n (cycle walking; under four rounds expected).
inline uint32_t permute(uint32_t i, uint32_t n, uint64_t key) {
    int h = 0;
    while ((uint64_t(1) << (2 * h)) < n) ++h;
    const uint32_t half = (uint32_t(1) << h) - 1;
    do {
        uint32_t l = i >> h, r = i & half;
        for (uint64_t round = 0; round < 4; ++round) {
            const uint32_t f = uint32_t(mix_seed(key + round, r)) & half;
            const uint32_t next = l ^ f;
            l = r;
            r = next;
        }
        i = (l << h) | r;
    } while (i >= n);
    return i;
}

/// Number `dim` of a pixel's sample `stratum` of `strata`, stratified over the pixel's samples:
/// in each dimension the samples take the strata [k/strata, (k+1)/strata) once each, in an order
/// of the pixel's own (`key`) per dimension, at `jitter` within the stratum. Uniform in [0,1)
/// for each sample, as the unstratified number would be.
inline float stratified(uint64_t key, uint32_t stratum, uint32_t strata, int dim, float jitter) {
    const uint32_t s = permute(stratum, strata, mix_seed(key, uint64_t(dim)));
    return std::min((float(s) + jitter) / float(strata), 0x1.fffffep-1f);
}

/// A point in [0,1)^2 of a pixel's sample `stratum` of nx x ny, stratified in 2-D: the pixel's
/// samples take the nx x ny cells once each, in the order `key` chooses, at (ju, jv) within the
/// cell. Uniform in [0,1)^2 for each sample.
inline void stratified2(uint64_t key, uint32_t stratum, uint32_t nx, uint32_t ny, float ju,
                        float jv, float& u, float& v) {
    const uint32_t cell = permute(stratum, nx * ny, key);
    u = std::min((float(cell % nx) + ju) / float(nx), 0x1.fffffep-1f);
    v = std::min((float(cell / nx) + jv) / float(ny), 0x1.fffffep-1f);
}

/// The lens sample in [0,1)^2 of a pixel's camera sample `sample` (of nx x ny), stratified as its
/// image-plane position is: the pixel's samples take the nx x ny strata of the lens square once
/// each, in a random order of the pixel's own (so that a sample's lens stratum does not follow its
/// image-plane stratum), jittered within the stratum by the sample's own numbers.
inline void lens_sample(uint64_t pixel_seed, int sample, int nx, int ny, float& lu, float& lv) {
    constexpr uint64_t kLensStream = 0x4c656e73ull;
    const uint64_t key = mix_seed(pixel_seed, kLensStream);
    const uint64_t seed = mix_seed(key, uint64_t(sample) + 1);
    stratified2(key, uint32_t(sample), uint32_t(nx), uint32_t(ny), Rng::float_at(seed, 0),
                Rng::float_at(seed, 1), lu, lv);
}

/// A shadow ray of one light sample at a hit, traced one by one or in packets: the segment
/// org + t dir, t in (0, tmax), and what the sample adds to direct lighting when nothing lies
/// along it (`clear`; set directly when there is nothing to trace, `traced` false).
struct ShadowRay {
    Vec3 org, dir;
    float tmax = 0;
    int light = 0;  // the light's index in Scene::lights
    Rgb contribution;
    bool traced = true;
    bool clear = false;
};

/// Sets r.clear by tracing r (when it is to be traced).
inline void trace_shadow_ray(const Scene& scene, ShadowRay& r) {
    if (r.traced) r.clear = !scene.occluded(r.org, r.dir, 0, r.tmax);
}

/// A ray with the footprint state it carries.
struct TracedRay {
    Vec3 org, dir;
    RayFootprint fp;
};

/// A hit's radiance in parts, as trace_packet keeps it until every shadow ray of its packet is
/// traced: what the hit emits, its direct light (its shadow rays), and its reflected and
/// transmitted children's radiance (other deferred hits) times their weights, summed in li's
/// order once those are known.
struct DeferredHit {
    bool pending = false;              // false: `radiance` is the ray's whole radiance
    Rgb radiance;                      // pending: what the hit emits
    bool lit = false;                  // the direct light is added
    std::size_t first = 0, count = 0;  // the hit's shadow rays in the scratch's `shadow`
    std::size_t cursor = 0;            // the next of them to trace (light by light)
    bool children = false;             // under the depth limit: the children are added
    struct Child {
        bool made = false;  // false: no child along this lobe (its radiance is zero)
        Rgb weight;         // the lobe's reflectance times its Fresnel term
        int hit = -1;       // the child ray's deferred hit
    };
    Child child[2];  // reflected, transmitted
};

/// A ray made at a deferred hit and waiting to be traced: the ray, its depth and its own
/// deferred hit.
struct PendingRay {
    TracedRay ray;
    int depth = 0;
    int hit = -1;
};

/// trace_packet's scratch, reused between calls (no allocation per packet once grown). The
/// slots a packet fills are made here once, not on the stack per packet (GCC clears an array of
/// empty optionals whole: 4 KB per packet for the camera rays' hits).
struct PacketScratch {
    static constexpr int kSamples = 16;  // Scene::kPacketSize
    std::vector<ShadowRay> shadow;
    std::vector<DeferredHit> hits;
    std::vector<PendingRay> pending[kSamples];  // per sample, a stack
    // Hit slots of the camera rays and of a step's rays, each written by
    // Scene::intersect_packet; the rays made at each sample's hit (2 per sample); a step's rays
    // taken from the stacks.
    std::vector<std::optional<SurfaceHit>> camera_hits =
        std::vector<std::optional<SurfaceHit>>(kSamples);
    std::vector<std::optional<SurfaceHit>> step_hits =
        std::vector<std::optional<SurfaceHit>>(kSamples);
    std::vector<TracedRay> made = std::vector<TracedRay>(2 * kSamples);
    std::vector<PendingRay> step = std::vector<PendingRay>(kSamples);
};

/// One camera sample as trace_packet takes it: its ray and random seed, and where its counts
/// (may be null) and AOV sample (null: radiance) go.
struct CameraPath {
    TracedRay ray;
    uint64_t seed = 0;
    // The pixel's seed and the sample's number among the pixel's samples (path tracing
    // stratifies the sample's first numbers over them).
    uint64_t pixel_seed = 0;
    uint32_t sample = 0, samples = 1, samples_x = 1;  // (samples_x: the strata along x)
    RayCounts* counts = nullptr;
    Aov* aov = nullptr;
    // The sample's weight (a realistic camera's, CameraRay::weight); 0: blocked by the lens, not
    // traced, its radiance 0.
    float weight = 1;
};

/// What trace_one gives for each of n <= Scene::kPacketSize camera samples, into radiance[i],
/// bit for bit: each sample's hits shaded in trace_one's order, but with the samples' camera
/// rays, then their reflected and transmitted rays (the samples' paths in lock step),
/// intersected as packets, and the shadow rays of every hit towards each delta light (point,
/// spot, distant, ...) traced in packets (coherent rays: Embree's packet traversal shares node
/// tests between them).
void trace_packet(const Scene& scene, const FootprintProducers& footprints, const CameraPath* paths,
                  int n, CmamRowState* cmam, PacketScratch& scratch, Rgb* radiance);

/// The footprint producers of the film's camera rays at `spp` samples per pixel.
FootprintProducers film_footprints(const Scene& scene, int spp);

/// The camera ray of raster position (fx, fy), one ray at a time, into `ray` (every member but
/// the footprint's tag): a lens's sample is stratum `sample` of the pixel's nx x ny (pixel seed
/// `pixel_seed`), (to_stratum_x, to_stratum_y) the offset to the sample's stratum's centre. Its
/// weight: 1, or a realistic camera's (0: blocked by the lens, or dropped, and not to be traced).
float camera_ray(const Scene& scene, const FootprintProducers& footprints, float fx, float fy,
                 uint64_t pixel_seed, int sample, int nx, int ny, float to_stratum_x,
                 float to_stratum_y, TracedRay& ray);

/// What SPPM's camera path of one pixel found in one iteration (sppm.cpp): the light it gathered
/// on the way (`ld`: emitted and direct), and, where it reached a diffuse (or, at its last depth,
/// a glossy) surface, the visible point: its position, its BSDF (whose mix layers `layers` holds)
/// and the outgoing direction's terms, and the path's weight up to it.
struct SppmVisiblePoint {
    Rgb ld;
    bool found = false;
    Vec3 p;
    Rgb beta;
    std::optional<Bsdf> bsdf;
    std::forward_list<Bsdf> layers;
    Bsdf::Outgoing wo;
};

/// SPPM's camera path along `ray` (its footprints those of `footprints`), random numbers from
/// `seed`, into `vp`; `counts` and `cmam` (the CMAM's caches) may be null.
void sppm_visible_point(const Scene& scene, const FootprintProducers& footprints,
                        const TracedRay& ray, uint64_t seed, RayCounts* counts, CmamRowState* cmam,
                        SppmVisiblePoint& vp);

/// Where a photon arrives: the hit point, the direction it came from (towards where it was), and
/// its weight.
using PhotonDeposit = std::function<void(const Vec3& p, const Vec3& wi, const Rgb& beta)>;

/// A photon's path from org along dir with weight `beta`, its random numbers from `seed`: each
/// hit after the first goes to `deposit`.
void sppm_photon(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
                 const Vec3& dir, const Rgb& beta, uint64_t seed, RayCounts* counts,
                 const PhotonDeposit& deposit);

/// Where a light path's vertex joins the camera (lighttrace.cpp): the unit direction from the
/// vertex towards the camera's lens point `lens`, the camera's importance over the density of
/// choosing that point (W_e / pdf, by solid angle at the vertex: 1 / (d^2 A cos^3 theta) for a
/// film of area A at unit distance), and the pixel of the cropped film it lands in.
struct CameraJoin {
    Vec3 wi, lens;
    float importance = 0;
    uint32_t pixel = 0;
};

/// Joins a vertex at p to the camera with two uniform numbers (a lens point); false where the
/// camera does not see p's direction (behind it, outside the cropped film).
using CameraJoinFn = std::function<bool(const Vec3& p, float u1, float u2, CameraJoin& join)>;

/// What a light path adds to a pixel of the cropped film.
using LightSplatFn = std::function<void(uint32_t pixel, const Rgb& L)>;

/// A light path of pbrt-v3's bdpt from a delta light (algorithms.md §27): from org along dir with
/// weight `beta`, its random numbers from `seed`. A path whose first bounce is not specular ends
/// there (the path tracer's light sample at that hit is its estimate); past a specular first
/// bounce each hit with non-specular lobes is joined to the camera by `join`, and what it sees
/// there, unoccluded, goes to `splat`; the path scatters with importance's weights and shading
/// normals' correction, and goes on with the probability that keeps its weight's luminance.
void light_path(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
                const Vec3& dir, const Rgb& beta, uint64_t seed, RayCounts* counts,
                const CameraJoinFn& join, const LightSplatFn& splat);

/// A point, spot, goniometric or projection light's intensity towards the unit direction w (away
/// from the light), `i` (its intensity, or that over a distance squared) times its image and
/// spot falloff: 0 outside a spot's cone.
Rgb positional_intensity(const Light& light, const Vec3& w, Rgb i);

/// Radiance (or, with `aov`, the AOV sample) along one camera ray with footprint state `fp`;
/// `counts` and `cmam` may be null.
Rgb trace_one(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
              const Vec3& dir, const RayFootprint& fp, uint64_t seed, RayCounts* counts,
              CmamRowState* cmam, Aov* aov);

}  // namespace cmam::render
