// pbrt-v3's hair BSDF and "hair" material: energy conservation, sampling that matches the value,
// the absorption's three sources, and the fibre's frame on a curve.
#include "render/hair.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/shading.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {
// A small generator of uniform floats in [0, 1).
struct Uniform {
    uint32_t state;
    float operator()() {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * (1.0f / 16777216.0f);
    }
};
Vec3 uniform_sphere(float u1, float u2) {
    const float z = 1 - 2 * u1, r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
}  // namespace

// Without absorption the fibre scatters all the light it gets: f |cos theta_i| integrates to 1
// over the sphere (uniform directions, 60,000 a case), for every roughness and offset h.
TEST(Hair, WithoutAbsorptionItConservesEnergy) {
    Uniform u{7};
    for (float beta_m : {0.2f, 0.5f, 0.8f})
        for (float beta_n : {0.2f, 0.5f, 0.8f}) {
            HairParams p;
            p.beta_m = beta_m;
            p.beta_n = beta_n;
            p.h = -1 + 2 * u();
            const Vec3 wo = uniform_sphere(u(), u());
            const int n = 60000;
            double sum = 0;
            for (int i = 0; i < n; ++i) {
                const Vec3 wi = uniform_sphere(u(), u());
                sum += hair_f(p, wo, wi).g * std::abs(wi.z);
            }
            EXPECT_NEAR(sum * 4 * kPi / n, 1, 0.05) << beta_m << " " << beta_n;
        }
}

// Without absorption the sampling density is the value (each lobe picked by its share, M_p and
// N_p drawn exactly): every sample weighs f |cos| / pdf = 1. With absorption, the samples'
// estimate of the albedo is the quadrature's: they follow the density they report.
TEST(Hair, SamplesWeighWhatTheValueSays) {
    Uniform u{11};
    for (int c = 0; c < 4; ++c) {
        HairParams p;
        p.beta_m = 0.2f + 0.6f * u();
        p.beta_n = 0.2f + 0.6f * u();
        p.h = -1 + 2 * u();
        p.alpha = 2;
        const Vec3 wo = uniform_sphere(u(), u());
        for (int i = 0; i < 2000; ++i) {
            const std::optional<Vec3> wi = hair_sample(p, wo, u(), u(), u());
            if (!wi) continue;
            const float pdf = hair_pdf(p, wo, *wi);
            ASSERT_GT(pdf, 0);
            const Rgb w = hair_f(p, wo, *wi) * (std::abs(wi->z) / pdf);
            EXPECT_NEAR(w.r, 1, 2e-3) << c << " " << i;
            EXPECT_NEAR(w.b, 1, 2e-3);
        }
        p.sigma_a = Rgb(0.2f, 0.8f, 2.5f);
        // The albedo by the midpoint rule on an equal-area grid (z by phi, 400 by 800 cells),
        // and by 100,000 samples.
        double grid = 0;
        for (int iz = 0; iz < 400; ++iz)
            for (int ip = 0; ip < 800; ++ip) {
                const Vec3 wi = uniform_sphere((iz + 0.5f) / 400, (ip + 0.5f) / 800);
                grid += hair_f(p, wo, wi).g * std::abs(wi.z);
            }
        grid *= 4 * kPi / (400 * 800);
        const int n = 100000;
        double sampled = 0;
        for (int i = 0; i < n; ++i) {
            const std::optional<Vec3> s = hair_sample(p, wo, u(), u(), u());
            if (s) sampled += hair_f(p, wo, *s).g * std::abs(s->z) / hair_pdf(p, wo, *s);
        }
        EXPECT_NEAR(sampled / n, grid, 0.01 * grid) << c;
    }
}

