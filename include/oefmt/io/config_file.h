// SPDX-License-Identifier: GPL-3.0-or-later
// The configuration file (config/default.yaml, oefmt_offline --config): YAML maps of the
// parameters of estimatorParameters(), read and written through that table.
#pragma once

#include <string>

#include "oefmt/estimation/estimator_config.h"

namespace oefmt {

/// Reads a configuration file: top-level keys and sections of keys (a leading "%YAML" directive
/// and "---" are optional). Missing keys keep their defaults; a null value ("key:") too. Throws
/// InputError naming the file, the line and the key for: an unknown key or section, a value of
/// the wrong kind (a number, an integer, true/false, one of the listed words) or outside its
/// range, a key that appears twice, a value where a section's map is expected (or the other way
/// round), a second document, and YAML syntax errors. The result is validated.
EstimatorConfig loadConfig(const std::string& yaml_path);

/// The same from YAML text; `source` names it in messages ("configuration file 'x.yaml'").
EstimatorConfig parseConfigText(const std::string& text, const std::string& source);

/// Every parameter of `config` as YAML that loadConfig reads back identically. With `comments`,
/// each section's heading and each key's meaning, unit and accepted values as comments (the
/// text of config/default.yaml for a default config).
std::string configToYaml(const EstimatorConfig& config, bool comments = false);

}  // namespace oefmt
