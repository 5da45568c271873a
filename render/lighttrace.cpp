#include "render/lighttrace.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "render/parallel.h"
#include "render/sppm.h"
#include "render/tracer.h"

namespace cmam::render {

namespace {

// Light paths are traced in tasks of kPathChunk; the splats of kWaveChunks tasks are kept and
// then added to the pixels in the tasks' order, so that the sums are the same for any thread
// count.
constexpr int kPathChunk = 4096;
constexpr int kWaveChunks = 64;

// The perspective camera as the light paths see it (pbrt-v3's PerspectiveCamera::Sample_Wi and
// We): a point of its lens (its centre for the pinhole) towards a point p, the pixel whose rays
// from that lens point pass through p, and the importance over the density of the lens point.
// The camera's importance is 1 / (A lens_area cos^4 theta) per unit lens area and solid angle,
// A the film's area at unit distance (the whole film's, cropped or not), so that a radiance of 1
// everywhere gives 1; a lens point drawn uniformly has density 1 / lens_area by area, which is
// d^2 / (cos theta lens_area) by solid angle at p: their ratio is 1 / (d^2 A cos^3 theta).
class CameraImportance {
  public:
    CameraImportance(const Camera& camera, const FilmSettings& film)
        : m_camera(camera), m_film(film) {
        // The camera's frame is rigid (light_tracing_camera), so its inverse is the transpose.
        const auto& m = camera.world_from_camera;
        m_origin = Vec3(m[3], m[7], m[11]);
        m_x = Vec3(m[0], m[4], m[8]);
        m_y = Vec3(m[1], m[5], m[9]);
        m_z = Vec3(m[2], m[6], m[10]);
        const double t = camera.tan_half_fov;
        m_area = float(double(camera.screen[1] - camera.screen[0]) *
                       double(camera.screen[3] - camera.screen[2]) * t * t);
    }

    bool join(const Vec3& p, float u1, float u2, CameraJoin& j) const {
        const Camera& c = m_camera;
        float lx = 0, ly = 0;
        if (c.lens_radius > 0) {
            concentric_disc(u1, u2, lx, ly);
            lx *= c.lens_radius;
            ly *= c.lens_radius;
        }
        // p in camera space, seen from the lens point.
        const Vec3 q = p - m_origin;
        const Vec3 d(dot(q, m_x) - lx, dot(q, m_y) - ly, dot(q, m_z));
        if (!(d.z > 0)) return false;
        // Where the ray from the lens point through p meets the plane of focus (z = 1 for the
        // pinhole), and the raster position whose pinhole ray passes there (generate_ray's map).
        const float focus = c.lens_radius > 0 ? c.focal_distance : 1.0f;
        const float sx = (lx + d.x * (focus / d.z)) / (focus * c.tan_half_fov);
        const float sy = (ly + d.y * (focus / d.z)) / (focus * c.tan_half_fov);
        const float px = (sx - c.screen[0]) / (c.screen[1] - c.screen[0]) * float(c.xres);
        const float py = (c.screen[3] - sy) / (c.screen[3] - c.screen[2]) * float(c.yres);
        if (!(px >= float(m_film.x0) && px < float(m_film.x1) && py >= float(m_film.y0) &&
              py < float(m_film.y1)))
            return false;
        const int ix = std::min(static_cast<int>(px), m_film.x1 - 1);
        const int iy = std::min(static_cast<int>(py), m_film.y1 - 1);
        const float len2 = dot(d, d), cos_theta = d.z / std::sqrt(len2);
        j.lens = m_origin + lx * m_x + ly * m_y;
        const Vec3 to = j.lens - p;
        const float dist2 = dot(to, to);
        if (!(dist2 > 0)) return false;
        j.wi = to / std::sqrt(dist2);
        j.importance = 1 / (dist2 * m_area * cos_theta * cos_theta * cos_theta);
        j.pixel = static_cast<uint32_t>(iy - m_film.y0) * static_cast<uint32_t>(m_film.width()) +
                  static_cast<uint32_t>(ix - m_film.x0);
        return std::isfinite(j.importance);
    }

