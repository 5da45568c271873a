// Fresnel, refraction, BSDF values and glass energy conservation.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <complex>
#include <forward_list>
#include <limits>

#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/shading.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

// finite(Vec3) is a branch-free sum of x * 0: it must agree with std::isfinite on every
// component, at the extremes of float's range too.
TEST(Math, FiniteVectorIsEveryComponentFinite) {
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float finite_values[] = {0.0f,
                                   -0.0f,
                                   1.0f,
                                   -2.5f,
                                   std::numeric_limits<float>::max(),
                                   -std::numeric_limits<float>::max(),
                                   std::numeric_limits<float>::denorm_min()};
    for (float a : finite_values)
        for (float b : finite_values) EXPECT_TRUE(finite(Vec3(a, b, -a))) << a << " " << b;
    for (float bad : {inf, -inf, nan}) {
        EXPECT_FALSE(finite(Vec3(bad, 0, 0)));
        EXPECT_FALSE(finite(Vec3(0, bad, 0)));
        EXPECT_FALSE(finite(Vec3(0, 0, bad)));
        EXPECT_FALSE(finite(Vec3(std::numeric_limits<float>::max(), bad, 1)));
    }
    EXPECT_FALSE(finite(Vec3(inf, -inf, 0)));  // infinities of both signs do not cancel
}

TEST(Fresnel, DielectricReferenceValues) {
    EXPECT_NEAR(fresnel_dielectric(1, 1, 1.5f), 0.04, 1e-6);    // normal incidence
    EXPECT_NEAR(fresnel_dielectric(-1, 1, 1.5f), 0.04, 1e-6);   // from inside, same
    EXPECT_NEAR(fresnel_dielectric(0, 1, 1.5f), 1.0, 1e-6);     // grazing
    EXPECT_FLOAT_EQ(fresnel_dielectric(-0.5f, 1, 1.5f), 1.0f);  // total internal reflection
    // 45 degrees into glass: Rs = 0.0920, Rp = 0.0085 (textbook values)
    float c = std::sqrt(0.5f);
    EXPECT_NEAR(fresnel_dielectric(c, 1, 1.5f), (0.092013 + 0.008466) / 2, 2e-5);
}

TEST(Refract, SnellsLawAndTotalInternalReflection) {
    Vec3 n(0, 0, 1);
    Vec3 wi = normalize(Vec3(1, 0, 1));  // 45 degrees, pointing away from the surface
    const std::optional<Vec3> refracted = refract(wi, n, 1 / 1.5f);
    ASSERT_TRUE(refracted.has_value());
    const Vec3 wt = *refracted;
    EXPECT_NEAR(length(wt), 1, 1e-6);
    EXPECT_NEAR(-wt.x, std::sin(0.785398f) / 1.5f, 1e-6);  // sin(theta_t) = sin(theta_i)/eta
    EXPECT_LT(wt.z, 0);
    EXPECT_FALSE(refract(wi, n, 1.5f).has_value());  // inside glass at 45 degrees: TIR
}

TEST(Bsdf, LambertianIsKdOverPiOnlyInReflection) {
    Bsdf b;
    b.frame = Frame::from_z(Vec3(0, 0, 1));
    b.ng = Vec3(0, 0, 1);
    b.kd = Rgb(0.5f);
    Vec3 wo = normalize(Vec3(0.3f, 0.2f, 1)), wi = normalize(Vec3(-0.5f, 0.1f, 0.7f));
    EXPECT_NEAR(b.f(wo, wi).g, 0.5 / kPi, 1e-7);
    EXPECT_TRUE(b.f(wo, Vec3(0, 0, -1)).is_black());
}

TEST(Bsdf, OrenNayarReducesToLambertWithoutRoughnessAndIsReciprocal) {
    Bsdf b;
    b.frame = Frame::from_z(Vec3(0, 0, 1));
    b.ng = Vec3(0, 0, 1);
    b.kd = Rgb(1);
    float s = 20 * kPi / 180, s2 = s * s;
    b.on_a = 1 - s2 / (2 * (s2 + 0.33f));
    b.on_b = 0.45f * s2 / (s2 + 0.09f);
    Vec3 wo = normalize(Vec3(0.6f, 0.1f, 0.5f)), wi = normalize(Vec3(0.4f, -0.3f, 0.8f));
    EXPECT_NEAR(b.f(wo, wi).r, b.f(wi, wo).r, 1e-6);
    EXPECT_NE(b.f(wo, wi).r, kInvPi);
}

TEST(Bsdf, PlasticGlossyLobeIsReciprocalAndPeaksAtTheMirrorDirection) {
    Bsdf b;
    b.frame = Frame::from_z(Vec3(0, 0, 1));
    b.ng = Vec3(0, 0, 1);
    b.ks = Rgb(1);
    b.alpha = 0.1f;
    Vec3 wo = normalize(Vec3(0.5f, 0, 1));
    Vec3 mirror(-wo.x, -wo.y, wo.z), off = normalize(Vec3(-0.2f, 0.3f, 1));
    EXPECT_GT(b.f(wo, mirror).r, 10 * b.f(wo, off).r);
    EXPECT_NEAR(b.f(wo, off).r, b.f(off, wo).r, 1e-5);
}

