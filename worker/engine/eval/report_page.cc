#include "worker/engine/eval/report_page.h"

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string_view>

#include "common/error.h"

namespace endorecon::eval {
namespace detail {
// Defined by the generated report_page_template.cc.
extern const char kReportPageTemplate[];
extern const std::size_t kReportPageTemplate_size;
}  // namespace detail

namespace {
constexpr std::string_view kSlot = "@ENDORECON_REPORT_DATA@";
}  // namespace

std::string FillReportPage(const nlohmann::json& data) {
  const std::string_view page(detail::kReportPageTemplate, detail::kReportPageTemplate_size);
  const std::size_t at = page.find(kSlot);
  if (at == std::string_view::npos || page.find(kSlot, at + 1) != std::string_view::npos) {
    Fail(ErrorCode::kInternal,
         "the compiled-in report page must have exactly one data slot " + std::string(kSlot));
  }
  const std::string json = data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(page.size() + json.size() + json.size() / 64);
  out.append(page.substr(0, at));
  for (char c : json) {
    if (c == '<') {
      out.append("\\u003c");
    } else {
      out.push_back(c);
    }
  }
  out.append(page.substr(at + kSlot.size()));
  return out;
}

}  // namespace endorecon::eval