  private:
    const Camera& m_camera;
    const FilmSettings& m_film;
    Vec3 m_origin, m_x, m_y, m_z;
    float m_area = 1;
};

struct Splat {
    uint32_t pixel;
    Rgb L;
};

}  // namespace

bool light_tracing_camera(const Camera& c) {
    if (c.orthographic || c.environment || c.realistic) return false;
    const auto& m = c.world_from_camera;
    const Vec3 x(m[0], m[4], m[8]), y(m[1], m[5], m[9]), z(m[2], m[6], m[10]);
    auto near = [](float a, float b) { return std::abs(a - b) < 1e-3f; };
    return near(dot(x, x), 1) && near(dot(y, y), 1) && near(dot(z, z), 1) && near(dot(x, y), 0) &&
           near(dot(x, z), 0) && near(dot(y, z), 0);
}

std::size_t light_path_pixel_bytes() {
    return 3 * sizeof(double);
}

void add_light_paths(const Scene& scene, const RenderOptions& options, RenderStats* stats,
                     Framebuffer& fb) {
    if (!scene.light_tracing) return;  // (set only for a camera and scene they can join)
    const FilmSettings& film = scene.film;
    const std::size_t count = std::size_t(film.width()) * std::size_t(film.height());
    if (count == 0 || fb.rgb.size() != count * 3) return;

    const LightEmitter lights(scene, true);
    if (lights.empty()) return;

    // As many paths as the film has camera samples (pbrt-v3 traces one for each); a pixel's
    // splats estimate its radiance times the cropped film's share of the whole film over that.
    const uint64_t paths = uint64_t(scene.sampler.spp()) * count;
    const double scale = double(film.scale) * double(film.xres) * double(film.yres) / double(paths);
    const CameraImportance camera(scene.camera, film);
    const CameraJoinFn join = [&camera](const Vec3& p, float u1, float u2, CameraJoin& j) {
        return camera.join(p, u1, u2, j);
    };
    const FootprintProducers footprints = film_footprints(scene, scene.sampler.spp());

    std::vector<double> sum(count * 3, 0.0);
    std::vector<std::vector<Splat>> splats(kWaveChunks);
    const uint64_t chunks = (paths + kPathChunk - 1) / kPathChunk;
    in_waves(
        chunks, kWaveChunks, options.threads,
        [&](uint64_t first, int begin, int end) {
            RayCounts counts;
            counts.count_lookups = options.count_lookups;
            for (int c = begin; c < end; ++c) {
                std::vector<Splat>& out = splats[static_cast<std::size_t>(c)];
                out.clear();
                const LightSplatFn splat = [&out](uint32_t pixel, const Rgb& L) {
                    out.push_back({pixel, L});
                };
                const uint64_t k0 = (first + uint64_t(c)) * kPathChunk,
                               k1 = std::min(paths, k0 + kPathChunk);
                for (uint64_t k = k0; k < k1; ++k) {
                    // The light, its position and direction from the Halton sequence, the
                    // path's bounces and lens points from a generator of its own.
                    Emission e;
                    if (!lights.emit(k, e)) continue;
                    light_path(scene, footprints, e.org, e.dir, e.beta,
                               mix_seed(0x6c69676874ull, k), &counts, join, splat);
                }
            }
            counts.add_to(stats);
        },
        [&](uint64_t first, int wave) {
            for (int c = 0; c < wave; ++c)
                for (const Splat& s : splats[static_cast<std::size_t>(c)]) {
                    double* px = &sum[std::size_t(s.pixel) * 3];
                    px[0] += s.L.r;
                    px[1] += s.L.g;
                    px[2] += s.L.b;
                }
            // (In thousandths: the waves may be more than an int holds.)
            if (options.progress)
                options.progress(static_cast<int>(1000 * (first + uint64_t(wave)) / chunks), 1000);
        });
    for (std::size_t i = 0; i < count * 3; ++i)
        fb.rgb[i] = static_cast<float>(double(fb.rgb[i]) + sum[i] * scale);
}

}  // namespace cmam::render