// A clear glass sphere under a uniform white sky, no other light: Whitted splitting with
// Fresnel weights and pbrt-v3's radiance scaling conserves energy, so every ray sees ~1.
TEST(Glass, SphereUnderUniformSkyConservesEnergy) {
    auto s = test::scene_from(
        "Camera \"perspective\" Integrator \"whitted\" \"integer maxdepth\" 14 WorldBegin "
        "LightSource \"infinite\" \"rgb L\" [1 1 1] Material \"glass\" \"float index\" 1.5 "
        "Translate 0 0 5 Shape \"sphere\" WorldEnd");
    for (float x : {0.0f, 0.3f, 0.6f, 0.9f}) {
        Vec3 org(x, 0.1f, 0), dir(0, 0, 1);
        Rgb L = trace_radiance(*s, org, dir, 1, nullptr);
        EXPECT_NEAR(L.r, 1.0, 2e-3) << "offset " << x;
        EXPECT_NEAR(L.b, 1.0, 2e-3) << "offset " << x;
    }
}

TEST(Mirror, ReflectsWithKr) {
    auto s = test::scene_from(
        "Camera \"perspective\" WorldBegin LightSource \"infinite\" \"rgb L\" [2 2 2] "
        "Material \"mirror\" \"rgb Kr\" [0.5 0.25 1] Shape \"sphere\" WorldEnd");
    Rgb L = trace_radiance(*s, Vec3(0.2f, 0.1f, -5), Vec3(0, 0, 1), 1, nullptr);
    EXPECT_NEAR(L.r, 1.0, 1e-6);
    EXPECT_NEAR(L.g, 0.5, 1e-6);
    EXPECT_NEAR(L.b, 2.0, 1e-6);
}

namespace {
// The BSDF of the first material of a one-sphere scene with `material`, at the sphere's top.
Bsdf bsdf_of(const std::string& material, std::vector<std::string>* warnings = nullptr) {
    const std::string text = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n" +
                             material + "\nShape \"sphere\" \"float radius\" 1\nWorldEnd\n";
    auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), {}, [&](const std::string& w) {
        if (warnings) warnings->push_back(w);
    });
    const std::optional<SurfaceHit> h = s->intersect(Vec3(0, 0, 5), Vec3(0, 0, -1), 0, 100);
    EXPECT_TRUE(h.has_value());
    const std::optional<Bsdf> b =
        make_bsdf(*s, s->materials.at(0), h.value_or(SurfaceHit{}), TexContext{});
    EXPECT_TRUE(b.has_value());
    return b.value_or(Bsdf{});
}
}  // namespace

TEST(Materials, UberIsDiffusePlusPlasticsLobePlusGlassesSpecularLobes) {
    const Bsdf b = bsdf_of(
        "Material \"uber\" \"rgb Kd\" [0.5 0.4 0.3] \"rgb Ks\" [0.1 0.1 0.1] \"rgb Kr\" [0.2 0.2 "
        "0.2] \"rgb Kt\" [0.3 0.3 0.3] \"float index\" 1.33 \"float roughness\" 0.05");
    EXPECT_FLOAT_EQ(b.kd.g, 0.4f);
    EXPECT_FLOAT_EQ(b.ks.r, 0.1f);
    EXPECT_FLOAT_EQ(b.kr.r, 0.2f);
    EXPECT_FLOAT_EQ(b.kt.r, 0.3f);
    EXPECT_FLOAT_EQ(b.eta, 1.33f);
    EXPECT_FALSE(b.fresnel_noop);
    // An uber with only Kd is a matte: the same BSDF values.
    const Bsdf u = bsdf_of("Material \"uber\" \"rgb Kd\" [0.5 0.4 0.3] \"rgb Ks\" [0 0 0]");
    const Bsdf m = bsdf_of("Material \"matte\" \"rgb Kd\" [0.5 0.4 0.3]");
    const Vec3 wo = normalize(Vec3(0.3f, 0.2f, 1)), wi = normalize(Vec3(-0.5f, 0.1f, 0.7f));
    EXPECT_FLOAT_EQ(u.f(wo, wi).b, m.f(wo, wi).b);
}

// pbrt-v3's uber gives its microfacet lobe a dielectric Fresnel term from air to its eta, where
// plastic's goes from 1.5 to 1 (and so reaches 1 past about 42 degrees): an uber of index 1 has
// no glossy reflection at all, and against a plastic of the same Ks and roughness its lobe is
// F(1 -> 1.5) over plastic's F(1.5 -> 1), here with the half vector on the normal and the light
// 60 degrees off it (plastic's term 1 there).
TEST(Materials, UbersGlossyFresnelIsAirToItsEta) {
    const std::string lobe = "\"rgb Kd\" [0 0 0] \"rgb Ks\" [1 1 1] \"float roughness\" 0.3";
    const Bsdf u1 = bsdf_of("Material \"uber\" " + lobe + " \"float index\" 1"),
               u15 = bsdf_of("Material \"uber\" " + lobe + " \"float index\" 1.5"),
               p = bsdf_of("Material \"plastic\" " + lobe);
    const float s = std::sin(60 * 3.14159265f / 180), c = std::cos(60 * 3.14159265f / 180);
    for (const auto& [wo_l, wi_l] :
         {std::pair{Vec3(s, 0, c), Vec3(-s, 0, c)}, std::pair{Vec3(0, 0, 1), Vec3(0, 0, 1)}}) {
        auto world = [&](const Vec3& l) {
            return l.x * p.frame.s + l.y * p.frame.t + l.z * p.frame.n;
        };
        const Vec3 wo = world(wo_l), wi = world(wi_l);
        EXPECT_NEAR(u1.f(wo, wi).g, 0.0f, 1e-9f);
        const float fp = p.f(wo, wi).g, fu = u15.f(wo, wi).g;
        ASSERT_GT(fp, 0);
        const float cos_h = wo_l.z;  // the half vector is the normal
        EXPECT_NEAR(fu / fp,
                    fresnel_dielectric(cos_h, 1, 1.5f) / fresnel_dielectric(cos_h, 1.5f, 1), 1e-4f);
    }
    // At 60 degrees plastic's term is total reflection, uber's about 0.09.
    EXPECT_EQ(fresnel_dielectric(c, 1.5f, 1), 1.0f);
    EXPECT_NEAR(fresnel_dielectric(c, 1, 1.5f), 0.089f, 0.001f);
}

