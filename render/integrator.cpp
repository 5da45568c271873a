#include "render/integrator.h"

#include <algorithm>
#include <bit>
#include <memory>

#include "render/footprint/footprint.h"
#include "render/shading.h"
#include "render/subsurface.h"
#include "render/tracer.h"

namespace cmam::render {

Rgb positional_intensity(const Light& light, const Vec3& w, Rgb i) {
    if (light.image) i = i * light.image->scale(w);
    if (light.type == Light::Type::Spot) {
        const float c = dot(w, light.direction);
        if (c < light.cos_total) return {};
        if (c < light.cos_falloff_start) {
            const float delta = (c - light.cos_total) / (light.cos_falloff_start - light.cos_total);
            i = i * ((delta * delta) * (delta * delta));
        }
    }
    return i;
}

namespace {
// What a ray that leaves the scene sees: the infinite lights, environment maps filtered over the
// ray differential's footprint when the ray carries one.
Rgb escaped_radiance(const Scene& scene, const Vec3& dir, const RayDifferential& diff) {
    Rgb l{};
    for (const Light& light : scene.lights) {
        if (light.type != Light::Type::Infinite) continue;
        if (!light.env)
            l += light.intensity;
        else if (diff.valid && light.env_footprint)
            l += light.intensity * light.env->radiance(dir, &diff.dddx, &diff.dddy);
        else
            l += light.intensity * light.env->radiance(dir);
    }
    return l;
}

float ray_epsilon(const Vec3& p) {
    return 1e-4f * (1 + max_abs(p));
}

// (A curve's hit is left by more: SurfaceHit::offset.)
Vec3 offset_origin(const SurfaceHit& h, const Vec3& w) {
    const Vec3 n = faceforward(h.ng, w);
    return h.p +
           n * (ray_epsilon(h.p) + h.offset * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z)));
}

struct Tracer {
    const Scene& scene;
    const FootprintProducers& footprints;
    RayCounts* counts;
    Rng& rng;
    CmamRowState* cmam;              // the strip's CMAM caches
    std::vector<ShadowRay>& shadow;  // shadow rays being traced (direct lighting's scratch)

    // Path tracing stratifies a sample's first numbers over its pixel's samples (set by
    // trace_packet; strata 0: none), as pbrt-v3's stratified sampler does its first dimensions:
    // its first kStratified1D single numbers (next) each in 1-D strata, its first
    // kStratified2D pairs (next2: a light's point, a BSDF's direction) each in the pixel's
    // nx x ny cells, in random orders of the pixel's own per dimension, jittered by the sample's
    // own generator. Each number stays uniform, so every estimate keeps its mean; the pixel's
    // samples cover each dimension evenly. Without strata both draw the generator's numbers in
    // order.
    static constexpr int kStratified1D = 8, kStratified2D = 8;
    uint64_t strata_key = 0;
    uint32_t stratum = 0, strata = 0, strata_x = 1;
    int dim1 = 0, dim2 = 0;
    [[gnu::always_inline]] float next() {
        if (strata > 1 && dim1 < kStratified1D)
            return stratified(strata_key, stratum, strata, dim1++, rng.next_float());
        return rng.next_float();
    }
    [[gnu::always_inline]] void next2(float& u, float& v) {
        u = rng.next_float();
        v = rng.next_float();
        if (strata > 1 && dim2 < kStratified2D)
            stratified2(mix_seed(strata_key, 0x3244ull + uint64_t(dim2++)), stratum, strata_x,
                        strata / strata_x, u, v, u, v);
    }

    // pbrt-v3's "ambientocclusion" integrator at a hit seen along `dir` (algorithms.md §23):
    // scene.ao_samples directions over the hemisphere of the geometric normal turned to the
    // viewer, cosine-weighted or uniform, from pairs of numbers in a Latin hypercube (each
    // number in its own of n strata, the strata paired at random), as pbrt-v3's stratified
    // sampler makes a sample's arrays; each direction nothing occludes, however far, adds
    // cos / (pdf n): pi / n for the cosine's, 2 pi cos / n for the uniform's. Traced in packets.
    Rgb ambient_occlusion(const SurfaceHit& h, const Vec3& dir) {
        const int n = scene.ao_samples;
        if (n <= 0) return {};
        const Vec3 ng = faceforward(h.ng, -dir);
        const Frame frame = Frame::from_z(ng);
        thread_local std::vector<uint32_t> strata;  // the second number's stratum per direction
        strata.resize(static_cast<std::size_t>(n));
        for (int i = 0; i < n; ++i) strata[static_cast<std::size_t>(i)] = static_cast<uint32_t>(i);
        for (int i = n - 1; i > 0; --i)
            std::swap(strata[static_cast<std::size_t>(i)],
                      strata[static_cast<std::size_t>(rng.next_u64() % uint64_t(i + 1))]);
        constexpr int N = Scene::kPacketSize;
        Vec3 org[N], dirs[N];
        float tmax[N], weight[N];
        bool occluded[N];
        int m = 0;
        float sum = 0;
        auto flush = [&] {
            scene.occluded_packet(org, dirs, tmax, m, occluded);
            for (int k = 0; k < m; ++k)
                if (!occluded[k]) sum += weight[k];
            if (counts) counts->shadow += static_cast<uint64_t>(m);
            m = 0;
        };
        const float inv_n = 1.0f / float(n);
        for (int i = 0; i < n; ++i) {
            const float u1 = std::min((float(i) + rng.next_float()) * inv_n, 0x1.fffffep-1f),
                        u2 = std::min(
                            (float(strata[static_cast<std::size_t>(i)]) + rng.next_float()) * inv_n,
                            0x1.fffffep-1f);
            const Vec3 local = hemisphere_direction(u1, u2, !scene.ao_cosine),
                       wi = frame.to_world(local);
            org[m] = offset_origin(h, wi);
            dirs[m] = wi;
            tmax[m] = std::numeric_limits<float>::infinity();
            weight[m] = scene.ao_cosine ? kPi : 2 * kPi * local.z;
            if (++m == N) flush();
        }
        if (m > 0) flush();
        return Rgb(sum * inv_n);
    }

    // What an area light's surface emits towards w (pbrt-v3: along its oriented normal only,
    // unless two-sided).
    Rgb emitted(const SurfaceHit& h, const Vec3& w) const {
        if (h.prim->area_light < 0) return {};
        const Light& l = scene.lights[static_cast<std::size_t>(h.prim->area_light)];
        return l.two_sided || dot(h.ng, w) > 0 ? l.intensity : Rgb();
    }

    /// Light arriving at a shading point from one sample of a light: its direction, its
    /// radiance (or intensity over distance squared), the density it was drawn with, and what a
    /// shadow ray must clear (a distance, or for area lights the point on the light).
    struct LightSample {
        Rgb li;
        Vec3 wi;
        float dist = std::numeric_limits<float>::infinity();
        float pdf = 1;
        Vec3 target;  // area lights: the point sampled on the light
    };

    // Point, spot, goniometric and projection lights: a delta position.
    static std::optional<LightSample> sample_positional(const Light& light, const SurfaceHit& h) {
        LightSample ls;
        Vec3 d = light.position - h.p;
        float d2 = dot(d, d);
        ls.dist = std::sqrt(d2);
        ls.wi = d / ls.dist;
        if (light.type == Light::Type::Spot && dot(-ls.wi, light.direction) < light.cos_total)
            return std::nullopt;
        ls.li = positional_intensity(light, -ls.wi, light.intensity / d2);
        return ls;
    }

    // A light sample from the sample of its environment map (none where the map gave none).
    static std::optional<LightSample> from_map(const Light& light,
                                               const EnvironmentMap::Sample& s) {
        if (s.pdf == 0) return std::nullopt;
        LightSample ls;
        ls.li = light.intensity * s.radiance;
        ls.wi = s.wi;
        ls.pdf = s.pdf;
        return ls;
    }

    std::optional<LightSample> sample_infinite(const Light& light, const SurfaceHit& h,
                                               const Vec3& wo) {
        LightSample ls;
        if (light.env) {  // by the map's luminance
            float u1, u2;
            next2(u1, u2);
            return from_map(light, light.env->sample(u1, u2));
        }
        // The BSDFs it lights reflect only, over the hemisphere of the geometric normal on wo's
        // side, weighted by |wi . ns|: sampled cosine-weighted about that normal, the same
        // expected value as pbrt-v3's sphere sampling with lower variance. Where the shading
        // normal differs (a mesh's given normals, bump mapping), a share q = min(1/2, 1 - ns.ng)
        // of the samples is uniform over the geometric hemisphere and the rest cosine-weighted
        // about the shading normal, and the pdf is the mixture's: |wi . ns| / pdf stays bounded,
        // where |wi . ns| / cos about the geometric normal grows without bound towards its
        // horizon (fireflies; algorithms.md §13), and a shading normal near the geometric one
        // keeps nearly all of the cosine's samples.
        float u1, u2;
        next2(u1, u2);
        const Vec3 ng = faceforward(h.ng, wo), ns = faceforward(h.ns, wo);
        const bool mixture = !(ns.x == ng.x && ns.y == ng.y && ns.z == ng.z);
        const float share = mixture ? uniform_share(ng, ns) : 0.0f;
        const bool uniform = u1 < share;
        if (mixture) u1 = uniform ? u1 / share : (u1 - share) / (1 - share);
        const Vec3 local = hemisphere_direction(u1, u2, uniform);
        ls.wi = Frame::from_z(uniform || !mixture ? ng : ns).to_world(local);
        ls.pdf = !mixture ? local.z * kInvPi : mixture_pdf(ng, ns, share, ls.wi);
        if (ls.pdf == 0) return std::nullopt;
        ls.li = light.intensity;
        return ls;
    }

    // The share of sample_infinite's samples uniform over ng's hemisphere where the shading
    // normal ns differs from the geometric one ng.
    static float uniform_share(const Vec3& ng, const Vec3& ns) {
        return std::clamp(1 - dot(ns, ng), 1e-3f, 0.5f);
    }

    // The density of sample_infinite's mixture (a share uniform over ng's hemisphere, the rest
    // cosine-weighted about ns) at wi.
    static float mixture_pdf(const Vec3& ng, const Vec3& ns, float share, const Vec3& wi) {
        const float cos_s = std::max(0.0f, dot(wi, ns)), cos_g = dot(wi, ng);
        return (1 - share) * cos_s * kInvPi + (cos_g > 0 ? share * 0.5f * kInvPi : 0.0f);
    }

