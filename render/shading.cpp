#include "render/shading.h"

#include <cmam/texture/area.h>

#include <limits>

#include "render/noise.h"

namespace cmam::render {

texture::Texel lookup_image(const texture::FilteredTexture& image,
                            const texture::FilterOptions& filter, double s, double t,
                            const texture::Footprint& footprint, LookupCounts* counts) {
    if (!counts) return image.lookup(s, t, footprint, filter);
    if (footprint.kind == texture::Footprint::Kind::None)
        ++counts->point_sampled;
    else
        ++counts->by_filter[static_cast<int>(filter.kind)];
    const texture::LookupResult r = image.lookup_with_info(s, t, footprint, filter);
    counts->non_finite += r.info.fallback;
    return r.value;
}

texture::Footprint node_footprint(const TextureNode& n, const TexContext& ctx) {
    texture::Footprint fp = ctx.footprints.of(n.lod);
    if (fp.kind == texture::Footprint::Kind::Axes) {
        // The area filter integrates a parallelogram: a cone's cross-section (a disc or an
        // ellipse of diameters a, b) becomes the one with equal second moments, sides
        // (sqrt 3 / 2) a and (sqrt 3 / 2) b (algorithms.md §5.2; measured best at 1 spp).
        const bool cone = n.lod == FootprintMethod::Cones || n.lod == FootprintMethod::ConesAniso;
        const double k = cone && n.filter.kind == texture::FilterKind::Area ? kConeToArea : 1.0;
        fp.axis_a = {fp.axis_a.u * n.su * k, fp.axis_a.v * n.sv * k};
        fp.axis_b = {fp.axis_b.u * n.su * k, fp.axis_b.v * n.sv * k};
    }
    return fp;
}

namespace {

Vec3 texture_point(const TextureNode& n, const Vec3& p) {
    const auto& m = n.texture_from_world;
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
            m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}
Vec3 texture_vector(const TextureNode& n, const Vec3& v) {
    const auto& m = n.texture_from_world;
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
}

// (s,t) of world point p under a spherical, cylindrical or planar mapping (pbrt-v3's: planar
// projects the world-space point, the others the texture-space direction from the origin).
texture::Vec2d mapped_st(const TextureNode& n, const Vec3& p) {
    if (n.mapping == TextureNode::Mapping::Planar)
        return {double(n.du) + dot(p, n.v1), double(n.dv) + dot(p, n.v2)};
    const Vec3 q = texture_point(n, p);
    const float len = length(q);
    const Vec3 d = len > 0 ? q / len : Vec3(0, 0, 1);
    if (n.mapping == TextureNode::Mapping::Spherical) {
        float phi = std::atan2(d.y, d.x);
        if (phi < 0) phi += 2 * kPi;
        return {std::acos(std::clamp(d.z, -1.0f, 1.0f)) * kInvPi, phi / (2 * kPi)};
    }
    return {(kPi + std::atan2(d.y, d.x)) / (2 * kPi), d.z};
}

// A 2-D mapping's (s,t) at the hit and the footprint its lookup uses: for uv mapping the
// node's (node_footprint); for the others the images of the world-space footprint the node's
// lod gives, dP/dx and dP/dy or a ray cone's cross-section (exact for planar, finite
// differences for the angular mappings, across their seam the short way), or none without one.
struct MappedSt {
    texture::Vec2d st;
    texture::Footprint footprint;  // None unless asked for
};
// The (s,t) alone.
texture::Vec2d node_st_only(const TextureNode& n, const TexContext& ctx) {
    if (n.mapping == TextureNode::Mapping::Uv)
        return {double(n.su) * ctx.u + n.du, double(n.sv) * ctx.v + n.dv};
    return mapped_st(n, ctx.p);
}
MappedSt node_st(const TextureNode& n, const TexContext& ctx, bool with_footprint) {
    const texture::Vec2d st = node_st_only(n, ctx);
    if (!with_footprint) return {st, {}};
    if (n.mapping == TextureNode::Mapping::Uv) return {st, node_footprint(n, ctx)};
    const HitFootprint& f = ctx.footprints;
    Vec3 dp[2];
    switch (n.lod) {
        case FootprintMethod::Differentials:
            dp[0] = f.dpdx, dp[1] = f.dpdy;
            break;
        case FootprintMethod::Cones:
            dp[0] = f.cone_world[0], dp[1] = f.cone_world[1];
            break;
        case FootprintMethod::ConesAniso:
            dp[0] = f.cone_aniso_world[0], dp[1] = f.cone_aniso_world[1];
            break;
        default:
            return {st, {}};
    }
    if (dot(dp[0], dp[0]) == 0 && dot(dp[1], dp[1]) == 0) return {st, {}};
    // A cone's cross-section integrated by the area filter: the parallelogram of equal second
    // moments, as node_footprint makes it for (u,v).
    if (n.lod != FootprintMethod::Differentials && n.filter.kind == texture::FilterKind::Area) {
        dp[0] = dp[0] * float(kConeToArea);
        dp[1] = dp[1] * float(kConeToArea);
    }
    texture::Vec2d axis[2];
    for (int k = 0; k < 2; ++k) {
        if (n.mapping == TextureNode::Mapping::Planar) {
            axis[k] = {dot(dp[k], n.v1), dot(dp[k], n.v2)};
            continue;
        }
        constexpr float kDelta = 0.01f;
        const texture::Vec2d o = mapped_st(n, ctx.p + kDelta * dp[k]);
        double a[2] = {(o.u - st.u) / kDelta, (o.v - st.v) / kDelta};
        double& angle = a[n.mapping == TextureNode::Mapping::Spherical ? 1 : 0];
        const double period = 1 / kDelta;
        if (angle > period / 2) angle -= period;
        if (angle < -period / 2) angle += period;
        axis[k] = {a[0], a[1]};
    }
    return {st, texture::Footprint::axes(axis[0], axis[1])};
}

}  // namespace

texture::Footprint lookup_footprint(const TextureNode& n, const TexContext& ctx) {
    return node_st(n, ctx, n.lod != FootprintMethod::Cmam).footprint;
}

namespace {

float noise2(float x, float y) {
    return perlin_noise(Vec3(x, y, 0.5f));
}

// pbrt-v3's marble: a sine of height perturbed by fbm, through a Bezier spline of nine greys
// and blues. Its segment index is clamped to at most 1 (pbrt-v3 does so; later segments are
// reached by extrapolating the first two).
Rgb marble(const TextureNode& n, const TexContext& ctx) {
    const Vec3 p = texture_point(n, ctx.p) * n.scale;
    const Vec3 dx = texture_vector(n, ctx.footprints.dpdx) * n.scale,
               dy = texture_vector(n, ctx.footprints.dpdy) * n.scale;
    float t = 0.5f + 0.5f * std::sin(p.y + n.variation * fbm(p, dx, dy, n.omega, n.octaves));
    static const Rgb c[9] = {{.58f, .58f, .6f}, {.58f, .58f, .6f}, {.58f, .58f, .6f},
                             {.5f, .5f, .5f},   {.6f, .59f, .58f}, {.58f, .58f, .6f},
                             {.58f, .58f, .6f}, {.2f, .2f, .33f},  {.58f, .58f, .6f}};
    constexpr int kSegments = 6;
    const int first = std::min(1, static_cast<int>(std::floor(t * kSegments)));
    t = t * kSegments - float(first);
    auto mix = [t](const Rgb& a, const Rgb& b) { return (1 - t) * a + t * b; };
    Rgb s0 = mix(c[first], c[first + 1]), s1 = mix(c[first + 1], c[first + 2]),
        s2 = mix(c[first + 2], c[first + 3]);
    s0 = mix(s0, s1);
    s1 = mix(s1, s2);
    return 1.5f * mix(s0, s1);
}

// The CMAM's options for node `n` at a hit: the scene's, and which of the node's (s,t) are
// angles, whose neighbours across the seam are taken the short way round: the longitude of a
// spherical or cylindrical mapping (period 1), or under the uv mapping the u of a closed
// quadric or the u or v of a mesh found periodic (period 1 in u, |uscale| in s; |vscale| in t).
texture::CmamOptions cmam_options(const Scene& scene, const TextureNode& n, const TexContext& ctx) {
    texture::CmamOptions o = scene.cmam;
    o.periodic_u = n.mapping == TextureNode::Mapping::Cylindrical;
    o.periodic_v = n.mapping == TextureNode::Mapping::Spherical;
    if (n.mapping == TextureNode::Mapping::Uv && ctx.u_periodic && n.su != 0) {
        o.periodic_u = true;
        o.period_u = std::abs(double(n.su));
    }
    if (n.mapping == TextureNode::Mapping::Uv && ctx.v_periodic && n.sv != 0) {
        o.periodic_v = true;
        o.period_v = std::abs(double(n.sv));
    }
    return o;
}

// The CMAM sits between the texture and the parameterization: the ray's tag and (s,t) in, the
// filtered value out; it records what it filtered where the context asks.
texture::Texel cmam_texel(const Scene& scene, const TextureNode& n, int node, double s, double t,
                          const TexContext& ctx) {
    texture::CmamOptions o = cmam_options(scene, n, ctx);
    o.filter = n.filter.kind;
    o.max_aniso = n.filter.max_aniso;
    texture::CmamCache& cache =
        ctx.cmam->cache(ctx.object, static_cast<uint32_t>(node), ctx.footprints.path);
    CmamRecord* rec = ctx.cmam_record && ctx.cmam_record->node == node ? ctx.cmam_record : nullptr;
    if (!rec && !ctx.counts)  // nothing to record: the lookup alone
        return texture::cmam_lookup(*n.image, cache, ctx.footprints.tag, s, t, o);
    const texture::CmamResult r =
        texture::cmam_lookup_with_info(*n.image, cache, ctx.footprints.tag, s, t, o);
    if (rec) {
        rec->info = r.info;
        rec->region = r.region;
        rec->filled = true;
    }
    if (ctx.counts) {
        ++ctx.counts->by_filter[static_cast<int>(o.filter)];
        ctx.counts->non_finite += r.info.fallback;
        ctx.counts->cmam_2d_without_above += o.two_d && !r.region.used_above;
    }
    return r.value;
}

// The area filter's parallelogram on its stratum's centre (algorithms.md §5.2, "Strata"):
// through the differentials, or for cones the camera ray's at the first hit (the offset is zero
// where none was computed). Not for the CMAM, whose regions are centred by its own tags.
void to_stratum_centre(const TextureNode& n, const TexContext& ctx, double& s, double& t) {
    if (n.filter.kind == texture::FilterKind::Area && n.mapping == TextureNode::Mapping::Uv &&
        (n.lod == FootprintMethod::Differentials
             ? ctx.footprints.axes.valid
             : n.lod == FootprintMethod::Cones || n.lod == FootprintMethod::ConesAniso)) {
        s += n.su * ctx.footprints.stratum_offset.u;
        t += n.sv * ctx.footprints.stratum_offset.v;
    }
}

Rgb image_texture(const Scene& scene, const TextureNode& n, int node, const TexContext& ctx) {
    texture::Texel x;
    if (n.lod == FootprintMethod::Cmam) {
        // The CMAM's footprint is its cache's, not the hit's (which is none for it); without
        // the CMAM's caches, a point sample.
        const texture::Vec2d st = node_st_only(n, ctx);
        x = ctx.cmam ? cmam_texel(scene, n, node, st.u, st.v, ctx)
                     : lookup_image(*n.image, n.filter, st.u, st.v, {}, ctx.counts);
    } else {
        const MappedSt m = node_st(n, ctx, true);
        double s = m.st.u, t = m.st.v;
        to_stratum_centre(n, ctx, s, t);
        x = lookup_image(*n.image, n.filter, s, t, m.footprint, ctx.counts);
    }
    if (n.image->image().channels() == 1) return Rgb(x[0]);
    return Rgb(x[0], x[1], x[2]);
}

Rgb checkerboard(const Scene& scene, const TextureNode& n, int node, const TexContext& ctx) {
    const MappedSt m = node_st(n, ctx, n.closed_form);
    texture::Footprint fp = m.footprint;
    double s = m.st.u, t = m.st.v;
    if (n.closed_form && n.lod == FootprintMethod::Cmam && ctx.cmam) {
        // The CMAM as this texture's footprint producer: its own cache of (s,t) samples gives
        // the region the closed form filters (algorithms.md §6.3), centred on the stratum with
        // positioned 2-D tags; a miss point-samples.
        texture::Vec2d to_stratum;
        fp = texture::cmam_footprint(
            ctx.cmam->cache(ctx.object, static_cast<uint32_t>(node), ctx.footprints.path),
            ctx.footprints.tag, s, t, cmam_options(scene, n, ctx), &to_stratum);
        s += to_stratum.u;
        t += to_stratum.v;
    }
    if (fp.kind == texture::Footprint::Kind::Axes && n.filter.kind == texture::FilterKind::Area) {
        // The area filter: the exact share of the footprint's parallelogram on each colour
        // (algorithms.md §5.4), on its stratum's centre as for images.
        if (!(n.lod == FootprintMethod::Cmam && ctx.cmam)) to_stratum_centre(n, ctx, s, t);
        const double odd = texture::checker_odd_share({s, t}, fp.axis_a, fp.axis_b);
        if (odd == 0) return eval_texture(scene, n.tex1, ctx);
        if (odd == 1) return eval_texture(scene, n.tex2, ctx);
        if (odd > 0)
            return float(1 - odd) * eval_texture(scene, n.tex1, ctx) +
                   float(odd) * eval_texture(scene, n.tex2, ctx);
        // (not finite, or beyond kCheckerMaxLines: pbrt-v3's box below)
    }
    if (fp.kind == texture::Footprint::Kind::Axes) {
        // pbrt-v3's closed-form box filter of the checkerboard over the footprint's box.
        double ds = std::max(std::abs(fp.axis_a.u), std::abs(fp.axis_b.u));
        double dt = std::max(std::abs(fp.axis_a.v), std::abs(fp.axis_b.v));
        double s0 = s - ds, s1 = s + ds, t0 = t - dt, t1 = t + dt;
        if (std::floor(s0) != std::floor(s1) || std::floor(t0) != std::floor(t1)) {
            auto bump = [](double x) {
                return std::floor(x / 2) + 2 * std::max(x / 2 - std::floor(x / 2) - 0.5, 0.0);
            };
            double sint = (bump(s1) - bump(s0)) / (2 * ds), tint = (bump(t1) - bump(t0)) / (2 * dt);
            double area2 = sint + tint - 2 * sint * tint;
            if (ds > 1 || dt > 1) area2 = 0.5;
            return float(1 - area2) * eval_texture(scene, n.tex1, ctx) +
                   float(area2) * eval_texture(scene, n.tex2, ctx);
        }
    }
    auto parity = static_cast<long long>(std::floor(s)) + static_cast<long long>(std::floor(t));
    return eval_texture(scene, (parity & 1) == 0 ? n.tex1 : n.tex2, ctx);
}

// A dot of radius 0.35 in about half the unit cells (centred on the integers), jittered inside
// its cell by noise.
Rgb dots(const Scene& scene, const TextureNode& n, const TexContext& ctx) {
    const texture::Vec2d st = node_st(n, ctx, false).st;
    const float s_cell = std::floor(float(st.u) + 0.5f), t_cell = std::floor(float(st.v) + 0.5f);
    if (noise2(s_cell + 0.5f, t_cell + 0.5f) > 0) {
        constexpr float kRadius = 0.35f, kShift = 0.5f - kRadius;
        const float sc = s_cell + kShift * noise2(s_cell + 1.5f, t_cell + 2.8f);
        const float tc = t_cell + kShift * noise2(s_cell + 4.5f, t_cell + 9.8f);
        const float ds = float(st.u) - sc, dt = float(st.v) - tc;
        if (ds * ds + dt * dt < kRadius * kRadius) return eval_texture(scene, n.tex1, ctx);
    }
    return eval_texture(scene, n.tex2, ctx);
}

// fbm, wrinkled and windy: noise whose octaves follow the footprint.
Rgb noise_texture(const TextureNode& n, const TexContext& ctx) {
    const Vec3 p = texture_point(n, ctx.p), dx = texture_vector(n, ctx.footprints.dpdx),
               dy = texture_vector(n, ctx.footprints.dpdy);
    if (n.kind == TextureNode::Kind::Fbm) return Rgb(fbm(p, dx, dy, n.omega, n.octaves));
    if (n.kind == TextureNode::Kind::Wrinkled)
        return Rgb(turbulence(p, dx, dy, n.omega, n.octaves));
    // Windy: small waves whose height follows a slowly varying wind strength.
    const float wind = fbm(0.1f * p, 0.1f * dx, 0.1f * dy, 0.5f, 3);
    return Rgb(std::abs(wind) * fbm(p, dx, dy, 0.5f, 6));
}

}  // namespace

Rgb eval_texture_node(const Scene& scene, int node, const TexContext& ctx) {
    const TextureNode& n = scene.textures[static_cast<std::size_t>(node)];
    switch (n.kind) {
        case TextureNode::Kind::Constant:
            return n.constant;
        case TextureNode::Kind::Image:
            return image_texture(scene, n, node, ctx);
        case TextureNode::Kind::Checkerboard:
            return checkerboard(scene, n, node, ctx);
        case TextureNode::Kind::Bilerp: {
            const texture::Vec2d st = node_st(n, ctx, false).st;
            const float s = float(st.u), t = float(st.v);
            return (1 - s) * (1 - t) * n.corners[0] + (1 - s) * t * n.corners[1] +
                   s * (1 - t) * n.corners[2] + s * t * n.corners[3];
        }
        case TextureNode::Kind::Uv: {
            const texture::Vec2d st = node_st(n, ctx, false).st;
            const Rgb c(float(st.u - std::floor(st.u)), float(st.v - std::floor(st.v)), 0);
            return n.is_float ? Rgb(c.r) : c;
        }
        case TextureNode::Kind::Dots:
            return dots(scene, n, ctx);
        case TextureNode::Kind::Checkerboard3D: {
            const Vec3 p = texture_point(n, ctx.p);
            const long long parity = static_cast<long long>(std::floor(p.x)) +
                                     static_cast<long long>(std::floor(p.y)) +
                                     static_cast<long long>(std::floor(p.z));
            return eval_texture(scene, (parity & 1) == 0 ? n.tex1 : n.tex2, ctx);
        }
        case TextureNode::Kind::Fbm:
        case TextureNode::Kind::Wrinkled:
        case TextureNode::Kind::Windy:
            return noise_texture(n, ctx);
        case TextureNode::Kind::Marble: {
            const Rgb c = marble(n, ctx);
            return n.is_float ? Rgb(c.luminance()) : c;
        }
        case TextureNode::Kind::Scale:
            return eval_texture(scene, n.tex1, ctx) * eval_texture(scene, n.tex2, ctx);
        case TextureNode::Kind::Mix: {
            float amt = eval_texture(scene, n.amount, ctx).r;
            Rgb a = amt != 1 ? eval_texture(scene, n.tex1, ctx) : Rgb();
            Rgb b = amt != 0 ? eval_texture(scene, n.tex2, ctx) : Rgb();
            return (1 - amt) * a + amt * b;
        }
    }
    return {};
}

// pbrt-v3's FrDielectric with its two ratios' terms multiplied by eta_t (then eta_t cos_t is
// sqrt(eta_t^2 - eta_i^2 sin_i^2)) and their squares summed over one denominator: one division
// (algorithms.md §18).
float fresnel_dielectric(float cos_i, float eta_i, float eta_t) {
    cos_i = std::clamp(cos_i, -1.0f, 1.0f);
    if (cos_i <= 0) {
        std::swap(eta_i, eta_t);
        cos_i = -cos_i;
    }
    const float sin2_i = std::max(0.0f, 1 - cos_i * cos_i);
    const float t2 = eta_t * eta_t - eta_i * eta_i * sin2_i;  // (eta_t cos_t)^2
    if (t2 <= 0) return 1;                                    // total internal reflection
    const float tc = std::sqrt(t2);
    const float a = eta_t * eta_t * cos_i, b = eta_i * tc;  // r_parl = (a - b) / (a + b)
    const float c = eta_i * eta_t * cos_i, d = eta_t * tc;  // r_perp = (c - d) / (c + d)
    const float ab = (a - b) * (c + d), cd = (c - d) * (a + b), den = (a + b) * (c + d);
    return (ab * ab + cd * cd) / (2 * den * den);
}

// The Fresnel equations of a conductor (complex index eta + i k, from air) for unpolarised
// light, in the form pbrt-v3's FrConductor evaluates them: a^2 + b^2 = |(eta + i k)^2 -
// sin^2|, Rs = (a^2 + b^2 + cos^2 - 2a cos) / (a^2 + b^2 + cos^2 + 2a cos), and Rp from Rs.
namespace {
float fresnel_conductor(float cos_i, float eta, float k) {
    cos_i = std::clamp(std::abs(cos_i), 0.0f, 1.0f);
    const float cos2 = cos_i * cos_i, sin2 = 1 - cos2;
    const float eta2 = eta * eta, k2 = k * k;
    const float t0 = eta2 - k2 - sin2;
    const float a2_b2 = std::sqrt(t0 * t0 + 4 * eta2 * k2);
    const float t1 = a2_b2 + cos2;
    const float a = std::sqrt(0.5f * (a2_b2 + t0));
    const float t2 = 2 * cos_i * a;
    const float rs = (t1 - t2) / (t1 + t2);
    const float t3 = cos2 * a2_b2 + sin2 * sin2, t4 = t2 * sin2;
    const float rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5f * (rp + rs);
}
}  // namespace

Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
    return {fresnel_conductor(cos_i, eta.r, k.r), fresnel_conductor(cos_i, eta.g, k.g),
            fresnel_conductor(cos_i, eta.b, k.b)};
}

