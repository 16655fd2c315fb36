// SPDX-License-Identifier: GPL-3.0-or-later
// Parameters of a table (parameter_table.h) read from the ROS parameter server, as rosparam
// loads the configuration file into a namespace: top-level keys as <ns>/key, sections as
// <ns>/section/key.
#pragma once

#include <string>
#include <vector>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "oefmt/estimation/parameter_table.h"

namespace oefmt {

/// Sets the fields of `table` from the parameters in `nh`'s namespace; keys the server does not
/// have keep their values. Numbers may be given as integers, integers as whole doubles,
/// booleans as 0 or 1. Throws InputError naming the parameter (its ROS name and its key) for a
/// value of the wrong type or outside its rule, an unknown key inside one of the table's
/// sections, a section that is not a map, and a key the table retired (retiredParameterHint).
/// Returns the other top-level names in the namespace that the table does not have (other code,
/// such as image_transport, keeps parameters there too).
std::vector<std::string> readParameterServer(const ros::NodeHandle& nh, const ParameterTable& table);

/// The same from the namespace's parameters as one XmlRpc struct (`ns` names it in messages).
std::vector<std::string> readParameterValues(XmlRpc::XmlRpcValue& parameters, const std::string& ns,
                                             const ParameterTable& table);

}  // namespace oefmt
