// Path tracing (pbrt-v3's "path" integrator): BSDF sampling against its own density and against
// uniform sampling, a closed emitting sphere seen from inside against the sum of its bounces, a
// glass sphere (smooth, rough, translucent) inside an emitting one, multiple importance sampling's
// mean and noise, the stratified numbers, and the integrators a scene may name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <forward_list>
#include <numeric>
#include <string>
#include <vector>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/shading.h"
#include "render/tracer.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

// Lambertian; glossy alone; diffuse under an anisotropic glossy lobe; rough glass (microfacet
// reflection and transmission); substrate (FresnelBlend), isotropic and anisotropic; translucent
// (Lambertian and microfacet, each reflected and transmitted); a mix whose lobes do not fit one
// Bsdf (a metal's glossy lobe, and a layer of an Oren-Nayar lobe under a rougher dielectric one).
std::vector<Bsdf> test_bsdfs() {
    static std::forward_list<Bsdf> layers;  // the mix's
    Bsdf base;
    base.frame = Frame::from_z(Vec3(0, 0, 1));
    base.ng = Vec3(0, 0, 1);
    Bsdf lambert = base, glossy = base, both = base, glass = base, substrate = base,
         substrate_aniso = base, translucent = base;
    lambert.kd = Rgb(0.8f);
    glossy.ks = Rgb(1);
    glossy.alpha = 0.2f;
    glossy.lobe_eta_i = 1;
    both.kd = Rgb(0.5f);
    both.ks = Rgb(0.5f);
    both.alpha = 0.05f;
    both.alpha_y = 0.4f;
    both.anisotropic = true;
    glass.ks = Rgb(1);
    glass.kt_rough = Rgb(1);
    glass.alpha = 0.3f;
    glass.lobe_eta_i = 1;
    glass.lobe_eta_t = 1.5f;
    substrate.fresnel_blend = true;
    substrate.kd = Rgb(0.7f);
    substrate.ks = Rgb(0.05f);
    substrate.alpha = 0.25f;
    substrate_aniso = substrate;
    substrate_aniso.alpha_y = 0.05f;
    substrate_aniso.anisotropic = true;
    translucent.kd = Rgb(0.3f);
    translucent.kt_diffuse = Rgb(0.4f);
    translucent.ks = Rgb(0.1f);
    translucent.kt_rough = Rgb(0.2f);
    translucent.alpha = 0.2f;
    translucent.lobe_eta_i = 1;
    translucent.lobe_eta_t = 1.5f;
    Bsdf metal = base, under = base;
    metal.ks = Rgb(1);
    metal.alpha = 0.1f;
    metal.conductor = true;
    metal.conductor_eta = Rgb(0.2f, 0.9f, 1.1f);
    metal.conductor_k = Rgb(3.9f, 2.4f, 2.1f);
    under.kd = Rgb(0.6f);
    under.on_a = 0.8f;
    under.on_b = 0.3f;
    under.ks = Rgb(0.3f);
    under.alpha = 0.5f;
    metal.scale(Rgb(0.4f));
    under.scale(Rgb(0.6f));
    Bsdf mix = metal;
    mix.add(under, layers);
    EXPECT_NE(mix.layer, nullptr);
    // pbrt-v3's Disney BSDF: a rough dielectric with sheen and a clearcoat; an anisotropic metal;
    // a thin surface with fake subsurface and diffuse transmission.
    Bsdf disney = base, disney_metal = base, disney_thin = base;
    auto model = [](auto set) {
        auto d = std::make_shared<DisneyModel>();
        set(*d);
        return d;
    };
    disney.disney = model([](DisneyModel& d) {
        d.diffuse_group = d.has_sheen = d.has_clearcoat = true;
        d.diffuse = d.retro = Rgb(0.6f, 0.4f, 0.3f);
        d.sheen = Rgb(0.3f);
        d.roughness = 0.4f;
        d.ax = d.ay = 0.16f;
        d.cspec0 = Rgb(0.04f);
        d.clearcoat = 0.7f;
        d.gloss = 0.03f;
    });
    disney_metal.disney = model([](DisneyModel& d) {
        d.ax = 0.05f;
        d.ay = 0.3f;
        d.cspec0 = Rgb(0.9f, 0.6f, 0.3f);
        d.metallic = 1;
    });
    disney_metal.anisotropic = true;
    disney_thin.disney = model([](DisneyModel& d) {
        d.diffuse_group = d.thin = true;
        d.diffuse = Rgb(0.2f);
        d.fake_ss = d.retro = Rgb(0.3f);
        d.lambert_t = Rgb(0.25f);
        d.roughness = 0.7f;
        d.ax = d.ay = 0.49f;
        d.cspec0 = Rgb(0.04f);
    });
    Bsdf disney_glass = base;  // spectrans 1: specular reflection and rough transmission
    disney_glass.disney = model([](DisneyModel& d) {
        d.ax = d.ay = 0.09f;
        d.tax = d.tay = 0.09f;
        d.cspec0 = Rgb(0.04f);
        d.eta = 1.5f;
        d.has_transmission = true;
        d.transmit = Rgb(0.9f);
    });
    return {lambert,     glossy, both,   glass,        substrate,   substrate_aniso,
            translucent, mix,    disney, disney_metal, disney_thin, disney_glass};
}

}  // namespace