std::optional<Vec3> refract(const Vec3& wi, const Vec3& n, float eta) {
    float cos_i = dot(n, wi);
    float sin2_i = std::max(0.0f, 1 - cos_i * cos_i);
    float sin2_t = eta * eta * sin2_i;
    if (sin2_t >= 1) return std::nullopt;
    float cos_t = std::sqrt(1 - sin2_t);
    return eta * -wi + (eta * cos_i - cos_t) * n;
}

namespace {

// The Trowbridge-Reitz (GGX) microfacet distribution in the local frame, pbrt-v3's
// D = 1 / (pi ax ay cos^4 (1 + e)^2), e = tan^2 (cos^2 phi / ax^2 + sin^2 phi / ay^2), of the
// direction of h, which need not be a unit vector (l2 = |h|^2): cos^4 (1 + e)^2 is
// (hz^2 + hx^2 / ax^2 + hy^2 / ay^2)^2 / l2^2 (algorithms.md §18). 0 where h lies in the plane.
float tr_d(const Vec3& h, float l2, float alpha) {
    if (h.z == 0) return 0;
    const float a2 = alpha * alpha, q = a2 * (h.z * h.z) + (h.x * h.x + h.y * h.y);
    return a2 * (l2 * l2) / (kPi * (q * q));
}
float tr_d(const Vec3& h, float l2, float ax, float ay) {
    if (h.z == 0) return 0;
    const float q = h.z * h.z + h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay);
    return l2 * l2 / (kPi * ax * ay * (q * q));
}
// Smith's Lambda(w) = (sqrt(1 + alpha^2 tan^2) - 1) / 2 is (r / |cos| - 1) / 2 with r =
// sqrt(cos^2 + alpha^2 sin^2) (ax^2 x^2 + ay^2 y^2 for alpha^2 sin^2 when anisotropic), of a
// unit w; so G = 1 / (1 + Lambda(wo) + Lambda(wi)) = 2 |cos_o cos_i| / (r_o |cos_i| + r_i |cos_o|).
float smith_r(const Vec3& w, float alpha) {
    return std::sqrt(w.z * w.z + alpha * alpha * (w.x * w.x + w.y * w.y));
}
float smith_r(const Vec3& w, float ax, float ay) {
    return std::sqrt(w.z * w.z + (ax * ax * (w.x * w.x) + ay * ay * (w.y * w.y)));
}

