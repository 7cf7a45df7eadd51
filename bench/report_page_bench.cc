// How long report.html takes to open: each run starts a fresh headless Chromium (tests/e2e's driver),
// opens the page and reads when, after the navigation started, its script had built everything but
// the 3D view and everything (the page's own marks, dataset.shownMs and readyMs), and the renderer's
// counters (the DevTools Performance domain). Prints one line per run and the medians.
// Usage: report_page_bench RESULTS/report.html [--runs N]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/e2e/headless_chromium.h"

int main(int argc, char** argv) {
  std::string report_file;
  int runs = 5;
  CLI::App app{"report_page_bench: how long a results page takes to open in a fresh headless Chromium"};
  app.add_option("report", report_file, "a results folder's report.html")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--runs", runs, "fresh browsers, one page load each")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  const std::filesystem::path report = std::filesystem::absolute(report_file);
  std::printf("%s: %.2f MB\n", report.c_str(), double(std::filesystem::file_size(report)) / 1e6);
  std::printf("%-4s %10s %10s %12s %12s %12s\n", "run", "shown (s)", "ready (s)", "tasks (s)", "script (s)",
              "CPU (s)");
  std::vector<double> shown, ready;
  for (int run = 0; run < runs; ++run) {
    endorecon::testing::HeadlessChromium browser(1280, 900);
    browser.Call("Performance.enable");
    browser.Navigate("file://" + report.string());
    if (!browser.WaitFor("document.body.dataset.ready === 'true'", std::chrono::seconds(60))) {
      std::fprintf(stderr, "the page was not ready within 60 s\n");
      return 1;
    }
    const auto marks =
        browser.Evaluate("[Number(document.body.dataset.shownMs), Number(document.body.dataset.readyMs)]");
    shown.push_back(marks[0].get<double>() / 1000);
    ready.push_back(marks[1].get<double>() / 1000);
    double tasks = 0, script = 0, cpu = 0;
    const auto metrics = browser.Call("Performance.getMetrics");
    for (const auto& metric : metrics["metrics"]) {
      const std::string name = metric["name"];
      if (name == "TaskDuration") tasks = metric["value"];
      if (name == "ScriptDuration") script = metric["value"];
      if (name == "ProcessTime") cpu = metric["value"];
    }
    std::printf("%-4d %10.2f %10.2f %12.2f %12.2f %12.2f\n", run, shown.back(), ready.back(), tasks, script,
                cpu);
  }
  for (auto* times : {&shown, &ready}) std::sort(times->begin(), times->end());
  std::printf("median over %d runs: shown %.2f s, ready %.2f s\n", runs, shown[shown.size() / 2],
              ready[ready.size() / 2]);
  return 0;
}
