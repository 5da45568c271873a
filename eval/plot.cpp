#include "eval/plot.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cmam::eval {

namespace {

// Plot styles: a colour, a marker, a fill and a dash pattern per method. The marker, fill and
// dash together differ for the first 48 methods, so the plot reads in grey as well.
const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                         "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#393b79",
                         "#637939", "#843c39", "#7b4173", "#3182bd", "#e6550d",
                         "#31a354", "#756bb1", "#636363", "#a55194", "#8c6d31"};
constexpr int kColorCount = sizeof kColors / sizeof kColors[0];
const char* kDashes[] = {"", "6 3", "2 2"};

struct Style {
    const char* color;
    int marker;  // 0 circle, 1 square, 2 triangle up, 3 diamond, 4 triangle down, 5 plus,
                 // 6 cross, 7 star
    bool hollow;
    const char* dash;
};

Style style_of(std::size_t m) {
    return {kColors[m % kColorCount], static_cast<int>(m % 8), (m / 8) % 2 == 1,
            kDashes[(m / 16) % 3]};
}

std::string marker_svg(const Style& st, double x, double y, const std::string& title) {
    const double r = 4.5;
    std::ostringstream s;
    const std::string paint =
        st.hollow ? std::string("fill=\"#fff\" stroke=\"") + st.color + "\" stroke-width=\"1.6\""
                  : std::string("fill=\"") + st.color + "\" stroke=\"" + st.color +
                        "\" stroke-width=\"1\"";
    auto poly = [&](std::initializer_list<std::pair<double, double>> pts) {
        s << "<polygon " << paint << " points=\"";
        for (auto [dx, dy] : pts) s << x + dx * r << "," << y + dy * r << " ";
        s << "\">";
    };
    switch (st.marker) {
        case 0:
            s << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"" << r << "\" " << paint << ">";
            break;
        case 1:
            poly({{-0.85, -0.85}, {0.85, -0.85}, {0.85, 0.85}, {-0.85, 0.85}});
            break;
        case 2:
            poly({{0, -1.1}, {1, 0.75}, {-1, 0.75}});
            break;
        case 3:
            poly({{0, -1.15}, {1.15, 0}, {0, 1.15}, {-1.15, 0}});
            break;
        case 4:
            poly({{0, 1.1}, {1, -0.75}, {-1, -0.75}});
            break;
        case 5:
            poly({{-0.3, -1},
                  {0.3, -1},
                  {0.3, -0.3},
                  {1, -0.3},
                  {1, 0.3},
                  {0.3, 0.3},
                  {0.3, 1},
                  {-0.3, 1},
                  {-0.3, 0.3},
                  {-1, 0.3},
                  {-1, -0.3},
                  {-0.3, -0.3}});
            break;
        case 6:
            poly({{-1, -0.6},
                  {-0.6, -1},
                  {0, -0.4},
                  {0.6, -1},
                  {1, -0.6},
                  {0.4, 0},
                  {1, 0.6},
                  {0.6, 1},
                  {0, 0.4},
                  {-0.6, 1},
                  {-1, 0.6},
                  {-0.4, 0}});
            break;
        default:
            poly({{0, -1.2},
                  {0.3, -0.4},
                  {1.15, -0.37},
                  {0.48, 0.15},
                  {0.71, 0.97},
                  {0, 0.5},
                  {-0.71, 0.97},
                  {-0.48, 0.15},
                  {-1.15, -0.37},
                  {-0.3, -0.4}});
    }
    s << "<title>" << html_escape(title) << "</title>"
      << (st.marker == 0 ? "</circle>" : "</polygon>") << "\n";
    return s.str();
}

