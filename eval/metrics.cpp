#include "eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "eval/error.h"

namespace cmam::eval {

namespace {

void require_same_size(const std::vector<float>& ref, const std::vector<float>& img) {
    if (ref.size() != img.size() || ref.size() % 3 != 0)
        throw EvalError("images differ in size (" + std::to_string(ref.size() / 3) + " vs " +
                        std::to_string(img.size() / 3) + " pixels)");
}

}  // namespace

ErrorStats compare(const std::vector<float>& ref, const std::vector<float>& img,
                   const std::vector<bool>* mask) {
    require_same_size(ref, img);
    if (mask && mask->size() * 3 != ref.size())
        throw EvalError("mask size does not match the image");
    double se = 0, sum = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < ref.size() / 3; ++p) {
        if (mask && !(*mask)[p]) continue;
        for (int c = 0; c < 3; ++c) {
            double d = double(img[3 * p + c]) - ref[3 * p + c];
            se += d * d;
            sum += ref[3 * p + c];
        }
        ++n;
    }
    ErrorStats s;
    s.pixels = n;
    if (n == 0) return s;
    s.rmse = std::sqrt(se / (3.0 * n));
    s.reference_mean = sum / (3.0 * n);
    s.relative_rmse = s.reference_mean > 0 ? s.rmse / s.reference_mean : 0;
    s.psnr = s.rmse > 0 ? 20 * std::log10(1.0 / s.rmse) : std::numeric_limits<double>::infinity();
    return s;
}

namespace {
double luminance(const std::vector<float>& rgb, std::size_t p) {
    double y = 0.212671 * rgb[3 * p] + 0.715160 * rgb[3 * p + 1] + 0.072169 * rgb[3 * p + 2];
    return std::clamp(y, 0.0, 1.0);
}
}  // namespace

double ssim(const std::vector<float>& ref, const std::vector<float>& img, int w, int h,
            const std::vector<bool>* mask) {
    require_same_size(ref, img);
    if (ref.size() != static_cast<std::size_t>(w) * h * 3)
        throw EvalError("images are not " + std::to_string(w) + "x" + std::to_string(h));
    const std::size_t n = static_cast<std::size_t>(w) * h;
    std::vector<double> x(n), y(n);
    for (std::size_t p = 0; p < n; ++p) {
        x[p] = luminance(ref, p);
        y[p] = luminance(img, p);
    }
    constexpr int R = 5;
    double g[2 * R + 1];
    for (int k = -R; k <= R; ++k) g[k + R] = std::exp(-k * k / (2 * 1.5 * 1.5));
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double sum = 0;
    std::size_t count = 0;
    for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
            std::size_t p = static_cast<std::size_t>(py) * w + px;
            if (mask && !(*mask)[p]) continue;
            double ws = 0, mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
            for (int dy = -R; dy <= R; ++dy) {
                int yy = py + dy;
                if (yy < 0 || yy >= h) continue;
                for (int dx = -R; dx <= R; ++dx) {
                    int xx = px + dx;
                    if (xx < 0 || xx >= w) continue;
                    double wt = g[dx + R] * g[dy + R];
                    std::size_t q = static_cast<std::size_t>(yy) * w + xx;
                    ws += wt;
                    mx += wt * x[q];
                    my += wt * y[q];
                    sxx += wt * x[q] * x[q];
                    syy += wt * y[q] * y[q];
                    sxy += wt * x[q] * y[q];
                }
            }
            mx /= ws;
            my /= ws;
            double vx = std::max(0.0, sxx / ws - mx * mx), vy = std::max(0.0, syy / ws - my * my);
            double cxy = sxy / ws - mx * my;
            sum +=
                ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
            ++count;
        }
    return count ? sum / count : 1.0;
}

std::vector<bool> edge_mask(const std::vector<float>& ref, const std::vector<float>& img,
                            double rel, double abs_tol) {
    require_same_size(ref, img);
    std::vector<bool> m(ref.size() / 3, true);
    for (std::size_t p = 0; p < m.size(); ++p)
        for (int c = 0; c < 3; ++c) {
            double r = ref[3 * p + c], v = img[3 * p + c];
            if (std::abs(v - r) > std::max(abs_tol, rel * std::abs(r))) m[p] = false;
        }
    return m;
}

std::vector<unsigned char> to_srgb8(const std::vector<float>& rgb) {
    std::vector<unsigned char> out(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        double v = std::isfinite(rgb[i]) ? std::clamp(double(rgb[i]), 0.0, 1.0) : 0.0;
        double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
        out[i] = static_cast<unsigned char>(std::clamp(e * 255 + 0.5, 0.0, 255.0));
    }
    return out;
}

std::vector<unsigned char> error_heatmap(const std::vector<float>& ref,
                                         const std::vector<float>& img, double scale) {
    require_same_size(ref, img);
    // A black-purple-orange-yellow-white ramp (inferno-like), 5 stops.
    static const double stops[5][3] = {
        {0, 0, 0.02}, {0.34, 0.06, 0.43}, {0.8, 0.25, 0.2}, {0.99, 0.7, 0.1}, {1, 1, 1}};
    std::vector<unsigned char> out(ref.size());
    for (std::size_t p = 0; p < ref.size() / 3; ++p) {
        double e = std::abs(luminance(img, p) - luminance(ref, p));
        double t = std::clamp(e / scale, 0.0, 1.0) * 4;
        int k = std::min(3, static_cast<int>(t));
        double f = t - k;
        for (int c = 0; c < 3; ++c)
            out[3 * p + c] = static_cast<unsigned char>(
                255 * ((1 - f) * stops[k][c] + f * stops[k + 1][c]) + 0.5);
    }
    return out;
}

}  // namespace cmam::eval
