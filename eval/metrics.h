// eval — image error metrics against a reference: RMSE, relative RMSE, PSNR.
// Images are linear RGB, top row first, 3 floats per pixel; an optional mask selects pixels.
#pragma once

#include <cstddef>
#include <vector>

#include "eval/error.h"

namespace cmam::eval {

struct ErrorStats {
    double rmse = 0;           // over all channels of the selected pixels
    double relative_rmse = 0;  // rmse / mean of the reference over the same pixels
    double psnr = 0;           // dB, with peak 1 (linear values); infinite when rmse = 0
    double reference_mean = 0;
    std::size_t pixels = 0;
};

/// Throws EvalError when the sizes differ or the mask has the wrong size.
ErrorStats compare(const std::vector<float>& reference, const std::vector<float>& image,
                   const std::vector<bool>* mask = nullptr);

/// Mean SSIM (Wang et al. 2004) of the luminance of two linear RGB images of `width` x
/// `height`, values clamped to [0,1] (dynamic range L = 1, C1 = (0.01 L)^2, C2 = (0.03 L)^2),
/// with an 11x11 Gaussian window (sigma 1.5) renormalised where it leaves the image; averaged
/// over the pixels of `mask` (all when null).
double ssim(const std::vector<float>& reference, const std::vector<float>& image, int width,
            int height, const std::vector<bool>* mask = nullptr);

/// Pixels away from geometric edges: where an untextured render agrees with the untextured
/// ground truth to within max(abs_tol, rel_tol * value) in every channel.
std::vector<bool> edge_mask(const std::vector<float>& untextured_reference,
                            const std::vector<float>& untextured, double rel_tol = 0.02,
                            double abs_tol = 1e-3);

/// Linear RGB to 8-bit sRGB bytes (for report images); `heat` maps the per-pixel error instead.
std::vector<unsigned char> to_srgb8(const std::vector<float>& rgb);
/// A heat map of |image - reference| (luminance), 0 -> black, `scale` -> white through a
/// perceptual ramp; 3 bytes per pixel.
std::vector<unsigned char> error_heatmap(const std::vector<float>& reference,
                                         const std::vector<float>& image, double scale);

}  // namespace cmam::eval
