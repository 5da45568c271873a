// Whole-render throughput of the demo scene beside a bare Embree loop that casts the same
// camera and shadow rays (rtcIntersect1 / rtcOccluded1, no shading), and their ratio; and each
// footprint method's render time against --lod none, separately and paired; and the area filter's
// against EWA, paired.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <map>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/integrator.h"
#include "render/scene.h"

using namespace cmam;

namespace {

std::unique_ptr<render::Scene> demo_scene(render::BuildOptions bo = {}) {
    pbrt::SceneDesc d = pbrt::parse_file(std::string(CMAM_SCENES_DIR) + "/demo.pbrt");
    return render::build_scene(d, bo, {});
}

// How the benchmarks render: as `cmam render` without --stats, lookups not counted (counting
// them costs the filters bookkeeping that no plain render pays).
render::RenderOptions bench_options() {
    render::RenderOptions ro;
    ro.count_lookups = false;
    return ro;
}

// The demo scene with one footprint source and filter (--lod / --filter), its pyramids and
// tables built (outside any timing).
std::unique_ptr<render::Scene> lod_scene(render::FootprintMethod lod, texture::FilterKind filter) {
    render::BuildOptions bo;
    bo.lod = lod;
    bo.filter = filter;
    auto scene = demo_scene(bo);
    for (auto& [k, tex] : scene->images) {
        tex->pyramid();
        tex->sat();
        if (filter == texture::FilterKind::Area)
            for (int l = 0; l < tex->pyramid().levels(); ++l) tex->row_prefix(l).build_all();
    }
    return scene;
}

// Whole render of the demo scene with one footprint source and filter.
void BM_RenderLod(benchmark::State& state, render::FootprintMethod lod,
                  texture::FilterKind filter) {
    const auto scene = lod_scene(lod, filter);
    for (auto _ : state) {
        render::Framebuffer fb = render::render(*scene, bench_options(), nullptr);
        benchmark::DoNotOptimize(fb.rgb.data());
    }
}

// Two renders alternately within one benchmark (which goes first alternates too), each timed on
// its own: on a shared machine whose speed drifts by tens of percent between runs, separate
// benchmarks would read the drift as a difference. The counter `name` is the first's total
// render time over the second's, minus one, in percent.
void paired(benchmark::State& state, const render::Scene& first, const render::Scene& second,
            const char* name) {
    using Clock = std::chrono::steady_clock;
    Clock::duration with{}, without{};
    auto timed = [](const render::Scene& sc, Clock::duration& total) {
        const auto t0 = Clock::now();
        render::Framebuffer fb = render::render(sc, bench_options(), nullptr);
        benchmark::DoNotOptimize(fb.rgb.data());
        total += Clock::now() - t0;
    };
    bool method_first = true;
    for (auto _ : state) {
        if (method_first) {
            timed(first, with);
            timed(second, without);
        } else {
            timed(second, without);
            timed(first, with);
        }
        method_first = !method_first;
    }
    state.counters[name] = 100.0 * (std::chrono::duration<double>(with).count() /
                                        std::chrono::duration<double>(without).count() -
                                    1);
}

// A footprint method's render against `--lod none`'s, paired. Counter "overhead".
void BM_RenderLodVsNone(benchmark::State& state, render::FootprintMethod lod,
                        texture::FilterKind filter) {
    const auto scene = lod_scene(lod, filter),
               none = lod_scene(render::FootprintMethod::None, texture::FilterKind::Bilinear);
    paired(state, *scene, *none, "overhead");
}

// The exact area filter against EWA with ray differentials (pbrt-v3's default), paired.
// Counter "area_vs_ewa": area's render time over EWA's, minus one, in percent.
void BM_RenderAreaVsEwa(benchmark::State& state) {
    const auto area = lod_scene(render::FootprintMethod::Differentials, texture::FilterKind::Area),
               ewa = lod_scene(render::FootprintMethod::Differentials, texture::FilterKind::Ewa);
    paired(state, *area, *ewa, "area_vs_ewa");
}

double g_render_rate = 0, g_bare_rate = 0;

void BM_RenderDemo(benchmark::State& state) {
    auto scene = demo_scene();
    uint64_t rays = 0;
    for (auto _ : state) {
        render::RenderStats stats;
        render::Framebuffer fb = render::render(*scene, bench_options(), &stats);
        benchmark::DoNotOptimize(fb.rgb.data());
        rays += stats.total_rays();
    }
    state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
    state.counters["Mrays/s"] = benchmark::Counter(double(rays) / 1e6, benchmark::Counter::kIsRate);
    g_render_rate = double(rays) / state.iterations();
}

// The bare loop: for every camera sample, rtcIntersect1; for every hit, one rtcOccluded1
// towards each delta light, as the integrator would. No materials, textures or recursion.
void BM_BareEmbreeDemo(benchmark::State& state) {
    auto scene = demo_scene();
    const auto& film = scene->film;
    const int nx = scene->sampler.xsamples, ny = scene->sampler.ysamples;
    uint64_t rays_total = 0;
    for (auto _ : state) {
        std::atomic<uint64_t> rays{0};
        tbb::parallel_for(
            tbb::blocked_range<int>(film.y0, film.y1, 1), [&](const tbb::blocked_range<int>& r) {
                uint64_t local = 0;
                RTCIntersectContext ctx;
                for (int py = r.begin(); py < r.end(); ++py)
                    for (int px = film.x0; px < film.x1; ++px)
                        for (int s = 0; s < nx * ny; ++s) {
                            const render::CameraRay ray = scene->camera.generate_ray(
                                px + (s % nx + 0.5f) / nx, py + (s / nx + 0.5f) / ny);
                            const render::Vec3 &o = ray.org, &d = ray.dir;
                            RTCRayHit rh{};
                            rh.ray.org_x = o.x;
                            rh.ray.org_y = o.y;
                            rh.ray.org_z = o.z;
                            rh.ray.dir_x = d.x;
                            rh.ray.dir_y = d.y;
                            rh.ray.dir_z = d.z;
                            rh.ray.tfar = std::numeric_limits<float>::infinity();
                            rh.ray.mask = ~0u;
                            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                            rtcInitIntersectContext(&ctx);
                            rtcIntersect1(scene->embree_scene(), &ctx, &rh);
                            ++local;
                            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
                            render::Vec3 p = o + d * rh.ray.tfar;
                            for (const auto& l : scene->lights) {
                                if (l.type == render::Light::Type::Infinite) continue;
                                render::Vec3 w = l.type == render::Light::Type::Distant
                                                     ? l.direction
                                                     : l.position - p;
                                float tmax = l.type == render::Light::Type::Distant
                                                 ? std::numeric_limits<float>::infinity()
                                                 : 0.9999f;
                                RTCRay sr{};
                                render::Vec3 so = p + w * 1e-4f;
                                sr.org_x = so.x;
                                sr.org_y = so.y;
                                sr.org_z = so.z;
                                sr.dir_x = w.x;
                                sr.dir_y = w.y;
                                sr.dir_z = w.z;
                                sr.tfar = tmax;
                                sr.mask = ~0u;
                                rtcInitIntersectContext(&ctx);
                                rtcOccluded1(scene->embree_scene(), &ctx, &sr);
                                ++local;
                            }
                        }
                rays += local;
            });
        rays_total += rays;
    }
    state.counters["rays/s"] = benchmark::Counter(double(rays_total), benchmark::Counter::kIsRate);
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays_total) / 1e6, benchmark::Counter::kIsRate);
    g_bare_rate = double(rays_total) / state.iterations();
}

