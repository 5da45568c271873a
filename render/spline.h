// render — Catmull-Rom splines through tabulated values (pbrt-v3's CatmullRomWeights,
// SampleCatmullRom2D, IntegrateCatmullRom and InvertCatmullRom): the Fourier BSDF's tables and
// the BSSRDF's profile (algorithms.md §18, "Fourier BSDFs", and §26). A segment between nodes
// x_i and x_{i+1} is the cubic Hermite curve through their values whose end derivatives are the
// neighbours' finite differences (one-sided at the table's ends).
#pragma once

#include <algorithm>

namespace cmam::render {

/// The largest i in [0, size - 2] with below(i) true (0 if none): below must be true up to some
/// index and false after it.
template <class Pred>
int last_below(int size, const Pred& below) {
    int first = 0, len = size;
    while (len > 0) {
        const int half = len >> 1, middle = first + half;
        if (below(middle)) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    return std::clamp(first - 1, 0, size - 2);
}

/// The weights of the four nodes offset..offset+3 whose spline through `nodes` gives the value at
/// x (a weight of a node outside the table is 0). False when x is outside [nodes[0],
/// nodes[size - 1]]. Repeated nodes (published tables have -0 and 0) can make the interval found
/// one of no width (at the table's end, where the search stops): x there is its node, and a
/// difference over no width is taken one-sided.
bool spline_weights(int size, const float* nodes, float x, int* offset, float w[4]);

/// A value drawn from a row of a table (`size2` columns at `nodes2`; `values` and their running
/// integrals `cdf`, integrate_spline's, row by row), the row interpolated over the table's first
/// dimension with the four weights `w` of rows offset..offset+3 (spline_weights'): the segment by
/// the interpolated integrals, then the point within it by inverting the segment's cubic integral
/// (Newton's method, bisection where a step leaves the bracket). `fval` (may be null) gets the
/// interpolant there, `pdf` its density (fval over the row's integral); 0 and a density of 0
/// where the row's integral is not positive.
float sample_spline(int size2, const float* nodes2, const float* values, const float* cdf,
                    int offset, const float w[4], float u, float* fval, float* pdf);

/// The integral of the spline through values[i] at x[i] (n nodes) over [x[0], x[n - 1]], with the
/// running integral to each node in cdf[0..n-1].
float integrate_spline(int n, const float* x, const float* values, float* cdf);

/// The x where the spline through values[i] at x[i] (increasing values) takes the value u: x[0]
/// or x[n - 1] beyond the values' range.
float invert_spline(int n, const float* x, const float* values, float u);

}  // namespace cmam::render
