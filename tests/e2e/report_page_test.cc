// report.html in a real browser (headless Chromium over the DevTools protocol): a page of a short
// reconstruction of a synthetic clip like the demo's loads with no console error, failed load or network
// request; the slider changes the shown frame; the 3D view draws the surface and turns when dragged; every
// number on the page is the one in metrics.json (or config.json). And `endorecon-worker render` writes a page
// of its views. Skipped with one line where Chromium cannot start.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/json_file.h"
#include "tests/e2e/headless_chromium.h"
#include "tests/unit/report_data.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/eval/report.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using testing::HeadlessChromium;
using Clock = std::chrono::steady_clock;

std::unique_ptr<HeadlessChromium> StartChromium(std::string& why) {
  try {
    return std::make_unique<HeadlessChromium>(1280, 900);
  } catch (const std::exception& e) {
    why = e.what();
    return nullptr;
  }
}

cv::Mat DecodeImage(const std::string& bytes) {
  return cv::imdecode(cv::Mat(1, int(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data())),
                      cv::IMREAD_COLOR);
}

// The fraction of pixels farther than a few levels from `bgr` in any channel.
double FractionUnlike(const cv::Mat& image, cv::Vec3b bgr) {
  int count = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const auto pixel = image.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) {
        if (std::abs(int(pixel[c]) - int(bgr[c])) > 6) {
          ++count;
          break;
        }
      }
    }
  }
  return double(count) / double(image.total());
}

double FractionChanged(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat difference, grey;
  cv::absdiff(a, b, difference);
  cv::cvtColor(difference, grey, cv::COLOR_BGR2GRAY);
  return double(cv::countNonZero(grey > 6)) / double(grey.total());
}

// Evaluation settings that make a short reconstruction cheap: few samples, two dropout passes, a
// coarse occupancy grid, no depth refinement, a curve point every quarter second of training.
constexpr const char* kQuickConfig =
    R"({"rays_per_batch": 512, "depth_refine_every": 0, "occupancy_resolution": 16, "eval_coarse_samples": 16,
        "eval_fine_samples": 16, "mc_passes": 2, "curve_interval_s": 0.25, "curve_frames": 1})";

// A synthetic clip like the demo's (tool, depth, ground truth; fewer and smaller frames, so the test
// takes seconds), reconstructed briefly: a results folder with every part the page shows.
fs::path ReconstructSmallClip(const testing::TempDir& dir, int frames, int iterations) {
  scene::SynthOptions synth;
  synth.frames = frames;
  synth.width = 80;
  synth.height = 64;
  scene::WriteSyntheticClip(synth, dir / "clip");
  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "out").string();
  options.config = nlohmann::json::parse(kQuickConfig);
  options.iterations = iterations;
  Reconstruct(options, {});
  return dir / "out";
}

// Every element showing a number of metrics.json (data-metric) or config.json (data-config) against
// the file: the text is the value times data-factor, to data-digits decimals or data-precision
// significant digits; a null metric shows a dash. Returns how many were checked.
int CheckNumbers(HeadlessChromium& browser, const nlohmann::json& metrics, const nlohmann::json& config) {
  const auto shown = browser.Evaluate(R"(
    [...document.querySelectorAll('[data-metric],[data-config]')].map((e) => ({
      metric: e.dataset.metric || null, config: e.dataset.config || null, text: e.textContent,
      digits: e.dataset.digits ? Number(e.dataset.digits) : null,
      precision: e.dataset.precision ? Number(e.dataset.precision) : null,
      factor: e.dataset.factor ? Number(e.dataset.factor) : 1 })))");
  int checked = 0;
  for (const auto& item : shown) {
    const bool is_metric = !item["metric"].is_null();
    const std::string pointer = is_metric ? item["metric"] : item["config"];
    const auto& source = is_metric ? metrics : config;
    const nlohmann::json::json_pointer where(pointer);
    const std::string text = item["text"];
    if (!source.contains(where)) {
      ADD_FAILURE() << pointer << " is shown (" << text << ") but is not in "
                    << (is_metric ? "metrics" : "config") << ".json";
      continue;
    }
    const auto& value = source.at(where);
    ++checked;
    if (value.is_null()) {
      EXPECT_EQ(text, "\u2014") << pointer;
      continue;
    }
    const double expected = value.get<double>() * item["factor"].get<double>();
    double tolerance = 1e-12 * std::abs(expected);
    if (!item["digits"].is_null())
      tolerance += 0.5 * std::pow(10.0, -item["digits"].get<double>()) * (1 + 1e-9);
    if (!item["precision"].is_null()) {
      tolerance +=
          0.5 * std::abs(expected) * std::pow(10.0, 1 - item["precision"].get<double>()) * (1 + 1e-9);
    }
    EXPECT_NEAR(std::stod(text), expected, tolerance) << pointer << " shows " << text;
  }
  return checked;
}

