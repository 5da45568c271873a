// Nanoseconds per lookup of each filter over footprints of 1 to 4096 texels and anisotropy
// 1 to 16 on a 2048^2 RGB texture, beside the same lookups (same uv and derivatives) through
// OpenImageIO's TextureSystem on a MIP-mapped copy (its trilinear and anisotropic modes), the two
// run alternately; at the exact sizes and spread over an octave around them. Prints our/their
// ratios, and EWA's cost spread across footprint sizes at each anisotropy (ours and OpenImageIO's,
// over all sizes and over the footprints that minify).
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>
#include <benchmark/benchmark.h>
#include <cmam/texture/filter.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

using namespace cmam::texture;

namespace {

constexpr int kRes = 2048;
constexpr int kBatch = 1024;
constexpr int kSizes[] = {1, 16, 256, 4096};
// 8 is the maximum anisotropy both sides are given: beyond it both widen the minor axis.
constexpr int kAnisos[] = {1, 4, 8, 16};

std::vector<float> make_texels() {
    std::vector<float> px(static_cast<std::size_t>(kRes) * kRes * 3);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    for (float& p : px) p = u(rng);
    return px;
}

struct Fixture {
    std::unique_ptr<FilteredTexture> ours;
    OIIO::TextureSystem* ts = nullptr;
    OIIO::ustring file;
    Fixture() {
        auto px = make_texels();
        ours = std::make_unique<FilteredTexture>(Image(kRes, kRes, 3, px));
        ours->pyramid();
        ours->sat();
        for (int l = 0; l < ours->pyramid().levels(); ++l) ours->row_prefix(l).build_all();
        std::string path = (std::filesystem::temp_directory_path() /
                            ("cmam_bench_" + std::to_string(::getpid()) + ".exr"))
                               .string();
        OIIO::ImageBuf buf(OIIO::ImageSpec(kRes, kRes, 3, OIIO::TypeDesc::FLOAT), px.data());
        OIIO::ImageSpec config;
        config.tile_width = config.tile_height = 64;
        config.attribute("maketx:filtername", "box");
        if (!OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, buf, path, config))
            std::fprintf(stderr, "make_texture failed: %s\n", OIIO::geterror().c_str());
        file = OIIO::ustring(path);
        ts = OIIO::TextureSystem::create(false);
        ts->attribute("max_memory_MB", 2048.0f);
    }
    ~Fixture() {
        OIIO::TextureSystem::destroy(ts);
        std::filesystem::remove(file.string());
    }
};

Fixture& fixture() {
    static Fixture f;
    return f;
}

struct Query {
    float u, v, au, av, bu, bv;
};

// Footprints whose major axis is `size` texels and minor axis size/aniso, at random angles,
// visited the way a renderer visits them: runs of 32 lookups, each one pixel step (the first
// axis) beyond the previous, starting at random points. Random points alone would measure DRAM
// latency rather than filtering.
//
// With `spread`, each run's size is scaled by 2^x, x uniform in [-1/2, 1/2): the level of detail
// then has a uniformly distributed fractional part, as a renderer's footprints do. At the exact
// sizes (powers of two) every lookup's level of detail is an integer to within rounding, a
// boundary case of level selection: there OpenImageIO and our EWA, which both take the level
// from the minor axis in single precision, mostly read one level, and our trilinear reads its
// two levels as always.
std::vector<Query> queries(double size, double aniso, bool spread) {
    std::mt19937 rng(static_cast<unsigned>(size * 131 + aniso));
    std::uniform_real_distribution<double> u(0, 1), ang(0, 2 * M_PI);
    std::vector<Query> q(kBatch);
    double pu = 0, pv = 0, th = 0, scale = 1;
    for (int i = 0; i < kBatch; ++i) {
        if (i % 32 == 0 && spread) scale = std::exp2(u(rng) - 0.5);
        const double a = scale * size / kRes, b = scale * size / aniso / kRes;
        if (i % 32 == 0) {
            pu = u(rng);
            pv = u(rng);
            th = ang(rng);
        } else {
            pu += a * std::cos(th);
            pv += a * std::sin(th);
        }
        q[i] = {float(pu - std::floor(pu)), float(pv - std::floor(pv)), float(a * std::cos(th)),
                float(a * std::sin(th)),    float(-b * std::sin(th)),   float(b * std::cos(th))};
    }
    return q;
}

