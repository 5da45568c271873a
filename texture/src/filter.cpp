#include <cmam/texture/cmam.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

std::optional<FilterKind> parse_filter(std::string_view n) {
    return kFilterNames.parse(n);
}

std::string_view to_string(FilterKind k) {
    return kFilterNames.name(k);
}

std::string filter_names(std::string_view quote) {
    return kFilterNames.list(quote);
}

FilteredTexture::FilteredTexture(Image level0) : m_image(std::move(level0)) {
    const int levels =
        1 + static_cast<int>(std::floor(std::log2(std::max(m_image.width(), m_image.height()))));
    m_level_sats.resize(static_cast<std::size_t>(levels));
    m_level_ready =
        std::make_unique<std::atomic<SummedAreaTable*>[]>(static_cast<std::size_t>(levels));
    m_row_prefix.resize(static_cast<std::size_t>(levels));
    m_row_prefix_ready =
        std::make_unique<std::atomic<RowPrefixTable*>[]>(static_cast<std::size_t>(levels));
}

const RowPrefixTable& FilteredTexture::row_prefix(int l) const {
    l = std::clamp<int>(l, 0, static_cast<int>(m_row_prefix.size()) - 1);
    if (RowPrefixTable* p = m_row_prefix_ready[l].load(std::memory_order_acquire)) return *p;
    const Image& level = l > 0 ? pyramid().level(l) : m_image;
    std::lock_guard<std::mutex> lock(m_build);
    if (!m_row_prefix[l]) {
        m_row_prefix[l] = std::make_unique<RowPrefixTable>(level, RowPrefixTable::OnDemand{});
        m_row_prefix_ready[l].store(m_row_prefix[l].get(), std::memory_order_release);
    }
    return *m_row_prefix[l];
}

std::size_t FilteredTexture::row_prefix_bytes() const {
    std::size_t n = 0;
    for (std::size_t l = 0; l < m_row_prefix.size(); ++l)
        if (RowPrefixTable* p = m_row_prefix_ready[l].load(std::memory_order_acquire))
            n += p->memory_bytes();
    return n;
}

const SummedAreaTable& FilteredTexture::level_sat(int l) const {
    if (l <= 0) return sat();
    l = std::min<int>(l, static_cast<int>(m_level_sats.size()) - 1);
    if (SummedAreaTable* p = m_level_ready[l].load(std::memory_order_acquire)) return *p;
    const MipPyramid& pyr = pyramid();
    std::lock_guard<std::mutex> lock(m_build);
    if (!m_level_sats[l]) {
        m_level_sats[l] = std::make_unique<SummedAreaTable>(pyr.level(l));
        m_level_ready[l].store(m_level_sats[l].get(), std::memory_order_release);
    }
    return *m_level_sats[l];
}

const MipPyramid& FilteredTexture::build_pyramid() const {
    std::lock_guard<std::mutex> lock(m_build);
    if (!m_pyramid) {
        // Level 0 is the texture's own image, not a copy (m_image outlives m_pyramid).
        m_pyramid = std::make_unique<MipPyramid>(MipPyramid::over(m_image));
        m_pyr_ready.store(m_pyramid.get(), std::memory_order_release);
    }
    return *m_pyramid;
}

const SummedAreaTable& FilteredTexture::sat() const {
    if (SummedAreaTable* p = m_sat_ready.load(std::memory_order_acquire)) return *p;
    std::lock_guard<std::mutex> lock(m_build);
    if (!m_sat) {
        m_sat = std::make_unique<SummedAreaTable>(m_image);
        m_sat_ready.store(m_sat.get(), std::memory_order_release);
    }
    return *m_sat;
}

std::size_t FilteredTexture::memory_bytes() const {
    std::size_t n = m_image.memory_bytes();
    if (pyramid_built()) n += m_pyramid->memory_bytes();  // levels 1 and up
    if (sat_built()) n += m_sat->memory_bytes();
    for (std::size_t l = 1; l < m_level_sats.size(); ++l)
        if (SummedAreaTable* p = m_level_ready[l].load(std::memory_order_acquire))
            n += p->memory_bytes();
    return n + row_prefix_bytes();
}