// sample() draws directions with the density pdf() reports: the density integrates over the
// sphere to the share of draws that give a direction (those a microfacet reflects below the
// surface, or refracts back to wo's side or not at all, give none; all of the Lambertian's), and
// the estimate of the scattered fraction, f |cos| / pdf, agrees with uniform sampling's. The
// rough glass is seen from outside and from inside (theta_o beyond 90 degrees).
//
// Both integrals leave out what no microfacet facing wo's side can refract: pbrt-v3's microfacet
// transmission gives those pairs a value and a density too (it takes D at the half vector
// whichever way it faces), and its sampler, drawing normals on wo's side, never reaches them;
// from inside the glass at 114 degrees they are 3% of what is transmitted, and they hold up to
// 3% of the density.
TEST(PathTracing, BsdfSamplesHaveTheDensityTheyReport) {
    const std::vector<Bsdf> bsdfs = test_bsdfs();
    for (std::size_t b = 0; b < bsdfs.size(); ++b) {
        SCOPED_TRACE(b);
        const Bsdf& bsdf = bsdfs[b];
        for (float theta_o : {0.1f, 0.8f, 1.3f, 2.0f, 2.9f}) {
            SCOPED_TRACE(theta_o);
            const Vec3 wo(std::sin(theta_o), 0, std::cos(theta_o));
            const Bsdf::Outgoing o = bsdf.outgoing(wo);
            const int lobes = int(bsdf.has_diffuse()) + int(bsdf.has_glossy()) +
                              int(bsdf.has_transmission()) + int(bsdf.has_diffuse_transmission());
            // The density over the sphere, by a midpoint rule in (cos theta, phi).
            const int n = 800;
            double integral = 0, uniform = 0, everywhere = 0;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const float z = -1 + 2 * (i + 0.5f) / n, phi = 2 * kPi * (j + 0.5f) / n;
                    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
                    const Vec3 wi(r * std::cos(phi), r * std::sin(phi), z);
                    const double w = 4 * kPi / (double(n) * n);
                    everywhere += bsdf.pdf(o, wi) * w;
                    if (z * wo.z < 0) {
                        // The microfacet's normal, h = wo + eta wi turned to face wo, on wo's
                        // side of the surface (eta: the index on wi's side over wo's).
                        const float eta = wo.z > 0 ? 1.5f : 1 / 1.5f;  // (both have 1.5)
                        const Vec3 h = wo + wi * eta;
                        const Vec3 m = dot(wo, h) > 0 ? h : -h;
                        const bool refracts = bsdf.has_transmission() ||
                                              (bsdf.disney && bsdf.disney->has_transmission);
                        if (m.z * wo.z <= 0 && refracts) {
                            // Only a Lambertian transmission reaches such a pair.
                            if (bsdf.has_diffuse_transmission()) {
                                integral += std::abs(z) * kInvPi / lobes * w;
                                uniform += bsdf.kt_diffuse.g * kInvPi * std::abs(z) * w;
                            }
                            continue;
                        }
                    }
                    integral += bsdf.pdf(o, wi) * w;
                    uniform += bsdf.f(o, wi).g * std::abs(z) * w;
                }
            EXPECT_LT(integral, 1.01);
            EXPECT_LT(everywhere, integral + 0.035);
            if (b == 0) {
                EXPECT_NEAR(integral, 1, 0.005);
            }
            // Importance sampling's estimate of the same integral.
            Rng rng(7 + b);
            double sampled = 0;
            int drawn = 0;
            const int m = 200000;
            for (int k = 0; k < m; ++k) {
                const float u0 = rng.next_float(), u1 = rng.next_float(), u2 = rng.next_float();
                const Bsdf::Sample s = bsdf.sample(o, u0, u1, u2);
                if (s.pdf == 0) continue;
                ++drawn;
                EXPECT_NEAR(s.pdf, bsdf.pdf(o, s.wi), 1e-4f * s.pdf);
                EXPECT_NEAR(length(s.wi), 1, 1e-5);
                sampled += s.f.g * std::abs(s.wi.z) / s.pdf;
            }
            EXPECT_NEAR(double(drawn) / m, integral, 0.01);
            EXPECT_NEAR(sampled / m, uniform, 0.01 + 0.01 * uniform);
        }
    }
}

