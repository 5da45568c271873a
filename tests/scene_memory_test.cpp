// The scene description grows with the file, not with the number of names in scope at each
// line: named textures and materials are scoped without copying them per directive or per
// AttributeBegin. This program replaces the global operator new to count what is allocated.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/scene.h"

namespace {
std::atomic<std::size_t> g_allocated_bytes{0};
}  // namespace

void* operator new(std::size_t n) {
    g_allocated_bytes += n;
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}

using namespace cmam;

namespace {
// `n` chained float textures (in chains of 128, within kMaxTextureDepth) and as many materials
// using them, then n/2 nested and n/2 serial AttributeBegin blocks, each declaring a texture and
// a named material of its own.
std::string many_names(int n) {
    auto name = [](char prefix, int i) { return prefix + std::to_string(i); };
    std::string s =
        "Camera \"perspective\"\nWorldBegin\nLightSource \"point\"\n"
        "Texture \"t0\" \"float\" \"constant\" \"float value\" 0.5\n";
    for (int i = 1; i < n; ++i) {
        s += "Texture \"" + name('t', i) + "\" \"float\" \"scale\" \"texture tex1\" \"" +
             name('t', i % 128 == 0 ? 0 : i - 1) + "\"\n";
        s += "Material \"matte\" \"texture sigma\" \"" + name('t', i) + "\"\n";
    }
    for (int i = 0; i < n; ++i) {
        const std::string b = name('b', i);
        s += "AttributeBegin\nTexture \"" + b + "\" \"float\" \"scale\" \"texture tex1\" \"t0\"\n";
        s += "MakeNamedMaterial \"" + b + "\" \"string type\" \"matte\" \"texture sigma\" \"" + b +
             "\"\nNamedMaterial \"" + b + "\"\n";
        if (i >= n / 2) s += "AttributeEnd\n";
    }
    for (int i = 0; i < n / 2; ++i) s += "AttributeEnd\n";
    return s + "Shape \"sphere\"\nWorldEnd\n";
}

// Bytes allocated while parsing and building many_names(n).
std::size_t bytes_to_build(int n) {
    const std::string text = many_names(n);
    const std::size_t before = g_allocated_bytes;
    auto scene = render::build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
    EXPECT_EQ(scene->textures.size(), 2u * n);
    EXPECT_EQ(scene->materials.size(), 2u * n - 1);
    return g_allocated_bytes - before;
}
}  // namespace

// Each Texture or Material directive once copied every texture name in scope, and each
// AttributeBegin every name: the bytes allocated grew with the square of the file's length
// (10,000 Texture lines took 4 GB). Doubling the file must at most double them (plus slack).
TEST(SceneMemory, DescriptionGrowsLinearlyWithTexturesMaterialsAndBlocks) {
    bytes_to_build(100);  // one-time allocations (Embree, locale, ...) out of the way
    const std::size_t once = bytes_to_build(1000), twice = bytes_to_build(2000);
    EXPECT_LT(static_cast<double>(twice), 2.5 * static_cast<double>(once))
        << "1000 names: " << once << " bytes, 2000 names: " << twice << " bytes";
}

// The same file at 20,000 texture lines and 10,000 blocks stays within bytes proportional to
// its length (the quadratic copies would have allocated tens of gigabytes).
TEST(SceneMemory, TwentyThousandTexturesBuildWithinALinearBudget) {
    const std::string text = many_names(20000);
    const std::size_t bytes = bytes_to_build(20000);
    EXPECT_LT(bytes, 100 * text.size()) << text.size() << " bytes of scene text";
}
