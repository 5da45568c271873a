// render — pbrt-v3's pixel reconstruction filters (PixelFilter): each camera sample counts for
// every pixel whose centre lies within the filter's radius of it, weighted by the filter, and a
// pixel is its samples' weighted mean. algorithms.md §17.
#pragma once

#include <array>

namespace cmam::render {

/// A separable reconstruction filter with pbrt-v3's parameters and its weights as pbrt-v3's film
/// reads them: from a table of kTableSize steps over [0, radius) per axis, each step holding the
/// filter at its midpoint (pbrt-v3 tabulates 16 x 16 products of the same two factors).
/// The largest filter radius, in pixels, a scene may ask for (more is used as this, with a
/// warning).
constexpr double kMaxFilterRadius = 16;

struct PixelFilter {
    enum class Kind { Box, Gaussian, Mitchell, Sinc, Triangle };
    static constexpr int kTableSize = 16;

    Kind kind = Kind::Box;
    float rx = 0.5f, ry = 0.5f;        // radii in pixels (pbrt-v3's "xwidth", "ywidth")
    float alpha = 2;                   // gaussian
    float b = 1.0f / 3, c = 1.0f / 3;  // mitchell
    float tau = 3;                     // sinc (Lanczos)

    /// pbrt-v3's default box: every sample counts for its own pixel alone, with weight 1.
    bool own_pixel() const { return kind == Kind::Box && rx == 0.5f && ry == 0.5f; }

    /// The filter's factor along one axis at offset x from the pixel centre, radius r (pbrt-v3's
    /// Filter::Evaluate is the product of the two axes' factors).
    float factor(float x, float r) const;

    /// The weight tables along x and along y (call after setting the parameters).
    void tabulate();
    std::array<float, kTableSize> table_x{}, table_y{};
};

}  // namespace cmam::render