namespace {

// The camera inside a sphere of radius 1 that emits 1 from both sides and reflects with albedo
// 0.5: every ray sees 1 + 0.5 + 0.25 + ..., one term per bounce lit.
std::string furnace(int maxdepth, const std::string& integrator = "path") {
    return "LookAt 0 0 0  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 60 "
           "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
           "Sampler \"stratified\" \"integer xsamples\" 8 \"integer ysamples\" 8 "
           "Integrator \"" +
           integrator + "\" \"integer maxdepth\" " + std::to_string(maxdepth) +
           " WorldBegin AttributeBegin "
           "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" \"true\" "
           "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5] Shape \"sphere\" \"float radius\" 1 "
           "AttributeEnd WorldEnd";
}

double bounces(int lit) {  // 1 + 0.5 + ... + 0.5^lit
    double s = 0;
    for (int k = 0; k <= lit; ++k) s += std::pow(0.5, k);
    return s;
}

}  // namespace

TEST(PathTracing, ClosedEmittingSphereSeesEveryBounce) {
    // maxdepth 5: five shaded hits, each lit by the sphere, and the emission seen directly:
    // 1 + 0.5 + ... + 0.5^5 (no Russian roulette yet). Inside a sphere both of a hit's light
    // estimates are constant (its light sample's cos cos / d^2 is 1 / 4R^2, its BSDF sample's
    // f cos / pdf is the albedo); only their power-heuristic weights vary, so a pixel's mean of
    // 64 samples is within a few 1e-3 of the sum, and the image's mean within 2e-4.
    {
        auto s = test::scene_from(furnace(5));
        const Framebuffer fb = render::render(*s, {}, nullptr);
        for (float v : fb.rgb) EXPECT_NEAR(v, bounces(5), 5e-3);
        const double mean = std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
        EXPECT_NEAR(mean, bounces(5), 2e-4 * bounces(5));
    }
    // maxdepth 8: Russian roulette from the fourth bounce on; its weights keep the mean.
    {
        auto s = test::scene_from(furnace(8));
        const Framebuffer fb = render::render(*s, {}, nullptr);
        const double mean = std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
        EXPECT_NEAR(mean, bounces(8), 0.005 * bounces(8));
        EXPECT_GT(*std::max_element(fb.rgb.begin(), fb.rgb.end()), bounces(5) + 1e-3);
    }
    // Whitted: the emission and the direct light only.
    auto w = test::scene_from(furnace(5, "whitted"));
    const Framebuffer fw = render::render(*w, {}, nullptr);
    for (float v : fw.rgb) EXPECT_NEAR(v, bounces(1), 1e-4);
}

namespace {
// A sphere of radius 1 of `material` inside a sphere of radius 10 that emits 1 on both sides and
// reflects nothing, seen from 3 units away (16 x 16 pixels, 64 spp, path tracing to depth 30).
std::unique_ptr<Scene> inside_emitter(const std::string& material) {
    return test::scene_from(
        "LookAt 0 0 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 30 "
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
        "Sampler \"stratified\" \"integer xsamples\" 8 \"integer ysamples\" 8 "
        "Integrator \"path\" \"integer maxdepth\" 30 WorldBegin "
        "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" \"true\" "
        "Material \"matte\" \"rgb Kd\" [0 0 0] Shape \"sphere\" \"float radius\" 10 AttributeEnd " +
        material + " Shape \"sphere\" \"float radius\" 1 WorldEnd");
}
}  // namespace

// A glass sphere inside a sphere that emits 1 everywhere (and reflects nothing) is invisible:
// glass loses no light (its Fresnel reflection and transmission add up to 1, and the radiance's
// (eta_i / eta_t)^2 on the way in is undone on the way out), so every path that reaches the
// emitter carries 1, reflected or transmitted by the lobe chosen at each hit and weighted by the
// inverse of its probability. One ray per hit: 30 hits deep, both lobes' children would be 2^30.
TEST(PathTracing, GlassInsideAnEmittingSphereIsInvisible) {
    auto s = inside_emitter("Material \"glass\" \"float index\" 1.5");
    RenderStats stats;
    const Framebuffer fb = render::render(*s, {}, &stats);
    const double mean = std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
    EXPECT_NEAR(mean, 1, 0.01);
    for (float v : fb.rgb) EXPECT_GT(v, 0.8f);
    EXPECT_LT(stats.total_rays(), 40u * 16 * 16 * 64);  // a path, not a tree, per sample
}

