// render — the film's render loop: spans of rows traced sample by sample, scheduled in row
// blocks or, with the CMAM, in strips (algorithms.md §6.3.1); the image is the same for any
// thread count.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "render/integrator.h"
#include "render/lighttrace.h"
#include "render/memory.h"
#include "render/parallel.h"
#include "render/sppm.h"
#include "render/tracer.h"

namespace cmam::render {

namespace {

bool reads_cones(const TextureNode& n) {
    return n.lod == FootprintMethod::Cones || n.lod == FootprintMethod::ConesAniso;
}

// Whether an image texture filtered by `area` takes its footprint from ray cones: the camera
// rays then carry differentials to centre the first hit's parallelogram on its stratum.
bool cones_read_by_area(const Scene& scene) {
    return std::any_of(scene.textures.begin(), scene.textures.end(), [](const TextureNode& n) {
        return n.kind == TextureNode::Kind::Image && n.filter.kind == texture::FilterKind::Area &&
               n.mapping == TextureNode::Mapping::Uv && reads_cones(n);
    });
}

// Whether a texture with a spherical, cylindrical or planar mapping takes its footprint from ray
// cones: the hits then keep the cones' cross-sections as world-space vectors.
bool cones_read_by_mapping(const Scene& scene) {
    return std::any_of(scene.textures.begin(), scene.textures.end(), [](const TextureNode& n) {
        return (n.kind == TextureNode::Kind::Image || n.kind == TextureNode::Kind::Checkerboard) &&
               n.mapping != TextureNode::Mapping::Uv && reads_cones(n);
    });
}

// The pixels traced, in the cropped film's coordinates: the film's own, or with a filtered film
// also those whose samples reach into it.
struct Traced {
    int x0, x1, y0, y1;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
};

// The film of a pixel filter other than pbrt-v3's default box (algorithms.md §17): as pbrt-v3's,
// each sample adds L w and w to every pixel whose centre is within the filter's radius of it, w
// the filter's weight from its tables, and a pixel is the sum of the first over the sum of the
// second (negative values, from the negative lobes of mitchell and sinc, made 0, as pbrt-v3).
// Each task of the render loop traces its part of the image (a tile: a block of rows, or a strip
// segment) into a buffer of its own that reaches the filter's radius beyond the tile, and the
// buffers are added to the image in the tiles' order, whichever finishes first, so the image is
// the same for any thread count.
class SplatFilm {
  public:
    explicit SplatFilm(const FilmSettings& film)
        : m_film(film),
          m_filter(film.filter),
          m_mx(static_cast<int>(std::ceil(film.filter.rx)) + 1),
          m_my(static_cast<int>(std::ceil(film.filter.ry)) + 1),
          m_sum(static_cast<std::size_t>(film.width()) * film.height() * 4, 0.0) {}

    // The pixels traced: as pbrt-v3's film asks its sampler for, every pixel whose samples can
    // reach the film's, [floor(0.5 - r), W + ceil(r - 0.5)) along each axis (the first pixel's
    // centre less the radius, the last one's plus it).
    Traced traced() const {
        return {static_cast<int>(std::floor(0.5f - m_filter.rx)),
                m_film.width() + static_cast<int>(std::ceil(m_filter.rx - 0.5f)),
                static_cast<int>(std::floor(0.5f - m_filter.ry)),
                m_film.height() + static_cast<int>(std::ceil(m_filter.ry - 0.5f))};
    }

    // A tile's buffer: pixels [x0, x0 + w) x [y0, y0 + h) of the cropped film, 4 doubles each
    // (the weighted r, g, b and the weights).
    struct Tile {
        int id = 0, x0 = 0, y0 = 0, w = 0, h = 0;
        std::vector<double> px;
    };

    // The buffer of tile `id`, which traces the film's (cropped) pixels [x_begin, x_end) x
    // [y_begin, y_end).
    Tile tile(int id, int x_begin, int x_end, int y_begin, int y_end) const {
        Tile t;
        t.id = id;
        t.x0 = std::max(0, x_begin - m_mx);
        t.y0 = std::max(0, y_begin - m_my);
        t.w = std::min(m_film.width(), x_end + m_mx) - t.x0;
        t.h = std::min(m_film.height(), y_end + m_my) - t.y0;
        t.px.assign(static_cast<std::size_t>(t.w) * t.h * 4, 0.0);
        return t;
    }

