#include "worker/engine/eval/curve_plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::eval {
namespace {

// Every element opened is closed in order (self-closing tags and the XML declaration aside).
bool TagsBalance(const std::string& svg) {
  std::vector<std::string> open;
  const std::regex tag(R"re(<(/?)([A-Za-z?][A-Za-z0-9:-]*)[^>]*?(/?)>)re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), tag); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[2];
    if (name[0] == '?' || (*it)[3] == "/") continue;
    if ((*it)[1] == "/") {
      if (open.empty() || open.back() != name) return false;
      open.pop_back();
    } else {
      open.push_back(name);
    }
  }
  return open.empty();
}

std::vector<std::string> Polylines(const std::string& svg) {
  std::vector<std::string> points;
  const std::regex polyline(R"re(<polyline[^>]*points="([^"]*)")re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), polyline); it != std::sregex_iterator(); ++it) {
    points.push_back((*it)[1]);
  }
  return points;
}

int PointCount(const std::string& points) {
  return points.empty() ? 0 : static_cast<int>(std::count(points.begin(), points.end(), ' ')) + 1;
}

TEST(CurvePlot, LogAxisGivesDecadesEqualWidths) {
  const LogAxis axis(1, 1000, 50, 350);
  EXPECT_NEAR(axis(1), 50, 1e-9);
  EXPECT_NEAR(axis(10), 150, 1e-9);
  EXPECT_NEAR(axis(100), 250, 1e-9);
  EXPECT_NEAR(axis(1000), 350, 1e-9);
  EXPECT_NEAR(axis(0.1), -50, 1e-9);
  EXPECT_NEAR(axis(std::sqrt(10.0)), 100, 1e-9);
  EXPECT_THROW(LogAxis(0, 10, 0, 1), Error);
}

TEST(CurvePlot, OnePolylinePerSeriesWithItsPoints) {
  CurveSeries training{"training PSNR", {3, 15, 30, 60, 120, 250}, {18, 24, 27, 29, 31, 33}, true, ""};
  CurveSeries held_out{"held-out PSNR", {0, 15, 30, 60, 120, 250}, {NAN, 23, NAN, 28, 30, 32}, false, ""};
  const std::vector<CurveSeries> series = {training, held_out};
  const std::string svg = CurveSvg(series);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_TRUE(TagsBalance(svg));
  const std::vector<std::string> lines = Polylines(svg);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(PointCount(lines[0]), 6);
  EXPECT_EQ(PointCount(lines[1]), 4);  // the t = 0 point and the NaN values are left out
  EXPECT_EQ(std::regex_search(svg, std::regex("<circle")), true);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_NE(svg.find(">training PSNR</text>"), std::string::npos);
  EXPECT_NE(svg.find(">held-out PSNR</text>"), std::string::npos);
  // Data from 3 s to 250 s: decade ticks 1, 10, 100, 1000.
  for (const char* tick : {">1</text>", ">10</text>", ">100</text>", ">1000</text>"}) {
    EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  }
  EXPECT_EQ(svg.find(">10000</text>"), std::string::npos);
}

TEST(CurvePlot, PointsLandWhereTheAxesSay) {
  // Default 760 x 480: plot area x from 64 to 740 over 1..100 s, so 10 s sits at x = 402.
  const std::vector<CurveSeries> series = {{"run", {1, 10, 100}, {20, 25, 30}, false, "#123456"}};
  const std::string svg = CurveSvg(series);
  const std::vector<std::string> lines = Polylines(svg);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].rfind("64.00,", 0), 0u);
  EXPECT_NE(lines[0].find(" 402.00,"), std::string::npos);
  EXPECT_NE(lines[0].find(" 740.00,"), std::string::npos);
  EXPECT_NE(svg.find("stroke=\"#123456\""), std::string::npos);
}

TEST(CurvePlot, LabelsAreEscapedAndEmptyPlotsAreValid) {
  CurvePlotOptions options;
  options.title = "a<b & \"c\"";
  const std::vector<CurveSeries> series = {{"x>y", {}, {}, false, ""}};
  const std::string svg = CurveSvg(series, options);
  EXPECT_NE(svg.find("a&lt;b &amp; &quot;c&quot;"), std::string::npos);
  EXPECT_NE(svg.find("x&gt;y"), std::string::npos);
  EXPECT_TRUE(TagsBalance(svg));
  EXPECT_EQ(PointCount(Polylines(svg).at(0)), 0);
}

TEST(CurvePlot, BadInputThrows) {
  const std::vector<CurveSeries> mismatched = {{"bad", {1, 2}, {3}, false, ""}};
  EXPECT_THROW(CurveSvg(mismatched), Error);
  CurvePlotOptions tiny;
  tiny.width = 10;
  EXPECT_THROW(CurveSvg({}, tiny), Error);
}

TEST(CurvePlot, WritesTheFile) {
  testing::TempDir dir("curve");
  const std::vector<CurveSeries> series = {{"run", {1, 2}, {20, 21}, false, ""}};
  WriteCurveSvg(dir / "curve.svg", series);
  EXPECT_EQ(testing::ReadBytes(dir / "curve.svg"), CurveSvg(series));
  std::ofstream(dir / "a-file") << "x";  // a parent that is a file: nothing can be written there
  EXPECT_THROW(WriteCurveSvg(dir / "a-file" / "curve.svg", series), Error);
}

}  // namespace
}  // namespace endorecon::eval