// Rough glass (pbrt-v3's microfacet reflection and transmission) inside the same emitter: light
// now reaches the eye through light samples and BSDF samples weighted by multiple importance
// sampling at every hit, the transmitted radiance scaled by (eta_i / eta_t)^2 each way. With a
// small roughness the sphere is nearly invisible as smooth glass is; what it takes away is the
// microfacet model's own loss (light its shadowing term stops, and pairs of directions no
// microfacet facing wo can refract), which grows with roughness: pbrt-v3 renders this image's
// mean as 0.987 at roughness 0.02 and 0.773 at 0.3 (256 samples per pixel; 0.998 at 0.02 with
// 2304).
TEST(PathTracing, RoughGlassInsideAnEmittingSphereIsNearlyInvisible) {
    auto mean_of = [](const char* roughness) {
        auto s = inside_emitter(
            std::string("Material \"glass\" \"float index\" 1.5 \"bool remaproughness\" \"false\" "
                        "\"float uroughness\" ") +
            roughness + " \"float vroughness\" " + roughness);
        const Framebuffer fb = render::render(*s, {}, nullptr);
        return std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
    };
    const double smooth = mean_of("0.02"), rough = mean_of("0.3");
    EXPECT_NEAR(smooth, 1, 0.02);
    EXPECT_NEAR(rough, 0.773, 0.02);
}

// pbrt-v3's translucent material with a white Kd, no Ks, and half reflected, half transmitted
// loses no light: a sphere of it inside a sphere emitting 1 everywhere is invisible (mean 1),
// every path leaving it, after any number of diffuse reflections and transmissions, carrying 1.
TEST(PathTracing, LosslessTranslucentSphereInsideAnEmitterIsInvisible) {
    auto s = inside_emitter(
        "Material \"translucent\" \"rgb Kd\" [1 1 1] \"rgb Ks\" [0 0 0] "
        "\"rgb reflect\" [0.5 0.5 0.5] \"rgb transmit\" [0.5 0.5 0.5]");
    const Framebuffer fb = render::render(*s, {}, nullptr);
    const double mean = std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
    EXPECT_NEAR(mean, 1, 0.01);
}

// Multiple importance sampling: on a glossy plane under a large area light, path tracing's
// direct light (maxdepth 1: light and BSDF samples, power heuristic) and whitted's (light samples
// alone) have the same mean (roughness 0.2, where the light samples converge: pbrt-v3's path
// and whitted integrators give the same mean within 0.1%); on a nearly mirror-like one
// (roughness 0.02) the light's samples rarely fall in the narrow lobe while the BSDF's find the
// light, and at 16 spp the first's error is a fraction of the second's.
TEST(PathTracing, MultipleImportanceSamplingKeepsTheMeanAndCutsTheNoise) {
    auto render_at = [](const std::string& integrator, int spp, const char* roughness) {
        auto s = test::scene_from(
            "LookAt 0 3 -3  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 50 "
            "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16 "
            "Integrator \"" +
                integrator +
                "\" \"integer maxdepth\" 1 WorldBegin "
                "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" [5 5 5] "
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-2 2 0  2 2 0  2 2 4  -2 2 4] AttributeEnd "
                "Material \"plastic\" \"rgb Kd\" [0 0 0] \"rgb Ks\" [1 1 1] \"float roughness\" " +
                roughness +
                " \"bool remaproughness\" \"false\" "
                "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                "\"point3 P\" [-10 0 -10  10 0 -10  10 0 10  -10 0 10] WorldEnd",
            "t.pbrt", spp);
        return render::render(*s, {}, nullptr).rgb;
    };
    auto mean = [](const std::vector<float>& v) {
        return std::accumulate(v.begin(), v.end(), 0.0) / v.size();
    };
    auto rmse = [](const std::vector<float>& a, const std::vector<float>& b) {
        double se = 0;
        for (std::size_t i = 0; i < a.size(); ++i) se += (a[i] - b[i]) * (a[i] - b[i]);
        return std::sqrt(se / a.size());
    };
    const double m = mean(render_at("path", 1024, "0.2"));
    EXPECT_GT(m, 0.05);  // the light's reflection fills part of the image
    EXPECT_NEAR(mean(render_at("whitted", 1024, "0.2")), m, 0.015 * m);
    const std::vector<float> reference = render_at("path", 1024, "0.02");
    const double e_mis = rmse(render_at("path", 16, "0.02"), reference),
                 e_light = rmse(render_at("whitted", 16, "0.02"), reference);
    EXPECT_LT(e_mis, 0.5 * e_light) << e_mis << " " << e_light;
}