    // Samples of one row of pixels (a packet's) added up in single precision before they go to
    // the tile, pixel by pixel in 4 lanes (r, g, b and the weight): rows [y0, y0 + h) of the
    // cropped film, columns [x0, x0 + w).
    struct RowSums {
        int x0 = 0, y0 = 0, w = 0, h = 0;
        std::vector<std::array<float, 4>> px;
    };

    // Makes `r` the sums of the samples of pixels [x_begin, x_end) of row `row` (cropped film).
    void start(RowSums& r, int row, int x_begin, int x_end) const {
        r.x0 = std::max(0, x_begin - m_mx);
        r.y0 = std::max(0, row - m_my);
        r.w = std::max(0, std::min(m_film.width(), x_end + m_mx) - r.x0);
        r.h = std::max(0, std::min(m_film.height(), row + m_my + 1) - r.y0);
        r.px.assign(static_cast<std::size_t>(r.w) * r.h, {0, 0, 0, 0});
    }

    // Adds a sample at raster position (fx, fy) (the whole film's) with radiance L to the pixels
    // of the cropped film in its filter's reach: pbrt-v3's FilmTile::AddSample, in its
    // single-precision steps, so that the same pixels take the same table entries. Returns the
    // columns it reached, [x0, x1) of the cropped film (empty when none).
    std::pair<int, int> splat(RowSums& r, float fx, float fy, const Rgb& L) const {
        constexpr int N = PixelFilter::kTableSize;
        const float dx = fx - 0.5f, dy = fy - 0.5f;
        const int px0 = std::max(m_film.x0, static_cast<int>(std::ceil(dx - m_filter.rx))),
                  px1 = std::min(m_film.x1, static_cast<int>(std::floor(dx + m_filter.rx)) + 1),
                  py0 = std::max(m_film.y0, static_cast<int>(std::ceil(dy - m_filter.ry))),
                  py1 = std::min(m_film.y1, static_cast<int>(std::floor(dy + m_filter.ry)) + 1);
        if (px0 >= px1 || py0 >= py1) return {0, 0};
        const float inv_rx = 1 / m_filter.rx, inv_ry = 1 / m_filter.ry;
        // The factors along x, once for every row (at most 2 kMaxFilterRadius + 1 of them).
        float wx[2 * static_cast<int>(kMaxFilterRadius) + 2];
        // (The table positions are at least 0, so truncation is their floor.)
        for (int x = px0; x < px1; ++x) {
            const float tx = std::abs((float(x) - dx) * inv_rx * N);
            wx[x - px0] =
                m_filter.table_x[static_cast<std::size_t>(std::min(static_cast<int>(tx), N - 1))];
        }
#if defined(__SSE2__)
        const __m128 l = _mm_setr_ps(L.r, L.g, L.b, 1);
#else
        const float l[4] = {L.r, L.g, L.b, 1};
#endif
        for (int y = py0; y < py1; ++y) {
            const float ty = std::abs((float(y) - dy) * inv_ry * N);
            const float wy =
                m_filter.table_y[static_cast<std::size_t>(std::min(static_cast<int>(ty), N - 1))];
            float* p = r.px[static_cast<std::size_t>(y - m_film.y0 - r.y0) * r.w +
                            static_cast<std::size_t>(px0 - m_film.x0 - r.x0)]
                           .data();
            for (int k = 0; k < px1 - px0; ++k, p += 4) {
                // pbrt-v3's table entry (the same product); per lane the scalar l[c] * w + p[c].
                const float w = wx[k] * wy;
#if defined(__SSE2__)
                _mm_storeu_ps(p, _mm_add_ps(_mm_loadu_ps(p), _mm_mul_ps(l, _mm_set1_ps(w))));
#else
                for (int c = 0; c < 4; ++c) p[c] += l[c] * w;
#endif
            }
        }
        return {px0 - m_film.x0, px1 - m_film.x0};
    }

    // Adds columns [x0, x1) of the sums to the tile (in double precision), and clears them.
    void flush(RowSums& r, Tile& t, int x0, int x1) const {
        x0 = std::max(x0, r.x0);
        x1 = std::min(x1, r.x0 + r.w);
        for (int y = 0; y < r.h && x0 < x1; ++y) {
            std::array<float, 4>* src = &r.px[static_cast<std::size_t>(y) * r.w + (x0 - r.x0)];
            double* dst =
                &t.px[(static_cast<std::size_t>(r.y0 + y - t.y0) * t.w + (x0 - t.x0)) * 4];
            for (int k = 0; k < x1 - x0; ++k) {
                for (int c = 0; c < 4; ++c) dst[4 * k + c] += double(src[k][c]);
                src[k] = {0, 0, 0, 0};
            }
        }
    }

