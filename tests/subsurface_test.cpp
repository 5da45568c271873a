// Subsurface scattering (pbrt-v3's "subsurface" and "kdsubsurface"): the Catmull-Rom splines the
// profile is tabulated and sampled with, the boundary's Fresnel moments, the profile table and
// its inversion from a diffuse reflectance, the radial profile's integral and sampling, and a
// semi-infinite slab under a uniform sky against its closed form.
#include "render/subsurface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "expect_throw.h"
#include "pbrt/error.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/spline.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

TEST(Spline, LinearFunctionsAreIntegratedInvertedAndSampledExactly) {
    // The spline through a linear function's values is that function (its finite differences
    // are its slope), on nodes spaced unevenly.
    const std::vector<float> x = {0, 0.1f, 0.25f, 0.7f, 1.3f, 2};
    auto f = [](float t) { return 0.5f + 2 * t; };
    std::vector<float> v, cdf(x.size());
    for (float t : x) v.push_back(f(t));
    const int n = static_cast<int>(x.size());
    const float total = integrate_spline(n, x.data(), v.data(), cdf.data());
    EXPECT_NEAR(total, 0.5 * 2 + 2 * 2, 1e-5);  // 0.5 t + t^2 over [0, 2]
    for (int i = 0; i < n; ++i) EXPECT_NEAR(cdf[i], 0.5 * x[i] + x[i] * x[i], 1e-5);
    // Inverting the (increasing) values: f^-1.
    for (float y : {0.6f, 1.0f, 2.9f, 4.4f})
        EXPECT_NEAR(invert_spline(n, x.data(), v.data(), y), (y - 0.5f) / 2, 1e-5);
    EXPECT_EQ(invert_spline(n, x.data(), v.data(), 0.1f), 0.0f);  // below the values
    EXPECT_EQ(invert_spline(n, x.data(), v.data(), 9.0f), 2.0f);  // above
    // Sampling a row (the first of a table of one row: weights 0, 1, 0, 0 at offset -1): the x
    // whose integral is the share u of the total, with density f(x) / total.
    const float w[4] = {0, 1, 0, 0};
    for (float u : {0.05f, 0.3f, 0.77f, 0.99f}) {
        float value, pdf;
        const float s = sample_spline(n, x.data(), v.data(), cdf.data(), -1, w, u, &value, &pdf);
        EXPECT_NEAR((0.5f * s + s * s) / total, u, 1e-5) << u;
        EXPECT_NEAR(value, f(s), 1e-4);
        EXPECT_NEAR(pdf, f(s) / total, 1e-5);
    }
    // Weights: the linear function between the nodes and at them, none outside the table.
    for (float t : {0.0f, 0.05f, 0.7f, 1.0f, 2.0f}) {
        int offset;
        float weights[4];
        ASSERT_TRUE(spline_weights(n, x.data(), t, &offset, weights));
        float value = 0;
        for (int k = 0; k < 4; ++k)
            if (weights[k] != 0) value += weights[k] * v[std::size_t(offset + k)];
        EXPECT_NEAR(value, f(t), 1e-5) << t;
    }
    int offset;
    float weights[4];
    EXPECT_FALSE(spline_weights(n, x.data(), 2.5f, &offset, weights));
}

TEST(Subsurface, FresnelMomentsOfTheBoundary) {
    // No boundary, no reflection.
    EXPECT_NEAR(fresnel_moment(1, 1.0), 0, 1e-9);
    EXPECT_NEAR(fresnel_moment(2, 1.0), 0, 1e-9);
    // Seen from inside water (1.33), and from outside (1/1.33): the integrals of the dielectric
    // reflectance times mu and mu^2 (an independent midpoint rule over 200,000 intervals).
    EXPECT_NEAR(fresnel_moment(1, 1.33), 0.235975, 2e-5);
    EXPECT_NEAR(fresnel_moment(2, 1.33), 0.109413, 2e-5);
    EXPECT_NEAR(fresnel_moment(1, 1 / 1.33), 0.032965, 2e-5);
    EXPECT_NEAR(fresnel_moment(2, 1 / 1.33), 0.013138, 2e-5);
}

