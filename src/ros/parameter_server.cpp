// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/parameter_server.h"

#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"

namespace oefmt {
namespace {

using XmlRpc::XmlRpcValue;

void setFromServer(const Parameter& parameter, XmlRpcValue& value) {
  switch (value.getType()) {
    case XmlRpcValue::TypeInt: {
      const int number = static_cast<int>(value);
      if (parameter.type == ParameterType::kBoolean && (number == 0 || number == 1)) {
        parameter.setBoolean(number == 1);
      } else {
        parameter.setNumber(number);
      }
      return;
    }
    case XmlRpcValue::TypeDouble: parameter.setNumber(static_cast<double>(value)); return;
    case XmlRpcValue::TypeBoolean: parameter.setBoolean(static_cast<bool>(value)); return;
    case XmlRpcValue::TypeString: parameter.setWord(static_cast<std::string>(value)); return;
    case XmlRpcValue::TypeStruct: throwInvalidParameter(parameter.key, "expected a value, not a map");
    default: throwInvalidParameter(parameter.key, "expected a value of type " + std::string(toString(parameter.type)));
  }
}

}  // namespace

std::vector<std::string> readParameterServer(const ros::NodeHandle& nh, const ParameterTable& table) {
  XmlRpcValue all;
  if (!nh.getParam(nh.getNamespace(), all)) return {};
  return readParameterValues(all, nh.getNamespace() == "/" ? "" : nh.getNamespace(), table);
}

std::vector<std::string> readParameterValues(XmlRpcValue& all, const std::string& ns,
                                             const ParameterTable& table) {
  std::vector<std::string> others;
  if (all.getType() != XmlRpcValue::TypeStruct) return others;
  for (auto& [name, value] : all) {
    const std::string where = ns + "/" + name;
    if (isParameterSection(table, name)) {
      if (value.getType() != XmlRpcValue::TypeStruct) {
        throw InputError(where + ": parameter section '" + name + "' must be a map of parameters");
      }
      for (auto& [inner, inner_value] : value) {
        const Parameter* parameter = findParameter(table, name + "." + inner);
        if (parameter == nullptr) {
          throw InputError(where + "/" + inner + ": unknown parameter '" + name + "." + inner + "'");
        }
        try {
          setFromServer(*parameter, inner_value);
        } catch (const InputError& e) {
          throw InputError(where + "/" + inner + ": " + e.what());
        }
      }
      continue;
    }
    const Parameter* parameter = findParameter(table, name);
    if (parameter == nullptr) {
      const std::string hint = retiredParameterHint(name);
      if (!hint.empty()) throw InputError(where + ": unknown parameter '" + name + "' (" + hint + ")");
      others.push_back(name);
      continue;
    }
    try {
      setFromServer(*parameter, value);
    } catch (const InputError& e) {
      throw InputError(where + ": " + e.what());
    }
  }
  return others;
}

}  // namespace oefmt
