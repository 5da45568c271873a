#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <cmath>

#include "kernels.h"

namespace cmam::texture {

std::optional<FilterKind> parse_filter(std::string_view n) {
    if (n == "nearest") return FilterKind::Nearest;
    if (n == "bilinear") return FilterKind::Bilinear;
    if (n == "trilinear") return FilterKind::Trilinear;
    if (n == "sat") return FilterKind::Sat;
    if (n == "ewa") return FilterKind::Ewa;
    return std::nullopt;
}

std::string_view to_string(FilterKind k) {
    switch (k) {
        case FilterKind::Nearest:
            return "nearest";
        case FilterKind::Bilinear:
            return "bilinear";
        case FilterKind::Trilinear:
            return "trilinear";
        case FilterKind::Sat:
            return "sat";
        case FilterKind::Ewa:
            return "ewa";
    }
    return "?";
}

FilteredTexture::FilteredTexture(Image level0) : m_image(std::move(level0)) {
    const int levels =
        1 + static_cast<int>(std::floor(std::log2(std::max(m_image.width(), m_image.height()))));
    m_level_sats.resize(static_cast<std::size_t>(levels));
    m_level_ready =
        std::make_unique<std::atomic<SummedAreaTable*>[]>(static_cast<std::size_t>(levels));
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

const MipPyramid& FilteredTexture::pyramid() const {
    if (MipPyramid* p = m_pyr_ready.load(std::memory_order_acquire)) return *p;
    std::lock_guard<std::mutex> lock(m_build);
    if (!m_pyramid) {
        m_pyramid = std::make_unique<MipPyramid>(m_image);
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
    if (pyramid_built()) n += m_pyramid->memory_bytes() - m_image.memory_bytes();
    if (sat_built()) n += m_sat->memory_bytes();
    for (std::size_t l = 1; l < m_level_sats.size(); ++l)
        if (SummedAreaTable* p = m_level_ready[l].load(std::memory_order_acquire))
            n += p->memory_bytes();
    return n;
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
// Bounding box of the footprint's points in level-0 texels: x0, y0, x1, y1.
void points_box(const Footprint& fp, double W, double H, double* r) {
    r[0] = r[2] = fp.points[0].u * W;
    r[1] = r[3] = fp.points[0].v * H;
    for (int i = 1; i < fp.point_count; ++i) {
        r[0] = std::min(r[0], fp.points[i].u * W);
        r[2] = std::max(r[2], fp.points[i].u * W);
        r[1] = std::min(r[1], fp.points[i].v * H);
        r[3] = std::max(r[3], fp.points[i].v * H);
    }
}
}  // namespace

Texel FilteredTexture::lookup(double u, double v, const Footprint& fp, const FilterOptions& opts,
                              LookupInfo* info) const {
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
    // Reduce the footprint to two axis vectors (uv units).
    Vec2d a = fp.axis_a, b = fp.axis_b;
    if (fp.kind ==
        Footprint::Kind::Points) {  // vectors from the current sample (first) to the others
        a = b = Vec2d{};
        if (fp.point_count > 1)
            a = {fp.points[1].u - fp.points[0].u, fp.points[1].v - fp.points[0].v};
        if (fp.point_count > 2)
            b = {fp.points[2].u - fp.points[0].u, fp.points[2].v - fp.points[0].v};
    }
    switch (opts.kind) {
        case FilterKind::Trilinear: {
            double width2;
            if (fp.kind == Footprint::Kind::Axes && opts.pbrt_trilinear_width) {
                double m = std::max({std::abs(a.u), std::abs(a.v), std::abs(b.u), std::abs(b.v)}) *
                           std::max(W, H);
                width2 = m * m;
            } else if (fp.kind == Footprint::Kind::Axes) {
                width2 = std::max(a.u * a.u * W * W + a.v * a.v * H * H,
                                  b.u * b.u * W * W + b.v * b.v * H * H);
            } else {  // diagonal of the points' bounding box
                double rect[4];
                points_box(fp, W, H, rect);
                width2 = (rect[2] - rect[0]) * (rect[2] - rect[0]) +
                         (rect[3] - rect[1]) * (rect[3] - rect[1]);
            }
            const MipPyramid& pyr = pyramid();
            double lambda = 0;
            Texel t;
            if (width2 > 1) {
                // lambda = log2(width^2) / 2, with no square root. With width^2 = m 2^e
                // (1 <= m < 2), lambda = (e + log2 m) / 2 lies in [floor(e/2), floor(e/2) + 1):
                // the level comes from the exponent alone, so the texel reads need not wait
                // for the logarithm; only the blend weight does.
                const int l = detail::floor_log2(width2) >> 1;
                lambda = 0.5 * std::log2(width2);
                t = pyr.trilinear_levels(u, v, l,
                                         static_cast<float>(std::clamp(lambda - l, 0.0, 1.0)));
                lambda = std::min(lambda, double(pyr.levels() - 1));
            } else {
                t = pyr.bilinear(0, u, v);
            }
            if (info) {
                info->width = std::sqrt(width2);
                info->lambda = lambda;
                info->level_lo = static_cast<int>(std::floor(lambda));
                info->level_hi = lambda > info->level_lo ? info->level_lo + 1 : info->level_lo;
                info->texels_read =
                    lambda >= pyr.levels() - 1 ? 1 : (info->level_lo == info->level_hi ? 4 : 8);
            }
            return t;
        }
        case FilterKind::Sat: {
            double r[4];
            if (fp.kind == Footprint::Kind::Axes) {
                // The pixel's own parallelogram c +- (a +- b)/2, bounded by its axis-aligned box.
                double hs = 0.5 * (std::abs(a.u) + std::abs(b.u)) * W,
                       ht = 0.5 * (std::abs(a.v) + std::abs(b.v)) * H;
                r[0] = u * W - hs;
                r[1] = v * H - ht;
                r[2] = u * W + hs;
                r[3] = v * H + ht;
            } else {
                points_box(fp, W, H, r);
            }
            constexpr double kMax = detail::kMaxTexelCoord;
            if (!(std::max({std::abs(r[0]), std::abs(r[1]), std::abs(r[2]), std::abs(r[3])}) <
                  kMax)) {
                note(1, true);
                return m_image.mean();
            }
            if (info) {
                std::copy(r, r + 4, info->rect);
                info->texels_read = 16;
            }
            return sat().average(r[0], r[1], r[2], r[3]);
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
        default:
            break;
    }
    note(4);
    return bilinear(m_image, u, v);
}

}  // namespace cmam::texture
