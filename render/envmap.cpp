#include "render/envmap.h"

#include <cmam/texture/filters.h>

#include <algorithm>
#include <numbers>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "render/huge_pages.h"

namespace cmam::render {

namespace {
// std::max(a, b) (b if a < b, else a) as one instruction: the profile-guided build otherwise
// turns the maxima of a map's cells into branches (they were predictable on its training map),
// which mispredict on a real map's texels (the weights of a 1500-pixel map took 4.7 times as
// long).
inline float max_of(float a, float b) {
#if defined(__SSE2__)
    return _mm_cvtss_f32(_mm_max_ss(_mm_set_ss(b), _mm_set_ss(a)));
#else
    return std::max(a, b);
#endif
}
}  // namespace

std::size_t Distribution1D::table_bytes(std::size_t n) {
    return (n + (n + 1)) * sizeof(float) + guide_count(n) * sizeof(uint32_t);
}

Distribution1D::Distribution1D(std::vector<float> weights)
    : m_own(std::make_unique<std::byte[]>(table_bytes(weights.size()))) {
    build(weights.data(), weights.size(), m_own.get());
}

Distribution1D::Distribution1D(const float* weights, std::size_t n, std::byte* storage) {
    build(weights, n, storage);
}

void Distribution1D::build(const float* weights, std::size_t n, std::byte* storage) {
    m_n = n;
    m_guides = guide_count(n);
    float* func = reinterpret_cast<float*>(storage);
    float* cdf = func + n;
    uint32_t* guide = reinterpret_cast<uint32_t*>(cdf + n + 1);
    m_func = func;
    m_cdf = cdf;
    m_guide = guide;
    std::copy_n(weights, n, func);
    std::vector<double> sums(n + 1, 0.0);
    for (std::size_t i = 0; i < n; ++i)
        sums[i + 1] = sums[i] + double(std::max(0.0f, func[i])) / double(n);
    m_integral = sums[n];
    for (std::size_t i = 0; i <= n; ++i)
        cdf[i] = float(m_integral > 0 ? sums[i] / m_integral : double(i) / double(n));
    if (n) cdf[n] = 1;
    // The guide: entry g is the cell holding g / guides, so that sample() starts next to its
    // cell instead of searching the whole table.
    const std::size_t guides = m_guides;
    std::size_t k = 0;
    for (std::size_t g = 0; g < guides; ++g) {
        const float at = float(double(g) / double(guides));
        while (k + 1 < n && !(at < cdf[k + 1])) ++k;
        guide[g] = static_cast<uint32_t>(k);
    }
}

float Distribution1D::pdf(int cell) const {
    if (m_integral <= 0) return 1;  // uniform
    return float(std::max(0.0f, m_func[static_cast<std::size_t>(cell)]) / m_integral);
}

Distribution1D::Sample Distribution1D::sample(float u) const {
    // The last cell whose cdf start is at or below u (cells of zero weight are never chosen:
    // their start equals the next cell's), clamped to the cells: what std::upper_bound gives,
    // found from the guide's entry for u by a short walk (about kCellsPerGuide cells on average,
    // on one or two cache lines, where a binary search over an environment map's row touched a
    // dozen, with a branch each that no predictor could follow). The walk back covers a guide
    // index rounded up. algorithms.md §13.
    const int n = size();
    std::size_t k = m_guide[guide_of(u)];
    __builtin_prefetch(m_func + k);  // pdf() reads the cell's, a few cells on at most
    while (k > 0 && u < m_cdf[k]) --k;
    while (k + 1 < static_cast<std::size_t>(n) && !(u < m_cdf[k + 1])) ++k;
    const double width = double(m_cdf[k + 1]) - m_cdf[k];
    const double t = width > 0 ? (double(u) - m_cdf[k]) / width : 0.5;
    const int cell = static_cast<int>(k);
    return {std::min(float((cell + std::clamp(t, 0.0, 1.0)) / n), 0x1.fffffep-1f), pdf(cell), cell};
}

void Distribution2D::FreeTables::operator()(std::byte* p) const noexcept {
    free_huge(p);
}

Distribution2D::Distribution2D(int nu, int nv,
                               const std::function<void(int, float*)>& row_weights) {
    const std::size_t n = static_cast<std::size_t>(std::max(nu, 0)),
                      rows = static_cast<std::size_t>(std::max(nv, 0)),
                      row_bytes = Distribution1D::table_bytes(n);
    m_tables.reset(static_cast<std::byte*>(allocate_huge(rows * row_bytes)));
    std::vector<float> marginal(rows), row(n);
    m_rows.reserve(rows);
    for (std::size_t v = 0; v < rows; ++v) {
        row_weights(static_cast<int>(v), row.data());
        m_rows.emplace_back(row.data(), n, m_tables.get() + v * row_bytes);
        marginal[v] = float(m_rows.back().integral());
    }
    m_marginal = Distribution1D(std::move(marginal));
}

void Distribution2D::sample(const float* u1, const float* u2, int n, Sample* out) const {
    for (int i0 = 0; i0 < n; i0 += kSampleBatch) {
        const int m = std::min(kSampleBatch, n - i0);
        Distribution1D::Sample v[kSampleBatch];
        for (int i = 0; i < m; ++i) v[i] = m_marginal.sample(u2[i0 + i]);
        for (int i = 0; i < m; ++i)
            m_rows[static_cast<std::size_t>(v[i].cell)].prefetch(u1[i0 + i]);
        for (int i = 0; i < m; ++i) out[i0 + i] = finish(v[i], u1[i0 + i]);
    }
}

float Distribution2D::pdf(float u, float v) const {
    const int nv = m_marginal.size(), nu = m_rows.empty() ? 0 : m_rows[0].size();
    if (nv == 0) return 0;
    const int row = std::clamp(static_cast<int>(v * nv), 0, nv - 1);
    const int col = std::clamp(static_cast<int>(u * nu), 0, nu - 1);
    return m_marginal.pdf(row) * m_rows[static_cast<std::size_t>(row)].pdf(col);
}

namespace {

Vec3 transform3(const std::array<float, 9>& m, const Vec3& v) {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
}

std::array<float, 9> inverse3(const std::array<float, 9>& m) {
    const double a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], f = m[5], g = m[6], h = m[7],
                 i = m[8];
    const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    const double det = a * A + b * B + c * C;
    if (det == 0) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double k = 1 / det;
    return {float(A * k), float(-(b * i - c * h) * k), float((b * f - c * e) * k),
            float(B * k), float((a * i - c * g) * k),  float(-(a * f - c * d) * k),
            float(C * k), float(-(a * h - b * g) * k), float((a * e - b * d) * k)};
}

}  // namespace

