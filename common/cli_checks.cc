#include "common/cli_checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/job_bounds.h"

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
        if (std::isnan(value)) return text + " is not a finite number";
        return value < 0 ? text + " is negative; expected a number >= 0" : "";
      },
      ">= 0", "AtLeastZero");
}

CLI::Validator AboveZero() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value)) return text + " is not a finite number";
        return value <= 0 ? text + " is not above 0" : "";
      },
      "> 0", "AboveZero");
}

CLI::Validator Within(double low, double high) {
  const auto shown = [](double bound) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", bound);
    return std::string(text);
  };
  const std::string range = shown(low) + " to " + shown(high);
  return CLI::Validator(
      [low, high, range](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value)) return text + " is not a finite number";
        return value < low || value > high ? text + ": expected " + range : "";
      },
      range, "Within");
}

CLI::Validator TimeBudget() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        const double value = Number(text);
        if (std::isnan(value)) return text + " is not a finite number";
        if (value == 0 || (value >= kLeastTimeBudgetS && value <= kMostTimeBudgetS)) return "";
        return text + ": expected 0 (no budget) or " + std::to_string(int(kLeastTimeBudgetS)) + " to " +
               std::to_string(int(kMostTimeBudgetS)) +
               " seconds (a week; the budget is in seconds, and covers loading, training, evaluation and "
               "writing)";
      },
      "0 or " + std::to_string(int(kLeastTimeBudgetS)) + " to " + std::to_string(int(kMostTimeBudgetS)) +
          " s",
      "TimeBudget");
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

namespace {

enum class AddressUse { kListen, kCall, kStorageScp };

// What is wrong with `text` as an address to listen on or to call; "" when nothing.
std::string AddressProblem(const std::string& text, AddressUse use) {
  if (text.rfind("unix:", 0) == 0) {
    if (use == AddressUse::kStorageScp) return text + ": a storage SCP listens on a TCP port (HOST:PORT)";
    return text.size() > 5 ? "" : text + ": unix: needs a path";
  }
  const auto colon = text.rfind(':');
  const std::string host = colon == std::string::npos ? "" : text.substr(0, colon);
  const std::string port = colon == std::string::npos ? "" : text.substr(colon + 1);
  const bool bracketed = host.size() >= 2 && host.front() == '[' && host.back() == ']';
  if (host.empty() || (!bracketed && host.find(':') != std::string::npos) ||
      host.find_first_of(" /") != std::string::npos) {
    return text + " is no address " + (use == AddressUse::kCall ? "of a server" : "to listen on") +
           "; expected HOST:PORT, [IPv6]:PORT" + (use == AddressUse::kStorageScp ? "" : " or unix:PATH");
  }
  const int least = use == AddressUse::kListen ? 0 : 1;
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(port) > 65535 || std::stoi(port) < least) {
    // 049531 is 49531, in the range: the digits' count is what is wrong (found 2026-12-07).
    return text + ": the port must be a number from " +
           (use == AddressUse::kListen ? "0 (any free port)" : "1") + " to 65535" +
           (port.size() > 5 ? ", in at most five digits" : "") +
           (use == AddressUse::kStorageScp ? ", the port the PACS is told to send to" : "");
  }
  return "";
}

}  // namespace

CLI::Validator ListenAddress() {
  return CLI::Validator([](const std::string& text) { return AddressProblem(text, AddressUse::kListen); },
                        "HOST:PORT", "ListenAddress");
}

void DecimalIntegers(CLI::App& app) {
  const CLI::Validator decimal(
      [](std::string& text) -> std::string {
        const std::size_t begin = text.find_first_not_of(" \t"), end = text.find_last_not_of(" \t");
        const std::string given = begin == std::string::npos ? "" : text.substr(begin, end - begin + 1);
        const std::size_t digits = given.empty() || (given[0] != '+' && given[0] != '-') ? 0 : 1;
        // Whole numbers only, said so: "9abc" was "not a finite number", "9.0" CLI11's "Could not
        // convert" (found 2026-12-07).
        if (given.size() == digits || given.find_first_not_of("0123456789", digits) != std::string::npos)
          return "'" + given + "': expected a whole number (decimal digits)";
        const std::size_t first = std::min(given.find_first_not_of('0', digits), given.size() - 1);
        text = given.substr(0, digits) + given.substr(first);
        return {};
      },
      "", "DecimalInteger");
  for (CLI::Option* option : app.get_options()) {
    const std::string type = option->get_type_name();
    if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0) option->transform(decimal);
  }
  for (CLI::App* command : app.get_subcommands(nullptr)) DecimalIntegers(*command);
}

CLI::Validator ServerAddress() {
  return CLI::Validator([](const std::string& text) { return AddressProblem(text, AddressUse::kCall); },
                        "HOST:PORT", "ServerAddress");
}

CLI::Validator StorageScpAddress() {
  return CLI::Validator([](const std::string& text) { return AddressProblem(text, AddressUse::kStorageScp); },
                        "HOST:PORT", "StorageScpAddress");
}

}  // namespace endorecon