// A path's first numbers are stratified over its pixel's samples: in each dimension the samples
// of a pixel fall in distinct strata, in an order that changes from dimension to dimension, and
// in each pair of dimensions in distinct cells.
TEST(PathTracing, FirstNumbersTakeEachStratumOncePerPixel) {
    const uint32_t n = 16;
    std::vector<uint32_t> first_order;
    int orders_differ = 0;
    for (int dim = 0; dim < 8; ++dim) {
        std::vector<int> taken(n, 0);
        std::vector<uint32_t> order;
        for (uint32_t s = 0; s < n; ++s) {
            const float u = stratified(0x1234, s, n, dim, 0.37f);
            ASSERT_GE(u, 0.0f);
            ASSERT_LT(u, 1.0f);
            const auto k = static_cast<uint32_t>(u * n);
            EXPECT_NEAR(u * n - k, 0.37f, 1e-4);  // at the jitter within its stratum
            ++taken[k];
            order.push_back(k);
        }
        for (uint32_t k = 0; k < n; ++k) EXPECT_EQ(taken[k], 1) << dim << " " << k;
        if (dim == 0)
            first_order = order;
        else
            orders_differ += order != first_order;
    }
    EXPECT_GE(orders_differ, 6);  // not one order for every dimension
    // Pairs (a light's point, a BSDF's direction): the samples take the 4 x 4 cells once each.
    for (uint64_t key : {1u, 2u, 3u}) {
        std::vector<int> taken(n, 0);
        for (uint32_t s = 0; s < n; ++s) {
            float u, v;
            stratified2(key, s, 4, 4, 0.5f, 0.25f, u, v);
            const auto cx = static_cast<uint32_t>(u * 4), cy = static_cast<uint32_t>(v * 4);
            EXPECT_NEAR(u * 4 - cx, 0.5f, 1e-4);
            EXPECT_NEAR(v * 4 - cy, 0.25f, 1e-4);
            ++taken[cy * 4 + cx];
        }
        for (uint32_t k = 0; k < n; ++k) EXPECT_EQ(taken[k], 1) << key << " " << k;
    }
}

TEST(PathTracing, SceneIntegratorsChooseIt) {
    auto integrator = [](const std::string& directive, std::vector<std::string>* warnings) {
        auto s = build_scene(pbrt::parse_string(directive + " WorldBegin WorldEnd", "i.pbrt"), {},
                             [&](const std::string& w) { warnings->push_back(w); });
        return std::make_pair(s->path_tracing, s->rr_threshold);
    };
    std::vector<std::string> warnings;
    EXPECT_EQ(integrator("Integrator \"path\"", &warnings), std::make_pair(true, 1.0f));
    EXPECT_EQ(integrator("Integrator \"path\" \"float rrthreshold\" 0.5", &warnings),
              std::make_pair(true, 0.5f));
    EXPECT_TRUE(integrator("", &warnings).first);  // pbrt-v3's default
    EXPECT_FALSE(integrator("Integrator \"whitted\"", &warnings).first);
    EXPECT_FALSE(integrator("Integrator \"directlighting\"", &warnings).first);
    const auto none = std::count_if(warnings.begin(), warnings.end(), [](const std::string& w) {
        return w.find("Integrator") != std::string::npos;
    });
    EXPECT_EQ(none, 0);
    // volpath is path tracing with media; bdpt and mlt are rendered as volpath, which computes
    // their light transport, with a warning (sppm has its own: sppm_test.cpp).
    for (const auto& pair : {std::pair{"volpath", ""}, {"bdpt", "volpath"}, {"mlt", "volpath"}}) {
        // (Plain copies, not a structured binding: Clang before 16 cannot capture those.)
        const char *other = pair.first, *as = pair.second;
        warnings.clear();
        EXPECT_TRUE(integrator(std::string("Integrator \"") + other + "\"", &warnings).first);
        EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                                [&](const std::string& w) {
                                    return w.find(std::string("is rendered as \"") + as + "\"") !=
                                           std::string::npos;
                                }),
                  *as ? 1 : 0)
            << other;
        EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                                [&](const std::string& w) {
                                    return w.find("Integrator") != std::string::npos;
                                }),
                  *as ? 1 : 0)
            << other;
    }
}

