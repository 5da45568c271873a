#include "render/sppm.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>

#include "render/envmap.h"
#include "render/parallel.h"
#include "render/tracer.h"

namespace cmam::render {

namespace {

// Photons are traced in tasks of kPhotonChunk; the deposits of kWaveChunks tasks are kept and
// then added to the pixels in the tasks' order, so that the sums are the same for any thread count.
constexpr int kPhotonChunk = 4096;
constexpr int kWaveChunks = 64;

Vec3 min(const Vec3& a, const Vec3& b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
Vec3 max(const Vec3& a, const Vec3& b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

// The luminance of an image's mean texel (a one-channel image's value).
float mean_luminance(const texture::Image& image) {
    const texture::Texel& m = image.mean();
    return image.channels() == 1 ? m[0] : Rgb(m[0], m[1], m[2]).luminance();
}

// The cosine of the half-angle of the cone that holds a projection light's screen.
float projection_cos_total(const LightImage& image) {
    const float x = std::max(std::abs(image.screen[0]), std::abs(image.screen[1]));
    const float y = std::max(std::abs(image.screen[2]), std::abs(image.screen[3]));
    const float tan_diagonal = image.tan_half_fov * std::sqrt(x * x + y * y);
    return 1 / std::sqrt(1 + tan_diagonal * tan_diagonal);
}

// The radical inverse of `a` in base B (digits reversed behind the point): the Halton
// sequence's coordinate of base B. The base is a constant, so the divisions are products.
template <uint64_t B>
float radical_inverse(uint64_t a) {
    uint64_t reversed = 0;
    double scale = 1;
    while (a != 0) {
        const uint64_t next = a / B;
        reversed = reversed * B + (a - next * B);
        scale /= double(B);
        a = next;
    }
    return std::min(float(double(reversed) * scale), 0x1.fffffep-1f);
}

// A photon of `light` from four uniform numbers (its weight before the light's choice); false
// when there is none (a zero density or weight, or a light at infinity around an empty scene).
bool emit(const Scene& scene, const Light& light, const float (&u)[4], Emission& e) {
    const float radius = scene.world_radius;
    // A ray into the scene's bounding sphere along d, from a point uniform on the disc of its
    // radius facing d (distant and infinite lights): density 1 / (pi r^2) by area.
    auto from_disc = [&](const Vec3& d) {
        const Frame f = Frame::from_z(d);
        float x, y;
        concentric_disc(u[2], u[3], x, y);
        e.org = scene.world_center - radius * d + radius * (x * f.s + y * f.t);
        e.dir = d;
    };
    switch (light.type) {
        case Light::Type::Point:
        case Light::Type::Goniometric:
        case Light::Type::Projection:
            // The whole sphere, uniform (a projection's image is black outside its screen).
            e.org = light.position;
            e.dir = sphere_direction(u[0], u[1]);
            e.beta = positional_intensity(light, e.dir, light.intensity) * (4 * kPi);
            break;
        case Light::Type::Spot: {
            // The cone, uniform by solid angle: density 1 / (2 pi (1 - cos_total)).
            const float c = 1 - u[0] * (1 - light.cos_total);
            const float s = std::sqrt(std::max(0.0f, 1 - c * c)), phi = 2 * kPi * u[1];
            const Frame f = Frame::from_z(light.direction);
            e.org = light.position;
            e.dir = f.to_world(Vec3(s * std::cos(phi), s * std::sin(phi), c));
            e.beta = positional_intensity(light, e.dir, light.intensity) *
                     (2 * kPi * (1 - light.cos_total));
            break;
        }
        case Light::Type::Distant:
            if (!(radius > 0)) return false;
            from_disc(-light.direction);
            e.beta = light.intensity * (kPi * radius * radius);
            break;
        case Light::Type::Infinite: {
            if (!(radius > 0)) return false;
            if (light.env) {  // by the map's luminance
                const EnvironmentMap::Sample s = light.env->sample(u[0], u[1]);
                if (s.pdf == 0) return false;
                from_disc(-s.wi);
                e.beta = light.intensity * s.radiance * (kPi * radius * radius / s.pdf);
            } else {
                from_disc(-sphere_direction(u[0], u[1]));
                e.beta = light.intensity * (4 * kPi * kPi * radius * radius);
            }
            break;
        }
        case Light::Type::Area: {
            // A point by area, then a cosine-weighted direction on the side it emits to (either,
            // evenly, when two-sided): |cos| / (pdf_area cos / pi) = pi / pdf_area.
            const Primitive& prim = *scene.primitives[static_cast<std::size_t>(light.prim)];
            const SurfaceSample s = prim.sample_area(u[0], u[1]);
            if (!(s.pdf > 0)) return false;
            float v = u[2];
            Vec3 n = s.n;
            float sides = 1;
            if (light.two_sided) {
                sides = 2;
                if (v < 0.5f) {
                    v *= 2;
                } else {
                    v = std::min(2 * v - 1, 0x1.fffffep-1f);
                    n = -n;
                }
            }
            e.dir = Frame::from_z(n).to_world(hemisphere_direction(v, u[3]));
            e.org = s.p + n * (1e-4f * (1 + max_abs(s.p)));
            e.beta = light.intensity * (sides * kPi / s.pdf);
            break;
        }
    }
    return !e.beta.is_black() && finite(e.dir);
}

// A light's power as pbrt-v3 gives it (the luminance of its Power()); a projection light's cone
// is the one that holds its screen.
float light_power(const Scene& scene, const Light& light) {
    const float r2 = scene.world_radius * scene.world_radius;
    const float mean = light.image ? mean_luminance(light.image->image->image())
                       : light.env ? mean_luminance(light.env->image().image())
                                   : 1.0f;
    const float y = light.intensity.luminance();
    switch (light.type) {
        case Light::Type::Point:
            return 4 * kPi * y;
        case Light::Type::Goniometric:
            return 4 * kPi * y * mean;
        case Light::Type::Projection:
            return 2 * kPi * y * mean * (1 - projection_cos_total(*light.image));
        case Light::Type::Spot:
            return 2 * kPi * y * (1 - 0.5f * (light.cos_falloff_start + light.cos_total));
        case Light::Type::Distant:
            return kPi * r2 * y;
        case Light::Type::Infinite:
            return kPi * r2 * y * mean;
        case Light::Type::Area: {
            const Primitive& prim = *scene.primitives[static_cast<std::size_t>(light.prim)];
            const SurfaceSample s = prim.sample_area(0.5f, 0.5f);
            return s.pdf > 0 ? (light.two_sided ? 2 : 1) * kPi * y / s.pdf : 0.0f;
        }
    }
    return 0;
}

bool is_delta(Light::Type t) {
    return t == Light::Type::Point || t == Light::Type::Spot || t == Light::Type::Goniometric ||
           t == Light::Type::Projection || t == Light::Type::Distant;
}

}  // namespace

LightEmitter::LightEmitter(const Scene& scene, bool delta_only) : m_scene(scene), m_cdf{0.0} {
    for (std::size_t l = 0; l < scene.lights.size(); ++l)
        if (!delta_only || is_delta(scene.lights[l].type)) {
            m_lights.push_back(l);
            m_cdf.push_back(m_cdf.back() + std::max(0.0f, light_power(scene, scene.lights[l])));
        }
    if (!(m_cdf.back() > 0))
        for (std::size_t k = 0; k < m_lights.size(); ++k) m_cdf[k + 1] = double(k + 1);
}

bool LightEmitter::emit(uint64_t index, Emission& e) const {
    if (m_lights.empty()) return false;
    const double pick = double(radical_inverse<2>(index)) * m_cdf.back();
    const std::size_t i = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(m_cdf.begin(), m_cdf.end(), pick) -
                                 m_cdf.begin()) -
            1,
        m_lights.size() - 1);
    const double chance = (m_cdf[i + 1] - m_cdf[i]) / m_cdf.back();
    if (!(chance > 0)) return false;
    const float u[4] = {radical_inverse<3>(index), radical_inverse<5>(index),
                        radical_inverse<7>(index), radical_inverse<11>(index)};
    if (!render::emit(m_scene, m_scene.lights[m_lights[i]], u, e)) return false;
    e.beta = e.beta / static_cast<float>(chance);
    return true;
}

namespace {

// One pixel's state across the iterations (pbrt-v3's SPPMPixel).
struct Pixel {
    SppmVisiblePoint vp;  // this iteration's
    double ld[3] = {0, 0, 0};
    double tau[3] = {0, 0, 0};
    double phi[3] = {0, 0, 0};  // this iteration's photons, times the visible point's BSDF
    uint64_t m = 0;             // how many
    double n = 0;               // photons kept so far (N)
    float radius = 0;
};

// The visible points in a uniform grid over their bounds, cells of about the largest radius,
// hashed into a power of two of buckets at least the pixels' count; each point is in the buckets of
// every cell its disc of radius overlaps.
class VisibleGrid {
  public:
    /// Built on `threads` workers (0: all cores). The order of a bucket's entries depends on
    /// them, no sum does: a photon adds to each pixel once, and each pixel's deposits are added in
    /// the photons' order.
    VisibleGrid(const std::vector<Pixel>& pixels, int threads) {
        float max_radius = 0;
        for (std::size_t i = 0; i < pixels.size(); ++i) {
            const Pixel& px = pixels[i];
            if (!px.vp.found || px.vp.beta.is_black()) continue;
            const Vec3 r(px.radius, px.radius, px.radius);
            m_lo = min(m_lo, px.vp.p - r);
            m_hi = max(m_hi, px.vp.p + r);
            max_radius = std::max(max_radius, px.radius);
            m_points.push_back(static_cast<uint32_t>(i));
        }
        if (m_points.empty()) return;
        const Vec3 diag = m_hi - m_lo;
        const float largest = std::max({diag.x, diag.y, diag.z});
        const float base = std::min(largest / max_radius, float(1 << 20));
        for (int a = 0; a < 3; ++a)
            m_res[a] = std::max(1, static_cast<int>(base * diag[a] / largest));
        // A power of two at least the pixels' count, indexed by the hash's top bits.
        while ((std::size_t(1) << m_bucket_bits) < pixels.size()) ++m_bucket_bits;
        m_buckets = std::size_t(1) << m_bucket_bits;
        // The buckets of the cells point i's ball overlaps, each once: two of its cells may hash
        // to one bucket, where the point entered twice would take a photon there twice. (Cells
        // are at least the largest radius wide: a ball meets at most 3 x 3 x 3 of them.)
        auto each_cell = [&](uint32_t i, auto&& f) {
            const Pixel& px = pixels[i];
            const Vec3 r(px.radius, px.radius, px.radius);
            int lo[3], hi[3];
            cell(px.vp.p - r, lo);
            cell(px.vp.p + r, hi);
            std::size_t seen[27];
            int n = 0;
            for (int z = lo[2]; z <= hi[2]; ++z)
                for (int y = lo[1]; y <= hi[1]; ++y)
                    for (int x = lo[0]; x <= hi[0]; ++x) {
                        const std::size_t b = bucket(x, y, z);
                        if (std::find(seen, seen + n, b) != seen + n) continue;
                        if (n < 27) seen[n++] = b;
                        f(b);
                    }
        };
        const int points = static_cast<int>(m_points.size());
        constexpr int kChunk = 4096;
        const int chunks = (points + kChunk - 1) / kChunk;
        std::vector<std::atomic<uint32_t>> count(m_buckets + 1);
        parallel_range(chunks, threads, [&](int begin, int end) {
            for (int k = begin * kChunk; k < std::min(points, end * kChunk); ++k)
                each_cell(m_points[std::size_t(k)], [&](std::size_t b) {
                    count[b + 1].fetch_add(1, std::memory_order_relaxed);
                });
        });
        m_start.resize(m_buckets + 1);
        uint32_t sum = 0;
        for (std::size_t b = 0; b <= m_buckets; ++b) {
            sum += count[b].load(std::memory_order_relaxed);
            m_start[b] = sum;
            count[b].store(sum, std::memory_order_relaxed);  // each bucket's next free entry
        }
        m_entries.resize(sum);
        parallel_range(chunks, threads, [&](int begin, int end) {
            for (int k = begin * kChunk; k < std::min(points, end * kChunk); ++k) {
                const uint32_t i = m_points[std::size_t(k)];
                each_cell(i, [&](std::size_t b) {
                    m_entries[count[b].fetch_add(1, std::memory_order_relaxed)] = i;
                });
            }
        });
    }

