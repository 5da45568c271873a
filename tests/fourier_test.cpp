// pbrt-v3's "fourier" material: a `.bsdf` table (here one written by the test: a Lambertian
// reflector in the spline x Fourier basis) read, evaluated, sampled, and named by a scene.
#include "render/fourier.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/error.h"
#include "render/integrator.h"
#include "render/shading.h"
#include "render/tracer.h"

using namespace cmam;
using namespace cmam::render;
namespace fs = std::filesystem;

namespace {

constexpr float kAlbedo = 0.5f;

// Elevation nodes -1, -0.75, ..., 1. For -wi at mu_i and wo at mu_o on opposite sides (a
// reflection), the series is the constant f |mu_i| = albedo / pi |mu_i|: a Lambertian
// reflector; nothing is transmitted. Three channels: Y, R and B the same (so G is Y too).
struct Table {
    std::vector<float> mu;
    std::vector<float> cdf, coeffs;
    std::vector<int32_t> offset_length;
    int channels;
};

Table lambertian(int channels, std::vector<float> nodes = {}) {
    Table t;
    t.channels = channels;
    t.mu = std::move(nodes);
    if (t.mu.empty())
        for (int k = 0; k <= 8; ++k) t.mu.push_back(-1 + 0.25f * k);
    const int n = static_cast<int>(t.mu.size());
    for (int o = 0; o < n; ++o) {
        float integral = 0;  // of a0 over mu_i up to node i (trapezoids: a0 is linear between)
        for (int i = 0; i < n; ++i) {
            const bool reflects = t.mu[i] * t.mu[o] < 0;
            const float a0 = reflects ? kAlbedo / kPi * std::abs(t.mu[i]) : 0.0f;
            if (i > 0) {
                const float prev =
                    t.mu[i - 1] * t.mu[o] < 0 ? kAlbedo / kPi * std::abs(t.mu[i - 1]) : 0.0f;
                integral += 0.5f * (prev + a0) * (t.mu[i] - t.mu[i - 1]);
            }
            t.cdf.push_back(integral);
            t.offset_length.push_back(static_cast<int32_t>(t.coeffs.size()));
            t.offset_length.push_back(reflects ? 1 : 0);
            if (reflects)
                for (int c = 0; c < channels; ++c) t.coeffs.push_back(a0);
        }
    }
    return t;
}

void put(std::ofstream& out, const void* p, std::size_t n) {
    out.write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
}

// The table as a version 1 SCATFUN file (little-endian, as x86 and ARM hosts write it);
// `truncate` bytes are left off its end.
void write_table(const fs::path& path, const Table& t, std::size_t truncate = 0) {
    {
        std::ofstream out(path, std::ios::binary);
        put(out, "SCATFUN\x01", 8);
        const int32_t n = static_cast<int32_t>(t.mu.size());
        const int32_t head[9] = {1, n, static_cast<int32_t>(t.coeffs.size()), 1, t.channels, 1, 0,
                                 0, 0};
        put(out, head, sizeof head);
        const float tail[5] = {1.0f, 0, 0, 0, 0};  // eta, alpha[2], unused[2]
        put(out, tail, sizeof tail);
        put(out, t.mu.data(), 4 * t.mu.size());
        put(out, t.cdf.data(), 4 * t.cdf.size());
        put(out, t.offset_length.data(), 4 * t.offset_length.size());
        put(out, t.coeffs.data(), 4 * t.coeffs.size());
    }
    if (truncate) fs::resize_file(path, fs::file_size(path) - truncate);
}

struct TempDir {
    fs::path dir = fs::temp_directory_path() / ("cmam_fourier_" + std::to_string(::getpid()));
    TempDir() { fs::create_directories(dir); }
    ~TempDir() { fs::remove_all(dir); }
};

Vec3 direction(float theta, float phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

}  // namespace

// Away from the horizon (where the spline meets the kink of |mu| at 0) the table is exactly a
// Lambertian reflector's: albedo / pi for every reflected pair, 0 across; one channel or three.
TEST(Fourier, EvaluatesTheTablesSeries) {
    TempDir tmp;
    for (int channels : {1, 3}) {
        SCOPED_TRACE(channels);
        write_table(tmp.dir / "l.bsdf", lambertian(channels));
        const FourierTable t = read_fourier_table((tmp.dir / "l.bsdf").string());
        EXPECT_EQ(t.n_mu, 9);
        EXPECT_EQ(t.channels, channels);
        for (float th_o : {0.1f, 0.7f, 1.0f})
            for (float th_i : {0.2f, 0.9f, 1.2f})
                for (float phi : {0.0f, 1.0f, 3.0f}) {
                    const Vec3 wo = direction(th_o, 0.3f), wi = direction(th_i, phi);
                    const Rgb f = fourier_f(t, wo, wi);
                    EXPECT_NEAR(f.r, kAlbedo / kPi, 1e-5f) << th_o << " " << th_i << " " << phi;
                    EXPECT_NEAR(f.g, kAlbedo / kPi, 1e-4f);
                    EXPECT_TRUE(fourier_f(t, wo, -wi).is_black());
                    // The density: cos theta_i / pi, the table's reflected share.
                    EXPECT_NEAR(fourier_pdf(t, wo, wi), std::cos(th_i) / kPi, 2e-3f);
                }
    }
}

// Published tables repeat the node 0 (as -0 and 0): values stay finite at the horizon and near
// the reflector's elsewhere. (A repeat at a table's end, the interval of no width that a lookup
// can land in, is fuzz/regressions/bsdf's input.)
TEST(Fourier, RepeatedNodesGiveFiniteValues) {
    TempDir tmp;
    write_table(tmp.dir / "r.bsdf", lambertian(1, {-1, -0.5f, -0.0f, 0, 0.5f, 1}));
    const FourierTable t = read_fourier_table((tmp.dir / "r.bsdf").string());
    const Vec3 grazing(1, 0, 0), up = normalize(Vec3(0.3f, 0, 1));
    for (const Vec3& wo : {grazing, up})
        for (const Vec3& wi : {grazing, up, Vec3(0, 0.6f, 0.8f)}) {
            EXPECT_TRUE(std::isfinite(fourier_f(t, wo, wi).r));
            EXPECT_TRUE(std::isfinite(fourier_pdf(t, wo, wi)));
        }
    // (Within 1%: the spline in mu_o reads the horizon's node, where the table steps to 0.)
    EXPECT_NEAR(fourier_f(t, up, Vec3(0, 0.6f, 0.8f)).r, kAlbedo / kPi, 0.01f * kAlbedo / kPi);
    const FourierSample s = fourier_sample(t, up, 0.3f, 0.6f);
    EXPECT_TRUE(std::isfinite(s.pdf) && std::isfinite(s.f.r));
}

// Directions drawn from the table: on wo's side, with the density they report (close to the
// tabulated one), and the albedo estimated from them.
TEST(Fourier, SamplesTheTablesLuminance) {
    TempDir tmp;
    write_table(tmp.dir / "l.bsdf", lambertian(3));
    const FourierTable t = read_fourier_table((tmp.dir / "l.bsdf").string());
    for (float th_o : {0.2f, 1.0f}) {
        const Vec3 wo = direction(th_o, 0.5f);
        Rng rng(3);
        double albedo = 0;
        const int n = 20000;
        for (int k = 0; k < n; ++k) {
            const float u1 = rng.next_float(), u2 = rng.next_float();
            const FourierSample s = fourier_sample(t, wo, u1, u2);
            ASSERT_GT(s.pdf, 0);
            EXPECT_GT(s.wi.z, 0);  // reflected only
            EXPECT_NEAR(length(s.wi), 1, 1e-5f);
            EXPECT_NEAR(s.pdf, fourier_pdf(t, wo, s.wi), 0.02f * s.pdf + 1e-3f);
            albedo += s.f.g * s.wi.z / s.pdf;
        }
        EXPECT_NEAR(albedo / n, kAlbedo, 0.01) << th_o;
    }
}

// A scene's fourier material reads its file once and shades with it; a file that cannot be read
// gives a warning with the reason, and the material is rendered as matte.
TEST(Fourier, MaterialReadsItsFileOrFallsBackToMatteWithTheReason) {
    TempDir tmp;
    write_table(tmp.dir / "l.bsdf", lambertian(1));
    write_table(tmp.dir / "short.bsdf", lambertian(1), 40);
    { std::ofstream(tmp.dir / "text.bsdf") << "not a table"; }
    auto build = [&](const std::string& file, std::vector<std::string>& warnings) {
        const std::string text =
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
            "LightSource \"point\"\nMaterial \"fourier\" \"string bsdffile\" \"" +
            file + "\"\nShape \"sphere\" \"float radius\" 1\nWorldEnd\n";
        return build_scene(pbrt::parse_string(text, (tmp.dir / "t.pbrt").string()), {},
                           [&](const std::string& w) { warnings.push_back(w); });
    };
    std::vector<std::string> warnings;
    auto s = build("l.bsdf", warnings);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    ASSERT_EQ(s->materials.at(0).type, Material::Type::Fourier);
    const std::optional<SurfaceHit> h = s->intersect(Vec3(0, 0, 5), Vec3(0, 0, -1), 0, 100);
    ASSERT_TRUE(h.has_value());
    const std::optional<Bsdf> b = make_bsdf(*s, s->materials[0], *h, TexContext{});
    ASSERT_TRUE(b.has_value());
    const Vec3 wo = normalize(Vec3(0.2f, 0.1f, 1)), wi = normalize(Vec3(-0.4f, 0.3f, 1));
    EXPECT_NEAR(b->f(b->frame.to_world(wo), b->frame.to_world(wi)).g, kAlbedo / kPi, 1e-4f);
    for (const auto& [file, reason] :
         {std::pair<std::string, std::string>{"short.bsdf", "shorter than its header says"},
          {"text.bsdf", "not a version 1 \"SCATFUN\" file"},
          {"missing.bsdf", "cannot read it"}}) {
        warnings.clear();
        s = build(file, warnings);
        EXPECT_EQ(s->materials.at(0).type, Material::Type::Matte) << file;
        ASSERT_EQ(warnings.size(), 1u) << file;
        EXPECT_NE(warnings[0].find(reason), std::string::npos) << warnings[0];
        EXPECT_NE(warnings[0].find("t.pbrt:5:20: warning: Fourier BSDF file"), std::string::npos)
            << warnings[0];
        EXPECT_NE(warnings[0].find("; the material is rendered as \"matte\""), std::string::npos)
            << warnings[0];
    }
}