// The microfacet roughness a material is built with, along u and v, with pbrt-v3's defaults and
// fallbacks: uber's "roughness" is 0.1, its "uroughness" falls back on it and its "vroughness" on
// "uroughness"; metal's each fall back on "roughness" (0.01); substrate has only the two (0.1
// each), and a "roughness" given to it is ignored with a warning, as pbrt-v3 reports it unused.
// The material is anisotropic where the two differ.
TEST(Materials, RoughnessDefaultsAndFallbacksArePbrtV3s) {
    struct Rough {
        float u, v;
        bool anisotropic;
    };
    auto roughness = [](const std::string& material, std::vector<std::string>* warnings = nullptr) {
        const std::string text =
            "Camera \"perspective\"\nWorldBegin\n" + material + "\nShape \"sphere\"\nWorldEnd\n";
        auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), {}, [&](const std::string& w) {
            if (warnings) warnings->push_back(w);
        });
        const Material& m = s->materials.at(0);
        EXPECT_LT(m.roughness.node, 0);
        EXPECT_LT(m.vroughness.node, 0);
        return Rough{m.roughness.value.r, m.vroughness.value.r, m.anisotropic};
    };
    auto expect = [](const Rough& r, float u, float v, const char* what) {
        EXPECT_FLOAT_EQ(r.u, u) << what;
        EXPECT_FLOAT_EQ(r.v, v) << what;
        EXPECT_EQ(r.anisotropic, u != v) << what;
    };
    expect(roughness("Material \"uber\""), 0.1f, 0.1f, "uber");
    expect(roughness("Material \"uber\" \"float roughness\" 0.3"), 0.3f, 0.3f, "uber r");
    expect(roughness("Material \"uber\" \"float uroughness\" 0.2"), 0.2f, 0.2f, "uber u");
    expect(roughness("Material \"uber\" \"float vroughness\" 0.3"), 0.1f, 0.3f, "uber v");
    expect(roughness("Material \"uber\" \"float roughness\" 0.4 \"float vroughness\" 0.2"), 0.4f,
           0.2f, "uber r v");
    expect(roughness("Material \"metal\""), 0.01f, 0.01f, "metal");
    expect(roughness("Material \"metal\" \"float uroughness\" 0.2"), 0.2f, 0.01f, "metal u");
    expect(roughness("Material \"metal\" \"float roughness\" 0.3 \"float vroughness\" 0.1"), 0.3f,
           0.1f, "metal r v");
    expect(roughness("Material \"substrate\""), 0.1f, 0.1f, "substrate");
    expect(roughness("Material \"substrate\" \"float uroughness\" 0.3"), 0.3f, 0.1f, "substrate u");
    expect(roughness("Material \"plastic\" \"float roughness\" 0.2"), 0.2f, 0.2f, "plastic");
    std::vector<std::string> warnings;
    expect(roughness("Material \"substrate\" \"float roughness\" 0.5", &warnings), 0.1f, 0.1f,
           "substrate r");
    EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                            [](const std::string& w) {
                                return w.find(
                                           "t.pbrt:3:22: warning: \"roughness\" is not a "
                                           "parameter of substrate") != std::string::npos;
                            }),
              1);
}