EnvironmentMap::EnvironmentMap(std::shared_ptr<const texture::FilteredTexture> image,
                               const std::array<float, 9>& light_from_world)
    : m_image(std::move(image)),
      m_light_from_world(light_from_world),
      m_world_from_light(inverse3(light_from_world)) {
    // One cell per texel, in the map's own order (row 0 at theta = 0). The bilinear
    // reconstruction inside a texel's cell blends it with its eight neighbours, and its largest
    // value there is at one of nine points: the centre, the edges' midpoints or the corners.
    // Weighting each cell by that maximum gives every direction with radiance a non-zero density,
    // so the estimate is unbiased; sin(theta) turns the (u,v) density into one over the sphere.
    const texture::Image& img = m_image->image();
    const int W = img.width(), H = img.height(), ch = img.channels();
    // The luminance of image rows (clamped at 0), three at a time: a distribution row reads its
    // image row and the two beside it (wrapped), and the rows go from the image's top down, so
    // each image row is computed about once, with no map-sized copy.
    struct LumRow {
        int j = -1;
        std::vector<float> y;
    };
    std::array<LumRow, 3> slots;
    auto lum_rows = [&](const std::array<int, 3>& want) {
        std::array<const float*, 3> out{};
        for (int k = 0; k < 3; ++k) {
            LumRow* have = nullptr;
            for (LumRow& s : slots)
                if (s.j == want[k]) have = &s;
            if (!have) {  // a slot none of the three wants
                for (LumRow& s : slots)
                    if (s.j != want[0] && s.j != want[1] && s.j != want[2]) have = &s;
                have->j = want[k];
                have->y.resize(static_cast<std::size_t>(W));
                for (int i = 0; i < W; ++i) {
                    const float* t = img.texel(i, want[k]);
                    const float y = ch >= 3 ? Rgb(t[0], t[1], t[2]).luminance() : t[0];
                    have->y[static_cast<std::size_t>(i)] = max_of(0.0f, y);
                }
            }
            out[static_cast<std::size_t>(k)] = have->y.data();
        }
        return out;
    };
    m_dist = Distribution2D(W, H, [&](int r, float* weights) {
        const int j = H - 1 - r;  // image row of distribution row r
        const auto [below, row, above] = lum_rows({(j - 1 + H) % H, j, (j + 1) % H});
        const float sin_theta = std::sin(kPi * (r + 0.5f) / H);
        for (int i = 0; i < W; ++i) {
            const int side[2] = {i == 0 ? W - 1 : i - 1, i == W - 1 ? 0 : i + 1};  // i -+ 1
            const float* beside[2] = {below, above};                               // j -+ 1
            const float c = row[i];
            float m = c;
            for (int dj = 0; dj < 2; ++dj)
                for (int di = 0; di < 2; ++di) {
                    const float side_u = row[side[di]], side_v = beside[dj][i];
                    const float corner = 0.25f * (c + side_u + side_v + beside[dj][side[di]]);
                    m = max_of(max_of(max_of(m, 0.5f * (c + side_u)), 0.5f * (c + side_v)), corner);
                }
            weights[i] = m * sin_theta;
        }
    });
}