BENCHMARK(BM_RenderDemo)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_BareEmbreeDemo)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// The footprint methods timed against --lod none (names as in the output).
struct Method {
    const char* name;
    render::FootprintMethod lod;
    texture::FilterKind filter;
    const char* target = nullptr;  // the bound set on the overhead, where there is one
};
constexpr Method kMethods[] = {
    {"cmam_trilinear", render::FootprintMethod::Cmam, texture::FilterKind::Trilinear, "+10%"},
    {"cmam_sat", render::FootprintMethod::Cmam, texture::FilterKind::Sat},
    {"cmam_ewa", render::FootprintMethod::Cmam, texture::FilterKind::Ewa},
    {"differentials_ewa", render::FootprintMethod::Differentials, texture::FilterKind::Ewa, "+25%"},
    {"differentials_trilinear", render::FootprintMethod::Differentials,
     texture::FilterKind::Trilinear},
    {"differentials_area", render::FootprintMethod::Differentials, texture::FilterKind::Area},
    {"cones_trilinear", render::FootprintMethod::Cones, texture::FilterKind::Trilinear},
    {"cones_aniso_ewa", render::FootprintMethod::ConesAniso, texture::FilterKind::Ewa},
    {"cones_aniso_area", render::FootprintMethod::ConesAniso, texture::FilterKind::Area}};

// The comparisons that have a target run kRepeats times: one run of 8 pairs moves by a few
// percent on a shared machine (+7.3% to +10.6% for the CMAM with MIP in six runs), so the figure
// printed is the median of the runs, with their range.
constexpr int kRepeats = 5;
double min_of(const std::vector<double>& v) {
    return *std::min_element(v.begin(), v.end());
}
double max_of(const std::vector<double>& v) {
    return *std::max_element(v.begin(), v.end());
}
void repeated(benchmark::internal::Benchmark* b) {
    b->Repetitions(kRepeats)
        ->ReportAggregatesOnly(true)
        ->ComputeStatistics("min", min_of)
        ->ComputeStatistics("max", max_of);
}

