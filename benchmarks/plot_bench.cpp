// plot_bench: the tables and plots of docs/results.md from `vdmap bench` outputs (scripts/results.sh).
// Speed: the median over runs of each method's per-frame median, as a markdown table and a
// log-scale bar chart. Accuracy: a markdown table and RMSE against element count (log x).
// Tracking (`vdmap bench --poses track`): the odometry peers' table, median time over the runs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "mapping/core/timing.h"
#include "mapping/io/image_codec.h"

namespace {

using nlohmann::json;

json load(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file + ": cannot open");
  return json::parse(in);
}

const cv::Scalar kInk(40, 40, 40), kGrid(220, 220, 220), kVdmap(180, 110, 30), kPeer(60, 130, 230);

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, cv::Scalar c = kInk) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
}

struct Bar {
  std::string name;
  double value;
  bool vdmap;
};

struct Point {
  std::string name;
  double elements, rmse_mm;
  bool vdmap;
};

// Horizontal bars on a log10 axis from 0.1 to 10^4 (ms).
void barChart(const std::vector<Bar>& bars, const std::string& title, const std::string& file) {
  const int left = 250, right = 40, top = 50, row = 34, w = 900;
  const int h = top + row * static_cast<int>(bars.size()) + 50;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const double lo = -1, hi = 4;
  const auto x = [&](double v) {
    return left + static_cast<int>((std::log10(std::max(v, 0.1)) - lo) / (hi - lo) * (w - left - right));
  };
  for (int e = -1; e <= 4; ++e) {
    cv::line(img, {x(std::pow(10, e)), top - 10}, {x(std::pow(10, e)), h - 40}, kGrid);
    text(img, e < 0 ? "0.1" : std::to_string(static_cast<int>(std::pow(10, e))), {x(std::pow(10, e)) - 10, h - 20});
  }
  text(img, title, {10, 25}, 0.6);
  for (std::size_t i = 0; i < bars.size(); ++i) {
    const int y = top + row * static_cast<int>(i);
    cv::rectangle(img, {left, y}, {x(bars[i].value), y + row - 10}, bars[i].vdmap ? kVdmap : kPeer, cv::FILLED);
    text(img, bars[i].name, {10, y + row - 16});
    char v[32];
    std::snprintf(v, sizeof v, "%.2f", bars[i].value);
    text(img, v, {x(bars[i].value) + 5, y + row - 16});
  }
  vdmap::writeImageFile(file, img, vdmap::ChannelOrder::kBgr);
}

// RMSE (mm, linear y) against element count (log x).
void scatter(const std::vector<Point>& points, const std::string& title, const std::string& file) {
  const int w = 900, h = 560, left = 70, right = 40, top = 50, bottom = 60;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  double ymax = 1;
  for (const Point& p : points) ymax = std::max(ymax, p.rmse_mm);
  ymax = std::ceil(ymax / 5) * 5;
  const double lo = 3, hi = 7;  // 10^3 .. 10^7 elements
  const auto px = [&](double n) {
    return left + static_cast<int>((std::log10(std::max(n, 1.0)) - lo) / (hi - lo) * (w - left - right));
  };
  const auto py = [&](double r) { return h - bottom - static_cast<int>(r / ymax * (h - top - bottom)); };
  for (int e = 3; e <= 7; ++e) {
    cv::line(img, {px(std::pow(10, e)), top}, {px(std::pow(10, e)), h - bottom}, kGrid);
    text(img, "1e" + std::to_string(e), {px(std::pow(10, e)) - 12, h - bottom + 20});
  }
  for (int k = 0; k <= 5; ++k) {
    const double r = ymax * k / 5;
    cv::line(img, {left, py(r)}, {w - right, py(r)}, kGrid);
    text(img, std::to_string(static_cast<int>(r)), {left - 35, py(r) + 5});
  }
  text(img, title, {10, 25}, 0.6);
  text(img, "elements (log)", {w / 2 - 50, h - 15});
  text(img, "RMSE mm", {5, top - 10});
  for (std::size_t i = 0; i < points.size(); ++i) {
    const cv::Point p(px(points[i].elements), py(points[i].rmse_mm));
    cv::circle(img, p, 6, points[i].vdmap ? kVdmap : kPeer, cv::FILLED, cv::LINE_AA);
    text(img, points[i].name, p + cv::Point(9, (i % 2 ? 14 : -6)), 0.4);
  }
  vdmap::writeImageFile(file, img, vdmap::ChannelOrder::kBgr);
}

