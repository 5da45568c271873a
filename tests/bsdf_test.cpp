// Fresnel, refraction, BSDF values and glass energy conservation.
#include <gtest/gtest.h>

#include "render/integrator.h"
#include "render/shading.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

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
    Vec3 wt;
    ASSERT_TRUE(refract(wi, n, 1 / 1.5f, &wt));
    EXPECT_NEAR(length(wt), 1, 1e-6);
    EXPECT_NEAR(-wt.x, std::sin(0.785398f) / 1.5f, 1e-6);  // sin(theta_t) = sin(theta_i)/eta
    EXPECT_LT(wt.z, 0);
    EXPECT_FALSE(refract(wi, n, 1.5f, &wt));  // inside glass at 45 degrees: TIR
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
