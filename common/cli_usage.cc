#include "common/cli_usage.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <string_view>
#include <vector>

#include "common/job_bounds.h"

namespace endorecon {
namespace {

// Edits (insertions, deletions, substitutions) between two short words. Written here: no library of
// ours offers it, and CLI11 suggests nothing.
std::size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The known name nearest `word`: within two edits (a third of a long word's letters), or one that
// begins with it; empty when none is near.
std::string Nearest(std::string_view word, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const std::string& name : known) {
    std::size_t distance = EditDistance(word, name);
    if (name.size() > word.size() + 1 && name.starts_with(word))
      distance = std::min<std::size_t>(distance, 1);
    if (distance < best_distance) {
      best_distance = distance;
      best = name;
    }
  }
  return best;
}

std::vector<const CLI::App*> Commands(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App*) { return true; });
}

std::vector<std::string> CommandNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* command : Commands(app)) names.push_back(command->get_name());
  return names;
}

std::string CommandList(const CLI::App& app) {
  std::string list;
  for (const std::string& name : CommandNames(app)) list += (list.empty() ? "" : ", ") + name;
  return list;
}

// The program's name as the user typed it, its folder aside.
std::string ProgramName(int argc, const char* const* argv) {
  return std::filesystem::path(argc > 0 ? argv[0] : "").filename().string();
}

// The program and the commands down to `app`, as the user types them: "endorecon-server token".
std::string CommandLine(const CLI::App& app, std::string_view program) {
  return app.get_parent() == nullptr ? std::string(program)
                                     : CommandLine(*app.get_parent(), program) + " " + app.get_name();
}

// An option `name` names in `app` or, as options fall through, in the commands above it.
const CLI::Option* FindOption(const CLI::App& app, const std::string& name) {
  for (const CLI::App* at = &app; at != nullptr; at = at->get_parent()) {
    if (const CLI::Option* option = at->get_option_no_throw(name)) return option;
  }
  return nullptr;
}

std::vector<std::string> OptionNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* at = &app; at != nullptr; at = at->get_parent()) {
    for (const CLI::Option* option : at->get_options()) {
      for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    }
  }
  return names;
}

bool TakesPositionals(const CLI::App& app) {
  const auto options = app.get_options();
  return std::any_of(options.begin(), options.end(),
                     [](const CLI::Option* o) { return o->get_positional(); });
}

}  // namespace

std::string UsageMistake(const CLI::App& app, int argc, const char* const* argv) {
  const std::string program = ProgramName(argc, argv);
  const CLI::App* at = &app;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") break;
    if (word.size() > 1 && word[0] == '-') {
      const std::string name = word.substr(0, word.find('='));
      const CLI::Option* option = FindOption(*at, name);
      if (option == nullptr) {
        const std::string nearest = Nearest(name, OptionNames(*at));
        return "unknown option " + name + (at == &app ? std::string() : " of '" + at->get_name() + "'") +
               (nearest.empty() ? std::string() : " (did you mean " + nearest + "?)") + "; " +
               CommandLine(*at, program) + " --help lists them";
      }
      if (name == word && option->get_items_expected_min() > 0) ++i;  // its value
      continue;
    }
    if (const auto commands = Commands(*at); !commands.empty()) {
      const auto command = std::find_if(commands.begin(), commands.end(),
                                        [&](const CLI::App* c) { return c->check_name(word); });
      if (command != commands.end()) {
        at = *command;
        continue;
      }
      if (!TakesPositionals(*at)) {
        const std::string nearest = Nearest(word, CommandNames(*at));
        return "unknown command '" + word + "'" +
               (nearest.empty() ? std::string() : " (did you mean '" + nearest + "'?)") +
               "; the commands of " + CommandLine(*at, program) + ": " + CommandList(*at);
      }
    }
  }
  if (at->get_require_subcommand_min() > 0 && !Commands(*at).empty()) {
    return "give a command: " + CommandList(*at) + " (" + CommandLine(*at, program) + " --help)";
  }
  return "";
}

int ExplainParseError(const CLI::App& app, const CLI::ParseError& e, int argc, const char* const* argv) {
  if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
  const std::string program = ProgramName(argc, argv);
  const std::string mistake = UsageMistake(app, argc, argv);
  std::cerr << program << ": " << PrintableLines(mistake.empty() ? std::string(e.what()) : mistake) << "\n";
  if (mistake.empty()) std::cerr << "Run with --help for more information.\n";
  return 2;
}

}  // namespace endorecon