// pbrt-v3's remapping of a roughness to the microfacet alpha. A material's roughness is mostly a
// constant, and a thread shades one material after another: the last value's alpha is kept, per
// thread, so that the logarithm runs only when the roughness changes (the same values: a roughness
// equal to the last one, +0 and -0 included, has the same alpha).
float roughness_to_alpha(float r) {
    thread_local float last_r = std::numeric_limits<float>::quiet_NaN(), last_alpha = 0;
    if (r == last_r) return last_alpha;
    last_r = r;
    const float x = std::log(std::max(r, 1e-3f));
    last_alpha = 1.62142f + 0.819955f * x + 0.1734f * x * x + 0.0171201f * x * x * x +
                 0.000640711f * x * x * x * x;
    return last_alpha;
}

}  // namespace

Bsdf::Outgoing Bsdf::outgoing(const Vec3& wo_w) const {
    Outgoing o;
    o.local = frame.to_local(wo_w);
    o.w_ng = dot(wo_w, ng);
    o.smith_r = !has_glossy() && !has_transmission() ? 0
                : anisotropic                        ? smith_r(o.local, alpha, alpha_y)
                                                     : smith_r(o.local, alpha);
    if (hair) o.hair = hair_outgoing(hair_model, o.local);
    return o;
}

void Bsdf::scale(const Rgb& w) {
    if (fresnel_blend) {  // (its kd and ks are reflectances, not weights: its value is scaled)
        blend_scale = blend_scale * w;
    } else {
        kd = kd * w;
        ks = ks * w;
    }
    kr = kr * w;
    kt = kt * w;
    kt_rough = kt_rough * w;
    kt_diffuse = kt_diffuse * w;
    fourier_scale = fourier_scale * w;
    hair_scale = hair_scale * w;
    disney_scale = disney_scale * w;
    if (layer) layer->scale(w);
}

namespace {
bool same(const Vec3& a, const Vec3& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}
bool same(const Rgb& a, const Rgb& b) {
    return a.r == b.r && a.g == b.g && a.b == b.b;
}

// The microfacet lobes (glossy, FresnelBlend's coat, rough transmission) share one distribution
// and Fresnel term.
bool microfacet(const Bsdf& b) {
    return b.fresnel_blend || !b.ks.is_black() || !b.kt_rough.is_black();
}
// Specular lobes with the index's Fresnel term: a glass's reflection and transmission (a
// mirror's reflection has none).
bool uses_eta(const Bsdf& b) {
    return (!b.kr.is_black() && !b.fresnel_noop) || !b.kt.is_black();
}
}  // namespace

bool Bsdf::takes(const Bsdf& o) const {
    if (!same(frame.n, o.frame.n) || !same(ng, o.ng)) return false;
    if (!kr.is_black() && !o.kr.is_black() && fresnel_noop != o.fresnel_noop) return false;
    return !(uses_eta(*this) && uses_eta(o) && eta != o.eta);
}

