// cmam::texture — one entry point for every filter: a texture plus a footprint in, a value out.
// Owns the level-0 image and builds the MIP pyramid and the summed-area table on first use.
#pragma once

#include <cmam/texture/area.h>
#include <cmam/texture/ewa.h>
#include <cmam/texture/footprint.h>
#include <cmam/texture/mip.h>
#include <cmam/texture/names.h>
#include <cmam/texture/sat.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cmam::texture {

/// The filters. `Area` is the exact mean over the footprint's own region (area.h); the others
/// approximate that region: trilinear by a square, the SAT by its bounding box, EWA by a
/// Gaussian ellipse.
enum class FilterKind : uint8_t { Nearest, Bilinear, Trilinear, Sat, Ewa, Area };
inline constexpr int kFilterKinds = 6;

/// The filters' names: "nearest", "bilinear", "trilinear", "sat", "ewa", "area".
inline constexpr NameTable kFilterNames{Named<FilterKind>{FilterKind::Nearest, "nearest"},
                                        Named{FilterKind::Bilinear, "bilinear"},
                                        Named{FilterKind::Trilinear, "trilinear"},
                                        Named{FilterKind::Sat, "sat"},
                                        Named{FilterKind::Ewa, "ewa"},
                                        Named{FilterKind::Area, "area"}};
static_assert(kFilterNames.entries.size() == kFilterKinds);

/// kFilterNames.parse; nullopt for an unknown name.
std::optional<FilterKind> parse_filter(std::string_view name);
std::string_view to_string(FilterKind kind);
/// Every filter's name, for messages: "nearest, bilinear, trilinear, sat, ewa or area", each
/// between `quote` characters if given.
std::string filter_names(std::string_view quote = "");

struct FilterOptions {
    FilterKind kind = FilterKind::Ewa;
    double max_aniso = 8;
    /// Trilinear footprint width: the longer axis's Euclidean length in texels (GL style,
    /// algorithms.md §2.2), or pbrt-v3's largest absolute component of the two axes, measured in
    /// texels of the larger image dimension (what pbrt-v3 does after its PR #275).
    bool pbrt_trilinear_width = false;
    /// How a `Points` footprint's region is read (the CMAM's options, algorithms.md §6.2).
    CmamEllipse ellipse = CmamEllipse::Conjugate;
    CmamSatBox sat_box = CmamSatBox::Spanned;
};

/// What a lookup did (for `cmam lookup`, statistics and tests).
struct LookupInfo {
    double lambda = 0;  // fractional MIP level (0 for level-0 filters; area: the level used)
    int level_lo = 0, level_hi = 0;
    int texels_read = 0;
    bool fallback = false;  // non-finite input: the texture mean was returned
    // The region filtered, in level-0 texels: a rectangle (SAT), ellipse semi-axes (EWA),
    // parallelogram sides (area; 0 for a CMAM triangle) or the footprint width (trilinear).
    Box2d rect;
    double major = 0, minor = 0, width = 0;
    double area = 0;  // area: the region's area in level-0 texels^2
};

/// A filtered value and what the lookup did.
struct LookupResult {
    Texel value{};
    LookupInfo info;
};

class FilteredTexture {
  public:
    explicit FilteredTexture(Image level0);

    const Image& image() const { return m_image; }
    /// Built on first use (thread-safe).
    const MipPyramid& pyramid() const {
        if (MipPyramid* p = m_pyr_ready.load(std::memory_order_acquire)) return *p;
        return build_pyramid();
    }
    const SummedAreaTable& sat() const;
    /// Summed-area table of MIP level `l` (level 0 is sat()); built on first use.
    const SummedAreaTable& level_sat(int l) const;
    /// Row prefix table of MIP level `l` for the area filter: made on first use, its rows built
    /// as regions first read them (a table of at most RowPrefixTable::kMarginMaxSize texels a
    /// side that repeats both ways is built whole).
    const RowPrefixTable& row_prefix(int l) const;
    /// Bytes of the row prefix tables' rows built so far (part of memory_bytes()).
    std::size_t row_prefix_bytes() const;
    std::size_t memory_bytes() const;  // level 0 + whatever has been built
    bool pyramid_built() const { return m_pyr_ready.load(std::memory_order_acquire) != nullptr; }
    bool sat_built() const { return m_sat_ready.load(std::memory_order_acquire) != nullptr; }

    /// Filtered value at (u,v) (unwrapped uv; v = 0 is the bottom row).
    Texel lookup(double u, double v, const Footprint& fp, const FilterOptions& opts) const;
    /// The same value and what the lookup did. Recording that costs every lookup a little (the
    /// record cleared, a square root and the level's bounds on some paths): lookup() does not.
    LookupResult lookup_with_info(double u, double v, const Footprint& fp,
                                  const FilterOptions& opts) const;

  private:
    Image m_image;
    mutable std::mutex m_build;
    mutable std::atomic<MipPyramid*> m_pyr_ready{nullptr};  // set once the pyramid is complete
    mutable std::atomic<SummedAreaTable*> m_sat_ready{nullptr};
    mutable std::unique_ptr<MipPyramid> m_pyramid;
    mutable std::unique_ptr<SummedAreaTable> m_sat;
    mutable std::vector<std::unique_ptr<SummedAreaTable>> m_level_sats;  // guarded by m_build
    mutable std::unique_ptr<std::atomic<SummedAreaTable*>[]> m_level_ready;
    mutable std::vector<std::unique_ptr<RowPrefixTable>> m_row_prefix;  // guarded by m_build
    mutable std::unique_ptr<std::atomic<RowPrefixTable*>[]> m_row_prefix_ready;

    // The lookup; `info`, when not null, receives what it did.
    Texel lookup_into(double u, double v, const Footprint& fp, const FilterOptions& opts,
                      LookupInfo* info) const;
    Texel lookup_points(double u, double v, const Footprint& fp, const FilterOptions& opts,
                        LookupInfo* info) const;
    const MipPyramid& build_pyramid() const;
    // Trilinear for a footprint `width2` level-0 texels squared wide, and what it read (into
    // `info` when not null).
    Texel trilinear_noted(double u, double v, double width2, LookupInfo* info) const {
        if (!info) return pyramid().trilinear_width2(u, v, width2);
        return trilinear_with_info(u, v, width2, *info);
    }
    Texel trilinear_with_info(double u, double v, double width2, LookupInfo& info) const;
};

}  // namespace cmam::texture