    // The density with which sample_light draws direction wi from h (solid angle): for an infinite
    // light, and for an area light whose surface the ray along wi meets first at `y`.
    float infinite_pdf(const Light& light, const SurfaceHit& h, const Vec3& wo,
                       const Vec3& wi) const {
        if (light.env) return light.env->pdf(wi);
        const Vec3 ng = faceforward(h.ng, wo), ns = faceforward(h.ns, wo);
        if (ns.x == ng.x && ns.y == ng.y && ns.z == ng.z)
            return std::max(0.0f, dot(wi, ng)) * kInvPi;
        return mixture_pdf(ng, ns, uniform_share(ng, ns), wi);
    }
    float area_pdf(const Light& light, const Vec3& p, const Vec3& wi, const SurfaceHit& y) const {
        const Primitive& prim = *scene.primitives[static_cast<std::size_t>(light.prim)];
        if (const std::optional<float> cone = prim.cone_pdf(p)) return *cone;
        const Vec3 d = y.p - p;
        const float cos_l = std::abs(dot(y.ng, wi));
        return cos_l > 0 ? prim.area_pdf(y.p) * dot(d, d) / cos_l : 0.0f;
    }

    // One point: in the cone a round sphere subtends, else uniform by area with its density
    // converted to solid angle.
    std::optional<LightSample> sample_area(const Light& light, const SurfaceHit& h) {
        const Primitive& prim = *scene.primitives[static_cast<std::size_t>(light.prim)];
        float u1, u2;
        next2(u1, u2);
        const std::optional<SurfaceSample> cone = prim.sample_cone(h.p, u1, u2);
        const SurfaceSample s = cone ? *cone : prim.sample_area(u1, u2);
        if (!cone && s.pdf == 0) return std::nullopt;
        LightSample ls;
        Vec3 d = s.p - h.p;
        float d2 = dot(d, d);
        if (d2 == 0) return std::nullopt;
        ls.dist = std::sqrt(d2);
        ls.wi = d / ls.dist;
        float cos_l = dot(s.n, -ls.wi);
        if (cos_l == 0 || (!light.two_sided && cos_l < 0)) return std::nullopt;
        ls.pdf = cone ? s.pdf : s.pdf * d2 / std::abs(cos_l);
        ls.target = s.p;
        ls.li = light.intensity;
        return ls;
    }

    std::optional<LightSample> sample_light(const Light& light, const SurfaceHit& h,
                                            const Vec3& wo) {
        switch (light.type) {
            case Light::Type::Point:
            case Light::Type::Spot:
            case Light::Type::Goniometric:
            case Light::Type::Projection:
                return sample_positional(light, h);
            case Light::Type::Distant: {
                LightSample ls;
                ls.wi = light.direction;
                ls.li = light.intensity;
                return ls;
            }
            case Light::Type::Infinite:
                return sample_infinite(light, h, wo);
            case Light::Type::Area:
                return sample_area(light, h);
        }
        return std::nullopt;
    }

    // The shadow rays of the light samples at h that could add light (neither the light's
    // radiance nor the BSDF zero), appended to `out` light by light, sample by sample. A ray
    // towards a point on an area light stops short of the light's own surface by its ray
    // epsilon; a positional light's by a relative 1e-4. `o`: bsdf.outgoing(wo).
    void shadow_rays(const SurfaceHit& h, const Bsdf& bsdf, const Vec3& wo, const Bsdf::Outgoing& o,
                     std::vector<ShadowRay>& out) {
        for (std::size_t l = 0; l < scene.lights.size(); ++l) {
            const Light& light = scene.lights[l];
            // A light sample's shadow ray, unless the light's radiance or the BSDF is zero.
            // Path tracing weighs the samples of area and infinite lights against the BSDF's
            // (multiple importance sampling, direct_by_bsdf).
            const bool mis = scene.path_tracing && (light.type == Light::Type::Area ||
                                                    light.type == Light::Type::Infinite);
            auto add = [&](const LightSample& ls) {
                if (ls.li.is_black()) return;
                const Rgb fv = bsdf.f(o, ls.wi);
                if (fv.is_black()) return;
                if (counts) ++counts->shadow;
                ShadowRay& r = out.emplace_back();  // in place: no copy of a half-written ray
                r.light = static_cast<int>(l);
                r.contribution = fv * ls.li * (absdot(ls.wi, h.ns) / ls.pdf);
                if (mis)
                    r.contribution = r.contribution * power_heuristic(ls.pdf, bsdf.pdf(o, ls.wi));
                r.org = offset_origin(h, ls.wi);
                if (light.type == Light::Type::Area) {
                    const Vec3 d = ls.target - r.org;
                    const float len = length(d);
                    r.dir = d / len;
                    r.tmax = len - ray_epsilon(ls.target);
                    if (r.tmax <= 0) {  // the hit is on the light: nothing to trace
                        r.traced = false;
                        r.clear = true;
                    }
                } else {
                    r.dir = ls.wi;
                    r.tmax = std::isinf(ls.dist) ? std::numeric_limits<float>::infinity()
                                                 : ls.dist * (1 - 1e-4f);
                }
            };
            // Lights that are sampled (infinite, area) take light.samples shadow rays, averaged.
            if (light.type == Light::Type::Infinite && light.env && light.samples > 1) {
                // An environment map's samples (pbrt-v3's directlighting takes nsamples of them)
                // drawn in batches: their table reads in the map's distribution, mostly cache
                // misses on a large map, then overlap (EnvironmentMap::sample's batch). The
                // random numbers are drawn in sample_infinite's order, and each sample is the
                // one it gives.
                for (int k0 = 0; k0 < light.samples; k0 += kSampleBatch) {
                    const int m = std::min(kSampleBatch, light.samples - k0);
                    float u1[kSampleBatch], u2[kSampleBatch];
                    for (int i = 0; i < m; ++i) {
                        next2(u1[i], u2[i]);
                    }
                    EnvironmentMap::Sample es[kSampleBatch];
                    light.env->sample(u1, u2, m, es);
                    for (int i = 0; i < m; ++i)
                        if (const std::optional<LightSample> ls = from_map(light, es[i])) add(*ls);
                }
                continue;
            }
            for (int k = 0; k < light.samples; ++k)
                if (const std::optional<LightSample> ls = sample_light(light, h, wo)) add(*ls);
        }
    }

    // Direct lighting from one hit's shadow rays (shadow_rays' order, `clear` set): each light's
    // clear samples summed in order and averaged over its samples.
    Rgb direct_from(const ShadowRay* r, std::size_t n) const {
        Rgb L{};
        std::size_t i = 0;
        for (std::size_t l = 0; l < scene.lights.size(); ++l) {
            Rgb sum{};
            for (; i < n && r[i].light == static_cast<int>(l); ++i)
                if (r[i].clear) sum += r[i].contribution;
            const int samples = scene.lights[l].samples;
            L += samples == 1 ? sum : sum / float(samples);
        }
        return L;
    }

    // Direct lighting at h, its shadow rays traced one by one (in `shadow`, after what it holds).
    Rgb direct(const SurfaceHit& h, const Bsdf& bsdf, const Vec3& wo, const Bsdf::Outgoing& o) {
        const std::size_t first = shadow.size();
        shadow_rays(h, bsdf, wo, o, shadow);
        for (std::size_t i = first; i < shadow.size(); ++i) {
            ShadowRay& r = shadow[i];
            if (!scene.volumetric || !r.traced) {
                trace_shadow_ray(scene, r);
                continue;
            }
            // Through media: the light arrives attenuated (and only through surfaces of
            // material "none").
            const Rgb tr =
                transmittance(r.org, r.dir, shadow_tmax(r.light, r.tmax), medium_toward(h, r.dir));
            r.contribution = r.contribution * tr;
            r.clear = !tr.is_black();
        }
        Rgb L = direct_from(shadow.data() + first, shadow.size() - first);
        shadow.resize(first);
        if (scene.path_tracing) L += direct_by_bsdf(h, bsdf, wo, o);
        return L;
    }

    // pbrt-v3's power heuristic: the weight of a sample drawn with density pa against another
    // strategy's pb.
    static float power_heuristic(float pa, float pb) {
        const float a = pa * pa, b = pb * pb;
        return a + b > 0 && std::isfinite(a + b) ? a / (a + b) : 1.0f;
    }

    // The other half of path tracing's direct light, as pbrt-v3's EstimateDirect: for each area
    // and infinite light, a direction drawn from the BSDF, whose ray adds the light if it meets
    // that light first (an area light's surface, or for an infinite light nothing), weighted by
    // the power heuristic against the light's own sampling (algorithms.md §18).
    Rgb direct_by_bsdf(const SurfaceHit& h, const Bsdf& bsdf, const Vec3& wo,
                       const Bsdf::Outgoing& o) {
        Rgb L{};
        for (std::size_t l = 0; l < scene.lights.size(); ++l) {
            const Light& light = scene.lights[l];
            if (light.type != Light::Type::Area && light.type != Light::Type::Infinite) continue;
            const float u0 = next();
            float u1, u2;
            next2(u1, u2);
            const Bsdf::Sample s = bsdf.sample(o, u0, u1, u2);
            if (s.pdf == 0 || s.f.is_black() || !finite(s.wi)) continue;
            if (counts) ++counts->shadow;
            Rgb tr(1);
            const std::optional<SurfaceHit> y =
                scene.volumetric ? intersect_tr(offset_origin(h, s.wi), s.wi,
                                                std::numeric_limits<float>::infinity(),
                                                medium_toward(h, s.wi), tr)
                                 : scene.intersect(offset_origin(h, s.wi), s.wi, 0,
                                                   std::numeric_limits<float>::infinity(), false);
            if (tr.is_black()) continue;
            Rgb le;
            float p_light;
            if (light.type == Light::Type::Infinite) {
                if (y) continue;
                le = light.env ? light.intensity * light.env->radiance(s.wi) : light.intensity;
                p_light = infinite_pdf(light, h, wo, s.wi);
            } else {
                if (!y || y->prim->area_light != static_cast<int>(l)) continue;
                le = emitted(*y, -s.wi);
                p_light = area_pdf(light, h.p, s.wi, *y);
            }
            if (le.is_black()) continue;
            L += s.f * le * tr * (absdot(s.wi, h.ns) / s.pdf * power_heuristic(s.pdf, p_light));
        }
        return L;
    }

    // --- participating media (volpath; algorithms.md §19) ---