    /// The pixels whose visible points may lie within their radius of p (none outside the
    /// bounds), as [begin, end).
    std::pair<const uint32_t*, const uint32_t*> near(const Vec3& p) const {
        if (m_entries.empty() || !(p.x >= m_lo.x && p.y >= m_lo.y && p.z >= m_lo.z &&
                                   p.x <= m_hi.x && p.y <= m_hi.y && p.z <= m_hi.z))
            return {nullptr, nullptr};
        int c[3];
        cell(p, c);
        const std::size_t b = bucket(c[0], c[1], c[2]);
        return {m_entries.data() + m_start[b], m_entries.data() + m_start[b + 1]};
    }

  private:
    void cell(const Vec3& p, int (&c)[3]) const {
        for (int a = 0; a < 3; ++a) {
            const float extent = m_hi[a] - m_lo[a];
            const float t = extent > 0 ? (p[a] - m_lo[a]) / extent : 0.0f;
            c[a] = std::clamp(static_cast<int>(t * float(m_res[a])), 0, m_res[a] - 1);
        }
    }
    // The cell's bucket: its coordinates mixed by large primes, then Fibonacci hashing (the top
    // bits of the product with 2^64 / golden ratio), without a division.
    std::size_t bucket(int x, int y, int z) const {
        const uint64_t h = (uint64_t(uint32_t(x)) * 73856093u) ^
                           (uint64_t(uint32_t(y)) * 19349663u) ^
                           (uint64_t(uint32_t(z)) * 83492791u);
        return m_bucket_bits == 0
                   ? 0
                   : static_cast<std::size_t>((h * 0x9E3779B97F4A7C15ull) >> (64 - m_bucket_bits));
    }