void record(benchmark::State& state) {
    state.SetItemsProcessed(state.iterations() * kBatch);
    state.counters["ns/lookup"] =
        benchmark::Counter(double(state.iterations()) * kBatch,
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// Our lookups of one case, and OpenImageIO's (its trilinear mode, or its anisotropic mode with
// the same maximum anisotropy), on the same uv and derivatives.
struct Case {
    std::vector<Query> q;
    std::vector<Footprint> fps;
    FilterOptions ours;
    OIIO::TextureOpt theirs;
    Case(const benchmark::State& state, FilterKind kind, bool aniso, bool spread = false)
        : q(queries(double(state.range(0)), double(state.range(1)), spread)), ours{kind, 8} {
        for (const Query& x : q) fps.push_back(Footprint::axes({x.au, x.av}, {x.bu, x.bv}));
        theirs.mipmode =
            aniso ? OIIO::TextureOpt::MipModeAniso : OIIO::TextureOpt::MipModeTrilinear;
        theirs.interpmode = OIIO::TextureOpt::InterpBilinear;
        theirs.anisotropic = 8;
        theirs.swrap = theirs.twrap = OIIO::TextureOpt::WrapPeriodic;
    }
    void run_ours(Fixture& f) const {
        for (int i = 0; i < kBatch; ++i) {
            Texel t = f.ours->lookup(q[i].u, q[i].v, fps[i], ours);
            benchmark::DoNotOptimize(t);
        }
    }
    void run_theirs(Fixture& f, OIIO::TextureSystem::Perthread* pt,
                    OIIO::TextureSystem::TextureHandle* h) const {
        float out[3];
        OIIO::TextureOpt opt = theirs;  // texture() takes it by non-const reference
        for (const Query& x : q) {
            f.ts->texture(h, pt, opt, x.u, 1 - x.v, x.au, -x.av, x.bu, -x.bv, 3, out);
            benchmark::DoNotOptimize(out);
        }
    }
};

void BM_Ours(benchmark::State& state, FilterKind kind, bool spread = false) {
    Fixture& f = fixture();
    const Case c(state, kind, false, spread);
    for (auto _ : state) c.run_ours(f);
    record(state);
}

// Ours and theirs alternately within one benchmark, each side timed on its own: the ratio
// compares the two under the same machine conditions (a shared machine's speed drifts by tens of
// percent within seconds, which separate runs would read as a difference between the
// libraries). Each turn is kTurn batches, so that a side's working set, which the other side's
// turn may have pushed out of the L2 cache, is refilled once per turn rather than once per
// batch (alternating batch by batch slowed both sides' anisotropic cases by up to 1.8x).
// Counters: "ours" and "oiio" in ns per lookup, "ratio" = their time over ours.
constexpr int kTurn = 32;

void BM_Versus(benchmark::State& state, FilterKind kind, bool spread) {
    Fixture& f = fixture();
    const Case c(state, kind, kind == FilterKind::Ewa, spread);
    auto* pt = f.ts->get_perthread_info();
    auto* h = f.ts->get_texture_handle(f.file);
    using Clock = std::chrono::steady_clock;
    Clock::duration ours{}, theirs{};
    for (auto _ : state) {
        const auto t0 = Clock::now();
        for (int k = 0; k < kTurn; ++k) c.run_ours(f);
        const auto t1 = Clock::now();
        for (int k = 0; k < kTurn; ++k) c.run_theirs(f, pt, h);
        ours += t1 - t0;
        theirs += Clock::now() - t1;
    }
    const double n = double(state.iterations()) * kTurn * kBatch;
    state.counters["ours"] = std::chrono::duration<double, std::nano>(ours).count() / n;
    state.counters["oiio"] = std::chrono::duration<double, std::nano>(theirs).count() / n;
    state.counters["ratio"] =
        std::chrono::duration<double>(theirs).count() / std::chrono::duration<double>(ours).count();
}

// Three repetitions of each case, at the exact sizes and spread over an octave around them; the
// summary uses medians.
void register_benchmarks() {
    for (int size : kSizes)
        for (int aniso : kAnisos) {
            auto add = [&](const char* name, auto fn, auto... arg) {
                benchmark::RegisterBenchmark(name, fn, arg...)
                    ->Args({size, aniso})
                    ->MinTime(0.1)
                    ->Repetitions(3);
            };
            add("BM_Versus/trilinear", BM_Versus, FilterKind::Trilinear, false);
            add("BM_Versus/ewa", BM_Versus, FilterKind::Ewa, false);
            add("BM_VersusSpread/trilinear", BM_Versus, FilterKind::Trilinear, true);
            add("BM_VersusSpread/ewa", BM_Versus, FilterKind::Ewa, true);
            add("BM_Ours/sat", BM_Ours, FilterKind::Sat, false);
            // The exact area filter beside EWA and trilinear, ours alone, at spread sizes.
            add("BM_OursSpread/trilinear", BM_Ours, FilterKind::Trilinear, true);
            add("BM_OursSpread/ewa", BM_Ours, FilterKind::Ewa, true);
            add("BM_OursSpread/area", BM_Ours, FilterKind::Area, true);
            // Nearest and bilinear ignore the footprint: one size and anisotropy is enough.
            if (size == 1 && aniso == 1) {
                add("BM_Ours/nearest", BM_Ours, FilterKind::Nearest, false);
                add("BM_Ours/bilinear", BM_Ours, FilterKind::Bilinear, false);
            }
        }
}

class SummaryReporter : public benchmark::ConsoleReporter {
  public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            if (r.run_type != Run::RT_Aggregate || r.aggregate_name != "median") continue;
            for (const char* c : {"ours", "oiio", "ratio", "ns/lookup"}) {
                auto it = r.counters.find(c);
                if (it != r.counters.end()) m_value[r.run_name.str() + "#" + c] = it->second;
            }
        }
    }
    void Finalize() override {
        ConsoleReporter::Finalize();
        table("BM_Versus", "exact sizes");
        table("BM_VersusSpread", "sizes spread over an octave around each");
        area_table();
    }

    // The exact area filter beside our EWA and trilinear (ours alone, spread sizes).
    void area_table() {
        std::printf(
            "\nBM_OursSpread (ns per lookup, medians of 3 repetitions)\n%-12s %10s %10s "
            "%10s %12s\n",
            "size/aniso", "trilinear", "ewa", "area", "area/ewa");
        for (int size : kSizes)
            for (int aniso : kAnisos) {
                const std::string key = "/" + std::to_string(size) + "/" + std::to_string(aniso) +
                                        "/min_time:0.100/repeats:3#ns/lookup";
                auto get = [&](const char* filter) {
                    auto it = m_value.find(std::string("BM_OursSpread/") + filter + key);
                    return it == m_value.end() ? 0.0 : it->second;
                };
                // The counter is seconds per lookup (an inverted rate).
                const double t = 1e9 * get("trilinear"), e = 1e9 * get("ewa"),
                             a = 1e9 * get("area");
                if (t <= 0 || e <= 0 || a <= 0) continue;
                std::printf("%5d/%-6d %10.1f %10.1f %10.1f %11.2fx\n", size, aniso, t, e, a, a / e);
            }
    }

  private:
    // The summary of one family of BM_Versus runs: per case our and their ns per lookup and the
    // ratio, EWA's cost spread across sizes, and the targets.
    void table(const std::string& family, const char* title) {
        std::printf("\n%s (%s)\n%-12s %8s %10s %10s %10s %10s %10s  %s\n", family.c_str(), title,
                    "size/aniso", "ours-tri", "oiio-tri", "ratio", "ours-ewa", "oiio-aniso",
                    "ratio", "(ns per lookup; ratio = their time over ours, measured alternately)");
        double ewa_min = 1e30, ewa_max = 0, worst_tri = 1e30, worst_ewa = 1e30;
        // Per anisotropy: fastest and slowest over all sizes, and over the sizes that minify
        // (16-4096: at size 1 the footprint is under a texel, so EWA reads only a few texels).
        std::map<int, std::pair<double, double>> spread, spread_min, spread_oiio;
        // Per anisotropy, ours and OpenImageIO's, over the footprints EWA filters by minifying:
        // minor axis from one texel (below it the footprint magnifies, and the +1 reconstruction
        // term leaves a nearly round ellipse of a few texels whatever the anisotropy) up to the
        // texture's size (beyond it the lookup is the coarsest level's mean).
        std::map<int, std::pair<double, double>> minify_ours, minify_oiio;
        auto widen = [](std::map<int, std::pair<double, double>>& m, int aniso, double t) {
            auto& [lo, hi] = m.try_emplace(aniso, 1e30, 0.0).first->second;
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        };
        std::map<int, double> worst_ewa_at;  // per anisotropy, over all sizes
        for (int size : kSizes)
            for (int aniso : kAnisos) {
                std::string key = "/" + std::to_string(size) + "/" + std::to_string(aniso) +
                                  "/min_time:0.100/repeats:3";
                auto get = [&](const char* filter, const char* counter) {
                    auto it = m_value.find(family + "/" + filter + key + "#" + counter);
                    return it == m_value.end() ? 0.0 : it->second;
                };
                const double ot = get("trilinear", "ours"), tt = get("trilinear", "oiio"),
                             rt = get("trilinear", "ratio");
                const double oe = get("ewa", "ours"), te = get("ewa", "oiio"),
                             re = get("ewa", "ratio");
                if (ot <= 0 || tt <= 0 || oe <= 0 || te <= 0) continue;
                std::printf("%5d/%-6d %8.1f %10.1f %9.2fx %10.1f %10.1f %9.2fx\n", size, aniso, ot,
                            tt, rt, oe, te, re);
                worst_tri = std::min(worst_tri, rt);
                worst_ewa = std::min(worst_ewa, re);
                auto& w = worst_ewa_at.try_emplace(aniso, 1e30).first->second;
                w = std::min(w, re);
                ewa_min = std::min(ewa_min, oe);
                ewa_max = std::max(ewa_max, oe);
                widen(spread, aniso, oe);
                widen(spread_oiio, aniso, te);
                if (size >= 16) widen(spread_min, aniso, oe);
                const int minor = size / aniso;
                if (size >= aniso && minor <= kRes) {
                    widen(minify_ours, aniso, oe);
                    widen(minify_oiio, aniso, te);
                }
            }
        if (ewa_max <= 0) return;
        // One line: slowest over fastest per anisotropy; returns the largest.
        auto line = [](const char* label, const std::map<int, std::pair<double, double>>& m) {
            double worst = 0;
            std::printf("\n%s:", label);
            for (auto& [aniso, lh] : m) {
                worst = std::max(worst, lh.second / lh.first);
                std::printf("  aniso %d: %.2fx", aniso, lh.second / lh.first);
            }
            return worst;
        };
        std::printf("(medians of 3 repetitions)");
        line("EWA slowest/fastest across sizes 1-4096", spread);
        line("OpenImageIO's anisotropic mode, the same", spread_oiio);
        line("EWA slowest/fastest across sizes 16-4096", spread_min);
        const std::string minify =
            "EWA slowest/fastest over the footprints that minify (minor axis 1-" +
            std::to_string(kRes) + " texels)";
        const double minify_worst = line(minify.c_str(), minify_ours);
        line("OpenImageIO's anisotropic mode, the same", minify_oiio);
        std::printf("\nworst EWA/aniso ratio per anisotropy:");
        for (auto& [aniso, w] : worst_ewa_at) std::printf("  aniso %d: %.2fx", aniso, w);
        std::printf(
            "\nworst trilinear ratio %.2fx (target >= 3x); worst EWA/aniso ratio %.2fx (target "
            ">= 1.5x); EWA slowest/fastest footprint %.2fx (over all sizes and anisotropies); "
            "EWA slowest/fastest minifying footprint at one anisotropy %.2fx (target <= 2x)\n",
            worst_tri, worst_ewa, ewa_max / ewa_min, minify_worst);
    }

    std::map<std::string, double> m_value;  // "name/args#counter" -> median
};

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    register_benchmarks();
    SummaryReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