    // The medium of the ray being traced (li), -1 for vacuum; a child ray's is set around its li.
    int medium = -1;
    float uniform() { return rng.next_float(); }

    // How far a shadow ray towards light l goes through media: a distant or infinite light's
    // (infinitely long) 2 world_radius, to the point pbrt-v3 gives such a light's sample (within
    // the world's bounds nothing is further away; beyond them, in a medium, pbrt-v3 stops there).
    float shadow_tmax(int l, float tmax) const {
        const Light::Type type = scene.lights[static_cast<std::size_t>(l)].type;
        return type == Light::Type::Distant || type == Light::Type::Infinite
                   ? std::min(tmax, 2 * scene.world_radius)
                   : tmax;
    }

    // The medium a ray leaving h along w is in: the side of h's boundary it leaves by, or where
    // h is no boundary, the medium of the ray that found h (pbrt-v3).
    int medium_toward(const SurfaceHit& h, const Vec3& w) const {
        return h.prim ? h.prim->medium_after(medium, h.ng, w) : medium;
    }
    const Material& material_of(const Primitive& p) const {
        return p.material >= 0 ? scene.materials[static_cast<std::size_t>(p.material)]
                               : scene.default_material;
    }

    // The first surface along org + t dir, 0 < t < tmax, that is not of material "none",
    // starting in medium `med`, with the transmittance up to it (or to tmax) multiplied into tr:
    // the media's along the way, through the surfaces of material "none", which change the
    // medium where they bound one (pbrt-v3's Scene::IntersectTr).
    std::optional<SurfaceHit> intersect_tr(Vec3 org, const Vec3& dir, float tmax, int med,
                                           Rgb& tr) {
        for (int guard = 0; guard < 256; ++guard) {
            std::optional<SurfaceHit> y = scene.intersect(org, dir, 0, tmax, false);
            if (med >= 0)
                tr = tr * medium_transmittance(scene.media[static_cast<std::size_t>(med)], org, dir,
                                               y ? y->t : tmax, [this] { return uniform(); });
            if (!y || tr.is_black() || material_of(*y->prim).type != Material::Type::None) return y;
            med = y->prim->medium_after(med, y->ng, dir);
            const Vec3 next = offset_origin(*y, dir);
            tmax -= dot(next - org, dir);
            org = next;
            if (!(tmax > 0)) return std::nullopt;
        }
        tr = Rgb();
        return std::nullopt;
    }
    // The light a shadow ray passes over (0, tmax): 0 when a surface not of material "none" is in
    // the way (pbrt-v3's VisibilityTester::Tr).
    Rgb transmittance(const Vec3& org, const Vec3& dir, float tmax, int med) {
        Rgb tr(1);
        return intersect_tr(org, dir, tmax, med, tr) ? Rgb() : tr;
    }

    // A light sample at a point p in a medium (no surface, so an infinite light without a map
    // is sampled uniformly over the sphere).
    std::optional<LightSample> sample_light_in_medium(const Light& light, const Vec3& p) {
        if (light.type == Light::Type::Infinite && !light.env) {
            float u1, u2;
            next2(u1, u2);
            LightSample ls;
            ls.wi = sphere_direction(u1, u2);
            ls.pdf = 1 / (4 * kPi);
            ls.li = light.intensity;
            return ls;
        }
        SurfaceHit at;  // (the other lights read only the point)
        at.p = p;
        return sample_light(light, at, Vec3());
    }

    // Light scattered at a point p of medium m towards wo (pbrt-v3's EstimateDirect for a medium
    // interaction, over every light): each light's samples, attenuated on their way, and for
    // area and infinite lights a direction drawn from the phase function too, the two weighted
    // by the power heuristic.
    Rgb direct_in_medium(const Vec3& p, const Vec3& wo, const Medium& m) {
        Rgb L{};
        for (std::size_t l = 0; l < scene.lights.size(); ++l) {
            const Light& light = scene.lights[l];
            const bool mis = light.type == Light::Type::Area || light.type == Light::Type::Infinite;
            Rgb sum{};
            for (int k = 0; k < light.samples; ++k) {
                const std::optional<LightSample> ls = sample_light_in_medium(light, p);
                if (!ls || ls->li.is_black() || ls->pdf == 0) continue;
                const float f = hg_phase(dot(wo, ls->wi), m.g);
                if (f == 0) continue;
                if (counts) ++counts->shadow;
                float tmax = shadow_tmax(static_cast<int>(l), ls->dist * (1 - 1e-4f));
                Vec3 wi = ls->wi;
                if (light.type == Light::Type::Area) {
                    const Vec3 d = ls->target - p;
                    const float len = length(d);
                    wi = d / len;
                    tmax = len - ray_epsilon(ls->target);
                }
                if (!(tmax > 0)) continue;
                const Rgb tr = transmittance(p, wi, tmax, medium);
                if (tr.is_black()) continue;
                Rgb c = ls->li * tr * (f / ls->pdf);
                if (mis) c = c * power_heuristic(ls->pdf, f);
                sum += c;
            }
            L += light.samples == 1 ? sum : sum / float(light.samples);
            if (!mis) continue;
            // The phase function's sample (its value over its density is 1).
            float u1, u2;
            next2(u1, u2);
            Vec3 wi;
            const float pf = hg_sample(wo, m.g, u1, u2, wi);
            if (!(pf > 0) || !finite(wi)) continue;
            if (counts) ++counts->shadow;
            Rgb tr(1);
            const std::optional<SurfaceHit> y =
                intersect_tr(p, wi, std::numeric_limits<float>::infinity(), medium, tr);
            if (tr.is_black()) continue;
            Rgb le;
            float p_light;
            if (light.type == Light::Type::Infinite) {
                if (y) continue;
                le = light.env ? light.intensity * light.env->radiance(wi) : light.intensity;
                p_light = light.env ? light.env->pdf(wi) : 1 / (4 * kPi);
            } else {
                if (!y || y->prim->area_light != static_cast<int>(l)) continue;
                le = emitted(*y, -wi);
                p_light = area_pdf(light, p, wi, *y);
            }
            if (le.is_black()) continue;
            L += le * tr * power_heuristic(pf, p_light);
        }
        return L;
    }

    // A ray scattered at p in medium m (it came along -wo): the light there, and with depth to
    // spare one more ray drawn from the phase function, continued by Russian roulette as
    // bounce() continues a surface's. What it meets lights the path only through its own light
    // samples (after_diffuse).
    Rgb scatter(const Vec3& p, const Vec3& wo, const Medium& m, int depth) {
        Rgb L = direct_in_medium(p, wo, m);
        if (depth + 1 >= scene.max_depth) return L;
        float u1, u2;
        next2(u1, u2);
        Vec3 wi;
        if (!(hg_sample(wo, m.g, u1, u2, wi) > 0) || !finite(wi)) return L;
        Rgb weight(1);
        const float mx = std::max({beta.r, beta.g, beta.b});
        if (depth > 3 && mx < scene.rr_threshold) {
            const float q = std::max(0.05f, 1 - mx);
            if (next() < q) return L;
            weight = weight / (1 - q);
        }
        if (counts) ++counts->secondary;
        const Ray next_ray{p, wi, RayFootprint{}};
        CmamRowState* const caches = cmam;
        const Rgb saved = beta;
        const int saved_medium = medium;
        cmam = nullptr;
        beta = beta * weight;
        L += weight * li(next_ray, depth + 1, nullptr, -1, true);
        beta = saved;
        medium = saved_medium;
        cmam = caches;
        return L;
    }

    // A "mix" material is pbrt-v3's: amount x its first material's BSDF + (1 - amount) x its
    // second's, per channel, their lobes added into one BSDF (Bsdf::add: into the first's lobes
    // where they fit, else as a layer of the first). As in pbrt-v3 the sum is in the first
    // material's shading frame, down the tree (frame_material: its bump map is applied, the
    // others' are not). Where the two have specular lobes the integrator cannot follow as one
    // (a mirror's reflection and a glass's, two indices: Bsdf::takes), where either is material
    // "none", and in trees of more than kMaxMixMaterials materials, one of the two is picked per
    // shading point with probability p = the amount's mean for the first, and weighted by
    // amount / p or (1 - amount) / (1 - p): the blend in expectation, noise instead of bias
    // (docs/algorithms.md §18, "Mix").
    static constexpr int kMaxMixMaterials = 8;

    // A mix's material `i` (0: namedmaterial1).
    const Material& mix_child(const Material& m, int i) const {
        const int c = m.mix[i];
        return c >= 0 ? scene.materials[static_cast<std::size_t>(c)] : scene.default_material;
    }
    // The materials of m's tree, counted up to cap (more: cap + 1). A mix names materials made
    // before it, so a tree is no deeper than their number.
    int mix_materials(const Material& m, int cap, std::size_t depth) const {
        if (m.type != Material::Type::Mix || depth > scene.materials.size()) return 1;
        int n = 0;
        for (int i = 0; i < 2; ++i) {
            n += mix_materials(mix_child(m, i), cap, depth + 1);
            if (n > cap) return cap + 1;
        }
        return n;
    }
    // The material whose shading frame (and bump map) a mix keeps: its first's, down the tree.
    const Material& frame_material(const Material& m) const {
        const Material* cur = &m;
        for (std::size_t k = 0; k <= scene.materials.size() && cur->type == Material::Type::Mix;
             ++k)
            cur = &mix_child(*cur, 0);
        return *cur;
    }
    // The BSDF of m at h (none: pass through), mixes resolved as above, their layers kept in
    // `layers`.
    std::optional<Bsdf> material_bsdf(const Material& m, const SurfaceHit& h, const TexContext& ctx,
                                      std::forward_list<Bsdf>& layers, std::size_t depth = 0) {
        if (m.type != Material::Type::Mix || depth > scene.materials.size())
            return make_bsdf(scene, m, h, ctx);
        Rgb a = eval_texture(scene, m.amount, ctx);
        a = Rgb(std::clamp(a.r, 0.0f, 1.0f), std::clamp(a.g, 0.0f, 1.0f),
                std::clamp(a.b, 0.0f, 1.0f));
        const Rgb b = Rgb(1) - a;
        const float p = (a.r + a.g + a.b) / 3;
        const bool whole = mix_materials(m, kMaxMixMaterials, depth) <= kMaxMixMaterials;
        std::optional<Bsdf> first, second;
        if (whole) {
            first = material_bsdf(mix_child(m, 0), h, ctx, layers, depth + 1);
            second = material_bsdf(mix_child(m, 1), h, ctx, layers, depth + 1);
            if (first && second && first->takes(*second)) {
                first->scale(a);
                second->scale(b);
                first->add(*second, layers);
                return first;
            }
        }
        // One of the two; in a tree too large, only it is shaded (its textures read).
        const bool one = next() < p;
        std::optional<Bsdf> c =
            whole ? std::move(one ? first : second)
                  : material_bsdf(mix_child(m, one ? 0 : 1), h, ctx, layers, depth + 1);
        if (c) c->scale(one ? a / p : b / (1 - p));
        return c;
    }