    // Hands a finished tile over: the finished tiles are added to the image in their order.
    void finish(Tile&& t) {
        std::lock_guard<std::mutex> lock(m_mutex);
        const int id = t.id;
        m_waiting.emplace(id, std::move(t));
        for (auto it = m_waiting.find(m_next); it != m_waiting.end(); it = m_waiting.find(m_next)) {
            add(it->second);
            m_waiting.erase(it);
            ++m_next;
        }
    }

    // The image, every tile added: each pixel's weighted mean, at least 0, times the film scale.
    void resolve(Framebuffer& fb) const {
        const double scale = m_film.scale;
        const std::size_t n = static_cast<std::size_t>(fb.width) * fb.height;
        for (std::size_t p = 0; p < n; ++p) {
            const double* s = &m_sum[p * 4];
            for (int c = 0; c < 3; ++c)
                fb.rgb[p * 3 + c] =
                    s[3] != 0 ? static_cast<float>(std::max(0.0, s[c] / s[3]) * scale) : 0.0f;
        }
    }

  private:
    void add(const Tile& t) {
        const int W = m_film.width();
        for (int y = 0; y < t.h; ++y) {
            const double* src = &t.px[static_cast<std::size_t>(y) * t.w * 4];
            double* dst = &m_sum[(static_cast<std::size_t>(t.y0 + y) * W + t.x0) * 4];
            for (int k = 0; k < t.w * 4; ++k) dst[k] += src[k];
        }
    }

    const FilmSettings& m_film;
    const PixelFilter& m_filter;
    const int m_mx, m_my;  // how far beyond its tile a sample reaches, in pixels (at most)
    std::vector<double> m_sum;
    std::mutex m_mutex;
    std::map<int, Tile> m_waiting;  // finished tiles not yet added (an earlier one is not)
    int m_next = 0;                 // the next tile to add
};

}  // namespace

FootprintProducers film_footprints(const Scene& scene, int spp) {
    return FootprintProducers(scene.footprint_methods, scene.camera, spp, cones_read_by_area(scene),
                              cones_read_by_mapping(scene));
}

float camera_ray(const Scene& scene, const FootprintProducers& footprints, float fx, float fy,
                 uint64_t pixel_seed, int sample, int nx, int ny, float to_stratum_x,
                 float to_stratum_y, TracedRay& r) {
    const Camera& camera = scene.camera;
    if (camera.environment && footprints.differentials()) {
        // The ray and its neighbours' directions together (they share sines and cosines).
        Vec3 dirs[3];
        camera.environment_directions(fx, fy, dirs);
        const auto& m = camera.world_from_camera;
        r.org = Vec3(m[3], m[7], m[11]);
        r.dir = dirs[0];
        footprints.start_environment_ray(r.fp, dirs, to_stratum_x, to_stratum_y);
        return 1;
    }
    if (camera.has_lens()) {
        // A thin lens (or a realistic camera's exit pupil): the sample's point on it, stratified
        // over the pixel's samples.
        float lu, lv;
        lens_sample(pixel_seed, sample, nx, ny, lu, lv);
        const CameraRay ray = camera.generate_ray(fx, fy, lu, lv);
        r.org = ray.org;
        r.dir = ray.dir;
        if (!camera.realistic)
            footprints.start_lens_ray(r.fp, fx, fy, lu, lv, r.dir, to_stratum_x, to_stratum_y);
        else if (ray.weight == 0 || !footprints.start_realistic_ray(r.fp, fx, fy, lu, lv, ray,
                                                                    to_stratum_x, to_stratum_y))
            return 0;  // blocked (or dropped as pbrt-v3 drops it): not traced
        return ray.weight;
    }
    // Pinhole, orthographic and environment cameras, one ray at a time.
    const CameraRay ray = camera.generate_ray(fx, fy);
    r.org = ray.org;
    r.dir = ray.dir;
    footprints.start_camera_ray(r.fp, fx, fy, r.dir, to_stratum_x, to_stratum_y);
    return 1;
}

namespace {

// Traces the film's samples into a framebuffer, a span of one row at a time.
//
// Scanline tags with several samples per pixel: the paper's scanline is a row of sample
// strata. Sub-row sy of pixel row py has ID py * ny + sy, its samples are numbered left to
// right (col * nx + sx), and the row is traced sub-row by sub-row, so each sample's cached
// neighbours are one stratum to the left and (2-D CMAM) one stratum above, as the pixels are
// at one sample per pixel. Pixel tags trace pixel by pixel. Either way every sample has the
// same position and seed and each pixel sums its samples in the same order, so only the CMAM
// sees the difference. Without the CMAM the film traces pixel by pixel whatever the tags: a
// pixel's samples, traced together, reuse what their rays touch while it is in the cache (the
// mesh scene at 64 spp 3% faster than sub-row by sub-row).
class FilmTracer {
  public:
    FilmTracer(const Scene& scene, const RenderOptions& options, RenderStats* stats,
               Framebuffer& fb, SplatFilm* splat)
        : m_scene(scene),
          m_film(scene.film),
          m_options(options),
          m_stats(stats),
          m_fb(fb),
          m_nx(scene.sampler.xsamples),
          m_ny(scene.sampler.ysamples),
          m_spp(m_nx * m_ny),
          m_stratum_x(m_nx),
          m_stratum_y(m_ny),
          m_sub_rows(scene.tags == TagPolicy::Scanline &&
                     scene.footprint_methods.has(FootprintMethod::Cmam)),
          m_tags(scene.footprint_methods.has(FootprintMethod::Cmam)),
          m_limit_luminance(options.aov == AovKind::None &&
                            scene.film.max_sample_luminance <
                                std::numeric_limits<float>::infinity()),
          m_footprints(film_footprints(scene, m_spp)),
          m_splat(splat),
          m_traced(splat ? splat->traced() : Traced{0, m_film.width(), 0, m_film.height()}) {}

