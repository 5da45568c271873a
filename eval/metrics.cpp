#include "eval/metrics.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace cmam::eval {

ErrorStats compare(const std::vector<float>& ref, const std::vector<float>& img,
                   const std::vector<bool>* mask) {
    if (ref.size() != img.size() || ref.size() % 3 != 0)
        throw std::invalid_argument("images differ in size (" + std::to_string(ref.size() / 3) +
                                    " vs " + std::to_string(img.size() / 3) + " pixels)");
    if (mask && mask->size() * 3 != ref.size())
        throw std::invalid_argument("mask size does not match the image");
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

}  // namespace cmam::eval
