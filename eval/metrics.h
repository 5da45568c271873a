// eval — image error metrics against a reference: RMSE, relative RMSE, PSNR.
// Images are linear RGB, top row first, 3 floats per pixel; an optional mask selects pixels.
#pragma once

#include <vector>

namespace cmam::eval {

struct ErrorStats {
    double rmse = 0;           // over all channels of the selected pixels
    double relative_rmse = 0;  // rmse / mean of the reference over the same pixels
    double psnr = 0;           // dB, with peak 1 (linear values); infinite when rmse = 0
    double reference_mean = 0;
    std::size_t pixels = 0;
};

/// Throws std::invalid_argument when the sizes differ or the mask has the wrong size.
ErrorStats compare(const std::vector<float>& reference, const std::vector<float>& image,
                   const std::vector<bool>* mask = nullptr);

}  // namespace cmam::eval