// A sample carries the value and the density the two functions give in its direction, bit for
// bit (the renderer takes them from the sample, computed from one refracted path), and a model
// made once gives what one made per call does.
TEST(Hair, SampleCarriesExactlyTheValueAndDensity) {
    Uniform u{5};
    int drawn = 0;
    for (int c = 0; c < 20; ++c) {
        HairParams p;
        p.beta_m = 0.05f + 0.9f * u();
        p.beta_n = 0.05f + 0.9f * u();
        p.h = -1 + 2 * u();
        p.eta = 1.2f + u();
        p.alpha = 4 * u();
        p.sigma_a = Rgb(3 * u(), 3 * u(), 3 * u());
        const HairModel m(p);
        for (int i = 0; i < 200; ++i) {
            const Vec3 wo = uniform_sphere(u(), u());
            const float u0 = u(), u1 = u(), u2 = u();
            const std::optional<HairSample> s = hair_sample_f(m, hair_outgoing(m, wo), u0, u1, u2);
            const std::optional<Vec3> wi = hair_sample(p, wo, u0, u1, u2);
            ASSERT_EQ(s.has_value(), wi.has_value());
            if (!s) continue;
            ++drawn;
            EXPECT_EQ(s->wi.x, wi->x);
            EXPECT_EQ(s->wi.z, wi->z);
            const Rgb f = hair_f(p, wo, s->wi);
            EXPECT_EQ(s->f.r, f.r) << c << " " << i;
            EXPECT_EQ(s->f.g, f.g);
            EXPECT_EQ(s->f.b, f.b);
            EXPECT_EQ(s->pdf, hair_pdf(p, wo, s->wi)) << c << " " << i;
            EXPECT_EQ(hair_pdf(m, hair_outgoing(m, wo), s->wi), s->pdf);
        }
    }
    EXPECT_GT(drawn, 3500);
}

// The lobes leave where pbrt-v3's exit angles put them: at h = 0 (through the fibre's axis),
// perpendicular to the fibre, R is reflected straight back (Phi = -2 gamma_o = 0) and TT passes
// straight through (Phi = pi), with about (1 - F)^2 = 0.91 of the light against R's F = 0.047.
TEST(Hair, AtTheAxisTransmissionGoesStraightThrough) {
    HairParams p;
    p.beta_m = 0.2f;
    p.beta_n = 0.2f;
    p.alpha = 0;
    const Vec3 wo(0, 1, 0), back(0, 1, 0), through(0, -1, 0), side(0, 0, 1);
    const float f_through = hair_f(p, wo, through).g, f_back = hair_f(p, wo, back).g,
                f_side = hair_f(p, wo, side).g;
    EXPECT_GT(f_through, 10 * f_back);
    EXPECT_GT(f_back, 3 * f_side);
}