TEST(ReportPageTest, APageWorksInHeadlessChromium) {
  std::string why;
  auto browser = StartChromium(why);
  if (!browser)
    GTEST_SKIP() << "Chromium cannot start here, so report.html is not checked in a browser: " << why;
  testing::TempDir dir("report-page");
  constexpr int kFrames = 16;
  const fs::path out = ReconstructSmallClip(dir, kFrames, 40);
  const fs::path report = out / "report.html";
  ASSERT_TRUE(fs::exists(report));
  const double megabytes = double(fs::file_size(report)) / 1e6;
  const auto metrics = ReadJsonFile(out / "metrics.json");
  const auto config = ReadJsonFile(out / "config.json");

  const auto start = Clock::now();
  browser->Navigate("file://" + report.string());
  ASSERT_TRUE(browser->WaitFor("document.body.dataset.ready === 'true'", std::chrono::seconds(20)));
  const double load_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("report.html of %d frames: %.1f MB, ready %.2f s after navigation\n", kFrames, megabytes,
              load_seconds);

  // The slider: a key press moves one frame; a new value shows that frame (a held-out one, marked).
  const auto shown = [&] {
    return browser->Evaluate(
        "[document.getElementById('frame-label').dataset.frame, "
        "document.querySelector('img[data-layer=rendered]').src, "
        "document.getElementById('frame-label').textContent]");
  };
  const auto first = shown();
  EXPECT_EQ(first[0], "0");
  // Sparsification plots: the paper's map against the observed error, and both maps against the
  // synthetic clip's noise-free truth, for the held-out and the training frames.
  EXPECT_EQ(browser->Evaluate("Array.from(document.querySelectorAll('#calibration figure svg'), s => "
                              "s.querySelector('text').textContent).join('|')"),
            "Sparsification, held-out frames|Sparsification, training frames|"
            "Sparsification of the noise-free error, held-out frames|"
            "Sparsification of the noise-free error, training frames");
  // What the clip did not need, and what a measurement kept (the deformation of a moving clip).
  const std::string reasons =
      browser->Evaluate("Array.from(document.querySelectorAll('#left-out th'), h => h.textContent).join('|')")
          .get<std::string>();
  EXPECT_NE(reasons.find("left out|why"), std::string::npos) << reasons;
  EXPECT_NE(reasons.find("kept, as measured|why"), std::string::npos) << reasons;
  // Every layer a reconstruction has is a panel: the model map's heat map beside the paper's map.
  EXPECT_EQ(browser->Evaluate("Array.from(document.querySelectorAll('#panels img[data-layer]'), i => "
                              "i.dataset.layer).filter(l => l !== 'tool').join()"),
            "input,rendered,depth,uncertainty,model,error");
  browser->Evaluate("document.getElementById('frame-slider').focus()");
  browser->PressKey("ArrowRight", 39);
  const auto next = shown();
  EXPECT_EQ(next[0], "1");
  EXPECT_NE(next[1], first[1]) << "the rendered image did not change";
  const int heldout = metrics["heldout"]["frames"][1];
  browser->Evaluate(
      fmt::format("(() => {{ const s = document.getElementById('frame-slider'); s.value = '{}'; "
                  "s.dispatchEvent(new Event('input')); }})()",
                  heldout));
  const auto jumped = shown();
  EXPECT_EQ(jumped[0], std::to_string(heldout));
  EXPECT_NE(jumped[2].get<std::string>().find("held out"), std::string::npos) << jumped[2];
  const std::string uri = jumped[1];
  const cv::Mat page_image = DecodeImage(testing::DecodeBase64(uri.substr(uri.find(",") + 1)));
  const cv::Mat file_image = cv::imread((out / "rgb" / eval::FrameFileName(heldout, ".png")).string());
  ASSERT_EQ(page_image.size(), file_image.size());
  EXPECT_LT(cv::norm(page_image, file_image, cv::NORM_L1) / double(file_image.total() * 3), 3.0)
      << "the page shows frame " << heldout << "'s rendering";
  browser->Evaluate("document.getElementById('play').click()");
  EXPECT_TRUE(
      browser->WaitFor(fmt::format("document.getElementById('frame-label').dataset.frame !== '{}'", heldout),
                       std::chrono::seconds(3)))
      << "play advances the frames";
  EXPECT_EQ(browser->Evaluate("document.getElementById('play').getAttribute('aria-label')"), "pause");
  browser->Evaluate("document.getElementById('play').click()");
  EXPECT_EQ(browser->Evaluate("document.getElementById('play').getAttribute('aria-label')"), "play");
  // A row of the per-frame table is reached with the keyboard and shows its frame on Enter.
  browser->Evaluate("document.querySelector('#per-frame-table tr[data-frame=\"3\"]').focus()");
  browser->PressKey("Enter", 13);
  EXPECT_EQ(shown()[0], "3") << "Enter on a focused row shows its frame";
  // Which frames were rendered reduced, in the table and above it, as metrics.json says.
  const auto reduced = metrics["evaluation"].value("reduced_frames", nlohmann::json::array());
  EXPECT_EQ(browser->Evaluate("document.querySelectorAll('#per-frame-table td').length > 0 && "
                              "Array.from(document.querySelectorAll('#per-frame-table tr[data-frame]'))"
                              ".filter(r => Array.from(r.cells).some(c => c.textContent === 'reduced')).length"),
            reduced.size());
  EXPECT_EQ(browser->Evaluate("document.getElementById('warnings').textContent.includes('rendered reduced')"),
            !reduced.empty());
  // Printed, the per-frame table shows every row (on screen it scrolls in a box).
  browser->Evaluate("window.dispatchEvent(new Event('beforeprint'))");
  EXPECT_EQ(browser->Evaluate("document.querySelector('#run-section details').open"), true);
  EXPECT_NE(browser->Evaluate("document.querySelector('footer').textContent").get<std::string>().find(
                "not a medical device"),
            std::string::npos);

  // The 3D view draws the surface, and dragging turns it.
  const auto box = browser->Evaluate(
      "(() => { const c = document.getElementById('surface'); c.scrollIntoView({block: 'center'});"
      " const r = c.getBoundingClientRect(); return [r.left, r.top, r.width, r.height, window.scrollX, "
      "window.scrollY]; })()");
  const double left = box[0], top = box[1], width = box[2], height = box[3];
  const auto canvas = [&] {
    return DecodeImage(
        browser->Screenshot(left + box[4].get<double>(), top + box[5].get<double>(), width, height));
  };
  const cv::Mat before = canvas();
  const double drawn = FractionUnlike(before, cv::Vec3b(26, 19, 16));
  EXPECT_GT(drawn, 0.05) << "the 3D canvas shows (almost) only its background";
  browser->Drag(left + width / 2, top + height / 2, left + width / 2 + 160, top + height / 2 + 40, 8);
  const cv::Mat turned = canvas();
  EXPECT_GT(FractionChanged(before, turned), 0.02) << "dragging did not turn the surface";
  browser->Evaluate(
      "(() => { const s = document.getElementById('surface-colour'); s.value = 'uncertainty';"
      " s.dispatchEvent(new Event('change')); })()");
  const cv::Mat uncertain = canvas();
  EXPECT_GT(FractionChanged(turned, uncertain), 0.02) << "the uncertainty colouring looks like the colour";
  browser->Evaluate(
      "(() => { const s = document.getElementById('surface-colour'); s.value = 'model';"
      " s.dispatchEvent(new Event('change')); })()");
  EXPECT_GT(FractionChanged(uncertain, canvas()), 0.02)
      << "the model map's colouring looks like the uncertainty's";
  EXPECT_EQ(browser->Evaluate("document.querySelector('#surface-scale .hint').textContent"),
            "model map colouring");

  const int checked = CheckNumbers(*browser, metrics, config);
  EXPECT_GE(checked, kFrames * 9) << "the per-frame table shows nine metrics of every frame";
  for (const char* pointer : {"/heldout/image/psnr_tissue/mean", "/heldout/calibration/spearman/mean",
                              "/heldout/calibration/ause/mean", "/heldout/depth/rmse/mean", "/iterations",
                              "/time/total_s", "/time/evaluation_s"}) {
    EXPECT_EQ(browser->Evaluate(
                  fmt::format("document.querySelectorAll('[data-metric=\"{}\"]').length", pointer)) > 0,
              true)
        << pointer << " is not shown";
  }
  EXPECT_TRUE(browser->problems().empty()) << fmt::format("{}", fmt::join(browser->problems(), "\n"));

  // A picture of the page to look at after a run (docs/report.png is the demo clip's, docs/benchmarks.md).
  browser->Evaluate(
      "(() => { const s = document.getElementById('surface-colour'); s.value = 'rgb';"
      " s.dispatchEvent(new Event('change')); window.scrollTo(0, 0); })()");
  testing::WriteBytes(fs::path(ENDORECON_BINARY_DIR) / "report_page.png", browser->Screenshot());

  // The run's warnings (metrics.json "warnings") are above the numbers, each a sentence.
  nlohmann::json warned = metrics;
  warned["warnings"].push_back("the canonical frame shows no tissue surface: mesh.ply holds no triangle");
  testing::WriteBytes(out / "metrics.json", warned.dump());
  eval::WriteReport(out);
  browser->Navigate("file://" + report.string());
  ASSERT_TRUE(browser->WaitFor("document.body.dataset.ready === 'true'", std::chrono::seconds(20)));
  EXPECT_EQ(browser->Evaluate("document.getElementById('warnings').textContent.includes('The canonical frame "
                              "shows no tissue surface: mesh.ply holds no triangle.')"),
            true);
}