// An anisotropic microfacet lobe (pbrt-v3's Trowbridge-Reitz with alpha_x along dp/du and alpha_y
// across): its value against pbrt-v3's formula in angles, the highlight stretched along u, and the
// isotropic lobe's value where the two alphas are equal.
TEST(Materials, AnisotropicRoughnessStretchesTheHighlightAlongDpdu) {
    // A plane z = 0 whose u runs along +y: dp/du = (0, 4, 0), not the arbitrary frame's s (+x).
    auto bsdf = [](const std::string& rough) {
        const std::string text =
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
            "Material \"metal\" \"bool remaproughness\" false " +
            rough +
            "\nShape \"trianglemesh\" \"point3 P\" [-2 -2 0  2 -2 0  2 2 0  -2 2 0] "
            "\"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 0 1 1 1 1 0]\nWorldEnd\n";
        auto s = build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
        const std::optional<SurfaceHit> h =
            s->intersect(Vec3(0.3f, 0.2f, 5), Vec3(0, 0, -1), 0, 100);
        EXPECT_TRUE(h.has_value());
        const std::optional<Bsdf> b =
            make_bsdf(*s, s->materials.at(0), h.value_or(SurfaceHit{}), TexContext{});
        EXPECT_TRUE(b.has_value());
        return b.value_or(Bsdf{});
    };
    const float ax = 0.3f, ay = 0.05f;
    const Bsdf b = bsdf("\"float uroughness\" 0.3 \"float vroughness\" 0.05");
    ASSERT_TRUE(b.anisotropic);
    EXPECT_FLOAT_EQ(b.alpha, ax);
    EXPECT_FLOAT_EQ(b.alpha_y, ay);
    EXPECT_NEAR(std::abs(b.frame.s.y), 1, 1e-6);  // along dp/du
    EXPECT_NEAR(std::abs(b.frame.t.x), 1, 1e-6);
    // The microfacet term against pbrt-v3's D and Smith G in angles (theta, and phi from u, +y
    // here, for the half vector and each direction).
    auto pbrt_d = [&](const Vec3& wh) {
        const double cos_t = wh.z, sin_t = std::sqrt(1 - cos_t * cos_t),
                     tan2 = sin_t * sin_t / (cos_t * cos_t);
        const double phi = std::atan2(wh.x, wh.y);
        const double e = (std::cos(phi) * std::cos(phi) / (ax * ax) +
                          std::sin(phi) * std::sin(phi) / (ay * ay)) *
                         tan2;
        return 1 / (3.14159265358979 * ax * ay * std::pow(cos_t, 4) * (1 + e) * (1 + e));
    };
    auto pbrt_lambda = [&](const Vec3& w) {
        const double cos_t = w.z, tan_t = std::sqrt(1 - cos_t * cos_t) / cos_t;
        const double phi = std::atan2(w.x, w.y);
        const double a = std::sqrt(std::cos(phi) * std::cos(phi) * ax * ax +
                                   std::sin(phi) * std::sin(phi) * ay * ay);
        return (-1 + std::sqrt(1 + a * a * tan_t * tan_t)) / 2;
    };
    const Vec3 wo = normalize(Vec3(0.3f, -0.2f, 1)), wi = normalize(Vec3(-0.1f, 0.25f, 1));
    const Vec3 wh = normalize(wo + wi);
    // Local and world frames agree up to the signs of s and t, which D and G do not see.
    const double expected =
        pbrt_d(wh) / (1 + pbrt_lambda(wo) + pbrt_lambda(wi)) / (4 * wo.z * wi.z);
    const float fresnel = fresnel_conductor(dot(wi, wh), b.conductor_eta, b.conductor_k).r;
    EXPECT_NEAR(b.f(wo, wi).r / fresnel / expected, 1, 1e-4);  // float arithmetic
    // Tilting the half vector 10 degrees along u keeps far more of the lobe than along v.
    const Vec3 n(0, 0, 1);
    auto mirrored = [&](const Vec3& h) { return normalize(2 * dot(n, h) * h - n); };
    const float t = std::tan(10 * 3.14159265f / 180);
    const float along_u = b.f(n, mirrored(normalize(Vec3(0, t, 1)))).r;
    const float along_v = b.f(n, mirrored(normalize(Vec3(t, 0, 1)))).r;
    EXPECT_GT(along_u, 50 * along_v);
    // Equal alphas: the isotropic lobe's value (the same formula, rounded differently).
    Bsdf iso = bsdf("\"float roughness\" 0.2");
    ASSERT_FALSE(iso.anisotropic);
    Bsdf same = iso;
    same.anisotropic = true;
    same.alpha_y = same.alpha;
    for (const Vec3& d : {Vec3(0.3f, -0.2f, 1), Vec3(-0.7f, 0.1f, 0.4f), Vec3(0.05f, 0.5f, 1)}) {
        const Vec3 w = normalize(d);
        EXPECT_NEAR(same.f(wo, w).r / iso.f(wo, w).r, 1, 1e-5);
    }
}

// pbrt-v3's metal: a microfacet lobe with the Fresnel equations of a conductor of complex index
// eta + i k (pbrt-v3's default is copper), checked against the equations in complex numbers.
TEST(Materials, MetalTakesTheConductorsFresnelEquations) {
    const Bsdf b = bsdf_of("Material \"metal\"");
    EXPECT_TRUE(b.conductor);
    // At normal incidence ((n-1)^2 + k^2) / ((n+1)^2 + k^2): copper's red, n 0.2004, k 3.9129.
    EXPECT_NEAR(fresnel_conductor(1, b.conductor_eta, b.conductor_k).r, 0.95215, 1e-4);
    const Bsdf gold = bsdf_of(
        "Material \"metal\" \"rgb eta\" [0.143 0.374 1.442] \"rgb k\" "
        "[3.983 2.385 1.603] \"float roughness\" 0.2");
    const Rgb eta = gold.conductor_eta, k = gold.conductor_k;
    EXPECT_FLOAT_EQ(eta.b, 1.442f);
    EXPECT_FLOAT_EQ(k.b, 1.603f);
    for (double deg : {0.0, 30.0, 60.0, 80.0, 89.0}) {
        const double c = std::cos(deg * 3.14159265358979 / 180), s2 = 1 - c * c;
        const std::complex<double> n(eta.b, k.b), root = std::sqrt(n * n - s2);
        const double rs = std::norm((c - root) / (c + root)),
                     rp = std::norm((n * n * c - root) / (n * n * c + root));
        EXPECT_NEAR(fresnel_conductor(float(c), eta, k).b, (rs + rp) / 2, 2e-5) << deg;
        EXPECT_FLOAT_EQ(fresnel_conductor(float(-c), eta, k).b,
                        fresnel_conductor(float(c), eta, k).b);
    }
    EXPECT_NEAR(fresnel_conductor(0, eta, k).g, 1, 1e-6);  // grazing
    // Reflection only, and brighter towards grazing.
    const Vec3 n(0, 0, 1);
    const Vec3 wo = normalize(Vec3(0.2f, 0, 1)), wi = normalize(Vec3(-0.2f, 0, 1));
    EXPECT_GT(gold.f(wo, wi).r, 0);
    EXPECT_TRUE(gold.f(wo, -n).is_black());
}

