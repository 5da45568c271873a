#include "render/pixel_filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cmam::render {

namespace {
float sinc(float x) {
    x = std::abs(x);
    if (x < 1e-5f) return 1;
    const float px = std::numbers::pi_v<float> * x;
    return std::sin(px) / px;
}
}  // namespace

float PixelFilter::factor(float x, float r) const {
    switch (kind) {
        case Kind::Box:
            return 1;
        case Kind::Gaussian:
            // exp(-alpha x^2) less its value at the radius, so the filter ends at zero there.
            return std::max(0.0f, std::exp(-alpha * x * x) - std::exp(-alpha * r * r));
        case Kind::Mitchell: {
            // Mitchell and Netravali's cubic over [-2, 2], stretched to the radius.
            const float t = std::abs(2 * (x * (1 / r)));
            if (t > 1)
                return ((-b - 6 * c) * t * t * t + (6 * b + 30 * c) * t * t +
                        (-12 * b - 48 * c) * t + (8 * b + 24 * c)) *
                       (1.0f / 6);
            return ((12 - 9 * b - 6 * c) * t * t * t + (-18 + 12 * b + 6 * c) * t * t +
                    (6 - 2 * b)) *
                   (1.0f / 6);
        }
        case Kind::Sinc:  // windowed by Lanczos's sinc(x / tau)
            return std::abs(x) > r ? 0.0f : sinc(x) * sinc(x / tau);
        case Kind::Triangle:
            return std::max(0.0f, r - std::abs(x));
    }
    return 0;
}

void PixelFilter::tabulate() {
    for (int i = 0; i < kTableSize; ++i) {
        table_x[static_cast<std::size_t>(i)] = factor((i + 0.5f) * rx / kTableSize, rx);
        table_y[static_cast<std::size_t>(i)] = factor((i + 0.5f) * ry / kTableSize, ry);
    }
}

}  // namespace cmam::render
