#include "worker/engine/eval/report_page.h"

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string_view>

#include "common/error.h"
#include "worker/engine/eval/markup_text.h"

namespace endorecon::eval {
namespace detail {
// Defined by the generated report_page_template.cc.
extern const char kReportPageTemplate[];
extern const std::size_t kReportPageTemplate_size;
}  // namespace detail

namespace {
constexpr std::string_view kSlot = "@ENDORECON_REPORT_DATA@";
constexpr std::string_view kHeadingSlot = "@ENDORECON_REPORT_HEADING@";

// The page's heading, in its <title> and <h1> from the start: a viewer without scripts, a browser's
// tab list and its history name the run (they read "endorecon report" for every run).
std::string Heading(const nlohmann::json& data) {
  const bool render = data.is_object() && data.value("kind", "") == "render";
  std::string heading = render ? "endorecon views" : "endorecon report";
  if (data.is_object() && data.contains("title") && data["title"].is_string())
    heading += ": " + data["title"].get<std::string>();
  // Re-encoded so that invalid UTF-8 is replaced as in the data block.
  heading = nlohmann::json(heading).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  heading = nlohmann::json::parse(heading).get<std::string>();
  return EscapeMarkup(heading);
}
}  // namespace

std::string FillReportPage(const nlohmann::json& data) {
  const std::string_view page(detail::kReportPageTemplate, detail::kReportPageTemplate_size);
  const std::size_t at = page.find(kSlot);
  if (at == std::string_view::npos || page.find(kSlot, at + 1) != std::string_view::npos) {
    Fail(ErrorCode::kInternal,
         "the compiled-in report page must have exactly one data slot " + std::string(kSlot));
  }
  const std::string json = data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  const std::string heading = Heading(data);
  std::string out;
  out.reserve(page.size() + json.size() + json.size() / 64);
  // The template's text around the data slot, with the heading in its slots (never inside the data).
  const auto append_template = [&](std::string_view part) {
    for (auto slot = part.find(kHeadingSlot); slot != std::string_view::npos;
         slot = part.find(kHeadingSlot)) {
      out.append(part.substr(0, slot));
      out.append(heading);
      part.remove_prefix(slot + kHeadingSlot.size());
    }
    out.append(part);
  };
  append_template(page.substr(0, at));
  for (char c : json) {
    if (c == '<') {
      out.append("\\u003c");
    } else {
      out.push_back(c);
    }
  }
  append_template(page.substr(at + kSlot.size()));
  return out;
}

}  // namespace endorecon::eval
