// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/config_file.h"

#include <fstream>
#include <iterator>
#include <sstream>

#include "oefmt/error.h"
#include "yaml_document.h"

namespace oefmt {
namespace {

// Sets `parameter` from a scalar node; InputError (without the place, added by the caller).
void setFromYaml(const Parameter& parameter, const YAML::Node& node) {
  if (!node.IsScalar()) {
    throwInvalidParameter(parameter.key, std::string("expected a value, not a ") +
                                             (node.IsMap() ? "map" : "sequence"));
  }
  // Leading and trailing blanks are not part of a plain scalar; a quoted one keeps them.
  const std::string& text = node.Scalar();
  switch (parameter.type) {
    case ParameterType::kNumber:
    case ParameterType::kInteger: {
      double value = 0.0;
      bool out_of_range = false;
      if (!yamlNumber(text, value, &out_of_range) || out_of_range) {
        throwInvalidParameter(parameter.key, parameter.type == ParameterType::kNumber
                                                 ? "expected a number, got '" + text + "'"
                                                 : "expected an integer, got '" + text + "'");
      }
      parameter.setNumber(value);
      return;
    }
    case ParameterType::kBoolean:
      // YAML 1.1's words as rosparam reads them, and 1/0.
      if (text == "true" || text == "True" || text == "TRUE" || text == "yes" || text == "on" || text == "1") {
        parameter.setBoolean(true);
      } else if (text == "false" || text == "False" || text == "FALSE" || text == "no" || text == "off" ||
                 text == "0") {
        parameter.setBoolean(false);
      } else {
        throwInvalidParameter(parameter.key, "expected true or false, got '" + text + "'");
      }
      return;
    case ParameterType::kWord:
    case ParameterType::kText: parameter.setWord(text); return;
  }
}

// The keys of one map: `section` "" for the top level (where sections are read separately).
void readMap(const ParameterTable& table, const YAML::Node& map, const std::string& section,
             const std::string& what) {
  requireUniqueKeys(map, what);
  for (const auto& entry : map) {
    const std::string& name = entry.first.Scalar();
    const YAML::Node& value = entry.second;
    const std::string where = yamlWhere(what, entry.first);
    if (section.empty() && isParameterSection(table, name)) {
      if (value.IsNull()) continue;
      if (!value.IsMap()) {
        throw InputError(where + ": parameter section '" + name + "' must be a map of 'key: value' lines");
      }
      readMap(table, value, name, what);
      continue;
    }
    const std::string key = section.empty() ? name : section + "." + name;
    const Parameter* parameter = findParameter(table, key);
    if (parameter == nullptr) {
      if (section.empty() && value.IsMap()) throw InputError(where + ": unknown parameter section '" + name + "'");
      const std::string hint = section.empty() ? retiredParameterHint(name) : "";
      throw InputError(where + ": unknown parameter '" + key + "'" + (hint.empty() ? "" : " (" + hint + ")"));
    }
    if (value.IsNull()) continue;
    try {
      setFromYaml(*parameter, value);
    } catch (const InputError& e) {
      throw InputError(where + ": " + e.what());
    }
  }
}

// `text` as comment lines of at most 100 columns, each starting with `indent` "# ".
std::string commentLines(const std::string& text, const std::string& indent) {
  std::istringstream words(text);
  std::string word, line, out;
  while (words >> word) {
    if (!line.empty() && indent.size() + 2 + line.size() + 1 + word.size() > 100) {
      out += indent + "# " + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += indent + "# " + line + "\n";
  return out;
}

}  // namespace

EstimatorConfig parseConfigText(const std::string& text, const std::string& source) {
  const YAML::Node root = parseYamlMap(text, source);
  EstimatorConfig config;
  readMap(estimatorParameters(config), root, "", source);
  try {
    config.validate();
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
  return config;
}

EstimatorConfig loadConfig(const std::string& yaml_path) {
  std::ifstream in(yaml_path, std::ios::binary);
  if (!in) throw InputError("cannot open configuration file '" + yaml_path + "'");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError("cannot read configuration file '" + yaml_path + "'");
  return parseConfigText(text, "configuration file '" + yaml_path + "'");
}

std::string configToYaml(const EstimatorConfig& config, bool comments) {
  EstimatorConfig copy = config;
  const ParameterTable table = estimatorParameters(copy);
  std::ostringstream out;
  out << "%YAML 1.0\n---\n";
  if (comments) {
    out << "# Every parameter of oefmt's estimator with its default, generated from the parameter table\n"
           "# in the code (oefmt_parameters --yaml); doc/parameters.md describes each one. Read by\n"
           "# oefmt_offline --config and, loaded into the node's private namespace, by the ROS node.\n"
           "# Missing keys keep these defaults; an unknown key or a bad value stops the program with a\n"
           "# message naming the file, the line and the key.\n";
  }
  for (const ParameterSection& section : estimatorParameterSections()) {
    const std::string indent = section.name[0] == '\0' ? "" : "  ";
    if (comments) out << "\n" << commentLines(section.title, "");
    if (indent.size() > 0) out << section.name << ":\n";
    for (const Parameter& p : table) {
      if (p.section() != section.name) continue;
      if (comments) {
        std::string text = p.meaning;
        if (!p.unit.empty()) text += "; unit " + p.unit;
        if (!p.rule().empty()) text += (p.unit.empty() ? "; accepted " : ", accepted ") + p.rule();
        out << commentLines(text, indent);
      }
      out << indent << p.name() << ": " << p.valueText() << "\n";
    }
  }
  return out.str();
}

}  // namespace oefmt