    using Ray = TracedRay;

    // The texture context at hit h of `ray`: h's (u,v) (computed first) and the footprint
    // producers' footprints in it where `uv`, otherwise only what the ray's children need.
    TexContext context_at(const Ray& ray, SurfaceHit& h, bool uv) const {
        if (uv) h.ensure_uv();
        TexContext ctx{h.u,
                       h.v,
                       h.p,
                       {},
                       counts && counts->count_lookups ? &counts->lookups : nullptr,
                       h.object_id,
                       cmam,
                       nullptr,
                       h.prim->u_periodic,
                       h.prim->v_periodic};
        footprints.at_hit(ctx.footprints, ray.fp, ray.dir, h, uv);
        ctx.footprints.tag.patch = h.prim->uv_chart(h.triangle);  // the CMAM's (u,v) chart
        return ctx;
    }

    // pbrt-v3's bump map of m (a mix's: its first material's) on h's shading normal, its
    // derivatives over half the ray differentials' (u,v) extent.
    void bump(const Material& m, SurfaceHit& h, const TexContext& ctx) const {
        const Material& framed = frame_material(m);
        if (framed.bump.node < 0) return;
        const HitDifferential& hd = ctx.footprints.diff;
        h.ns =
            bump_normal(scene, framed.bump, h, ctx, 0.5f * (std::abs(hd.dudx) + std::abs(hd.dudy)),
                        0.5f * (std::abs(hd.dvdx) + std::abs(hd.dvdy)));
    }

    // Deferred hits (trace_packet): where they are kept, where a deferred hit's reflected and
    // transmitted rays are made and left untraced (two slots), and a count of those made.
    std::vector<DeferredHit>* deferred_hits = nullptr;
    Ray* made_rays = nullptr;
    int* made_count = nullptr;

    // The radiance along `ray`. `first`: the ray's nearest hit when it was found already (a
    // camera ray's, in a packet). `deferred` (an index in deferred_hits): the hit's shadow rays
    // are left in `shadow`, untraced, and its radiance kept in parts; its reflected and
    // transmitted rays are made and left in made_rays. Everything else is done in li's order:
    // the random numbers, texture lookups and CMAM cache entries are li's.
    //
    // `after_diffuse`: the ray left a non-specular bounce of a path (path tracing), so what it
    // meets lights the path only through the bounce's light samples: the lights it hits or
    // escapes to add nothing: the bounce's direct light estimate counted them (its BSDF sample
    // weighted against its light sample), as pbrt-v3's path integrator counts them.
    Rgb li(const Ray& camera_or_child, int depth, std::optional<SurfaceHit>* first = nullptr,
           int deferred = -1, bool after_diffuse = false) {
        // A ray that is not finite (a NaN or infinite index, texel or parameter upstream) has no
        // radiance: its sample is counted as non-finite and taken as black (FilmTracer).
        if (!finite(camera_or_child.org) || !finite(camera_or_child.dir))
            return Rgb(std::numeric_limits<float>::quiet_NaN());
        // The ray, or past surfaces of material "none" its continuation (not copied otherwise).
        const Ray* cur = &camera_or_child;
        std::unique_ptr<Ray> through;                // allocated only then: most rays need none
        Rgb through_media(1);                        // the media's weights on the way (volpath)
        for (int guard = 0; guard < 256; ++guard) {  // passes through material "none"
            const Ray& ray = *cur;
            // The hit found already, or traced (each initialised in place, not copied).
            std::optional<SurfaceHit> traced =
                first ? std::nullopt
                      : scene.intersect(ray.org, ray.dir, 0, std::numeric_limits<float>::infinity(),
                                        false);
            std::optional<SurfaceHit>& hit = first ? *first : traced;
            first = nullptr;
            if (scene.volumetric && medium >= 0) {
                // The ray's medium, up to the hit: it scatters there, or what lies beyond is
                // weighted by the medium's sample (its transmittance over the sample's density).
                const Medium& m = scene.media[static_cast<std::size_t>(medium)];
                const MediumSample ms = sample_medium(
                    m, ray.org, ray.dir, hit ? hit->t : std::numeric_limits<float>::infinity(),
                    [this] { return uniform(); });
                if (ms.weight.is_black() || !std::isfinite(ms.weight.r + ms.weight.g + ms.weight.b))
                    return {};
                through_media = through_media * ms.weight;
                beta = beta * ms.weight;
                if (ms.scattered)
                    return through_media * scatter(ray.org + ms.t * ray.dir, -ray.dir, m, depth);
            }
            if (!hit)
                return after_diffuse || scene.ambient_occlusion
                           ? Rgb()
                           : through_media * escaped_radiance(scene, ray.dir, ray.fp.diff);
            SurfaceHit& h = *hit;
            const Material& m = material_of(*h.prim);
            // A hit whose shading reads no texture needs no (u,v) (nor footprints in it below);
            // the footprint AOV records it wherever it is.
            TexContext ctx = context_at(ray, h, aov || m.reads_textures());
            const HitFootprint& at = ctx.footprints;
            if (counts && at.dropped) ++counts->dropped_differentials;
            // The footprint AOV of a CMAM texture, made only then (an empty std::optional of the
            // record, which GCC clears whole, cost every hit 232 bytes of stores).
            std::unique_ptr<CmamRecord> cmam_record;
            if (aov && !aov->recorded && aov->kind == AovKind::Footprint &&
                footprints.uses(FootprintMethod::Cmam)) {
                cmam_record = std::make_unique<CmamRecord>();
                ctx.cmam_record = record_cmam_of(m, cmam_record.get());
            }
            Vec3 wo = -ray.dir;
            bump(m, h, ctx);
            std::forward_list<Bsdf> layers;  // a mix's (material_bsdf), mostly none
            std::optional<Bsdf> made = material_bsdf(m, h, ctx, layers);
            if (!made) {
                // Continue through: the footprint state moves to the hit point.
                RayFootprint fp = footprints.passed_through(ray.fp, at, h);
                const Vec3 org = offset_origin(h, ray.dir), dir = ray.dir;
                medium = medium_toward(h, dir);
                if (!through) through = std::make_unique<Ray>();
                *through = Ray{org, dir, fp};
                cur = through.get();
                continue;
            }
            Bsdf& bsdf = *made;
            if (aov) record_aov(ctx, h, bsdf);
            if (scene.ambient_occlusion) return ambient_occlusion(h, ray.dir);
            Rgb L = after_diffuse ? Rgb() : emitted(h, wo);
            if (deferred >= 0) {
                // (Children add deferred hits: `d` is not kept across them.)
                DeferredHit& d = (*deferred_hits)[static_cast<std::size_t>(deferred)];
                d.pending = true;
                d.radiance = L;
                d.lit = bsdf.has_nonspecular();
                d.first = d.cursor = shadow.size();
                if (d.lit) shadow_rays(h, bsdf, wo, bsdf.outgoing(wo), shadow);
                d.count = shadow.size() - d.first;
                d.children = depth + 1 < scene.max_depth;
                if (d.children) {  // (a call each when a lobe is black cost 2% on matte scenes)
                    if (!bsdf.kr.is_black())
                        specular_reflect(ray, h, at, bsdf, wo, depth, deferred);
                    if (!bsdf.kt.is_black())
                        specular_transmit(ray, h, at, bsdf, wo, depth, deferred);
                }
                return {};
            }
            // (What the non-specular lobes compute of wo, once for the light and the bounce.)
            const Bsdf::Outgoing o = bsdf.has_nonspecular() ? bsdf.outgoing(wo) : Bsdf::Outgoing{};
            if (bsdf.has_nonspecular()) L += direct(h, bsdf, wo, o);
            if (!scene.path_tracing) {
                if (depth + 1 < scene.max_depth) {
                    L += specular_reflect(ray, h, at, bsdf, wo, depth);
                    L += specular_transmit(ray, h, at, bsdf, wo, depth);
                }
            } else if (depth + 1 < scene.max_depth || m.subsurface()) {
                // (A path entering a subsurface material takes its exit point's direct light at
                // this depth, as pbrt-v3's does: at the last depth too.)
                L += continue_path(ray, h, at, bsdf, wo, o, depth,
                                   m.subsurface() ? Subsurface{&m, &ctx} : Subsurface{});
            }
            return scene.volumetric ? through_media * L : L;
        }
        return {};
    }

    // Path tracing: the product of the weights from the camera to the ray being traced, which
    // Russian roulette reads (pbrt-v3's beta).
    Rgb beta{1, 1, 1};

    // The material a path leaves h of where it may scatter below the surface (pbrt-v3's
    // BSSRDF), and its texture context at h; none elsewhere.
    struct Subsurface {
        const Material* material = nullptr;
        const TexContext* ctx = nullptr;
    };

    // A path goes on from h by one ray (path tracing), as pbrt-v3's path integrator samples one
    // component of the BSDF: a specular lobe or a non-specular bounce, evenly when there are
    // both, and of the specular lobes the reflection with the probability of its Fresnel term
    // (pbrt-v3's FresnelSpecular), each weighted by the inverse of its probability. Every other
    // lobe's children would double the rays at each hit of a glass or a glossy mirror.
    //
    // At a subsurface material (`sss`) a path that enters the surface goes on from the BSSRDF's
    // exit point instead (subsurface); at the last depth only that is taken.
    Rgb continue_path(const Ray& ray, const SurfaceHit& h, const HitFootprint& at, const Bsdf& b,
                      const Vec3& wo, const Bsdf::Outgoing& o, int depth, const Subsurface& sss) {
        const bool reflect = !b.kr.is_black(), transmit = !b.kt.is_black();
        const bool specular = reflect || transmit, other = b.has_nonspecular();
        if (!specular && !other) return {};
        const float p_specular = specular && other ? 0.5f : specular ? 1.0f : 0.0f;
        if (!(next() < p_specular)) return bounce(h, b, o, depth, sss) / (1 - p_specular);
        float p_reflect = reflect ? 1.0f : 0.0f;
        if (reflect && transmit)
            p_reflect = b.fresnel_noop ? 0.5f : fresnel_dielectric(dot(wo, h.ns), 1.0f, b.eta);
        const bool deeper = depth + 1 < scene.max_depth;
        Rgb L;
        if (next() < p_reflect) {
            L = deeper ? specular_reflect(ray, h, at, b, wo, depth) / p_reflect : Rgb();
        } else if (sss.material) {  // into the material: its weight, then the BSSRDF's exit
            L = enter_subsurface(h, sss, b, wo, depth) / (1 - p_reflect);
        } else {
            L = deeper ? specular_transmit(ray, h, at, b, wo, depth) / (1 - p_reflect) : Rgb();
        }
        return L / p_specular;
    }

