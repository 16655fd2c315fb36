// SPDX-License-Identifier: GPL-3.0-or-later
// The estimator's parameters on the ROS parameter server, read through the same parser as the
// YAML file of oefmt_offline, so that every key is defined and validated in one place.
#pragma once

#include <string>

#include <ros/node_handle.h>

#include "oefmt/estimation/estimator_config.h"

namespace oefmt {

/// YAML text (the parseYaml subset) of the estimator keys found under `nh`: the top-level
/// keys of config/default.yaml (mode, altitude, registration, ...); other parameters of the
/// node (frames, topics) are left out.
std::string estimatorYamlFromParameters(const ros::NodeHandle& nh);

/// Parses YAML text with parseConfig; `source` names it in error messages (InputError).
EstimatorConfig parseConfigText(const std::string& yaml, const std::string& source);

}  // namespace oefmt
