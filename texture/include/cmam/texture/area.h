// cmam::texture — exact area filtering: the mean of the texture over a footprint's own region
// (the pixel's parallelogram c ± a/2 ± b/2, or a CMAM triangle), the quantity a box-filtered
// pixel converges to. algorithms.md §5.2: Green's theorem on per-level row prefix tables turns
// the area integral into a walk along the region's boundary; the level is the coarsest one on
// which the region is still at least kAreaMinWidth texels wide, so the cost is bounded by the
// perimeter there (O(1) per lookup) and the level's box average errs only along the boundary.
#pragma once

#include <cmam/texture/footprint.h>
#include <cmam/texture/image.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace cmam::texture {

class FilteredTexture;

/// Exclusive prefix sums along each row of one image, of (texel - image mean) so that float
/// storage keeps its precision (4 B per channel per entry): D[j][i] = sum_{k<i} (T(k,j) - mean),
/// 0 <= i <= width. The integral of the box-reconstructed texture from s = 0 to s = x along a row
/// is piecewise linear in x between these knots: all Green's theorem needs.
class RowPrefixTable {
  public:
    RowPrefixTable() = default;
    /// The whole table, built now.
    explicit RowPrefixTable(const Image& image);
    /// Rows built on demand, a band of kBandRows at a time, when a region first reads them (by
    /// whichever thread gets there first; the others wait for that band): a render that reads a
    /// few regions of a large texture builds and holds only the bands they cross. `image` must
    /// outlive the table. A table with a margin (below) is small and built now.
    struct OnDemand {};
    RowPrefixTable(const Image& image, OnDemand);
    static constexpr int kBandRows = 16;
    /// A copy is a whole table (the source's rows not built yet are built first).
    RowPrefixTable(const RowPrefixTable& other);
    RowPrefixTable& operator=(const RowPrefixTable& other);
    RowPrefixTable(RowPrefixTable&&) noexcept = default;
    RowPrefixTable& operator=(RowPrefixTable&&) noexcept = default;

    int width() const { return m_w; }
    int height() const { return m_h; }
    int channels() const { return m_c; }
    const Texel& mean() const { return m_mean; }
    /// Memory of the rows built so far.
    std::size_t memory_bytes() const;
    /// Builds every row not built yet (a benchmark's set-up, outside its timing).
    void build_all() const;

    /// Exact integral of the box-reconstructed texture over the convex polygon `v` (n >= 3
    /// vertices in either orientation, texel space of this image: texel (i,j) covers
    /// [i,i+1)x[j,j+1)), with the image's wrap modes (Black: zero outside). The result is the
    /// integral for the counter-clockwise polygon. Cost: O(rows + columns the boundary crosses).
    /// A vertex beyond 2^30 texels or not a number gives the mean times the area.
    Texel integral(const Vec2d* v, int n) const;
    /// The same without the range check: every vertex must lie within 2^30 texels, and
    /// `signed_area2` is twice the polygon's signed area (what the caller has computed already).
    Texel integral_in_range(const Vec2d* v, int n, double signed_area2) const;

    /// Knots beyond D[W] stored at the end of each row, and rows stored after row H - 1, when
    /// the image repeats along both axes and is at most kMarginMaxSize texels wide and high: the
    /// table then continues by periodicity (knot W + i is D[W] + D[i], row H + j is row j), so
    /// that a region that leaves the base period by less than about 32 texels, as every region
    /// the area filter walks does (its perimeter is at most kAreaMaxPerimeter), is walked
    /// without cutting its edges at x = W and y = H. Regions cross those lines often on small
    /// levels only, where the margin's memory is small too (algorithms.md §5.2).
    static constexpr int kMarginKnots = 36, kMarginRows = 34, kMarginMaxSize = 128;

  private:
    int m_w = 0, m_h = 0, m_c = 0;
    WrapMode m_wrap_s{}, m_wrap_t{};
    Texel m_mean{};
    // Knots per stored row (W + 1, or W + 1 + kMarginKnots) and rows stored (H, or
    // H + kMarginRows); edges within [0, m_walk_w) x [0, m_rows] are walked directly.
    int m_row_len = 0, m_rows = 0;
    double m_walk_w = 0;
    // Floats from one stored row to the next: m_row_len * C, padded with zeros to an odd number
    // of 64-byte cache lines. A steep edge reads one knot a row down a column; with a stride near
    // a power of two bytes (a 512-texel grey row is 2,052 bytes) those knots fall in two sets of
    // the first-level cache, eight lines of a 16-row edge in each.
    int m_stride = 0;
    // m_rows rows of m_stride floats, in the image's buffer type: aligned and, when large,
    // on transparent huge pages, since a region's boundary reads one row after another. Mutable:
    // a table built on demand fills its rows as regions first read them.
    mutable TexelBuffer m_d;
    // Built on demand: the image the rows are made from, and each band's state (0 not built,
    // 1 being built, 2 built); null when the whole table was built at once.
    const Image* m_source = nullptr;
    std::unique_ptr<std::atomic<uint8_t>[]> m_bands;
    int m_band_count = 0;

