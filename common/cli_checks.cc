#include "common/cli_checks.h"

#include <cmath>
#include <string>

namespace endorecon {
namespace {

// The value as a finite number, or NaN when it is none.
double Number(const std::string& text) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    return used == text.size() && std::isfinite(value) ? value : NAN;
  } catch (const std::exception&) {
    return NAN;
  }
}

}  // namespace

CLI::Validator AtLeastZero() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value)) return text + " is not a number";
        return value < 0 ? text + " is negative; expected a number >= 0" : "";
      },
      ">= 0", "AtLeastZero");
}

CLI::Validator AboveZero() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value)) return text + " is not a number";
        return value <= 0 ? text + " is not above 0" : "";
      },
      "> 0", "AboveZero");
}

CLI::Validator HoldoutSpacing() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value) || value != std::floor(value)) return text + " is not a whole number";
        if (value < 0 || value == 1) {
          return text + ": expected 0 (no frame held out) or K >= 2 (every K-th frame held out; 1 would "
                        "hold out every frame)";
        }
        return "";
      },
      "0 or K >= 2", "HoldoutSpacing");
}

}  // namespace endorecon