namespace {
bool finite(const Footprint& fp, double u, double v) {
    if (!std::isfinite(u) || !std::isfinite(v)) return false;
    if (fp.kind == Footprint::Kind::Axes)
        return std::isfinite(fp.axis_a.u) && std::isfinite(fp.axis_a.v) &&
               std::isfinite(fp.axis_b.u) && std::isfinite(fp.axis_b.v);
    for (int i = 0; i < fp.point_count; ++i)
        if (!std::isfinite(fp.points[i].u) || !std::isfinite(fp.points[i].v)) return false;
    return true;
}
}  // namespace

Texel FilteredTexture::lookup(double u, double v, const Footprint& fp,
                              const FilterOptions& opts) const {
    return lookup_into(u, v, fp, opts, nullptr);
}

LookupResult FilteredTexture::lookup_with_info(double u, double v, const Footprint& fp,
                                               const FilterOptions& opts) const {
    LookupResult r;
    r.value = lookup_into(u, v, fp, opts, &r.info);
    return r;
}

Texel FilteredTexture::trilinear_with_info(double u, double v, double width2,
                                           LookupInfo& info) const {
    const MipPyramid& pyr = pyramid();
    double lambda = 0;
    const Texel t = pyr.trilinear_width2(u, v, width2, &lambda);
    info.width = std::sqrt(width2);
    info.lambda = lambda;
    info.level_lo = static_cast<int>(std::floor(lambda));
    info.level_hi = lambda > info.level_lo ? info.level_lo + 1 : info.level_lo;
    // At the coarsest level and beyond, the level's mean: one value read.
    info.texels_read = lambda >= pyr.levels() - 1 ? 1 : (info.level_lo == info.level_hi ? 4 : 8);
    return t;
}

Texel FilteredTexture::lookup_into(double u, double v, const Footprint& fp,
                                   const FilterOptions& opts, LookupInfo* info) const {
    // Written only when the caller asks for it (no scratch copy to clear on the hot paths).
    auto note = [info](int texels_read, bool fallback = false) {
        if (info) {
            info->texels_read = texels_read;
            info->fallback = fallback;
        }
    };
    if (info) *info = LookupInfo{};
    const double W = m_image.width(), H = m_image.height();
    if (!finite(fp, u, v)) {
        note(1, true);
        return m_image.mean();
    }
    if (opts.kind == FilterKind::Nearest) {
        note(1);
        return nearest(m_image, u, v);
    }
    if (fp.kind == Footprint::Kind::None || opts.kind == FilterKind::Bilinear) {
        note(4);
        return bilinear(m_image, u, v);
    }
    if (fp.kind == Footprint::Kind::Points) return lookup_points(u, v, fp, opts, info);
    const Vec2d a = fp.axis_a, b = fp.axis_b;  // the Jacobian columns (uv units)
    switch (opts.kind) {
        case FilterKind::Trilinear: {
            double width2;
            if (opts.pbrt_trilinear_width) {
                double m = std::max({std::abs(a.u), std::abs(a.v), std::abs(b.u), std::abs(b.v)}) *
                           std::max(W, H);
                width2 = m * m;
            } else {
                width2 = std::max(a.u * a.u * W * W + a.v * a.v * H * H,
                                  b.u * b.u * W * W + b.v * b.v * H * H);
            }
            return trilinear_noted(u, v, width2, info);
        }
        case FilterKind::Sat: {
            // The pixel's own parallelogram c +- (a +- b)/2, bounded by its axis-aligned box,
            // at least one texel wide (a unit box is the bilinear value) with the anisotropy
            // clamp (algorithms.md §6.4).
            const Vec2d c{u * W, v * H};
            const Vec2d half{0.5 * (std::abs(a.u) + std::abs(b.u)) * W,
                             0.5 * (std::abs(a.v) + std::abs(b.v)) * H};
            Box2d r{c - half, c + half};
            constexpr double kMax = detail::kMaxTexelCoord;
            if (!(std::max({std::abs(r.lo.u), std::abs(r.lo.v), std::abs(r.hi.u),
                            std::abs(r.hi.v)}) < kMax)) {
                note(1, true);
                return m_image.mean();
            }
            detail::sat_min_extent(r, opts.max_aniso);
            if (info) {
                info->rect = r;
                info->texels_read = 16;
            }
            return sat().average(r.lo.u, r.lo.v, r.hi.u, r.hi.v);
        }
        case FilterKind::Ewa: {
            EwaResult r = ewa(pyramid(), u, v, a.u, a.v, b.u, b.v, opts.max_aniso);
            if (info) {
                info->lambda = r.lambda;
                info->level_lo = static_cast<int>(std::floor(r.lambda));
                info->level_hi = r.lambda > info->level_lo ? info->level_lo + 1 : info->level_lo;
                info->texels_read = r.texels_read;
                info->major = r.major;
                info->minor = r.minor;
            }
            return r.value;
        }
        case FilterKind::Area: {
            AreaResult r = area_parallelogram(*this, u, v, a, b);
            if (info) {
                info->lambda = r.level;
                info->level_lo = info->level_hi = r.level;
                info->texels_read = r.knots;
                info->major = r.major;
                info->minor = r.minor;
                info->area = r.area;
            }
            return r.value;
        }
        default:
            break;
    }
    note(4);
    return bilinear(m_image, u, v);
}

