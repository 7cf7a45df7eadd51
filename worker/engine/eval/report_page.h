// The page of report.html: the HTML, stylesheet and scripts of eval/report_page/, inlined into one
// document at build time (cmake/EmbedPage.cmake) with one data slot, and the one way data enters it.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

namespace endorecon::eval {

// The page with `data` as its data block (a <script type="application/json"> element the page's
// script reads). Every "<" in the JSON is written as \u003c, so no string in it can end the element;
// invalid UTF-8 in strings is replaced by U+FFFD. The page's <title> and <h1> read "endorecon report:
// TITLE" ("endorecon views: TITLE" for data["kind"] "render"), HTML-escaped. Throws Error(kInternal) when the
// compiled-in page does not have exactly one slot (a fault of the build, not of the data).
std::string FillReportPage(const nlohmann::json& data);

}  // namespace endorecon::eval
