// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/parameter_yaml.h"

#include <iomanip>
#include <set>
#include <sstream>

#include <xmlrpcpp/XmlRpcValue.h>

#include "oefmt/error.h"
#include "oefmt/io/yaml_map.h"

namespace oefmt {
namespace {

// Top-level keys of the estimator's YAML, taken from its own writer (no second list to keep).
std::set<std::string> estimatorKeys() {
  std::set<std::string> keys;
  std::istringstream text(configToYaml(EstimatorConfig{}));
  std::string line;
  while (std::getline(text, line)) {
    if (line.empty() || line[0] == ' ' || line[0] == '%' || line[0] == '#' || line[0] == '-') continue;
    const auto colon = line.find(':');
    if (colon != std::string::npos) keys.insert(line.substr(0, colon));
  }
  return keys;
}

void emit(std::ostream& out, const XmlRpc::XmlRpcValue& value, int indent, const std::string& key) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  XmlRpc::XmlRpcValue v = value;  // the accessors are not const
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeStruct:
      out << pad << key << ":\n";
      for (auto& entry : v) emit(out, entry.second, indent + 3, entry.first);
      break;
    case XmlRpc::XmlRpcValue::TypeBoolean:
      out << pad << key << ": " << (static_cast<bool>(v) ? "true" : "false") << "\n";
      break;
    case XmlRpc::XmlRpcValue::TypeInt:
      out << pad << key << ": " << static_cast<int>(v) << "\n";
      break;
    case XmlRpc::XmlRpcValue::TypeDouble:
      out << pad << key << ": " << std::setprecision(17) << static_cast<double>(v) << "\n";
      break;
    case XmlRpc::XmlRpcValue::TypeString: {
      // Double-quoted, so any text stays one scalar (parseYaml undoes these escapes).
      std::string quoted;
      for (const char c : static_cast<std::string>(v)) {
        if (c == '"' || c == '\\') quoted += '\\';
        quoted += c == '\n' ? std::string("\\n") : std::string(1, c);
      }
      out << pad << key << ": \"" << quoted << "\"\n";
      break;
    }
    default:
      throw InputError("parameter '" + key + "' has a type the estimator does not use");
  }
}

}  // namespace

std::string estimatorYamlFromParameters(const ros::NodeHandle& nh) {
  std::ostringstream out;
  out << "%YAML:1.0\n---\n";
  for (const std::string& key : estimatorKeys()) {
    XmlRpc::XmlRpcValue value;
    if (nh.getParam(key, value)) emit(out, value, 0, key);
  }
  return out.str();
}

EstimatorConfig parseConfigText(const std::string& yaml, const std::string& source) {
  return parseConfig(parseYaml(yaml, source), source);
}

}  // namespace oefmt
