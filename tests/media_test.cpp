// Participating media (pbrt-v3's volpath): the Henyey–Greenstein phase function and its
// sampling, distance sampling and transmittance in homogeneous media and density grids, the
// MediumInterface directives, the builder's checks, and whole renders with closed-form answers:
// light through an absorbing sphere, a shadow ray through one, and a non-absorbing medium in a
// uniform light field (which must stay uniform).
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/medium.h"
#include "render/tracer.h"
#include "scene_util.h"

using namespace cmam;
using namespace cmam::render;

namespace {

Vec3 normalized(const Vec3& v) {
    return v / length(v);
}

}  // namespace

TEST(Media, HenyeyGreensteinIsADensityThatItsSamplesFollow) {
    for (float g : {-0.7f, 0.0f, 0.3f, 0.9f}) {
        // Its integral over the sphere (in the cosine, 2 pi p dmu) is 1.
        const int n = 200000;
        double total = 0;
        for (int i = 0; i < n; ++i) total += 2 * kPi * hg_phase(-1 + 2 * (i + 0.5f) / n, g);
        EXPECT_NEAR(total * 2 / n, 1.0, 1e-3) << g;
        // Samples: unit directions, their density the phase function's value there, their
        // cosines with wo distributed as it says (20 bins, each within 5 sigma), and their mean
        // cosine -g (forward scattering leaves along -wo).
        const Vec3 wo = normalized(Vec3(0.3f, -0.5f, 0.8f));
        Rng rng(17);
        constexpr int kBins = 20, kSamples = 200000;
        std::vector<int> count(kBins, 0);
        double mean_cos = 0;
        for (int i = 0; i < kSamples; ++i) {
            const float u1 = rng.next_float(), u2 = rng.next_float();
            Vec3 wi;
            const float pdf = hg_sample(wo, g, u1, u2, wi);
            ASSERT_NEAR(length(wi), 1.0f, 1e-5f);
            const float c = std::clamp(dot(wo, wi), -1.0f, 1.0f);
            ASSERT_NEAR(pdf, hg_phase(c, g), 2e-3f * hg_phase(c, g) + 1e-6f) << g << " " << c;
            mean_cos += c;
            ++count[std::min(kBins - 1, int((c + 1) / 2 * kBins))];
        }
        EXPECT_NEAR(mean_cos / kSamples, -g, 0.01) << g;
        for (int b = 0; b < kBins; ++b) {
            double p = 0;
            const int steps = 2000;
            for (int k = 0; k < steps; ++k) {
                const float mu = -1 + (b + (k + 0.5f) / steps) * 2.0f / kBins;
                p += 2 * kPi * hg_phase(mu, g) * (2.0 / kBins) / steps;
            }
            const double expected = p * kSamples, sigma = std::sqrt(expected * (1 - p)) + 1;
            EXPECT_NEAR(count[b], expected, 5 * sigma) << "g " << g << " bin " << b;
        }
    }
}

