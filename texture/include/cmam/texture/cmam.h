// cmam::texture — the Convolution Mask Approximation Module (Nimeroff, Badler & Metaxas 1994).
// Sits between the texture and the surface parameterization: the ray tracer hands it a ray tag
// and a texture coordinate, it compares the tag with the last two samples it cached for this
// textured object, approximates the pixel's texture-space region from the samples that match
// (paper §3.2; algorithms.md §6), filters that region with MIP maps, a summed-area table or EWA,
// and returns the value. The tracer otherwise behaves as if it point-sampled. O(1) extra work.
#pragma once

#include <cmam/texture/filter.h>
#include <cmam/texture/polygon.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace cmam::texture {

/// A ray's tag as the CMAM sees it (paper §3.1): the ray ID (scanline or pixel) and the
/// recursion level (0 for primary rays, +1 per specular bounce). `seq` numbers the camera
/// samples of one ID in the order they are traced (algorithms.md §6.3.2), so the CMAM can
/// accept only adjacent samples.
struct RayTag {
    uint32_t id = 0;
    uint32_t level = 0;
    uint32_t seq = 0;
    /// Optional, beyond the paper: the camera sample's position on the image plane in strata
    /// (x across, y down; stratum (i,j) covers [i,i+1)x[j,j+1)). With it the 2-D CMAM turns its
    /// neighbours' differences into the Jacobian exactly, however the samples are jittered, and
    /// centres the footprint on the sample's stratum (algorithms.md §6.3.1).
    bool positioned = false;
    double x = 0, y = 0;
    /// Optional, beyond the paper: which piece of the object's parameterization the sample lies
    /// on (any number the caller chooses: a mesh's (u,v) chart, algorithms.md §6.3). Samples of
    /// different patches are never neighbours: across a (u,v) seam their coordinates jump, and
    /// a region spanning the jump would cover texture the pixel never sees.
    uint32_t patch = 0;
};

/// What a sample that matches no cached sample gets (paper §3.2.1 item 1).
enum class CmamMiss : uint8_t { Average, Point };
/// SAT on a miss: the whole-texture mean, or the paper's literal origin-to-(u,v) rectangle.
enum class CmamSatMiss : uint8_t { Average, PaperLiteral };

inline constexpr NameTable kCmamMissNames{Named<CmamMiss>{CmamMiss::Average, "average"},
                                          Named{CmamMiss::Point, "point"}};
inline constexpr NameTable kCmamEllipseNames{
    Named<CmamEllipse>{CmamEllipse::Conjugate, "conjugate"},
    Named{CmamEllipse::Orthogonal, "orthogonal"},
    Named{CmamEllipse::Orthogonalised, "orthogonalised"}};
inline constexpr NameTable kCmamSatMissNames{Named<CmamSatMiss>{CmamSatMiss::Average, "average"},
                                             Named{CmamSatMiss::PaperLiteral, "paper-literal"}};

std::optional<CmamMiss> parse_cmam_miss(std::string_view);
std::optional<CmamEllipse> parse_cmam_ellipse(std::string_view);
std::optional<CmamSatMiss> parse_cmam_sat_miss(std::string_view);
std::string_view to_string(CmamMiss);
std::string_view to_string(CmamEllipse);
std::string_view to_string(CmamSatMiss);