    // The pixels traced (the cropped film's coordinates).
    const Traced& traced() const { return m_traced; }

    int samples_x() const { return m_nx; }
    bool sub_rows() const { return m_sub_rows; }

    // Traces pixels [x_begin, x_end) of one row, after `prime` pixels to their left whose
    // samples only feed the CMAM's caches (their radiance is dropped): they are what a row
    // traced whole would have put there.
    //
    // With a SplatFilm's tile the samples are added to the tile, not to the framebuffer.
    void span(int row, int x_begin, int x_end, int prime, CmamRowState& cmam,
              SplatFilm::Tile* tile = nullptr) const {
        Span sp{
            row, m_film.y0 + row, x_begin - prime, x_end - (x_begin - prime), prime, {}, {}, {}, {},
            {}};
        sp.counts.count_lookups = m_options.count_lookups;
        seed_pixels(sp);
        if (tile)
            m_splat->start(sp.row_sums, row, sp.c0, sp.c0 + sp.n);
        else
            sp.sum.assign(static_cast<std::size_t>(sp.n) * 3, 0.0);
        Packet packet;
        auto add = [&](int i, int sx, int sy) {
            add_sample(sp, packet, i, sx, sy);
            if (packet.n == Scene::kPacketSize) trace(sp, packet, cmam, tile);
        };
        if (m_sub_rows) {
            for (int sy = 0; sy < m_ny; ++sy)
                for (int i = 0; i < sp.n; ++i)
                    for (int sx = 0; sx < m_nx; ++sx) add(i, sx, sy);
        } else {
            for (int i = 0; i < sp.n; ++i)
                for (int sy = 0; sy < m_ny; ++sy)
                    for (int sx = 0; sx < m_nx; ++sx) add(i, sx, sy);
        }
        trace(sp, packet, cmam, tile);
        sp.counts.add_to(m_stats);
        if (tile) return;
        float* out = &m_fb.rgb[(static_cast<std::size_t>(row) * m_fb.width + x_begin) * 3];
        const double scale = m_options.aov == AovKind::None ? double(m_film.scale) : 1.0;
        const std::size_t skip = static_cast<std::size_t>(prime) * 3;
        for (std::size_t k = skip; k < sp.sum.size(); ++k)
            out[k - skip] = static_cast<float>(sp.sum[k] / m_spp * scale);
    }

  private:
    struct Span {
        int row, py;
        int c0, n;  // first column (primed pixels included) and pixel count
        int prime;
        std::vector<uint64_t> seeds;  // per pixel
        std::vector<double> sum;      // 3 per pixel
        RayCounts counts;
        PacketScratch scratch;        // trace_packet's
        SplatFilm::RowSums row_sums;  // a filtered film's
    };