namespace {

// The mean weights of n distance samples along a unit ray of length d: what passes (weight where
// no scattering was sampled) and what scatters (weight where it was).
struct SampleMeans {
    Rgb passed, scattered;
};
SampleMeans sample_means(const Medium& m, const Vec3& o, const Vec3& dir, float d, int n) {
    Rng rng(5);
    auto u = [&] { return rng.next_float(); };
    double pass[3] = {0, 0, 0}, scat[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        const MediumSample s = sample_medium(m, o, dir, d, u);
        double* acc = s.scattered ? scat : pass;
        acc[0] += s.weight.r;
        acc[1] += s.weight.g;
        acc[2] += s.weight.b;
        if (s.scattered) {
            EXPECT_LT(s.t, d);
        }
    }
    return {Rgb(float(pass[0] / n), float(pass[1] / n), float(pass[2] / n)),
            Rgb(float(scat[0] / n), float(scat[1] / n), float(scat[2] / n))};
}

// What a medium of constant coefficients gives over a length d: transmittance exp(-sigma_t d),
// and scattered sigma_s / sigma_t (1 - exp(-sigma_t d)), per channel.
void expect_means(const SampleMeans& got, const Rgb& sigma_s, const Rgb& sigma_t, float d,
                  double tol, const char* what) {
    const float st[3] = {sigma_t.r, sigma_t.g, sigma_t.b},
                ss[3] = {sigma_s.r, sigma_s.g, sigma_s.b};
    const float pass[3] = {got.passed.r, got.passed.g, got.passed.b},
                scat[3] = {got.scattered.r, got.scattered.g, got.scattered.b};
    for (int c = 0; c < 3; ++c) {
        const double tr = std::exp(-double(st[c]) * d);
        EXPECT_NEAR(pass[c], tr, tol * std::max(tr, 0.05)) << what << " channel " << c;
        const double sc = ss[c] / st[c] * (1 - tr);
        EXPECT_NEAR(scat[c], sc, tol * std::max(sc, 0.05)) << what << " channel " << c;
    }
}

}  // namespace

TEST(Media, HomogeneousSamplesWeighTransmittanceAndScattering) {
    Medium m;
    m.sigma_a = Rgb(0.2f, 0.5f, 1.0f);
    m.sigma_s = Rgb(0.8f, 0.3f, 0.1f);
    m.sigma_t = m.sigma_a + m.sigma_s;
    const Vec3 o(1, 2, 3), dir = normalized(Vec3(1, 1, -2));
    const float d = 1.3f;
    // This medium absorbs more than it scatters (distances drawn by sigma_s); one that scatters
    // more (drawn by sigma_t, as pbrt-v3) has the same expectations.
    expect_means(sample_means(m, o, dir, d, 400000), m.sigma_s, m.sigma_t, d, 0.01, "absorbing");
    Medium fog = m;
    fog.sigma_a = Rgb(0.1f, 0.2f, 0.05f);
    fog.sigma_s = Rgb(1.0f, 0.5f, 2.0f);
    fog.sigma_t = fog.sigma_a + fog.sigma_s;
    expect_means(sample_means(fog, o, dir, d, 400000), fog.sigma_s, fog.sigma_t, d, 0.01, "fog");
    // The transmittance in closed form.
    Rng rng(1);
    const Rgb tr = medium_transmittance(m, o, dir, d, [&] { return rng.next_float(); });
    EXPECT_FLOAT_EQ(tr.r, std::exp(-1.0f * d));
    EXPECT_FLOAT_EQ(tr.b, std::exp(-1.1f * d));
    // Along an infinite ray nothing passes where the medium attenuates, and a channel that does
    // not is passed whole (never NaN).
    Medium clear = m;
    clear.sigma_a = Rgb(0.5f, 0, 0.5f);
    clear.sigma_s = Rgb(0.5f, 0, 0);
    clear.sigma_t = clear.sigma_a + clear.sigma_s;
    const SampleMeans inf =
        sample_means(clear, o, dir, std::numeric_limits<float>::infinity(), 20000);
    EXPECT_EQ(inf.passed.r, 0.0f);
    EXPECT_TRUE(std::isfinite(inf.passed.g) && std::isfinite(inf.scattered.g));
}

