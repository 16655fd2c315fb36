// SPDX-License-Identifier: GPL-3.0-or-later
// EstimatorConfig: YAML loading, validation and config/default.yaml.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/io/yaml_text.h"

namespace oefmt {
namespace {

namespace fs = std::filesystem;

// The package root, from this file's path (test/unit/...).
fs::path packageRoot() { return fs::path(__FILE__).parent_path().parent_path().parent_path(); }

// Writes `text` to a fresh temporary YAML file and returns its path.
std::string writeYaml(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("oefmt_test_" + name + ".yaml");
  std::ofstream(path) << text;
  return path.string();
}

std::string errorOf(const std::string& yaml) {
  try {
    loadConfig(writeYaml("error", yaml));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(EstimatorConfig, DefaultYamlHoldsEveryDefault) {
  const EstimatorConfig loaded = loadConfig((packageRoot() / "config" / "default.yaml").string());
  EXPECT_EQ(configToYaml(loaded), configToYaml(EstimatorConfig{}));
}

TEST(EstimatorConfig, DefaultYamlDocumentsEveryKey) {
  std::ifstream file(packageRoot() / "config" / "default.yaml");
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::istringstream keys(configToYaml(EstimatorConfig{}));
  std::string line;
  while (std::getline(keys, line)) {
    const auto colon = line.find(':');
    if (line.empty() || line[0] == '%' || line[0] == '-' || colon == std::string::npos) continue;
    // Each key's line is preceded by its comment line.
    const std::string key_line = line.substr(0, colon + 1);
    const auto at = text.find("\n" + key_line);
    ASSERT_NE(at, std::string::npos) << key_line;
    const auto previous_line_start = text.rfind('\n', at - 1);
    EXPECT_NE(text.substr(previous_line_start + 1, at - previous_line_start).find('#'), std::string::npos)
        << "no comment above " << key_line;
  }
}

TEST(EstimatorConfig, RoundTripThroughYaml) {
  EstimatorConfig config;
  config.mode = EstimatorMode::kEfmt;
  config.altitude = 62.8;
  config.fx = 373.5;
  config.registration.size = 256;
  config.registration.resolve_half_turn = false;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.matching.shift_step = 0.02;
  config.optimizer.robust_loss = RobustLoss::kHuber;
  config.optimizer.function_tolerance = 1e-7;
  config.tracking.predict_failed_frames = false;
  config.efmt.zoom_samples = 3;
  const EstimatorConfig loaded = loadConfig(writeYaml("roundtrip", configToYaml(config)));
  EXPECT_EQ(configToYaml(loaded), configToYaml(config));
  EXPECT_EQ(loaded.mode, EstimatorMode::kEfmt);
  EXPECT_DOUBLE_EQ(loaded.optimizer.function_tolerance, 1e-7);
}

TEST(EstimatorConfig, MissingKeysKeepTheirDefaults) {
  const EstimatorConfig c =
      loadConfig(writeYaml("partial", "%YAML:1.0\nmode: fmt\nregistration:\n  size: 256\n"));
  EXPECT_EQ(c.mode, EstimatorMode::kFmt);
  EXPECT_EQ(c.registration.size, 256);
  EXPECT_DOUBLE_EQ(c.registration.taper_fraction, 0.12);
  EXPECT_EQ(c.tracking.max_failed_frames, 3);
}

TEST(EstimatorConfig, AcceptsCommonSpellings) {
  const EstimatorConfig c = loadConfig(writeYaml(
      "spellings", "%YAML:1.0\noptimizer:\n  function_tolerance: 1e-7\n"
                   "tracking:\n  predict_failed_frames: false\nregistration:\n  resolve_half_turn: 0\n"));
  EXPECT_DOUBLE_EQ(c.optimizer.function_tolerance, 1e-7);
  EXPECT_FALSE(c.tracking.predict_failed_frames);
  EXPECT_FALSE(c.registration.resolve_half_turn);
}

TEST(EstimatorConfig, EveryFftPlanningEffortRoundTrips) {
  for (const FftPlanning planning : {FftPlanning::kEstimate, FftPlanning::kMeasure, FftPlanning::kPatient}) {
    EstimatorConfig config;
    config.registration.fft_planning = planning;
    const EstimatorConfig loaded = loadConfig(writeYaml("planning", configToYaml(config)));
    EXPECT_EQ(loaded.registration.fft_planning, planning) << toString(planning);
  }
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  fft_planning: exhaustive\n").find("estimate, measure or patient"),
            std::string::npos);
}

TEST(EstimatorConfig, ErrorsNameTheKey) {
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  sise: 512\n").find("registration.sise"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nmode: slam\n").find("'mode'"), std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  size: 300.5\n").find("registration.size"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  size: 3\n").find("'size'"), std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\naltitude: -5.0\n").find("'altitude'"), std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\noptimizer:\n  robust_loss: tukey\n").find("optimizer.robust_loss"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\ntracking:\n  predict_failed_frames: maybe\n")
                .find("tracking.predict_failed_frames"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nlocal_optimizer:\n  max_iterations: 5\n").find("local_optimizer"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nmatching:\n  shift_step: abc\n").find("matching.shift_step"),
            std::string::npos);
  // The parameters added for dense multi-depth scenes: out-of-range values are refused by name.
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  rotation_zoom_candidates: 0\n").find("'rotation_zoom_candidates'"),
            std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\ntracking:\n  steady_layer_min_fraction: 1.5\n").find("'steady_layer_min_fraction'"),
            std::string::npos);
  // A number with a unit after it, and one beyond float range (strtod: ERANGE).
  EXPECT_NE(errorOf("%YAML:1.0\naltitude: 12m\n").find("'altitude'"), std::string::npos);
  EXPECT_NE(errorOf("%YAML:1.0\nregistration:\n  min_texture: 1e-400\n").find("registration.min_texture"),
            std::string::npos);
}

