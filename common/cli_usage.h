// What a command line got wrong, in the user's words. CLI11 says "A subcommand is required" for a
// mistyped command (`endorecon-worker reconstrct CLIP`) and "The following arguments were not
// expected: 15 --time-budjet" for a mistyped option, words reversed, the option's value first.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace endorecon {

// Once `app.parse(argc, argv)` threw: an unknown command or option, named with the command it was
// given to and the nearest known name ("unknown option --time-budjet of 'submit' (did you mean
// --time-budget?)"), or a missing command with the commands listed; empty when the mistake is none of
// those (CLI11's own message then says it). Without the program's name in front.
std::string UsageMistake(const CLI::App& app, int argc, const char* const* argv);

// What endorecon-worker and endorecon-server do when `app.parse` threw `e`: --help and --version print
// and give 0; a usage mistake is said on stderr after the program's name, in UsageMistake's words or
// else CLI11's ("endorecon-worker: --out is required"), and gives 2, as every other invalid input.
int ExplainParseError(const CLI::App& app, const CLI::ParseError& e, int argc, const char* const* argv);

}  // namespace endorecon
