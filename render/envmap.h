// render — pbrt-v3's "infinite" light with an environment map: a lat-long image around the
// scene, seen by rays that escape and importance-sampled for direct lighting by a
// piecewise-constant 2-D distribution of its luminance (algorithms.md §13).
#pragma once

#include <cmam/texture/filter.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "render/math.h"

namespace cmam::render {

/// How many samples the batched sample() functions below take together (their table reads
/// overlap); callers drawing many samples hand them over in batches of this size.
inline constexpr int kSampleBatch = 16;

/// A piecewise-constant density on [0,1): n equal cells with non-negative weights.
class Distribution1D {
  public:
    Distribution1D() = default;
    explicit Distribution1D(std::vector<float> weights);
    /// The same from n weights, its tables written in `storage` (table_bytes(n) bytes, aligned
    /// to 4, which the caller keeps while the distribution is used): Distribution2D's rows, all
    /// in one allocation.
    Distribution1D(const float* weights, std::size_t n, std::byte* storage);
    static std::size_t table_bytes(std::size_t n);
    // Rows share their Distribution2D's tables: moved (the tables' pointers stay valid), not
    // copied.
    Distribution1D(const Distribution1D&) = delete;
    Distribution1D& operator=(const Distribution1D&) = delete;
    Distribution1D(Distribution1D&&) noexcept = default;
    Distribution1D& operator=(Distribution1D&&) noexcept = default;

    int size() const { return static_cast<int>(m_n); }
    /// The weights' integral over [0,1) (their mean).
    double integral() const { return m_integral; }
    struct Sample {
        float x;    // in [0,1)
        float pdf;  // the density at x
        int cell;   // x's cell
    };
    /// Maps a uniform number in [0,1) to x in [0,1) with its density and cell.
    Sample sample(float u) const;
    /// Asks the cache for the guide entry sample(u) starts from (a batch's rows ask first).
    void prefetch(float u) const { __builtin_prefetch(m_guide + guide_of(u)); }
    /// The cell sample(u) starts its walk from: the one it returns or one a few cells from it.
    int start_cell(float u) const { return static_cast<int>(m_guide[guide_of(u)]); }
    float pdf(int cell) const;

  private:
    static constexpr std::size_t kCellsPerGuide = 4;
    static std::size_t guide_count(std::size_t n) {
        return std::max<std::size_t>(1, n / kCellsPerGuide);
    }
    void build(const float* weights, std::size_t n, std::byte* storage);
    std::unique_ptr<std::byte[]> m_own;  // the tables, when they are its own
    // The tables: the weights, the cumulative sums (n + 1 entries, from 0 to 1, summed in
    // double) and the guide (the cell holding g / guides, for each g), one after another.
    const float* m_func = nullptr;
    const float* m_cdf = nullptr;
    const uint32_t* m_guide = nullptr;
    std::size_t m_n = 0, m_guides = 0;
    double m_integral = 0;
    std::size_t guide_of(float u) const {  // u's guide entry (the last one from u = 1 on)
        const std::size_t guides = m_guides;
        const float gu = u * float(guides);
        return gu >= 0 && gu < float(guides) ? static_cast<std::size_t>(gu)
                                             : (gu >= 0 ? guides - 1 : 0);
    }
};

/// A piecewise-constant density on [0,1)^2 over an nu x nv grid (weights row by row, v major):
/// v is drawn from the rows' marginal, then u from that row's conditional.
class Distribution2D {
  public:
    Distribution2D() = default;
    /// Over nu x nv cells, row v's nu weights written by row_weights(v, row), one row at a time.
    Distribution2D(int nu, int nv, const std::function<void(int, float*)>& row_weights);
    bool empty() const { return m_marginal.size() == 0 || m_marginal.integral() == 0; }
    struct Sample {
        std::array<float, 2> uv;  // in [0,1)^2
        float pdf;                // with respect to du dv
    };
    Sample sample(float u1, float u2) const { return finish(m_marginal.sample(u2), u1); }
    /// sample(u1, u2) in two steps. start() draws the row (v) and finds the cell its walk
    /// starts from (the cell drawn or one a few cells from it): a caller that will read near it
    /// can ask the cache for that before finish() walks, so that the misses overlap.
    struct Start {
        Distribution1D::Sample v;
        int cell;
    };
    Start start(float u1, float u2) const {
        const Distribution1D::Sample v = m_marginal.sample(u2);
        return {v, m_rows[static_cast<std::size_t>(v.cell)].start_cell(u1)};
    }
    /// The column in the row v drew, and the pair's sample (the batch's last step too).
    Sample finish(const Distribution1D::Sample& v, float u1) const {
        const Distribution1D::Sample u = m_rows[static_cast<std::size_t>(v.cell)].sample(u1);
        return {{u.x, v.x}, u.pdf * v.pdf};
    }
    /// The same for n pairs (u1[i], u2[i]) into out[i]: every pair's row first, then every
    /// pair's column, so the pairs' table reads (each a likely cache miss on a large map) wait
    /// together rather than one after another. Each out[i] is sample(u1[i], u2[i]).
    void sample(const float* u1, const float* u2, int n, Sample* out) const;
    float pdf(float u, float v) const;