    // pbrt-v3's subsurface scattering from h, where a path with weight `weight` (its BSDF
    // sample's through the surface) enters a subsurface material (algorithms.md §26): an exit
    // point drawn by the BSSRDF's radial profile (a probe segment along one of h's shading axes,
    // at a radius drawn from one channel's profile, meeting the material's surfaces), weighted
    // by the profile over the density of drawing it; its direct light through the BSSRDF's exit
    // lobe (its Fresnel-weighted diffuse lobe); and one bounce drawn from that lobe.
    // (Out of line: it is rare, and its callers' inlining is kept for the common paths.)
    [[gnu::noinline]] Rgb subsurface(const SurfaceHit& h, const Subsurface& sss, const Rgb& weight,
                                     int depth) {
        const Material& m = *sss.material;
        Rgb sigma_a, sigma_s;
        if (m.type == Material::Type::Subsurface) {
            sigma_a = clamp0(eval_texture(scene, m.sss_sigma_a, *sss.ctx)) * m.sss_scale;
            sigma_s = clamp0(eval_texture(scene, m.sss_sigma_s, *sss.ctx)) * m.sss_scale;
        } else {
            subsurface_from_diffuse(*m.bssrdf, clamp0(eval_texture(scene, m.kd, *sss.ctx)),
                                    eval_texture(scene, m.mfp, *sss.ctx) * m.sss_scale, sigma_a,
                                    sigma_s);
        }
        const Bssrdf bssrdf(*m.bssrdf, sigma_a, sigma_s);
        // The probe's axis (h's normal with probability 1/2, each tangent 1/4) and channel.
        float u1 = next(), ur, uphi;
        next2(ur, uphi);
        const Frame f = Frame::from_z(h.ns);
        Vec3 vx = f.s, vy = f.t, vz = f.n;
        if (u1 < 0.5f) {
            u1 *= 2;
        } else if (u1 < 0.75f) {
            vx = f.t, vy = f.n, vz = f.s;
            u1 = (u1 - 0.5f) * 4;
        } else {
            vx = f.n, vy = f.s, vz = f.t;
            u1 = (u1 - 0.75f) * 4;
        }
        const int ch = std::min(static_cast<int>(u1 * 3), 2);
        u1 = std::min(u1 * 3 - float(ch), 0x1.fffffep-1f);
        const float r = bssrdf.sample_sr(ch, ur), r_max = bssrdf.sample_sr(ch, 0.999f);
        if (r < 0 || !(r < r_max)) return {};
        const float phi = 2 * kPi * uphi, l = 2 * std::sqrt(r_max * r_max - r * r);
        // The probe: the segment of length l through the point at (r, phi) about h, along vz;
        // every surface of the same material on it is a candidate exit point.
        Vec3 org = h.p + r * (std::cos(phi) * vx + std::sin(phi) * vy) - (0.5f * l) * vz;
        thread_local std::vector<SurfaceHit> found;
        found.clear();
        float left = l;
        for (int k = 0; k < kMaxProbeHits && left > 0; ++k) {
            if (counts) ++counts->secondary;
            const std::optional<SurfaceHit> y = scene.intersect(org, vz, 0, left, false);
            if (!y) break;
            if (y->prim->material == h.prim->material) found.push_back(*y);
            const Vec3 next_org = offset_origin(*y, vz);
            left -= dot(next_org - org, vz);
            org = next_org;
        }
        if (found.empty()) return {};
        const int n = static_cast<int>(found.size());
        const SurfaceHit& pi = found[static_cast<std::size_t>(std::min(int(u1 * float(n)), n - 1))];
        const float pdf = bssrdf.pdf_sp(f, h.p, pi.p, pi.ng) / float(n);
        const Rgb sp = bssrdf.sr(length(h.p - pi.p));
        if (!(pdf > 0) || sp.is_black()) return {};
        const Rgb w = weight * sp / pdf;
        // The exit lobe, facing along pi's shading normal.
        Bsdf exit;
        exit.frame = Frame::from_z(pi.ns);
        exit.ng = pi.ng;
        exit.sss_eta = m.eta.value.r;
        exit.kd = Rgb(exit.sss_eta * exit.sss_eta / m.bssrdf->exit_norm);
        const Vec3 wo_exit = pi.ns;
        const Bsdf::Outgoing o = exit.outgoing(wo_exit);
        Rgb L = w * direct(pi, exit, wo_exit, o);
        if (depth + 1 < scene.max_depth) {
            const Rgb saved = beta;
            beta = beta * w;
            L += w * bounce(pi, exit, o, depth, Subsurface{});
            beta = saved;
        }
        return L;
    }
    // subsurface() for a path entering by a smooth dielectric's refraction at h.
    [[gnu::noinline]] Rgb enter_subsurface(const SurfaceHit& h, const Subsurface& sss,
                                           const Bsdf& b, const Vec3& wo, int depth) {
        Vec3 wt;
        const float ft = transmittance_into(h, b, wo, wt);
        return ft > 0 ? subsurface(h, sss, b.kt * ft, depth) : Rgb();
    }
    // Surfaces a subsurface probe meets at most (a mesh folded on itself many times over).
    static constexpr int kMaxProbeHits = 64;

    // The weight of a smooth dielectric's refraction from h into the other side (1 - F times
    // (eta_i / eta_t)^2, radiance's), its direction in wt; 0 under total internal reflection.
    [[gnu::always_inline]] static float transmittance_into(const SurfaceHit& h, const Bsdf& b,
                                                           const Vec3& wo, Vec3& wt) {
        const Vec3& n = h.ns;
        const float cos_o = dot(wo, n);
        const bool entering = cos_o > 0;
        const float eta_i = entering ? 1.0f : b.eta, eta_t = entering ? b.eta : 1.0f;
        const std::optional<Vec3> refracted =
            render::refract(wo, faceforward(n, wo), eta_i / eta_t);
        if (!refracted) return 0;
        wt = *refracted;
        float ft = 1 - fresnel_dielectric(dot(wt, n), 1.0f, b.eta);
        ft *= (eta_i * eta_i) / (eta_t * eta_t);
        if (dot(wt, n) == 0) return 0;
        return ft;
    }

    // One non-specular bounce of a path from h (path tracing): a direction drawn from the BSDF,
    // weighted f |cos| / pdf, continued past three bounces by Russian roulette as pbrt-v3's path
    // integrator does (a path whose throughput's largest channel m is under rr_threshold goes
    // on with probability 1 - max(0.05, 1 - m), its weight divided by that). The ray carries no
    // footprint, as pbrt-v3's rays from such bounces carry no differentials: the textures it
    // meets are read at full resolution, and the CMAM's caches (whose paths are specular
    // chains) are not used below it.
    Rgb bounce(const SurfaceHit& h, const Bsdf& bsdf, const Bsdf::Outgoing& o, int depth,
               const Subsurface& sss) {
        const float u0 = next();
        float u1, u2;
        next2(u1, u2);
        const Bsdf::Sample s = bsdf.sample(o, u0, u1, u2);
        if (s.pdf == 0 || s.f.is_black()) return {};
        Rgb weight = s.f * (absdot(s.wi, h.ns) / s.pdf);
        const Rgb through = beta * weight;
        const float m = std::max({through.r, through.g, through.b});
        if (depth > 3 && m < scene.rr_threshold) {
            const float q = std::max(0.05f, 1 - m);
            if (next() < q) return {};
            weight = weight / (1 - q);
        }
        if (!finite(s.wi)) return {};
        if (sss.material && dot(s.wi, h.ng) * o.w_ng < 0) return subsurface(h, sss, weight, depth);
        if (depth + 1 >= scene.max_depth) return {};  // (only a subsurface exit at the last depth)
        if (counts) ++counts->secondary;
        const Ray next{offset_origin(h, s.wi), s.wi, RayFootprint{}};
        CmamRowState* const caches = cmam;
        const Rgb saved = beta;
        const int saved_medium = medium;
        cmam = nullptr;
        beta = beta * weight;
        medium = medium_toward(h, s.wi);
        const Rgb L = weight * li(next, depth + 1, nullptr, -1, true);
        beta = saved;
        medium = saved_medium;
        cmam = caches;
        return L;
    }

    // The radiance of a deferred hit once every shadow ray is traced: li's sum, in li's order.
    Rgb finish(int index) const {
        const DeferredHit& d = (*deferred_hits)[static_cast<std::size_t>(index)];
        if (!d.pending) return d.radiance;
        Rgb L = d.radiance;
        if (d.lit) L += direct_from(shadow.data() + d.first, d.count);
        if (d.children)
            for (const DeferredHit::Child& c : d.child)
                L += c.made ? c.weight * finish(c.hit) : Rgb();
        return L;
    }

    // The deferred hit of a ray traced from here on (li with `first` its hit, when found).
    void li_deferred(const Ray& ray, int depth, std::optional<SurfaceHit>* first, int index) {
        const Rgb L = li(ray, depth, first, index);
        DeferredHit& d = (*deferred_hits)[static_cast<std::size_t>(index)];
        if (!d.pending) d.radiance = L;
    }

    // The child ray `next` (its direction and footprint set) of a hit at `depth` leaves from h
    // with `weight`: its weighted radiance, or with a deferred parent (`parent` >= 0) nothing,
    // the child (in made_rays[lobe]) being kept as the parent's child `lobe` (0 reflected, 1
    // transmitted), to be traced by trace_packet.
    [[gnu::always_inline]] Rgb spawn(const SurfaceHit& h, Ray& next, int depth, const Rgb& weight,
                                     int parent, int lobe) {
        if (counts) ++counts->secondary;
        next.org = offset_origin(h, next.dir);
        if (parent < 0) {
            const Rgb saved = beta;
            const int saved_medium = medium;
            beta = beta * weight;
            medium = medium_toward(h, next.dir);
            const Rgb L = weight * li(next, depth + 1);
            beta = saved;
            medium = saved_medium;
            return L;
        }
        (*deferred_hits)[static_cast<std::size_t>(parent)].child[lobe] = {true, weight, -1};
        ++*made_count;
        return {};
    }