Rgb EnvironmentMap::at(float s, float theta_over_pi) const {
    // The image is stored bottom row first; theta = 0 is the file's top row.
    const texture::Texel x = texture::bilinear(m_image->image(), s, 1.0 - theta_over_pi);
    if (m_image->image().channels() == 1) return Rgb(x[0]);
    return {x[0], x[1], x[2]};
}

Rgb EnvironmentMap::radiance(const Vec3& dir, const Vec3* dddx, const Vec3* dddy) const {
    const Vec3 q = transform3(m_light_from_world, dir);
    const float len = length(q);
    const Vec3 w = q / len;
    const float theta = std::acos(std::clamp(w.z, -1.0f, 1.0f));
    float phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2 * kPi;
    const float rho2 = w.x * w.x + w.y * w.y;
    if (!dddx || !dddy || !(rho2 > 1e-12f)) return at(phi / (2 * kPi), theta / kPi);
    // The footprint's axes: (s,t) = (phi / 2 pi, 1 - theta / pi) differentiated along the unit
    // light-space direction's derivatives, d(q/|q|) = (dq - (w.dq) w) / |q|.
    texture::Vec2d axis[2];
    const Vec3* dd[2] = {dddx, dddy};
    for (int k = 0; k < 2; ++k) {
        const Vec3 dq = transform3(m_light_from_world, *dd[k]);
        const Vec3 dw = (dq - dot(w, dq) * w) / len;
        const double dphi = (double(w.x) * dw.y - double(w.y) * dw.x) / rho2;
        const double dtheta = -double(dw.z) / std::sqrt(double(rho2));  // sin(theta) = rho
        axis[k] = {dphi / (2 * std::numbers::pi), -dtheta / std::numbers::pi};
    }
    const texture::Texel x = m_image->lookup(phi / (2 * kPi), 1.0 - theta / kPi,
                                             texture::Footprint::axes(axis[0], axis[1]), m_filter);
    if (m_image->image().channels() == 1) return Rgb(x[0]);
    return {x[0], x[1], x[2]};
}

