// render — participating media (medium.h; docs/algorithms.md §19).
#include "render/medium.h"

namespace cmam::render {

float hg_sample(const Vec3& wo, float g, float u1, float u2, Vec3& wi) {
    // mu: the cosine between wi and the direction the ray travelled, -wo, which the
    // Henyey–Greenstein distribution gives by inverting its cumulative distribution in mu
    // (uniform where g is about 0).
    float mu;
    if (std::abs(g) < 1e-3f) {
        mu = 1 - 2 * u1;
    } else {
        const float s = (1 - g * g) / (1 - g + 2 * g * u1);
        mu = (1 + g * g - s * s) / (2 * g);
    }
    mu = std::clamp(mu, -1.0f, 1.0f);
    const float sin_t = std::sqrt(std::max(0.0f, 1 - mu * mu)), phi = 2 * kPi * u2;
    const Frame f = Frame::from_z(-wo);
    wi = f.to_world(Vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), mu));
    return hg_phase(-mu, g);
}

float Medium::density_at(const Vec3& p) const {
    // Samples at the cells' centres: continuous index p n - 1/2.
    const float x = p.x * float(nx) - 0.5f, y = p.y * float(ny) - 0.5f, z = p.z * float(nz) - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    if (!(fx >= -1 && fy >= -1 && fz >= -1 && fx < float(nx) && fy < float(ny) && fz < float(nz)))
        return 0;  // (NaN too) beyond every sample's reach
    const int ix = int(fx), iy = int(fy), iz = int(fz);
    const float dx = x - fx, dy = y - fy, dz = z - fz;
    auto at = [&](int i, int j, int k) {
        if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return 0.0f;
        return density[(static_cast<std::size_t>(k) * ny + j) * nx + i];
    };
    auto lerp = [](float t, float a, float b) { return (1 - t) * a + t * b; };
    const float d00 = lerp(dx, at(ix, iy, iz), at(ix + 1, iy, iz));
    const float d10 = lerp(dx, at(ix, iy + 1, iz), at(ix + 1, iy + 1, iz));
    const float d01 = lerp(dx, at(ix, iy, iz + 1), at(ix + 1, iy, iz + 1));
    const float d11 = lerp(dx, at(ix, iy + 1, iz + 1), at(ix + 1, iy + 1, iz + 1));
    return lerp(dz, lerp(dy, d00, d10), lerp(dy, d01, d11));
}

void Medium::build_majorants() {
    const int n[3] = {nx, ny, nz};
    int res[3];
    for (int a = 0; a < 3; ++a) res[a] = std::min(n[a], 16);
    mx = res[0];
    my = res[1];
    mz = res[2];
    majorant.assign(static_cast<std::size_t>(mx) * my * mz, 0.0f);
    // The samples density_at may read in a cell [c/res, (c+1)/res] along an axis: those whose
    // indices are floor(x n - 1/2) and one more for x in it, with one more on each side for
    // rounding at the cell's faces.
    auto span = [&](int a, int c, int& lo, int& hi) {
        lo = std::max(0, int(std::floor(float(c) / float(res[a]) * float(n[a]) - 0.5f)) - 1);
        hi = std::min(n[a] - 1,
                      int(std::floor(float(c + 1) / float(res[a]) * float(n[a]) - 0.5f)) + 2);
    };
    for (int k = 0; k < mz; ++k)
        for (int j = 0; j < my; ++j)
            for (int i = 0; i < mx; ++i) {
                int x0, x1, y0, y1, z0, z1;
                span(0, i, x0, x1);
                span(1, j, y0, y1);
                span(2, k, z0, z1);
                float mx_d = 0;
                for (int z = z0; z <= z1; ++z)
                    for (int y = y0; y <= y1; ++y)
                        for (int x = x0; x <= x1; ++x)
                            mx_d = std::max(
                                mx_d, density[(static_cast<std::size_t>(z) * ny + y) * nx + x]);
                majorant[(static_cast<std::size_t>(k) * my + j) * mx + i] = mx_d;
            }
}

}  // namespace cmam::render