    void build_rows(int j0, int j1) const;
    // Makes sure the rows that a region spanning rows floor(y0)..floor(y1) (before the wrap)
    // reads are built.
    void ensure_rows(double y0, double y1) const;
    void ensure_band(int64_t b) const;
    void build_band(int64_t b) const;

    template <int NC>
    void integrate(const Vec2d* v, int n, double* acc) const;
    template <int NC>
    void edge_inside(Vec2d p, Vec2d q, double sign, double dxdy, double h_per_x, double* acc) const;
    template <int NC>
    void edge_split(Vec2d p, Vec2d q, double sign, double dxdy, double h_per_x, double* acc) const;
    template <int NC>
    void row_piece(int64_t j, double x0, double x1, double h, double h_per_x, double* acc) const;
    template <int NC>
    void knot(const float* row, int64_t k, double* out) const;
    template <int NC>
    void outside_integral(const float* row, double a, double b, double* out) const;
};

/// The level rule (algorithms.md §5.2): integrate on the coarsest MIP level on which the region
/// is still this many texels wide (its area over its longest side)...
inline constexpr double kAreaMinWidth = 2;
/// ...unless its perimeter there exceeds this many texels (very anisotropic regions): then the
/// first coarser level where it does not. Bounds a lookup's cost.
inline constexpr double kAreaMaxPerimeter = 64;

/// Small regions (algorithms.md §5.2): a parallelogram whose longer side is under kAreaBlendLo
/// level-0 texels takes the mean of the bilinear reconstruction over it (exact within one
/// bilinear patch, a Gauss–Legendre product rule otherwise); up to kAreaBlendHi that is blended
/// linearly into the region integral.
inline constexpr double kAreaBlendLo = 5;
inline constexpr double kAreaBlendHi = 5.5;
/// The Gauss rule has 3x3 points up to kAreaRule4Lo texels, 4x4 from kAreaRule4Hi to
/// kAreaRule5Lo and 5x5 from kAreaRule5Hi, blended linearly between.
inline constexpr double kAreaRule4Lo = 2.5;
inline constexpr double kAreaRule4Hi = 2.75;
inline constexpr double kAreaRule5Lo = 3.5;
inline constexpr double kAreaRule5Hi = 3.75;

struct AreaResult {
    Texel value{};
    int level = 0;                // MIP level integrated on
    int knots = 0;                // row-prefix entries read (a cost measure)
    double area = 0;              // the region's area, level-0 texels^2 (after the reconstruction
                                  // term)
    double major = 0, minor = 0;  // parallelogram: side lengths in level-0 texels (after it)
};

/// The region area_parallelogram() integrates, in level-0 texels, and the level it picks.
struct AreaRegion {
    Vec2d corners[4];             // counter-clockwise or clockwise
    double area = 0;              // level-0 texels^2
    double area2 = 0;             // twice the signed area of `corners`
    double perimeter = 0;         // level-0 texels
    double major = 0, minor = 0;  // side lengths, level-0 texels
    int level = 0;
};

/// The parallelogram (u,v) ± a/2 ± b/2 (a, b in uv units: the Jacobian columns, one pixel or
/// stratum step each) with the bilinear reconstruction term: each side lengthened to
/// sqrt(|side|^2 + 1) texels, so that the box integral of the texels over it has the second
/// moments of the bilinear reconstruction's over the original (a region under one texel gives
/// the bilinear value, exactly when axis-aligned; large ones are unchanged). Collinear or zero
/// axes keep the major side with the perpendicular side of the area they span (about 0, then one
/// texel); two zero axes give the axis-aligned unit square.
AreaRegion area_region(const FilteredTexture& texture, double u, double v, Vec2d a, Vec2d b);

/// Mean of the texture over the parallelogram (u,v) ± a/2 ± b/2: area_region() integrated on
/// its level, or for small footprints the mean of the bilinear reconstruction (above).
AreaResult area_parallelogram(const FilteredTexture& texture, double u, double v, Vec2d a, Vec2d b);

/// Mean of the box-reconstructed texture over a convex polygon given in uv units (the CMAM's
/// triangle), on the level the same rule picks for it. Precondition: its area is at least one
/// level-0 texel (smaller regions go to area_parallelogram's reconstruction term).
AreaResult area_polygon(const FilteredTexture& texture, const Vec2d* uv, int n);

/// Regions crossing more lines than this both ways are left to the caller (below).
inline constexpr int kCheckerMaxLines = 1024;

/// The share of the parallelogram c ± a/2 ± b/2 that lies on a checkerboard's odd cells (cell
/// (i,j) is [i,i+1) x [j,j+1), odd where i + j is), exactly: Green's theorem with the
/// checkerboard's row integral in closed form, walking the rows or the columns the region
/// crosses, whichever are fewer (algorithms.md §5.4). A region of no area gives the parity of
/// the cell holding c. Not finite, or crossing more than kCheckerMaxLines lines both ways: -1.
double checker_odd_share(Vec2d c, Vec2d a, Vec2d b);

}  // namespace cmam::texture