bool Bsdf::fits(const Bsdf& o) const {
    // Only an anisotropic distribution turns with the frame about its normal: two of them need
    // the same frame; with one, the sum takes its frame.
    const bool same_frame = same(frame.s, o.frame.s) && same(frame.t, o.frame.t);
    if (!same_frame && anisotropic && o.anisotropic) return false;
    // A Fourier BSDF takes no other non-specular lobe beside it.
    if ((fourier && o.own_lobes() > 0) || (o.fourier && own_lobes() > 0)) return false;
    if ((hair && o.own_lobes() > 0) || (o.hair && own_lobes() > 0)) return false;  // the same
    if ((disney && o.own_lobes() > 0) || (o.disney && own_lobes() > 0)) return false;
    if (microfacet(*this) && microfacet(o) &&
        (alpha != o.alpha || alpha_y != o.alpha_y || anisotropic != o.anisotropic ||
         lobe_eta_i != o.lobe_eta_i || lobe_eta_t != o.lobe_eta_t || conductor != o.conductor ||
         !same(conductor_eta, o.conductor_eta) || !same(conductor_k, o.conductor_k) ||
         fresnel_blend != o.fresnel_blend))
        return false;
    // A FresnelBlend's kd and ks are its colours, not weights: two add only when they are the
    // same colours, and a blend takes no Lambertian lobe beside it.
    if (fresnel_blend && o.fresnel_blend && !(same(kd, o.kd) && same(ks, o.ks))) return false;
    if (fresnel_blend != o.fresnel_blend && !(fresnel_blend ? o.kd : kd).is_black()) return false;
    const bool diffuse = !fresnel_blend && !kd.is_black(),
               diffuse_o = !o.fresnel_blend && !o.kd.is_black();
    return !(diffuse && diffuse_o && (on_a != o.on_a || on_b != o.on_b));
}

void Bsdf::add(const Bsdf& o, std::forward_list<Bsdf>& layers) {
    Bsdf* tail = nullptr;  // what goes on the end of the chain
    const bool mf = microfacet(*this);
    if (fits(o)) {
        if (!(same(frame.s, o.frame.s) && same(frame.t, o.frame.t)) && o.anisotropic)
            frame = o.frame;
        const bool diffuse = !fresnel_blend && !kd.is_black(),
                   diffuse_o = !o.fresnel_blend && !o.kd.is_black();
        if (fresnel_blend && o.fresnel_blend) {
            blend_scale += o.blend_scale;
        } else if (o.fresnel_blend) {
            fresnel_blend = true;
            kd = o.kd;
            ks = o.ks;
            blend_scale = o.blend_scale;
        } else if (!fresnel_blend) {
            if (diffuse_o && !diffuse) {
                on_a = o.on_a;
                on_b = o.on_b;
            }
            kd += o.kd;
            ks += o.ks;
        }
        if (microfacet(o) && !mf) {
            alpha = o.alpha;
            alpha_y = o.alpha_y;
            anisotropic = o.anisotropic;
            lobe_eta_i = o.lobe_eta_i;
            lobe_eta_t = o.lobe_eta_t;
            conductor = o.conductor;
            conductor_eta = o.conductor_eta;
            conductor_k = o.conductor_k;
        }
        kt_rough += o.kt_rough;
        kt_diffuse += o.kt_diffuse;
        if (o.hair) {
            hair = true;
            hair_model = o.hair_model;
            hair_scale = o.hair_scale;
        }
        if (o.disney) {
            disney = o.disney;
            disney_scale = o.disney_scale;
        }
        if (o.fourier) {
            fourier = o.fourier;
            fourier_scale = o.fourier_scale;
        }
        tail = o.layer;
    } else {
        Bsdf& l = layers.emplace_front(o);  // (its own layers stay behind it)
        l.kr = Rgb();
        l.kt = Rgb();
        tail = &l;
    }
    // The specular lobes, in this Bsdf either way (takes(o): they fit).
    if (kr.is_black() && !o.kr.is_black()) fresnel_noop = o.fresnel_noop;
    if (!uses_eta(*this) && uses_eta(o)) eta = o.eta;
    kr += o.kr;
    kt += o.kt;
    Bsdf* end = this;
    while (end->layer) end = end->layer;
    end->layer = tail;
}

Rgb Bsdf::f(const Vec3& wo_w, const Vec3& wi_w) const {
    return f(outgoing(wo_w), wi_w);
}

int Bsdf::own_lobes() const {
    return int(has_glossy()) + int(has_diffuse()) + int(has_transmission()) +
           int(has_diffuse_transmission()) + int(fourier != nullptr) + int(hair) +
           (disney ? disney->components() : 0);
}

// The layers' lobes are evaluated in their own frames, from wo in the world.
Rgb Bsdf::f(const Outgoing& o, const Vec3& wi_w) const {
    Rgb out = own_f(o, wi_w);
    if (!layer) return out;
    const Vec3 wo_w = frame.to_world(o.local);
    for (const Bsdf* l = layer; l; l = l->layer) out += l->own_f(l->outgoing(wo_w), wi_w);
    return out;
}

Rgb Bsdf::own_f(const Outgoing& o, const Vec3& wi_w) const {
    const Vec3& wo = o.local;
    if (wo.z == 0) return {};
    if (fourier) return fourier_f(*fourier, wo, frame.to_local(wi_w)) * fourier_scale;
    if (hair) return hair_f(hair_model, o.hair, frame.to_local(wi_w)) * hair_scale;
    bool reflect = dot(wi_w, ng) * o.w_ng > 0;
    if (disney) return disney_f(*disney, wo, frame.to_local(wi_w), reflect) * disney_scale;
    if (!reflect) {
        Rgb out = has_transmission() ? transmission_f(o, frame.to_local(wi_w)) : Rgb{};
        if (has_diffuse_transmission()) out += kt_diffuse * kInvPi;
        return out;
    }
    if (fresnel_blend) return blend_f(wo, frame.to_local(wi_w));
    if (on_b == 0 && !has_glossy()) {  // Lambertian: wi's local frame unused
        if (sss_eta > 0)
            return kd * (kInvPi * (1 - fresnel_dielectric(dot(wi_w, frame.n), 1, sss_eta)));
        return kd * kInvPi;
    }
    const Vec3 wi = frame.to_local(wi_w);
    Rgb out{};
    if (has_diffuse()) {
        if (on_b == 0) {
            out += kd * kInvPi;
        } else {
            // Oren-Nayar (pbrt-v3 OrenNayar::f)
            float sin_i = std::sqrt(std::max(0.0f, 1 - wi.z * wi.z));
            float sin_o = std::sqrt(std::max(0.0f, 1 - wo.z * wo.z));
            float max_cos = 0;
            if (sin_i > 1e-4f && sin_o > 1e-4f) {
                float cpi = std::clamp(wi.x / sin_i, -1.0f, 1.0f),
                      spi = std::clamp(wi.y / sin_i, -1.0f, 1.0f);
                float cpo = std::clamp(wo.x / sin_o, -1.0f, 1.0f),
                      spo = std::clamp(wo.y / sin_o, -1.0f, 1.0f);
                max_cos = std::max(0.0f, cpi * cpo + spi * spo);
            }
            float sin_alpha, tan_beta;
            if (std::abs(wi.z) > std::abs(wo.z)) {
                sin_alpha = sin_o;
                tan_beta = sin_i / std::abs(wi.z);
            } else {
                sin_alpha = sin_i;
                tan_beta = sin_o / std::abs(wo.z);
            }
            out += kd * kInvPi * (on_a + on_b * max_cos * sin_alpha * tan_beta);
        }
    }
    if (has_glossy()) {
        const float cos_o = std::abs(wo.z), cos_i = std::abs(wi.z);
        const Vec3 h = wi + wo;
        const float l2 = dot(h, h);
        if (cos_i != 0 && cos_o != 0 && l2 != 0) {
            const float c = dot(wi, faceforward(h, Vec3(0, 0, 1))) / std::sqrt(l2);
            const float r_i = anisotropic ? smith_r(wi, alpha, alpha_y) : smith_r(wi, alpha);
            const float d = anisotropic ? tr_d(h, l2, alpha, alpha_y) : tr_d(h, l2, alpha);
            // D G / (4 cos_i cos_o), G as at smith_r.
            const float common = d / (2 * (o.smith_r * cos_i + r_i * cos_o));
            if (conductor) {
                out += ks * fresnel_conductor(c, conductor_eta, conductor_k) * common;
            } else {
                out += ks * (fresnel_dielectric(c, lobe_eta_i, lobe_eta_t) * common);
            }
        }
    }
    return out;
}

// algorithms.md §18. The microfacet lobes' normals are drawn from the normals wo sees, as
// pbrt-v3 draws them: density D(h) G1(wo) |wo . h| / |cos theta_o|, so the reflected direction's
// is D(h) G1(wo) / (4 |cos theta_o|) and the refracted one's that times |wo . h| dwh/dwi.
float Bsdf::pdf(const Outgoing& o, const Vec3& wi_w) const {
    const float p = pdf_local(o, frame.to_local(wi_w));
    if (!layer) return p;
    // The chain's lobes evenly, as pbrt-v3 picks among all its BSDF's components: each Bsdf's
    // density (even among its own lobes) weighted by its share of the lobes.
    int n = own_lobes();
    float sum = float(n) * p;
    const Vec3 wo_w = frame.to_world(o.local);
    for (const Bsdf* l = layer; l; l = l->layer) {
        const int k = l->own_lobes();
        if (k == 0) continue;
        sum += float(k) * l->pdf_local(l->outgoing(wo_w), l->frame.to_local(wi_w));
        n += k;
    }
    return n > 0 ? sum / float(n) : 0.0f;
}

