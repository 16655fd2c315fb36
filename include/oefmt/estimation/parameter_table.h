// SPDX-License-Identifier: GPL-3.0-or-later
// A table of parameters: each one's key, type, unit, accepted values and one-line meaning,
// bound to the field it sets. The configuration file's reader, the ROS node's parameter reading,
// the validation and the generated documentation (doc/parameters.md) all read such a table, so
// that a parameter is described in one place. No file I/O here.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "oefmt/enum_names.h"

namespace oefmt {

enum class ParameterType {
  kNumber,   ///< double
  kInteger,  ///< int (a number without a fraction)
  kBoolean,  ///< bool
  kWord,     ///< one of a list of words (an enum)
  kText,     ///< free text (a frame name)
};
inline constexpr EnumName<ParameterType> kParameterTypeNames[] = {
    {ParameterType::kNumber, "double"}, {ParameterType::kInteger, "int"},
    {ParameterType::kBoolean, "bool"},  {ParameterType::kWord, "string"},
    {ParameterType::kText, "string"}};
inline const char* toString(ParameterType type) { return enumName(kParameterTypeNames, type); }

/// Accepted values of a number or an integer: finite, within the bounds (inclusive unless open).
struct ParameterRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;
  bool even = false;  ///< integers: even values only

  bool contains(double value) const;
  /// "[2, 1000]", "(0, 1)", ">= 0", "> 0", "even, >= 64"; "" when anything finite goes.
  std::string text() const;
};
/// [min, max]
ParameterRange closedRange(double min, double max);
/// >= min
ParameterRange atLeast(double min);
/// > min
ParameterRange above(double min);

struct Parameter {
  std::string key;  ///< "registration.size": section, '.', name; top-level keys have no section
  ParameterType type = ParameterType::kNumber;
  std::string unit;     ///< "px", "m", "s"; "" for none
  std::string meaning;  ///< one line
  ParameterRange range;            ///< kNumber, kInteger
  std::vector<std::string> words;  ///< kWord: the accepted words
  /// A further rule that the owner's validate() checks (documentation only), e.g. "<= max_rate".
  std::string extra_rule;

  // The field in the configuration the table was made for (the one matching `type`).
  double* number = nullptr;
  int* integer = nullptr;
  bool* boolean = nullptr;
  std::string* text = nullptr;
  std::function<std::string()> get_word;
  std::function<void(const std::string&)> set_word;  ///< called with one of `words`

  std::string section() const;  ///< "" for a top-level key
  std::string name() const;     ///< the key without its section

  /// The current value as a configuration file writes it (a number keeps a dot: 0.0, 1.0e-6).
  std::string valueText() const;
  /// The accepted values as the documentation gives them: the range, the words, the extra rule.
  std::string rule() const;
  /// Empty when the current value is accepted; otherwise why not ("must be in [1, 50], got 0").
  std::string problem() const;

  // Setters: each throws InputError "invalid parameter '<key>': ..." for a value of the wrong
  // kind or outside the rule, and leaves the field unchanged then.
  void setNumber(double value) const;  ///< kNumber; kInteger when the value is a whole number
  void setBoolean(bool value) const;   ///< kBoolean
  void setWord(const std::string& value) const;  ///< kWord (one of `words`) or kText
};

using ParameterTable = std::vector<Parameter>;

/// Builders of table rows, bound to `field`.
Parameter numberParameter(const std::string& key, double& field, const std::string& unit,
                          ParameterRange range, const std::string& meaning);
Parameter integerParameter(const std::string& key, int& field, const std::string& unit,
                           ParameterRange range, const std::string& meaning);
Parameter booleanParameter(const std::string& key, bool& field, const std::string& meaning);
Parameter textParameter(const std::string& key, std::string& field, const std::string& meaning);
template <typename T, std::size_t N>
Parameter wordParameter(const std::string& key, T& field, const EnumName<T> (&names)[N],
                        const std::string& meaning) {
  Parameter p;
  p.key = key;
  p.type = ParameterType::kWord;
  p.meaning = meaning;
  p.words = enumNames(names);
  p.get_word = [&field, &names] { return std::string(enumName(names, field)); };
  p.set_word = [&field, &names](const std::string& word) {
    if (const auto value = findEnum(names, word)) field = *value;
  };
  return p;
}

/// The row with this key, or nullptr.
const Parameter* findParameter(const ParameterTable& table, const std::string& key);
/// True when some row's key starts with "<section>.".
bool isParameterSection(const ParameterTable& table, const std::string& section);
/// Throws InputError "invalid parameter '<key>': <problem>" for the first row whose value is not
/// accepted (rows whose key starts with `prefix` only).
void checkParameters(const ParameterTable& table, const std::string& prefix = "");

}  // namespace oefmt
