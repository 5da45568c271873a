#include "eval/report.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace cmam::eval {

namespace fs = std::filesystem;

namespace {

void write_atomic(const fs::path& path, const std::string& text) {
    fs::path tmp =
        path.parent_path() / ("." + path.filename().string() + ".tmp" + std::to_string(::getpid()));
    {
        std::ofstream out(tmp, std::ios::binary);
        out << text;
        out.flush();
        if (!out) throw std::runtime_error("cannot write \"" + path.string() + "\"");
    }
    fs::rename(tmp, path);
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string html_escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '<')
            o += "&lt;";
        else if (c == '>')
            o += "&gt;";
        else if (c == '&')
            o += "&amp;";
        else if (c == '"')
            o += "&quot;";
        else
            o += c;
    }
    return o;
}

const char* kColors[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02",
                         "#a6761d", "#666666", "#1f78b4", "#b2df8a", "#fb9a99", "#cab2d6"};

// Error (RMSE, log) against render time (log), one polyline per method across spp.
std::string svg_plot(const std::vector<const ResultRow*>& rows,
                     const std::vector<std::string>& methods) {
    const int W = 640, H = 360, L = 70, R = 190, T = 20, B = 50;
    double tmin = 1e30, tmax = 0, emin = 1e30, emax = 0;
    for (const ResultRow* r : rows) {
        tmin = std::min(tmin, std::max(r->seconds, 1e-4));
        tmax = std::max(tmax, std::max(r->seconds, 1e-4));
        emin = std::min(emin, std::max(r->rmse, 1e-6));
        emax = std::max(emax, std::max(r->rmse, 1e-6));
    }
    double lt0 = std::floor(std::log10(tmin) * 2) / 2,
           lt1 = std::ceil(std::log10(tmax) * 2) / 2 + 1e-9;
    double le0 = std::floor(std::log10(emin) * 4) / 4,
           le1 = std::ceil(std::log10(emax) * 4) / 4 + 1e-9;
    auto X = [&](double t) {
        return L + (std::log10(std::max(t, 1e-4)) - lt0) / (lt1 - lt0) * (W - L - R);
    };
    auto Y = [&](double e) {
        return H - B - (std::log10(std::max(e, 1e-6)) - le0) / (le1 - le0) * (H - T - B);
    };
    std::ostringstream s;
    s << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\""
      << H << "\" viewBox=\"0 0 " << W << " " << H
      << "\" role=\"img\" aria-label=\"error versus render time\">\n";
    s << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << (W - L - R) << "\" height=\""
      << (H - T - B) << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
    // Ticks at 1, 2 and 5 times the powers of ten inside the ranges.
    for (double d = std::floor(lt0); d <= lt1; d += 1)
        for (double k : {1.0, 2.0, 5.0}) {
            double v = k * std::pow(10, d);
            if (std::log10(v) < lt0 || std::log10(v) > lt1) continue;
            s << "<text x=\"" << X(v) << "\" y=\"" << (H - B + 16)
              << "\" font-size=\"11\" text-anchor=\"middle\">" << fmt("%g", v) << "</text>\n";
        }
    for (double d = std::floor(le0); d <= le1; d += 1)
        for (double k : {1.0, 2.0, 5.0}) {
            double v = k * std::pow(10, d);
            if (std::log10(v) < le0 || std::log10(v) > le1) continue;
            s << "<line x1=\"" << L << "\" x2=\"" << (W - R) << "\" y1=\"" << Y(v) << "\" y2=\""
              << Y(v) << "\" stroke=\"#e4e4e4\"/><text x=\"" << (L - 6) << "\" y=\"" << Y(v) + 4
              << "\" font-size=\"11\" text-anchor=\"end\">" << fmt("%g", v) << "</text>\n";
        }
    s << "<text x=\"" << (L + (W - L - R) / 2) << "\" y=\"" << (H - 12)
      << "\" font-size=\"12\" text-anchor=\"middle\">render time (s, log)</text>\n";
    s << "<text x=\"14\" y=\"" << (T + (H - T - B) / 2)
      << "\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 14 "
      << (T + (H - T - B) / 2) << ")\">RMSE vs ground truth (log)</text>\n";
    for (std::size_t m = 0; m < methods.size(); ++m) {
        const char* col = kColors[m % 12];
        std::vector<const ResultRow*> pts;
        for (const ResultRow* r : rows)
            if (r->method == methods[m]) pts.push_back(r);
        std::sort(pts.begin(), pts.end(), [](auto* a, auto* b) { return a->spp < b->spp; });
        s << "<polyline fill=\"none\" stroke=\"" << col << "\" stroke-width=\"2\" points=\"";
        for (auto* p : pts) s << X(p->seconds) << "," << Y(p->rmse) << " ";
        s << "\"/>\n";
        for (auto* p : pts)
            s << "<circle cx=\"" << X(p->seconds) << "\" cy=\"" << Y(p->rmse)
              << "\" r=\"3.5\" fill=\"" << col << "\"><title>" << html_escape(p->method) << ", "
              << p->spp << " spp: RMSE " << fmt("%.5f", p->rmse) << ", " << fmt("%.3f", p->seconds)
              << " s</title></circle>\n";
        double ly = T + 10 + 16 * m;
        s << "<line x1=\"" << (W - R + 12) << "\" y1=\"" << ly << "\" x2=\"" << (W - R + 30)
          << "\" y2=\"" << ly << "\" stroke=\"" << col << "\" stroke-width=\"2\"/><text x=\""
          << (W - R + 34) << "\" y=\"" << (ly + 4) << "\" font-size=\"11\">"
          << html_escape(methods[m]) << "</text>\n";
    }
    s << "</svg>\n";
    return s.str();
}

}  // namespace