TEST(Media, GridsInterpolateTheirDensityAndTrackIt) {
    Medium m;
    m.type = Medium::Type::Grid;
    m.nx = 4;
    m.density = {0.0f, 1.0f, 2.0f, 3.0f};
    m.inv_max_density = 1 / 3.0f;
    m.sigma_a = Rgb(0.1f);
    m.sigma_s = Rgb(0.3f);
    m.sigma_t = m.sigma_a + m.sigma_s;
    m.grid_sigma_t = m.sigma_t.r;
    // Grid space is the world shifted by (-1, 0, 0) and halved along x: the grid spans x in [1, 3].
    m.grid_from_world = {0.5, 0, 0, -0.5, 0, 1, 0, 0, 0, 0, 1, 0};
    // Samples at the cells' centres, linear between them, towards 0 beyond the last centres,
    // 0 outside.
    EXPECT_FLOAT_EQ(m.density_at(Vec3(0.375f, 0.5f, 0.5f)), 1.0f);
    // (across y and z, one sample each: 0.7 of it at y = 0.2, 0.6 at z = 0.9)
    EXPECT_FLOAT_EQ(m.density_at(Vec3(0.5f, 0.2f, 0.9f)), 1.5f * 0.7f * 0.6f);
    EXPECT_FLOAT_EQ(m.density_at(Vec3(1.0f, 0.5f, 0.5f)), 1.5f);
    EXPECT_FLOAT_EQ(m.density_at(Vec3(0.5f, 0.5f, 1.0f)), 0.75f);
    EXPECT_EQ(m.density_at(Vec3(1.2f, 0.5f, 0.5f)), 0.0f);
    EXPECT_FLOAT_EQ(m.density_at(Vec3(0.5f, -0.3f, 0.5f)), 0.3f);  // (0.2 of the way)
    EXPECT_EQ(m.density_at(Vec3(0.5f, -0.6f, 0.5f)), 0.0f);
    // Along x through the grid's middle (from x = 0 to 4 in the world): the optical depth is
    // sigma_t times the density's integral, 2 (in world units: its 2 grid-x units are 1 each).
    const Vec3 o(0, 0.5f, 0.5f), dir(1, 0, 0);
    double depth = 0;
    for (int k = 0; k < 4000; ++k)
        depth += m.density_at(Vec3((k + 0.5f) / 4000, 0.5f, 0.5f)) * 2.0 / 4000;
    const double tr = std::exp(-m.grid_sigma_t * depth);
    Rng rng(9);
    // Ratio tracking's mean; delta tracking scatters with probability 1 - tr, weighted
    // sigma_s / sigma_t, and what passes has weight 1.
    auto expect_tracking = [&](const char* what) {
        const int n = 200000;
        double mean = 0;
        for (int i = 0; i < n; ++i)
            mean += medium_transmittance(m, o, dir, 4, [&] { return rng.next_float(); }).r;
        EXPECT_NEAR(mean / n, tr, 0.01 * tr) << what;
        const SampleMeans s = sample_means(m, o, dir, 4, n);
        EXPECT_NEAR(s.passed.r, tr, 0.01 * tr) << what;
        EXPECT_NEAR(s.scattered.r, (1 - tr) * 0.3 / 0.4, 0.01) << what;
    };
    expect_tracking("one majorant");
    // The same through the grid of majorants (one cell a sample here): the same expectations.
    m.build_majorants();
    ASSERT_EQ(m.majorant.size(), 4u);
    // (cell 0, x in [0, 1/4], reads samples 0 and 1; with one more each side for rounding: 2)
    EXPECT_EQ(m.majorant[0], 2.0f);
    EXPECT_EQ(m.majorant[3], 3.0f);
    expect_tracking("majorant grid");
    // A grid too dense to track in any time (a hostile file) ends its rays at the step bound:
    // absorbed, not hung.
    Medium dense = m;
    dense.grid_sigma_t = 1e30f;
    EXPECT_EQ(medium_transmittance(dense, o, dir, 4, [&] { return rng.next_float(); }).r, 0.0f);
    EXPECT_TRUE(
        sample_medium(dense, o, dir, 4, [&] { return rng.next_float(); }).weight.is_black());
    // A ray that misses the grid passes whole.
    EXPECT_EQ(medium_transmittance(m, Vec3(0, 2, 0.5f), dir, 4, [&] { return rng.next_float(); }).r,
              1.0f);
}