std::string tick_label(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

// Ticks of a log axis over [lo, hi] (values, lo > 0): the densest of 10^d, {1,2,5} 10^d and
// {1..9} 10^d whose labels keep `gap` pixels apart at `pixels_per_decade`; evenly spaced values
// when that leaves fewer than three in a narrow range.
std::vector<double> log_ticks(double lo, double hi, double pixels_per_decade, double gap) {
    std::vector<std::vector<double>> sets;
    for (auto mults : {std::vector<double>{1}, std::vector<double>{1, 2, 5},
                       std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
        std::vector<double> t;
        for (double d = std::floor(std::log10(lo)); d <= std::ceil(std::log10(hi)); d += 1)
            for (double k : mults) {
                double v = k * std::pow(10, d);
                if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) t.push_back(v);
            }
        sets.push_back(t);
    }
    auto fits = [&](const std::vector<double>& t) {
        for (std::size_t i = 1; i < t.size(); ++i)
            if (std::log10(t[i] / t[i - 1]) * pixels_per_decade < gap) return false;
        return true;
    };
    std::vector<double> best = sets[0];
    for (const auto& t : sets)
        if (fits(t)) best = t;
    if (best.size() >= 3) return best;
    // A narrow range: a round linear step giving about five values.
    double step = std::pow(10, std::floor(std::log10((hi - lo) / 5)));
    for (double k : {1.0, 2.0, 5.0, 10.0})
        if ((hi - lo) / (step * k) <= 6) {
            step *= k;
            break;
        }
    std::vector<double> t;
    for (double v = std::ceil(lo / step) * step; v <= hi * (1 + 1e-9); v += step) t.push_back(v);
    return t.size() >= 2 && fits(t) ? t : best;
}

struct Series {
    double x, y;
    int spp;
};

// One plot's geometry: its size and margins, the ranges of its axes (padded) and where a time
// (x) and an error (y) fall in pixels.
struct PlotFrame {
    static constexpr int W = 600, L = 64, R = 210, T = 14, B = 46;
    int H = 0;
    double tmin = 1e30, tmax = 0, emin = 1e30, emax = 0;
    bool zeros = false;  // an error of exactly 0 is plotted
    int zero_band = 0;
    double pw = 0, ph = 0, lt0 = 0, lt1 = 0, le0 = 0, le1 = 0;

    double X(double t) const {
        return L + (std::log10(std::max(t, 1e-4)) - lt0) / (lt1 - lt0) * pw;
    }
    double Y(double e) const {
        if (!(e > 0)) return T + ph + zero_band * 0.6;
        return T + ph - (std::log10(e) - le0) / (le1 - le0) * ph;
    }
};

PlotFrame plot_frame(const std::vector<const ResultRow*>& rows, std::size_t method_count,
                     double ResultRow::*error) {
    PlotFrame f;
    const int T = PlotFrame::T;
    f.H = std::max(340, T + 18 * static_cast<int>(method_count) + 24);
    // Errors of exactly 0 (an image equal to the ground truth) have no place on a log axis: they
    // sit on a line of their own below it, labelled 0.
    for (const ResultRow* r : rows) {
        const double t = std::max(r->seconds, 1e-4), e = r->*error;
        f.tmin = std::min({f.tmin, t, std::max(r->seconds_min, 1e-4)});
        f.tmax = std::max({f.tmax, t, r->seconds_max});
        if (e > 0) {
            f.emin = std::min(f.emin, e);
            f.emax = std::max(f.emax, e);
        } else {
            f.zeros = true;
        }
    }
    if (f.tmax == 0) f.tmin = 0.1, f.tmax = 1;
    if (f.emax == 0) f.emin = 0.01, f.emax = 0.1;
    // A margin of 8% of the span (at least a tenth of a decade) on each side.
    auto pad = [](double& lo, double& hi) {
        double a = std::log10(lo), b = std::log10(hi);
        double m = std::max(0.1, 0.08 * (b - a));
        lo = std::pow(10, a - m);
        hi = std::pow(10, b + m);
    };
    pad(f.tmin, f.tmax);
    pad(f.emin, f.emax);
    f.zero_band = f.zeros ? 22 : 0;
    f.pw = PlotFrame::W - PlotFrame::L - PlotFrame::R;
    f.ph = f.H - T - PlotFrame::B - f.zero_band;
    f.lt0 = std::log10(f.tmin);
    f.lt1 = std::log10(f.tmax);
    f.le0 = std::log10(f.emin);
    f.le1 = std::log10(f.emax);
    return f;
}

// The plot's frame, the line of zeros, the ticks and grid lines of both axes, and their labels.
void plot_axes(std::ostream& s, const PlotFrame& f, const std::string& ylabel,
               const std::string& xlabel) {
    const int L = PlotFrame::L, T = PlotFrame::T;
    const double pw = f.pw, ph = f.ph;
    const int zero_band = f.zero_band;
    s << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << pw << "\" height=\""
      << ph + zero_band << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
    if (f.zeros)
        s << "<line x1=\"" << L << "\" x2=\"" << (L + pw) << "\" y1=\"" << (T + ph) << "\" y2=\""
          << (T + ph) << "\" stroke=\"#999\" stroke-dasharray=\"3 3\"/><text x=\"" << (L - 5)
          << "\" y=\"" << f.Y(0) + 4 << "\" font-size=\"11\" text-anchor=\"end\">0</text>\n";
    for (double v : log_ticks(f.tmin, f.tmax, pw / (f.lt1 - f.lt0), 44))
        s << "<line x1=\"" << f.X(v) << "\" x2=\"" << f.X(v) << "\" y1=\"" << T << "\" y2=\""
          << (T + ph + zero_band) << "\" stroke=\"#e4e4e4\"/><text x=\"" << f.X(v) << "\" y=\""
          << (T + ph + zero_band + 15) << "\" font-size=\"11\" text-anchor=\"middle\">"
          << tick_label(v) << "</text>\n";
    for (double v : log_ticks(f.emin, f.emax, ph / (f.le1 - f.le0), 14))
        s << "<line x1=\"" << L << "\" x2=\"" << (L + pw) << "\" y1=\"" << f.Y(v) << "\" y2=\""
          << f.Y(v) << "\" stroke=\"#e4e4e4\"/><text x=\"" << (L - 5) << "\" y=\"" << f.Y(v) + 4
          << "\" font-size=\"11\" text-anchor=\"end\">" << tick_label(v) << "</text>\n";
    s << "<text x=\"" << (L + pw / 2) << "\" y=\"" << (f.H - 8)
      << "\" font-size=\"12\" text-anchor=\"middle\">" << html_escape(xlabel) << "</text>\n";
    s << "<text x=\"13\" y=\"" << (T + ph / 2)
      << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 13 " << (T + ph / 2)
      << ")\">" << html_escape(ylabel) << "</text>\n";
}

// Method m's polyline across spp, its markers (with the range of the timed runs) and its entry in
// the legend.
void plot_method(std::ostream& s, const PlotFrame& f, const std::vector<const ResultRow*>& rows,
                 const std::string& method, std::size_t m, double ResultRow::*error) {
    const Style st = style_of(m);
    std::vector<const ResultRow*> pts;
    for (const ResultRow* r : rows)
        if (r->method == method) pts.push_back(r);
    std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return a->spp < b->spp; });
    s << "<polyline fill=\"none\" stroke=\"" << st.color << "\" stroke-width=\"1.6\"";
    if (*st.dash) s << " stroke-dasharray=\"" << st.dash << "\"";
    s << " points=\"";
    for (auto* p : pts) s << f.X(p->seconds) << "," << f.Y(p->*error) << " ";
    s << "\"/>\n";
    for (auto* p : pts) {
        if (p->timing_runs > 1)  // the range of the timed runs
            s << "<line x1=\"" << f.X(p->seconds_min) << "\" x2=\"" << f.X(p->seconds_max)
              << "\" y1=\"" << f.Y(p->*error) << "\" y2=\"" << f.Y(p->*error) << "\" stroke=\""
              << st.color << "\" stroke-width=\"1\"/>\n";
        s << marker_svg(st, f.X(p->seconds), f.Y(p->*error),
                        p->method + ", " + std::to_string(p->spp) + " spp: " +
                            fmt("%.5f", p->*error) + ", " + fmt("%.3f", p->seconds) + " s");
    }
    const double ly = PlotFrame::T + 9 + 18 * m, lx = PlotFrame::L + f.pw + 12;
    s << "<line x1=\"" << lx << "\" y1=\"" << ly << "\" x2=\"" << (lx + 26) << "\" y2=\"" << ly
      << "\" stroke=\"" << st.color << "\" stroke-width=\"1.6\"";
    if (*st.dash) s << " stroke-dasharray=\"" << st.dash << "\"";
    s << "/>" << marker_svg(st, lx + 13, ly, method) << "<text x=\"" << (lx + 32) << "\" y=\""
      << (ly + 4) << "\" font-size=\"11\">" << html_escape(method) << "</text>\n";
}

}  // namespace

// One log-log plot: y (an error) against render time, one polyline per method across spp.
std::string svg_plot(const std::vector<const ResultRow*>& rows,
                     const std::vector<std::string>& methods, double ResultRow::*error,
                     const std::string& ylabel, const std::string& xlabel,
                     const std::string& aria) {
    const PlotFrame f = plot_frame(rows, methods.size(), error);
    std::ostringstream s;
    s << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << PlotFrame::W
      << "\" height=\"" << f.H << "\" viewBox=\"0 0 " << PlotFrame::W << " " << f.H
      << "\" role=\"img\" aria-label=\"" << html_escape(aria)
      << "\" font-family=\"system-ui,sans-serif\">\n";
    plot_axes(s, f, ylabel, xlabel);
    for (std::size_t m = 0; m < methods.size(); ++m) plot_method(s, f, rows, methods[m], m, error);
    s << "</svg>\n";
    return s.str();
}

}  // namespace cmam::eval