TEST(Subsurface, ProfileTableAndItsInversionFromAReflectance) {
    const auto t = BssrdfTable::beam_diffusion(0, 1.33f);
    ASSERT_EQ(t->rho.size(), 100u);
    ASSERT_EQ(t->radius.size(), 64u);
    // The effective albedo grows with the single-scattering albedo, from 0 at 0.
    EXPECT_EQ(t->rho_eff[0], 0);
    for (std::size_t i = 1; i < t->rho.size(); ++i)
        EXPECT_GT(t->rho_eff[i], t->rho_eff[i - 1]) << i;
    // Without absorption nearly all light comes back out (the photon beam diffusion model gives
    // 1.02 at index 1.33).
    EXPECT_NEAR(t->rho_eff.back(), 1.0f, 0.05f);
    for (float p : t->profile) EXPECT_GE(p, 0);
    // The single-scattering albedo and mean free path whose profile reflects kd.
    for (float kd : {0.05f, 0.3f, 0.5f, 0.9f}) {
        Rgb sa, ss;
        subsurface_from_diffuse(*t, Rgb(kd), Rgb(0.02f), sa, ss);
        EXPECT_NEAR(1 / (sa.r + ss.r), 0.02f, 1e-6);
        const float rho = ss.r / (sa.r + ss.r);
        int offset;
        float w[4];
        ASSERT_TRUE(spline_weights(100, t->rho.data(), rho, &offset, w));
        float eff = 0;
        for (int k = 0; k < 4; ++k)
            if (w[k] != 0) eff += w[k] * t->rho_eff[std::size_t(offset + k)];
        EXPECT_NEAR(eff, kd, 1e-4) << kd;
    }
}

TEST(Subsurface, RadialProfileIntegratesToTheEffectiveAlbedoAndIsSampledByItsDensity) {
    const auto t = BssrdfTable::beam_diffusion(0, 1.33f);
    // Skin-like coefficients (mm^-1 as numbers): per channel a different extinction and albedo.
    const Bssrdf b(*t, Rgb(0.032f, 0.17f, 0.48f), Rgb(0.74f, 0.88f, 1.01f));
    // The integrals over the plane (r from 0 to the table's end, logarithmic steps).
    double e[3] = {0, 0, 0}, p[3] = {0, 0, 0};
    double r0 = 0;
    for (int k = 0; k < 200000; ++k) {
        const double r1 = 1e-6 * std::pow(1.0001, k), rm = 0.5 * (r0 + r1);
        const Rgb s = b.sr(float(rm));
        const double ring = 2 * M_PI * rm * (r1 - r0);
        e[0] += s.r * ring;
        e[1] += s.g * ring;
        e[2] += s.b * ring;
        for (int c = 0; c < 3; ++c) p[c] += b.pdf_sr(c, float(rm)) * ring;
        r0 = r1;
    }
    for (int c = 0; c < 3; ++c) {
        int offset;
        float w[4];
        ASSERT_TRUE(spline_weights(100, t->rho.data(), b.rho[c], &offset, w));
        float eff = 0;
        for (int k = 0; k < 4; ++k)
            if (w[k] != 0) eff += w[k] * t->rho_eff[std::size_t(offset + k)];
        EXPECT_NEAR(e[c] / eff, 1.0, 0.01) << c;
        EXPECT_NEAR(p[c], 1.0, 0.01) << c;
    }
    // Radii drawn from channel 1's profile fall below r with the probability its density gives.
    const int n = 20000;
    std::vector<float> drawn;
    for (int i = 0; i < n; ++i) drawn.push_back(b.sample_sr(1, (i + 0.5f) / n));
    for (float r : {0.1f, 0.5f, 1.0f, 3.0f}) {
        double below = 0;
        for (float d : drawn) below += d < r;
        double mass = 0, q0 = 0;
        for (int k = 1; k <= 20000; ++k) {
            const double q1 = r * k / 20000.0, qm = 0.5 * (q0 + q1);
            mass += b.pdf_sr(1, float(qm)) * 2 * M_PI * qm * (q1 - q0);
            q0 = q1;
        }
        EXPECT_NEAR(below / n, mass, 0.01) << r;
    }
    EXPECT_EQ(Bssrdf(*t, Rgb(0), Rgb(0)).sample_sr(0, 0.5f), -1);  // no extinction
}

