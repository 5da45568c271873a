// fuzz — the filtering library's entry points on arbitrary footprints, decoded from the input:
// a small texture (size, channels, wrap modes, texels), then a sequence of operations, each
// FilteredTexture::lookup (every FilterKind, every footprint kind), cmam_lookup (options, tags
// and a cache shared by the sequence), RowPrefixTable::integral or polygon_integral, with
// coordinates that may be huge, tiny, infinite or not numbers. Lookups must return finite
// values (the texels are finite); the integrals must not crash.
#include <cmam/texture/area.h>
#include <cmam/texture/cmam.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/polygon.h>
#include <cmam/texture/sat.h>
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

namespace tx = cmam::texture;

namespace {

/// A coordinate: mostly moderate values, sometimes not a number, infinite, tiny or anything.
double number(FuzzedDataProvider& in, double scale = 1) {
    switch (in.ConsumeIntegralInRange(0, 9)) {
        case 0:
            return std::numeric_limits<double>::quiet_NaN();
        case 1:
            return in.ConsumeBool() ? HUGE_VAL : -HUGE_VAL;
        case 2:
            return in.ConsumeFloatingPoint<double>();
        case 3:
            return in.ConsumeFloatingPointInRange(-1e-6, 1e-6) * scale;
        case 4:
            return in.ConsumeFloatingPointInRange(-1e6, 1e6) * scale;
        default:
            return in.ConsumeFloatingPointInRange(-4.0, 4.0) * scale;
    }
}

tx::Vec2d vec(FuzzedDataProvider& in, double scale = 1) {
    const double u = number(in, scale);
    return {u, number(in, scale)};
}

tx::Footprint footprint(FuzzedDataProvider& in) {
    tx::Footprint fp;
    switch (in.ConsumeIntegralInRange(0, 2)) {
        case 0:
            return tx::Footprint::none();
        case 1: {
            const tx::Vec2d a = vec(in, 0.25);
            return tx::Footprint::axes(a, vec(in, 0.25));
        }
        default:
            fp.kind = tx::Footprint::Kind::Points;
            fp.point_count = in.ConsumeIntegralInRange(0, 3);
            for (int i = 0; i < fp.point_count; ++i) fp.points[i] = vec(in);
            return fp;
    }
}

tx::FilterKind filter_kind(FuzzedDataProvider& in) {
    return static_cast<tx::FilterKind>(in.ConsumeIntegralInRange(0, tx::kFilterKinds - 1));
}

/// A polygon in texel space: the convex hull of 3 to 8 points when they are all finite and
/// within 2^30 texels (RowPrefixTable::integral's precondition: convex), else the points as
/// they are (the entry points' range check).
tx::Polygon polygon(FuzzedDataProvider& in, double texels) {
    const int n = in.ConsumeIntegralInRange(3, 8);
    std::vector<tx::Vec2d> points;
    bool in_range = true;
    for (int i = 0; i < n; ++i) {
        tx::Vec2d p = vec(in, texels);
        // The integrals cost O(perimeter in texels): a finite vertex is kept within 2^12 texels
        // (beyond 2^30 the entry points take the mean at once, as they do for NaN).
        for (double* c : {&p.u, &p.v})
            if (std::isfinite(*c) && std::abs(*c) < 0x1p30) *c = std::fmod(*c, 0x1p12);
        points.push_back(p);
        in_range = in_range && std::abs(p.u) < 0x1p30 && std::abs(p.v) < 0x1p30;
    }
    return in_range ? tx::convex_hull(points) : points;
}

void check_finite(const tx::Texel& t, int channels, const char* what) {
    for (int c = 0; c < channels; ++c)
        if (!std::isfinite(t[c])) {
            std::fprintf(stderr, "%s returned a value that is not finite: %g\n", what, t[c]);
            std::abort();
        }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    FuzzedDataProvider in(data, size);
    const int w = in.ConsumeIntegralInRange(1, 16), h = in.ConsumeIntegralInRange(1, 16);
    const int channels = in.ConsumeIntegralInRange(1, 4);
    const auto wrap_s = static_cast<tx::WrapMode>(in.ConsumeIntegralInRange(0, 3));
    const auto wrap_t = static_cast<tx::WrapMode>(in.ConsumeIntegralInRange(0, 3));
    std::vector<float> texels(static_cast<std::size_t>(w) * h * channels);
    for (float& t : texels) t = in.ConsumeIntegral<uint8_t>() / 255.0f;
    const tx::FilteredTexture texture(tx::Image(w, h, channels, texels, wrap_s, wrap_t));
    const tx::SummedAreaTable sat(texture.image(),
                                  in.ConsumeBool() ? tx::SummedAreaTable::Storage::Double
                                                   : tx::SummedAreaTable::Storage::MeanOffsetFloat);

    tx::CmamOptions cmam;
    cmam.filter = filter_kind(in);
    cmam.miss = static_cast<tx::CmamMiss>(in.ConsumeIntegralInRange(0, 1));
    cmam.ellipse = static_cast<tx::CmamEllipse>(in.ConsumeIntegralInRange(0, 2));
    cmam.sat_miss = static_cast<tx::CmamSatMiss>(in.ConsumeIntegralInRange(0, 1));
    cmam.sat_box = static_cast<tx::CmamSatBox>(in.ConsumeIntegralInRange(0, 1));
    cmam.max_aniso = in.ConsumeFloatingPointInRange(1.0, 64.0);
    cmam.adjacent_only = in.ConsumeBool();
    cmam.hull = in.ConsumeBool();
    cmam.two_d = in.ConsumeBool();
    tx::CmamCache cache;

    const double texel_scale = std::max(w, h);
    for (int op = 0; op < 64 && in.remaining_bytes() > 0; ++op) {
        switch (in.ConsumeIntegralInRange(0, 3)) {
            case 0: {
                tx::FilterOptions opts;
                opts.kind = filter_kind(in);
                opts.max_aniso = in.ConsumeFloatingPointInRange(1.0, 64.0);
                opts.pbrt_trilinear_width = in.ConsumeBool();
                opts.ellipse = static_cast<tx::CmamEllipse>(in.ConsumeIntegralInRange(0, 2));
                opts.sat_box = static_cast<tx::CmamSatBox>(in.ConsumeIntegralInRange(0, 1));
                const tx::Footprint fp = footprint(in);
                const double u = number(in), v = number(in);
                check_finite(texture.lookup_with_info(u, v, fp, opts).value, channels,
                             "FilteredTexture::lookup");
                break;
            }
            case 1: {
                tx::RayTag tag;
                tag.id = in.ConsumeIntegralInRange(0, 3);
                tag.level = in.ConsumeIntegralInRange(0, 2);
                tag.seq = in.ConsumeIntegralInRange(0, 7);
                tag.positioned = in.ConsumeBool();
                tag.x = static_cast<float>(in.ConsumeFloatingPointInRange(-1.0, 17.0));
                tag.y = static_cast<float>(in.ConsumeFloatingPointInRange(-1.0, 17.0));
                const double u = number(in), v = number(in);
                check_finite(tx::cmam_lookup_with_info(texture, cache, tag, u, v, cmam).value,
                             channels, "cmam_lookup");
                break;
            }
            case 2: {
                const tx::Polygon p = polygon(in, texel_scale);
                if (p.size() < 3) break;
                const int level = in.ConsumeIntegralInRange(0, texture.pyramid().levels() - 1);
                texture.row_prefix(level).integral(p.data(), static_cast<int>(p.size()));
                break;
            }
            default: {
                const tx::Polygon p = polygon(in, texel_scale);
                if (p.size() >= 3) tx::polygon_integral(sat, p);
                break;
            }
        }
    }
    return 0;
}