std::string results_markdown(const EvalResult& r) {
    std::ostringstream s;
    s << "| scene | method | spp | RMSE | PSNR (dB) | SSIM | RMSE off edges | texture RMSE | time "
         "(s) | Mrays/s |\n";
    s << "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const ResultRow& row : r.rows)
        s << "| " << row.scene << " | " << row.method << " | " << row.spp << " | "
          << fmt("%.5f", row.rmse) << " | " << fmt("%.2f", row.psnr) << " | "
          << fmt("%.4f", row.ssim) << " | " << fmt("%.5f", row.rmse_masked) << " | "
          << fmt("%.5f", row.texture_rmse) << " | " << fmt("%.3f", row.seconds) << " | "
          << fmt("%.2f", row.rays_per_second / 1e6) << " |\n";
    return s.str();
}

void write_reports(const EvalOptions& o, const EvalResult& r) {
    const fs::path dir(o.out_dir);
    // CSV
    std::ostringstream csv;
    csv << "scene,method,spp,rmse,psnr,ssim,rmse_masked,psnr_masked,ssim_masked,masked_fraction,"
           "texture_rmse,"
           "texture_psnr,seconds,rays_per_second,image,heatmap\n";
    for (const ResultRow& x : r.rows)
        csv << x.scene << "," << x.method << "," << x.spp << "," << fmt("%.8g", x.rmse) << ","
            << fmt("%.6g", x.psnr) << "," << fmt("%.6g", x.ssim) << ","
            << fmt("%.8g", x.rmse_masked) << "," << fmt("%.6g", x.psnr_masked) << ","
            << fmt("%.6g", x.ssim_masked) << "," << fmt("%.4f", x.masked_fraction) << ","
            << fmt("%.8g", x.texture_rmse) << "," << fmt("%.6g", x.texture_psnr) << ","
            << fmt("%.6f", x.seconds) << "," << fmt("%.6g", x.rays_per_second) << "," << x.image
            << "," << x.heatmap << "\n";
    write_atomic(dir / "results.csv", csv.str());

    std::ostringstream md;
    md << "# cmam evaluation\n\nGround truth: " << o.reference_spp
       << " stratified jittered samples per pixel, point-sampled textures (bilinear at level 0). "
          "Errors are in linear RGB; \"off edges\" keeps the pixels where an untextured render at "
          "the same "
          "spp agrees with the untextured ground truth; \"texture\" compares the unlit texture "
          "AOV.\n\n"
       << results_markdown(r);
    write_atomic(dir / "results.md", md.str());

    std::vector<std::string> methods;
    for (const Method& m : o.methods) methods.push_back(m.name);
    std::ostringstream h;
    h << R"(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>cmam evaluation</title>
<style>
body{font-family:system-ui,sans-serif;margin:24px;color:#222;background:#fff}
h1{margin-top:0} section{margin-bottom:48px}
.grid{display:grid;gap:10px;align-items:start}
figure{margin:0} figcaption{font-size:12px;margin:2px 0 6px}
.zoom{overflow:hidden;border:1px solid #ccc;cursor:crosshair;line-height:0}
.zoom img{display:block;width:100%;image-rendering:pixelated;transition:transform .05s}
table{border-collapse:collapse;font-size:12px;margin-top:12px} td,th{border:1px solid #ddd;padding:3px 6px;text-align:right}
th{background:#f3f3f3} td:first-child,td:nth-child(2){text-align:left}
.note{font-size:13px;color:#555;max-width:900px}
</style></head>
<body data-images-ok="" data-images-broken="">
<h1>cmam evaluation</h1>
<p class="note">Ground truth: )"
      << o.reference_spp
      << R"( stratified jittered samples per pixel with point-sampled textures. Each row shows one sample count: the ground truth, then every method, with its error heat map (|luminance difference|, black = 0, white = the ground truth's mean) below. Move the mouse over any image to zoom all images of the scene at the same place; the wheel changes the zoom.</p>
)";
    for (const SceneReport& sc : r.scenes) {
        std::vector<const ResultRow*> rows;
        std::set<int> spps;
        for (const ResultRow& x : r.rows)
            if (x.scene == sc.name) {
                rows.push_back(&x);
                spps.insert(x.spp);
            }
        h << "<section class=\"scene\" id=\"" << html_escape(sc.name) << "\">\n<h2>"
          << html_escape(sc.name) << "</h2>\n";
        h << "<div class=\"grid\" style=\"grid-template-columns:repeat(" << (methods.size() + 1)
          << ",minmax(120px,1fr))\">\n";
        for (int spp : spps) {
            h << "<figure><figcaption><b>ground truth</b></figcaption><div class=\"zoom\"><img "
                 "src=\""
              << html_escape(sc.reference_image) << "\" alt=\"ground truth\"></div></figure>\n";
            for (const std::string& m : methods)
                for (const ResultRow* x : rows)
                    if (x->method == m && x->spp == spp)
                        h << "<figure><figcaption><b>" << html_escape(m) << "</b>, " << spp
                          << " spp, RMSE " << fmt("%.4f", x->rmse)
                          << "</figcaption><div class=\"zoom\"><img src=\"" << html_escape(x->image)
                          << "\" alt=\"" << html_escape(m)
                          << "\"></div><div class=\"zoom\"><img src=\"" << html_escape(x->heatmap)
                          << "\" alt=\"error of " << html_escape(m) << "\"></div></figure>\n";
        }
        h << "</div>\n" << svg_plot(rows, methods);
        h << "<table><tr><th>method</th><th>spp</th><th>RMSE</th><th>PSNR</th><th>SSIM</"
             "th><th>RMSE off edges</th>"
             "<th>SSIM off edges</th><th>texture RMSE</th><th>time (s)</th><th>Mrays/s</th></tr>\n";
        for (const ResultRow* x : rows)
            h << "<tr><td>" << html_escape(x->method) << "</td><td>" << x->spp << "</td><td>"
              << fmt("%.5f", x->rmse) << "</td><td>" << fmt("%.2f", x->psnr) << "</td><td>"
              << fmt("%.4f", x->ssim) << "</td><td>" << fmt("%.5f", x->rmse_masked) << "</td><td>"
              << fmt("%.4f", x->ssim_masked) << "</td><td>" << fmt("%.5f", x->texture_rmse)
              << "</td><td>" << fmt("%.3f", x->seconds) << "</td><td>"
              << fmt("%.2f", x->rays_per_second / 1e6) << "</td></tr>\n";
        h << "</table>\n</section>\n";
    }
    h << R"(<script>
// Synchronized zoom: the same point of every image of a scene, magnified.
document.querySelectorAll('section.scene').forEach(function (sec) {
  var zoom = 4;
  var imgs = sec.querySelectorAll('.zoom img');
  function apply(fx, fy, z) {
    imgs.forEach(function (im) { im.style.transformOrigin = (fx * 100) + '% ' + (fy * 100) + '%'; im.style.transform = 'scale(' + z + ')'; });
  }
  sec.querySelectorAll('.zoom').forEach(function (box) {
    box.addEventListener('mousemove', function (e) { var r = box.getBoundingClientRect(); apply((e.clientX - r.left) / r.width, (e.clientY - r.top) / r.height, zoom); });
    box.addEventListener('mouseleave', function () { apply(0.5, 0.5, 1); });
    box.addEventListener('wheel', function (e) { e.preventDefault(); zoom = Math.min(32, Math.max(1, zoom * (e.deltaY < 0 ? 1.25 : 0.8))); var r = box.getBoundingClientRect(); apply((e.clientX - r.left) / r.width, (e.clientY - r.top) / r.height, zoom); }, {passive: false});
  });
});
// Record whether every image loaded (read by the report test).
window.addEventListener('load', function () {
  var ok = 0, broken = 0;
  document.querySelectorAll('img').forEach(function (im) { if (im.complete && im.naturalWidth > 0) ok++; else broken++; });
  document.body.dataset.imagesOk = ok;
  document.body.dataset.imagesBroken = broken;
});
</script>
</body></html>
)";
    write_atomic(dir / "index.html", h.str());
}

}  // namespace cmam::eval
