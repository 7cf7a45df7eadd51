// The data block of a report.html (eval::WriteReport), parsed, for the tests that check what a page
// holds.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/unit/temp_dir.h"

namespace endorecon::testing {

inline nlohmann::json ReportData(const std::string& page) {
  const std::string open = "<script id=\"report-data\" type=\"application/json\">";
  const auto start = page.find(open);
  if (start == std::string::npos) return nullptr;
  const auto end = page.find("</script>", start);
  if (end == std::string::npos) return nullptr;
  return nlohmann::json::parse(page.substr(start + open.size(), end - start - open.size()));
}

inline nlohmann::json ReportData(const std::filesystem::path& report) {
  return ReportData(ReadBytes(report));
}

}  // namespace endorecon::testing
