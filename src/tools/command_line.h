// SPDX-License-Identifier: GPL-3.0-or-later
// What the tools' command lines have in common, on top of CLI11: an option given twice counts
// once, with its last value; numbers are finite; a word option names its words in the help; and
// a bad command line is one line on stderr and exit status 2 (--help: the help on stdout, 0).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "oefmt/enum_names.h"
#include "oefmt/error.h"

namespace oefmt {
namespace tools {

/// Exit status of a bad command line, in every tool.
constexpr int kUsageError = 2;

/// Sets up a tool's App: `footer` (the exit statuses) below the options; an option given twice
/// keeps its last value.
inline void setUpTool(CLI::App& app, const std::string& footer) {
  app.description(app.get_description() + "\n");  // a blank line before the usage line
  app.footer(footer);
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.get_formatter()->column_width(28);
}

/// `text` as a finite number, or nothing. CLI11 alone reads "inf", "nan" and "1e999" as numbers;
/// every number the tools take is finite.
inline std::optional<double> finiteNumber(const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(value)) return std::nullopt;
  return value;
}

/// The check of a number option: a finite number.
inline const CLI::Validator& finite() {
  static const CLI::Validator validator(
      [](const std::string& text) {
        return finiteNumber(text) ? std::string() : "needs a finite number, got '" + text + "'";
      },
      "");
  return validator;
}

/// A number option shown as `--name UNIT` in the help.
inline CLI::Option* addNumber(CLI::App& app, const std::string& name, double& value, const std::string& unit,
                              const std::string& help) {
  return app.add_option(name, value, help)->type_name(unit)->check(finite());
}

/// A list of finite numbers separated by commas ("1,2.5,3"); given twice, the last list counts.
inline CLI::Option* addNumberList(CLI::App& app, const std::string& name, std::vector<double>& values,
                                  const std::string& unit, const std::string& help) {
  return app
      .add_option_function<std::string>(
          name,
          [name, &values](const std::string& text) {
            values.clear();
            std::stringstream stream(text);
            std::string item;
            while (std::getline(stream, item, ',')) {
              const std::optional<double> value = finiteNumber(item);
              requireInput(value.has_value(),
                           "option " + name + " needs numbers separated by commas, got '" + text + "'");
              values.push_back(*value);
            }
          },
          help)
      ->type_name(unit);
}

/// An option whose value is one of `words`, each standing for a value of T (an enum): shown as
/// `--name a|b|c` in the help; any other word is an error that lists them.
template <typename T>
CLI::Option* addChoice(CLI::App& app, const std::string& name, T& value,
                       const std::vector<std::pair<std::string, T>>& words, const std::string& help) {
  std::vector<std::string> names;
  std::string shown;
  for (const auto& word : words) {
    names.push_back(word.first);
    shown += (shown.empty() ? "" : "|") + word.first;
  }
  CLI::Validator member = CLI::IsMember(names);
  member.description("");  // the words are the type name
  return app
      .add_option_function<std::string>(
          name,
          [&value, words](const std::string& given) {
            for (const auto& word : words) {
              if (word.first == given) value = word.second;
            }
          },
          help)
      ->type_name(shown)
      ->check(member);
}

/// The same for an enum with a name table: its words are the table's.
template <typename T, std::size_t N>
CLI::Option* addChoice(CLI::App& app, const std::string& name, T& value, const EnumName<T> (&names)[N],
                       const std::string& help) {
  std::vector<std::pair<std::string, T>> words;
  for (const EnumName<T>& entry : names) words.emplace_back(entry.name, entry.value);
  return addChoice(app, name, value, words, help);
}

/// "a|b|c": an enum's words as the help shows them.
template <typename T, std::size_t N>
std::string shownWords(const EnumName<T> (&names)[N]) {
  std::string shown;
  for (const EnumName<T>& entry : names) shown += (shown.empty() ? "" : "|") + std::string(entry.name);
  return shown;
}

/// A text option that is one of `words`.
inline CLI::Option* addChoice(CLI::App& app, const std::string& name, std::string& value,
                              const std::vector<std::string>& words, const std::string& help) {
  std::vector<std::pair<std::string, std::string>> same;
  for (const std::string& word : words) same.emplace_back(word, word);
  return addChoice(app, name, value, same, help);
}

/// Parses the command line. Returns the exit status when the tool is to stop here: 0 after
/// --help, kUsageError after a bad command line (a CLI11 error, or an InputError thrown by an
/// option's or the App's callback, which check what CLI11 does not) said on one line.
inline std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s (see --help)\n", app.get_name().c_str(), e.what());
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: %s\n", app.get_name().c_str(), e.what());
  }
  return kUsageError;
}

}  // namespace tools
}  // namespace oefmt