TEST(Media, InterfacesAreTheShapesAndTheCameraIsInTheOutsideAtWorldEnd) {
    std::vector<std::string> warnings;
    const pbrt::SceneDesc d = pbrt::parse_string(
        "MediumInterface \"\" \"fog\"\n"
        "WorldBegin\n"
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
        "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\"\n"
        "AttributeBegin\n"
        "  MediumInterface \"ink\" \"fog\"\n"
        "  Shape \"sphere\"\n"
        "  MediumInterface \"ink\"\n"
        "  Shape \"sphere\"\n"
        "AttributeEnd\n"
        "Shape \"sphere\"\n"
        "MediumInterface \"smoke\" \"\"\n"
        "Shape \"sphere\"\n"
        "Shape \"sphere\"\n"
        "MediumInterface \"\" \"ink\"\n"
        "WorldEnd\n",
        "m.pbrt", [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_EQ(d.media.size(), 2u);
    EXPECT_EQ(d.media[0].name, "fog");
    EXPECT_EQ(d.media[1].entity.type, "homogeneous");
    ASSERT_EQ(d.shapes.size(), 5u);
    auto sides = [&](int i) {
        return std::pair(d.shapes[i].medium_inside, d.shapes[i].medium_outside);
    };
    EXPECT_EQ(sides(0), std::pair(1, 0));
    EXPECT_EQ(sides(1), std::pair(1, 1));    // one name: both sides
    EXPECT_EQ(sides(2), std::pair(-1, 0));   // AttributeEnd restored the options' interface
    EXPECT_EQ(sides(3), std::pair(-1, -1));  // "smoke" is not defined: vacuum
    EXPECT_EQ(d.camera_medium, 1);
    ASSERT_EQ(warnings.size(), 1u);  // once for the name, however many shapes use it
    EXPECT_EQ(warnings[0],
              "m.pbrt:13:1: warning: medium \"smoke\" is not defined; vacuum is used there");
}

namespace {

std::vector<std::string> build_warnings(const std::string& text) {
    std::vector<std::string> w;
    render::build_scene(pbrt::parse_string(text, "b.pbrt"), {},
                        [&](const std::string& s) { w.push_back(s); });
    return w;
}

const char* kVolpath = "Integrator \"volpath\" WorldBegin\n";

}  // namespace

TEST(Media, PresetsArePbrtV3sMeasuredMedia) {
    // A preset's absorption and reduced scattering (mm^-1) are the defaults of sigma_a and
    // sigma_s, which "scale" multiplies as it does given ones.
    std::vector<std::string> warnings;
    auto medium = [&](const std::string& params) {
        warnings.clear();
        auto scene = render::build_scene(
            pbrt::parse_string("Integrator \"volpath\" Camera \"perspective\" WorldBegin\n"
                               "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" " +
                                   params +
                                   "\nMediumInterface \"m\" \"\"\nShape \"sphere\"\nWorldEnd\n",
                               "p.pbrt"),
            {}, [&](const std::string& w) {
                if (w.find("medi") != std::string::npos) warnings.push_back(w);
            });
        EXPECT_EQ(scene->media.size(), 1u);
        return scene->media.empty() ? render::Medium{} : scene->media[0];
    };
    render::Medium m = medium("\"string preset\" \"Skin1\" \"float scale\" 2");
    EXPECT_FLOAT_EQ(m.sigma_a.r, 0.064f);
    EXPECT_FLOAT_EQ(m.sigma_a.b, 0.96f);
    EXPECT_FLOAT_EQ(m.sigma_s.g, 1.76f);
    EXPECT_TRUE(warnings.empty());
    m = medium("\"string preset\" \"Coke\" \"rgb sigma_a\" [1 1 1]");  // a given one wins
    EXPECT_FLOAT_EQ(m.sigma_a.g, 1);
    EXPECT_FLOAT_EQ(m.sigma_s.r, 8.9053e-05f);
    m = medium("\"string preset\" \"Fog\"");
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("medium preset \"Fog\" is not one of pbrt-v3's measured media"),
              std::string::npos)
        << warnings[0];
    EXPECT_FLOAT_EQ(m.sigma_s.r, 2.55f);  // pbrt-v3's defaults
}

TEST(Media, TheBuilderChecksTheirParameters) {
    // Errors, located at the parameter.
    auto error = [](const std::string& medium) {
        try {
            build_warnings(std::string(kVolpath) + medium + "\nWorldEnd\n");
        } catch (const pbrt::SceneError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(
        error("MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 -1 1]"),
        "b.pbrt:2:49: error: sigma_a must not be negative");
    EXPECT_EQ(error("MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"float g\" 1"),
              "b.pbrt:2:49: error: g must lie strictly between -1 and 1, got 1");
    EXPECT_EQ(error("MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"float density\" [1] "
                    "\"point p0\" [0 0 0] \"point p1\" [1 0 1]"),
              "b.pbrt:2:1: error: the medium's grid has no volume (p0 and p1 must differ in x, y "
              "and z, and its transform must be invertible)");
    // What pbrt-v3 reports and renders as vacuum.
    auto about_media = [](const std::vector<std::string>& all) {
        std::vector<std::string> w;  // (not the one of the missing camera)
        for (const std::string& s : all)
            if (s.find("medi") != std::string::npos) w.push_back(s);
        return w;
    };
    auto one = [&](const std::string& medium) {
        const auto w = about_media(build_warnings(std::string(kVolpath) + medium + "\nWorldEnd\n"));
        return w.size() == 1 ? w[0] : std::to_string(w.size()) + " warnings";
    };
    EXPECT_EQ(one("MakeNamedMedium \"m\" \"string type\" \"foggy\""),
              "b.pbrt:2:21: warning: medium \"m\": unknown type \"foggy\" (cmam renders "
              "\"homogeneous\" and \"heterogeneous\"); it is rendered as vacuum");
    EXPECT_EQ(one("MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"integer nx\" 2 "
                  "\"float density\" [1 2 3]"),
              "b.pbrt:2:66: warning: medium \"m\": it has 3 density values; nx*ny*nz = 2; it is "
              "rendered as vacuum");
    EXPECT_EQ(one("MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"float density\" [1] "
                  "\"rgb sigma_a\" [1 2 1]"),
              "b.pbrt:2:1: warning: medium \"m\": a heterogeneous medium needs sigma_a + sigma_s "
              "equal in every channel; its first channel is used, as in pbrt-v3");
    // Media an integrator does not render.
    const auto w = about_media(build_warnings(
        "Integrator \"path\" WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
        "MediumInterface \"m\" \"\"\nWorldEnd\n"));
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0],
              "b.pbrt:3:1: warning: the scene has participating media, which the \"path\" "
              "integrator does not render (as in pbrt-v3; \"volpath\" renders them)");
    // Which integrators render media: pbrt-v3's volpath, bdpt and mlt (the last two rendered as
    // volpath), not sppm, path (the default), whitted or directlighting; and only where a
    // MediumInterface puts a defined medium somewhere.
    for (const auto& pair : {std::pair{"\"volpath\"", true},
                             {"\"bdpt\"", true},
                             {"\"mlt\"", true},
                             {"\"sppm\"", false},
                             {"\"path\"", false},
                             {"\"whitted\"", false},
                             {"\"directlighting\"", false}}) {
        const std::string integrator = pair.first;
        const auto with =
            test::scene_from("Integrator " + integrator +
                             " WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n"
                             "MediumInterface \"m\" \"\"\nWorldEnd\n");
        EXPECT_EQ(with->volumetric, pair.second) << integrator;
        EXPECT_EQ(with->media.size(), 1u) << integrator;
        const auto unused = test::scene_from(
            "Integrator " + integrator +
            " WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\"\nWorldEnd\n");
        EXPECT_FALSE(unused->volumetric) << integrator;
    }
}

namespace {

// An orthographic view (8 x 8 pixels over [-2, 2]^2, one ray through each pixel's centre) of a
// sphere of radius 1.5 at the origin holding `medium`, its surface of material "none", under a
// uniform infinite light of radiance 1.
std::string absorbing_sphere(const std::string& integrator, const std::string& medium) {
    return "LookAt 0 0 -5  0 0 0  0 1 0\n"
           "Camera \"orthographic\" \"float screenwindow\" [-2 2 -2 2]\n"
           "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
           "Sampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" "
           "\"false\"\n"
           "Integrator \"" +
           integrator +
           "\" \"integer maxdepth\" 5\n"
           "WorldBegin\n"
           "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
           "MakeNamedMedium \"m\" " +
           medium +
           "\n"
           "AttributeBegin Material \"\" MediumInterface \"m\" \"\" Shape \"sphere\" \"float "
           "radius\" 1.5 AttributeEnd\n"
           "WorldEnd\n";
}

}  // namespace

TEST(Media, LightThroughAnAbsorbingMediumIsAttenuatedByItsChord) {
    // A medium that only absorbs: distances drawn by sigma_s (0) never scatter, and every ray
    // passes weighted by its transmittance, so one ray per pixel gives exp(-sigma_a chord)
    // exactly (pbrt-v3's draw by sigma_t would end some rays and weight the rest up).
    const float sigma[3] = {0.3f, 0.7f, 1.5f};
    const std::string absorbing =
        "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.3 0.7 1.5] \"rgb sigma_s\" [0 0 0]";
    auto s = test::scene_from(absorbing_sphere("volpath", absorbing));
    ASSERT_TRUE(s->volumetric);
    const Framebuffer fb = render::render(*s, {}, nullptr);
    int inside = 0;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            const float x = -2 + (i + 0.5f) * 0.5f, y = -2 + (j + 0.5f) * 0.5f, r2 = x * x + y * y;
            const float chord = r2 < 2.25f ? 2 * std::sqrt(2.25f - r2) : 0.0f;
            inside += chord > 0;
            for (int c = 0; c < 3; ++c)
                // (within the rays' offsets from the surface: the chord is a few 1e-4 shorter)
                EXPECT_NEAR(fb.rgb[(j * 8 + i) * 3 + c], std::exp(-sigma[c] * chord),
                            3e-3f * std::exp(-sigma[c] * chord))
                    << i << " " << j << " " << c;
        }
    EXPECT_GT(inside, 20);
    // The path integrator leaves media out (as pbrt-v3's does): the light passes unchanged.
    auto p = test::scene_from(absorbing_sphere("path", absorbing));
    EXPECT_FALSE(p->volumetric);
    for (float v : render::render(*p, {}, nullptr).rgb) EXPECT_FLOAT_EQ(v, 1.0f);
}

