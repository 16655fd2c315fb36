// SPDX-License-Identifier: GPL-3.0-or-later
// The YAML files oefmt reads (the configuration file, cam_param.yaml): what they take, what
// they refuse with the line, and inputs that made a YAML reader hang or overflow its stack.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "oefmt/io/config_file.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"

namespace oefmt {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseConfigText(text, "f.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

// Expects `text` refused with a message holding each of `parts`.
void expectRefused(const std::string& text, std::initializer_list<const char*> parts) {
  const std::string message = errorOf(text);
  for (const char* part : parts) EXPECT_NE(message.find(part), std::string::npos) << text << "\n-> " << message;
}

TEST(ConfigFile, ReadsWhatTheFileSays) {
  const EstimatorConfig c = parseConfigText(
      "%YAML 1.0\n---\n# a comment\nmode: efmt   # trailing comment\n"
      "registration:\n  size: 256\n  fft_planning: 'measure'\n\n  taper_fraction:\n"
      "initial_altitude: \"12.5\"\ncamera_fx: 4.5e2\ntracking:\n",
      "f.yaml");
  EXPECT_EQ(c.mode, EstimatorMode::kEfmt);
  EXPECT_EQ(c.registration.size, 256);
  EXPECT_EQ(c.registration.fft_planning, FftPlanning::kMeasure);
  EXPECT_EQ(c.registration.taper_fraction, RegistrationConfig{}.taper_fraction) << "a null value keeps the default";
  EXPECT_EQ(c.initial_altitude, 12.5);
  EXPECT_EQ(c.camera_fx, 450.0);
  // Windows line ends, a tab after the colon, OpenCV's directive, an empty document.
  EXPECT_EQ(parseConfigText("%YAML:1.0\r\nmode:\tfmt\r\nregistration:\r\n  size: 128\r\n", "w").registration.size, 128);
  EXPECT_EQ(parseConfigText("", "empty").registration.size, 512);
  EXPECT_EQ(parseConfigText("# only a comment\n", "comment").mode, EstimatorMode::kOefmt);
}

TEST(ConfigFile, UnknownKeysAndSectionsAreRefusedWithTheLine) {
  expectRefused("mode: oefmt\nregistration:\n  sise: 512\n", {"f.yaml, line 3", "unknown parameter 'registration.sise'"});
  expectRefused("mode: oefmt\nlocal_optimizer:\n  max_iterations: 5\n",
                {"line 2", "unknown parameter section 'local_optimizer'"});
  expectRefused("\n\nmodus: fmt\n", {"line 3", "unknown parameter 'modus'"});
  // Keys that were renamed say so.
  expectRefused("altitude: 12.0\n", {"line 1", "'altitude'", "initial_altitude"});
  expectRefused("fx: 400.0\n", {"line 1", "'fx'", "camera_fx"});
}

TEST(ConfigFile, BadValuesAreRefusedWithTheLineAndTheKey) {
  // number
  expectRefused("registration:\n  size: 256\n  min_texture: abc\n", {"line 3", "registration.min_texture", "a number"});
  expectRefused("initial_altitude: 12m\n", {"line 1", "'initial_altitude'", "a number"});
  expectRefused("camera_fx: -1.5e3e\n", {"line 1", "'camera_fx'", "a number"});
  expectRefused("registration:\n  min_texture: 1e-400\n", {"line 2", "registration.min_texture"});
  // integer
  expectRefused("registration:\n  size: 300.5\n", {"line 2", "registration.size", "an integer"});
  // boolean
  expectRefused("tracking:\n  predict_failed_frames: maybe\n", {"line 2", "tracking.predict_failed_frames", "true or false"});
  // words: the message lists the accepted ones
  expectRefused("mode: slam\n", {"line 1", "'mode'", "oefmt, efmt or fmt"});
  expectRefused("optimizer:\n  robust_loss: tukey\n", {"line 2", "optimizer.robust_loss", "none, huber or cauchy"});
  expectRefused("registration:\n  fft_planning: exhaustive\n", {"line 2", "estimate, measure or patient"});
  // outside the accepted values
  expectRefused("registration:\n  size: 66\n  rotation_zoom_candidates: 0\n",
                {"line 3", "registration.rotation_zoom_candidates", "[1, 10]", "got 0"});
  expectRefused("registration:\n  size: 65\n", {"line 2", "registration.size", "even"});
  expectRefused("initial_altitude: -5.0\n", {"line 1", "'initial_altitude'", ">= 0"});
  expectRefused("tracking:\n  steady_layer_min_fraction: 1.5\n", {"line 2", "tracking.steady_layer_min_fraction"});
  expectRefused("camera_fx: .nan\n", {"line 1", "camera_fx"});
  // a map or a sequence where a value belongs
  expectRefused("mode:\n  name: oefmt\n", {"line 1", "'mode'", "not a map"});
  expectRefused("initial_altitude: [1, 2]\n", {"line 1", "'initial_altitude'", "not a sequence"});
}

TEST(ConfigFile, DuplicateKeysAreRefusedWithTheLine) {
  expectRefused("mode: fmt\nmode: efmt\n", {"line 2", "'mode' appears twice"});
  expectRefused("registration:\n  size: 256\n  taper_fraction: 0.1\n  size: 128\n", {"line 4", "'size' appears twice"});
  expectRefused("registration:\n  size: 256\nregistration:\n  size: 128\n", {"line 3", "'registration' appears twice"});
}

TEST(ConfigFile, ValuesWhereMapsBelongAreRefused) {
  expectRefused("registration: 512\n", {"line 1", "section 'registration' must be a map"});
  expectRefused("- mode\n- oefmt\n", {"line 1", "expected a map"});
  expectRefused("just words\n", {"expected a map"});
  expectRefused("? [a, b]\n: 1\n", {"line 1", "not a plain word"});
}

TEST(ConfigFile, SyntaxErrorsAndSecondDocumentsAreRefusedWithTheLine) {
  expectRefused("mode: oefmt\nregistration: [1\n", {"line 3"});
  expectRefused("mode: oefmt\n---\nmode: fmt\n", {"line 3", "second document"});
  expectRefused("mode: \"open\n", {"f.yaml"});
}

TEST(ConfigFile, WritesWhatItReadsBack) {
  EstimatorConfig config;
  config.mode = EstimatorMode::kEfmt;
  config.initial_altitude = 62.8;
  config.camera_fx = 373.5;
  config.registration.size = 256;
  config.registration.resolve_half_turn = false;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.matching.shift_step = 0.1 + 0.2;  // no short decimal: must still come back exactly
  config.optimizer.robust_loss = RobustLoss::kHuber;
  config.optimizer.function_tolerance = 1e-7;
  config.tracking.predict_failed_frames = false;
  config.efmt.zoom_samples = 3;
  for (const bool comments : {false, true}) {
    const EstimatorConfig loaded = parseConfigText(configToYaml(config, comments), "written");
    EXPECT_EQ(configToYaml(loaded), configToYaml(config));
    EXPECT_EQ(loaded.mode, EstimatorMode::kEfmt);
    EXPECT_EQ(loaded.matching.shift_step, 0.1 + 0.2);
    EXPECT_EQ(loaded.optimizer.function_tolerance, 1e-7);
  }
  // Numbers keep a dot, which rosparam's YAML reader needs to take them for numbers.
  EXPECT_NE(configToYaml(config).find("function_tolerance: 1.0e-7\n"), std::string::npos) << configToYaml(config);
  EXPECT_NE(configToYaml(config).find("camera_fx: 373.5\n"), std::string::npos);
}

// Text no parameter file holds is refused before the parser sees it.
TEST(ConfigFile, DeepNestingHugeFilesAndNulBytesAreRefused) {
  expectRefused("mode: " + std::string(100000, '['), {"f.yaml", "nests"});
  expectRefused("mode: " + std::string(100, '{'), {"line 1", "nests"});
  std::string indented = "a:\n";
  for (int level = 1; level <= 70; ++level) indented += std::string(level, ' ') + "k:\n";
  expectRefused(indented, {"nests"});
  std::string dashes;
  for (int i = 0; i < 40; ++i) dashes += "- ";
  expectRefused(dashes + "x\n", {"nests"});
  expectRefused(std::string("mode: oefmt\n") + '\0', {"NUL"});
  expectRefused(std::string((std::size_t{1} << 20) + 1, '#'), {"bytes"});
  // Brackets in comments and quotes do not count.
  EXPECT_EQ(errorOf("mode: oefmt  # [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\n"), "accepted");
}

// Documents on which a YAML reader never returned, found by fuzz_cam_param: OpenCV 4.6's reader
// (the first three) and yaml-cpp 0.7's LoadAll, whose parser reports empty documents for ever
// after a stray ',' (the rest). Refused, and at once (a hang would show as this test's timeout);
// so is text that yaml-cpp reads as nothing at all.
TEST(ConfigFile, DocumentsThatHungAYamlReaderAreRefused) {
  const std::string inputs[] = {
      "%YAML:1.0\n e: m\nmd--\n",
      "%YAML 1.0istration:\n  size: m-\n\nmd--oe: efmt\naltitude: 12.5\nregistration:\n"
      "  size: max_faile$_frAmes: ;\n",
      "%YA\x83L\"1A\x83L\"0\"1A\x83L\"1A\x83L\"0\"1A\x83L\"1.0\"1A\x83L\"1......%YAML 1.0\n----\x8f\x9a-.",
      ",",
      "&\",",
      "%YAML 1.0\n,---\nmode: efmt\n",
      "&\"",
  };
  for (const std::string& input : inputs) EXPECT_NE(errorOf(input), "accepted") << input;
}

TEST(ConfigFile, LoadConfigNamesTheFile) {
  const std::string path = ::testing::TempDir() + "/oefmt_config_file.yaml";
  std::ofstream(path) << "%YAML:1.0\nregistration:\n  size: 128\n";
  EXPECT_EQ(loadConfig(path).registration.size, 128);
  std::ofstream(path) << "%YAML:1.0\nmode: " << std::string(200000, '[') << "\n";
  try {
    loadConfig(path);
    FAIL() << "a 200000-deep file was parsed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("oefmt_config_file.yaml"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
  EXPECT_THROW(loadConfig("/nonexistent/oefmt.yaml"), InputError);
}

// cam_param.yaml goes through the same reader: the authors' layout, and its errors with the line.
TEST(ConfigFile, CameraParametersWithTheLine) {
  const std::string path = ::testing::TempDir() + "/oefmt_cam_param.yaml";
  const auto write = [&](const std::string& text) {
    std::ofstream(path, std::ios::trunc) << text;
    return path;
  };
  const CameraParameters camera = readCameraParameters(
      write("%YAML:1.0\n\nCamera.type: \"PinHole\"\nCamera.fx: 2955.7\nCamera.fy: 2950\nCamera.cx: 2028\n"
            "Camera.cy: 1520\nCamera.k1: -0.1\nCamera.fps: 30\nORBextractor.nFeatures: 1000"));
  EXPECT_EQ(camera.intrinsics.fx, 2955.7);
  EXPECT_EQ(camera.distortion.k1, -0.1);
  const auto error = [&](const std::string& text) {
    try {
      readCameraParameters(write(text));
    } catch (const DatasetError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string base = "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 320\n";
  EXPECT_NE(error(base + "Camera.cy: abc\n").find("line 4: Camera.cy is not a number"), std::string::npos);
  EXPECT_NE(error(base + "Camera.cy: 240\nCamera.fx: 400\n").find("line 5: the key 'Camera.fx' appears twice"),
            std::string::npos);
  EXPECT_NE(error(base).find("has no Camera.cy"), std::string::npos);
  EXPECT_NE(error(base + "Camera.cy: 240\nCamera.type: \"KannalaBrandt8\"\n").find("line 5"), std::string::npos);
  EXPECT_NE(error("- Camera.fx\n").find("expected a map"), std::string::npos);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace oefmt
