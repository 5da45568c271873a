// render — pbrt-v3's Whitted integrator and the image render loop.
// Work is scheduled by whole rows, processed left to right; every pixel's random numbers derive
// from its position and sample index, so the image is identical for any thread count.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "render/scene.h"

namespace cmam::render {

struct RenderStats {
    std::atomic<uint64_t> camera_rays{0}, secondary_rays{0}, shadow_rays{0};
    std::atomic<uint64_t> lookups_by_filter[texture::kFilterKinds] = {};  // with a footprint
    std::atomic<uint64_t> lookups_point_sampled{0};                       // without one
    std::atomic<uint64_t> lookups_non_finite{0};     // non-finite uv or footprint: texture mean
    std::atomic<uint64_t> dropped_differentials{0};  // grazing or non-finite: point sampled
    // 2-D CMAM lookups without a sample above on the same object and path (the image's first
    // row, or where the object or path was not hit above)
    std::atomic<uint64_t> cmam_2d_without_above{0};
    // Samples whose radiance was NaN or infinite (from NaN or infinite texels or parameters):
    // taken as black, as pbrt-v3 does after reporting them.
    std::atomic<uint64_t> non_finite_samples{0};
    uint64_t total_rays() const { return camera_rays + secondary_rays + shadow_rays; }
};

/// Arbitrary output variables: what `cmam render --aov` writes instead of radiance.
enum class AovKind : uint8_t { None, Footprint, Texture };

/// With the 2-D CMAM the image is traced in strips this many pixels wide, each top to bottom.
inline constexpr int kCmamStripWidth = 64;

struct RenderOptions {
    int threads = 0;  // 0: all cores
    AovKind aov = AovKind::None;
    /// Count texture lookups per filter (RenderStats::lookups_*, cmam_2d_without_above); off,
    /// the filters skip the bookkeeping the counts need. Rays are counted either way.
    bool count_lookups = true;
    /// Called after each finished row, or row of a strip with the CMAM, with (done, total); may
    /// be empty.
    std::function<void(int, int)> progress;
    /// The scene's PixelFilter; false: each sample counts for its own pixel alone (the box of
    /// radius 0.5, as `cmam eval` defines its pixels), whatever the scene's filter.
    bool pixel_filter = true;
};

/// Rendered image: linear RGB, top row first, film.width() x film.height().
struct Framebuffer {
    int width = 0, height = 0;
    std::vector<float> rgb;  // 3 floats per pixel (radiance, or the AOV's three channels)
    std::vector<std::string> channel_names = {"R", "G", "B"};
};

Framebuffer render(const Scene& scene, const RenderOptions& options, RenderStats* stats);

/// Radiance along one camera ray (exposed for tests).
Rgb trace_radiance(const Scene& scene, const Vec3& org, const Vec3& dir, uint64_t seed,
                   RenderStats* stats);

}  // namespace cmam::render