// pbrt-v3's "ambientocclusion": the cosine-weighted share of the hemisphere above the first hit
// that nothing occludes, times pi. A point on an endless floor a distance x from the foot of an
// endless wall of height H sees the wall over a share (1 - x / sqrt(x^2 + H^2)) / 2 of the
// cosine-weighted hemisphere (Nusselt's projection of the wall onto the base disc), so its value
// is pi/2 (1 + x / sqrt(x^2 + H^2)); uniform directions have the same mean. Lights, materials
// (but "none") and what lies beyond the first hit do not count; misses are black.
TEST(AmbientOcclusion, IsTheUnoccludedCosineWeightedShare) {
    auto render_ao = [](const std::string& integrator, const std::string& world) {
        auto s = test::scene_from(
            "LookAt 0 5 0  0 0 0  0 0 1 Camera \"orthographic\" \"float screenwindow\" [-0.001 "
            "0.001 -0.001 0.001] Film \"image\" \"integer xresolution\" 1 \"integer yresolution\" "
            "1 Sampler \"stratified\" \"integer xsamples\" 4 \"integer ysamples\" 4 " +
            integrator + " WorldBegin " + world + " WorldEnd");
        const Framebuffer fb = render::render(*s, {}, nullptr);
        EXPECT_EQ(fb.rgb[0], fb.rgb[1]);
        return fb.rgb[0];
    };
    const std::string floor =
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1000 0 -1000 "
        "1000 0 -1000 1000 0 1000 -1000 0 1000] ";
    const std::string wall =  // at z = 1, 1 high
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1000 0 1 1000 0 "
        "1 1000 1 1 -1000 1 1] ";
    const std::string cosine = "Integrator \"ambientocclusion\" \"integer nsamples\" 4096",
                      uniform = cosine + " \"bool cossample\" \"false\"";
    // Open: every cosine-weighted direction adds exactly pi / n.
    EXPECT_NEAR(render_ao(cosine, floor), kPi, 1e-5);
    EXPECT_NEAR(render_ao(uniform, floor), kPi, 0.01 * kPi);
    // Beside the wall: pi/2 (1 + 1/sqrt(2)) = 2.6815.
    const double want = kPi / 2 * (1 + 1 / std::sqrt(2.0));
    EXPECT_NEAR(render_ao(cosine, floor + wall), want, 0.005 * want);
    EXPECT_NEAR(render_ao(uniform, floor + wall), want, 0.01 * want);
    // A mirror floor and a light change nothing; an invisible ("none") wall still occludes, as
    // pbrt-v3's shadow rays meet it; a miss is black.
    EXPECT_NEAR(render_ao(cosine, "LightSource \"point\" \"rgb I\" [5 5 5] Material \"mirror\" " +
                                      floor + "Material \"none\" " + wall),
                want, 0.005 * want);
    EXPECT_EQ(render_ao(cosine,
                        "LightSource \"infinite\" \"rgb L\" [1 1 1] Shape \"sphere\" "
                        "\"float radius\" 0.1 \"float zmin\" 0.09"),
              0);
}

TEST(AmbientOcclusion, IntegratorParameters) {
    std::vector<std::string> warnings;
    auto build = [&](const std::string& integrator) {
        warnings.clear();
        return build_scene(pbrt::parse_string("Camera \"perspective\" " + integrator +
                                                  " WorldBegin Shape \"sphere\" WorldEnd",
                                              "i.pbrt"),
                           {}, [&](const std::string& w) { warnings.push_back(w); });
    };
    auto s = build("Integrator \"ambientocclusion\"");
    EXPECT_TRUE(s->ambient_occlusion);
    EXPECT_FALSE(s->path_tracing);
    EXPECT_EQ(s->ao_samples, 64);  // pbrt-v3's defaults
    EXPECT_TRUE(s->ao_cosine);
    EXPECT_TRUE(warnings.empty()) << warnings[0];  // (not "no lights": it needs none)
    s = build(
        "Integrator \"ambientocclusion\" \"integer nsamples\" 5 \"bool cossample\" "
        "\"false\" \"integer maxdepth\" 3");
    EXPECT_EQ(s->ao_samples, 5);
    EXPECT_FALSE(s->ao_cosine);
    ASSERT_EQ(warnings.size(), 1u);  // pbrt-v3's integrator has no maxdepth
    EXPECT_NE(warnings[0].find("\"maxdepth\""), std::string::npos) << warnings[0];
    EXPECT_THROW(build("Integrator \"ambientocclusion\" \"integer nsamples\" -1"),
                 pbrt::SceneError);
}