TEST(Materials, UnknownAndUnrenderedMaterialsAreMatteWithAWarning) {
    std::vector<std::string> warnings;
    const Bsdf b =
        bsdf_of("Material \"coateddiffuse\" \"rgb Kd\" [0.2 0.3 0.4] \"float eta\" 1.3", &warnings);
    EXPECT_FLOAT_EQ(b.kd.b, 0.4f);
    EXPECT_TRUE(b.ks.is_black());
    // (Besides the scene's own: no integrator, no lights.)
    auto count = [&](const std::string& text) {
        return std::count_if(warnings.begin(), warnings.end(), [&](const std::string& w) {
            return w.find(text) != std::string::npos;
        });
    };
    EXPECT_EQ(
        count("t.pbrt:4:1: warning: material \"coateddiffuse\" is rendered as \"matte\" "
              "with its Kd (cmam renders matte, mirror, glass, plastic, uber, metal, substrate, "
              "translucent, fourier, hair, disney, subsurface, kdsubsurface and mix)"),
        1);
    EXPECT_EQ(count("material"), 1);  // its other parameters (eta) are not reported one by one
    warnings.clear();
    // Substrate, translucent, uber's opacity of 1 (its default, what published scenes give) and
    // rough glass are rendered as pbrt-v3 renders them: no warning.
    warnings.clear();
    (void)bsdf_of("Material \"substrate\" \"float uroughness\" 0.1 \"float vroughness\" 0.3",
                  &warnings);
    (void)bsdf_of("Material \"uber\" \"rgb opacity\" [1 1 1]", &warnings);
    (void)bsdf_of("Material \"translucent\" \"rgb Kd\" [0.2 0.2 0.2]", &warnings);
    (void)bsdf_of("Material \"glass\" \"float uroughness\" 0.05 \"float vroughness\" 0.05",
                  &warnings);
    EXPECT_EQ(count("material"), 0);
    EXPECT_EQ(count("ignored"), 0);
    // An opacity below 1 beside the uber's own specular lobes (which the Bsdf's one specular
    // transmission cannot hold with it): opaque, with a warning.
    (void)bsdf_of("Material \"uber\" \"rgb opacity\" [0.5 0.5 0.5] \"rgb Kr\" [0.2 0.2 0.2]",
                  &warnings);
    EXPECT_EQ(count("uber \"opacity\" ignored beside its specular Kr or Kt"), 1);
    // Without them: the lobes times the opacity, the rest passed straight through.
    warnings.clear();
    const Bsdf half = bsdf_of(
        "Material \"uber\" \"rgb opacity\" [0.25 0.5 1] \"rgb Kd\" [0.4 0.4 0.4] \"rgb Ks\" [0 0 "
        "0]",
        &warnings);
    EXPECT_EQ(count("opacity"), 0);
    EXPECT_FLOAT_EQ(half.kd.r, 0.1f);
    EXPECT_FLOAT_EQ(half.kd.b, 0.4f);
    EXPECT_FLOAT_EQ(half.kt.r, 0.75f);
    EXPECT_FLOAT_EQ(half.kt.g, 0.5f);
    EXPECT_FLOAT_EQ(half.kt.b, 0.0f);
    EXPECT_FLOAT_EQ(half.eta, 1.0f);
}

namespace {
// pbrt-v3's FresnelBlend, written out in angles (theta and phi of each direction) from
// Ashikhmin and Shirley's paper's form: the half vector from the two directions' angles, the
// Trowbridge-Reitz D from its slope, Schlick's Fresnel term.
double fresnel_blend(double rd, double rs, double alpha, double th_o, double ph_o, double th_i,
                     double ph_i) {
    const double pi = 3.14159265358979;
    auto dir = [](double th, double ph) {
        return std::array<double, 3>{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                                     std::cos(th)};
    };
    const auto o = dir(th_o, ph_o), i = dir(th_i, ph_i);
    std::array<double, 3> h{o[0] + i[0], o[1] + i[1], o[2] + i[2]};
    const double len = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (double& c : h) c /= len;
    const double ih = i[0] * h[0] + i[1] * h[1] + i[2] * h[2];
    const double tan2_h = (1 - h[2] * h[2]) / (h[2] * h[2]);
    const double d =
        1 / (pi * alpha * alpha * std::pow(h[2], 4) * std::pow(1 + tan2_h / (alpha * alpha), 2));
    const double diffuse = 28 * rd / (23 * pi) * (1 - rs) *
                           (1 - std::pow(1 - std::cos(th_i) / 2, 5)) *
                           (1 - std::pow(1 - std::cos(th_o) / 2, 5));
    const double schlick = rs + std::pow(1 - ih, 5) * (1 - rs);
    return diffuse + d * schlick / (4 * ih * std::max(std::cos(th_i), std::cos(th_o)));
}
}  // namespace

// pbrt-v3's substrate is a FresnelBlend: a diffuse base whose light the coat's Fresnel term
// (Schlick's) takes away towards grazing angles, under the coat's microfacet reflection.
TEST(Materials, SubstrateIsPbrtV3sFresnelBlend) {
    const Bsdf b = bsdf_of(
        "Material \"substrate\" \"rgb Kd\" [0.6 0.3 0.1] \"rgb Ks\" [0.04 0.1 0.5] "
        "\"float uroughness\" 0.2 \"float vroughness\" 0.2 \"bool remaproughness\" \"false\"");
    ASSERT_TRUE(b.fresnel_blend);
    EXPECT_FLOAT_EQ(b.alpha, 0.2f);
    EXPECT_TRUE(b.kr.is_black() && b.kt.is_black());
    // The sphere's hit faces +z: its shading frame is the test's.
    const float ks[3] = {0.04f, 0.1f, 0.5f}, kd[3] = {0.6f, 0.3f, 0.1f};
    for (auto [th_o, ph_o, th_i, ph_i] : {std::array<double, 4>{0.3, 0.0, 0.5, 2.5},
                                          {1.2, 1.0, 0.2, 4.0},
                                          {0.7, 0.0, 0.7, 3.14159265},  // the mirror direction
                                          {1.45, 0.5, 1.4, 3.0}}) {
        auto world = [&](double th, double ph) {
            const Vec3 l(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                         float(std::cos(th)));
            return b.frame.to_world(l);
        };
        const Rgb v = b.f(world(th_o, ph_o), world(th_i, ph_i));
        const float f[3] = {v.r, v.g, v.b};
        for (int c = 0; c < 3; ++c) {
            const double want = fresnel_blend(kd[c], ks[c], 0.2, th_o, ph_o, th_i, ph_i);
            EXPECT_NEAR(f[c], want, 2e-4 * want) << th_o << " " << th_i << " channel " << c;
        }
        EXPECT_TRUE(b.f(world(th_o, ph_o), -world(th_i, ph_i)).is_black());  // no transmission
    }
    // A mix weighs its value, not its reflectances.
    Bsdf half = b;
    half.scale(Rgb(0.5f));
    const Vec3 wo = normalize(Vec3(0.3f, 0.1f, 1)), wi = normalize(Vec3(-0.5f, 0.2f, 1));
    EXPECT_NEAR(half.f(wo, wi).g, 0.5f * b.f(wo, wi).g, 1e-6f);
}

