#include "worker/engine/eval/report_page.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <regex>

#include "tests/unit/report_data.h"

namespace endorecon::eval {
namespace {

TEST(ReportPageTest, TheDataGoesIntoTheOneSlotAndComesBackEqual) {
  const nlohmann::json data = {
      {"title", "clip 7"}, {"numbers", {1.5, -2, 1e-9}}, {"nested", {{"a", nullptr}}}};
  const std::string page = FillReportPage(data);
  EXPECT_EQ(page.find("@ENDORECON_REPORT_DATA@"), std::string::npos);
  EXPECT_EQ(testing::ReportData(page), data);
}

TEST(ReportPageTest, NoStringInTheDataCanEndTheScriptElement) {
  const nlohmann::json data = {{"clip", "/data/</script><script>alert(1)</script><!--"}};
  const std::string page = FillReportPage(data);
  EXPECT_EQ(page.find("</script><script>alert"), std::string::npos);
  EXPECT_EQ(page.find("<!--\""), std::string::npos);
  EXPECT_EQ(testing::ReportData(page), data) << "\\u003c decodes back to <";
}

TEST(ReportPageTest, InvalidUtf8IsReplacedNotThrown) {
  const nlohmann::json data = {{"clip", std::string("/data/\xff\xfe")}};
  const nlohmann::json back = testing::ReportData(FillReportPage(data));
  EXPECT_EQ(back["clip"], "/data/\xEF\xBF\xBD\xEF\xBF\xBD");
}

// The run's name is in the page's <title> and heading without a script running (a browser's tabs and
// history, a viewer without JavaScript): every page read "endorecon report" until 2026-12-06.
TEST(ReportPageTest, TheTitleNamesTheRunEscapedWithoutAScript) {
  const std::string page = FillReportPage({{"title", "liver <3 & \"B\""}});
  EXPECT_NE(page.find("<title>endorecon report: liver &lt;3 &amp; &quot;B&quot;</title>"), std::string::npos);
  EXPECT_NE(page.find("<h1 id=\"title\">endorecon report: liver &lt;3 &amp; &quot;B&quot;</h1>"),
            std::string::npos);
  EXPECT_EQ(page.find("@ENDORECON_REPORT_HEADING@"), std::string::npos);
  EXPECT_EQ(testing::ReportData(page)["title"], "liver <3 & \"B\"");

  EXPECT_NE(
      FillReportPage({{"kind", "render"}, {"title", "views"}}).find("<title>endorecon views: views</title>"),
      std::string::npos);
  EXPECT_NE(FillReportPage(nlohmann::json::object()).find("<title>endorecon report</title>"),
            std::string::npos);
  EXPECT_NE(FillReportPage({{"title", std::string("c\xff")}})
                .find("<title>endorecon report: c\xEF\xBF\xBD</title>"),
            std::string::npos);
}

TEST(ReportPageTest, ThePageIsSelfContained) {
  const std::string page = FillReportPage(nlohmann::json::object());
  // The stylesheet and scripts are inlined at build time; nothing is loaded from anywhere.
  EXPECT_EQ(page.find("<link"), std::string::npos);
  EXPECT_FALSE(std::regex_search(page, std::regex(R"(<script[^>]*\ssrc=)")));
  EXPECT_FALSE(std::regex_search(page, std::regex(R"((src|href)\s*=\s*["']?(https?:)?//)")));
  EXPECT_EQ(page.find("url(http"), std::string::npos);
  EXPECT_NE(page.find("class SurfaceViewer"), std::string::npos);
  EXPECT_NE(page.find("const EndoPlots"), std::string::npos);
  EXPECT_NE(page.find("--heldout"), std::string::npos) << "the stylesheet";
}

}  // namespace
}  // namespace endorecon::eval