// Each method alone (BM_RenderLod, after --lod none), then each against --lod none alternately.
void register_methods() {
    auto add = [](const std::string& name, auto fn, render::FootprintMethod lod,
                  texture::FilterKind filter) {
        return benchmark::RegisterBenchmark(name.c_str(), fn, lod, filter)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    };
    add("BM_RenderLod/none", BM_RenderLod, render::FootprintMethod::None,
        texture::FilterKind::Bilinear)
        ->MinTime(1.0);
    for (const Method& m : kMethods)
        add(std::string("BM_RenderLod/") + m.name, BM_RenderLod, m.lod, m.filter)->MinTime(1.0);
    for (const Method& m : kMethods) {
        auto* b =
            add(std::string("BM_RenderLodVsNone/") + m.name, BM_RenderLodVsNone, m.lod, m.filter)
                ->Iterations(8);
        if (m.target) repeated(b);
    }
    repeated(benchmark::RegisterBenchmark("BM_RenderAreaVsEwa", BM_RenderAreaVsEwa)
                 ->Unit(benchmark::kMillisecond)
                 ->UseRealTime()
                 ->Iterations(8));
}

// A paired comparison's counter: one run's, or with repetitions their median and range.
struct Paired {
    double value = 0, lo = 0, hi = 0;
    bool repeated = false;
    bool seen = false;
    void take(const benchmark::BenchmarkReporter::Run& r, const char* counter) {
        auto o = r.counters.find(counter);
        if (o == r.counters.end()) return;
        if (r.aggregate_name.empty() || r.aggregate_name == "median") value = o->second;
        if (r.aggregate_name == "min") lo = o->second;
        if (r.aggregate_name == "max") hi = o->second;
        repeated = repeated || !r.aggregate_name.empty();
        seen = true;
    }
    // "+9.5% render time (paired; median of 5 runs of 8 pairs, +7.3% to +10.6%)".
    std::string text() const {
        char buf[160];
        if (repeated)
            std::snprintf(buf, sizeof buf,
                          "%+.1f%% render time (paired; median of %d runs of 8 pairs, %+.1f%% to "
                          "%+.1f%%)",
                          value, kRepeats, lo, hi);
        else
            std::snprintf(buf, sizeof buf, "%+.1f%% render time (paired)", value);
        return buf;
    }
};

// Prints the ratio of the two rays/s figures after the runs, and each comparison's figure.
class RatioReporter : public benchmark::ConsoleReporter {
  public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            const std::string name = r.benchmark_name();
            const bool usable = r.aggregate_name.empty() || r.aggregate_name == "median";
            if (usable && name.find("BM_RenderLod/") != std::string::npos)
                m_lod[name.substr(13, name.find('/', 13) - 13)] = r.GetAdjustedRealTime();
            if (name.find("BM_RenderLodVsNone/") != std::string::npos)
                m_paired[name.substr(19, name.find('/', 19) - 19)].take(r, "overhead");
            if (name.find("BM_RenderAreaVsEwa") != std::string::npos)
                m_area_vs_ewa.take(r, "area_vs_ewa");
            auto it = r.counters.find("rays/s");
            if (it == r.counters.end()) continue;
            if (name.find("RenderDemo") != std::string::npos) m_render = it->second;
            if (name.find("BareEmbree") != std::string::npos) m_bare = it->second;
        }
    }
    void Finalize() override {
        ConsoleReporter::Finalize();
        if (m_render > 0 && m_bare > 0)
            std::printf("\nwhole render / bare Embree loop (rays/s): %.1f%%  (target >= 70%%)\n",
                        100.0 * m_render / m_bare);
        // Each method's render time over --lod none's: from the paired benchmark when it ran
        // (the two alternate, so machine drift cancels), else from the separate ones.
        for (const Method& m : kMethods) {
            const std::string k = m.name;
            const bool paired = m_paired.count(k) > 0 && m_paired[k].seen;
            if (!paired && !(m_lod.count(k) && m_lod.count("none"))) continue;
            char separate[48];
            std::snprintf(separate, sizeof separate, "%+.1f%% render time",
                          paired ? 0.0 : 100.0 * (m_lod[k] / m_lod["none"] - 1));
            std::printf("--lod %s vs --lod none: %s", m.name,
                        paired ? m_paired[k].text().c_str() : separate);
            if (m.target) std::printf("  (target <= %s)", m.target);
            std::printf("\n");
        }
        if (m_area_vs_ewa.seen)
            std::printf("differentials: --filter area vs --filter ewa: %s  (target <= 0%%)\n",
                        m_area_vs_ewa.text().c_str());
    }

  private:
    double m_render = 0, m_bare = 0;
    Paired m_area_vs_ewa;
    std::map<std::string, double> m_lod;
    std::map<std::string, Paired> m_paired;
};

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    register_methods();
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