    // Each pixel's seed. Its generator gives the pixel's jitter in stratum order (sy, sx), two
    // numbers per sample; they are computed where the sample is made (jitter()), not stored: a
    // row's jitter at 64 spp is 200 KB, read back from beyond the cache.
    void seed_pixels(Span& sp) const {
        sp.seeds.resize(static_cast<std::size_t>(sp.n));
        for (int i = 0; i < sp.n; ++i) {
            const int px = m_film.x0 + sp.c0 + i;
            const bool outside = px < 0 || px >= m_film.xres || sp.py < 0 || sp.py >= m_film.yres;
            sp.seeds[i] =
                !outside ? mix_seed(uint64_t(sp.py) * uint64_t(m_film.xres) + uint64_t(px), 0x5eed)
                         // (a filtered film's pixels beyond the film: seeds of their own)
                         : mix_seed((uint64_t(uint32_t(sp.py)) << 32) | uint32_t(px), 0xb07de5);
        }
    }

    // The jitter of pixel i's stratum `sample`: the pixel generator's numbers 2 sample and
    // 2 sample + 1, or the stratum's centre without jitter.
    void jitter(const Span& sp, int i, int sample, float* j) const {
        if (!m_scene.sampler.jitter) {
            j[0] = j[1] = 0.5f;
            return;
        }
        const uint64_t seed = sp.seeds[static_cast<std::size_t>(i)], k = 2 * uint64_t(sample);
        j[0] = Rng::float_at(seed, k);
        j[1] = Rng::float_at(seed, k + 1);
    }

    // Sets every member of `tag`.
    void tag_of(const Span& sp, int col, int sx, int sy, const float* j,
                texture::RayTag& tag) const {
        // Counted from the first pixel traced (a filtered film's start beyond the film's own:
        // the tags stay non-negative, the CMAM's caches being indexed by them). Every field is
        // written (camera rays are level 0, patch 0).
        col -= m_traced.x0;
        const int py = sp.py - m_traced.y0, xres = m_film.xres - m_traced.x0 * 2;
        tag.level = 0;
        tag.patch = 0;
        if (m_sub_rows) {
            tag.id = static_cast<uint32_t>(py * m_ny + sy);
            tag.seq = static_cast<uint32_t>(col * m_nx + sx);
            tag.positioned = true;  // in strata: the 2-D CMAM's Jacobian and centre
            tag.x = double(col) * m_nx + sx + j[0];
            tag.y = double(py) * m_ny + sy + j[1];
        } else {
            tag.id = static_cast<uint32_t>(py * xres + m_film.x0 + col);
            tag.seq = static_cast<uint32_t>(sy * m_nx + sx);
            tag.positioned = false;
            tag.x = tag.y = 0;
        }
    }

    // Camera samples in the order they are traced, traced together (trace_packet): pixel i of
    // the span and stratum sample = sy * nx + sx of each, their paths and AOV samples.
    struct Packet {
        int i[Scene::kPacketSize], sample[Scene::kPacketSize];
        // Raster positions and offsets to the strata's centres, for the rays made together.
        float fx[Scene::kPacketSize], fy[Scene::kPacketSize];
        float to_stratum_x[Scene::kPacketSize], to_stratum_y[Scene::kPacketSize];
        CameraPath paths[Scene::kPacketSize];
        Aov aov[Scene::kPacketSize];
        int n = 0;
    };

    // Adds the camera sample of pixel i, stratum (sx, sy), to the packet.
    void add_sample(Span& sp, Packet& packet, int i, int sx, int sy) const {
        const int k = packet.n++;
        const int col = sp.c0 + i, px = m_film.x0 + col, sample = sy * m_nx + sx;
        float j[2];
        jitter(sp, i, sample, j);
        const float fx = px + m_stratum_x.step(sx + j[0]), fy = sp.py + m_stratum_y.step(sy + j[1]);
        packet.i[k] = i;
        packet.sample[k] = sample;
        if (m_options.aov != AovKind::None) packet.aov[k] = Aov{m_options.aov};
        CameraPath& p = packet.paths[k];
        p.seed = mix_seed(sp.seeds[i], uint64_t(sample) + 1);
        p.pixel_seed = sp.seeds[i];
        p.sample = static_cast<uint32_t>(sample);
        p.samples = static_cast<uint32_t>(m_spp);
        p.samples_x = static_cast<uint32_t>(m_nx);
        packet.fx[k] = fx;  // (a filter's splat reads them too)
        packet.fy[k] = fy;
        if (m_footprints.batches_camera_rays()) {  // made with the packet's others (trace)
            packet.to_stratum_x[k] = 0.5f - j[0];
            packet.to_stratum_y[k] = 0.5f - j[1];
        } else {
            p.weight = camera_ray(m_scene, m_footprints, fx, fy, sp.seeds[i], sample, m_nx, m_ny,
                                  0.5f - j[0], 0.5f - j[1], p.ray);
        }
        if (m_tags)
            tag_of(sp, col, sx, sy, j, p.ray.fp.tag);
        else
            p.ray.fp.tag = {};
        p.counts = i < sp.prime ? nullptr : &sp.counts;
        p.aov = m_options.aov == AovKind::None ? nullptr : &packet.aov[k];
    }

