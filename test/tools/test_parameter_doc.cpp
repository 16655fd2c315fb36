// SPDX-License-Identifier: GPL-3.0-or-later
// doc/parameters.md is what the parameter tables in the code give (oefmt_parameters --markdown),
// and the ROS node's parameters are read through their table.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"
#include "support/package_files.h"
#include "oefmt/ros/node_parameters.h"
#include "oefmt/ros/parameter_server.h"
#include "parameter_doc.h"

namespace oefmt {
namespace {

namespace fs = std::filesystem;

using test::packageRoot;
using test::readFile;

TEST(ParameterDoc, DocParametersMdIsTheGeneratedOne) {
  EXPECT_EQ(readFile(packageRoot() / "doc" / "parameters.md"), parametersMarkdown())
      << "doc/parameters.md is not what the parameter tables give: regenerate it with\n"
         "  rosrun oefmt oefmt_parameters --markdown > doc/parameters.md";
}

TEST(ParameterDoc, EveryParameterHasARow) {
  const std::string doc = parametersMarkdown();
  EstimatorConfig config;
  for (const Parameter& p : estimatorParameters(config)) {
    EXPECT_NE(doc.find("| `" + p.key + "` |"), std::string::npos) << p.key;
  }
  RosParameters parameters;
  for (const Parameter& p : nodeParameters(parameters)) {
    EXPECT_NE(doc.find("| `~" + p.key + "` |"), std::string::npos) << p.key;
  }
}

TEST(NodeParameters, TheTableChecksTheNodesParameters) {
  RosParameters defaults;
  EXPECT_NO_THROW(defaults.validate());
  std::set<std::string> keys;
  EstimatorConfig config;
  for (const Parameter& p : estimatorParameters(config)) keys.insert(p.key);
  for (const Parameter& p : nodeParameters(defaults)) {
    EXPECT_TRUE(keys.insert(p.key).second) << p.key << ": the node and the file share one namespace";
    EXPECT_FALSE(p.meaning.empty()) << p.key;
  }
  const auto message = [](RosParameters p) {
    try {
      p.validate();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  RosParameters p;
  p.queue_size = 0;
  EXPECT_EQ(message(p), "invalid parameter 'queue_size': must be in [1, 100], got 0");
  p = RosParameters{};
  p.base_frame = "odom";
  EXPECT_NE(message(p).find("'base_frame': must differ from odom_frame"), std::string::npos);
  p = RosParameters{};
  p.odom_frame = "/odom";
  EXPECT_NE(message(p).find("'odom_frame'"), std::string::npos);
  p = RosParameters{};
  p.max_rate = 0.5;
  EXPECT_NE(message(p).find("'max_rate': must be >= min_rate"), std::string::npos);
  p = RosParameters{};
  p.time_jump_tolerance = 0.0;
  EXPECT_NE(message(p).find("'time_jump_tolerance'"), std::string::npos);
}

// The node's parameters as rosparam loads the configuration file and roslaunch sets the rest.
TEST(ParameterServer, ReadsBothTablesWithTheirChecks) {
  EstimatorConfig config;
  RosParameters node;
  ParameterTable table = estimatorParameters(config);
  const ParameterTable node_table = nodeParameters(node);
  table.insert(table.end(), node_table.begin(), node_table.end());
  XmlRpc::XmlRpcValue all;
  all["mode"] = std::string("efmt");
  all["initial_altitude"] = 12;  // an integer where a number belongs
  all["camera_fx"] = 450.5;
  all["registration"]["size"] = 256;
  all["registration"]["resolve_half_turn"] = false;
  all["tracking"]["max_failed_frames"] = 7.0;  // a whole double where an integer belongs
  all["tracking"]["predict_failed_frames"] = 0;  // 0/1 for a boolean
  all["odom_frame"] = std::string("world");
  all["queue_size"] = 5;
  all["image_transport"] = std::string("raw");  // someone else's
  const std::vector<std::string> others = readParameterValues(all, "/oefmt", table);
  EXPECT_EQ(config.mode, EstimatorMode::kEfmt);
  EXPECT_EQ(config.initial_altitude, 12.0);
  EXPECT_EQ(config.camera_fx, 450.5);
  EXPECT_EQ(config.registration.size, 256);
  EXPECT_FALSE(config.registration.resolve_half_turn);
  EXPECT_EQ(config.tracking.max_failed_frames, 7);
  EXPECT_FALSE(config.tracking.predict_failed_frames);
  EXPECT_EQ(node.odom_frame, "world");
  EXPECT_EQ(node.queue_size, 5);
  EXPECT_EQ(others, std::vector<std::string>{"image_transport"});

  const auto error = [&table](const std::string& key, XmlRpc::XmlRpcValue value,
                              const std::string& section = "") {
    XmlRpc::XmlRpcValue parameters;
    if (section.empty()) {
      parameters[key] = value;
    } else {
      parameters[section][key] = value;
    }
    try {
      readParameterValues(parameters, "/oefmt", table);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error("size", 300.5, "registration"),
            "/oefmt/registration/size: invalid parameter 'registration.size': expected an integer, got 300.5");
  EXPECT_EQ(error("size", 65, "registration"),
            "/oefmt/registration/size: invalid parameter 'registration.size': must be even, >= 64, got 65");
  EXPECT_EQ(error("sise", 512, "registration"), "/oefmt/registration/sise: unknown parameter 'registration.sise'");
  EXPECT_NE(error("mode", std::string("slam")).find("expected oefmt, efmt or fmt, got 'slam'"), std::string::npos);
  EXPECT_NE(error("initial_altitude", std::string("12")).find("'initial_altitude': expected a number"),
            std::string::npos);
  EXPECT_NE(error("publish_tf", 2).find("'publish_tf': expected true or false"), std::string::npos);
  EXPECT_NE(error("odom_frame", 5).find("'odom_frame': expected text"), std::string::npos);
  EXPECT_NE(error("queue_size", 0).find("'queue_size': must be in [1, 100], got 0"), std::string::npos);
  EXPECT_NE(error("registration", 5).find("section 'registration' must be a map"), std::string::npos);
  EXPECT_NE(error("fx", 400.0).find("/oefmt/fx: unknown parameter 'fx' (replaced by camera_fx"), std::string::npos);
  EXPECT_NE(error("altitude", 4.0).find("renamed initial_altitude"), std::string::npos);
}

}  // namespace
}  // namespace oefmt