namespace {

// A thick slab (a closed box 20 deep) of a kdsubsurface material seen straight down from above
// under a uniform sky of radiance 1, its mean free path far below the box's size: a
// semi-infinite medium, whose radiance at normal incidence is F(0) + (1 - F(0)) Kd (the
// boundary's reflection, and the light that enters, reflected by the medium as its effective
// albedo, Kd, and leaving through the exit lobe, which passes all it is given).
std::string slab(const std::string& material, const std::string& integrator = "path") {
    return R"(LookAt 0 5 0  0 0 0  0 0 1
Camera "orthographic" "float screenwindow" [-1 1 -1 1]
Film "image" "integer xresolution" 8 "integer yresolution" 8
Sampler "stratified" "integer xsamples" 32 "integer ysamples" 32
Integrator ")" +
           integrator + R"("
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
)" + material +
           R"(
Shape "trianglemesh"
  "integer indices" [0 1 2 0 2 3 4 6 5 4 7 6 0 4 5 0 5 1 1 5 6 1 6 2 2 6 7 2 7 3 3 7 4 3 4 0]
  "point P" [-10 -20 -10 10 -20 -10 10 -20 10 -10 -20 10 -10 0 -10 10 0 -10 10 0 10 -10 0 10]
WorldEnd
)";
}

Rgb mean_of(const Framebuffer& fb) {
    double s[3] = {0, 0, 0};
    const std::size_t n = std::size_t(fb.width) * fb.height;
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) s[c] += fb.rgb[i * 3 + c];
    return Rgb(float(s[0] / n), float(s[1] / n), float(s[2] / n));
}

}  // namespace

TEST(Subsurface, SemiInfiniteSlabReflectsItsKd) {
    const float f0 = std::pow((1.33f - 1) / (1.33f + 1), 2.0f);  // 0.0201
    // A smooth surface (the path enters by the specular transmission), and a slightly rough one
    // (by the microfacet transmission; its reflection of the uniform sky is F(0)'s within a
    // fraction of a percent: pbrt-v3 gives 0.5100, 0.2157 and 0.8037 for the three channels).
    for (const char* rough : {"", R"("float uroughness" 0.05 "float vroughness" 0.05
                                   "bool remaproughness" "false")"}) {
        auto scene =
            test::scene_from(slab(std::string(R"(Material "kdsubsurface" "rgb Kd" [0.5 0.2 0.8]
                                "rgb mfp" [0.01 0.02 0.005] "float eta" 1.33 )") +
                                  rough));
        const Rgb L = mean_of(render::render(*scene, {}, nullptr));
        const double tolerance = *rough ? 0.015 : 0.01;
        EXPECT_NEAR(L.r / (f0 + (1 - f0) * 0.5f), 1.0, tolerance) << rough;
        EXPECT_NEAR(L.g / (f0 + (1 - f0) * 0.2f), 1.0, tolerance) << rough;
        EXPECT_NEAR(L.b / (f0 + (1 - f0) * 0.8f), 1.0, tolerance) << rough;
    }
}

TEST(Subsurface, TextureAovIsTheKdOfTheBssrdf) {
    // The texture AOV records a kdsubsurface's Kd where it is hit (its BSDF, a glass's, has none).
    auto scene = test::scene_from(slab(R"(Material "kdsubsurface" "rgb Kd" [0.5 0.2 0.8])"));
    RenderOptions o;
    o.aov = AovKind::Texture;
    const Rgb k = mean_of(render::render(*scene, o, nullptr));
    EXPECT_FLOAT_EQ(k.r, 0.5f);
    EXPECT_FLOAT_EQ(k.g, 0.2f);
    EXPECT_FLOAT_EQ(k.b, 0.8f);
}

