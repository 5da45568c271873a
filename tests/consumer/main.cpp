// A project outside cmam that finds the installed filtering library with find_package(cmam).
#include <cmam/texture/filter.h>

#include <cmath>
#include <cstdio>

int main() {
    using namespace cmam::texture;
    FilteredTexture t(Image(2, 2, 1, {1, 2, 3, 4}));
    float v = t.lookup(0.5, 0.5, Footprint::axes({1, 0}, {0, 1}), {FilterKind::Ewa})[0];
    std::printf("%g\n", v);
    return std::abs(v - 2.5f) < 1e-5f ? 0 : 1;  // a footprint covering the whole texture: the mean
}