TEST(ReportPageTest, RenderWritesAPageOfItsViews) {
  testing::TempDir dir("report-render");
  ReconstructSmallClip(dir, 6, 10);
  // Three views: the clip's camera (identity pose, f = 0.8898 W) at the start, moved sideways at the
  // end, and turned away from the tissue.
  testing::WriteBytes(dir / "cameras.json", R"({"w": 80, "h": 64, "fl_x": 71.18, "frames": [
      {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 0.0},
      {"transform_matrix": [[1,0,0,2],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 1.0},
      {"transform_matrix": [[-1,0,0,0],[0,1,0,0],[0,0,-1,0],[0,0,0,1]], "time": 0.5}]})");
  const std::string command = fmt::format(
      "{}/worker/runtime/endorecon-worker render {} --cameras {} -o {} --mc-passes 2 "
      "> {} 2>&1",
      ENDORECON_BINARY_DIR, (dir / "out").string(), (dir / "cameras.json").string(), (dir / "views").string(),
      (dir / "render.log").string());
  ASSERT_EQ(std::system(command.c_str()), 0) << testing::ReadBytes(dir / "render.log");
  const auto data = testing::ReportData(dir / "views" / "report.html");
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["kind"], "render");
  EXPECT_EQ(data["render"], ReadJsonFile(dir / "views" / "render.json"));
  EXPECT_EQ(data["frames"]["count"], 3);
  EXPECT_EQ(data["frames"]["sizes_vary"], false) << "every view 80 x 64";
  EXPECT_EQ(data["frames"]["times"], nlohmann::json::array({0.0, 1.0, 0.5}));
  EXPECT_TRUE(data["frames"]["input"].is_null()) << "rendered views have no input images";
  EXPECT_EQ(data["frames"]["uncertainty"].size(), 3u);
  EXPECT_EQ(data["frames"]["model"].size(), 3u);
  EXPECT_EQ(data["surface"]["frames"].size(), 3u);
  // The score's scale is shown divided by lambda (1e12 by default): as the colour's variance.
  EXPECT_DOUBLE_EQ(data["scales"]["uncertainty"]["factor"].get<double>(),
                   1.0 / data["render"]["lambda"].get<double>());
  // The page names where the views came from and the device.
  EXPECT_EQ(data["clip"], fs::absolute(dir / "out").lexically_normal().string());
  EXPECT_EQ(data["run"]["device"].get<std::string>().rfind("CPU, ", 0), 0u) << data["run"]["device"];
  // A view that sees no surface is said (it was written blank without a word), the others not.
  const std::string log = testing::ReadBytes(dir / "render.log");
  EXPECT_NE(log.find("view 2 sees no surface of the scene"), std::string::npos) << log;
  EXPECT_EQ(log.find("view 0 sees no surface"), std::string::npos) << log;
  // A view that sees no surface has grey heat maps, as its depth is grey (they were black: "certain").
  for (const char* map : {"000002.png", "000002_model.png"}) {
    const cv::Mat away = cv::imread((dir / "views" / "uncertainty" / map).string());
    ASSERT_FALSE(away.empty()) << map;
    EXPECT_LT(FractionUnlike(away, cv::Vec3b(128, 128, 128)), 0.01) << map;
  }
  // Views of two sizes: the page names no one size for all (it named the first's).
  testing::WriteBytes(dir / "mixed.json", R"({"fl_x": 71.18, "frames": [
      {"w": 80, "h": 64, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 0.0},
      {"w": 40, "h": 32, "fl_x": 35.59, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],
       "time": 1.0}]})");
  const std::string mixed =
      fmt::format("{}/worker/runtime/endorecon-worker render {} --cameras {} -o {} --mc-passes 0 > {} 2>&1",
                  ENDORECON_BINARY_DIR, (dir / "out").string(), (dir / "mixed.json").string(),
                  (dir / "mixed").string(), (dir / "mixed.log").string());
  ASSERT_EQ(std::system(mixed.c_str()), 0) << testing::ReadBytes(dir / "mixed.log");
  EXPECT_EQ(testing::ReportData(dir / "mixed" / "report.html")["frames"]["sizes_vary"], true);
  EXPECT_FALSE(fs::exists(dir / "mixed" / "uncertainty")) << "no dropout passes, no uncertainty maps";

  std::string why;
  auto browser = StartChromium(why);
  if (!browser)
    GTEST_SKIP() << "Chromium cannot start here, so the views' page is not opened in a browser: " << why;
  browser->Navigate("file://" + (dir / "views" / "report.html").string());
  ASSERT_TRUE(browser->WaitFor("document.body.dataset.ready === 'true'", std::chrono::seconds(20)));
  EXPECT_EQ(browser->Evaluate("document.querySelectorAll('#panels img[data-layer]').length"), 4)
      << "rendered, depth, uncertainty and the model map";
  // render.json's numbers as a reconstruction's are shown (999999995904 was printed as it is stored).
  EXPECT_EQ(browser->Evaluate("document.querySelector('[data-render=\"/lambda\"]').textContent"), "1.00e+12");
  EXPECT_TRUE(browser->problems().empty()) << fmt::format("{}", fmt::join(browser->problems(), "\n"));
}

}  // namespace
}  // namespace endorecon
