#include <cmam/texture/filter.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <cmath>

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
        case FilterKind::Nearest: return "nearest";
        case FilterKind::Bilinear: return "bilinear";
        case FilterKind::Trilinear: return "trilinear";
        case FilterKind::Sat: return "sat";
        case FilterKind::Ewa: return "ewa";
    }
    return "?";
}

FilteredTexture::FilteredTexture(Image level0) : m_image(std::move(level0)) {}

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
    return n;
}

namespace {
bool finite(const Footprint& fp, double u, double v) {
    if (!std::isfinite(u) || !std::isfinite(v)) return false;
    if (fp.kind == Footprint::Kind::Axes)
        return std::isfinite(fp.axis_a.u) && std::isfinite(fp.axis_a.v) && std::isfinite(fp.axis_b.u) &&
               std::isfinite(fp.axis_b.v);
    for (int i = 0; i < fp.point_count; ++i)
        if (!std::isfinite(fp.points[i].u) || !std::isfinite(fp.points[i].v)) return false;
    return true;
}
}  // namespace

Texel FilteredTexture::lookup(double u, double v, const Footprint& fp, const FilterOptions& opts,
                              LookupInfo* info) const {
    LookupInfo local;
    LookupInfo& in = info ? *info : local;
    in = LookupInfo{};
    const double W = m_image.width(), H = m_image.height();
    if (!finite(fp, u, v)) {
        in.fallback = true;
        in.texels_read = 1;
        return m_image.mean();
    }
    if (opts.kind == FilterKind::Nearest) {
        in.texels_read = 1;
        return nearest(m_image, u, v);
    }
    if (fp.kind == Footprint::Kind::None || opts.kind == FilterKind::Bilinear) {
        in.texels_read = 4;
        return bilinear(m_image, u, v);
    }
    // Reduce the footprint to two axis vectors (uv units) and, for SAT, a rectangle.
    Vec2d a = fp.axis_a, b = fp.axis_b;
    double rx0, ry0, rx1, ry1;
    if (fp.kind == Footprint::Kind::Axes) {
        // The pixel's own parallelogram c +- (a +- b)/2, bounded by its axis-aligned box.
        double hs = 0.5 * (std::abs(a.u) + std::abs(b.u)) * W, ht = 0.5 * (std::abs(a.v) + std::abs(b.v)) * H;
        rx0 = u * W - hs;
        rx1 = u * W + hs;
        ry0 = v * H - ht;
        ry1 = v * H + ht;
    } else {
        // Points: vectors from the current sample (first) to the others; box of all points.
        a = b = Vec2d{};
        if (fp.point_count > 1) a = {fp.points[1].u - fp.points[0].u, fp.points[1].v - fp.points[0].v};
        if (fp.point_count > 2) b = {fp.points[2].u - fp.points[0].u, fp.points[2].v - fp.points[0].v};
        rx0 = rx1 = fp.points[0].u * W;
        ry0 = ry1 = fp.points[0].v * H;
        for (int i = 1; i < fp.point_count; ++i) {
            rx0 = std::min(rx0, fp.points[i].u * W);
            rx1 = std::max(rx1, fp.points[i].u * W);
            ry0 = std::min(ry0, fp.points[i].v * H);
            ry1 = std::max(ry1, fp.points[i].v * H);
        }
    }
    switch (opts.kind) {
        case FilterKind::Trilinear: {
            double width = fp.kind == Footprint::Kind::Axes
                               ? std::sqrt(std::max(a.u * a.u * W * W + a.v * a.v * H * H, b.u * b.u * W * W + b.v * b.v * H * H))
                               : std::sqrt((rx1 - rx0) * (rx1 - rx0) + (ry1 - ry0) * (ry1 - ry0));  // box diagonal
            in.width = width;
            Texel t = pyramid().trilinear(u, v, width, &in.lambda);
            in.level_lo = static_cast<int>(std::floor(in.lambda));
            in.level_hi = in.lambda > in.level_lo ? in.level_lo + 1 : in.level_lo;
            in.texels_read = in.level_lo == in.level_hi ? 4 : 8;
            if (in.lambda >= pyramid().levels() - 1) in.texels_read = 1;
            return t;
        }
        case FilterKind::Sat: {
            constexpr double kMax = 1073741824.0;  // 2^30 texels: beyond, sums lose all precision
            if (!(std::max({std::abs(rx0), std::abs(rx1), std::abs(ry0), std::abs(ry1)}) < kMax)) {
                in.fallback = true;
                in.texels_read = 1;
                return m_image.mean();
            }
            in.rect[0] = rx0;
            in.rect[1] = ry0;
            in.rect[2] = rx1;
            in.rect[3] = ry1;
            in.texels_read = 16;
            return sat().average(rx0, ry0, rx1, ry1);
        }
        case FilterKind::Ewa: {
            EwaResult r = ewa(pyramid(), u, v, a.u, a.v, b.u, b.v, opts.max_aniso);
            in.lambda = r.lambda;
            in.level_lo = static_cast<int>(std::floor(r.lambda));
            in.level_hi = r.lambda > in.level_lo ? in.level_lo + 1 : in.level_lo;
            in.texels_read = r.texels_read;
            in.major = r.major;
            in.minor = r.minor;
            return r.value;
        }
        default: break;
    }
    in.texels_read = 4;
    return bilinear(m_image, u, v);
}

}  // namespace cmam::texture