// pbrt-v3's mix adds its materials' lobes into one BSDF. Bsdf::add sums lobes of different kinds,
// and of one kind with the same parameters, into one Bsdf; lobes of one kind with different
// parameters go on a layer, whose value adds to the sum's. Specular lobes the integrator could
// not follow as one are refused.
TEST(Materials, AddSumsTheLobesOfTwoBsdfs) {
    const Bsdf matte = bsdf_of("Material \"matte\" \"rgb Kd\" [0.5 0.4 0.3]");
    const Bsdf glass = bsdf_of("Material \"glass\" \"float index\" 1.33");
    const Bsdf plastic = bsdf_of(
        "Material \"plastic\" \"rgb Kd\" [0.2 0.2 0.2] \"rgb Ks\" [0.3 0.3 0.3] "
        "\"float roughness\" 0.1");
    const Vec3 wo = normalize(Vec3(0.3f, 0.1f, 1)), wi = normalize(Vec3(-0.5f, 0.2f, 1));
    std::forward_list<Bsdf> layers;
    // Glass's specular lobes and a matte's Lambertian one, each weighted.
    Bsdf sum = glass, part = matte;
    sum.scale(Rgb(0.25f));
    part.scale(Rgb(0.75f));
    ASSERT_TRUE(sum.takes(part));
    sum.add(part, layers);
    EXPECT_EQ(sum.layer, nullptr);
    EXPECT_FLOAT_EQ(sum.kr.g, 0.25f * glass.kr.g);
    EXPECT_FLOAT_EQ(sum.kt.g, 0.25f * glass.kt.g);
    EXPECT_FLOAT_EQ(sum.eta, 1.33f);
    EXPECT_FALSE(sum.fresnel_noop);
    EXPECT_NEAR(sum.f(wo, wi).r, 0.75f * matte.f(wo, wi).r, 1e-7f);
    // A matte and a plastic: the Lambertian lobes add, the glossy one is plastic's; either way
    // round.
    for (const bool plastic_first : {true, false}) {
        sum = plastic_first ? plastic : matte;
        sum.add(plastic_first ? matte : plastic, layers);
        EXPECT_EQ(sum.layer, nullptr);
        EXPECT_FLOAT_EQ(sum.kd.b, 0.2f + 0.3f);
        EXPECT_NEAR(sum.f(wo, wi).b, plastic.f(wo, wi).b + matte.f(wo, wi).b, 1e-6f);
    }
    // Lobes of one kind with different parameters: the second material's go on a layer, and the
    // value is the sum. Two roughnesses, two Oren-Nayar sigmas, a metal's Fresnel term and a
    // dielectric's, a glass (whose specular lobes stay in the sum) and a rough glass.
    const std::pair<const char*, const char*> layered[] = {
        {"Material \"plastic\" \"float roughness\" 0.1",
         "Material \"plastic\" \"float roughness\" 0.3"},
        {"Material \"matte\" \"float sigma\" 10", "Material \"matte\" \"float sigma\" 30"},
        {"Material \"metal\"", "Material \"uber\" \"float roughness\" 0.2"},
        {"Material \"uber\" \"rgb Kr\" [0.5 0.5 0.5] \"float roughness\" 0.05",
         "Material \"glass\" \"float uroughness\" 0.3 \"float vroughness\" 0.3"}};
    for (const auto& [a, b] : layered) {
        const Bsdf first = bsdf_of(a), second = bsdf_of(b);
        sum = first;
        ASSERT_TRUE(sum.takes(second)) << a << " + " << b;
        sum.add(second, layers);
        ASSERT_NE(sum.layer, nullptr) << a;
        for (const Vec3& w : {wi, Vec3(wi.x, wi.y, -wi.z)}) {  // reflected and transmitted
            const Rgb want = first.f(wo, w) + second.f(wo, w), got = sum.f(wo, w);
            EXPECT_NEAR(got.g, want.g, 1e-6f * (1 + want.g)) << a << " + " << b;
        }
        EXPECT_EQ(sum.kr.g, first.kr.g + second.kr.g) << a;
        // Scaling scales the layers too.
        const float whole = sum.f(wo, wi).g;
        sum.scale(Rgb(0.5f));
        EXPECT_NEAR(sum.f(wo, wi).g, 0.5f * whole, 1e-6f) << a;
    }
    // Specular lobes that do not fit: a mirror's reflection (no Fresnel term) and a glass's, two
    // glasses' indices.
    EXPECT_FALSE(bsdf_of("Material \"mirror\"").takes(bsdf_of("Material \"glass\"")));
    EXPECT_FALSE(bsdf_of("Material \"glass\" \"float index\" 1.5")
                     .takes(bsdf_of("Material \"glass\" \"float index\" 1.33")));
    // A lobe weighted zero is no lobe: a mix of amount 1 adds nothing, and no layer.
    Bsdf none = bsdf_of("Material \"plastic\" \"float roughness\" 0.3");
    none.scale(Rgb(0));
    sum = plastic;
    sum.add(none, layers);
    EXPECT_EQ(sum.layer, nullptr);
    EXPECT_EQ(sum.f(wo, wi).g, plastic.f(wo, wi).g);
}