    // Traces the packet's samples and adds each to its pixel, in order (or to `tile`'s pixels).
    void trace(Span& sp, Packet& packet, CmamRowState& cmam, SplatFilm::Tile* tile) const {
        if (packet.n == 0) return;
        if (m_footprints.batches_camera_rays()) {
            CameraRayBatch batch;
            m_footprints.camera_rays(packet.fx, packet.fy, packet.n, batch);
            for (int k = 0; k < packet.n; ++k) {
                TracedRay& r = packet.paths[k].ray;
                m_footprints.start_camera_ray(r.fp, r.org, r.dir, batch, k, packet.to_stratum_x[k],
                                              packet.to_stratum_y[k]);
            }
        }
        Rgb radiance[Scene::kPacketSize];
        if (!m_scene.camera.realistic) {
            trace_packet(m_scene, m_footprints, packet.paths, packet.n, &cmam, sp.scratch,
                         radiance);
        } else {
            // A realistic camera's samples: those the lens blocks are 0 (and their AOV), the
            // others traced together and weighted (pbrt-v3 multiplies the radiance by the
            // camera's weight, not the film's sum of weights).
            CameraPath traced[Scene::kPacketSize];
            int index[Scene::kPacketSize], m = 0;
            for (int k = 0; k < packet.n; ++k) {
                index[k] = -1;
                if (packet.paths[k].weight == 0) continue;
                index[k] = m;
                traced[m++] = packet.paths[k];
            }
            Rgb got[Scene::kPacketSize];
            trace_packet(m_scene, m_footprints, traced, m, &cmam, sp.scratch, got);
            for (int k = 0; k < packet.n; ++k) {
                radiance[k] = index[k] < 0 ? Rgb() : got[index[k]] * packet.paths[k].weight;
                if (index[k] < 0) packet.aov[k] = Aov{m_options.aov};
            }
        }
        if (tile) {  // a packet's samples summed in single precision, then added to the tile
            int x0 = std::numeric_limits<int>::max(), x1 = std::numeric_limits<int>::min();
            for (int k = 0; k < packet.n; ++k) {
                if (packet.i[k] < sp.prime) continue;  // (primed pixels feed the caches only)
                Rgb L = radiance[k];
                if (!finite(L)) {
                    ++sp.counts.non_finite_samples;
                    L = Rgb();
                }
                if (m_limit_luminance) L = limit_luminance(L);
                const auto [a, b] = m_splat->splat(sp.row_sums, packet.fx[k], packet.fy[k], L);
                if (a < b) {
                    x0 = std::min(x0, a);
                    x1 = std::max(x1, b);
                }
            }
            if (x0 < x1) m_splat->flush(sp.row_sums, *tile, x0, x1);
            packet.n = 0;
            return;
        }
        // Each pixel's samples added to its sum in order; a run of one pixel's samples (a packet
        // holds one or a few pixels' runs) in registers, not through memory sample by sample.
        int i = packet.i[0];
        double* acc = &sp.sum[static_cast<std::size_t>(i) * 3];
        double r = acc[0], g = acc[1], b = acc[2];
        for (int k = 0; k < packet.n; ++k) {
            if (packet.i[k] != i) {
                acc[0] = r;
                acc[1] = g;
                acc[2] = b;
                i = packet.i[k];
                acc = &sp.sum[static_cast<std::size_t>(i) * 3];
                r = acc[0];
                g = acc[1];
                b = acc[2];
            }
            Rgb L = radiance[k];
            if (m_options.aov != AovKind::None)
                L = Rgb(packet.aov[k].v[0], packet.aov[k].v[1], packet.aov[k].v[2]);
            if (!finite(L)) {
                if (i >= sp.prime) ++sp.counts.non_finite_samples;
                L = Rgb();
            }
            if (m_limit_luminance) L = limit_luminance(L);
            r += L.r;
            g += L.g;
            b += L.b;
        }
        acc[0] = r;
        acc[1] = g;
        acc[2] = b;
        packet.n = 0;
    }

