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

#include "eval/error.h"
#include "eval/plot.h"

namespace cmam::eval {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFileList = "report-files.txt";

void write_atomic(const fs::path& path, const std::string& text) {
    std::string name(1, '.');
    name += path.filename().string();
    name += ".tmp";
    name += std::to_string(::getpid());
    const fs::path tmp = path.parent_path() / name;
    {
        std::ofstream out(tmp, std::ios::binary);
        out << text;
        out.flush();
        if (!out) throw EvalError("cannot write \"" + path.string() + "\"");
    }
    fs::rename(tmp, path);
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

namespace {

std::string timing_note(const EvalResult& r) {
    int lo = 1 << 30, hi = 0;
    for (const ResultRow& x : r.rows) {
        lo = std::min(lo, x.timing_runs);
        hi = std::max(hi, x.timing_runs);
    }
    if (hi <= 1)
        return "Times are single runs (cmam eval --timing-runs N gives the median of N): they "
               "vary from run to run, by up to 2x on a busy machine.";
    return "Times are the median of " + std::to_string(lo) +
           " runs, with their range (min-max) in the tables and as bars in the plots.";
}

// The files of an earlier report in `dir`: its list, or, for a report written before the list
// existed, what its results.csv names (images, heat maps) and each scene's reference image.
std::set<std::string> previous_files(const fs::path& dir) {
    std::set<std::string> out;
    std::ifstream list(dir / kFileList);
    std::string line;
    if (list) {
        while (std::getline(list, line))
            if (!line.empty()) out.insert(line);
        return out;
    }
    std::ifstream csv(dir / "results.csv");
    if (!csv) return out;
    std::getline(csv, line);  // the header says whether it is a results.csv of cmam eval
    if (line.rfind("scene,method,spp,rmse,psnr,ssim,rmse_masked,", 0) != 0) return out;
    while (std::getline(csv, line)) {
        std::vector<std::string> f;
        std::stringstream ss(line);
        std::string item;
        while (std::getline(ss, item, ',')) f.push_back(item);
        if (f.size() < 16) continue;
        for (const std::string& image : {f[14], f[15]})
            if (fs::path(image).extension() == ".png") out.insert(image);
        if (fs::path(f[14]).has_parent_path())
            out.insert(fs::path(f[14]).parent_path().string() + "/reference.png");
    }
    return out;
}

// Removes the files of the earlier report that this one did not write again, and the scene
// folders they leave empty. Only relative paths inside `dir` are touched.
void remove_stale(const fs::path& dir, const std::set<std::string>& old,
                  const std::set<std::string>& now) {
    for (const std::string& f : old) {
        fs::path rel(f);
        if (now.count(f) || rel.is_absolute() || f.find("..") != std::string::npos) continue;
        std::error_code ec;
        fs::remove(dir / rel, ec);
        if (rel.has_parent_path() && fs::is_empty(dir / rel.parent_path(), ec))
            fs::remove(dir / rel.parent_path(), ec);
    }
}

// The results table, one row per scene, method and sample count.
std::string results_csv(const EvalResult& r) {
    // CSV (columns are only ever added at the end)
    std::ostringstream csv;
    csv << "scene,method,spp,rmse,psnr,ssim,rmse_masked,psnr_masked,ssim_masked,masked_fraction,"
           "texture_rmse,"
           "texture_psnr,seconds,rays_per_second,image,heatmap,seconds_min,seconds_max,"
           "timing_runs,texture_heatmap\n";
    for (const ResultRow& x : r.rows)
        csv << x.scene << "," << x.method << "," << x.spp << "," << fmt("%.8g", x.rmse) << ","
            << fmt("%.6g", x.psnr) << "," << fmt("%.6g", x.ssim) << ","
            << fmt("%.8g", x.rmse_masked) << "," << fmt("%.6g", x.psnr_masked) << ","
            << fmt("%.6g", x.ssim_masked) << "," << fmt("%.4f", x.masked_fraction) << ","
            << fmt("%.8g", x.texture_rmse) << "," << fmt("%.6g", x.texture_psnr) << ","
            << fmt("%.6f", x.seconds) << "," << fmt("%.6g", x.rays_per_second) << "," << x.image
            << "," << x.heatmap << "," << fmt("%.6f", x.seconds_min) << ","
            << fmt("%.6f", x.seconds_max) << "," << x.timing_runs << "," << x.texture_heatmap
            << "\n";
    return csv.str();
}

// results.md: how the numbers were made, the table and the scenes that failed.
std::string results_md(const EvalOptions& o, const EvalResult& r) {
    std::ostringstream md;
    md << "# cmam evaluation\n\nGround truth: " << o.reference_spp
       << " stratified jittered samples per pixel, point-sampled textures (bilinear at level 0). "
          "Errors are in linear RGB; \"off edges\" keeps the pixels where an untextured render at "
          "the same "
          "spp agrees with the untextured ground truth; \"texture\" compares the unlit texture "
          "AOV. "
       << timing_note(r) << "\n\n"
       << results_markdown(r);
    for (const FailedScene& f : r.failed)
        md << "\nFailed, skipped: `" << f.path << "`: " << f.message << "\n";
    return md.str();
}

// The page's head, its style sheet and the introduction up to the note on timing.
constexpr const char* kHtmlHead = R"(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>cmam evaluation</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{font-family:system-ui,sans-serif;margin:24px;color:#222;background:#fff;max-width:1400px}
h1{margin-top:0} section.scene{margin-bottom:56px;border-top:2px solid #ddd;padding-top:8px}
.note{font-size:13px;color:#444;max-width:980px;line-height:1.45}
.facts{font-size:13px;margin:4px 0 10px;line-height:1.5}
.facts b{font-weight:600}
.failed{background:#fff0f0;border:1px solid #e0a0a0;padding:8px 12px;font-size:13px;max-width:980px}
.failed code{white-space:pre-wrap;word-break:break-all}
details.warnings{font-size:12px;margin:4px 0 10px;max-width:980px}
details.numbers{font-size:13px;margin:10px 0}
details.warnings li{word-break:break-all}
.chooser{font-size:13px;margin:6px 0 10px}
.chooser label{margin-right:14px;cursor:pointer}
.rows{display:grid;grid-template-columns:minmax(170px,210px) repeat(3,var(--img-w));gap:8px 10px;align-items:start}
.rows .head{font-size:12px;font-weight:600;color:#555;align-self:end}
.cap{font-size:12px;line-height:1.35;overflow-wrap:anywhere}
.cap b{font-size:13px}
.cap .num{font-variant-numeric:tabular-nums}
.zoom{overflow:hidden;border:1px solid #ccc;cursor:crosshair;line-height:0;width:var(--img-w)}
.zoom img{display:block;width:100%;height:auto;image-rendering:pixelated;transition:transform .05s}
.empty{width:var(--img-w)}
.plots{display:flex;flex-wrap:wrap;gap:16px;margin-top:14px}
.tablewrap{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:12px;margin-top:12px} td,th{border:1px solid #ddd;padding:3px 6px;text-align:right;white-space:nowrap}
th{background:#f3f3f3} td:first-child,th:first-child{text-align:left}
.ramp{display:inline-block;width:120px;height:10px;vertical-align:middle;border:1px solid #999;background:linear-gradient(to right,#000005,#57106e,#cc4033,#fcb31a,#fff)}
</style></head>
<body data-images-ok="" data-images-broken="" data-overlaps="" data-overflow-x="">
<h1>cmam evaluation</h1>
<p class="note">Each scene shows its ground truth (stratified jittered samples, textures point-sampled), then one row per method: the image, the error of the image and the error of the texture AOV (the unlit filtered texture of the first diffuse hit, which is what texture filtering changes; lighting noise is not in it). Heat maps show |luminance difference|: <span class="ramp"></span> from 0 (black) to the mean of the ground truth (white; of its texture AOV for the texture error). "Off edges" metrics keep only the pixels where an untextured render at the same sample count matches the untextured ground truth, so that geometric aliasing does not mask texture error. )";

// The page's scripts (sample-count chooser, synchronized zoom, layout self-check) and its end.
constexpr const char* kHtmlTail = R"(<script>
// The sample-count chooser: shows the rows of one sample count (or all).
document.querySelectorAll('section.scene').forEach(function (sec) {
  function show(v) {
    sec.querySelectorAll('[data-spp]').forEach(function (el) { el.style.display = (v === 'all' || el.dataset.spp === v) ? '' : 'none'; });
  }
  sec.querySelectorAll('.chooser input').forEach(function (inp) {
    inp.addEventListener('change', function () { show(inp.value); });
    if (inp.checked) show(inp.value);
  });
});
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
// Self-check of the layout, read by the report test: whether every image loaded, how many pairs
// of visible boxes (captions, images, plot labels, tables) overlap, and how far the page is wider
// than the window.
window.addEventListener('load', function () {
  var ok = 0, broken = 0;
  document.querySelectorAll('img').forEach(function (im) { if (im.complete && im.naturalWidth > 0) ok++; else broken++; });
  document.body.dataset.imagesOk = ok;
  document.body.dataset.imagesBroken = broken;
  var boxes = [];
  document.querySelectorAll('h1, h2, p, .facts, .chooser, .cap, .zoom, .head, svg.plot, svg text, .tablewrap, .failed, details').forEach(function (el) {
    var closed = el.parentElement && el.parentElement.closest('details:not([open])');
    if (closed && !el.closest('summary')) return;  // folded away
    var r = el.getBoundingClientRect();
    if (r.width > 0 && r.height > 0) boxes.push({el: el, r: r});
  });
  var overlaps = 0, first = '';
  for (var i = 0; i < boxes.length; i++)
    for (var j = i + 1; j < boxes.length; j++) {
      var a = boxes[i], b = boxes[j];
      if (a.el.contains(b.el) || b.el.contains(a.el)) continue;
      var w = Math.min(a.r.right, b.r.right) - Math.max(a.r.left, b.r.left);
      var h = Math.min(a.r.bottom, b.r.bottom) - Math.max(a.r.top, b.r.top);
      if (w > 0.5 && h > 0.5) { if (!overlaps) first = (a.el.textContent || a.el.tagName).slice(0, 40) + ' / ' + (b.el.textContent || b.el.tagName).slice(0, 40); overlaps++; }
    }
  // Text wider than its own box spills over its neighbours without moving them.
  boxes.forEach(function (b) {
    if (b.el instanceof HTMLElement && b.el.matches('.cap, .head, .facts') && b.el.scrollWidth > b.el.clientWidth + 1) {
      if (!overlaps) first = (b.el.textContent || '').slice(0, 40) + ' / (wider than its box)';
      overlaps++;
    }
  });
  document.body.dataset.overlaps = overlaps;
  document.body.dataset.firstOverlap = first;
  document.body.dataset.overflowX = Math.max(0, document.documentElement.scrollWidth - window.innerWidth);
});
</script>
</body></html>
)";

// The scenes that failed, if any.
void failed_html(std::ostream& h, const EvalResult& r) {
    if (r.failed.empty()) return;
    h << "<div class=\"failed\"><b>" << r.failed.size()
      << (r.failed.size() == 1 ? " scene" : " scenes") << " failed and "
      << (r.failed.size() == 1 ? "is" : "are") << " not in this report:</b><ul>\n";
    for (const FailedScene& f : r.failed)
        h << "<li><code>" << html_escape(f.path) << "</code>: <code>" << html_escape(f.message)
          << "</code></li>\n";
    h << "</ul></div>\n";
}

// Links to the scenes, when there is more than one.
void scene_links_html(std::ostream& h, const EvalResult& r) {
    if (r.scenes.size() <= 1) return;
    h << "<p class=\"facts\"><b>Scenes</b> ";
    for (std::size_t k = 0; k < r.scenes.size(); ++k)
        h << (k ? " &middot; " : "") << "<a href=\"#" << html_escape(r.scenes[k].name) << "\">"
          << html_escape(r.scenes[k].name) << "</a>";
    h << "</p>\n";
}

// The scene's file, size, ground truth and pixels off edges, and its warnings.
void scene_facts_html(std::ostream& h, const SceneReport& sc) {
    h << "<div class=\"facts\"><b>File</b> <code>" << html_escape(sc.path) << "</code> &middot; "
      << sc.width << "&times;" << sc.height << " pixels &middot; <b>ground truth</b> "
      << sc.reference_spp << " spp" << (sc.reference_cached ? " (from the cache)" : "")
      << " &middot; <b>pixels off edges</b> ";
    for (std::size_t k = 0; k < sc.off_edge_fraction.size(); ++k)
        h << (k ? ", " : "") << fmt("%.1f%%", 100 * sc.off_edge_fraction[k].second) << " at "
          << sc.off_edge_fraction[k].first << " spp";
    h << "</div>\n";
    if (!sc.warnings.empty()) {
        h << "<details class=\"warnings\"><summary>" << sc.warnings.size()
          << (sc.warnings.size() == 1 ? " warning" : " warnings")
          << " about this scene</summary><ul>\n";
        for (const std::string& w : sc.warnings) h << "<li>" << html_escape(w) << "</li>\n";
        h << "</ul></details>\n";
    }
}

// The scene's two plots: image and texture error against render time.
void scene_plots_html(std::ostream& h, const std::vector<const ResultRow*>& rows,
                      const std::vector<std::string>& methods, bool single) {
    const std::string time_axis =
        single ? "render time (s, log; single runs)" : "render time (s, log; median of runs)";
    h << "<div class=\"plots\">\n"
      << svg_plot(rows, methods, &ResultRow::rmse, "image RMSE vs ground truth (log)", time_axis,
                  "image error versus render time")
      << svg_plot(rows, methods, &ResultRow::texture_rmse, "texture AOV RMSE (log)", time_axis,
                  "texture error versus render time")
      << "</div>\n";
}

// Every number of the scene's rows, in a folded table.
void scene_numbers_html(std::ostream& h, const std::vector<const ResultRow*>& rows, bool single) {
    h << "<details class=\"numbers\"><summary>All numbers (" << rows.size()
      << (rows.size() == 1 ? " row" : " rows")
      << "; also in results.csv)</summary><div "
         "class=\"tablewrap\"><table><tr><th>method</th><th>spp</th><th>RMSE</th><th>"
         "PSNR</th><th>SSIM</th><th>RMSE off edges</th>"
         "<th>SSIM off edges</th><th>texture RMSE</th><th>time (s)"
      << (single ? ", single run" : ", median [min&ndash;max]") << "</th><th>Mrays/s</th></tr>\n";
    for (const ResultRow* x : rows) {
        std::string t = fmt("%.3f", x->seconds);
        if (x->timing_runs > 1)
            t += " [" + fmt("%.3f", x->seconds_min) + "&ndash;" + fmt("%.3f", x->seconds_max) + "]";
        h << "<tr><td>" << html_escape(x->method) << "</td><td>" << x->spp << "</td><td>"
          << fmt("%.5f", x->rmse) << "</td><td>" << fmt("%.2f", x->psnr) << "</td><td>"
          << fmt("%.4f", x->ssim) << "</td><td>" << fmt("%.5f", x->rmse_masked) << "</td><td>"
          << fmt("%.4f", x->ssim_masked) << "</td><td>" << fmt("%.5f", x->texture_rmse)
          << "</td><td>" << t << "</td><td>" << fmt("%.2f", x->rays_per_second / 1e6)
          << "</td></tr>\n";
    }
    h << "</table></div></details>\n";
}

// The radio buttons that show one sample count (or all), when there is more than one.
void spp_chooser_html(std::ostream& h, const SceneReport& sc, const std::set<int>& spps) {
    if (spps.size() <= 1) return;
    h << "<div class=\"chooser\">Samples per pixel: ";
    bool first = true;
    for (int spp : spps) {
        h << "<label><input type=\"radio\" name=\"spp-" << html_escape(sc.name) << "\" value=\""
          << spp << "\"" << (first ? " checked" : "") << "> " << spp << "</label>";
        first = false;
    }
    h << "<label><input type=\"radio\" name=\"spp-" << html_escape(sc.name)
      << "\" value=\"all\"> all</label></div>\n";
}

// The images side by side: the ground truth, then a row per sample count and method.
void scene_images_html(std::ostream& h, const SceneReport& sc,
                       const std::vector<const ResultRow*>& rows, const std::set<int>& spps,
                       const std::vector<std::string>& methods) {
    h << "<div class=\"rows\">\n<div class=\"head\"></div><div class=\"head\">image</div><div "
         "class=\"head\">image error</div><div class=\"head\">texture AOV error</div>\n";
    h << "<div class=\"cap\"><b>ground truth</b><br>" << sc.reference_spp
      << " spp; right: its texture AOV</div><div class=\"zoom\"><img src=\""
      << html_escape(sc.reference_image)
      << "\" alt=\"ground truth\"></div><div class=\"empty\"></div><div class=\"zoom\"><img "
         "src=\""
      << html_escape(sc.reference_texture) << "\" alt=\"ground truth texture AOV\"></div>\n";
    for (int spp : spps)
        for (const std::string& m : methods)
            for (const ResultRow* x : rows)
                if (x->method == m && x->spp == spp) {
                    const std::string cls = " data-spp=\"" + std::to_string(spp) + "\"";
                    h << "<div class=\"cap\"" << cls << "><b>" << html_escape(m) << "</b><br>"
                      << spp << " spp<br><span class=\"num\">RMSE " << fmt("%.4f", x->rmse)
                      << "<br>off edges " << fmt("%.4f", x->rmse_masked) << "<br>texture "
                      << fmt("%.4f", x->texture_rmse) << "<br>" << fmt("%.3f", x->seconds) << " s"
                      << (x->timing_runs > 1 ? " (median)" : " (single run)") << "</span></div>";
                    h << "<div class=\"zoom\"" << cls << "><img src=\"" << html_escape(x->image)
                      << "\" alt=\"" << html_escape(m) << "\"></div><div class=\"zoom\"" << cls
                      << "><img src=\"" << html_escape(x->heatmap) << "\" alt=\"image error of "
                      << html_escape(m) << "\"></div><div class=\"zoom\"" << cls << "><img src=\""
                      << html_escape(x->texture_heatmap) << "\" alt=\"texture error of "
                      << html_escape(m) << "\"></div>\n";
                }
    h << "</div>\n";
}

// One scene's section of the page.
void scene_html(std::ostream& h, const SceneReport& sc, const EvalResult& r,
                const std::vector<std::string>& methods, bool single) {
    std::vector<const ResultRow*> rows;
    std::set<int> spps;
    for (const ResultRow& x : r.rows)
        if (x.scene == sc.name) {
            rows.push_back(&x);
            spps.insert(x.spp);
        }
    // Every image of the scene at one width: up to 320 px for landscape images (less for
    // portrait ones), and narrower in a narrow window, so that a row always fits.
    const int img_w = sc.width >= sc.height ? 320 : std::max(140, 320 * sc.width / sc.height);
    h << "<section class=\"scene\" id=\"" << html_escape(sc.name) << "\" style=\"--img-w:min("
      << img_w << "px, calc((100vw - 300px) / 3))\">\n<h2>" << html_escape(sc.name) << "</h2>\n";
    scene_facts_html(h, sc);
    scene_plots_html(h, rows, methods, single);
    scene_numbers_html(h, rows, single);
    spp_chooser_html(h, sc, spps);
    scene_images_html(h, sc, rows, spps, methods);
    h << "</section>\n";
}

// index.html: the introduction, the failed scenes, a section per scene.
std::string index_html(const EvalOptions& o, const EvalResult& r) {
    std::vector<std::string> methods;
    for (const Method& m : o.methods) methods.push_back(m.name);
    const bool single = timing_note(r).rfind("Times are single", 0) == 0;
    std::ostringstream h;
    h << kHtmlHead << html_escape(timing_note(r))
      << R"( Move the mouse over an image to zoom all images of the scene at the same place; the wheel changes the zoom.</p>
)";
    failed_html(h, r);
    scene_links_html(h, r);
    for (const SceneReport& sc : r.scenes) scene_html(h, sc, r, methods, single);
    h << kHtmlTail;
    return h.str();
}

}  // namespace

void write_reports(const EvalOptions& o, const EvalResult& r) {
    const fs::path dir(o.out_dir);
    const std::set<std::string> old = previous_files(dir);
    write_atomic(dir / "results.csv", results_csv(r));
    write_atomic(dir / "results.md", results_md(o, r));
    write_atomic(dir / "index.html", index_html(o, r));

    // What this report owns, so that the next one into the same folder replaces it cleanly.
    std::set<std::string> now(r.files.begin(), r.files.end());
    for (const char* f : {"results.csv", "results.md", "index.html"}) now.insert(f);
    remove_stale(dir, old, now);
    std::ostringstream list;
    for (const std::string& f : now) list << f << "\n";
    write_atomic(dir / kFileList, list.str());
}

}  // namespace cmam::eval
