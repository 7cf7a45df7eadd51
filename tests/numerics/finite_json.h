// Asserts a results document holds only finite numbers: nlohmann writes NaN and Inf as null, so a
// null anywhere is a NaN or Inf that reached the output.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace endorecon::testing {

inline void ExpectAllFinite(const nlohmann::json& json, const std::string& where) {
  if (json.is_null()) {
    ADD_FAILURE() << where << " is null (a NaN or Inf was written)";
  } else if (json.is_number()) {
    EXPECT_TRUE(std::isfinite(json.get<double>())) << where << " = " << json;
  } else if (json.is_array()) {
    for (std::size_t i = 0; i < json.size(); ++i)
      ExpectAllFinite(json[i], where + "[" + std::to_string(i) + "]");
  } else if (json.is_object()) {
    for (const auto& [key, value] : json.items()) ExpectAllFinite(value, where + "/" + key);
  }
}

}  // namespace endorecon::testing