TEST(Subsurface, WithoutAPathTracerItIsItsSurfacesGlass) {
    // pbrt-v3's whitted and directlighting leave the BSSRDF out: the material is its BSDF, a
    // glass of its index (here a smooth one: the sky through the slab, which is black below).
    const std::string glass = R"(Material "glass" "float eta" 1.33)";
    for (const char* m : {R"(Material "kdsubsurface" "rgb Kd" [0.5 0.2 0.8] "float eta" 1.33)",
                          R"(Material "subsurface" "string name" "Ketchup")"}) {
        auto a = test::scene_from(slab(m, "whitted"));
        auto b = test::scene_from(slab(glass, "whitted"));
        EXPECT_EQ(render::render(*a, {}, nullptr).rgb, render::render(*b, {}, nullptr).rgb) << m;
    }
}

TEST(Subsurface, MaterialParameters) {
    std::vector<std::string> warnings;
    auto material = [&](const std::string& text) {
        warnings.clear();
        auto s = build_scene(pbrt::parse_string("Camera \"perspective\" WorldBegin "
                                                "LightSource \"point\" " +
                                                    text + " Shape \"sphere\" WorldEnd",
                                                "m.pbrt"),
                             {}, [&](const std::string& w) { warnings.push_back(w); });
        return s->materials.empty() ? Material{} : s->materials.back();
    };
    // pbrt-v3's defaults: its coefficients (mm^-1), index 1.33, scale 1, white Kr and Kt.
    Material m = material("Material \"subsurface\"");
    EXPECT_EQ(m.type, Material::Type::Subsurface);
    EXPECT_FLOAT_EQ(m.sss_sigma_a.value.g, 0.0024f);
    EXPECT_FLOAT_EQ(m.sss_sigma_s.value.b, 3.77f);
    EXPECT_FLOAT_EQ(m.eta.value.r, 1.33f);
    EXPECT_FLOAT_EQ(m.sss_scale, 1);
    EXPECT_FLOAT_EQ(m.kt.value.r, 1);
    ASSERT_TRUE(m.bssrdf);
    EXPECT_FLOAT_EQ(m.bssrdf->eta, 1.33f);
    EXPECT_TRUE(warnings.empty());
    // A measured medium by name: its absorption and reduced scattering, g then 0.
    m = material(
        "Material \"subsurface\" \"string name\" \"Ketchup\" \"float g\" 0.5 \"float scale\" 2");
    EXPECT_FLOAT_EQ(m.sss_sigma_a.value.r, 0.061f);
    EXPECT_FLOAT_EQ(m.sss_sigma_s.value.r, 0.18f);
    EXPECT_FLOAT_EQ(m.sss_scale, 2);
    EXPECT_EQ(m.bssrdf->g, 0);
    // An unknown name: a warning, the defaults.
    m = material("Material \"subsurface\" \"string name\" \"Marmite\"");
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("unknown measured medium \"Marmite\""), std::string::npos);
    EXPECT_FLOAT_EQ(m.sss_sigma_s.value.r, 2.55f);
    // kdsubsurface: Kd, mfp; one table per (g, eta), shared.
    auto scene = build_scene(
        pbrt::parse_string("Camera \"perspective\" WorldBegin Material \"kdsubsurface\" \"rgb Kd\" "
                           "[0.1 0.2 0.3] \"rgb mfp\" [1 2 3] Shape \"sphere\" Material "
                           "\"subsurface\" \"float eta\" 1.33 Shape \"sphere\" WorldEnd",
                           "k.pbrt"),
        {}, {});
    ASSERT_EQ(scene->materials.size(), 2u);
    EXPECT_EQ(scene->materials[0].type, Material::Type::KdSubsurface);
    EXPECT_FLOAT_EQ(scene->materials[0].kd.value.b, 0.3f);
    EXPECT_FLOAT_EQ(scene->materials[0].mfp.value.g, 2);
    EXPECT_EQ(scene->materials[0].bssrdf, scene->materials[1].bssrdf);
    // Errors.
    EXPECT_THROW_CONTAINS(material("Material \"subsurface\" \"float g\" 1"), pbrt::SceneError,
                          "g must be in (-1, 1)");
    EXPECT_THROW_CONTAINS(material("Material \"kdsubsurface\" \"float eta\" 0"), pbrt::SceneError,
                          "eta must be positive");
    EXPECT_THROW_CONTAINS(material("Material \"subsurface\" \"float scale\" -1"), pbrt::SceneError,
                          "scale must not be negative");
}
