#include "render/integrator.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <memory>

#include "render/shading.h"

namespace cmam::render {

namespace {

/// Small counter-based generator (SplitMix64): reproducible streams per pixel sample.
class Rng {
  public:
    explicit Rng(uint64_t seed) : m_state(seed) {}
    uint64_t next_u64() {
        uint64_t z = (m_state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    float next_float() { return std::min(float(next_u64() >> 40) * 0x1.0p-24f, 0x1.fffffep-1f); }

  private:
    uint64_t m_state;
};

float ray_epsilon(const Vec3& p) {
    return 1e-4f * (1 + max_abs(p));
}

Vec3 offset_origin(const SurfaceHit& h, const Vec3& w) {
    return h.p + faceforward(h.ng, w) * ray_epsilon(h.p);
}

/// Ray counts of one row, added to the shared totals once per row (no per-ray atomics).
struct RayCounts {
    uint64_t camera = 0, secondary = 0, shadow = 0;
    LookupCounts lookups;

    void add_to(RenderStats* stats) const {
        if (!stats) return;
        stats->camera_rays += camera;
        stats->secondary_rays += secondary;
        stats->shadow_rays += shadow;
        for (int k = 0; k < texture::kFilterKinds; ++k)
            stats->lookups_by_filter[k] += lookups.by_filter[k];
        stats->lookups_point_sampled += lookups.point_sampled;
    }
};

struct Tracer {
    const Scene& scene;
    RayCounts* counts;
    Rng& rng;
    texture::RayTag tag{};         // the camera ray's tag; the level follows the depth
    CmamRowState* cmam = nullptr;  // the row's CMAM caches

    Rgb escaped() const {
        Rgb l{};
        for (const Light& light : scene.lights)
            if (light.type == Light::Type::Infinite) l += light.intensity;
        return l;
    }

    bool visible(const SurfaceHit& h, const Vec3& wi, float dist) {
        if (counts) ++counts->shadow;
        Vec3 o = offset_origin(h, wi);
        float tmax = std::isinf(dist) ? std::numeric_limits<float>::infinity() : dist * (1 - 1e-4f);
        return !scene.occluded(o, wi, 0, tmax);
    }

    Rgb direct(const SurfaceHit& h, const Bsdf& bsdf, const Vec3& wo) {
        Rgb L{};
        for (const Light& light : scene.lights) {
            Vec3 wi;
            Rgb li;
            float dist = std::numeric_limits<float>::infinity();
            float pdf = 1;
            switch (light.type) {
                case Light::Type::Point:
                case Light::Type::Spot: {
                    Vec3 d = light.position - h.p;
                    float d2 = dot(d, d);
                    dist = std::sqrt(d2);
                    wi = d / dist;
                    li = light.intensity / d2;
                    if (light.type == Light::Type::Spot) {
                        float c = dot(-wi, light.direction);
                        if (c < light.cos_total) continue;
                        if (c < light.cos_falloff_start) {
                            float delta =
                                (c - light.cos_total) / (light.cos_falloff_start - light.cos_total);
                            li = li * ((delta * delta) * (delta * delta));
                        }
                    }
                    break;
                }
                case Light::Type::Distant:
                    wi = light.direction;
                    li = light.intensity;
                    break;
                case Light::Type::Infinite: {
                    // Cosine-weighted about the geometric normal on wo's side: the same expected
                    // value as pbrt-v3's sphere sampling for reflection-only BSDFs, lower variance.
                    float u1 = rng.next_float(), u2 = rng.next_float();
                    float r = std::sqrt(u1), phi = 2 * kPi * u2;
                    Vec3 local(r * std::cos(phi), r * std::sin(phi),
                               std::sqrt(std::max(0.0f, 1 - u1)));
                    Frame f = Frame::from_z(faceforward(h.ng, wo));
                    wi = f.to_world(local);
                    pdf = local.z * kInvPi;
                    if (pdf == 0) continue;
                    li = light.intensity;
                    break;
                }
            }
            if (li.is_black()) continue;
            Rgb fv = bsdf.f(wo, wi);
            if (fv.is_black()) continue;
            if (!visible(h, wi, dist)) continue;
            L += fv * li * (absdot(wi, h.ns) / pdf);
        }
        return L;
    }

    Rgb li(Vec3 org, Vec3 dir, int depth) {
        for (int guard = 0; guard < 256; ++guard) {  // passes through material "none"
            SurfaceHit h;
            if (!scene.intersect(org, dir, 0, std::numeric_limits<float>::infinity(), &h))
                return escaped();
            const Material& m =
                h.prim->material >= 0 ? scene.materials[h.prim->material] : scene.default_material;
            texture::RayTag t = tag;
            t.level = static_cast<uint32_t>(depth);
            TexContext ctx{h.u, h.v, {}, t, counts ? &counts->lookups : nullptr, h.prim->id, cmam};
            Bsdf bsdf;
            Vec3 wo = -dir;
            if (!make_bsdf(scene, m, h, ctx, &bsdf)) {
                org = offset_origin(h, dir);
                continue;
            }
            Rgb L{};
            if (bsdf.has_nonspecular()) L += direct(h, bsdf, wo);
            if (depth + 1 < scene.max_depth) {
                L += specular_reflect(h, bsdf, wo, depth);
                L += specular_transmit(h, bsdf, wo, depth);
            }
            return L;
        }
        return {};
    }

    Rgb spawn(const SurfaceHit& h, const Vec3& wi, int depth) {
        if (counts) ++counts->secondary;
        return li(offset_origin(h, wi), wi, depth + 1);
    }

    Rgb specular_reflect(const SurfaceHit& h, const Bsdf& b, const Vec3& wo, int depth) {
        if (b.kr.is_black()) return {};
        const Vec3& n = h.ns;
        float cos_o = dot(wo, n);
        Vec3 wi = -wo + 2 * cos_o * n;
        if (dot(wi, n) == 0) return {};
        float fr = b.fresnel_noop ? 1.0f : fresnel_dielectric(cos_o, 1.0f, b.eta);
        if (fr == 0) return {};
        return b.kr * fr * spawn(h, wi, depth);
    }

    Rgb specular_transmit(const SurfaceHit& h, const Bsdf& b, const Vec3& wo, int depth) {
        if (b.kt.is_black()) return {};
        const Vec3& n = h.ns;
        float cos_o = dot(wo, n);
        bool entering = cos_o > 0;
        float eta_i = entering ? 1.0f : b.eta, eta_t = entering ? b.eta : 1.0f;
        Vec3 wt;
        if (!refract(wo, faceforward(n, wo), eta_i / eta_t, &wt)) return {};
        float ft = 1 - fresnel_dielectric(dot(wt, n), 1.0f, b.eta);
        ft *= (eta_i * eta_i) / (eta_t * eta_t);
        if (ft == 0 || dot(wt, n) == 0) return {};
        return b.kt * ft * spawn(h, wt, depth);
    }
};

uint64_t mix_seed(uint64_t a, uint64_t b) {
    uint64_t z = a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull;
    z = (z ^ (z >> 33)) * 0xff51afd7ed558ccdull;
    z = (z ^ (z >> 33)) * 0xc4ceb9fe1a85ec53ull;
    return z ^ (z >> 33);
}

Rgb trace_one(const Scene& scene, const Vec3& org, const Vec3& dir, uint64_t seed,
              RayCounts* counts, texture::RayTag tag = {}, CmamRowState* cmam = nullptr) {
    Rng rng(seed);
    Tracer t{scene, counts, rng, tag, cmam};
    if (counts) ++counts->camera;
    return t.li(org, dir, 0);
}

}  // namespace

Rgb trace_radiance(const Scene& scene, const Vec3& org, const Vec3& dir, uint64_t seed,
                   RenderStats* stats) {
    RayCounts c;
    Rgb L = trace_one(scene, org, dir, seed, &c);
    c.add_to(stats);
    return L;
}

Framebuffer render(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
    const FilmSettings& film = scene.film;
    Framebuffer fb;
    fb.width = film.width();
    fb.height = film.height();
    fb.rgb.assign(static_cast<std::size_t>(fb.width) * fb.height * 3, 0.0f);
    const SamplerSettings& smp = scene.sampler;
    const int nx = smp.xsamples, ny = smp.ysamples, spp = nx * ny;

    std::unique_ptr<tbb::global_control> limit;
    if (options.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      options.threads);
    std::atomic<int> rows_done{0};

    auto render_row = [&](int row) {
        int py = film.y0 + row;
        float* out = &fb.rgb[static_cast<std::size_t>(row) * fb.width * 3];
        RayCounts counts;
        CmamRowState cmam;  // caches live for one row: identical images for any thread count
        for (int col = 0; col < fb.width; ++col) {
            int px = film.x0 + col;
            uint64_t pixel_seed =
                mix_seed(uint64_t(py) * uint64_t(film.xres) + uint64_t(px), 0x5eed);
            Rng jitter(pixel_seed);
            double sum[3] = {0, 0, 0};
            for (int sy = 0; sy < ny; ++sy)
                for (int sx = 0; sx < nx; ++sx) {
                    float jx = smp.jitter ? jitter.next_float() : 0.5f;
                    float jy = smp.jitter ? jitter.next_float() : 0.5f;
                    float fx = px + (sx + jx) / nx, fy = py + (sy + jy) / ny;
                    Vec3 org, dir;
                    scene.camera.generate_ray(fx, fy, &org, &dir);
                    const int sample = sy * nx + sx;
                    texture::RayTag tag;
                    if (scene.tags == TagPolicy::Scanline) {
                        tag.id = static_cast<uint32_t>(py);
                        tag.seq = static_cast<uint32_t>(col * spp + sample);
                    } else {
                        tag.id = static_cast<uint32_t>(py * film.xres + px);
                        tag.seq = static_cast<uint32_t>(sample);
                    }
                    Rgb L = trace_one(scene, org, dir, mix_seed(pixel_seed, uint64_t(sample) + 1),
                                      &counts, tag, &cmam);
                    if (!std::isfinite(L.r) || !std::isfinite(L.g) || !std::isfinite(L.b))
                        L = Rgb();
                    sum[0] += L.r;
                    sum[1] += L.g;
                    sum[2] += L.b;
                }
            for (int c = 0; c < 3; ++c) out[3 * col + c] = static_cast<float>(sum[c] / spp);
        }
        counts.add_to(stats);
        int done = ++rows_done;
        if (options.progress) options.progress(done, fb.height);
    };

    tbb::parallel_for(tbb::blocked_range<int>(0, fb.height, 1),
                      [&](const tbb::blocked_range<int>& r) {
                          for (int row = r.begin(); row < r.end(); ++row) render_row(row);
                      });
    return fb;
}

}  // namespace cmam::render