struct CmamOptions {
    FilterKind filter = FilterKind::Trilinear;  // trilinear (MIP), sat or ewa
    CmamMiss miss = CmamMiss::Average;          // the paper's choice
    CmamEllipse ellipse = CmamEllipse::Conjugate;
    CmamSatMiss sat_miss = CmamSatMiss::Average;
    CmamSatBox sat_box = CmamSatBox::Spanned;
    double max_aniso = 8;
    /// Accept a cached sample only when it is the previous one in the tag's sequence
    /// (algorithms.md §6.3.2). Off is the paper's literal matching on (ID, level), where a
    /// sample behind an occluder still matches and spans the whole gap.
    bool adjacent_only = true;
    /// Convex hull weighting (paper §4; meant for pixel tags): each new triangle is differenced
    /// with the hull of what this ID has filtered so far, and only the new pieces are
    /// integrated, exactly (box-reconstructed texture, algorithms.md §5). A triangle wholly
    /// inside the hull returns the running mean, i.e. it adds nothing.
    bool hull = false;
    /// 2-D CMAM (algorithms.md §6.3.1, beyond the paper): besides the left neighbour, use the
    /// sample of the previous ID (scanline) with the same sequence number, i.e. the pixel above,
    /// so the two vectors approximate the screen-space Jacobian columns d(s,t)/dx and d(s,t)/dy
    /// instead of two nearly collinear steps along the row. Meant for scanline tags.
    bool two_d = false;
    /// Texture coordinates that are angles, u or v of period `period_u` or `period_v` (a
    /// spherical or cylindrical mapping's longitude, period 1; a closed quadric's own u, scaled
    /// by a uv mapping's uscale): each cached neighbour is taken the short way round, whole
    /// periods added to it, so that samples on either side of the seam are neighbours one step
    /// apart rather than a whole texture apart (algorithms.md §6.3).
    bool periodic_u = false, periodic_v = false;
    double period_u = 1, period_v = 1;
};

/// The last two samples of one textured object (the paper's Figure 6 fields): tag and
/// position in level-0 texels, s = u*W, t = v*H, with (u,v) unwrapped.
struct CmamCache {
    struct Entry {
        RayTag tag{};
        double s = 0, t = 0;  // texels (u W, v H)
        bool valid = false;
        double u = 0, v = 0;  // the texture coordinates s and t were made from
    };
    Entry last, second_last;
    // 2-D CMAM: this ID's and the previous ID's samples by sequence number (a row buffer), each
    // from the row's first sample's number on (row_*_first): a strip of the image keeps only its
    // own columns, not every column to its left.
    std::vector<Entry> row_current, row_previous;
    uint32_t row_current_first = 0, row_previous_first = 0;
    uint32_t row_id = 0;
    bool row_valid = false;
    // Convex hull weighting state of the current ID (pixel).
    Polygon hull;
    RayTag hull_tag{};
    bool hull_valid = false;
    double hull_integral[4] = {0, 0, 0, 0}, hull_area = 0;
    void reset() {
        last = second_last = Entry{};
        row_current.clear();
        row_previous.clear();
        row_valid = false;
        hull.clear();
        hull_valid = false;
    }
};

/// The region the paper's rules build for the current sample, in level-0 texels.
struct CmamRegion {
    int matches = 0;                   // 0: no match; 1: the most recent matches; 2: both match
    double width = 0;                  // MIP: segment length (1 match) or bounding-box diagonal (2)
    Box2d rect;                        // SAT: the rectangle (after the minimum-extent rule)
    Vec2d a, b;                        // EWA: the two axis vectors (texels)
    bool orthogonal_fallback = false;  // EWA: sin(theta) < 0.2 switched to the R2 reading
    bool nearly_collinear = false;     // two matches with sin(theta) < 0.2
    double triangle_area = 0;          // two matches: the three samples' triangle (texels^2)
    double hull_new_area = -1;         // hull weighting: area of the new pieces (-1: not used)
    bool used_above = false;           // 2-D CMAM: the sample above took part
    // 2-D CMAM with positioned tags: from the current sample to its stratum's centre (texels),
    // where the footprint is centred; a and b are then the Jacobian columns solved for.
    Vec2d offset;
};

/// The 2-D CMAM's region from the current sample p0, its left neighbour (may be null) and the
/// sample above (level-0 texels): the two vectors as Jacobian columns. When the three tags carry
/// positions (RayTag::positioned), the Jacobian is solved from the vectors and the samples'
/// image-plane offsets (exact for an affine mapping, whatever the jitter) and the region is
/// centred on the current sample's stratum. The row above's samples left and right of the one
/// above (may be null; used when positioned too) make that a least-squares fit over up to four
/// neighbours, which jittered samples nearly in line with the current one do not spoil
/// (algorithms.md §6.3.1, "Positioned tags").
CmamRegion cmam_region_2d(double s0, double t0, const CmamCache::Entry* left,
                          const CmamCache::Entry& above, const CmamOptions& options,
                          const RayTag& current = {}, const CmamCache::Entry* above_left = nullptr,
                          const CmamCache::Entry* above_right = nullptr);

