// render — the film's render loop: spans of rows traced sample by sample, scheduled in row
// blocks or, with the CMAM, in strips (algorithms.md §6.3.1); the image is the same for any
// thread count.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "render/integrator.h"
#include "render/memory.h"
#include "render/parallel.h"
#include "render/tracer.h"

namespace cmam::render {

namespace {

// Whether an image texture filtered by `area` takes its footprint from ray cones: the camera
// rays then carry differentials to centre the first hit's parallelogram on its stratum.
bool cones_read_by_area(const Scene& scene) {
    return std::any_of(scene.textures.begin(), scene.textures.end(), [](const TextureNode& n) {
        return n.kind == TextureNode::Kind::Image && n.filter.kind == texture::FilterKind::Area &&
               n.mapping == TextureNode::Mapping::Uv &&
               (n.lod == FootprintMethod::Cones || n.lod == FootprintMethod::ConesAniso);
    });
}

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
               Framebuffer& fb)
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
          m_footprints(scene.footprint_methods, scene.camera, m_spp, cones_read_by_area(scene)) {}

    int samples_x() const { return m_nx; }
    bool sub_rows() const { return m_sub_rows; }

    // Traces pixels [x_begin, x_end) of one row, after `prime` pixels to their left whose
    // samples only feed the CMAM's caches (their radiance is dropped): they are what a row
    // traced whole would have put there.
    void span(int row, int x_begin, int x_end, int prime, CmamRowState& cmam) const {
        Span sp{row, m_film.y0 + row, x_begin - prime, x_end - (x_begin - prime), prime, {}, {}, {},
                {}};
        sp.counts.count_lookups = m_options.count_lookups;
        seed_pixels(sp);
        sp.sum.assign(static_cast<std::size_t>(sp.n) * 3, 0.0);
        Packet packet;
        auto add = [&](int i, int sx, int sy) {
            add_sample(sp, packet, i, sx, sy);
            if (packet.n == Scene::kPacketSize) trace(sp, packet, cmam);
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
        trace(sp, packet, cmam);
        float* out = &m_fb.rgb[(static_cast<std::size_t>(row) * m_fb.width + x_begin) * 3];
        const double scale = m_options.aov == AovKind::None ? double(m_film.scale) : 1.0;
        const std::size_t skip = static_cast<std::size_t>(prime) * 3;
        for (std::size_t k = skip; k < sp.sum.size(); ++k)
            out[k - skip] = static_cast<float>(sp.sum[k] / m_spp * scale);
        sp.counts.add_to(m_stats);
    }

  private:
    struct Span {
        int row, py;
        int c0, n;  // first column (primed pixels included) and pixel count
        int prime;
        std::vector<uint64_t> seeds;  // per pixel
        std::vector<double> sum;      // 3 per pixel
        RayCounts counts;
        PacketScratch scratch;  // trace_packet's
    };

    // Each pixel's seed. Its generator gives the pixel's jitter in stratum order (sy, sx), two
    // numbers per sample; they are computed where the sample is made (jitter()), not stored: a
    // row's jitter at 64 spp is 200 KB, read back from beyond the cache.
    void seed_pixels(Span& sp) const {
        sp.seeds.resize(static_cast<std::size_t>(sp.n));
        for (int i = 0; i < sp.n; ++i) {
            const int px = m_film.x0 + sp.c0 + i;
            sp.seeds[i] = mix_seed(uint64_t(sp.py) * uint64_t(m_film.xres) + uint64_t(px), 0x5eed);
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
        tag = {};
        if (m_sub_rows) {
            tag.id = static_cast<uint32_t>(sp.py * m_ny + sy);
            tag.seq = static_cast<uint32_t>(col * m_nx + sx);
            tag.positioned = true;  // in strata: the 2-D CMAM's Jacobian and centre
            tag.x = double(col) * m_nx + sx + j[0];
            tag.y = double(sp.py) * m_ny + sy + j[1];
        } else {
            tag.id = static_cast<uint32_t>(sp.py * m_film.xres + m_film.x0 + col);
            tag.seq = static_cast<uint32_t>(sy * m_nx + sx);
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
        packet.aov[k] = Aov{m_options.aov};
        CameraPath& p = packet.paths[k];
        p.seed = mix_seed(sp.seeds[i], uint64_t(sample) + 1);
        if (m_footprints.batches_camera_rays()) {  // made with the packet's others (trace)
            packet.fx[k] = fx;
            packet.fy[k] = fy;
            packet.to_stratum_x[k] = 0.5f - j[0];
            packet.to_stratum_y[k] = 0.5f - j[1];
        } else if (m_scene.camera.environment && m_footprints.differentials()) {
            // The ray and its neighbours' directions together (they share sines and cosines).
            Vec3 dirs[3];
            m_scene.camera.environment_directions(fx, fy, dirs);
            const auto& m = m_scene.camera.world_from_camera;
            p.ray.org = Vec3(m[3], m[7], m[11]);
            p.ray.dir = dirs[0];
            m_footprints.start_environment_ray(p.ray.fp, dirs, 0.5f - j[0], 0.5f - j[1]);
        } else if (m_scene.camera.has_lens()) {
            // A thin lens: the sample's point on the lens, stratified over the pixel's samples.
            float lu, lv;
            lens_sample(sp.seeds[i], sample, m_nx, m_ny, lu, lv);
            const CameraRay ray = m_scene.camera.generate_ray(fx, fy, lu, lv);
            p.ray.org = ray.org;
            p.ray.dir = ray.dir;
            m_footprints.start_lens_ray(p.ray.fp, fx, fy, lu, lv, p.ray.dir, 0.5f - j[0],
                                        0.5f - j[1]);
        } else {  // orthographic and environment cameras, one ray at a time
            const CameraRay ray = m_scene.camera.generate_ray(fx, fy);
            p.ray.org = ray.org;
            p.ray.dir = ray.dir;
            m_footprints.start_camera_ray(p.ray.fp, fx, fy, p.ray.dir, 0.5f - j[0], 0.5f - j[1]);
        }
        tag_of(sp, col, sx, sy, j, p.ray.fp.tag);
        p.counts = i < sp.prime ? nullptr : &sp.counts;
        p.aov = m_options.aov == AovKind::None ? nullptr : &packet.aov[k];
    }

    // Traces the packet's samples and adds each to its pixel, in order.
    void trace(Span& sp, Packet& packet, CmamRowState& cmam) const {
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
        trace_packet(m_scene, m_footprints, packet.paths, packet.n, &cmam, sp.scratch, radiance);
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
            if (!std::isfinite(L.r) || !std::isfinite(L.g) || !std::isfinite(L.b)) {
                if (i >= sp.prime) ++sp.counts.non_finite_samples;
                L = Rgb();
            }
            r += L.r;
            g += L.g;
            b += L.b;
        }
        acc[0] = r;
        acc[1] = g;
        acc[2] = b;
        packet.n = 0;
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
    const FootprintProducers m_footprints;
};

// Rows in fixed blocks of 8, each row whole, so the image is the same for any thread count. The
// 1-D CMAM's caches, which live for one block, see each row as one scan from left to right, as
// in the paper: its matches never cross a row.
void render_rows(const FilmTracer& tracer, const RenderOptions& options, int height, int width) {
    constexpr int kBlockRows = 8;
    const int blocks = (height + kBlockRows - 1) / kBlockRows;
    std::atomic<int> rows_done{0};
    parallel_range(blocks, options.threads, [&](int begin, int end) {
        CmamRowState cmam;
        for (int b = begin; b < end; ++b)
            for (int row = b * kBlockRows; row < std::min(height, (b + 1) * kBlockRows); ++row) {
                tracer.span(row, 0, width, 0, cmam);
                int done = ++rows_done;
                if (options.progress) options.progress(done, height);
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
void render_cmam_strips(const FilmTracer& tracer, const RenderOptions& options, int height,
                        int width) {
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
            const int k = task / tasks_per_strip, r0 = (task % tasks_per_strip) * seg_rows;
            const int x0 = k * kCmamStripWidth, x1 = std::min(width, x0 + kCmamStripWidth);
            const int prime = std::min(x0, prime_pixels);
            if (r0 > 0)  // the row above, into the caches only
                tracer.span(r0 - 1, x1, x1, x1 - x0 + prime, cmam);
            for (int row = r0; row < std::min(height, r0 + seg_rows); ++row) {
                tracer.span(row, x0, x1, prime, cmam);
                int done = ++spans_done;
                if (options.progress) options.progress(done, strips * height);
            }
        }
    });
}

// The pyramids and tables the scene's filters read, built before tracing and in parallel: each
// texture's pyramid (and summed-area table), then every level's row prefix table. Left to the
// first lookup, one thread would build each while the others wait for it.
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
    const FilmTracer tracer(scene, options, stats, fb);
    if (scene.footprint_methods.has(FootprintMethod::Cmam) && scene.cmam.two_d)
        render_cmam_strips(tracer, options, fb.height, fb.width);
    else
        render_rows(tracer, options, fb.height, fb.width);
    return fb;
}

}  // namespace cmam::render