// pbrt-v3's translucent: Lambertian reflection and transmission of Kd times reflect and
// transmit, and microfacet reflection and transmission (into 1.5) of Ks times each.
TEST(Materials, TranslucentReflectsAndTransmitsBothItsLobes) {
    const Bsdf b = bsdf_of(
        "Material \"translucent\" \"rgb Kd\" [0.5 0.4 0.3] \"rgb Ks\" [0.2 0.2 0.2] "
        "\"rgb reflect\" [0.5 0.5 0.5] \"rgb transmit\" [0.25 0.5 1] "
        "\"float roughness\" 0.3 \"bool remaproughness\" \"false\"");
    EXPECT_FLOAT_EQ(b.kd.r, 0.25f);
    EXPECT_FLOAT_EQ(b.kt_diffuse.g, 0.2f);
    EXPECT_FLOAT_EQ(b.ks.b, 0.1f);
    EXPECT_FLOAT_EQ(b.kt_rough.b, 0.2f);
    EXPECT_FLOAT_EQ(b.lobe_eta_t, 1.5f);
    EXPECT_FLOAT_EQ(b.alpha, 0.3f);
    EXPECT_TRUE(b.kr.is_black() && b.kt.is_black());  // no specular lobe
    // Across the surface, away from the refracted direction's lobe: the Lambertian transmission.
    const Vec3 n = b.frame.to_world(Vec3(0, 0, 1));
    const Vec3 wo = b.frame.to_world(normalize(Vec3(0.9f, 0, 0.2f))),
               wi = b.frame.to_world(normalize(Vec3(0.9f, 0, -0.2f)));
    Bsdf diffuse_only = b;
    diffuse_only.kt_rough = Rgb();
    EXPECT_NEAR(diffuse_only.f(wo, wi).g, 0.2 / 3.14159265, 1e-6);
    EXPECT_GT(b.f(n, -n).g, diffuse_only.f(n, -n).g);  // the microfacet lobe straight through
    // Reflect and transmit both black: no lobe at all.
    const Bsdf none =
        bsdf_of("Material \"translucent\" \"rgb reflect\" [0 0 0] \"rgb transmit\" [0 0 0]");
    EXPECT_FALSE(none.has_nonspecular());
}

// pbrt-v3's glass with a roughness: microfacet reflection with the dielectric's Fresnel term and
// microfacet transmission in place of the specular lobes; smooth (specular) where both
// roughnesses are 0.
TEST(Materials, RoughGlassIsMicrofacetReflectionAndTransmission) {
    const Bsdf smooth = bsdf_of("Material \"glass\" \"float index\" 1.33");
    EXPECT_FALSE(smooth.has_nonspecular());
    EXPECT_FLOAT_EQ(smooth.kt.r, 1);
    const Bsdf b = bsdf_of(
        "Material \"glass\" \"float index\" 1.33 \"rgb Kt\" [0.9 0.8 0.7] \"float uroughness\" "
        "0.3 \"float vroughness\" 0.3 \"bool remaproughness\" \"false\"");
    EXPECT_TRUE(b.kr.is_black() && b.kt.is_black());
    EXPECT_FLOAT_EQ(b.ks.r, 1);
    EXPECT_FLOAT_EQ(b.kt_rough.b, 0.7f);
    EXPECT_FLOAT_EQ(b.alpha, 0.3f);
    EXPECT_FLOAT_EQ(b.lobe_eta_t, 1.33f);
    // Straight through at normal incidence the microfacet normal is n: pbrt-v3's (1 - F) D(h) G
    // |wi.h| |wo.h| / (wo.h + eta wi.h)^2 (eta the index on wi's side over wo's; its eta^2 and
    // the radiance's 1 / eta^2 cancel) with D(n) = 1 / (pi alpha^2), G = 1 (Lambda is 0 along n):
    // (1 - F) D / (1 - 1.33)^2 going in, (1 - F) D / (1 - 1 / 1.33)^2 coming out.
    const double f0 = std::pow(0.33 / 2.33, 2), d = 1 / (3.14159265358979 * 0.09);
    const Vec3 n = b.frame.to_world(Vec3(0, 0, 1));
    const double in = 0.7 * (1 - f0) * d / (0.33 * 0.33),
                 out = 0.7 * (1 - f0) * d / std::pow(1 - 1 / 1.33, 2);
    EXPECT_NEAR(b.f(n, -n).b, in, 1e-4 * in);
    EXPECT_NEAR(b.f(-n, n).b, out, 1e-4 * out);
    // Reflection: the microfacet lobe with glass's Fresnel term from air.
    const Vec3 wo = normalize(Vec3(0.4f, 0, 1)), wi = normalize(Vec3(-0.4f, 0, 1));
    const Vec3 wo_w = b.frame.to_world(wo), wi_w = b.frame.to_world(wi);
    const float cos = wo.z;
    const double tr_d = 1 / (3.14159265358979 * 0.09);  // h = n
    const double lambda = (-1 + std::sqrt(1 + 0.09 * (1 - cos * cos) / (cos * cos))) / 2;
    EXPECT_NEAR(b.f(wo_w, wi_w).r,
                fresnel_dielectric(cos, 1, 1.33f) * tr_d / (1 + 2 * lambda) / (4 * cos * cos),
                1e-4);
    // A roughness of 0 along both axes is smooth glass again.
    const Bsdf zero = bsdf_of("Material \"glass\" \"float uroughness\" 0 \"float vroughness\" 0");
    EXPECT_FALSE(zero.has_nonspecular());
}

