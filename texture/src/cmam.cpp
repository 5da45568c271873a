#include <cmam/texture/cmam.h>
#include <cmam/texture/filters.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "kernels.h"

namespace cmam::texture {

std::optional<CmamMiss> parse_cmam_miss(std::string_view n) {
    return kCmamMissNames.parse(n);
}
std::optional<CmamEllipse> parse_cmam_ellipse(std::string_view n) {
    return kCmamEllipseNames.parse(n);
}
std::optional<CmamSatMiss> parse_cmam_sat_miss(std::string_view n) {
    return kCmamSatMissNames.parse(n);
}
std::string_view to_string(CmamMiss m) {
    return kCmamMissNames.name(m);
}
std::string_view to_string(CmamEllipse e) {
    return kCmamEllipseNames.name(e);
}
std::string_view to_string(CmamSatMiss m) {
    return kCmamSatMissNames.name(m);
}

double cmam_width(Vec2d p0, const Vec2d* p, int matches) {
    return std::sqrt(cmam_width_squared(p0, p, matches));
}

CmamRegion cmam_region(double s0, double t0, const CmamCache::Entry* cached, int matches,
                       const CmamOptions& o) {
    CmamRegion r;
    r.matches = matches;
    if (matches == 0) return r;
    const Vec2d p0{s0, t0}, p1{cached[0].s, cached[0].t};
    // Vectors from the current sample to the matching cached ones.
    const Vec2d v1 = p1 - p0;
    Vec2d v2;
    // Bounding box of the samples.
    Box2d box{{std::min(s0, p1.u), std::min(t0, p1.v)}, {std::max(s0, p1.u), std::max(t0, p1.v)}};
    if (matches == 2) {
        const Vec2d p2{cached[1].s, cached[1].t};
        v2 = p2 - p0;
        box = {{std::min(box.lo.u, p2.u), std::min(box.lo.v, p2.v)},
               {std::max(box.hi.u, p2.u), std::max(box.hi.v, p2.v)}};
    }
    const double len1 = length(v1);
    const Vec2d others[2] = {p1, matches == 2 ? Vec2d{cached[1].s, cached[1].t} : p1};
    r.width = cmam_width(p0, others, matches);  // MIP
    // SAT: the spanned rectangle (or the square alternative for one match).
    if (matches == 1 && o.sat_box == CmamSatBox::Square) {
        const Vec2d half{len1 / 2, len1 / 2};
        r.rect = {p0 - half, p0 + half};
    } else {
        r.rect = box;
    }
    detail::sat_min_extent(r.rect, o.max_aniso);
    // EWA: a circle of radius |v1| (one match), or an ellipse from the two vectors.
    if (matches == 1) {
        r.a = {len1, 0};
        r.b = {0, len1};
        return r;
    }
    const double len2 = length(v2);
    const Vec2d major = len1 >= len2 ? v1 : v2;
    const Vec2d minor = len1 >= len2 ? v2 : v1;
    const double lmaj = std::max(len1, len2), lmin = std::min(len1, len2);
    r.a = major;
    r.b = minor;
    if (lmaj == 0) return r;
    const Vec2d unit = major / lmaj;
    const double span = std::abs(cross(major, minor));
    const double sin_theta = lmin > 0 ? span / (lmaj * lmin) : 0;
    r.triangle_area = span / 2;
    r.nearly_collinear = sin_theta < 0.2;
    CmamEllipse reading = o.ellipse;
    if (r.nearly_collinear) {  // nearly collinear: the conjugate ellipse would be a sliver
        reading = CmamEllipse::Orthogonal;
        r.orthogonal_fallback = o.ellipse != CmamEllipse::Orthogonal;
    }
    if (reading == CmamEllipse::Orthogonal)  // R2: minor axis perpendicular, length |b|
        r.b = {-unit.v * lmin, unit.u * lmin};
    else if (reading == CmamEllipse::Orthogonalised)  // R3: b minus its component along a
        r.b = minor - dot(minor, unit) * unit;
    return r;
}

namespace {

// round(x) == x, without the library call: x is a whole number (or infinite). Below 2^52 a
// truncation to an integer and back gives x exactly when x is whole; from there on every finite
// double is whole.
bool is_whole(double x) {
    if (std::abs(x) < 0x1p52) return double(static_cast<int64_t>(x)) == x;
    return !std::isnan(x);
}

// std::floor(x), without the library call where x is below 2^52 (from there on x is whole).
double floor_of(double x) {
    return std::abs(x) < 0x1p52 ? double(floor_to_int(x)) : std::floor(x);
}

// cmam_region_2d; with `full` false only what the filters read of it (the matches, the axes a
// and b, the offset to the stratum's centre, used_above), not the MIP width and the SAT box,
// whose square roots and divisions the renderer's lookups do not need (the dispatcher builds
// its own from the axes).
CmamRegion region_2d(double s0, double t0, const CmamCache::Entry* left,
                     const CmamCache::Entry& above, const CmamOptions& o, const RayTag& cur,
                     const CmamCache::Entry* above_left, const CmamCache::Entry* above_right,
                     bool full) {
    CmamRegion r;
    r.used_above = true;
    Vec2d p0{s0, t0};
    Vec2d b = Vec2d{above.s, above.t} - p0;
    Vec2d a;
    if (left) {
        a = Vec2d{left->s, left->t} - p0;
        r.matches = 1;
    } else {  // no left neighbour: a circle whose radius is the step to the sample above
        a = {b.v, -b.u};
    }
    auto positioned = [](const CmamCache::Entry* e) { return e && e->tag.positioned; };
    if (left && cur.positioned && left->tag.positioned && above.tag.positioned) {
        // J, whose columns are the steps of one stratum across and down, from the neighbours'
        // vectors p_i - p0 and image-plane offsets d_i (strata); false when they are too nearly
        // in line to give one (the plain vectors are kept).
        Vec2d jx, jy;
        bool solved;
        // Samples on a regular grid (no jitter): the left and above neighbours are exactly one
        // stratum away, and the two-neighbour solve is the plain backward difference.
        auto on_grid = [&](const CmamCache::Entry& e) {
            const double dx = e.tag.x - cur.x, dy = e.tag.y - cur.y;
            return is_whole(dx) && is_whole(dy);
        };
        if ((positioned(above_left) || positioned(above_right)) &&
            !(on_grid(*left) && on_grid(above))) {
            // Jittered samples, three or four neighbours: J minimises the sum over them of
            // |p_i - p0 - J d_i|^2, i.e. J = (sum (p_i - p0) d_i^T) (sum d_i d_i^T)^-1. (With
            // two, a jittered neighbour nearly in line with the current sample makes the solve
            // ill-conditioned.) A Gram determinant under 1/16 (two neighbours' |det| under 1/4)
            // gives none.
            double g00 = 0, g01 = 0, g11 = 0;
            Vec2d mx{}, my{};
            auto add = [&](const CmamCache::Entry& e) {
                const Vec2d d{e.tag.x - cur.x, e.tag.y - cur.y}, p = Vec2d{e.s, e.t} - p0;
                g00 += d.u * d.u;
                g01 += d.u * d.v;
                g11 += d.v * d.v;
                mx = mx + d.u * p;
                my = my + d.v * p;
            };
            add(*left);
            add(above);
            if (positioned(above_left)) add(*above_left);
            if (positioned(above_right)) add(*above_right);
            const double det = g00 * g11 - g01 * g01;
            solved = det >= 1.0 / 16;
            if (solved) {
                jx = (g11 * mx - g01 * my) / det;
                jy = (g00 * my - g01 * mx) / det;
            }
        } else {
            // [a b] = J [dl da]: J = [a b] [dl da]^-1. Nearly coincident samples (|det| < 1/4)
            // give none.
            const Vec2d dl{left->tag.x - cur.x, left->tag.y - cur.y};
            const Vec2d da{above.tag.x - cur.x, above.tag.y - cur.y};
            const double det = cross(dl, da);
            solved = std::abs(det) >= 0.25;
            if (solved) {
                // inverse of [dl da] = [[da.v -da.u] [-dl.v dl.u]] / det
                jx = (da.v * a - dl.v * b) / det;
                jy = (dl.u * b - da.u * a) / det;
            }
        }
        if (solved) {  // the axes are J's columns, the centre the stratum's
            const Vec2d c{floor_of(cur.x) + 0.5 - cur.x, floor_of(cur.y) + 0.5 - cur.y};
            r.offset = c.u * jx + c.v * jy;
            a = jx;
            b = jy;
            p0 = p0 + r.offset;
        }
    }
    // EWA: the Jacobian columns are conjugate semi-diameters (algorithms.md §4.1).
    r.a = a;
    r.b = b;
    if (!full) return r;
    r.width = std::max(length(a), length(b));  // GL-style: the longer Jacobian column
    // SAT: the box around the pixel's parallelogram p0 +- (a +- b) / 2.
    const Vec2d half{0.5 * (std::abs(a.u) + std::abs(b.u)), 0.5 * (std::abs(a.v) + std::abs(b.v))};
    r.rect = {p0 - half, p0 + half};
    detail::sat_min_extent(r.rect, o.max_aniso);
    return r;
}

}  // namespace

CmamRegion cmam_region_2d(double s0, double t0, const CmamCache::Entry* left,
                          const CmamCache::Entry& above, const CmamOptions& o, const RayTag& cur,
                          const CmamCache::Entry* above_left, const CmamCache::Entry* above_right) {
    return region_2d(s0, t0, left, above, o, cur, above_left, above_right, true);
}

namespace {

// What one sample's step through the cache found: how many of the cached samples (as they were
// before the step, which the caller copies) match, and with the 2-D CMAM the samples above it
// in the row buffer, which the cache keeps until the next row.
struct CacheStep {
    int matches = 0;
    const CmamCache::Entry* above = nullptr;
    const CmamCache::Entry *above_left = nullptr, *above_right = nullptr;
    bool in_range = false;
};

// Matches the sample at (s0, t0) (texture coordinate (u, v)) against the cache and enters it:
// the paper's matching and cache update (§3.1), and the 2-D CMAM's row buffer.
[[gnu::always_inline]] inline CacheStep advance(CmamCache& cache, const RayTag& tag, double s0,
                                                double t0, double u, double v,
                                                const CmamOptions& o) {
    // Matching (paper §3.1): the most recent sample, then both.
    int matches = 0;
    auto same = [&](const CmamCache::Entry& e, uint32_t steps_back) {
        return e.valid && e.tag.id == tag.id && e.tag.level == tag.level &&
               e.tag.patch == tag.patch && (!o.adjacent_only || e.tag.seq + steps_back == tag.seq);
    };
    if (same(cache.last, 1)) matches = same(cache.second_last, 2) ? 2 : 1;
    // Positions beyond 2^30 texels (or not numbers) get the mean, as in every filter; they are
    // not cached, so every region's samples lie within that range.
    const bool in_range =
        std::abs(s0) < detail::kMaxTexelCoord && std::abs(t0) < detail::kMaxTexelCoord;
    CacheStep st{matches, nullptr, nullptr, nullptr, in_range};
    // Shift the cache: the most recent becomes the second, the current the most recent.
    cache.second_last = cache.last;
    cache.last = {tag, s0, t0, in_range, u, v};
    // 2-D CMAM: the row buffer gives the sample above (same sequence number, previous ID).
    if (o.two_d) {
        if (!cache.row_valid || tag.id != cache.row_id) {
            if (cache.row_valid && tag.id == cache.row_id + 1) {
                std::swap(cache.row_previous, cache.row_current);
                cache.row_previous_first = cache.row_current_first;
            } else {
                cache.row_previous.clear();
            }
            cache.row_current.clear();
            cache.row_current_first = tag.seq;
            cache.row_id = tag.id;
            cache.row_valid = true;
        }
        // The row above's samples on either side of it too (the Jacobian's fit).
        auto previous = [&](int64_t seq) -> const CmamCache::Entry* {
            const int64_t i = seq - int64_t(cache.row_previous_first);
            if (i < 0 || i >= int64_t(cache.row_previous.size())) return nullptr;
            const CmamCache::Entry& e = cache.row_previous[std::size_t(i)];
            return e.valid && e.tag.level == tag.level && e.tag.patch == tag.patch ? &e : nullptr;
        };
        st.above = previous(tag.seq);
        if (st.above) {
            st.above_left = tag.seq > 0 ? previous(int64_t(tag.seq) - 1) : nullptr;
            st.above_right = previous(int64_t(tag.seq) + 1);
        }
        // A sample left of the row's first so far (not in a left-to-right scan): the buffer
        // grows to the left.
        if (tag.seq < cache.row_current_first) {
            cache.row_current.insert(cache.row_current.begin(), cache.row_current_first - tag.seq,
                                     CmamCache::Entry{});
            cache.row_current_first = tag.seq;
        }
        const std::size_t i = tag.seq - cache.row_current_first;
        if (i >= cache.row_current.size()) cache.row_current.resize(i + 1);
        cache.row_current[i] = cache.last;
    }
    return st;
}

// Whether the options make u (v) periodic with a usable period.
bool moves_u(const CmamOptions& o) {
    return o.periodic_u && o.period_u > 0 && std::isfinite(o.period_u);
}
bool moves_v(const CmamOptions& o) {
    return o.periodic_v && o.period_v > 0 && std::isfinite(o.period_v);
}
// Moves the texture coordinate `p` by whole periods along the periodic coordinates to the copy
// nearest the sample at (u, v). (A period of 1 moves it by round(u - p.u), exactly: the division
// and product by 1 are exact.)
Vec2d nearest_period(Vec2d p, double u, double v, const CmamOptions& o) {
    if (moves_u(o)) p.u += std::round((u - p.u) / o.period_u) * o.period_u;
    if (moves_v(o)) p.v += std::round((v - p.v) / o.period_v) * o.period_v;
    return p;
}
// The same for a cached entry: s and t follow, at `kw` and `kh` texels per unit of u and v.
void nearest_period(CmamCache::Entry& e, double u, double v, double kw, double kh,
                    const CmamOptions& o) {
    const Vec2d p = nearest_period(Vec2d{e.u, e.v}, u, v, o);
    if (moves_u(o)) e.s = (e.u = p.u) * kw;
    if (moves_v(o)) e.t = (e.v = p.v) * kh;
}

// The sample's neighbours taken the short way round periodic coordinates: the cached samples in
// place, and copies of the row above's (`above`, `left`, `right` then point at the copies).
struct NearestNeighbours {
    CmamCache::Entry above, left, right;
};
void take_short_way(CmamCache::Entry (&cached)[2], const CmamCache::Entry*& above,
                    const CmamCache::Entry*& left, const CmamCache::Entry*& right,
                    std::optional<NearestNeighbours>& copies, double u, double v, double kw,
                    double kh, const CmamOptions& o) {
    for (CmamCache::Entry& e : cached) nearest_period(e, u, v, kw, kh, o);
    if (!above) return;
    copies.emplace();
    auto move = [&](const CmamCache::Entry*& p, CmamCache::Entry& copy) {
        if (!p) return;
        copy = *p;
        nearest_period(copy, u, v, kw, kh, o);
        p = &copy;
    };
    move(above, copies->above);
    move(left, copies->left);
    move(right, copies->right);
}

// A sample beyond 2^30 texels (or not a number): the texture's mean, as in every filter.
Texel out_of_range(const Image& img, LookupInfo* info) {
    if (info) {
        info->fallback = true;
        info->texels_read = 1;
    }
    return img.mean();
}

// What a sample that matches no cached sample gets (paper §3.2.1 item 1).
Texel miss_value(const FilteredTexture& tex, double u, double v, double s0, double t0,
                 const CmamOptions& o, LookupInfo* info) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    if (o.filter == FilterKind::Sat && o.sat_miss == CmamSatMiss::PaperLiteral) {
        // The region from the table's origin to the texture coordinate (in the base tile).
        double s = s0 - std::floor(s0 / W) * W, t = t0 - std::floor(t0 / H) * H;
        if (info) {
            info->texels_read = 16;
            info->rect = {{0, 0}, {s, t}};
        }
        return tex.sat().average(0, 0, std::max(s, 1e-6), std::max(t, 1e-6));
    }
    if (o.miss == CmamMiss::Average) {  // d = MAXLEVEL: the texture's average
        if (info) {
            info->texels_read = 1;
            info->lambda = tex.pyramid().levels() - 1;
            info->level_lo = info->level_hi = tex.pyramid().levels() - 1;
        }
        return img.mean();
    }
    if (info) info->texels_read = 4;  // d = 0: point sample
    return bilinear(img, u, v);
}

// The 1-D CMAM's footprint: the current sample and its matching cached ones (the dispatcher
// builds their region with cmam_region()).
Footprint points_footprint(double u, double v, const Vec2d* cached_uv, int matches) {
    Footprint fp;
    fp.kind = Footprint::Kind::Points;
    fp.point_count = 1 + std::min(matches, 2);
    fp.points[0] = {u, v};
    for (int k = 0; k + 1 < fp.point_count; ++k)
        fp.points[k + 1] = cached_uv[k];  // s = u W exactly as cached
    return fp;
}

// One route into the filters: the 2-D CMAM's left and above neighbours are the Jacobian columns
// (an Axes footprint); the 1-D CMAM hands over its matching samples (a Points footprint).
Texel filter(const FilteredTexture& tex, double u, double v, const Footprint& fp,
             const CmamOptions& o, LookupInfo* info) {
    FilterOptions fo;
    fo.kind = o.filter;
    fo.max_aniso = o.max_aniso;
    fo.ellipse = o.ellipse;
    fo.sat_box = o.sat_box;
    if (!info) return tex.lookup(u, v, fp, fo);
    const LookupResult filtered = tex.lookup_with_info(u, v, fp, fo);
    *info = filtered.info;
    return filtered.value;
}

// The 2-D CMAM's region filtered: its Jacobian columns (level-0 texels) as an Axes footprint,
// on the stratum's centre (positioned tags; otherwise the offset is zero).
Texel filter_2d(const FilteredTexture& tex, double u, double v, const CmamRegion& r,
                const CmamOptions& o, LookupInfo* info) {
    const double W = tex.image().width(), H = tex.image().height();
    const Footprint fp = Footprint::axes({r.a.u / W, r.a.v / H}, {r.b.u / W, r.b.v / H});
    return filter(tex, u + r.offset.u / W, v + r.offset.v / H, fp, o, info);
}

// The lookup; `info` and `region_out`, when not null, receive what the filter did and the region.
Texel lookup_into(const FilteredTexture& tex, CmamCache& cache, const RayTag& tag, double u,
                  double v, const CmamOptions& o, LookupInfo* info, CmamRegion* region_out) {
    const Image& img = tex.image();
    const double W = img.width(), H = img.height();
    const double s0 = u * W, t0 = v * H;
    // The cached samples before the step. Their texture coordinates are read from the cache
    // itself (read from the copies, a 16-byte read of u and v spans two of their stores and
    // waits for both).
    CmamCache::Entry cached[2] = {cache.last, cache.second_last};
    Vec2d cached_uv[2] = {{cache.last.u, cache.last.v}, {cache.second_last.u, cache.second_last.v}};
    const CacheStep st = advance(cache, tag, s0, t0, u, v, o);
    int matches = st.matches;
    const CmamCache::Entry *above = st.above, *above_left = st.above_left,
                           *above_right = st.above_right;
    std::optional<NearestNeighbours> near_copies;
    if (o.periodic_u || o.periodic_v) {
        take_short_way(cached, above, above_left, above_right, near_copies, u, v, W, H, o);
        for (int k = 0; k < 2; ++k) cached_uv[k] = {cached[k].u, cached[k].v};
    }
    const bool in_range = st.in_range;

    if (info) *info = LookupInfo{};
    if (!in_range) return out_of_range(img, info);
    // The region: the 2-D CMAM's Jacobian columns; the 1-D region only where the hull weighting
    // or the caller needs it here (the dispatcher builds it from the Points footprint anyway).
    // (Built only where it is read: a CmamRegion is large enough that clearing it shows.)
    std::optional<CmamRegion> region;
    if (above)
        region = region_2d(s0, t0, matches > 0 ? &cached[0] : nullptr, *above, o, tag, above_left,
                           above_right, region_out != nullptr);
    else if (o.hull || region_out)
        region = cmam_region(s0, t0, cached, matches, o);
    if (above) matches = std::max(matches, 1);  // a region exists: no miss
    if (o.hull && matches == 2 && !above) {
        // Paper §4: integrate only the part of the new triangle outside the hull so far.
        if (!cache.hull_valid || cache.hull_tag.id != tag.id || cache.hull_tag.level != tag.level ||
            cache.hull_tag.patch != tag.patch) {
            cache.hull.clear();
            cache.hull_tag = tag;
            cache.hull_valid = true;
            std::fill(std::begin(cache.hull_integral), std::end(cache.hull_integral), 0.0);
            cache.hull_area = 0;
        }
        Polygon tri = {{s0, t0}, {cached[0].s, cached[0].t}, {cached[1].s, cached[1].t}};
        if (std::abs(signed_area(tri)) > 1e-9) {
            // Integrate exactly at level 0 while the triangle's perimeter is short; longer
            // ones go to the coarsest level where it stays under kMaxPerimeter texels (the
            // box-filtered level makes that an approximation at the coarse cells' scale).
            constexpr double kMaxPerimeter = 32;
            double perimeter = 0;
            for (int k = 0; k < 3; ++k)
                perimeter +=
                    std::hypot(tri[(k + 1) % 3].u - tri[k].u, tri[(k + 1) % 3].v - tri[k].v);
            const int L = tex.pyramid().levels();
            const int want = perimeter > kMaxPerimeter
                                 ? static_cast<int>(std::ceil(std::log2(perimeter / kMaxPerimeter)))
                                 : 0;
            const int level = std::min(L - 1, want);
            const Image& lev = level > 0 ? tex.pyramid().level(level) : img;
            const double kx = lev.width() / W, ky = lev.height() / H;
            double new_area = 0, integral[4] = {0, 0, 0, 0};
            for (Polygon piece : difference(tri, cache.hull)) {
                const double area = std::abs(signed_area(piece));
                new_area += area;
                if (want > L - 1) {  // far wider than the texture even at its coarsest level:
                    for (int c = 0; c < 4; ++c) integral[c] += img.mean()[c] * area;  // the mean
                    continue;  // (integrating would cost the perimeter in texels there)
                }
                for (Vec2d& p : piece) p = {p.u * kx, p.v * ky};
                Texel t = polygon_integral(tex.level_sat(level), piece);
                for (int c = 0; c < 4; ++c) integral[c] += t[c] / (kx * ky);
            }
            region->hull_new_area = new_area;
            if (region_out) *region_out = *region;
            if (info) info->texels_read = 16;
            Texel out{};
            if (new_area > 1e-9) {
                std::vector<Vec2d> pts = cache.hull;
                pts.insert(pts.end(), tri.begin(), tri.end());
                cache.hull = convex_hull(std::move(pts));
                for (int c = 0; c < 4; ++c) {
                    cache.hull_integral[c] += integral[c];
                    out[c] = static_cast<float>(integral[c] / new_area);
                }
                cache.hull_area += new_area;
                return out;
            }
            if (cache.hull_area > 0) {  // nothing new: the DC value, read as the running mean
                for (int c = 0; c < 4; ++c)
                    out[c] = static_cast<float>(cache.hull_integral[c] / cache.hull_area);
                return out;
            }
        }
    }
    if (region_out) *region_out = *region;
    if (matches == 0) return miss_value(tex, u, v, s0, t0, o, info);
    if (!above) return filter(tex, u, v, points_footprint(u, v, cached_uv, matches), o, info);
    return filter_2d(tex, u, v, *region, o, info);
}

// The plain lookup, cmam_lookup's usual case and the renderer's: no hull weighting, no record
// asked for, and with the 2-D CMAM no periodic coordinates. lookup_into's steps for it without
// copying the cached entries: the 1-D footprint reads only their texture coordinates, and after
// the step the cache's second entry is the sample before, the 2-D CMAM's left neighbour; only
// the 2-D region's axes and centre are built. The same values and cache step as lookup_into
// (tests compare the values, and for the 1-D CMAM the caches).
Texel lookup_plain(const FilteredTexture& tex, CmamCache& cache, const RayTag& tag, double u,
                   double v, const CmamOptions& o) {
    const Image& img = tex.image();
    const double s0 = u * img.width(), t0 = v * img.height();
    Vec2d cached_uv[2] = {{cache.last.u, cache.last.v}, {cache.second_last.u, cache.second_last.v}};
    const CacheStep st = advance(cache, tag, s0, t0, u, v, o);
    if (o.periodic_u || o.periodic_v)  // (the 1-D CMAM's only: see cmam_lookup)
        for (Vec2d& p : cached_uv) p = nearest_period(p, u, v, o);
    if (!st.in_range) return out_of_range(img, nullptr);
    if (st.above)
        return filter_2d(tex, u, v,
                         region_2d(s0, t0, st.matches > 0 ? &cache.second_last : nullptr, *st.above,
                                   o, tag, st.above_left, st.above_right, false),
                         o, nullptr);
    if (st.matches == 0) return miss_value(tex, u, v, s0, t0, o, nullptr);
    return filter(tex, u, v, points_footprint(u, v, cached_uv, st.matches), o, nullptr);
}

}  // namespace