// pbrt-v3's Disney BSDF at normal incidence (wo = wi = n), from its lobes' definitions: the
// Schlick weights vanish, so the diffuse lobe is c / pi, retro-reflection and sheen 0; the
// specular lobe's half vector is n, where D = 1 / (pi ax ay), G1 = 1 and the Fresnel term is
// (1 - metallic) ((eta - 1) / (eta + 1))^2 + metallic cspec0, over 4; the clearcoat's GTR1 is
// (a^2 - 1) / (pi ln(a^2) a^2), its Fresnel term 0.04 and its masking (1 / 2)^2, over 4. A
// thin surface transmits lambert_t / pi and reflects nothing the other way.
TEST(Disney, LobesAtNormalIncidence) {
    DisneyModel d;
    d.diffuse_group = d.has_sheen = d.has_clearcoat = true;
    d.diffuse = d.retro = Rgb(0.6f, 0.4f, 0.3f);
    d.sheen = Rgb(0.5f);
    d.ax = 0.2f;
    d.ay = 0.1f;
    d.metallic = 0.25f;
    d.eta = 1.6f;
    d.cspec0 = Rgb(0.5f, 0.3f, 0.2f);
    d.clearcoat = 0.8f;
    d.gloss = 0.05f;
    const Vec3 n(0, 0, 1);
    const Rgb f = disney_f(d, n, n, true);
    const double r0 = std::pow((1.6 - 1) / (1.6 + 1), 2), dspec = 1 / (kPi * 0.2 * 0.1);
    const double a2 = 0.05 * 0.05, dr = (a2 - 1) / (kPi * std::log(a2) * a2);
    const double coat = 0.8 * 0.25 * 0.04 * dr / 4;
    const double want_r = 0.6 / kPi + (0.75 * r0 + 0.25 * 0.5) * dspec / 4 + coat;
    const double want_b = 0.3 / kPi + (0.75 * r0 + 0.25 * 0.2) * dspec / 4 + coat;
    EXPECT_NEAR(f.r, want_r, 1e-4 * want_r);
    EXPECT_NEAR(f.b, want_b, 1e-4 * want_b);
    // The density: the mean of the components' (diffuse, retro, sheen: cos / pi each; specular:
    // D G1 / 4; clearcoat: GTR1 / 4) at this direction.
    const double want_pdf = (3 / kPi + dspec / 4 + dr / 4) / 5;
    EXPECT_NEAR(disney_pdf(d, n, n), want_pdf, 1e-4 * want_pdf);
    DisneyModel thin;
    thin.diffuse_group = thin.thin = true;
    thin.lambert_t = Rgb(0.4f);
    EXPECT_NEAR(disney_f(thin, n, -n, false).g, 0.4 / kPi, 1e-6);
    EXPECT_EQ(thin.components(), 5);  // diffuse, fake subsurface, retro, specular, transmission
}

// The material in a scene: pbrt-v3's parameters give the lobes' weights (metallic takes the
// diffuse group away; the specular colour is a blend of the dielectric's and the base colour).
TEST(Disney, MaterialParametersMakeItsLobes) {
    auto bsdf_at = [](const std::string& material) {
        auto s = test::scene_from(
            "LookAt 0 0 5  0 0 0  0 1 0 Camera \"perspective\" Film \"image\" \"integer "
            "xresolution\" 4 \"integer yresolution\" 4 WorldBegin " +
            material +
            " Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1 -1 0 1 -1 "
            "0 1 1 0 -1 1 0] WorldEnd");
        const std::optional<SurfaceHit> h = s->intersect(Vec3(0, 0, 5), Vec3(0, 0, -1), 0, 10);
        EXPECT_TRUE(h.has_value());
        TexContext ctx{};
        ctx.u = h->u;
        ctx.v = h->v;
        ctx.p = h->p;
        const std::optional<Bsdf> b = make_bsdf(*s, s->materials.at(0), *h, ctx);
        EXPECT_TRUE(b && b->disney);
        return *b->disney;
    };
    const DisneyModel plain = bsdf_at("Material \"disney\" \"rgb color\" [0.8 0.4 0.2]");
    EXPECT_TRUE(plain.diffuse_group);
    EXPECT_FALSE(plain.has_sheen || plain.has_clearcoat || plain.thin);
    EXPECT_FLOAT_EQ(plain.diffuse.r, 0.8f);
    EXPECT_FLOAT_EQ(plain.base.g, 0.4f);
    EXPECT_FLOAT_EQ(plain.ax, 0.25f);          // roughness 0.5 squared
    EXPECT_NEAR(plain.cspec0.g, 0.04f, 1e-6);  // ((1.5 - 1) / (1.5 + 1))^2, untinted
    const DisneyModel metal = bsdf_at(
        "Material \"disney\" \"rgb color\" [0.8 0.4 0.2] \"float metallic\" 1 \"float "
        "roughness\" 0.2 \"float anisotropic\" 0.5 \"float clearcoat\" 1");
    EXPECT_FALSE(metal.diffuse_group);
    EXPECT_FLOAT_EQ(metal.cspec0.b, 0.2f);
    EXPECT_NEAR(metal.ax, 0.04f / std::sqrt(0.55f), 1e-6);
    EXPECT_NEAR(metal.ay, 0.04f * std::sqrt(0.55f), 1e-6);
    EXPECT_TRUE(metal.has_clearcoat);
    EXPECT_NEAR(metal.gloss, 0.001f, 1e-7);  // clearcoatgloss 1
    const DisneyModel thin = bsdf_at(
        "Material \"disney\" \"rgb color\" [0.5 0.5 0.5] \"bool thin\" \"true\" \"float "
        "flatness\" 0.25 \"float difftrans\" 0.5 \"float sheen\" 1");
    EXPECT_NEAR(thin.diffuse.r, 0.5f * 0.75f * 0.75f, 1e-6);  // (1 - flat) (1 - difftrans / 2)
    EXPECT_NEAR(thin.fake_ss.r, 0.5f * 0.25f * 0.75f, 1e-6);
    EXPECT_NEAR(thin.lambert_t.r, 0.5f * 0.25f, 1e-6);  // difftrans / 2 of the colour
    EXPECT_NEAR(thin.sheen.r, 1.0f, 1e-6);              // sheentint 0.5 of a grey: white
}

