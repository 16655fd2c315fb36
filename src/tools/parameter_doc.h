// SPDX-License-Identifier: GPL-3.0-or-later
// The parameter documentation generated from the tables in the code: doc/parameters.md and
// config/default.yaml (oefmt_parameters prints them; a test compares them with the files).
#pragma once

#include <string>

namespace oefmt {

/// doc/parameters.md: the configuration file's parameters (estimatorParameters) by section, where
/// the initial altitude and the focal length come from, and the ROS node's own parameters
/// (nodeParameters).
std::string parametersMarkdown();

/// config/default.yaml: every default, with each key's meaning, unit and accepted values.
std::string defaultConfigYaml();

}  // namespace oefmt