    // The specular children: their weighted radiance, or with a deferred parent nothing (spawn).
    [[gnu::always_inline]] Rgb specular_reflect(const Ray& ray, const SurfaceHit& h,
                                                const HitFootprint& at, const Bsdf& b,
                                                const Vec3& wo, int depth, int parent = -1) {
        if (b.kr.is_black()) return {};
        const Vec3& n = h.ns;
        float cos_o = dot(wo, n);
        Vec3 wi = -wo + 2 * cos_o * n;
        if (dot(wi, n) == 0) return {};
        float fr = b.fresnel_noop ? 1.0f : fresnel_dielectric(cos_o, 1.0f, b.eta);
        if (fr == 0) return {};
        Ray own;  // its footprint written in place (a returned one was copied twice)
        Ray& next = parent >= 0 ? *std::construct_at(made_rays) : own;
        next.dir = wi;
        footprints.reflected(next.fp, ray.fp, at, ray.dir, h);
        return spawn(h, next, depth, b.kr * fr, parent, 0);
    }

    [[gnu::always_inline]] Rgb specular_transmit(const Ray& ray, const SurfaceHit& h,
                                                 const HitFootprint& at, const Bsdf& b,
                                                 const Vec3& wo, int depth, int parent = -1) {
        if (b.kt.is_black()) return {};
        Vec3 wt;
        const float ft = transmittance_into(h, b, wo, wt);
        if (ft == 0) return {};
        const bool entering = dot(wo, h.ns) > 0;
        const float eta_i = entering ? 1.0f : b.eta, eta_t = entering ? b.eta : 1.0f;
        Ray own;
        Ray& next = parent >= 0 ? *std::construct_at(made_rays + 1) : own;
        next.dir = wt;
        footprints.refracted(next.fp, ray.fp, at, ray.dir, h, eta_i / eta_t);
        return spawn(h, next, depth, b.kt * ft, parent, 1);
    }

    // --- AOVs: the first non-specular hit along the specular chain ---
    Aov* aov = nullptr;
    void record_aov(const TexContext& ctx, const SurfaceHit& h, const Bsdf& bsdf);
    CmamRecord* record_cmam_of(const Material& m, CmamRecord* record) const;

    // --- stochastic progressive photon mapping's paths (sppm.cpp; algorithms.md §25) ---

    // The BSDF of h's material seen along `ray` (none: material "none"), textures filtered over
    // the ray's footprints (a photon's ray carries none), its layers in `layers`; `at` gets the
    // footprints at h.
    std::optional<Bsdf> shade(const Ray& ray, SurfaceHit& h, HitFootprint& at,
                              std::forward_list<Bsdf>& layers) {
        const Material& m = material_of(*h.prim);
        const TexContext ctx = context_at(ray, h, m.reads_textures());
        bump(m, h, ctx);
        at = ctx.footprints;
        return material_bsdf(m, h, ctx, layers);
    }

    // Whether b has a diffuse lobe (pbrt-v3's BSDF_DIFFUSE components: Lambert, Oren-Nayar,
    // diffuse transmission, the Disney BSDF's diffuse group and thin transmission), where a
    // camera path of SPPM stops at a visible point. FresnelBlend, microfacet, Fourier and hair
    // lobes are glossy.
    static bool has_diffuse_lobe(const Bsdf& b) {
        for (const Bsdf* l = &b; l; l = l->layer)
            if ((!l->fresnel_blend && !l->kd.is_black()) || l->has_diffuse_transmission() ||
                (l->disney && (l->disney->diffuse_components() > 0 || l->disney->thin)))
                return true;
        return false;
    }

    // One scattering of an SPPM path at h, chosen as continue_path chooses (a specular lobe or
    // the non-specular ones, evenly where there are both; reflection or transmission by the
    // Fresnel term): the next ray (with the footprints of a specular child when `footprinted`,
    // none otherwise), its weight f |cos| / pdf, and whether it was specular. A photon's weight
    // (`importance`) is pbrt-v3's for importance: refraction does not scale it by
    // (eta_i / eta_t)^2, and a rough dielectric's transmission is scaled by eta^2 where
    // radiance's is not (algorithms.md §25).
    bool scatter(const Ray& ray, const SurfaceHit& h, const HitFootprint& at, const Bsdf& b,
                 const Vec3& wo, const Bsdf::Outgoing& o, bool footprinted, bool importance,
                 Ray& next, Rgb& weight, bool& specular) {
        const bool reflect = !b.kr.is_black(), transmit = !b.kt.is_black();
        const bool any_specular = reflect || transmit, other = b.has_nonspecular();
        if (!any_specular && !other) return false;
        const float p_specular = any_specular && other ? 0.5f : any_specular ? 1.0f : 0.0f;
        specular = this->next() < p_specular;
        next.fp = RayFootprint{};
        if (!specular) {
            const float u0 = this->next();
            float u1, u2;
            next2(u1, u2);
            const Bsdf::Sample smp = b.sample(o, u0, u1, u2);
            if (smp.pdf == 0 || smp.f.is_black() || !finite(smp.wi)) return false;
            weight = smp.f * (absdot(smp.wi, h.ns) / (smp.pdf * (1 - p_specular)));
            const float side_o = dot(wo, b.frame.n), side_i = dot(smp.wi, b.frame.n);
            if (importance && b.has_transmission() && side_o * side_i < 0) {
                const float eta =
                    side_o > 0 ? b.lobe_eta_t / b.lobe_eta_i : b.lobe_eta_i / b.lobe_eta_t;
                weight = weight * (eta * eta);
            }
            next.dir = smp.wi;
            next.org = offset_origin(h, smp.wi);
            return true;
        }
        const Vec3& n = h.ns;
        const float cos_o = dot(wo, n);
        float p_reflect = reflect ? 1.0f : 0.0f;
        if (reflect && transmit)
            p_reflect = b.fresnel_noop ? 0.5f : fresnel_dielectric(cos_o, 1.0f, b.eta);
        if (this->next() < p_reflect) {
            next.dir = -wo + 2 * cos_o * n;
            if (dot(next.dir, n) == 0) return false;
            const float fr = b.fresnel_noop ? 1.0f : fresnel_dielectric(cos_o, 1.0f, b.eta);
            weight = b.kr * (fr / (p_reflect * p_specular));
            if (footprinted) footprints.reflected(next.fp, ray.fp, at, ray.dir, h);
        } else {
            const bool entering = cos_o > 0;
            const float eta_i = entering ? 1.0f : b.eta, eta_t = entering ? b.eta : 1.0f;
            const std::optional<Vec3> wt = render::refract(wo, faceforward(n, wo), eta_i / eta_t);
            if (!wt || dot(*wt, n) == 0) return false;
            float ft = 1 - fresnel_dielectric(dot(*wt, n), 1.0f, b.eta);
            if (!importance) ft *= (eta_i * eta_i) / (eta_t * eta_t);
            next.dir = *wt;
            weight = b.kt * (ft / ((1 - p_reflect) * p_specular));
            if (footprinted) footprints.refracted(next.fp, ray.fp, at, ray.dir, h, eta_i / eta_t);
        }
        if (weight.is_black()) return false;
        next.org = offset_origin(h, next.dir);
        return true;
    }

    // SPPM's camera path (pbrt-v3's, algorithms.md §25): from the camera through specular (and,
    // before the last depth, glossy) bounces, adding at each hit what it emits (first hits and
    // after specular bounces) and its direct light, up to the first hit with a diffuse lobe (or a
    // glossy one at the last depth): the visible point, which keeps its BSDF. The path goes on
    // past a throughput of luminance 1/4 by Russian roulette.
    void visible_point(Ray ray, SppmVisiblePoint& vp) {
        Rgb beta(1);
        bool specular = false;
        int passes = 0;
        for (int depth = 0; depth < scene.max_depth;) {
            std::optional<SurfaceHit> hit =
                scene.intersect(ray.org, ray.dir, 0, std::numeric_limits<float>::infinity(), false);
            if (!hit) {
                if (depth == 0 || specular)
                    vp.ld += beta * escaped_radiance(scene, ray.dir, ray.fp.diff);
                break;
            }
            SurfaceHit& h = *hit;
            HitFootprint at;
            vp.layers.clear();
            vp.bsdf = shade(ray, h, at, vp.layers);
            if (!vp.bsdf) {  // material "none": on through it, at the same depth
                if (++passes > 256) break;
                ray.fp = footprints.passed_through(ray.fp, at, h);
                ray.org = offset_origin(h, ray.dir);
                continue;
            }
            const Bsdf& bsdf = *vp.bsdf;
            const Vec3 wo = -ray.dir;
            if (depth == 0 || specular) vp.ld += beta * emitted(h, wo);
            const bool other = bsdf.has_nonspecular();
            const Bsdf::Outgoing o = other ? bsdf.outgoing(wo) : Bsdf::Outgoing{};
            if (other) vp.ld += beta * direct(h, bsdf, wo, o);
            if (has_diffuse_lobe(bsdf) || (other && depth == scene.max_depth - 1)) {
                vp.found = true;
                vp.p = h.p;
                vp.wo = o;
                vp.beta = beta;
                return;
            }
            if (depth == scene.max_depth - 1) break;
            Ray next_ray;
            Rgb weight;
            if (!scatter(ray, h, at, bsdf, wo, o, true, false, next_ray, weight, specular)) break;
            if (!specular) cmam = nullptr;  // (the CMAM's caches hold specular chains only)
            if (counts) ++counts->secondary;
            beta = beta * weight;
            const float y = beta.luminance();
            if (y < 0.25f) {
                const float p = std::min(1.0f, y);
                if (this->next() > p) break;
                beta = beta / p;
            }
            ray = next_ray;
            ++depth;
        }
        vp.bsdf.reset();
        vp.layers.clear();
    }

    // What a path from a light does at its hits: SPPM's photon deposits (`deposit`), or bdpt's
    // joins to the camera (`join`, their splats to `splat`).
    struct LightHits {
        const PhotonDeposit* deposit = nullptr;
        const CameraJoinFn* join = nullptr;
        const LightSplatFn* splat = nullptr;
    };