// The material's absorption: sigma_a when given (its colour then ignored, with pbrt-v3's
// warning), else the colour after multiple scattering, else the melanin concentrations, else
// eumelanin 1.3; the fibre's frame runs along the curve (s = dp/du), its h across it.
TEST(Hair, MaterialTakesItsAbsorptionAsPbrtV3Does) {
    auto bsdf_at = [](const std::string& material, std::vector<std::string>* warnings) {
        pbrt::SceneDesc d = pbrt::parse_string(
            "Camera \"perspective\" WorldBegin LightSource \"point\" " + material +
                " Shape \"curve\" \"point P\" [-2 0 0  -0.6666667 0 0  0.6666667 0 0  2 0 0] "
                "\"float width\" 0.4 WorldEnd",
            "h.pbrt");
        auto s = build_scene(d, {}, [&](const std::string& w) {
            if (warnings) warnings->push_back(w);
        });
        const std::optional<SurfaceHit> h =
            s->intersect(Vec3(0, 0.1f, 5), Vec3(0, 0, -1), 0, 1e30f);
        EXPECT_TRUE(h);
        TexContext ctx;
        ctx.u = h->u;
        ctx.v = h->v;
        ctx.p = h->p;
        return make_bsdf(*s, s->materials.at(0), *h, ctx).value();
    };
    const Bsdf def = bsdf_at("Material \"hair\"", nullptr);
    ASSERT_TRUE(def.hair);
    EXPECT_NEAR(def.hair_model.sigma_a.b, 1.3f * 1.37f, 1e-5);
    EXPECT_NEAR(def.hair_model.h, -1 + 2 * (0.5f - 0.1f / 0.4f), 1e-3);  // v = 1/4
    EXPECT_NEAR(std::abs(def.frame.s.x), 1, 1e-5);                       // along the fibre
    EXPECT_FLOAT_EQ(def.hair_model.eta, 1.55f);
    // The Bsdf's value, density and samples are its model's, wo's angles and refracted path made
    // once per outgoing direction (Bsdf::outgoing) and shared by them.
    Uniform u{9};
    for (int i = 0; i < 50; ++i) {
        const Vec3 wo = uniform_sphere(u(), u()), wi = uniform_sphere(u(), u());
        const HairOutgoing ho = hair_outgoing(def.hair_model, def.frame.to_local(wo));
        const Rgb f = def.f(wo, wi), g = hair_f(def.hair_model, ho, def.frame.to_local(wi));
        EXPECT_EQ(f.r, g.r) << i;
        EXPECT_EQ(f.b, g.b) << i;
        const Bsdf::Outgoing o = def.outgoing(wo);
        EXPECT_EQ(def.pdf(o, wi), hair_pdf(def.hair_model, ho, def.frame.to_local(wi))) << i;
        const Bsdf::Sample s = def.sample(o, u(), u(), u());
        if (s.pdf > 0) {  // (s.wi made world and back: equal up to rounding)
            EXPECT_NEAR(s.pdf, def.pdf(o, s.wi), 1e-3f * s.pdf) << i;
        }
    }
    const Bsdf mel =
        bsdf_at("Material \"hair\" \"float eumelanin\" 0.5 \"float pheomelanin\" 2", nullptr);
    EXPECT_NEAR(mel.hair_model.sigma_a.g, 0.5f * 0.697f + 2 * 0.4f, 1e-5);
    const Bsdf col =
        bsdf_at("Material \"hair\" \"rgb color\" [0.3 0.2 0.1] \"float beta_n\" 0.5", nullptr);
    const float k = 5.969f - 0.215f * 0.5f + 2.532f * 0.25f - 10.73f * 0.125f + 5.574f * 0.0625f +
                    0.245f * 0.03125f;
    EXPECT_NEAR(col.hair_model.sigma_a.r, std::pow(std::log(0.3f) / k, 2.0f), 1e-5);
    std::vector<std::string> w;
    const Bsdf sig =
        bsdf_at("Material \"hair\" \"rgb sigma_a\" [0.1 0.2 0.3] \"rgb color\" [0.3 0.2 0.1]", &w);
    EXPECT_FLOAT_EQ(sig.hair_model.sigma_a.b, 0.3f);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_NE(w[0].find("\"color\" is ignored since \"sigma_a\" is given"), std::string::npos)
        << w[0];
}

// Parameters pbrt-v3 does not guard (an index below 1, where nothing refracts at grazing angles;
// the smallest roughnesses the material passes, 0.001) give finite values and densities.
TEST(Hair, ExtremeParametersStayFinite) {
    Uniform u{3};
    for (const auto& [eta, beta] : {std::pair{0.5f, 0.3f}, std::pair{1.55f, 1e-3f},
                                    std::pair{0.9f, 1e-3f}, std::pair{1.0f, 1.0f}}) {
        HairParams p;
        p.eta = eta;
        p.beta_m = p.beta_n = beta;
        for (int i = 0; i < 2000; ++i) {
            p.h = -1 + 2 * u();
            p.sigma_a = i % 2 ? Rgb(0) : Rgb(0.3f, 1, 3);
            const Vec3 wo = uniform_sphere(u(), u()), wi = uniform_sphere(u(), u());
            const Rgb f = hair_f(p, wo, wi);
            ASSERT_TRUE(std::isfinite(f.r) && std::isfinite(f.g) && std::isfinite(f.b))
                << eta << " " << beta << " " << i;
            ASSERT_TRUE(std::isfinite(hair_pdf(p, wo, wi))) << eta << " " << beta;
            if (const std::optional<Vec3> s = hair_sample(p, wo, u(), u(), u())) {
                ASSERT_TRUE(std::isfinite(hair_f(p, wo, *s).g)) << eta << " " << beta;
            }
        }
    }
}