// The specular lobe away from the normal, against the microfacet model written out: a metal's
// (metallic 1: Schlick's Fresnel term of cspec0), D of the anisotropic Trowbridge-Reitz
// distribution in angles, and G1 = 1 / (1 + Lambda) for each direction separately (pbrt-v3's
// Disney distribution), with Lambda = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2.
TEST(Disney, SpecularLobeIsTheUncorrelatedMicrofacetModel) {
    DisneyModel d;
    d.ax = 0.15f;
    d.ay = 0.35f;
    d.metallic = 1;
    d.cspec0 = Rgb(0.9f, 0.6f, 0.3f);
    auto dir = [](double theta, double phi) {
        return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                    float(std::cos(theta)));
    };
    const Vec3 wo = dir(0.7, 0.3), wi = dir(0.5, 2.6);
    const Vec3 h = normalize(wo + wi);
    const double ax = 0.15, ay = 0.35;
    auto lambda = [&](const Vec3& w) {
        const double c2 = double(w.z) * w.z, s2 = 1 - c2, phi = std::atan2(w.y, w.x);
        const double a2 =
            ax * ax * std::cos(phi) * std::cos(phi) + ay * ay * std::sin(phi) * std::sin(phi);
        return (std::sqrt(1 + a2 * s2 / c2) - 1) / 2;
    };
    const double ct = h.z, tan2 = (1 - ct * ct) / (ct * ct), phi_h = std::atan2(h.y, h.x);
    const double e = tan2 * (std::pow(std::cos(phi_h) / ax, 2) + std::pow(std::sin(phi_h) / ay, 2));
    const double D = 1 / (kPi * ax * ay * std::pow(ct, 4) * (1 + e) * (1 + e));
    const double G = 1 / (1 + lambda(wo)) / (1 + lambda(wi));
    const double w5 = std::pow(1 - double(dot(wi, h)), 5);
    const double F = 0.6 + w5 * (1 - 0.6);  // the green channel
    const double want = D * G * F / (4 * wo.z * wi.z);
    EXPECT_NEAR(disney_f(d, wo, wi, true).g, want, 1e-4 * want);
}

// The rough transmission straight through (wo = n, wi = -n): the half vector is the axis, D =
// 1 / (pi ax ay), both masking terms 1, the dielectric's Fresnel term ((eta - 1) / (eta + 1))^2,
// and wo . h + eta wi . h = eta - 1: T (1 - F) D / (eta - 1)^2; the density is D times
// eta^2 / (eta - 1)^2 over the components.
TEST(Disney, TransmissionStraightThrough) {
    DisneyModel d;
    d.ax = d.ay = 0.2f;
    d.tax = 0.1f;
    d.tay = 0.3f;
    d.eta = 1.5f;
    d.has_transmission = true;
    d.transmit = Rgb(0.8f);
    const Vec3 n(0, 0, 1);
    const double D = 1 / (kPi * 0.1 * 0.3), F = 0.04, want = 0.8 * (1 - F) * D / 0.25;
    EXPECT_NEAR(disney_f(d, n, -n, false).g, want, 1e-4 * want);
    EXPECT_NEAR(disney_pdf(d, n, -n), D * 2.25 / 0.25 / 2, 1e-4 * D * 2.25 / 0.25 / 2);
}
