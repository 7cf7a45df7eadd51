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