    // A sample's radiance scaled down to the film's maxsampleluminance where its luminance
    // (pbrt-v3's y of an RGB) is above it. Only radiance is limited, and only below infinity
    // (pbrt-v3's default, which limits nothing: then m_limit_luminance is false).
    Rgb limit_luminance(const Rgb& L) const {
        const float y = 0.212671f * L.r + 0.715160f * L.g + 0.072169f * L.b;
        return y > m_film.max_sample_luminance ? L * (m_film.max_sample_luminance / y) : L;
    }

    const Scene& m_scene;
    const FilmSettings& m_film;
    const RenderOptions& m_options;
    RenderStats* m_stats;
    Framebuffer& m_fb;
    const int m_nx, m_ny, m_spp;
    // x / n for the strata's raster offsets: a product by the reciprocal when n is a power of two,
    // where the two are the same float (the quotient of a division waits about 10 cycles, and a
    // sample has two on its way to its ray).
    struct Stratum {
        explicit Stratum(int n_)
            : n(float(n_)), inv(1.0f / float(n_)), power_of_two(n_ > 0 && (n_ & (n_ - 1)) == 0) {}
        float step(float x) const { return power_of_two ? x * inv : x / n; }
        float n, inv;
        bool power_of_two;
    };
    const Stratum m_stratum_x, m_stratum_y;
    const bool m_sub_rows;
    const bool m_tags;             // a CMAM reads the rays' tags (nothing else does)
    const bool m_limit_luminance;  // radiance (not an AOV) under a finite maxsampleluminance
    const FootprintProducers m_footprints;
    SplatFilm* m_splat;  // the filtered film, or null (each sample counts for its own pixel)
    const Traced m_traced;
};

// Rows in fixed blocks of 8, each row whole, so the image is the same for any thread count. The
// 1-D CMAM's caches, which live for one block, see each row as one scan from left to right, as
// in the paper: its matches never cross a row.
// With a filtered film, each block is a tile.
void render_rows(const FilmTracer& tracer, const RenderOptions& options, const Traced& px,
                 SplatFilm* splat) {
    constexpr int kBlockRows = 8;
    const int height = px.height(), blocks = (height + kBlockRows - 1) / kBlockRows;
    std::atomic<int> rows_done{0};
    parallel_range(blocks, options.threads, [&](int begin, int end) {
        CmamRowState cmam;
        for (int b = begin; b < end; ++b) {
            const int r0 = px.y0 + b * kBlockRows, r1 = std::min(px.y1, r0 + kBlockRows);
            std::optional<SplatFilm::Tile> tile;
            if (splat) tile = splat->tile(b, px.x0, px.x1, r0, r1);
            for (int row = r0; row < r1; ++row) {
                tracer.span(row, px.x0, px.x1, 0, cmam, tile ? &*tile : nullptr);
                int done = ++rows_done;
                if (options.progress) options.progress(done, height);
            }
            if (splat) splat->finish(std::move(*tile));
        }
    });
}

// With the 2-D CMAM the image goes in fixed strips of kCmamStripWidth columns, each traced top
// to bottom with caches of its own, each row left to right: every row but the image's first has
// the row above in the caches (the 2-D CMAM's Jacobian column), and each strip row starts with
// the pixels to its left primed (the left neighbours; two at one sample per pixel, where the
// region needs the two previous samples). Samples reach the caches exactly as in a whole-row
// scan, and the image is the same for any thread count (algorithms.md §6.3.1).
//
// So that the threads finish together, a strip is cut into segments of rows when there are
// fewer than 16 strips a thread: each segment is a task of its own, whose caches start with the
// row above the segment traced into them. Caches are then in the state a whole strip would have
// left them in, so the cut changes no pixel.
void render_cmam_strips(const FilmTracer& tracer, const RenderOptions& options, const Traced& px,
                        SplatFilm* splat) {
    const int height = px.height(), width = px.width();
    const int strips = (width + kCmamStripWidth - 1) / kCmamStripWidth;
    const int prime_pixels = tracer.sub_rows() ? (tracer.samples_x() >= 2 ? 1 : 2) : 0;
    const int threads = worker_count(options.threads);
    const int segments = std::clamp(16 * threads / strips, 1, std::max(1, height / 16));
    const int seg_rows = (height + segments - 1) / segments;
    const int tasks_per_strip = (height + seg_rows - 1) / seg_rows;
    std::atomic<int> spans_done{0};
    parallel_range(strips * tasks_per_strip, options.threads, [&](int begin, int end) {
        for (int task = begin; task < end; ++task) {
            CmamRowState cmam;
            const int k = task / tasks_per_strip, r0 = px.y0 + (task % tasks_per_strip) * seg_rows;
            const int x0 = px.x0 + k * kCmamStripWidth, x1 = std::min(px.x1, x0 + kCmamStripWidth);
            const int prime = std::min(x0 - px.x0, prime_pixels);
            const int r1 = std::min(px.y1, r0 + seg_rows);
            std::optional<SplatFilm::Tile> tile;  // with a filtered film, the segment's
            if (splat) tile = splat->tile(task, x0, x1, r0, r1);
            if (r0 > px.y0)  // the row above, into the caches only
                tracer.span(r0 - 1, x1, x1, x1 - x0 + prime, cmam, tile ? &*tile : nullptr);
            for (int row = r0; row < r1; ++row) {
                tracer.span(row, x0, x1, prime, cmam, tile ? &*tile : nullptr);
                int done = ++spans_done;
                if (options.progress) options.progress(done, strips * height);
            }
            if (splat) splat->finish(std::move(*tile));
        }
    });
}

// The pyramids and tables the scene's filters read, built before tracing and in parallel: each
// texture's pyramid (and summed-area table), then every level's row prefix table. Left to the
// first lookup, one thread would build each while the others wait for it. (A row prefix table
// larger than its margin's bound is only made here: its rows are built a band at a time as the
// workers' regions first read them, so a short render of large textures builds what it reads.)
void build_texture_tables(const Scene& scene, int threads) {
    const auto uses = texture_uses(scene);
    const std::vector<std::pair<const texture::FilteredTexture*, TextureUses>> textures(
        uses.begin(), uses.end());
    parallel_range(static_cast<int>(textures.size()), threads, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
            const auto& [tex, u] = textures[static_cast<std::size_t>(i)];
            if (u.pyramid) tex->pyramid();
            if (u.sat) tex->sat();
        }
    });
    std::vector<std::pair<const texture::FilteredTexture*, int>> levels;
    for (const auto& [tex, u] : textures)
        if (u.row_prefix)
            for (int l = 0; l < tex->pyramid().levels(); ++l) levels.emplace_back(tex, l);
    parallel_range(static_cast<int>(levels.size()), threads, [&](int begin, int end) {
        for (int i = begin; i < end; ++i)
            levels[static_cast<std::size_t>(i)].first->row_prefix(
                levels[static_cast<std::size_t>(i)].second);
    });
}

}  // namespace