    Vec3 m_lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
              std::numeric_limits<float>::infinity()};
    Vec3 m_hi = -m_lo;
    int m_res[3] = {1, 1, 1};
    std::size_t m_buckets = 0;
    int m_bucket_bits = 0;
    std::vector<uint32_t> m_points, m_start, m_entries;
};

// A photon's contribution to one pixel.
struct Deposit {
    uint32_t pixel;
    Rgb phi;
};

}  // namespace

std::size_t sppm_pixel_bytes() {
    // The pixel, a bucket of the grid and about four cells' entries per visible point.
    return sizeof(Pixel) + 5 * sizeof(uint32_t);
}

Framebuffer render_sppm(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
    const FilmSettings& film = scene.film;
    const int width = film.width(), height = film.height();
    const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    const int iterations = scene.sppm.iterations;
    const uint64_t photons =
        scene.sppm.photons > 0 ? static_cast<uint64_t>(scene.sppm.photons) : uint64_t(count);
    // A camera sample's footprint is the pixel's over sqrt(iterations), as pbrt-v3 scales it.
    const FootprintProducers footprints = film_footprints(scene, iterations);
    // The camera samples of a pixel over the iterations in strata of nx x ny >= iterations.
    const int nx = std::max(1, static_cast<int>(std::sqrt(double(iterations))));
    const int ny = (iterations + nx - 1) / nx;

    constexpr int kBlockRows = 8;
    const int blocks = (height + kBlockRows - 1) / kBlockRows;
    const bool cmam_used = scene.footprint_methods.has(FootprintMethod::Cmam);
    const bool cmam_2d = cmam_used && scene.cmam.two_d;

    std::vector<Pixel> pixels(count);
    for (Pixel& p : pixels) p.radius = scene.sppm.radius;

    const LightEmitter lights(scene, false);

    const uint64_t chunks = (photons + kPhotonChunk - 1) / kPhotonChunk;
    std::vector<std::vector<Deposit>> deposits(kWaveChunks);
    for (int iter = 0; iter < iterations; ++iter) {
        // Visible points, row by row, in blocks of kBlockRows whose rows share the CMAM's
        // caches (each row a scanline, as at one sample per pixel). With the 2-D CMAM a block
        // first traces the row above it into its caches only (its visible points dropped), so
        // that every row but the image's first has its row above, as in the film's strips.
        parallel_range(blocks, options.threads, [&](int begin, int end) {
            RayCounts counts;
            counts.count_lookups = options.count_lookups;
            CmamRowState cmam;
            SppmVisiblePoint primed;
            // Pixel (x, y)'s camera path into vp: its weight (0: blocked by the lens, no path).
            auto trace = [&](int x, int y, SppmVisiblePoint& vp, RayCounts* c) {
                const int px = film.x0 + x, py = film.y0 + y;
                const uint64_t pixel_seed =
                    mix_seed(uint64_t(py) * uint64_t(film.xres) + uint64_t(px), 0x5eed);
                const uint64_t seed = mix_seed(pixel_seed, uint64_t(iter) + 1);
                const float ju = Rng::float_at(seed, 0), jv = Rng::float_at(seed, 1);
                float su, sv;
                stratified2(mix_seed(pixel_seed, 0x73707031ull), uint32_t(iter), uint32_t(nx),
                            uint32_t(ny), ju, jv, su, sv);
                TracedRay ray;
                const float weight =
                    camera_ray(scene, footprints, float(px) + su, float(py) + sv, pixel_seed, iter,
                               nx, ny, 0.5f - ju, 0.5f - jv, ray);
                ray.fp.tag = {};
                ray.fp.tag.id = static_cast<uint32_t>(y);
                ray.fp.tag.seq = static_cast<uint32_t>(x);
                ray.fp.tag.positioned = true;
                ray.fp.tag.x = double(x) + su;
                ray.fp.tag.y = double(y) + sv;
                vp.found = false;
                if (weight != 0)
                    sppm_visible_point(scene, footprints, ray, mix_seed(seed, 0x7670ull), c,
                                       cmam_used ? &cmam : nullptr, vp);
                return weight;
            };
            for (int y = begin * kBlockRows; y < std::min(height, end * kBlockRows); ++y) {
                if (y % kBlockRows == 0) {
                    cmam.clear();
                    if (cmam_2d && y > 0)
                        for (int x = 0; x < width; ++x) trace(x, y - 1, primed, nullptr);
                }
                for (int x = 0; x < width; ++x) {
                    Pixel& p = pixels[static_cast<std::size_t>(y) * width + x];
                    const float weight = trace(x, y, p.vp, &counts);
                    if (weight == 0) continue;
                    Rgb ld = p.vp.ld * weight;
                    if (!finite(ld)) {
                        ++counts.non_finite_samples;
                        ld = Rgb();
                    }
                    p.ld[0] += ld.r;
                    p.ld[1] += ld.g;
                    p.ld[2] += ld.b;
                    p.vp.beta = p.vp.beta * weight;
                    if (!finite(p.vp.beta)) p.vp.found = false;
                }
            }
            counts.add_to(stats);
        });

        // Photons, in waves of tasks; each wave's deposits added in the tasks' order.
        const VisibleGrid grid(pixels, options.threads);
        in_waves(
            lights.empty() ? 0 : chunks, kWaveChunks, options.threads,
            [&](uint64_t first, int begin, int end) {
                RayCounts counts;
                counts.count_lookups = options.count_lookups;
                for (int c = begin; c < end; ++c) {
                    std::vector<Deposit>& out = deposits[static_cast<std::size_t>(c)];
                    out.clear();
                    const PhotonDeposit deposit = [&](const Vec3& p, const Vec3& wi,
                                                      const Rgb& beta) {
                        const auto [b, e] = grid.near(p);
                        for (const uint32_t* i = b; i != e; ++i) {
                            const Pixel& px = pixels[*i];
                            const Vec3 d = px.vp.p - p;
                            if (dot(d, d) > px.radius * px.radius) continue;
                            const Rgb phi = beta * px.vp.bsdf->f(px.vp.wo, wi);
                            if (finite(phi)) out.push_back({*i, phi});
                        }
                    };
                    const uint64_t p0 = (first + uint64_t(c)) * kPhotonChunk,
                                   p1 = std::min(photons, p0 + kPhotonChunk);
                    for (uint64_t k = p0; k < p1; ++k) {
                        // The photon's light, position and direction from the Halton sequence
                        // (its index counts on across the iterations), its bounces from a
                        // generator of its own.
                        Emission e;
                        if (!lights.emit(uint64_t(iter) * photons + k, e)) continue;
                        sppm_photon(scene, footprints, e.org, e.dir, e.beta,
                                    mix_seed(0x70686f74ull + uint64_t(iter), k), &counts, deposit);
                    }
                }
                counts.add_to(stats);
            },
            [&](uint64_t, int wave) {
                for (int c = 0; c < wave; ++c)
                    for (const Deposit& d : deposits[static_cast<std::size_t>(c)]) {
                        Pixel& p = pixels[d.pixel];
                        p.phi[0] += d.phi.r;
                        p.phi[1] += d.phi.g;
                        p.phi[2] += d.phi.b;
                        ++p.m;
                    }
            });

        // Each pixel's radius and flux (pbrt-v3's update, alpha = 2/3).
        parallel_range(height, options.threads, [&](int begin, int end) {
            for (std::size_t i = std::size_t(begin) * width; i < std::size_t(end) * width; ++i) {
                Pixel& p = pixels[i];
                if (p.m > 0) {
                    constexpr double kGamma = 2.0 / 3.0;
                    const double n = p.n + kGamma * double(p.m);
                    const double r = double(p.radius) * std::sqrt(n / (p.n + double(p.m)));
                    const double shrink = (r * r) / (double(p.radius) * double(p.radius));
                    const float beta[3] = {p.vp.beta.r, p.vp.beta.g, p.vp.beta.b};
                    for (int c = 0; c < 3; ++c) {
                        p.tau[c] = (p.tau[c] + beta[c] * p.phi[c]) * shrink;
                        p.phi[c] = 0;
                    }
                    p.n = n;
                    p.radius = static_cast<float>(r);
                    p.m = 0;
                }
                p.vp.bsdf.reset();
                p.vp.layers.clear();
                p.vp.found = false;
            }
        });
        if (options.progress) options.progress(iter + 1, iterations);
    }

    // A pixel: its direct light's mean plus its photons' radiance estimate.
    Framebuffer fb;
    fb.width = width;
    fb.height = height;
    fb.rgb.assign(count * 3, 0.0f);
    const double shot = double(iterations) * double(photons);
    for (std::size_t i = 0; i < count; ++i) {
        const Pixel& p = pixels[i];
        const double area = double(kPi) * double(p.radius) * double(p.radius);
        for (int c = 0; c < 3; ++c)
            fb.rgb[i * 3 + c] = static_cast<float>(
                (p.ld[c] / iterations + p.tau[c] / (shot * area)) * double(film.scale));
    }
    return fb;
}

}  // namespace cmam::render