float Bsdf::pdf_local(const Outgoing& o, const Vec3& wi) const {
    const Vec3& wo = o.local;
    if (wo.z == 0) return 0;
    if (fourier) return fourier_pdf(*fourier, wo, wi);
    if (hair) return hair_pdf(hair_model, o.hair, wi);
    if (disney) return disney_pdf(*disney, wo, wi);
    // The visible normals' density is D(h) G1(wo) |wo . h| / |cos theta_o|; G1 = 1 / (1 +
    // Lambda(wo)).
    // Lambda(wo) = (r_o / |cos_o| - 1) / 2 (smith_r).
    const float g1_over_cos = 2 / (o.smith_r + std::abs(wo.z));
    const bool diffuse = has_diffuse(), glossy = has_glossy(), transmission = has_transmission(),
               diffuse_t = has_diffuse_transmission();
    const int lobes = int(diffuse) + int(glossy) + int(transmission) + int(diffuse_t);
    const float share = lobes == 2 ? 0.5f : lobes == 3 ? 1.0f / 3 : lobes == 4 ? 0.25f : 1.0f;
    if (wo.z * wi.z < 0) {  // through the surface: the transmission lobes
        const float p_diffuse = diffuse_t ? share * std::abs(wi.z) * kInvPi : 0.0f;
        if (!transmission) return p_diffuse;
        const float eta = wo.z > 0 ? lobe_eta_t / lobe_eta_i : lobe_eta_i / lobe_eta_t;
        const Vec3 h = wo + wi * eta;
        if (h.x == 0 && h.y == 0 && h.z == 0) return p_diffuse;
        const float l2 = dot(h, h);
        const Vec3 wh = h / std::sqrt(l2);
        const float oh = dot(wo, wh), ih = dot(wi, wh);
        if (oh * ih > 0) return p_diffuse;  // wo, wi on one side of the microfacet: no refraction
        // The visible normal's density times dwh/dwi = eta^2 |wi . h| / denom^2.
        const float denom = oh + eta * ih;
        const float d = anisotropic ? tr_d(h, l2, alpha, alpha_y) : tr_d(h, l2, alpha);
        return p_diffuse +
               share * d * g1_over_cos * std::abs(oh) * std::abs(eta * eta * ih / (denom * denom));
    }
    if (wo.z * wi.z == 0) return 0;
    float p = 0;
    if (diffuse) p += share * std::abs(wi.z) * kInvPi;
    if (glossy) {
        const Vec3 h = wi + wo;
        const float l2 = dot(h, h);
        if (l2 == 0) return p;
        const float d = anisotropic ? tr_d(h, l2, alpha, alpha_y) : tr_d(h, l2, alpha);
        // The visible normal's density over dwi/dwh = 4 |wo . h|, which cancels its |wo . h|.
        if (dot(wo, h) != 0) p += share * d * g1_over_cos / 4;
    }
    return p;
}

namespace {
// A Trowbridge-Reitz microfacet normal drawn from the normals wo sees (algorithms.md §18):
// density D(h) G1(wo) max(0, wo . h) / cos theta_o, pbrt-v3's "visible area" sampling (its
// TrowbridgeReitzDistribution's default), by Heitz's 2018 construction: wo stretched by the
// roughness, a point on the unit disk warped onto the half of it wo sees, lifted onto the
// hemisphere about the stretched wo and unstretched. wo on the upper side; nothing where the
// result is not finite.
std::optional<Vec3> sample_visible_normal(const Vec3& wo, float ax, float ay, float u1, float u2) {
    const Vec3 v = normalize(Vec3(ax * wo.x, ay * wo.y, wo.z));
    const float len2 = v.x * v.x + v.y * v.y;
    const Vec3 t1 = len2 > 0 ? Vec3(-v.y, v.x, 0) / std::sqrt(len2) : Vec3(1, 0, 0);
    const Vec3 t2 = cross(v, t1);
    const float r = std::sqrt(u1), phi = 2 * kPi * u2;
    const float p1 = r * std::cos(phi), s = 0.5f * (1 + v.z);
    const float p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * (r * std::sin(phi));
    const Vec3 n = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2)) * v;
    const Vec3 h = normalize(Vec3(ax * n.x, ay * n.y, std::max(0.0f, n.z)));
    if (!finite(h)) return std::nullopt;
    return h;
}
}  // namespace

Bsdf::Sample Bsdf::sample(const Outgoing& o, float u0, float u1, float u2) const {
    if (!layer) return own_sample(o, u0, u1, u2);
    // A lobe of the chain evenly (u0 rescaled within the Bsdf that has it), then the chain's
    // value and density in the direction drawn.
    int n = 0;
    for (const Bsdf* l = this; l; l = l->layer) n += l->own_lobes();
    if (n == 0) return {};
    const float x = u0 * float(n);
    const int k = std::min(static_cast<int>(x), n - 1);
    int start = 0;  // b's first lobe in the chain
    const Bsdf* b = this;
    while (k >= start + b->own_lobes()) {
        start += b->own_lobes();
        b = b->layer;
    }
    const float v0 = std::min((x - float(start)) / float(b->own_lobes()), 0x1.fffffep-1f);
    Sample s = b->own_sample(b == this ? o : b->outgoing(frame.to_world(o.local)), v0, u1, u2);
    if (!(s.pdf > 0)) return s;
    s.pdf = pdf(o, s.wi);
    if (!(s.pdf > 0)) return Sample{};
    s.f = f(o, s.wi);
    return s;
}

Bsdf::Sample Bsdf::own_sample(const Outgoing& o, float u0, float u1, float u2) const {
    Sample out;
    const Vec3& wo = o.local;
    if (wo.z == 0 || own_lobes() == 0) return out;
    if (fourier) {  // its own density (pdf() is its tabulated one, equal up to interpolation)
        const FourierSample s = fourier_sample(*fourier, wo, u1, u2);
        if (!(s.pdf > 0)) return out;
        out.wi = frame.to_world(s.wi);
        out.pdf = s.pdf;
        out.f = s.f * fourier_scale;
        return out;
    }
    if (hair) {
        const std::optional<HairSample> s = hair_sample_f(hair_model, o.hair, u0, u1, u2);
        if (!s || !(s->pdf > 0)) return out;
        out.wi = frame.to_world(s->wi);
        out.pdf = s->pdf;
        out.f = s->f * hair_scale;
        return out;
    }
    if (disney) {  // the direction from its own components, the value and density from all
        const std::optional<Vec3> wi = disney_sample(*disney, wo, u0, u1, u2);
        if (!wi) return out;
        out.wi = frame.to_world(*wi);
        out.pdf = disney_pdf(*disney, wo, *wi);
        if (!(out.pdf > 0)) {
            out.pdf = 0;
            return out;
        }
        out.f = own_f(o, out.wi);
        return out;
    }
    // The lobe: glossy (0), diffuse (1), transmission (2), diffuse transmission (3), evenly
    // among those there are.
    const bool present[4] = {has_glossy(), has_diffuse(), has_transmission(),
                             has_diffuse_transmission()};
    const int lobes = int(present[0]) + int(present[1]) + int(present[2]) + int(present[3]);
    int k = std::min(static_cast<int>(u0 * float(lobes)), lobes - 1), lobe = 0;
    while (!present[lobe] || k-- > 0) ++lobe;
    Vec3 wi;
    if (lobe == 1 || lobe == 3) {
        // Cosine-weighted on wo's side of the shading normal, or the other side.
        wi = hemisphere_direction(u1, u2);
        if ((wo.z < 0) == (lobe == 1)) wi.z = -wi.z;
    } else {
        const float ay = anisotropic ? alpha_y : alpha;
        const Vec3 up = wo.z < 0 ? -wo : wo;  // (the normals are drawn on wo's side)
        const std::optional<Vec3> h = sample_visible_normal(up, alpha, ay, u1, u2);
        if (!h) return out;
        const Vec3 wh = wo.z < 0 ? -*h : *h;
        const float dot_oh = dot(wo, wh);
        if (dot_oh <= 0) return out;
        if (lobe == 0) {  // reflected about the microfacet
            wi = -wo + 2 * dot_oh * wh;
            if (wi.z * wo.z <= 0) return out;
        } else {  // refracted through it, from wo's side to the other
            const float eta = wo.z > 0 ? lobe_eta_i / lobe_eta_t : lobe_eta_t / lobe_eta_i;
            const std::optional<Vec3> t = refract(wo, wh, eta);
            if (!t || t->z * wo.z >= 0) return out;
            wi = *t;
        }
    }
    out.wi = frame.to_world(wi);
    out.pdf = pdf_local(o, wi);
    if (!(out.pdf > 0)) {
        out.pdf = 0;
        return out;
    }
    out.f = own_f(o, out.wi);
    return out;
}