/// CmamRegion::width alone, what the MIP filter reads, for the current sample p0 and the
/// `matches` matching samples p[0..]: the distance to the one, or the diagonal of the three
/// samples' bounding box for two (0 for none).
double cmam_width(Vec2d p0, const Vec2d* p, int matches);
/// Its square (cmam_width() is the square root of exactly this). Inline: the MIP filters read
/// nothing else of the region.
[[gnu::always_inline]] inline double cmam_width_squared(Vec2d p0, const Vec2d* p, int matches) {
    if (matches <= 0) return 0;
    const double du = p[0].u - p0.u, dv = p[0].v - p0.v;
    if (matches == 1) return du * du + dv * dv;
    const double lo_u = std::min(p0.u, std::min(p[0].u, p[1].u)),
                 hi_u = std::max(p0.u, std::max(p[0].u, p[1].u)),
                 lo_v = std::min(p0.v, std::min(p[0].v, p[1].v)),
                 hi_v = std::max(p0.v, std::max(p[0].v, p[1].v));
    return (hi_u - lo_u) * (hi_u - lo_u) + (hi_v - lo_v) * (hi_v - lo_v);
}

/// Region for the current sample p0 and the `matches` cached samples that match it
/// (cached[0] is the most recent). Pure geometry, no texture access.
CmamRegion cmam_region(double s0, double t0, const CmamCache::Entry* cached, int matches,
                       const CmamOptions& options);

/// The paper's module call: filtered value of `texture` at (u,v) for a ray with `tag`, using
/// and then updating `cache` (the cache shifts: most recent becomes second, current becomes
/// most recent).
Texel cmam_lookup(const FilteredTexture& texture, CmamCache& cache, const RayTag& tag, double u,
                  double v, const CmamOptions& options);

/// A CMAM lookup's value, what its filter did and the region it built.
struct CmamResult {
    Texel value{};
    LookupInfo info;
    CmamRegion region;
};
/// cmam_lookup() with what the filter did and the region (the 1-D region is built for it even
/// where the filter does not need it). The value and the cache's update are cmam_lookup()'s.
CmamResult cmam_lookup_with_info(const FilteredTexture& texture, CmamCache& cache,
                                 const RayTag& tag, double u, double v, const CmamOptions& options);

/// The CMAM as a footprint producer for a texture that is not an image (a closed-form
/// checkerboard): the same matching and cache update as cmam_lookup(), with positions in the
/// texture's own (u,v) units, and the region as two axes in those units: the 2-D CMAM's
/// Jacobian columns, or for the 1-D CMAM the circle of radius |p1 - p0| to the most recent
/// match (algorithms.md §6.3.3); none on a miss. `offset` receives the move to the sample's
/// stratum centre (positioned 2-D tags), else zero.
Footprint cmam_footprint(CmamCache& cache, const RayTag& tag, double u, double v,
                         const CmamOptions& options, Vec2d* offset);

/// Convenience object for a ray tracer: one per textured object and worker thread.
class Cmam {
  public:
    Cmam(const FilteredTexture& texture, const CmamOptions& options)
        : m_texture(&texture), m_options(options) {}
    /// A tag and a texture coordinate in, a filtered value out.
    Texel lookup(RayTag tag, double u, double v) {
        return cmam_lookup(*m_texture, m_cache, tag, u, v, m_options);
    }
    void reset() { m_cache.reset(); }

  private:
    const FilteredTexture* m_texture;
    CmamOptions m_options;
    CmamCache m_cache;
};

}  // namespace cmam::texture
