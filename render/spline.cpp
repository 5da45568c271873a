#include "render/spline.h"

#include <cmath>

namespace cmam::render {

bool spline_weights(int size, const float* nodes, float x, int* offset, float w[4]) {
    if (!(x >= nodes[0] && x <= nodes[size - 1])) return false;
    const int i = last_below(size, [&](int k) { return nodes[k] <= x; });
    *offset = i - 1;
    const float x0 = nodes[i], x1 = nodes[i + 1];
    const float t = x1 > x0 ? (x - x0) / (x1 - x0) : 0.0f, t2 = t * t, t3 = t2 * t;
    // Hermite basis: values at t = 0 and 1, then the derivatives' terms.
    w[0] = 0;
    w[1] = 2 * t3 - 3 * t2 + 1;
    w[2] = -2 * t3 + 3 * t2;
    w[3] = 0;
    const float d0 = t3 - 2 * t2 + t, d1 = t3 - t2;  // times the derivative at x0, at x1
    if (i > 0 && x1 > nodes[i - 1]) {  // derivative at x0: (f(x1) - f(x_{-1})) / (x1 - x_{-1})
        const float s = d0 * (x1 - x0) / (x1 - nodes[i - 1]);
        w[0] -= s;
        w[2] += s;
    } else {  // one-sided: f(x1) - f(x0)
        w[1] -= d0;
        w[2] += d0;
    }
    if (i + 2 < size && nodes[i + 2] > x0) {  // derivative at x1: (f(x2) - f(x0)) / (x2 - x0)
        const float s = d1 * (x1 - x0) / (nodes[i + 2] - x0);
        w[1] -= s;
        w[3] += s;
    } else {
        w[1] -= d1;
        w[2] += d1;
    }
    return true;
}

float sample_spline(int size2, const float* nodes2, const float* values, const float* cdf,
                    int offset, const float w[4], float u, float* fval, float* pdf) {
    *pdf = 0;
    if (fval) *fval = 0;
    const int n = size2;
    auto at = [&](const float* table, int i) {
        float v = 0;
        for (int k = 0; k < 4; ++k)
            if (w[k] != 0) v += table[std::size_t(offset + k) * n + i] * w[k];
        return v;
    };
    const float total = at(cdf, n - 1);
    if (!(total > 0)) return 0;
    u *= total;
    const int i = last_below(n, [&](int k) { return at(cdf, k) <= u; });
    const float f0 = at(values, i), f1 = at(values, i + 1);
    const float x0 = nodes2[i], x1 = nodes2[i + 1], width = x1 - x0;
    if (!(width > 0)) return 0;
    u = (u - at(cdf, i)) / width;
    // The segment's end derivatives (per unit t), by finite differences as the spline's.
    const float d0 = i > 0 && x1 > nodes2[i - 1]
                         ? width * (f1 - at(values, i - 1)) / (x1 - nodes2[i - 1])
                         : f1 - f0;
    const float d1 = i + 2 < n && nodes2[i + 2] > x0
                         ? width * (at(values, i + 2) - f0) / (nodes2[i + 2] - x0)
                         : f1 - f0;
    // The first guess: the same inversion for the linear interpolant.
    float s = f0 != f1 ? (f0 - std::sqrt(std::max(0.0f, f0 * f0 + 2 * u * (f1 - f0)))) / (f0 - f1)
                       : u / f0;
    float lo = 0, hi = 1, F = 0, f = 0;
    for (int iter = 0; iter < 100; ++iter) {
        if (!(s >= lo && s <= hi)) s = 0.5f * (lo + hi);
        // The cubic and its integral from 0, in Horner form.
        F = s * (f0 + s * (0.5f * d0 + s * ((1.0f / 3) * (-2 * d0 - d1) + f1 - f0 +
                                            s * (0.25f * (d0 + d1) + 0.5f * (f0 - f1)))));
        f = f0 + s * (d0 + s * (-2 * d0 - d1 + 3 * (f1 - f0) + s * (d0 + d1 + 2 * (f0 - f1))));
        if (std::abs(F - u) < 1e-6f || hi - lo < 1e-6f) break;
        if (F - u < 0)
            lo = s;
        else
            hi = s;
        s -= (F - u) / f;
    }
    if (fval) *fval = f;
    *pdf = f / total;
    return x0 + width * s;
}

namespace {
// The end derivatives (per unit t) of segment i of the spline through values at x.
void segment_slopes(int n, const float* x, const float* values, int i, float& d0, float& d1) {
    const float width = x[i + 1] - x[i], f0 = values[i], f1 = values[i + 1];
    d0 = i > 0 ? width * (f1 - values[i - 1]) / (x[i + 1] - x[i - 1]) : f1 - f0;
    d1 = i + 2 < n ? width * (values[i + 2] - f0) / (x[i + 2] - x[i]) : f1 - f0;
}
}  // namespace

float integrate_spline(int n, const float* x, const float* values, float* cdf) {
    float sum = 0;
    cdf[0] = 0;
    for (int i = 0; i + 1 < n; ++i) {
        float d0, d1;
        segment_slopes(n, x, values, i, d0, d1);
        // The Hermite cubic's integral over the segment: width ((f0 + f1) / 2 + (d0 - d1) / 12).
        sum += ((d0 - d1) * (1.0f / 12) + (values[i] + values[i + 1]) * 0.5f) * (x[i + 1] - x[i]);
        cdf[i + 1] = sum;
    }
    return sum;
}

float invert_spline(int n, const float* x, const float* values, float u) {
    if (!(u > values[0])) return x[0];
    if (!(u < values[n - 1])) return x[n - 1];
    const int i = last_below(n, [&](int k) { return values[k] <= u; });
    const float f0 = values[i], f1 = values[i + 1];
    float d0, d1;
    segment_slopes(n, x, values, i, d0, d1);
    // Newton's method on the segment's cubic, bisection where a step leaves the bracket.
    float lo = 0, hi = 1, t = 0.5f;
    for (int iter = 0; iter < 100; ++iter) {
        if (!(t > lo && t < hi)) t = 0.5f * (lo + hi);
        const float t2 = t * t, t3 = t2 * t;
        const float F = (2 * t3 - 3 * t2 + 1) * f0 + (-2 * t3 + 3 * t2) * f1 +
                        (t3 - 2 * t2 + t) * d0 + (t3 - t2) * d1;
        const float f = (6 * t2 - 6 * t) * f0 + (-6 * t2 + 6 * t) * f1 + (3 * t2 - 4 * t + 1) * d0 +
                        (3 * t2 - 2 * t) * d1;
        if (std::abs(F - u) < 1e-6f || hi - lo < 1e-6f) break;
        if (F - u < 0)
            lo = t;
        else
            hi = t;
        t -= (F - u) / f;
    }
    return x[i] + t * (x[i + 1] - x[i]);
}

}  // namespace cmam::render