// ---------------------------------------------------------------------------------------------
// pbrt-v3's Disney BSDF (algorithms.md §24), in the shading frame.

namespace {
float schlick_weight(float cos_theta) {
    const float m = std::clamp(1 - cos_theta, 0.0f, 1.0f);
    return (m * m) * (m * m) * m;
}
// GTR1 (the clearcoat's distribution) and its masking term as Burley writes them.
float gtr1(float cos_theta, float alpha) {
    const float a2 = alpha * alpha;
    return (a2 - 1) / (kPi * std::log(a2) * (1 + (a2 - 1) * cos_theta * cos_theta));
}
float smith_g_ggx(float cos_theta, float alpha) {
    const float a2 = alpha * alpha, c2 = cos_theta * cos_theta;
    return 1 / (cos_theta + std::sqrt(a2 + c2 - a2 * c2));
}
// The specular lobe's uncorrelated masking-shadowing G1(wo) G1(wi), G1 = 2 |cos| / (|cos| + r).
float disney_g1(const DisneyModel& m, const Vec3& w) {
    const float c = std::abs(w.z);
    return 2 * c / (c + smith_r(w, m.ax, m.ay));
}
Vec3 reflect_about(const Vec3& wo, const Vec3& wh) {
    return -wo + 2 * dot(wo, wh) * wh;
}
// The rough transmission (pbrt-v3's MicrofacetTransmission from air into eta, for radiance): with
// eta' the index on wi's side over wo's and h = normalize(wo + eta' wi), (1 - F(wo . h)) D G
// |wi . h| |wo . h| / (|cos_i cos_o| (wo . h + eta' wi . h)^2) times `transmit`; G uncorrelated
// (the Disney distribution's) or, on a thin surface, correlated (pbrt-v3's Trowbridge-Reitz).
// Its density: the visible normal's times |dh/dwi| = eta'^2 |wi . h| / (wo . h + eta' wi . h)^2.
struct Refraction {
    Vec3 h;
    float eta = 1, oh = 0, ih = 0, denom = 0;
};
std::optional<Refraction> refraction_of(const DisneyModel& m, const Vec3& wo, const Vec3& wi) {
    if (!(wo.z * wi.z < 0)) return std::nullopt;
    Refraction r;
    r.eta = wo.z > 0 ? m.eta : 1 / m.eta;
    const Vec3 h = wo + wi * r.eta;
    if (h.x == 0 && h.y == 0 && h.z == 0) return std::nullopt;
    r.h = normalize(h);
    r.oh = dot(wo, r.h);
    r.ih = dot(wi, r.h);
    if (r.oh * r.ih > 0) return std::nullopt;  // one side of the microfacet: no refraction
    r.denom = r.oh + r.eta * r.ih;
    return r;
}
Rgb disney_transmission_f(const DisneyModel& m, const Vec3& wo, const Vec3& wi) {
    const std::optional<Refraction> r = refraction_of(m, wo, wi);
    if (!r) return {};
    const float co = std::abs(wo.z), ci = std::abs(wi.z);
    const float ro = smith_r(wo, m.tax, m.tay), ri = smith_r(wi, m.tax, m.tay);
    const float g =
        m.thin ? 2 * co * ci / (ro * ci + ri * co) : (2 * co / (co + ro)) * (2 * ci / (ci + ri));
    const float f = fresnel_dielectric(r->oh * (r->h.z < 0 ? -1.0f : 1.0f), 1, m.eta);
    const float d = tr_d(r->h, 1, m.tax, m.tay);
    return m.transmit *
           ((1 - f) * std::abs(d * g * r->ih * r->oh / (ci * co * r->denom * r->denom)));
}
float disney_transmission_pdf(const DisneyModel& m, const Vec3& wo, const Vec3& wi) {
    const std::optional<Refraction> r = refraction_of(m, wo, wi);
    if (!r) return 0;
    const float co = std::abs(wo.z), g1 = 2 * co / (co + smith_r(wo, m.tax, m.tay));
    return tr_d(r->h, 1, m.tax, m.tay) * g1 * std::abs(r->oh) / co *
           std::abs(r->eta * r->eta * r->ih / (r->denom * r->denom));
}
}  // namespace

Rgb disney_f(const DisneyModel& m, const Vec3& wo, const Vec3& wi, bool reflect) {
    if (!reflect) {
        Rgb out = m.thin ? m.lambert_t * kInvPi : Rgb();
        if (m.has_transmission) out += disney_transmission_f(m, wo, wi);
        return out;
    }
    const float co = std::abs(wo.z), ci = std::abs(wi.z);
    const Vec3 h = wi + wo;
    const bool has_h = !(h.x == 0 && h.y == 0 && h.z == 0);
    const Vec3 wh = has_h ? normalize(h) : Vec3();
    const float cos_d = dot(wi, wh);
    Rgb out{};
    if (m.diffuse_group) {
        const float fo = schlick_weight(co), fi = schlick_weight(ci);
        out += m.diffuse * (kInvPi * (1 - fo / 2) * (1 - fi / 2));
        if (has_h) {
            if (m.thin) {
                const float fss90 = cos_d * cos_d * m.roughness;
                const float fss = (1 + fo * (fss90 - 1)) * (1 + fi * (fss90 - 1));
                const float ss = 1.25f * (fss * (1 / (co + ci) - 0.5f) + 0.5f);
                out += m.fake_ss * (kInvPi * ss);
            }
            const float rr = 2 * m.roughness * cos_d * cos_d;
            out += m.retro * (kInvPi * rr * (fo + fi + fo * fi * (rr - 1)));
            if (m.has_sheen) out += m.sheen * schlick_weight(cos_d);
        }
    }
    if (has_h && ci != 0 && co != 0) {
        // The specular lobe: Trowbridge-Reitz with G1 G1 and the Disney Fresnel term, a blend by
        // metallic of the dielectric's from air to eta and Schlick's of cspec0.
        const float c = dot(wi, wh.z < 0 ? -wh : wh);
        const float dielectric = fresnel_dielectric(c, 1, m.eta), w = schlick_weight(c);
        const Rgb schlick = m.cspec0 + (Rgb(1) - m.cspec0) * w;
        const Rgb fresnel = Rgb(dielectric) * (1 - m.metallic) + schlick * m.metallic;
        const float d = tr_d(wh, 1, m.ax, m.ay);
        out += fresnel * (d * disney_g1(m, wo) * disney_g1(m, wi) / (4 * ci * co));
        if (m.has_clearcoat) {
            const float dr = gtr1(std::abs(wh.z), m.gloss);
            const float fr = 0.04f + (1 - 0.04f) * schlick_weight(dot(wo, wh));
            const float gr = smith_g_ggx(co, 0.25f) * smith_g_ggx(ci, 0.25f);
            out += Rgb(m.clearcoat * gr * fr * dr / 4);
        }
    }
    return out;
}

float disney_pdf(const DisneyModel& m, const Vec3& wo, const Vec3& wi) {
    const bool same_side = wo.z * wi.z > 0;
    const float cosine = std::abs(wi.z) * kInvPi;
    float sum = 0;
    if (m.diffuse_group && same_side)  // each diffuse-type component's cosine density
        sum += float(m.diffuse_components()) * cosine;
    if (m.thin && !same_side) sum += cosine;
    if (m.has_transmission) sum += disney_transmission_pdf(m, wo, wi);
    const Vec3 h = wo + wi;
    if (same_side && !(h.x == 0 && h.y == 0 && h.z == 0) && wo.z != 0) {
        const Vec3 wh = normalize(h);
        const float oh = dot(wo, wh);
        // The visible normals' density D G1(wo) |wo . h| / |cos theta_o|, over 4 wo . h.
        sum +=
            tr_d(wh, 1, m.ax, m.ay) * disney_g1(m, wo) * std::abs(oh) / (std::abs(wo.z) * 4 * oh);
        if (m.has_clearcoat) sum += gtr1(std::abs(wh.z), m.gloss) * std::abs(wh.z) / (4 * oh);
    }
    return sum / float(m.components());
}

