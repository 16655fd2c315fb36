// SPDX-License-Identifier: GPL-3.0-or-later
// EstimatorConfig: its parameter table, validation and config/default.yaml.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <string>

#include "oefmt/io/config_file.h"
#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"
#include "support/package_files.h"

namespace oefmt {
namespace {

namespace fs = std::filesystem;

using test::packageRoot;
using test::readFile;

TEST(EstimatorConfig, DefaultYamlIsTheGeneratedOne) {
  const fs::path path = packageRoot() / "config" / "default.yaml";
  EXPECT_EQ(readFile(path), configToYaml(EstimatorConfig{}, true))
      << "config/default.yaml is not what the parameter table gives: regenerate it with\n"
         "  rosrun oefmt oefmt_parameters --yaml > config/default.yaml";
  EXPECT_EQ(configToYaml(loadConfig(path.string())), configToYaml(EstimatorConfig{}));
}

TEST(EstimatorConfig, EveryParameterIsDescribedOnce) {
  EstimatorConfig config;
  const ParameterTable table = estimatorParameters(config);
  std::set<std::string> keys;
  std::set<std::string> sections;
  for (const ParameterSection& s : estimatorParameterSections()) sections.insert(s.name);
  for (const Parameter& p : table) {
    EXPECT_TRUE(keys.insert(p.key).second) << p.key << " twice";
    EXPECT_FALSE(p.meaning.empty()) << p.key;
    EXPECT_EQ(p.meaning.find('\n'), std::string::npos) << p.key << ": one line";
    EXPECT_EQ(sections.count(p.section()), 1u) << p.key << ": a section without a heading";
    if (p.type == ParameterType::kNumber || p.type == ParameterType::kInteger) {
      EXPECT_FALSE(p.rule().empty()) << p.key << ": no accepted range";
    }
    EXPECT_TRUE(p.problem().empty()) << p.key << ": the default is refused: " << p.problem();
  }
  // The fields bound are the config's own: setting through the table changes the config.
  findParameter(table, "registration.size")->setNumber(256);
  findParameter(table, "optimizer.robust_loss")->setWord("huber");
  EXPECT_EQ(config.registration.size, 256);
  EXPECT_EQ(config.optimizer.robust_loss, RobustLoss::kHuber);
  EXPECT_EQ(findParameter(table, "working_fx"), nullptr) << "set from the camera, not a parameter";
}

// The accepted values the table documents are the ones enforced, also by the registration's and
// the optimizer's own checks (their libraries run those without the table): at each finite bound
// the value is accepted unless the bound is open, and the nearest value beyond it is refused.
TEST(EstimatorConfig, DocumentedRangesAreTheEnforcedOnes) {
  int bounds_checked = 0;
  const auto accepted = [](const EstimatorConfig& c, const std::string& section) {
    try {
      c.validate();
      if (section == "registration") c.registration.validate();
      if (section == "optimizer") c.optimizer.validate();
      if (section == "matching") c.matching.validate();
      if (section == "tracking") c.tracking.validate();
      if (section == "uncertainty") c.uncertainty.validate();
      if (section == "efmt") c.efmt.validate();
    } catch (const InputError&) {
      return false;
    }
    return true;
  };
  EstimatorConfig reference;
  const std::size_t rows = estimatorParameters(reference).size();
  for (std::size_t row = 0; row < rows; ++row) {
    for (const bool upper : {false, true}) {
      EstimatorConfig c;
      const Parameter p = estimatorParameters(c)[row];
      if (p.type != ParameterType::kNumber && p.type != ParameterType::kInteger) continue;
      const double bound = upper ? p.range.max : p.range.min;
      if (!std::isfinite(bound)) continue;
      const bool open = upper ? p.range.max_open : p.range.min_open;
      const double outward = upper ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
      const auto set = [&](double value) {
        if (p.type == ParameterType::kNumber) *p.number = value;
        else *p.integer = static_cast<int>(value);
      };
      const bool integer = p.type == ParameterType::kInteger;
      set(bound);
      EXPECT_EQ(accepted(c, p.section()), !open) << p.key << " = " << bound;
      set(integer ? bound + (upper ? -(p.range.even ? 2 : 1) : (p.range.even ? 2 : 1))
                  : std::nextafter(bound, -outward));
      EXPECT_TRUE(accepted(c, p.section())) << p.key << " just inside " << bound;
      set(integer ? bound + (upper ? 1 : -1) : std::nextafter(bound, outward));
      EXPECT_FALSE(accepted(c, p.section())) << p.key << " just beyond " << bound;
      ++bounds_checked;
    }
  }
  EXPECT_GT(bounds_checked, 60);
  EstimatorConfig odd;
  odd.registration.size = 66 + 1;
  EXPECT_THROW(odd.registration.validate(), InputError);
  EXPECT_THROW(odd.validate(), InputError);
}

TEST(EstimatorConfig, ValidationNamesTheParameter) {
  const auto message = [](const EstimatorConfig& c) {
    try {
      c.validate();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EstimatorConfig c;
  c.efmt.zoom_samples = 0;
  EXPECT_EQ(message(c), "invalid parameter 'efmt.zoom_samples': must be in [1, 50], got 0");
  c = EstimatorConfig{};
  c.tracking.assumed_altitude = std::nan("");
  EXPECT_NE(message(c).find("'tracking.assumed_altitude'"), std::string::npos);
  c = EstimatorConfig{};
  c.working_fx = -1.0;
  EXPECT_NE(message(c).find("focal length"), std::string::npos);
  EXPECT_NO_THROW(MatchingConfig{}.validate());
}

TEST(EstimatorConfig, ScaleHelpers) {
  EstimatorConfig c;
  EXPECT_DOUBLE_EQ(c.effectiveFx(), 512.0);
  EXPECT_DOUBLE_EQ(c.initialAltitudeOrOne(), 1.0);
  c.working_fx = 400.0;
  c.camera_fx = 3000.0;  // the input images': not the estimator's
  c.initial_altitude = 50.0;
  EXPECT_DOUBLE_EQ(c.effectiveFx(), 400.0);
  EXPECT_DOUBLE_EQ(c.initialAltitudeOrOne(), 50.0);
}

TEST(EnumNames, OneTablePerEnum) {
  EXPECT_STREQ(toString(EstimatorMode::kOefmt), "oefmt");
  EXPECT_EQ(parseEnum(kEstimatorModeNames, "efmt", "mode"), EstimatorMode::kEfmt);
  try {
    parseEnum(kEstimatorModeNames, "OEFMT", "mode");
    FAIL() << "case matters";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown mode 'OEFMT': expected oefmt, efmt or fmt");
  }
  for (const FftPlanning planning : {FftPlanning::kEstimate, FftPlanning::kMeasure, FftPlanning::kPatient}) {
    EXPECT_EQ(parseEnum(kFftPlanningNames, toString(planning), "planning"), planning);
  }
  EXPECT_STREQ(toString(RobustLoss::kCauchy), "cauchy");
  EXPECT_STREQ(toString(static_cast<RobustLoss>(17)), "unknown");
  EXPECT_EQ(wordList({"a"}), "a");
  EXPECT_EQ(wordList({"a", "b"}), "a or b");
}

}  // namespace
}  // namespace oefmt