Footprint cmam_footprint(CmamCache& cache, const RayTag& tag, double u, double v,
                         const CmamOptions& o, Vec2d* offset) {
    *offset = {};
    CmamCache::Entry cached[2] = {cache.last, cache.second_last};
    const CacheStep st = advance(cache, tag, u, v, u, v, o);
    if (!st.in_range) return Footprint::none();
    const CmamCache::Entry *above = st.above, *above_left = st.above_left,
                           *above_right = st.above_right;
    std::optional<NearestNeighbours> near_copies;
    if (o.periodic_u || o.periodic_v)
        take_short_way(cached, above, above_left, above_right, near_copies, u, v, 1, 1, o);
    if (above) {
        const CmamRegion r = region_2d(u, v, st.matches > 0 ? &cached[0] : nullptr, *above, o, tag,
                                       above_left, above_right, false);
        *offset = r.offset;
        return Footprint::axes(r.a, r.b);
    }
    if (st.matches == 0) return Footprint::none();
    // The 1-D CMAM: the one-match region, a circle of radius |p1 - p0| (the sample step, as a
    // Jacobian column is; the second match, two steps back along the same scanline, would only
    // double its width).
    const CmamRegion r = cmam_region(u, v, cached, 1, o);
    return Footprint::axes(r.a, r.b);
}

Texel cmam_lookup(const FilteredTexture& tex, CmamCache& cache, const RayTag& tag, double u,
                  double v, const CmamOptions& o) {
    // (The 2-D CMAM's periodic neighbours, copies of the row above's moved by whole periods,
    // take the general way.)
    if (!o.hull && !(o.two_d && (o.periodic_u || o.periodic_v)))
        return lookup_plain(tex, cache, tag, u, v, o);
    return lookup_into(tex, cache, tag, u, v, o, nullptr, nullptr);
}

CmamResult cmam_lookup_with_info(const FilteredTexture& tex, CmamCache& cache, const RayTag& tag,
                                 double u, double v, const CmamOptions& o) {
    CmamResult r;
    r.value = lookup_into(tex, cache, tag, u, v, o, &r.info, &r.region);
    return r;
}

}  // namespace cmam::texture
