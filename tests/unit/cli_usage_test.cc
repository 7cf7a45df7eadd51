// A mistyped command or option is named with the nearest known one, at whatever depth of commands;
// a missing command lists the commands; other mistakes are left to CLI11's message.
#include "common/cli_usage.h"

#include <gtest/gtest.h>

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace endorecon {
namespace {

// A program shaped as the product's: global options, commands with options and positionals, and a
// command of commands.
struct Program {
  CLI::App app{"test"};
  std::string clip, server;
  double budget = 0;
  Program() {
    app.require_subcommand(0, 1);
    app.add_option("--server", server);
    auto* reconstruct = app.add_subcommand("reconstruct");
    reconstruct->add_option("clip", clip);
    reconstruct->add_option("--time-budget", budget);
    reconstruct->add_flag("--full-eval");
    reconstruct->fallthrough();
    app.add_subcommand("render");
    auto* token = app.add_subcommand("token");
    token->require_subcommand(1);
    token->add_subcommand("create");
    token->add_subcommand("revoke");
  }
  // The mistake of `words` typed after the program's name.
  std::string Mistake(std::vector<const char*> words) {
    words.insert(words.begin(), "/usr/bin/prog");
    try {
      app.parse(int(words.size()), const_cast<char**>(words.data()));
      return "(parsed)";
    } catch (const CLI::ParseError&) {
      return UsageMistake(app, int(words.size()), words.data());
    }
  }
};

TEST(CliUsageTest, AMistypedCommandIsNamedWithTheNearestOne) {
  EXPECT_EQ(Program().Mistake({"reconstrct", "clip"}),
            "unknown command 'reconstrct' (did you mean 'reconstruct'?); the commands of prog: reconstruct, "
            "render, token");
  EXPECT_EQ(
      Program().Mistake({"--server", "h:1", "recon", "clip"}),
      "unknown command 'recon' (did you mean 'reconstruct'?); the commands of prog: reconstruct, render, "
      "token")
      << "an option's value is no command, and a command's start is near it";
  EXPECT_EQ(Program().Mistake({"token", "creat"}),
            "unknown command 'creat' (did you mean 'create'?); the commands of prog token: create, revoke");
  EXPECT_EQ(Program().Mistake({"xyzzy"}),
            "unknown command 'xyzzy'; the commands of prog: reconstruct, render, token")
      << "nothing near";
}

TEST(CliUsageTest, AMistypedOptionIsNamedWithItsCommand) {
  EXPECT_EQ(Program().Mistake({"reconstruct", "--time-budjet", "10", "clip"}),
            "unknown option --time-budjet of 'reconstruct' (did you mean --time-budget?); prog reconstruct "
            "--help lists them");
  EXPECT_EQ(Program().Mistake({"reconstruct", "clip", "--servr=h:1"}),
            "unknown option --servr of 'reconstruct' (did you mean --server?); prog reconstruct --help lists "
            "them")
      << "the options above a command count as its own";
  EXPECT_EQ(Program().Mistake({"--sever", "h:1"}),
            "unknown option --sever (did you mean --server?); prog --help lists them");
}

TEST(CliUsageTest, AMissingCommandListsTheCommands) {
  EXPECT_EQ(Program().Mistake({"token"}), "give a command: create, revoke (prog token --help)");
}

TEST(CliUsageTest, OtherMistakesAreLeftToCli11) {
  EXPECT_EQ(Program().Mistake({"reconstruct", "clip", "extra"}), "");
  EXPECT_EQ(Program().Mistake({"reconstruct", "clip", "--time-budget"}), "") << "a value missing";
  EXPECT_EQ(Program().Mistake({"reconstruct", "clip", "--full-eval", "--time-budget", "5"}), "(parsed)");
}

// The binaries' handler: a mistake after the program's name, CLI11's words where it names none, 2;
// --help 0.
TEST(CliUsageTest, AParseErrorIsSaidAfterTheProgramsName) {
  CLI::App app{"test"};
  std::string out;
  app.add_option("-o,--out", out)->required();
  const auto explain = [&](std::vector<const char*> words, std::string& said) {
    words.insert(words.begin(), "/usr/bin/prog");
    std::ostringstream err;
    std::streambuf* const was = std::cerr.rdbuf(err.rdbuf());
    std::ostringstream help;
    std::streambuf* const was_out = std::cout.rdbuf(help.rdbuf());
    int code = -1;
    try {
      app.parse(int(words.size()), const_cast<char**>(words.data()));
    } catch (const CLI::ParseError& e) {
      code = ExplainParseError(app, e, int(words.size()), words.data());
    }
    std::cerr.rdbuf(was);
    std::cout.rdbuf(was_out);
    said = err.str() + help.str();
    return code;
  };
  std::string said;
  EXPECT_EQ(explain({}, said), 2);
  EXPECT_EQ(said, "prog: --out is required\nRun with --help for more information.\n");
  EXPECT_EQ(explain({"--otu", "x"}, said), 2);
  EXPECT_EQ(said, "prog: unknown option --otu (did you mean --out?); prog --help lists them\n");
  EXPECT_EQ(explain({"--help"}, said), 0);
  EXPECT_NE(said.find("--out"), std::string::npos) << said;
}

}  // namespace
}  // namespace endorecon