// A Points footprint: the paper's region for the current sample and the CMAM's matching cached
// samples (cmam_region(), the same rules the CMAM applies), then the filter.
Texel FilteredTexture::lookup_points(double u, double v, const Footprint& fp,
                                     const FilterOptions& opts, LookupInfo* info) const {
    const double W = m_image.width(), H = m_image.height();
    const int matches = std::clamp(fp.point_count, 1, 3) - 1;
    if (matches == 0) {  // one point: no region
        if (info) info->texels_read = 4;
        return bilinear(m_image, u, v);
    }
    const double s0 = fp.points[0].u * W, t0 = fp.points[0].v * H;
    if (opts.kind != FilterKind::Sat && opts.kind != FilterKind::Ewa &&
        opts.kind != FilterKind::Area) {  // MIP: the region's width is all it reads
        const Vec2d others[2] = {{fp.points[1].u * W, fp.points[1].v * H},
                                 {fp.points[2].u * W, fp.points[2].v * H}};
        // The width squared: its square root would delay the level (trilinear_width2).
        const double width2 = cmam_width_squared({s0, t0}, others, matches);
        return trilinear_noted(u, v, width2, info);
    }
    CmamCache::Entry cached[2];
    for (int k = 0; k < matches; ++k) {
        cached[k].s = fp.points[k + 1].u * W;
        cached[k].t = fp.points[k + 1].v * H;
        cached[k].valid = true;
    }
    CmamOptions o;
    o.filter = opts.kind;
    o.max_aniso = opts.max_aniso;
    o.ellipse = opts.ellipse;
    o.sat_box = opts.sat_box;
    const CmamRegion r = cmam_region(s0, t0, cached, matches, o);
    LookupInfo scratch;
    LookupInfo& in = info ? *info : scratch;
    switch (opts.kind) {
        case FilterKind::Ewa: {
            EwaResult e =
                ewa(pyramid(), u, v, r.a.u / W, r.a.v / H, r.b.u / W, r.b.v / H, opts.max_aniso);
            in.lambda = e.lambda;
            in.level_lo = static_cast<int>(std::floor(e.lambda));
            in.level_hi = e.lambda > in.level_lo ? in.level_lo + 1 : in.level_lo;
            in.texels_read = e.texels_read;
            in.major = e.major;
            in.minor = e.minor;
            return e.value;
        }
        case FilterKind::Area: {
            // The triangle of three samples where it has area (not nearly collinear, at least a
            // texel); otherwise the parallelogram of the EWA reading's two axes taken as
            // Jacobian columns (one match: the square of side |p1 - p0|).
            AreaResult a;
            if (r.triangle_area >= 1 && !r.nearly_collinear) {
                a = area_polygon(*this, fp.points.data(), 3);
            } else {
                a = area_parallelogram(*this, u, v, {r.a.u / W, r.a.v / H}, {r.b.u / W, r.b.v / H});
                in.major = a.major;
                in.minor = a.minor;
            }
            in.lambda = a.level;
            in.level_lo = in.level_hi = a.level;
            in.texels_read = a.knots;
            in.area = a.area;
            return a.value;
        }
        default:  // Sat, the last of the three
            in.rect = r.rect;
            in.texels_read = 16;
            return sat().average(r.rect.lo.u, r.rect.lo.v, r.rect.hi.u, r.rect.hi.v);
    }
}

}  // namespace cmam::texture