    // A path from a light, SPPM's photon (pbrt-v3's, algorithms.md §25) or bdpt's light path
    // (tracer.h's light_path, algorithms.md §27). A photon's hits after the first (the direct
    // light is the camera paths') get its deposit: the hit point, the direction it came from and
    // its weight. A light path's hits with non-specular lobes after the first are joined to the
    // camera, and the path ends at a first bounce that is not specular. Then the path scatters
    // (`scatter`'s choice, importance's weights; a light path's times the shading normals'
    // correction, as pbrt-v3's bdpt weighs them, not its photons) and goes on with the
    // probability that keeps its weight's luminance.
    void light_walk(Ray ray, Rgb beta, const LightHits& at_hits) {
        const bool bdpt = at_hits.join != nullptr;
        int passes = 0;
        for (int depth = 0; depth < scene.max_depth;) {
            if (counts) ++counts->secondary;
            std::optional<SurfaceHit> hit =
                scene.intersect(ray.org, ray.dir, 0, std::numeric_limits<float>::infinity(), false);
            if (!hit) return;
            SurfaceHit& h = *hit;
            const Vec3 wo = -ray.dir;
            if (at_hits.deposit && depth > 0) (*at_hits.deposit)(h.p, wo, beta);
            HitFootprint at;
            std::forward_list<Bsdf> layers;
            const std::optional<Bsdf> bsdf = shade(ray, h, at, layers);
            if (!bsdf) {
                if (++passes > 256) return;
                ray.org = offset_origin(h, ray.dir);
                continue;
            }
            const bool other = bsdf->has_nonspecular();
            const Bsdf::Outgoing o = other ? bsdf->outgoing(wo) : Bsdf::Outgoing{};
            if (bdpt && depth > 0 && other)
                to_camera(h, *bsdf, o, wo, beta, *at_hits.join, *at_hits.splat);
            Ray next_ray;
            Rgb weight;
            bool specular;
            if (!scatter(ray, h, at, *bsdf, wo, o, false, true, next_ray, weight, specular)) return;
            if (bdpt && depth == 0 && !specular) return;
            if (bdpt) weight = weight * shading_correction(h, wo, next_ray.dir);
            const Rgb after = beta * weight;
            const float y = beta.luminance();
            if (!(y > 0)) return;
            const float q = std::max(0.0f, 1 - after.luminance() / y);
            if (this->next() < q) return;
            beta = after / (1 - q);
            ray = next_ray;
            ++depth;
        }
    }

    // --- the light paths of pbrt-v3's bdpt (lighttrace.cpp; algorithms.md §27) ---

    // pbrt-v3's correction for shading normals on a path carrying importance: the adjoint BSDF
    // with shading normals is f(wi, wo) |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|) (Veach 1997, §5.3).
    // wo points to where the path came from, wi to where it goes.
    static float shading_correction(const SurfaceHit& h, const Vec3& wo, const Vec3& wi) {
        const float den = std::abs(dot(wo, h.ng)) * std::abs(dot(wi, h.ns));
        return den > 0 ? std::abs(dot(wo, h.ns)) * std::abs(dot(wi, h.ng)) / den : 0.0f;
    }

    // pbrt-v3's bdpt strategy t = 1 at a light path's vertex h (with non-specular lobes): the
    // vertex joined to a point of the camera's lens, its BSDF for importance (a rough
    // dielectric's transmission times eta^2, as scatter weighs it) with the shading normals'
    // correction, times the camera's importance, when nothing lies between.
    void to_camera(const SurfaceHit& h, const Bsdf& b, const Bsdf::Outgoing& o, const Vec3& wo,
                   const Rgb& beta, const CameraJoinFn& join, const LightSplatFn& splat) {
        float u1, u2;
        next2(u1, u2);
        CameraJoin j;
        if (!join(h.p, u1, u2, j)) return;
        Rgb f = b.f(o, j.wi);
        if (f.is_black()) return;
        const float side_o = dot(wo, b.frame.n), side_i = dot(j.wi, b.frame.n);
        if (b.has_transmission() && side_o * side_i < 0) {
            const float eta =
                side_o > 0 ? b.lobe_eta_t / b.lobe_eta_i : b.lobe_eta_i / b.lobe_eta_t;
            f = f * (eta * eta);
        }
        const float den = std::abs(dot(wo, h.ng));
        if (!(den > 0)) return;
        const Rgb L =
            beta * f * (std::abs(dot(wo, h.ns)) * std::abs(dot(j.wi, h.ng)) / den * j.importance);
        if (L.is_black() || !finite(L)) return;
        const Vec3 org = offset_origin(h, j.wi), to = j.lens - org;
        const float dist = length(to);
        if (!(dist > 0)) return;
        if (counts) ++counts->shadow;
        if (scene.occluded(org, to / dist, 0, dist * (1 - 1e-4f))) return;
        splat(j.pixel, L);
    }
};

// The first image texture feeding a material's diffuse (or reflective) input.
const TextureNode* first_image(const Scene& scene, const TexInput& in, int budget = 8) {
    if (in.node < 0 || budget == 0) return nullptr;
    const TextureNode& n = scene.textures[static_cast<std::size_t>(in.node)];
    if (n.kind == TextureNode::Kind::Image) return &n;
    for (const TexInput* c : {&n.tex1, &n.tex2})
        if (const TextureNode* f = first_image(scene, *c, budget - 1)) return f;
    return nullptr;
}

void Tracer::record_aov(const TexContext& ctx, const SurfaceHit& h, const Bsdf& bsdf) {
    if (aov->recorded) return;
    const Material& m = material_of(*h.prim);
    // (Glass with a roughness has no specular chain: its own hit is the first non-specular one.)
    const bool specular = (m.type == Material::Type::Mirror || m.type == Material::Type::Glass) &&
                          !bsdf.has_nonspecular();
    if (specular) return;  // follow the specular chain
    aov->recorded = true;
    if (aov->kind == AovKind::Texture) {
        // The Kd the BSDF was built with: the same lookup (a second one would disturb the
        // CMAM's cache); a mix's, its layers' too.
        // (A Disney BSDF's: its base colour.)
        auto kd_of = [](const Bsdf& b) { return b.disney ? b.disney->base : b.kd; };
        // (A kdsubsurface's Kd is its BSSRDF's, not its BSDF's, which is a glass's.)
        Rgb k = m.type == Material::Type::KdSubsurface ? clamp0(eval_texture(scene, m.kd, ctx))
                                                       : kd_of(bsdf);
        for (const Bsdf* l = bsdf.layer; l; l = l->layer) k += kd_of(*l);
        aov->v[0] = k.r;
        aov->v[1] = k.g;
        aov->v[2] = k.b;
        return;
    }
    // Footprint: semi-axis lengths in level-0 texels of the first image texture, and its level.
    const TextureNode* n = first_image(scene, m.kd);
    if (!n) return;
    if (n->lod == FootprintMethod::Cmam) {
        // The region the CMAM built from its matching samples (level-0 texels; none on a
        // miss) and the MIP level its filter read.
        const CmamRecord* r = ctx.cmam_record;
        if (!r || !r->filled) return;
        const double la = std::hypot(r->region.a.u, r->region.a.v),
                     lb = std::hypot(r->region.b.u, r->region.b.v);
        aov->v[0] = float(std::max(la, lb));
        aov->v[1] = float(std::min(la, lb));
        aov->v[2] = float(std::max(0.0, r->info.lambda));
        return;
    }
    const texture::Footprint fp = lookup_footprint(*n, ctx);  // in the node's (s,t) units
    if (fp.kind != texture::Footprint::Kind::Axes) return;
    const double W = n->image->image().width(), H = n->image->image().height();
    double la = std::hypot(fp.axis_a.u * W, fp.axis_a.v * H),
           lb = std::hypot(fp.axis_b.u * W, fp.axis_b.v * H);
    double major = std::max(la, lb), minor = std::min(la, lb);
    double lambda = n->filter.kind == texture::FilterKind::Ewa
                        ? std::log2(std::max({minor, major / n->filter.max_aniso, 1e-8}))
                        : std::log2(std::max(major, 1e-8));
    aov->v[0] = float(major);
    aov->v[1] = float(minor);
    aov->v[2] = float(std::max(0.0, lambda));
}

// The footprint AOV of a material whose first image texture is filtered by the CMAM: where its
// lookup records what it filtered (null for other materials).
CmamRecord* Tracer::record_cmam_of(const Material& m, CmamRecord* record) const {
    const TextureNode* n = first_image(scene, m.kd);
    if (!n || n->lod != FootprintMethod::Cmam) return nullptr;
    record->node = static_cast<int>(n - scene.textures.data());
    return record;
}

}  // namespace

void sppm_visible_point(const Scene& scene, const FootprintProducers& footprints,
                        const TracedRay& ray, uint64_t seed, RayCounts* counts, CmamRowState* cmam,
                        SppmVisiblePoint& vp) {
    Rng rng(seed);
    thread_local std::vector<ShadowRay> shadow;
    Tracer t{scene, footprints, counts, rng, cmam, shadow};
    vp.found = false;
    vp.ld = Rgb();
    if (counts) ++counts->camera;
    if (finite(ray.org) && finite(ray.dir)) t.visible_point(ray, vp);
}

void sppm_photon(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
                 const Vec3& dir, const Rgb& beta, uint64_t seed, RayCounts* counts,
                 const PhotonDeposit& deposit) {
    Rng rng(seed);
    thread_local std::vector<ShadowRay> shadow;
    Tracer t{scene, footprints, counts, rng, nullptr, shadow};
    if (finite(org) && finite(dir)) t.light_walk({org, dir, RayFootprint{}}, beta, {&deposit});
}

void light_path(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
                const Vec3& dir, const Rgb& beta, uint64_t seed, RayCounts* counts,
                const CameraJoinFn& join, const LightSplatFn& splat) {
    Rng rng(seed);
    thread_local std::vector<ShadowRay> shadow;
    Tracer t{scene, footprints, counts, rng, nullptr, shadow};
    if (finite(org) && finite(dir))
        t.light_walk({org, dir, RayFootprint{}}, beta, {nullptr, &join, &splat});
}

