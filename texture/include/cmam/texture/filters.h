// cmam::texture — point filters (nearest, bilinear) on level 0.
// algorithms.md §0: nearest uses floor(s); bilinear uses the lattice s' = u*W - 1/2.
// Non-finite coordinates return the texture mean (§11).
#pragma once

#include <cmam/texture/image.h>

namespace cmam::texture {

/// Nearest texel at (u,v) (unwrapped uv; the image's wrap modes apply).
Texel nearest(const Image& image, double u, double v);

/// Bilinear interpolation of the four texels around (u,v) on the texel-centre lattice.
Texel bilinear(const Image& image, double u, double v);

}  // namespace cmam::texture