Framebuffer render(const Scene& scene, const RenderOptions& options, RenderStats* stats) {
    Framebuffer fb;
    fb.width = scene.film.width();
    fb.height = scene.film.height();
    fb.rgb.assign(static_cast<std::size_t>(fb.width) * fb.height * 3, 0.0f);
    if (options.aov == AovKind::Footprint) fb.channel_names = {"major", "minor", "lambda"};

    std::unique_ptr<tbb::global_control> limit;
    if (options.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      options.threads);
    build_texture_tables(scene, options.threads);
    if (scene.sppm.on && options.aov == AovKind::None) return render_sppm(scene, options, stats);
    // bdpt's and mlt's light paths after the film, each reported as half of the progress.
    const bool light_paths = scene.light_tracing && options.aov == AovKind::None;
    RenderOptions film_options = options, light_options = options;
    if (light_paths && options.progress) {
        film_options.progress = [&options](int done, int total) {
            options.progress(done, 2 * total);
        };
        light_options.progress = [&options](int done, int total) {
            options.progress(total + done, 2 * total);
        };
    }
    // A pixel filter reaching beyond the pixel splats its samples; AOVs are each pixel's own.
    std::unique_ptr<SplatFilm> splat;
    if (!scene.film.filter.own_pixel() && options.pixel_filter && options.aov == AovKind::None)
        splat = std::make_unique<SplatFilm>(scene.film);
    const FilmTracer tracer(scene, film_options, stats, fb, splat.get());
    const Traced& px = tracer.traced();
    if (scene.footprint_methods.has(FootprintMethod::Cmam) && scene.cmam.two_d)
        render_cmam_strips(tracer, film_options, px, splat.get());
    else
        render_rows(tracer, film_options, px, splat.get());
    if (splat) splat->resolve(fb);
    if (light_paths) add_light_paths(scene, light_options, stats, fb);
    return fb;
}

}  // namespace cmam::render