Rgb trace_one(const Scene& scene, const FootprintProducers& footprints, const Vec3& org,
              const Vec3& dir, const RayFootprint& fp, uint64_t seed, RayCounts* counts,
              CmamRowState* cmam, Aov* aov) {
    Rng rng(seed);
    std::vector<ShadowRay> shadow;
    Tracer t{scene, footprints, counts, rng, cmam, shadow};
    t.aov = aov;
    t.medium = scene.volumetric ? scene.camera_medium : -1;
    if (counts) ++counts->camera;
    return t.li({org, dir, fp}, 0);
}

namespace {
// How many hits and shadow rays a packet keeps deferred at most (about 1 MB), beyond which the
// rays it takes are traced to the end at once.
constexpr std::size_t kMaxDeferredHits = 4096, kMaxDeferredShadowRays = 16384;

// Whether path a comes before path b in a depth-first walk of the bounces, the reflected child
// first (paths as RayFootprint::path: 1, then 2p for the reflected and 2p + 1 for the
// transmitted child of p): a path before its extensions, else by the first bounce that differs.
bool walked_before(uint64_t a, uint64_t b) {
    const int la = std::bit_width(a), lb = std::bit_width(b);
    if (la < lb) return a <= b >> (lb - la);
    if (la > lb) return a >> (la - lb) < b;
    return a < b;
}
}  // namespace

void trace_packet(const Scene& scene, const FootprintProducers& footprints, const CameraPath* paths,
                  int n, CmamRowState* cmam, PacketScratch& scratch, Rgb* radiance) {
    constexpr int N = Scene::kPacketSize;
    n = std::clamp(n, 0, N);
    Vec3 org[N], dir[N];
    for (int k = 0; k < n; ++k) {
        org[k] = paths[k].ray.org;
        dir[k] = paths[k].ray.dir;
    }
    // (The slots below are the scratch's, made once: an array of 16 empty optionals on the
    // stack was cleared whole, 4 KB per packet.)
    static_assert(PacketScratch::kSamples == N);
    std::optional<SurfaceHit>* hits = scratch.camera_hits.data();
    scene.intersect_packet(org, dir, n, hits, false);  // (u,v) as li needs them

    // Each sample's first hit shaded in order, as trace_one would, but with its shadow rays left
    // for the packets below and its reflected and transmitted rays made but not traced. Sample
    // k's first hit is deferred hit k; each sample's random numbers go on in its children.
    std::vector<ShadowRay>& shadow = scratch.shadow;
    std::vector<DeferredHit>& deferred = scratch.hits;
    shadow.clear();
    deferred.clear();
    deferred.resize(static_cast<std::size_t>(n));  // in place (a copied one waits on its stores)
    Tracer::Ray* made = scratch.made.data();       // sample k's children: made[2 k], made[2 k + 1]
    int children = 0;                              // made so far
    std::optional<Rng> rng[N];
    // Sample k's tracer: its random numbers, its AOV, its children made in made[2 k ...].
    auto tracer = [&](int k) {
        const CameraPath& p = paths[k];
        Tracer t{scene, footprints, p.counts, *rng[k], cmam, shadow};
        if (scene.path_tracing) {
            t.strata_key = mix_seed(p.pixel_seed, 0x5472617461ull);
            t.stratum = p.sample;
            t.strata = p.samples;
            t.strata_x = std::max(1u, p.samples_x);
        }
        t.aov = p.aov;
        t.medium = scene.volumetric ? scene.camera_medium : -1;
        t.deferred_hits = &deferred;
        t.made_rays = made + 2 * k;
        t.made_count = &children;
        return t;
    };
    // Each sample's path traced to its end, one ray at a time (ambient occlusion: its first hit,
    // whose rays go in packets of their own).
    if (scene.path_tracing || scene.ambient_occlusion) {
        for (int k = 0; k < n; ++k) {
            rng[k].emplace(paths[k].seed);
            if (paths[k].counts) ++paths[k].counts->camera;
            radiance[k] = tracer(k).li(paths[k].ray, 0, &hits[k]);
        }
        return;
    }
    // A camera ray that leaves the scene sees what escapes it, as li would find without a
    // medium to cross (nor random numbers, shadow rays or children): its radiance set here,
    // without a tracer and li's set-up for it (paper scene 1's sky, half the image).
    const bool plain_misses = !scene.volumetric;
    const bool sky = std::any_of(scene.lights.begin(), scene.lights.end(),
                                 [](const Light& l) { return l.type == Light::Type::Infinite; });
    for (int k = 0; k < n; ++k) {
        rng[k].emplace(paths[k].seed);
        if (paths[k].counts) ++paths[k].counts->camera;
        const TracedRay& ray = paths[k].ray;
        if (plain_misses && !hits[k] && finite(ray.org) && finite(ray.dir)) {
            deferred[static_cast<std::size_t>(k)].radiance =
                sky ? escaped_radiance(scene, ray.dir, ray.fp.diff) : Rgb{};
            continue;
        }
        tracer(k).li_deferred(ray, 0, &hits[k], k);
    }

    // Then the samples' paths in lock step, each depth first as li traces it: each sample's
    // rays wait on its own stack (a hit's transmitted ray below its reflected one, so the
    // reflected ray's whole subtree comes first), and each step takes the top rays of the
    // stacks, intersects them as one packet, then shades their hits in sample order, whose
    // children go on the stacks. Every sample's hits are shaded in li's order, so its random
    // numbers are a single ray's. With a CMAM texture a step takes only the rays of one path
    // (RayFootprint::path: the bounces that led there), the first such path in a depth-first
    // walk, so that each path's hits are shaded in sample order and each CMAM cache (a path's)
    // sees its samples in order; without, every top ray (fuller packets: 2% less time).
    const bool by_path = footprints.uses(FootprintMethod::Cmam);
    std::vector<PendingRay>* stack = scratch.pending;
    // Sample k's children made at deferred hit `hit`, at `depth`, onto its stack.
    auto push_children = [&](int k, int hit, int depth) {
        for (int lobe = 1; lobe >= 0; --lobe) {
            if (!deferred[static_cast<std::size_t>(hit)].children ||
                !deferred[static_cast<std::size_t>(hit)].child[lobe].made)
                continue;
            const int index = static_cast<int>(deferred.size());  // the child's deferred hit
            deferred.emplace_back();
            deferred[static_cast<std::size_t>(hit)].child[lobe].hit = index;
            stack[k].push_back({made[2 * k + lobe], depth + 1, index});
        }
    };
    if (children > 0)  // (else a packet of matte surfaces or misses: nothing more to trace)
        for (int k = 0; k < n; ++k) push_children(k, k, 0);  // (each stack ends empty)
    PendingRay* step = scratch.step.data();
    std::optional<SurfaceHit>* step_hits = scratch.step_hits.data();
    for (;;) {
        bool any = false;
        uint64_t path = 0;  // with the CMAM, the step's
        for (int k = 0; k < n; ++k)
            if (!stack[k].empty()) {
                const uint64_t p = stack[k].back().ray.fp.path;
                if (by_path && (!any || walked_before(p, path))) path = p;
                any = true;
            }
        if (!any) break;
        int m = 0, who[N];
        for (int k = 0; k < n; ++k)
            if (!stack[k].empty() && (!by_path || stack[k].back().ray.fp.path == path)) {
                step[m] = stack[k].back();
                stack[k].pop_back();
                org[m] = step[m].ray.org;
                dir[m] = step[m].ray.dir;
                who[m++] = k;
            }
        scene.intersect_packet(org, dir, m, step_hits, false);
        // Deep trees (glass in glass under a high depth limit doubles a sample's rays at every
        // level) would keep every hit and shadow ray of the packet until its end: past a bound,
        // each ray taken is traced to the end of its subtree at once, as li does (its shadow
        // rays one by one). The order stays li's for each sample, and each path's hits are all
        // in this step's subtrees, taken in sample order, so the CMAM's caches keep theirs.
        const bool deep =
            deferred.size() > kMaxDeferredHits || shadow.size() > kMaxDeferredShadowRays;
        for (int i = 0; i < m; ++i) {
            if (deep) {
                deferred[static_cast<std::size_t>(step[i].hit)].radiance =
                    tracer(who[i]).li(step[i].ray, step[i].depth, &step_hits[i]);
                continue;
            }
            tracer(who[i]).li_deferred(step[i].ray, step[i].depth, &step_hits[i], step[i].hit);
            push_children(who[i], step[i].hit, step[i].depth);
        }
    }

    // The shadow rays towards each delta light in packets (from neighbouring points to one
    // point or along one direction), light by light, hit by hit: each hit's rays are in light
    // order already, so a cursor per hit walks them (one pass, however many lights). Those of
    // sampled lights (area, infinite), which scatter, one by one.
    for (std::size_t l = 0; l < scene.lights.size(); ++l) {
        const Light::Type type = scene.lights[l].type;
        const bool packets = type != Light::Type::Area && type != Light::Type::Infinite;
        std::size_t idx[N];
        int m = 0;
        auto flush = [&] {
            Vec3 o[N], d[N];
            float tmax[N];
            bool occluded[N];
            for (int i = 0; i < m; ++i) {
                o[i] = shadow[idx[i]].org;
                d[i] = shadow[idx[i]].dir;
                tmax[i] = shadow[idx[i]].tmax;
            }
            scene.occluded_packet(o, d, tmax, m, occluded);
            for (int i = 0; i < m; ++i) shadow[idx[i]].clear = !occluded[i];
            m = 0;
        };
        for (DeferredHit& h : deferred)
            for (const std::size_t end = h.first + h.count;
                 h.cursor < end && shadow[h.cursor].light == static_cast<int>(l); ++h.cursor) {
                ShadowRay& r = shadow[h.cursor];
                if (!r.traced) continue;
                if (!packets) {
                    trace_shadow_ray(scene, r);
                    continue;
                }
                idx[m++] = h.cursor;
                if (m == N) flush();
            }
        if (m > 0) flush();
    }

    // Then each sample's sum.
    Rng unused(0);
    Tracer sum{scene, footprints, nullptr, unused, cmam, shadow};
    sum.deferred_hits = &deferred;
    for (int k = 0; k < n; ++k) radiance[k] = sum.finish(k);
}

Rgb trace_radiance(const Scene& scene, const Vec3& org, const Vec3& dir, uint64_t seed,
                   RenderStats* stats) {
    RayCounts c;
    const FootprintProducers footprints(scene.footprint_methods, scene.camera, 1);
    Rgb L = trace_one(scene, footprints, org, dir, {}, seed, &c, nullptr, nullptr);
    c.add_to(stats);
    return L;
}

}  // namespace cmam::render
