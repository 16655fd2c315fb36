// SPDX-License-Identifier: GPL-3.0-or-later
#include "parameter_doc.h"

#include <sstream>

#include "oefmt/io/config_file.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/ros/node_parameters.h"

namespace oefmt {
namespace {

std::string cell(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string code(const std::string& text) { return "`" + (text.empty() ? std::string("\"\"") : text) + "`"; }

void writeRows(std::ostream& out, const ParameterTable& table, const std::string& section,
               const std::string& prefix) {
  out << "| parameter | type | default | unit | accepted | meaning |\n";
  out << "|---|---|---|---|---|---|\n";
  for (const Parameter& p : table) {
    if (p.section() != section) continue;
    out << "| " << code(prefix + p.key) << " | " << toString(p.type) << " | " << code(p.valueText()) << " | "
        << cell(p.unit) << " | " << cell(p.rule()) << " | " << cell(p.meaning) << " |\n";
  }
}

}  // namespace

std::string parametersMarkdown() {
  EstimatorConfig config;
  const ParameterTable estimator = estimatorParameters(config);
  RosParameters node_parameters;
  const ParameterTable node = nodeParameters(node_parameters);
  std::ostringstream out;
  out << "<!-- Generated from the parameter tables in the code by `oefmt_parameters --markdown`: do not\n"
         "     edit. The unit tests fail when this file differs from what the tables give. -->\n"
         "# Parameters\n"
         "\n"
         "## The configuration file\n"
         "\n"
         "One YAML file holds the estimator's parameters: `oefmt_offline --config FILE` reads it, and\n"
         "`launch/oefmt.launch` loads it (argument `config`) into the node's private namespace, where\n"
         "the node reads it from the parameter server. [config/default.yaml](../config/default.yaml)\n"
         "holds every default (`oefmt_parameters --yaml` writes it). Keys of a section are indented\n"
         "under its name (`registration:` then `  size: 512`); on the parameter server they are\n"
         "`~registration/size`. Missing keys keep their defaults. An unknown key or section, a key\n"
         "given twice, a value of the wrong type or outside the accepted values stops the program with\n"
         "a message naming the file, the line and the key (the node: the parameter).\n"
         "\n"
         "### Where the scale and the camera come from\n"
         "\n"
         "**Initial altitude** (the altitude of the first frame above the dominant plane, which makes\n"
         "the poses metric), first that applies:\n"
         "\n"
         "1. the node with `use_altitude_topic`: the first valid range on the `altitude` topic\n"
         "   (`sensor_msgs/Range`); the odometry waits for it;\n"
         "2. `oefmt_offline --altitude M`;\n"
         "3. the parameter `initial_altitude` (the configuration file; for the node, the launch\n"
         "   argument `initial_altitude` when given, which overrides the file's);\n"
         "4. unknown (`initial_altitude: 0.0`): the poses are in units of the initial altitude.\n"
         "\n"
         "**Focal length.** `camera_fx` is the focal length of the input images in their own pixels;\n"
         "the programs scale the camera to the working image (`registration.size`) in one place, the\n"
         "undistortion set-up, which also maps a calibration made for another resolution. First that\n"
         "applies:\n"
         "\n"
         "1. `oefmt_offline --fx PX`: replaces the calibration's focal length (its principal point and\n"
         "   distortion are kept);\n"
         "2. the calibration that comes with the frames: `cam_param.yaml` in a dataset folder, the\n"
         "   bag's or the camera's `camera_info`;\n"
         "3. the parameter `camera_fx` (the configuration file; for the node, the launch argument\n"
         "   `camera_fx` when given);\n"
         "4. none: `oefmt_offline` assumes a 53 degree field of view (the working image's focal length\n"
         "   equals `registration.size`); the node reports the missing intrinsics and waits.\n";
  for (const ParameterSection& section : estimatorParameterSections()) {
    out << "\n### " << section.title << "\n\n";
    writeRows(out, estimator, section.name, "");
  }
  out << "\n## ROS node parameters\n"
         "\n"
         "The node's own parameters, in its private namespace beside the configuration file's\n"
         "(`~initial_altitude`, `~registration/size`, ...). `launch/oefmt.launch` sets several of\n"
         "them from its arguments of the same names. A private parameter that neither table has is\n"
         "reported and ignored; a bad value of either stops the node, naming the parameter.\n\n";
  writeRows(out, node, "", "~");
  return out.str();
}

std::string defaultConfigYaml() { return configToYaml(EstimatorConfig{}, true); }

}  // namespace oefmt
