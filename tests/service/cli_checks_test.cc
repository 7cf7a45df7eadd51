// The command lines' number checks shared by the three binaries.
#include "common/cli_checks.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace endorecon {
namespace {

// Parses `args` (after the program's name) with every integer read as decimal; the error's text,
// or "" when it parsed.
std::string Parse(CLI::App& app, std::vector<std::string> args) {
  DecimalIntegers(app);
  std::vector<const char*> argv{"program"};
  for (const auto& arg : args) argv.push_back(arg.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return "";
}

// CLI11 reads integers as C's strtoll with base 0 does: 011 was octal 9 and 0x9 hex, so
// `--skip-left 011` skipped 9 frames without a word (found 2026-12-07).
TEST(DecimalIntegersTest, LeadingZerosAreDecimalAndHexIsRefusedInEveryCommand) {
  CLI::App app;
  int count = -1;
  unsigned total = 0;
  double seconds = 0;
  std::vector<int> list;
  app.add_option("--count", count)->check(AtLeastZero());
  app.add_option("--total", total);
  app.add_option("--seconds", seconds);
  CLI::App* command = app.add_subcommand("run");
  int skip = -1;
  command->add_option("--skip", skip);
  command->add_option("--list", list);
  EXPECT_EQ(Parse(app, {"--count", "011", "--total", "0009", "--seconds", "011.5", "run", "--skip", "-007",
                        "--list", "010", "0", "000"}),
            "");
  EXPECT_EQ(count, 11);
  EXPECT_EQ(total, 9u);
  EXPECT_DOUBLE_EQ(seconds, 11.5);
  EXPECT_EQ(skip, -7);
  EXPECT_EQ(list, (std::vector<int>{10, 0, 0}));

  CLI::App hex;
  hex.add_subcommand("run")->add_option("--skip", skip);
  const std::string message = Parse(hex, {"run", "--skip", "0x9"});
  EXPECT_NE(message.find("'0x9': expected a whole number"), std::string::npos) << message;
  for (const char* not_whole : {"9.0", "9abc", "1e1", "", "-"}) {
    CLI::App app2;
    app2.add_option("--skip", skip);
    EXPECT_NE(Parse(app2, {"--skip", not_whole}).find("expected a whole number"), std::string::npos)
        << not_whole;
  }
  // Its check still applies after the zeros are dropped.
  CLI::App negative;
  negative.add_option("--count", count)->check(AtLeastZero());
  EXPECT_NE(Parse(negative, {"--count", "-01"}).find("-1 is negative"), std::string::npos);
}

}  // namespace
}  // namespace endorecon