TEST(Media, ShadowRaysAreAttenuatedThroughBoundaries) {
    // A matte floor (Kd 0.5) below a point light of intensity 9 at height 3, and between them a
    // sphere of radius 1 (centre at height 1.5) of absorbing medium; the camera sees the point
    // below the light, past the sphere. Its radiance: Kd / pi * I / 3^2 * exp(-sigma_a * 2).
    auto scene = [](const std::string& integrator) {
        return test::scene_from(
            "LookAt 0 0.2 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 10\n"
            "Film \"image\" \"integer xresolution\" 3 \"integer yresolution\" 3\n"
            "Sampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" "
            "\"false\"\n"
            "Integrator \"" +
            integrator +
            "\" \"integer maxdepth\" 1\nWorldBegin\n"
            "LightSource \"point\" \"point from\" [0 3 0] \"rgb I\" [9 9 9]\n"
            "MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 0.5 1] "
            "\"rgb sigma_s\" [0 0 0]\n"
            "AttributeBegin Material \"\" MediumInterface \"m\" \"\" Translate 0 1.5 0 Shape "
            "\"sphere\" \"float radius\" 1 AttributeEnd\n"
            "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
            "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-9 0 -9 9 0 -9 "
            "9 "
            "0 9 -9 0 9]\nWorldEnd\n");
    };
    const Framebuffer fb = render::render(*scene("volpath"), {}, nullptr);
    const float sigma[3] = {0.2f, 0.5f, 1.0f};
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(fb.rgb[4 * 3 + c], 0.5f / kPi * std::exp(-2 * sigma[c]), 1e-4f) << c;
    // Without media the sphere of material "none" blocks the light, as it does in pbrt-v3's
    // path integrator (only volpath passes light through the surfaces of material "none").
    EXPECT_EQ(render::render(*scene("path"), {}, nullptr).rgb[4 * 3], 0.0f);
}