std::optional<Vec3> disney_sample(const DisneyModel& m, const Vec3& wo, float u0, float u1,
                                  float u2) {
    if (wo.z == 0) return std::nullopt;
    const int n = m.components();
    int k = std::min(static_cast<int>(u0 * float(n)), n - 1);
    const int diffuse = m.diffuse_components();
    auto cosine = [&](bool through) {
        Vec3 wi = hemisphere_direction(u1, u2);
        if ((wo.z < 0) != through) wi.z = -wi.z;
        return wi;
    };
    if (k < diffuse) return cosine(false);
    k -= diffuse;
    if (k == 0) {  // the specular lobe: a visible normal on wo's side, reflected about
        const std::optional<Vec3> h =
            sample_visible_normal(wo.z < 0 ? -wo : wo, m.ax, m.ay, u1, u2);
        if (!h) return std::nullopt;
        const Vec3 wh = wo.z < 0 ? -*h : *h;
        if (dot(wo, wh) < 0) return std::nullopt;
        const Vec3 wi = reflect_about(wo, wh);
        if (wi.z * wo.z <= 0) return std::nullopt;
        return wi;
    }
    if (m.has_clearcoat && k == 1) {  // GTR1's normal, reflected about
        const float a2 = m.gloss * m.gloss;
        const float cos_t = std::sqrt(std::max(0.0f, (1 - std::pow(a2, 1 - u1)) / (1 - a2)));
        const float sin_t = std::sqrt(std::max(0.0f, 1 - cos_t * cos_t)), phi = 2 * kPi * u2;
        Vec3 wh(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t);
        if (wh.z * wo.z < 0) wh = -wh;
        const Vec3 wi = reflect_about(wo, wh);
        if (wi.z * wo.z <= 0) return std::nullopt;
        return wi;
    }
    if (m.has_transmission && k == 1 + int(m.has_clearcoat)) {
        // A visible normal of the transmission's distribution on wo's side, refracted through.
        const std::optional<Vec3> h =
            sample_visible_normal(wo.z < 0 ? -wo : wo, m.tax, m.tay, u1, u2);
        if (!h) return std::nullopt;
        const Vec3 wh = wo.z < 0 ? -*h : *h;
        if (dot(wo, wh) < 0) return std::nullopt;
        return refract(wo, wh, wo.z > 0 ? 1 / m.eta : m.eta);
    }
    return cosine(true);  // a thin surface's diffuse transmission
}

// pbrt-v3's FresnelBlend: the diffuse base under the coat, 28 / (23 pi) kd (1 - ks) times
// (1 - (1 - |cos|/2)^5) for each direction, plus the coat's microfacet reflection with Schlick's
// Fresnel term, D(h) F(wi . h) / (4 |wi . h| max(|cos theta_i|, |cos theta_o|)).
Rgb Bsdf::blend_f(const Vec3& wo, const Vec3& wi) const {
    auto pow5 = [](float v) { return (v * v) * (v * v) * v; };
    const float ci = std::abs(wi.z), co = std::abs(wo.z);
    const Vec3 h = wi + wo;
    const float l2 = dot(h, h);
    if (l2 == 0) return {};
    const Rgb diffuse = kd * (Rgb(1) - ks) *
                        (28 / (23 * kPi) * (1 - pow5(1 - 0.5f * ci)) * (1 - pow5(1 - 0.5f * co)));
    const float ih = dot(wi, h) / std::sqrt(l2);
    const float d = anisotropic ? tr_d(h, l2, alpha, alpha_y) : tr_d(h, l2, alpha);
    const Rgb schlick = ks + (Rgb(1) - ks) * pow5(1 - ih);
    const Rgb specular = schlick * (d / (4 * std::abs(ih) * std::max(ci, co)));
    return (diffuse + specular) * blend_scale;
}

// pbrt-v3's MicrofacetTransmission for radiance: with eta the index on wi's side over wo's and
// h = normalize(wo + eta wi), (1 - F(wo . h)) D(h) G(wo, wi) |wi . h| |wo . h| / (|cos theta_i
// cos theta_o| (wo . h + eta wi . h)^2) times kt_rough. (pbrt-v3's eta^2 of the Jacobian and the
// 1 / eta^2 of radiance crossing the boundary cancel.)
Rgb Bsdf::transmission_f(const Outgoing& o, const Vec3& wi) const {
    const Vec3& wo = o.local;
    if (!(wo.z * wi.z < 0)) return {};
    const float eta = wo.z > 0 ? lobe_eta_t / lobe_eta_i : lobe_eta_i / lobe_eta_t;
    const Vec3 h = wo + wi * eta;
    if (h.x == 0 && h.y == 0 && h.z == 0) return {};
    const float l2 = dot(h, h);
    Vec3 wh = h / std::sqrt(l2);
    if (wh.z < 0) wh = -wh;
    const float oh = dot(wo, wh), ih = dot(wi, wh);
    if (oh * ih > 0) return {};
    const float fresnel = fresnel_dielectric(oh, lobe_eta_i, lobe_eta_t);
    const float denom = oh + eta * ih;
    const float r_i = anisotropic ? smith_r(wi, alpha, alpha_y) : smith_r(wi, alpha);
    const float d = anisotropic ? tr_d(h, l2, alpha, alpha_y) : tr_d(h, l2, alpha);
    // G / |cos_i cos_o| = 2 / (r_o |cos_i| + r_i |cos_o|) (smith_r).
    const float g_over_cos = 2 / (o.smith_r * std::abs(wi.z) + r_i * std::abs(wo.z));
    return kt_rough * ((1 - fresnel) * std::abs(d * g_over_cos * ih * oh / (denom * denom)));
}

Vec3 bump_normal(const Scene& scene, const TexInput& bump, const SurfaceHit& hit,
                 const TexContext& ctx, float du, float dv) {
    if (!(du > 0)) du = 0.0005f;
    if (!(dv > 0)) dv = 0.0005f;
    const Partials partials = hit.partials();
    const Vec3 &dpdu = partials.dpdu, &dpdv = partials.dpdv;
    const Vec3 n = hit.ns;
    const auto [dndu, dndv] = hit.normal_offsets(dpdu, dpdv);
    // The displacement at the point and one step along u and along v (the world point moves
    // with them, for the textures that read it).
    auto displacement = [&](float su, float sv) {
        TexContext c = ctx;
        c.u = ctx.u + su;
        c.v = ctx.v + sv;
        c.p = ctx.p + su * dpdu + sv * dpdv;
        return eval_texture(scene, bump, c).r;
    };
    const float d = displacement(0, 0);
    const float ddu = (displacement(du, 0) - d) / du, ddv = (displacement(0, dv) - d) / dv;
    const Vec3 bu = dpdu + ddu * n + d * dndu, bv = dpdv + ddv * n + d * dndv;
    Vec3 nb = cross(bu, bv);
    const float len = length(nb);
    if (!(len > 0) || !std::isfinite(len)) return n;
    nb = nb / len;
    if (dot(nb, n) < 0) nb = -nb;  // the side of the unbumped shading normal
    return faceforward(nb, hit.ng);
}

namespace {
// An index of refraction a texture gives. A constant one is checked when the scene is read; a
// texture's value that is not a positive finite number has no meaning (a negative one bent rays
// into radiance of 1e24): NaN, so the sample's radiance is not a number, counted and taken as
// black with the render's warning.
float index_of(float eta) {
    return eta > 0 && std::isfinite(eta) ? eta : std::numeric_limits<float>::quiet_NaN();
}

// The microfacet alpha of a material's roughness at a shading point (pbrt-v3's remapping, or the
// roughness itself, not below `floor`), and along v for an anisotropic one.
void set_alphas(Bsdf& b, const Scene& scene, const Material& m, const TexContext& ctx,
                float floor) {
    auto alpha_of = [&](const TexInput& in) {
        const float rough = eval_texture(scene, in, ctx).r;
        return m.remap_roughness ? roughness_to_alpha(rough) : std::max(rough, floor);
    };
    b.alpha = alpha_of(m.roughness);
    if (m.anisotropic) {
        b.alpha_y = alpha_of(m.vroughness);
        b.anisotropic = true;
    }
}
}  // namespace