TEST(EstimatorConfig, UnreadableFilesAreInputErrors) {
  EXPECT_THROW(loadConfig("/nonexistent/oefmt.yaml"), InputError);
  EXPECT_THROW(loadConfig(writeYaml("garbage", "this is: [not closed\n")), InputError);
}

TEST(EstimatorConfig, ScaleHelpers) {
  EstimatorConfig c;
  EXPECT_DOUBLE_EQ(c.effectiveFx(), 512.0);
  EXPECT_DOUBLE_EQ(c.initialAltitude(), 1.0);
  c.fx = 400.0;
  c.altitude = 50.0;
  EXPECT_DOUBLE_EQ(c.effectiveFx(), 400.0);
  EXPECT_DOUBLE_EQ(c.initialAltitude(), 50.0);
  EXPECT_EQ(parseEnum(kEstimatorModeNames, "efmt", "mode"), EstimatorMode::kEfmt);
  EXPECT_STREQ(toString(EstimatorMode::kOefmt), "oefmt");
  EXPECT_THROW(parseEnum(kEstimatorModeNames, "OEFMT", "mode"), InputError);
}

}  // namespace
}  // namespace oefmt

namespace oefmt {
namespace {

// What OpenCV's YAML reader would hang or overflow its stack on is refused before parsing.
TEST(YamlText, DeepNestingHugeFilesAndNulBytesAreRefused) {
  EXPECT_NO_THROW(checkYamlText("%YAML:1.0\nmode: oefmt\nregistration:\n  size: 512\n", "f"));
  EXPECT_NO_THROW(checkYamlText("a: [1, [2, 3], {b: 4}]  # [[[[ in a comment\nc: \"[[[[\"\n", "f"));
  const auto message = [](const std::string& text) {
    try {
      checkYamlText(text, "file 'x.yaml'");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("a: " + std::string(100000, '[')).find("nests"), std::string::npos);
  EXPECT_NE(message("a: " + std::string(100, '{')).find("line 1"), std::string::npos);
  std::string indented = "a:\n";
  for (int level = 1; level <= 70; ++level) indented += std::string(level, ' ') + "k:\n";
  EXPECT_NE(message(indented).find("nests"), std::string::npos);
  std::string dashes;
  for (int i = 0; i < 40; ++i) dashes += "- ";
  EXPECT_NE(message(dashes + "x\n").find("nests"), std::string::npos);
  EXPECT_NE(message(std::string("a: 1\n") + '\0').find("NUL"), std::string::npos);
  EXPECT_NE(message(std::string(kMaxYamlBytes + 1, '#')).find("bytes"), std::string::npos);
  EXPECT_NE(message("a: [").find("accepted"), std::string::npos) << "OpenCV's to refuse";
}

TEST(YamlText, LoadConfigRefusesADeeplyNestedFileWithoutParsingIt) {
  const std::string path = ::testing::TempDir() + "/oefmt_deep.yaml";
  std::ofstream(path) << "%YAML:1.0\nmode: " << std::string(200000, '[') << "\n";
  try {
    loadConfig(path);
    FAIL() << "a 200000-deep file was parsed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("oefmt_deep.yaml"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace oefmt