TEST(Media, ANonAbsorbingMediumKeepsAUniformLightFieldUniform) {
    // Scattering without absorption in a uniform field of radiance 1: every path ends in the
    // light, so every pixel's expected value is 1, however the light and the phase function are
    // sampled and weighted (the power heuristic's weights sum to 1) and whatever the density.
    // Each pixel's mean of 16 samples is noisy; the image's mean of 4096 is within 1%.
    for (const std::string medium :
         {"\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1.5 1.5 1.5] "
          "\"float g\" 0.6",
          "\"string type\" \"heterogeneous\" \"integer nx\" 2 \"integer ny\" 2 \"integer nz\" 1 "
          "\"float density\" [0.2 2 1 3] \"point p0\" [-1.5 -1.5 -1.5] \"point p1\" [1.5 1.5 1.5] "
          "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1 1 1] \"float g\" -0.3"}) {
        std::string text = absorbing_sphere("volpath", medium);
        auto set = [&](const std::string& from, const std::string& to) {
            ASSERT_NE(text.find(from), std::string::npos) << from;
            text.replace(text.find(from), from.size(), to);
        };
        set("\"integer maxdepth\" 5", "\"integer maxdepth\" 100");
        set("\"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" \"false\"",
            "\"integer xsamples\" 4 \"integer ysamples\" 4");
        set("\"integer xresolution\" 8 \"integer yresolution\" 8",
            "\"integer xresolution\" 16 \"integer yresolution\" 16");
        auto s = test::scene_from(text);
        const Framebuffer fb = render::render(*s, {}, nullptr);
        const double mean = std::accumulate(fb.rgb.begin(), fb.rgb.end(), 0.0) / fb.rgb.size();
        EXPECT_NEAR(mean, 1.0, 0.01) << medium;
    }
}

