// cmam::texture — MIP pyramid (Williams 1983) and trilinear filtering.
// algorithms.md §2: exact area (box) downsampling with floor sizes (option 2), so the mean and
// the cell-to-uv correspondence are exact at every level, for any size; trilinear blends two
// levels with no jump at lambda = 1.
#pragma once

#include <cmam/texture/image.h>

#include <memory>
#include <vector>

namespace cmam::texture {

class MipPyramid {
  public:
    MipPyramid() = default;
    /// Builds all levels, 1 + floor(log2(max(W,H))) of them, from `base` (copied).
    explicit MipPyramid(const Image& base);
    /// The same with `base` itself as level 0, not copied: it must outlive the pyramid (a
    /// texture's largest level is then stored once).
    static MipPyramid over(const Image& base);

    int levels() const { return m_base ? 1 + static_cast<int>(m_upper.size()) : 0; }
    const Image& level(int l) const {
        return l == 0 ? *m_base : m_upper[static_cast<std::size_t>(l - 1)];
    }
    /// Bytes the pyramid holds: every level, level 0 only when it was copied.
    std::size_t memory_bytes() const;

    /// Bilinear lookup at level `l` (lattice s' = u*W_l - 1/2 with that level's own size).
    Texel bilinear(int l, double u, double v) const;
    /// Trilinear lookup for a footprint `width` in level-0 texels (lambda = log2(width)).
    Texel trilinear(double u, double v, double width) const;
    /// The fractional level trilinear() reads for `width`: log2(width) clamped to [0, L-1].
    double trilinear_lambda(double width) const;
    /// trilinear() for a footprint whose width squared is `width2` (lambda = log2(width2) / 2):
    /// no square root, and the level comes from width2's binary exponent, so the texel reads
    /// wait for neither the root nor the logarithm. `lambda`, when not null, receives the level
    /// read, clamped to [0, L-1] (0 for magnification or NaN).
    Texel trilinear_width2(double u, double v, double width2, double* lambda = nullptr) const;
    /// The same at a given level of detail `lambda` (log2 of the width in level-0 texels):
    /// lambda <= 0 (or NaN) is bilinear at level 0, lambda >= L-1 the coarsest level's mean.
    /// For callers that have the width squared: lambda = log2(width^2) / 2 needs no square root.
    Texel trilinear_lod(double u, double v, double lambda) const;
    /// Levels l >= 0 and l+1 blended with weight f (in [0,1]) on level l+1, i.e. lambda = l + f;
    /// l >= L-1 is the coarsest level's mean. For callers that know the level before the
    /// weight: the texel reads need not wait for the logarithm.
    Texel trilinear_levels(double u, double v, int l, float f) const;

  private:
    std::unique_ptr<Image> m_owned_base;  // level 0 when copied (on the heap: moves keep m_base)
    const Image* m_base = nullptr;        // level 0
    std::vector<Image> m_upper;           // levels 1 ..

    void build_upper();
};

/// Box-downsamples `src` to `w` x `h` texels: output texel k covers source cells
/// [k*N/n, (k+1)*N/n) per axis, averaged with their overlap lengths.
Image box_downsample(const Image& src, int w, int h);

}  // namespace cmam::texture