    // Its rows share one allocation: copies would share it, so it is moved, not copied.
    Distribution2D(const Distribution2D&) = delete;
    Distribution2D& operator=(const Distribution2D&) = delete;
    Distribution2D(Distribution2D&&) noexcept = default;
    Distribution2D& operator=(Distribution2D&&) noexcept = default;

  private:
    // Every row's tables, one after another, in one allocation (on 2 MB pages from 2 MB on: a
    // 2048x1024 map's are 18 MB, read at random by every sample).
    struct FreeTables {
        void operator()(std::byte* p) const noexcept;
    };
    std::unique_ptr<std::byte[], FreeTables> m_tables;
    std::vector<Distribution1D> m_rows;
    Distribution1D m_marginal;
};

/// A lat-long environment map in the light's frame (z up): direction (theta, phi) in the light's
/// frame shows the image at (phi / 2 pi, theta / pi), measured from the file's top-left corner.
class EnvironmentMap {
  public:
    /// `image` is stored as load_texture() returns it (row 0 is the file's bottom row);
    /// `light_from_world` is the light's transform's inverse (3x3, row-major).
    EnvironmentMap(std::shared_ptr<const texture::FilteredTexture> image,
                   const std::array<float, 9>& light_from_world);

    /// Radiance the map shows along world direction `dir`: bilinear at full resolution (pbrt-v3's
    /// lookup without a width), or, given the direction's screen derivatives dD/dx and dD/dy (a
    /// ray differential), filtered over their image in the map by `filter`.
    Rgb radiance(const Vec3& dir, const Vec3* dddx = nullptr, const Vec3* dddy = nullptr) const;
    /// The filter for lookups with a footprint (default EWA, pbrt-v3's imagemap default).
    void set_filter(const texture::FilterOptions& filter) { m_filter = filter; }
    struct Sample {
        Rgb radiance;
        Vec3 wi;        // the world direction towards the map
        float pdf = 0;  // with respect to solid angle (0: nothing sampled)
    };
    /// Samples a world direction towards the map by its luminance.
    Sample sample(float u1, float u2) const;
    /// The same for n pairs (Distribution2D's batch): out[i] is sample(u1[i], u2[i]).
    void sample(const float* u1, const float* u2, int n, Sample* out) const;
    /// Density sample() gives the world direction `dir`, with respect to solid angle.
    float pdf(const Vec3& dir) const;
    const texture::FilteredTexture& image() const { return *m_image; }

  private:
    std::shared_ptr<const texture::FilteredTexture> m_image;
    std::array<float, 9> m_light_from_world, m_world_from_light;
    Distribution2D m_dist;
    texture::FilterOptions m_filter{texture::FilterKind::Ewa};
    Rgb at(float s, float theta_over_pi) const;
    Sample direction_of(const Distribution2D::Sample& d, const Rgb& radiance) const;
};

/// The image of pbrt-v3's goniometric or projection light: a point light whose intensity in
/// direction w (away from the light) is multiplied by the image (bilinear at full resolution, as
/// pbrt-v3 looks it up).
struct LightImage {
    enum class Kind { Goniometric, Projection };
    Kind kind = Kind::Goniometric;
    std::shared_ptr<const texture::FilteredTexture> image;  // as load_texture() returns it
    std::array<float, 9> light_from_world{1, 0, 0, 0, 1, 0, 0, 0, 1};
    // Projection: tan(fov / 2) and the screen window [x0, x1] x [y0, y1] (the image's aspect).
    float tan_half_fov = 1;
    float screen[4] = {-1, 1, -1, 1};

    /// Goniometric: the image in lat-long about the light's y axis (pbrt-v3 swaps y and z, then
    /// u = phi / 2 pi, v = theta / pi from the file's top). Projection: the image on the
    /// light's screen, a pinhole looking along +z; black outside it and behind the light.
    Rgb scale(const Vec3& w) const;
};

}  // namespace cmam::render