TEST(Media, DistantLightIsAttenuatedOverTwoWorldRadiiAsInPbrt) {
    // The camera and a matte floor (Kd 0.5, 18 x 18, so the world's bounding sphere has radius
    // R = 9 sqrt 2) in one absorbing medium, lit from straight above by a distant light of
    // radiance 1. pbrt-v3 puts a distant or infinite light's point 2R away, so the light reaches
    // the floor through 2R of medium, not through an infinite length (which would leave it
    // black); the camera ray's own transmittance is its length's, here 5.004.
    const float sigma = 0.02f;
    auto s = test::scene_from(
        "LookAt 0 0.2 -5  0 0 0  0 1 0\nCamera \"perspective\"\n"
        "Integrator \"volpath\" \"integer maxdepth\" 1\n"
        "MediumInterface \"fog\" \"fog\"\n"
        "WorldBegin\n"
        "LightSource \"distant\" \"point from\" [0 1 0] \"point to\" [0 0 0] \"rgb L\" [1 1 1]\n"
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.02 0.02 0.02] "
        "\"rgb sigma_s\" [0 0 0]\n"
        "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-9 0 -9 9 0 -9 9 0 "
        "9 -9 0 9]\nWorldEnd\n");
    ASSERT_TRUE(s->volumetric);
    EXPECT_EQ(s->camera_medium, 0);
    EXPECT_NEAR(s->world_radius, 9 * std::sqrt(2.0f), 1e-3f);
    const int n = 40000;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        sum +=
            trace_radiance(*s, Vec3(0, 0.2f, -5), normalized(Vec3(0, -0.2f, 5)), 7 + i, nullptr).r;
    const double expected =
        0.5 / kPi * std::exp(-sigma * std::sqrt(25.04)) * std::exp(-sigma * 18 * std::sqrt(2.0));
    EXPECT_NEAR(sum / n, expected, 0.03 * expected);
}