// The microfacet lobes' values and density at random directions against pbrt-v3's formulas,
// written in its tan^2 form in double: D = 1 / (pi ax ay cos^4 (1 + tan^2 (cos^2 phi / ax^2 +
// sin^2 phi / ay^2))^2), Lambda = (sqrt(1 + tan^2 (ax^2 cos^2 phi + ay^2 sin^2 phi)) - 1) / 2,
// G = 1 / (1 + Lambda(wo) + Lambda(wi)); reflection F D G / (4 cos_i cos_o) (plastic's Fresnel
// from 1.5 to 1) with density D G1(wo) / (4 cos_o), and transmission as at
// RoughGlassIsMicrofacetReflectionAndTransmission. Isotropic and anisotropic.
TEST(Bsdf, MicrofacetValuesAndDensitiesArePbrtV3sFormulasEverywhere) {
    using V = std::array<double, 3>;
    auto d_of = [](V h, double ax, double ay) {
        const double l = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        for (double& c : h) c /= l;
        const double cos2 = h[2] * h[2], sin2 = 1 - cos2, tan2 = sin2 / cos2;
        const double cos2phi = sin2 > 0 ? h[0] * h[0] / sin2 : 1, sin2phi = 1 - cos2phi;
        const double e = tan2 * (cos2phi / (ax * ax) + sin2phi / (ay * ay));
        return 1 / (3.14159265358979 * ax * ay * cos2 * cos2 * (1 + e) * (1 + e));
    };
    auto lambda_of = [](const V& w, double ax, double ay) {
        const double cos2 = w[2] * w[2], sin2 = 1 - cos2, tan2 = sin2 / cos2;
        const double cos2phi = sin2 > 0 ? w[0] * w[0] / sin2 : 1, sin2phi = 1 - cos2phi;
        return (std::sqrt(1 + tan2 * (ax * ax * cos2phi + ay * ay * sin2phi)) - 1) / 2;
    };
    auto fr = [](double c, double ei, double et) {
        if (c < 0) {
            std::swap(ei, et);
            c = -c;
        }
        const double st = ei / et * std::sqrt(std::max(0.0, 1 - c * c));
        if (st >= 1) return 1.0;
        const double ct = std::sqrt(1 - st * st);
        const double a = (et * c - ei * ct) / (et * c + ei * ct),
                     b = (ei * c - et * ct) / (ei * c + et * ct);
        return (a * a + b * b) / 2;
    };
    uint32_t state = 12345;
    auto uniform = [&] {
        state = state * 1664525u + 1013904223u;
        return (state >> 8) * (1.0 / 16777216.0);
    };
    auto direction = [&](double sign) {  // on the side of `sign`, not within 3 degrees of the plane
        const double z = 0.05 + 0.95 * uniform(), phi = 2 * 3.14159265358979 * uniform();
        const double r = std::sqrt(1 - z * z);
        return V{r * std::cos(phi), r * std::sin(phi), sign * z};
    };
    auto vec = [](const V& v) { return Vec3(float(v[0]), float(v[1]), float(v[2])); };
    for (const auto& [ax, ay] : {std::pair{0.3, 0.3}, std::pair{0.05, 0.05}, std::pair{0.4, 0.1}}) {
        Bsdf b;
        b.frame = Frame{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
        b.ng = Vec3(0, 0, 1);
        b.ks = Rgb(1);
        b.alpha = float(ax);
        b.alpha_y = float(ay);
        b.anisotropic = ax != ay;
        Bsdf t = b;  // rough transmission alone, from 1 into 1.33
        t.ks = Rgb();
        t.kt_rough = Rgb(1);
        t.lobe_eta_i = 1;
        t.lobe_eta_t = 1.33f;
        for (int k = 0; k < 200; ++k) {
            const V wo = direction(1), wi = direction(1), wt = direction(-1);
            const V h{wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
            const double hl = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            const double ih = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
            const double d = d_of(h, ax, ay), lo = lambda_of(wo, ax, ay);
            const double g = 1 / (1 + lo + lambda_of(wi, ax, ay));
            const double f = fr(ih, 1.5, 1) * d * g / (4 * wi[2] * wo[2]);
            const double p = d / (1 + lo) / (4 * wo[2]);
            EXPECT_NEAR(b.f(vec(wo), vec(wi)).r, f, 2e-4 * f + 1e-6) << ax << " " << ay << " " << k;
            EXPECT_NEAR(b.pdf(b.outgoing(vec(wo)), vec(wi)), p, 2e-4 * p + 1e-6) << k;
            // Into the glass (eta = 1.33 on wt's side): h = normalize(wo + eta wt), facing up.
            const double eta = 1.33;
            V ht{wo[0] + eta * wt[0], wo[1] + eta * wt[1], wo[2] + eta * wt[2]};
            const double tl = std::sqrt(ht[0] * ht[0] + ht[1] * ht[1] + ht[2] * ht[2]);
            for (double& c : ht) c *= (ht[2] < 0 ? -1 : 1) / tl;
            const double oh = wo[0] * ht[0] + wo[1] * ht[1] + wo[2] * ht[2],
                         th = wt[0] * ht[0] + wt[1] * ht[1] + wt[2] * ht[2];
            if (oh * th > 0) continue;  // no refraction between them
            const double gt = 1 / (1 + lo + lambda_of(wt, ax, ay)), den = oh + eta * th;
            const double ft = (1 - fr(oh, 1, 1.33)) * d_of(ht, ax, ay) * gt *
                              std::abs(th * oh / (wt[2] * wo[2] * den * den));
            EXPECT_NEAR(t.f(vec(wo), vec(wt)).r, ft, 2e-4 * ft + 1e-6) << ax << " " << k;
        }
    }
}