// The odometry table of `bench --poses track` runs: median over the runs of each peer's per-frame
// median; ATE, failures and keyframes from the first run (the peers are deterministic).
void trackingTable(const std::vector<json>& runs) {
  std::printf("| method | t [ms/frame], median of %zu runs | runs (min-max) | ATE RMSE [cm] | frames not registered | "
              "keyframes |\n|---|---:|---:|---:|---:|---:|\n",
              runs.size());
  for (const std::string& k : runs[0]["odometry_order"].get<std::vector<std::string>>()) {
    const json& m = runs[0]["odometry"][k];
    if (m.contains("note")) {
      std::printf("| %s | not run: %s |\n", m["name"].get<std::string>().c_str(), m["note"].get<std::string>().c_str());
      continue;
    }
    std::vector<double> ms;
    for (const json& r : runs) ms.push_back(r["odometry"][k]["ms_per_frame"].get<double>());
    std::printf("| %s | %.2f | %.2f-%.2f | %.2f | %d | %s |\n", m["name"].get<std::string>().c_str(), vdmap::median(ms),
                *std::min_element(ms.begin(), ms.end()), *std::max_element(ms.begin(), ms.end()),
                m["ate_rmse_m"].is_number() ? 100 * m["ate_rmse_m"].get<double>() : NAN, m["failures"].get<int>(),
                m.contains("keyframes") ? std::to_string(m["keyframes"].get<int>()).c_str() : "-");
  }
}