TEST(Media, MajorantsSkipEmptySpaceAndKeepTheTransmittance) {
    // A 32^3 grid, empty but for a ball of density 4 (radius 0.15 about the centre), over the
    // unit cube: rays that cross only empty cells draw no number and pass whole; rays through
    // the ball keep exp(-sigma_t * optical depth), measured along the ray by a fine sum.
    Medium m;
    m.type = Medium::Type::Grid;
    m.nx = m.ny = m.nz = 32;
    m.density.assign(32 * 32 * 32, 0.0f);
    for (int k = 0; k < 32; ++k)
        for (int j = 0; j < 32; ++j)
            for (int i = 0; i < 32; ++i) {
                const Vec3 c((i + 0.5f) / 32 - 0.5f, (j + 0.5f) / 32 - 0.5f,
                             (k + 0.5f) / 32 - 0.5f);
                if (dot(c, c) < 0.15f * 0.15f) m.density[(k * 32 + j) * 32 + i] = 4;
            }
    m.inv_max_density = 0.25f;
    m.sigma_a = Rgb(1);
    m.sigma_s = Rgb(2);
    m.sigma_t = m.sigma_a + m.sigma_s;
    m.grid_sigma_t = 3;
    m.grid_from_world = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    m.build_majorants();
    ASSERT_EQ(m.majorant.size(), 16u * 16u * 16u);
    // Each cell's majorant bounds the density everywhere in it (what tracking needs to be
    // unbiased), on its faces too.
    Rng pick(11);
    for (int c = 0; c < 16 * 16 * 16; ++c)
        for (int s = 0; s < 24; ++s) {
            const int i = c % 16, j = (c / 16) % 16, k = c / 256;
            const float fx = s < 8 ? float(s & 1) : pick.next_float(),
                        fy = s < 8 ? float((s >> 1) & 1) : pick.next_float(),
                        fz = s < 8 ? float((s >> 2) & 1) : pick.next_float();
            const Vec3 p((i + fx) / 16, (j + fy) / 16, (k + fz) / 16);
            ASSERT_LE(m.density_at(p), m.majorant[c]) << i << " " << j << " " << k;
        }
    int draws = 0;
    Rng rng(3);
    auto u = [&] {
        ++draws;
        return rng.next_float();
    };
    const Vec3 corner_dir = normalized(Vec3(1, 0.2f, 0.1f));
    EXPECT_EQ(medium_transmittance(m, Vec3(-1, 0.05f, 0.05f), corner_dir, 10, u).r, 1.0f);
    EXPECT_FALSE(sample_medium(m, Vec3(-1, 0.05f, 0.05f), corner_dir, 10, u).scattered);
    EXPECT_EQ(draws, 0);
    const Vec3 o(-1, 0.52f, 0.47f), dir = normalized(Vec3(1, 0.05f, -0.02f));
    double depth = 0;
    const int steps = 20000;
    for (int k = 0; k < steps; ++k) {
        const float t = 3.0f * (k + 0.5f) / steps;
        depth += m.density_at(o + t * dir) * 3.0 / steps;
    }
    const double tr = std::exp(-3 * depth);
    ASSERT_LT(tr, 0.6);
    ASSERT_GT(tr, 0.05);
    const int n = 200000;
    double mean = 0, passed = 0;
    for (int i = 0; i < n; ++i) {
        mean += medium_transmittance(m, o, dir, 3, u).r;
        passed += sample_medium(m, o, dir, 3, u).scattered ? 0 : 1;
    }
    EXPECT_NEAR(mean / n, tr, 0.015 * tr);
    EXPECT_NEAR(passed / n, tr, 0.015 * tr);
}