EnvironmentMap::Sample EnvironmentMap::sample(float u1, float u2) const {
    if (m_dist.empty()) return {};
    // Once the row and the cell its walk starts from are known, the texels around them, which the
    // radiance's bilinear read takes (the walk ends a few cells on at most), are asked of the
    // cache: a large map's misses there then overlap the walk's instead of following them.
    const Distribution2D::Start s = m_dist.start(u1, u2);
    const texture::Image& img = m_image->image();
    const int j = img.height() - 1 - s.v.cell;  // the image row of distribution row v
    const int i0 = std::max(s.cell - 1, 0), i1 = std::min(s.cell + 3, img.width() - 1);
    for (int dj = -1; dj <= 1; ++dj)
        if (j + dj >= 0 && j + dj < img.height()) {
            __builtin_prefetch(img.texel(i0, j + dj));
            __builtin_prefetch(img.texel(i1, j + dj));
        }
    const Distribution2D::Sample d = m_dist.finish(s.v, u1);
    return direction_of(d, d.pdf != 0 ? at(d.uv[0], d.uv[1]) : Rgb());
}

void EnvironmentMap::sample(const float* u1, const float* u2, int n, Sample* out) const {
    if (m_dist.empty()) {
        std::fill(out, out + n, Sample{});
        return;
    }
    Distribution2D::Sample d[kSampleBatch];
    for (int i0 = 0; i0 < n; i0 += kSampleBatch) {
        const int m = std::min(kSampleBatch, n - i0);
        m_dist.sample(u1 + i0, u2 + i0, m, d);
        // The radiances (each a read at a random place in the image) together, then the rest.
        Rgb radiance[kSampleBatch];
        for (int i = 0; i < m; ++i)
            if (d[i].pdf != 0) radiance[i] = at(d[i].uv[0], d[i].uv[1]);
        for (int i = 0; i < m; ++i) out[i0 + i] = direction_of(d[i], radiance[i]);
    }
}

// The world direction and density of a point the distribution drew, with its radiance.
EnvironmentMap::Sample EnvironmentMap::direction_of(const Distribution2D::Sample& d,
                                                    const Rgb& radiance) const {
    const auto [uv, map_pdf] = d;
    if (map_pdf == 0) return {};
    const float theta = uv[1] * kPi, phi = uv[0] * 2 * kPi;
    const float sin_theta = std::sin(theta);
    if (sin_theta == 0) return {};
    // d(omega) = sin(theta) dtheta dphi = 2 pi^2 sin(theta) du dv.
    Sample s;
    s.pdf = map_pdf / (2 * kPi * kPi * sin_theta);
    s.wi =
        normalize(transform3(m_world_from_light, Vec3(sin_theta * std::cos(phi),
                                                      sin_theta * std::sin(phi), std::cos(theta))));
    s.radiance = radiance;
    return s;
}

float EnvironmentMap::pdf(const Vec3& dir) const {
    if (m_dist.empty()) return 0;
    const Vec3 w = normalize(transform3(m_light_from_world, dir));
    const float theta = std::acos(std::clamp(w.z, -1.0f, 1.0f));
    const float sin_theta = std::sin(theta);
    if (sin_theta == 0) return 0;
    float phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2 * kPi;
    return m_dist.pdf(phi / (2 * kPi), theta / kPi) / (2 * kPi * kPi * sin_theta);
}

Rgb LightImage::scale(const Vec3& w) const {
    Vec3 q = transform3(light_from_world, w);
    float s, t;  // from the file's top-left corner
    if (kind == Kind::Goniometric) {
        q = normalize(Vec3(q.x, q.z, q.y));
        float phi = std::atan2(q.y, q.x);
        if (phi < 0) phi += 2 * kPi;
        s = phi / (2 * kPi);
        t = std::acos(std::clamp(q.z, -1.0f, 1.0f)) / kPi;
    } else {
        constexpr float kHither = 1e-3f;
        if (!(q.z >= kHither)) return {};
        const float x = q.x / (q.z * tan_half_fov), y = q.y / (q.z * tan_half_fov);
        if (x < screen[0] || x > screen[1] || y < screen[2] || y > screen[3]) return {};
        s = (x - screen[0]) / (screen[1] - screen[0]);
        t = (y - screen[2]) / (screen[3] - screen[2]);
    }
    const texture::Texel x = texture::bilinear(image->image(), s, 1.0 - t);
    if (image->image().channels() == 1) return Rgb(x[0]);
    return {x[0], x[1], x[2]};
}

}  // namespace cmam::render
