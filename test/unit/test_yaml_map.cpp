// SPDX-License-Identifier: GPL-3.0-or-later
// The parameter-file YAML reader: what it takes, what it refuses (with the line), and the
// documents that made OpenCV's reader loop forever.
#include <gtest/gtest.h>

#include <string>

#include "oefmt/error.h"
#include "oefmt/io/yaml_map.h"

namespace oefmt {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseYaml(text, "f.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

// Scalars are numbers only when strtod reads all of the text.
TEST(YamlMap, ScalarsAsNumbers) {
  EXPECT_EQ(yamlNumber("512"), 512.0);
  EXPECT_EQ(yamlNumber("-1.5e-3"), -1.5e-3);
  EXPECT_EQ(yamlNumber(" 7"), 7.0);  // leading blanks, as strtod
  EXPECT_FALSE(yamlNumber(""));
  EXPECT_FALSE(yamlNumber("12m"));
  EXPECT_FALSE(yamlNumber("7 "));
  EXPECT_FALSE(yamlNumber("abc"));
  bool out_of_range = false;
  EXPECT_TRUE(yamlNumber("1e-400", &out_of_range));
  EXPECT_TRUE(out_of_range);
  EXPECT_TRUE(yamlNumber("0.25", &out_of_range));
  EXPECT_FALSE(out_of_range);
}

TEST(YamlMap, NestedMapsScalarsCommentsAndQuotes) {
  const YamlNode root = parseYaml(
      "%YAML 1.0\n---\n# a comment\nmode: oefmt   # trailing comment\n"
      "registration:\n  size: 512\n  fft_planning: 'measure'\n\n"
      "  empty:\nname: \"a # not a comment\"\nquote: 'it''s'\nnegative: -1.5e-3\n...\nignored: [1\n",
      "f.yaml");
  ASSERT_TRUE(root.is_map);
  ASSERT_EQ(root.children.size(), 5u);
  EXPECT_EQ(root.find("mode")->scalar, "oefmt");
  EXPECT_EQ(root.find("mode")->line, 4);
  const YamlNode* registration = root.find("registration");
  ASSERT_TRUE(registration != nullptr && registration->is_map);
  EXPECT_EQ(registration->find("size")->scalar, "512");
  EXPECT_EQ(registration->find("fft_planning")->scalar, "measure");
  EXPECT_TRUE(registration->find("empty")->is_null);
  EXPECT_EQ(root.find("name")->scalar, "a # not a comment");
  EXPECT_EQ(root.find("quote")->scalar, "it's");
  EXPECT_EQ(root.find("negative")->scalar, "-1.5e-3");
  EXPECT_EQ(root.find("ignored"), nullptr) << "after the end marker";
  // The authors' cam_param.yaml style: OpenCV's directive, dotted keys, no final newline.
  const YamlNode camera = parseYaml("%YAML:1.0\n\nCamera.type: \"PinHole\"\nCamera.fx: 2955.7", "c");
  EXPECT_EQ(camera.find("Camera.fx")->scalar, "2955.7");
  EXPECT_EQ(camera.find("Camera.type")->scalar, "PinHole");
  EXPECT_TRUE(parseYaml("", "empty").children.empty());
  // Windows line ends and a tab after the colon.
  const YamlNode windows = parseYaml("a:\t1\r\nb: 2\r\n", "w");
  EXPECT_EQ(windows.find("a")->scalar, "1");
  EXPECT_EQ(windows.find("b")->scalar, "2");
}

TEST(YamlMap, WhatItDoesNotTakeIsRefusedWithTheLine) {
  EXPECT_NE(errorOf("a: 1\n- b\n").find("line 2: a sequence"), std::string::npos);
  EXPECT_NE(errorOf("a: [1, 2]\n").find("line 1: a flow collection"), std::string::npos);
  EXPECT_NE(errorOf("a: {b: 1}\n").find("flow collection"), std::string::npos);
  EXPECT_NE(errorOf("a: &x 1\n").find("anchor"), std::string::npos);
  EXPECT_NE(errorOf("a: *x\n").find("alias"), std::string::npos);
  EXPECT_NE(errorOf("a: !!float 1\n").find("tag"), std::string::npos);
  EXPECT_NE(errorOf("a: |\n  text\n").find("block scalar"), std::string::npos);
  EXPECT_NE(errorOf("a:\n\tb: 1\n").find("line 2: a tab"), std::string::npos);
  EXPECT_NE(errorOf("a: 1\na: 2\n").find("line 2: the key 'a' appears twice"), std::string::npos);
  EXPECT_NE(errorOf("a: 1\n---\nb: 2\n").find("second document"), std::string::npos);
  EXPECT_NE(errorOf("a:\n    b: 1\n  c: 2\n").find("line 3: unexpected indentation"), std::string::npos);
  EXPECT_NE(errorOf("a: \"open\n").find("unterminated"), std::string::npos);
  EXPECT_NE(errorOf("just words\n").find("expected 'key: value'"), std::string::npos);
  EXPECT_NE(errorOf("a: \"x\" y\n").find("text after the quoted value"), std::string::npos);
  std::string deep;
  for (int level = 0; level < 20; ++level) deep += std::string(level, ' ') + "k:\n";
  deep += std::string(20, ' ') + "v: 1\n";
  EXPECT_NE(errorOf(deep).find("nested deeper"), std::string::npos);
  EXPECT_NE(errorOf(std::string("a: 1\n") + '\0').find("NUL"), std::string::npos);
}

// Inputs on which OpenCV 4.6's YAML reader never returned (found by fuzz_cam_param): refused
// here (one pass over the lines: a hang would show as this test's timeout).
TEST(YamlMap, DocumentsThatHungOpenCvAreRefused) {
  const std::string inputs[] = {
      "%YAML:1.0\n e: m\nmd--\n",
      "%YAML 1.0istration:\n  size: m-\n\nmd--oe: efmt\naltitude: 12.5\nregistration:\n"
      "  size: max_faile$_frAmes: ;\n",
      "%YA\x83L\"1A\x83L\"0\"1A\x83L\"1A\x83L\"0\"1A\x83L\"1.0\"1A\x83L\"1......%YAML 1.0\n----\x8f\x9a-.",
  };
  for (const std::string& input : inputs) {
    EXPECT_NE(errorOf(input), "accepted") << input;
  }
}

}  // namespace
}  // namespace oefmt