std::optional<Bsdf> make_bsdf(const Scene& scene, const Material& m, const SurfaceHit& hit,
                              const TexContext& ctx) {
    std::optional<Bsdf> made;
    if (m.type == Material::Type::None) return made;
    Bsdf& b = made.emplace();
    b.frame = Frame::from_z(hit.ns);
    b.ng = hit.ng;
    switch (m.type) {
        case Material::Type::Matte: {
            b.kd = clamp0(eval_texture(scene, m.kd, ctx));
            float sigma = eval_texture(scene, m.sigma, ctx).r;
            if (sigma != 0) {
                float s = sigma * kPi / 180, s2 = s * s;
                b.on_a = 1 - s2 / (2 * (s2 + 0.33f));
                b.on_b = 0.45f * s2 / (s2 + 0.09f);
            }
            break;
        }
        case Material::Type::Plastic: {
            b.kd = clamp0(eval_texture(scene, m.kd, ctx));
            b.ks = clamp0(eval_texture(scene, m.ks, ctx));
            set_alphas(b, scene, m, ctx, -std::numeric_limits<float>::infinity());
            break;
        }
        case Material::Type::Mirror:
            b.kr = clamp0(eval_texture(scene, m.kr, ctx));
            b.fresnel_noop = true;
            break;
        case Material::Type::Glass:
        case Material::Type::Subsurface:  // (its BSSRDF is the path tracer's: Tracer::subsurface)
        case Material::Type::KdSubsurface: {
            b.kr = clamp0(eval_texture(scene, m.kr, ctx));
            b.kt = clamp0(eval_texture(scene, m.kt, ctx));
            b.eta = index_of(eval_texture(scene, m.eta, ctx).r);
            // pbrt-v3's glass is rough where its roughness is not 0 along u or v: microfacet
            // reflection (with the dielectric's Fresnel term from air to eta) and transmission
            // in place of the specular lobes.
            const bool rough_anywhere = m.roughness.node >= 0 || m.vroughness.node >= 0 ||
                                        m.roughness.value.r != 0 || m.vroughness.value.r != 0;
            if (rough_anywhere && (eval_texture(scene, m.roughness, ctx).r != 0 ||
                                   eval_texture(scene, m.vroughness, ctx).r != 0)) {
                set_alphas(b, scene, m, ctx, 1e-3f);
                b.ks = b.kr;
                b.kt_rough = b.kt;
                b.kr = b.kt = Rgb();
                b.lobe_eta_i = 1;
                b.lobe_eta_t = b.eta;
            }
            break;
        }
        case Material::Type::Translucent: {
            // pbrt-v3's translucent: Lambertian reflection and transmission (Kd times reflect and
            // transmit) and microfacet reflection and transmission into an index of 1.5 (Ks times
            // each), each lobe where its colour is not black.
            const Rgb r = clamp0(eval_texture(scene, m.kr, ctx)),
                      t = clamp0(eval_texture(scene, m.kt, ctx));
            if (r.is_black() && t.is_black()) break;
            const Rgb kd = clamp0(eval_texture(scene, m.kd, ctx)),
                      ks = clamp0(eval_texture(scene, m.ks, ctx));
            b.kd = r * kd;
            b.kt_diffuse = t * kd;
            if (!ks.is_black()) {
                set_alphas(b, scene, m, ctx, -std::numeric_limits<float>::infinity());
                b.ks = r * ks;
                b.kt_rough = t * ks;
                b.lobe_eta_i = 1;
                b.lobe_eta_t = 1.5f;
            }
            break;
        }
        case Material::Type::Substrate: {
            b.kd = clamp0(eval_texture(scene, m.kd, ctx));
            b.ks = clamp0(eval_texture(scene, m.ks, ctx));
            b.fresnel_blend = !b.kd.is_black() || !b.ks.is_black();
            set_alphas(b, scene, m, ctx, -std::numeric_limits<float>::infinity());
            break;
        }
        case Material::Type::Uber: {
            b.kd = clamp0(eval_texture(scene, m.kd, ctx));
            b.ks = clamp0(eval_texture(scene, m.ks, ctx));
            set_alphas(b, scene, m, ctx, 1e-3f);
            b.kr = clamp0(eval_texture(scene, m.kr, ctx));
            b.kt = clamp0(eval_texture(scene, m.kt, ctx));
            b.eta = index_of(eval_texture(scene, m.eta, ctx).r);
            b.lobe_eta_i = 1;  // pbrt-v3's uber: its microfacet lobe's Fresnel is air to eta
            b.lobe_eta_t = b.eta;
            if (m.opacity.node >= 0 ||
                !(m.opacity.value.r == 1 && m.opacity.value.g == 1 && m.opacity.value.b == 1)) {
                // pbrt-v3's opacity (the builder gives one only to an uber without Kr and Kt):
                // the lobes times it, the rest straight through, a transmission of index 1.
                const Rgb op = clamp0(eval_texture(scene, m.opacity, ctx));
                b.kd = b.kd * op;
                b.ks = b.ks * op;
                b.kt = clamp0(Rgb(1) - op);
                b.eta = 1;
            }
            break;
        }
        case Material::Type::Metal: {
            b.conductor = true;
            b.conductor_eta = eval_texture(scene, m.eta, ctx);
            b.conductor_k = eval_texture(scene, m.k, ctx);
            b.ks = Rgb(1);
            set_alphas(b, scene, m, ctx, 1e-3f);
            break;
        }
        case Material::Type::Fourier:
            b.fourier = m.fourier.get();
            break;
        case Material::Type::Disney: {
            // pbrt-v3's DisneyMaterial (algorithms.md §24): the lobes' weights from the base
            // colour c, metallic and (for a thin surface) flatness and difftrans.
            auto d = std::make_shared<DisneyModel>();
            const Rgb c = clamp0(eval_texture(scene, m.kd, ctx));
            const float metallic = eval_texture(scene, m.metallic, ctx).r;
            const float e = eval_texture(scene, m.eta, ctx).r;
            const float strans = eval_texture(scene, m.spec_trans, ctx).r;
            const float diffuse_weight = (1 - metallic) * (1 - strans);
            const float dt = eval_texture(scene, m.diff_trans, ctx).r / 2;
            const float rough = eval_texture(scene, m.roughness, ctx).r;
            const float lum = 0.212671f * c.r + 0.715160f * c.g + 0.072169f * c.b;
            const Rgb tint = lum > 0 ? c / lum : Rgb(1);
            const float sheen = eval_texture(scene, m.sheen, ctx).r;
            d->base = c;
            d->thin = m.thin;
            d->roughness = rough;
            if (diffuse_weight > 0) {
                d->diffuse_group = true;
                if (m.thin) {
                    const float flat = eval_texture(scene, m.flatness, ctx).r;
                    d->diffuse = c * (diffuse_weight * (1 - flat) * (1 - dt));
                    d->fake_ss = c * (diffuse_weight * flat * (1 - dt));
                } else {
                    d->diffuse = c * diffuse_weight;
                }
                d->retro = c * diffuse_weight;
                if (sheen > 0) {
                    const float st = eval_texture(scene, m.sheen_tint, ctx).r;
                    d->has_sheen = true;
                    d->sheen = (Rgb(1) * (1 - st) + tint * st) * (diffuse_weight * sheen);
                }
            }
            const float aspect =
                std::sqrt(1 - eval_texture(scene, m.disney_anisotropic, ctx).r * 0.9f);
            d->ax = std::max(0.001f, rough * rough / aspect);
            d->ay = std::max(0.001f, rough * rough * aspect);
            const float spec_tint = eval_texture(scene, m.specular_tint, ctx).r;
            const float r0 = (e - 1) * (e - 1) / ((e + 1) * (e + 1));
            d->cspec0 = (Rgb(1) * (1 - spec_tint) + tint * spec_tint) * (r0 * (1 - metallic)) +
                        c * metallic;
            d->metallic = metallic;
            d->eta = e;
            const float cc = eval_texture(scene, m.clearcoat, ctx).r;
            if (cc > 0) {
                const float gloss = eval_texture(scene, m.clearcoat_gloss, ctx).r;
                d->has_clearcoat = true;
                d->clearcoat = cc;
                d->gloss = 0.1f * (1 - gloss) + 0.001f * gloss;
            }
            if (strans > 0) {
                // Walter et al.'s transmission, its weight strans sqrt(c) (two refractions give c
                // back); a thin surface's roughness scaled by its index (Burley 2015).
                d->has_transmission = true;
                d->transmit = Rgb(std::sqrt(c.r), std::sqrt(c.g), std::sqrt(c.b)) * strans;
                const float rs = m.thin ? (0.65f * e - 0.35f) * rough : rough;
                d->tax = std::max(0.001f, rs * rs / aspect);
                d->tay = std::max(0.001f, rs * rs * aspect);
            }
            if (m.thin) d->lambert_t = c * dt;
            b.anisotropic = d->ax != d->ay;  // (the frame along dp/du, below)
            b.disney = std::move(d);
            break;
        }
        case Material::Type::Hair: {
            // pbrt-v3's hair: h = -1 + 2v across the fibre (a curve's v), roughnesses in [0, 1]
            // (from 0.001: at 0 its lobes' variances are 0, and its values not finite).
            b.hair = true;
            HairParams p;
            p.h = std::clamp(-1 + 2 * ctx.v, -1.0f, 1.0f);
            p.eta = eval_texture(scene, m.eta, ctx).r;
            p.beta_m = std::clamp(eval_texture(scene, m.beta_m, ctx).r, 1e-3f, 1.0f);
            p.beta_n = std::clamp(eval_texture(scene, m.beta_n, ctx).r, 1e-3f, 1.0f);
            p.alpha = eval_texture(scene, m.hair_alpha, ctx).r;
            switch (m.hair_absorption) {
                case Material::HairAbsorption::SigmaA:
                    p.sigma_a = clamp0(eval_texture(scene, m.hair_sigma_a, ctx));
                    break;
                case Material::HairAbsorption::Colour:
                    p.sigma_a = hair_sigma_a_from_reflectance(
                        clamp0(eval_texture(scene, m.hair_colour, ctx)), p.beta_n);
                    break;
                case Material::HairAbsorption::Concentration:
                    p.sigma_a = hair_sigma_a_from_concentration(
                        std::max(0.0f, eval_texture(scene, m.eumelanin, ctx).r),
                        std::max(0.0f, eval_texture(scene, m.pheomelanin, ctx).r));
                    break;
            }
            b.hair_model = HairModel(p);
            break;
        }
        case Material::Type::None:
        case Material::Type::Mix:  // the integrator resolves its materials (material_bsdf)
            made.reset();
            return made;
    }
    if (b.anisotropic || b.hair) {
        // pbrt-v3's shading frame: s along dp/du in the shading plane (its sign, which pbrt-v3's
        // triangles with normals turn, does not change the distribution), t = n x s. Where dp/du
        // has no direction in that plane the frame stays an arbitrary one.
        const Vec3 dpdu = hit.partials().dpdu;
        const Vec3 s = dpdu - dot(dpdu, hit.ns) * hit.ns;
        const float len = length(s);
        if (len > 0 && std::isfinite(len)) {
            b.frame.s = s / len;
            b.frame.t = cross(hit.ns, b.frame.s);
        }
    }
    return made;
}

}  // namespace cmam::render