// The long run (`vdmap bench --long`, long.csv): per frame, stacked panels over the frame index:
// CPU time (each frame grey, the running median of 101 frames blue), resident memory, keyframes,
// and the global map's size where it was built.
void longRunPlot(const std::string& csv_file, const std::string& file) {
  std::ifstream in(csv_file);
  if (!in) throw std::runtime_error(csv_file + ": cannot open");
  std::string line;
  std::getline(in, line);  // header
  std::vector<double> cpu, rss, heap, keyframes, global_frame, global_size;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
    if (f.size() < 5) throw std::runtime_error(csv_file + ": a row has fewer than 5 columns: " + line);
    cpu.push_back(std::stod(f[1]));
    rss.push_back(std::stod(f[3]));
    keyframes.push_back(std::stod(f[4]));
    if (f.size() > 7) heap.push_back(std::stod(f[7]));
    if (f.size() > 5 && !f[5].empty())
      global_frame.push_back(static_cast<double>(cpu.size() - 1)), global_size.push_back(std::stod(f[5]));
  }
  if (cpu.empty()) throw std::runtime_error(csv_file + ": no frames");
  std::vector<double> running(cpu.size());
  for (std::size_t i = 0; i < cpu.size(); ++i) {
    const std::size_t a = i >= 50 ? i - 50 : 0, b = std::min(cpu.size(), i + 51);
    running[i] =
        vdmap::median(std::vector<double>(cpu.begin() + static_cast<long>(a), cpu.begin() + static_cast<long>(b)));
  }
  const int w = 1000, left = 80, right = 30, top = 70, panel = 150, gap = 40;
  const int h = top + 4 * (panel + gap) + 20;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const double frames = static_cast<double>(cpu.size());
  const auto px = [&](double frame) { return left + static_cast<int>(frame / frames * (w - left - right)); };
  text(img,
       "long run: " + std::to_string(cpu.size()) +
           " frames; CPU of the mapping thread (decoding and ORB run on the prefetch thread)",
       {10, 25}, 0.6);
  int y0 = top;
  // One panel: y from 0 to the largest value (of `clip` if given, so a few slow frames do not
  // flatten the rest), a dot or a line per series.
  auto axes = [&](const std::string& title, double ymax) {
    cv::rectangle(img, {left, y0}, {w - right, y0 + panel}, kGrid);
    for (int k = 0; k <= 2; ++k) {
      char v[32];
      std::snprintf(v, sizeof v, ymax * k / 2 >= 100 ? "%.0f" : "%.1f", ymax * k / 2);
      const int y = y0 + panel - panel * k / 2;
      cv::line(img, {left, y}, {w - right, y}, kGrid);
      text(img, v, {left - 60, y + 5}, 0.4);
    }
    text(img, title, {left + 5, y0 - 6}, 0.45);
  };
  auto py = [&](double v, double ymax) { return y0 + panel - static_cast<int>(std::min(v, ymax) / ymax * panel); };
  auto series = [&](const std::vector<double>& x, const std::vector<double>& v, double ymax, cv::Scalar c, bool dots) {
    for (std::size_t i = 0; i < v.size(); ++i) {
      const cv::Point p(px(x.empty() ? static_cast<double>(i) : x[i]), py(v[i], ymax));
      if (dots) cv::circle(img, p, 1, c, cv::FILLED);
      if (i > 0 && !dots)
        cv::line(img, {px(x.empty() ? static_cast<double>(i - 1) : x[i - 1]), py(v[i - 1], ymax)}, p, c, 2,
                 cv::LINE_AA);
    }
  };
  auto maxOf = [](const std::vector<double>& v) { return std::max(1e-9, *std::max_element(v.begin(), v.end())) * 1.1; };
  std::vector<double> sorted = cpu;
  std::sort(sorted.begin(), sorted.end());
  const double cpu_max = sorted[sorted.size() * 99 / 100] * 1.5;  // the 99th percentile sets the scale
  axes("mapping thread CPU ms per frame (grey: each frame, blue: running median of 101; the slowest 1% may be cut)",
       cpu_max);
  series({}, cpu, cpu_max, cv::Scalar(190, 190, 190), true);
  series({}, running, cpu_max, kVdmap, false);
  y0 += panel + gap;
  axes(heap.empty() ? "resident memory, MB" : "memory, MB (blue: resident, grey: live heap)", maxOf(rss));
  if (heap.size() == rss.size()) series({}, heap, maxOf(rss), cv::Scalar(150, 150, 150), false);
  series({}, rss, maxOf(rss), kVdmap, false);
  y0 += panel + gap;
  axes("keyframes", maxOf(keyframes));
  series({}, keyframes, maxOf(keyframes), kVdmap, false);
  y0 += panel + gap;
  if (!global_size.empty()) {
    axes("global map ellipsoids", maxOf(global_size));
    series(global_frame, global_size, maxOf(global_size), kVdmap, false);
    for (std::size_t i = 0; i < global_size.size(); ++i)
      cv::circle(img, {px(global_frame[i]), py(global_size[i], maxOf(global_size))}, 4, kVdmap, cv::FILLED,
                 cv::LINE_AA);
  }
  for (int k = 0; k <= 4; ++k)
    text(img, std::to_string(static_cast<int>(frames * k / 4)), {px(frames * k / 4) - 12, h - 8}, 0.4);
  vdmap::writeImageFile(file, img, vdmap::ChannelOrder::kBgr);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Tables and plots of vdmap bench outputs"};
  std::vector<std::string> speed, tracking;
  std::string accuracy, png_dir = ".", long_csv;
  auto* speed_option = app.add_option("--speed", speed, "bench.json of each speed run");
  app.add_option("--tracking", tracking, "bench.json of each `bench --poses track` run: the odometry peers' table");
  app.add_option("--accuracy", accuracy, "bench.json of the run with --mesh");
  app.add_option("--long", long_csv, "long.csv of `vdmap bench --long`: plots it into long.png instead")
      ->excludes(speed_option);
  app.add_option("--png-dir", png_dir, "where speed.png and accuracy.png (or long.png) go");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!long_csv.empty()) {
      longRunPlot(long_csv, png_dir + "/long.png");
      return 0;
    }
    if (!tracking.empty()) {
      std::vector<json> runs;
      for (const auto& f : tracking) runs.push_back(load(f));
      trackingTable(runs);
    }
    if (speed.empty()) {
      if (!tracking.empty()) return 0;
      throw std::runtime_error("--speed, --tracking or --long is required");
    }
    std::vector<json> runs;
    for (const auto& f : speed) runs.push_back(load(f));
    // Methods in the order of the first run; medians over the runs.
    std::vector<Bar> bars;
    std::printf(
        "| method | t_u [ms/frame], median of %zu runs | runs (min-max) | x vdmap update | elements |\n|---|---:|---:|---:|---:|\n",
        runs.size());
    double vd = 0;
    std::vector<std::string> order = runs[0]["method_order"];
    // Not timed: a peer that did not run (note) and the accuracy-only cell sizes (0 ms).
    std::erase_if(order, [&](const std::string& k) {
      const json& m = runs[0]["methods"][k];
      return m.contains("note") || !(m["ms_per_frame"].get<double>() > 0);
    });
    for (const std::string& k : order) {
      std::vector<double> ms;
      for (const json& r : runs) ms.push_back(r["methods"][k]["ms_per_frame"].get<double>());
      const double med = vdmap::median(ms);
      if (k == "vd_update") vd = med;
      const json& m = runs[0]["methods"][k];
      std::printf("| %s | %.2f | %.2f-%.2f | %.1f | %zu |\n", m["name"].get<std::string>().c_str(), med,
                  *std::min_element(ms.begin(), ms.end()), *std::max_element(ms.begin(), ms.end()),
                  vd > 0 ? med / vd : 0.0, m["elements"].get<std::size_t>());
      bars.push_back({m["name"].get<std::string>(), med, k.rfind("vd_", 0) == 0});
    }
    std::vector<double> tg;
    for (const json& r : runs) tg.push_back(r["t_g_us_per_ellipsoid"].get<double>());
    std::printf("\nt_g: median %.2f us per input ellipsoid (Sigma_e %zu -> Sigma_e' %zu in the first run)\n",
                vdmap::median(tg), runs[0]["sigma_e"].get<std::size_t>(), runs[0]["sigma_e_prime"].get<std::size_t>());
    barChart(bars,
             "update time per frame, ms (log scale), 7-Scenes RedKitchen, " +
                 std::to_string(runs[0]["frames"].get<int>()) + " frames, one thread",
             png_dir + "/speed.png");
    if (accuracy.empty()) return 0;
    const json a = load(accuracy);
    std::printf("\n| method | elements | RMSE [mm] | mean [mm] | median [mm] | completion [mm] | within 5 cm |\n"
                "|---|---:|---:|---:|---:|---:|---:|\n");
    // Rows: vdmap from the finest cell to the coarsest (most elements first), then the peers in
    // the speed table's order. The pipeline's map is vd_update's.
    std::vector<std::pair<std::string, json>> rows;
    for (const auto& [key, m] : a["methods"].items())
      if (m.contains("accuracy") && key.rfind("vd_", 0) == 0 && key != "vd_pipeline") rows.emplace_back(key, m);
    std::sort(rows.begin(), rows.end(), [](const auto& x, const auto& y) {
      return x.second["elements"].template get<std::size_t>() > y.second["elements"].template get<std::size_t>();
    });
    for (const std::string& k : a["method_order"].get<std::vector<std::string>>())
      if (k.rfind("vd_", 0) != 0 && a["methods"][k].contains("accuracy")) rows.emplace_back(k, a["methods"][k]);
    std::vector<Point> pts;
    for (const auto& [key, m] : rows) {
      const json& r = m["accuracy"];
      std::string name = m["name"].get<std::string>();
      if (key == "vd_update") name = "vdmap " + std::to_string(a["cell_size_px"].get<int>()) + " px";
      name = name.substr(0, name.find(" (accuracy only)"));
      std::printf("| %s | %zu | %.2f | %.2f | %.2f | %.1f | %.1f%% |\n", name.c_str(), r["elements"].get<std::size_t>(),
                  r["rmse_mm"].get<double>(), r["mean_mm"].get<double>(), r["median_mm"].get<double>(),
                  r["completion_mean_mm"].get<double>(), 100 * r["completion_ratio_5cm"].get<double>());
      pts.push_back({name, r["elements"].get<double>(), r["rmse_mm"].get<double>(), key.rfind("vd_", 0) == 0});
    }
    scatter(pts,
            "RMSE vs elements, noisy Replica office0 render (" + std::to_string(a["frames"].get<int>()) + " frames)",
            png_dir + "/accuracy.png");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plot_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
