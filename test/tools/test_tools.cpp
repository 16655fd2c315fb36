// SPDX-License-Identifier: GPL-3.0-or-later
// The command-line tools end to end: simulate -> folder + bag, folder -> bag, evaluate; their
// exit codes and messages for bad input.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "support/package_files.h"
#include "support/temp_dir.h"
#include "oefmt/io/dataset.h"
#include "oefmt/io/tum.h"
#include "oefmt/ros/bag_io.h"

namespace oefmt {
namespace {

using test::TempDir;

struct ToolRun {
  int status = -1;
  std::string out;
  std::string err;
};

using test::readFile;

// Runs `command` (a tool path and arguments, no shell characters) and collects its output.
ToolRun run(const TempDir& dir, const std::string& command) {
  const std::string out = dir / "stdout.txt", err = dir / "stderr.txt";
  const int raw = std::system((command + " >" + out + " 2>" + err + " </dev/null").c_str());
  ToolRun result;
  result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.out = readFile(out);
  result.err = readFile(err);
  return result;
}

// Runs `command` + OPTIONS + `last` for each {OPTIONS, MESSAGE}: exit status 2 (a bad command
// line) and one line on stderr that says MESSAGE.
void expectUsageErrors(const TempDir& dir, const std::string& command, const std::string& last,
                       const std::vector<std::pair<std::string, std::string>>& cases) {
  for (const auto& [options, message] : cases) {
    const ToolRun result = run(dir, command + options + last);
    EXPECT_EQ(result.status, 2) << options;
    EXPECT_NE(result.err.find(message), std::string::npos) << options << ": " << result.err;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  }
}

// A 3-frame 128 x 128 flight in dir/flight (PNG images, ground truth, cam_param.yaml).
void simulateThreeFrames(const TempDir& dir) {
  const ToolRun simulate = run(dir, std::string(OEFMT_SIMULATE) + " --quiet --size 128 --frames 3 --length 5 --seed 4 " +
                                    (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
}

TEST(Tools, SimulateConvertAndEvaluate) {
  TempDir dir;
  const ToolRun simulate = run(dir, std::string(OEFMT_SIMULATE) + " --size 96 --frames 6 --length 15 --seed 3 --bag " +
                                    (dir / "sim.bag") + " " + (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
  EXPECT_NE(simulate.out.find("overlap"), std::string::npos);
  EXPECT_EQ(simulate.err.find('\r'), std::string::npos);  // no progress bar when not a terminal

  const FolderDataset dataset(dir / "flight");
  EXPECT_EQ(dataset.size(), 6u);
  EXPECT_EQ(BagImageReader(dir / "sim.bag").size(), 6u);

  const ToolRun convert = run(dir, std::string(OEFMT_FOLDER_TO_BAG) + " --quiet " + (dir / "flight") + " " + (dir / "conv.bag"));
  ASSERT_EQ(convert.status, 0) << convert.err;
  BagImageReader reader(dir / "conv.bag");
  BagFrame frame;
  ASSERT_TRUE(reader.next(frame));
  EXPECT_EQ(cv::norm(frame.image, dataset.loadImage(0), cv::NORM_INF), 0.0);

  const std::string truth = dir / "flight/groundtruth.tum";
  const ToolRun evaluate = run(dir, std::string(OEFMT_EVALUATE) + " --json-only " + truth + " " + truth);
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  EXPECT_EQ(evaluate.out.rfind("{\"estimate_poses\":6,", 0), 0u) << evaluate.out;
  EXPECT_NE(evaluate.out.find("\"rmse\":0"), std::string::npos) << evaluate.out;
}

// The corpus options: a small flight with every one of them, a spin, and their one-line errors.
TEST(Tools, SimulateCorpusOptions) {
  TempDir dir;
  const std::string simulate = std::string(OEFMT_SIMULATE) + " --size 96 --frames 3 ";
  ToolRun result = run(dir, simulate + "--length 6 --texture-style natural,brick,tiles --contrast 10 --noise-grey 5 "
                                      "--flicker 0.1 --walls --climb -1 --climb-profile hill --track line " +
                                (dir / "varied"));
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_NE(result.out.find("ground natural, 1 brick "), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("rescaled to grey std 10.0"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("walls"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("grey std    of the written frames: mean "), std::string::npos) << result.out;
  EXPECT_EQ(FolderDataset(dir / "varied").size(), 3u);

  // Options are read in order: the later of --size and --width, and of a repeated option, counts.
  result = run(dir, simulate + "--width 80 --size 64 --height 72 --frames 4 --noise-grey 5 --noise 0 --track spin " +
                        (dir / "ordered"));
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_NE(result.out.find("camera      64x72,"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("spin at the origin, 4 frames"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("sensor      noise 0 "), std::string::npos) << result.out;

  result = run(dir, simulate + "--track spin --spin-rate -10 " + (dir / "spin"));
  ASSERT_EQ(result.status, 0) << result.err;
  EXPECT_NE(result.out.find("spin at the origin, 3 frames, yaw 0.0 deg turning -10.00 deg per frame"),
            std::string::npos) << result.out;
  EXPECT_NE(result.out.find("altitude    20.000 m"), std::string::npos) << result.out;

  expectUsageErrors(dir, simulate, " " + (dir / "bad"), {
      {"--track spin --overlap 0.8", "--overlap does not apply to --track spin"},
      {"--track spin --length 10", "--length does not apply to --track spin"},
      {"--track spin --climb 2", "--climb does not apply to --track spin"},
      {"--spin-rate 5", "--spin-rate applies to --track spin only"},
      {"--track spin --spin-rate 200", "--spin-rate must be in (-180, 180) deg"},
      {"--climb-profile ramp", "--climb-profile ramp needs --track line"},
      {"--climb-profile up", "--climb-profile: up not in {ramp,hill}"},
      {"--heading north", "--heading: north not in {fixed,track}"},
      {"--texture-style cells,marble", "--texture-style: unknown texture style 'marble'"},
      {"--contrast 0", "--contrast must be in (0, 127.5]"},
      {"--flicker 1", "--flicker must be in [0, 1)"},
      {"--noise-grey -1", "--noise-grey must be >= 0"},
      {"--track line --altitude 10 --climb -8", "descend less"},
  });
}

TEST(Tools, ExitCodesAndMessages) {
  TempDir dir;
  EXPECT_EQ(run(dir, std::string(OEFMT_SIMULATE) + " --help").status, 0);
  EXPECT_EQ(run(dir, std::string(OEFMT_FOLDER_TO_BAG) + " --help").status, 0);
  EXPECT_EQ(run(dir, std::string(OEFMT_EVALUATE) + " --help").status, 0);

  ToolRun bad = run(dir, std::string(OEFMT_SIMULATE) + " --track square " + (dir / "x"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("unknown track 'square': expected circle, eight, line or spin"), std::string::npos) << bad.err;
  bad = run(dir, std::string(OEFMT_SIMULATE) + " --frames");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--frames: 1 required N missing"), std::string::npos) << bad.err;

  bad = run(dir, std::string(OEFMT_FOLDER_TO_BAG) + " " + (dir / "missing") + " " + (dir / "out.bag"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("missing"), std::string::npos) << bad.err;

  std::ofstream(dir / "a.tum") << "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n";
  std::ofstream(dir / "b.tum") << "5 0 0 0 0 0 0 1\n6 1 0 0 0 0 0 1\n";
  bad = run(dir, std::string(OEFMT_EVALUATE) + " " + (dir / "a.tum") + " " + (dir / "b.tum"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("--match index"), std::string::npos) << bad.err;
  const ToolRun by_index = run(dir, std::string(OEFMT_EVALUATE) + " --match index " + (dir / "a.tum") + " " + (dir / "b.tum"));
  EXPECT_EQ(by_index.status, 0) << by_index.err;
  EXPECT_EQ(run(dir, std::string(OEFMT_EVALUATE) + " --tolerance x a b").status, 2);
  EXPECT_EQ(run(dir, std::string(OEFMT_EVALUATE) + " --match frame a b").status, 2);

  const ToolRun help = run(dir, std::string(OEFMT_OFFLINE) + " --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("--mode oefmt|efmt|fmt"), std::string::npos) << help.out;
  expectUsageErrors(dir, std::string(OEFMT_OFFLINE) + " ", "", {
      {"--output x.tum", "give exactly one of --images and --bag"},
      {"--images a --bag b --output x.tum", "give exactly one of --images and --bag"},
      {"--images a", "--output is required"},
      {"--images a --output x.tum --mode slow", "unknown mode 'slow'"},
      {"--images a --output x.tum --altitude 0", "--altitude must be > 0"},
      {"--images a --output x.tum --max-frames ten", "--max-frames"},
      {"--images a --output x.tum --frames 3", "--frames"},
  });
}

}  // namespace
}  // namespace oefmt

namespace oefmt {
namespace {

// Truncates a file to `bytes` (a PNG cut short by a full disk or a copy that was interrupted).
void truncateFile(const std::string& path, std::size_t bytes) {
  const std::string text = readFile(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(std::min(bytes, text.size())));
}

std::size_t trajectoryLines(const std::string& path) {
  std::ifstream in(path);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') ++lines;
  }
  return lines;
}

// oefmt_offline on a folder whose 6th image is truncated and on a corrupt bag: a message naming
// the file, exit status 1, and the trajectory up to the bad frame kept and valid.
TEST(Tools, OfflineKeepsTheTrajectoryOnBadInput) {
  TempDir dir;
  const ToolRun simulate = run(dir, std::string(OEFMT_SIMULATE) + " --quiet --size 128 --frames 10 --length 25 --seed 4 --bag " +
                                    (dir / "flight.bag") + " " + (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
  const ToolRun good = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") +
                                    " --output " + (dir / "good.tum"));
  ASSERT_EQ(good.status, 0) << good.err;
  EXPECT_EQ(trajectoryLines(dir / "good.tum"), 10u);

  truncateFile(dir / "flight/Images/0006.png", 200);
  const ToolRun bad = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") +
                                   " --output " + (dir / "bad.tum"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("0006.png"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("corrupt or unsupported PNG"), std::string::npos) << bad.err;
  EXPECT_EQ(trajectoryLines(dir / "bad.tum"), 5u);  // frames 0..4, each line complete
  const ToolRun evaluate = run(dir, std::string(OEFMT_EVALUATE) + " --match index --json-only " +
                                        (dir / "bad.tum") + " " + (dir / "flight/groundtruth.tum"));
  EXPECT_EQ(evaluate.status, 0) << evaluate.err;  // the partial file is a valid trajectory

  truncateFile(dir / "flight.bag", 5000);
  const ToolRun corrupt = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --bag " + (dir / "flight.bag") +
                                       " --output " + (dir / "bag.tum"));
  EXPECT_EQ(corrupt.status, 1);
  EXPECT_NE(corrupt.err.find("flight.bag"), std::string::npos) << corrupt.err;

  const ToolRun missing = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "nowhere") +
                                       " --output " + (dir / "none.tum"));
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("nowhere"), std::string::npos) << missing.err;
}

// The poses (x y z qx qy qz qw) of a TUM file, without the stamps.
std::vector<std::vector<double>> poses(const std::string& path) {
  std::vector<std::vector<double>> rows;
  std::istringstream text(readFile(path));
  std::string line;
  while (std::getline(text, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double stamp = 0.0;
    std::vector<double> pose(7);
    fields >> stamp;
    for (double& value : pose) fields >> value;
    rows.push_back(pose);
  }
  return rows;
}

// Largest difference between two trajectories' poses (infinite when their lengths differ).
double largestDifference(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b) {
  if (a.size() != b.size()) return HUGE_VAL;
  double largest = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < a[i].size(); ++j) largest = std::max(largest, std::fabs(a[i][j] - b[i][j]));
  }
  return largest;
}

// A folder's cam_param.yaml and a bag's CameraInfo set up the same undistortion: the same poses
// from both, each run saying what it undoes; --no-undistort takes the frames as they are.
TEST(Tools, OfflineUndistortsFoldersAndBagsAlike) {
  TempDir dir;
  const ToolRun simulate = run(dir, std::string(OEFMT_SIMULATE) + " --quiet --size 128 --track line --frames 6 --length 10 " +
                                    "--seed 4 --k1 -0.2 --k2 0.05 --bag " + (dir / "flight.bag") + " " + (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
  const std::string offline = std::string(OEFMT_OFFLINE) + " --config " + (dir / "size128.yaml");
  std::ofstream(dir / "size128.yaml") << "registration:\n   size: 128\n";
  const ToolRun folder = run(dir, offline + " --images " + (dir / "flight") + " --output " + (dir / "folder.tum"));
  ASSERT_EQ(folder.status, 0) << folder.err;
  EXPECT_NE(folder.err.find("undistorting (cam_param.yaml: k1 -0.2 k2 0.05): 128x128 working frames, fx = fy"), std::string::npos)
      << folder.err;
  const ToolRun bag = run(dir, offline + " --bag " + (dir / "flight.bag") + " --output " + (dir / "bag.tum"));
  ASSERT_EQ(bag.status, 0) << bag.err;
  EXPECT_NE(bag.err.find("undistorting (CameraInfo on /camera/camera_info: k1 -0.2 k2 0.05)"), std::string::npos)
      << bag.err;
  // Equal up to float rounding (FFTW picks its algorithms by timing, per process).
  EXPECT_LT(largestDifference(poses(dir / "folder.tum"), poses(dir / "bag.tum")), 1e-6);
  ASSERT_EQ(poses(dir / "folder.tum").size(), 6u);
  EXPECT_GT(largestDifference({poses(dir / "folder.tum")[1]}, {poses(dir / "folder.tum")[0]}), 0.1);  // it moved

  const ToolRun raw = run(dir, offline + " --no-undistort --images " + (dir / "flight") + " --output " + (dir / "raw.tum"));
  ASSERT_EQ(raw.status, 0) << raw.err;
  EXPECT_EQ(raw.err.find("undistorting"), std::string::npos) << raw.err;
  EXPECT_GT(largestDifference(poses(dir / "raw.tum"), poses(dir / "folder.tum")), 0.1);
}

// The diagnostics file has the documented header and, per frame, the pose the trajectory holds.
TEST(Tools, OfflineDiagnosticsHoldThePosesOfTheTrajectory) {
  TempDir dir;
  const ToolRun simulate = run(dir, std::string(OEFMT_SIMULATE) + " --quiet --size 128 --track line --frames 6 --length 10 " +
                                    "--seed 4 " + (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
  std::ofstream(dir / "size128.yaml") << "registration:\n   size: 128\n";
  const ToolRun offline = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --config " + (dir / "size128.yaml") +
                                       " --images " + (dir / "flight") + " --output " + (dir / "x.tum") +
                                       " --diagnostics " + (dir / "x.csv"));
  ASSERT_EQ(offline.status, 0) << offline.err;
  const ToolRun columns = run(dir, std::string(OEFMT_OFFLINE) + " --diagnostics-columns");
  ASSERT_EQ(columns.status, 0) << columns.err;
  std::istringstream csv(readFile(dir / "x.csv"));
  std::string header;
  ASSERT_TRUE(std::getline(csv, header));
  std::vector<std::string> names;
  std::istringstream fields(header);
  for (std::string name; std::getline(fields, name, ',');) {
    names.push_back(name);
    EXPECT_NE(columns.out.find("| `" + name + "` |"), std::string::npos) << name << " undocumented";
  }
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  ASSERT_LT(column("x"), names.size());
  ASSERT_LT(column("y"), names.size());
  const StampedTrajectory trajectory = readTum(dir / "x.tum");
  ASSERT_EQ(trajectory.size(), 6u);
  std::size_t lines = 0;
  for (std::string line; std::getline(csv, line); ++lines) {
    std::vector<std::string> values;
    std::istringstream cells(line);
    for (std::string value; std::getline(cells, value, ',');) values.push_back(value);
    ASSERT_EQ(values.size(), names.size()) << line;
    ASSERT_LT(lines, trajectory.size());
    EXPECT_NEAR(std::stod(values[column("x")]), trajectory[lines].position.x(), 1e-5) << line;
    EXPECT_NEAR(std::stod(values[column("y")]), trajectory[lines].position.y(), 1e-5) << line;
  }
  EXPECT_EQ(lines, trajectory.size());
  EXPECT_GT(std::fabs(trajectory.back().position.x()) + std::fabs(trajectory.back().position.y()), 0.1);  // it moved
}

// A calibration of another resolution is said in one line; an unusable cam_param.yaml stops the
// run with one line naming the file and the problem (exit status 1).
TEST(Tools, OfflineSaysHowTheCalibrationIsUsedAndRefusesUnusableOnes) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  const std::string yaml = dir / "flight/cam_param.yaml";
  const std::string command = std::string(OEFMT_OFFLINE) + " --images " + (dir / "flight") + " --output " + (dir / "x.tum");
  const std::string quiet = std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") + " --output " + (dir / "x.tum");
  const auto camParam = [&](const std::string& distortion) {
    std::ofstream(yaml) << "%YAML:1.0\nCamera.fx: 2955.7\nCamera.fy: 2949.9\nCamera.cx: 2023.1\n"
                           "Camera.cy: 1510.7\nCamera.width: 4056\nCamera.height: 3040\n"
                        << distortion;
  };
  camParam("");
  const ToolRun authors = run(dir, command);
  ASSERT_EQ(authors.status, 0) << authors.err;
  EXPECT_NE(authors.err.find("oefmt_offline: cam_param.yaml describes a 4056x3040 camera; the 128x128 images are "
                             "taken as its centred 3040x3040 crop resized: fx 124.5 px"),
            std::string::npos)
      << authors.err;
  const auto expectRefused = [&](const std::string& distortion, const std::string& part) {
    camParam(distortion);
    const ToolRun refused = run(dir, quiet);
    EXPECT_EQ(refused.status, 1) << distortion;
    EXPECT_NE(refused.err.find(part), std::string::npos) << refused.err;
    EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  };
  expectRefused("Camera.k1: -5.0\n", "error: cam_param.yaml: lens distortion (k1 -5) cannot be undone");
  expectRefused("Camera.k1: 1e300\nCamera.k2: 1e300\n", "cannot be undone");
  expectRefused("Camera.k2: nan\n", "Camera.k2 is not finite");
  expectRefused("Camera.type: \"KannalaBrandt8\"\n", "Camera.type 'KannalaBrandt8' is not supported");
}

// Frames smaller than registration.size are upscaled, which registers worse: a warning names the
// size to set; with that size, none.
TEST(Tools, OfflineWarnsWhenFramesAreUpscaled) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  const ToolRun upscaled = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") +
                                        " --output " + (dir / "a.tum"));
  EXPECT_EQ(upscaled.status, 0) << upscaled.err;
  EXPECT_NE(upscaled.err.find("upscaled to registration.size 512"), std::string::npos) << upscaled.err;
  EXPECT_NE(upscaled.err.find("at most 128"), std::string::npos) << upscaled.err;
  {
    std::ofstream config(dir / "size128.yaml");
    config << "%YAML:1.0\nregistration:\n  size: 128\n";
  }
  const ToolRun native = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --config " + (dir / "size128.yaml") +
                                      " --images " + (dir / "flight") + " --output " + (dir / "b.tum"));
  EXPECT_EQ(native.status, 0) << native.err;
  EXPECT_EQ(native.err.find("upscaled"), std::string::npos) << native.err;
}

// The first column of a TUM trajectory's poses.
std::vector<double> trajectoryStamps(const std::string& path) {
  std::vector<double> stamps;
  std::istringstream lines(readFile(path));
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line[0] != '#') stamps.push_back(std::stod(line));
  }
  return stamps;
}

// A folder's frames carry its timestamps.txt (the motion model needs the real frame interval);
// a timestamps.txt that cannot be used is said, even with --quiet, and the frames are indexed.
TEST(Tools, OfflineStampsFramesWithTimestampsAndSaysWhenItCannot) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  const std::string offline = std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight");
  const ToolRun stamped = run(dir, offline + " --output " + (dir / "a.tum"));
  ASSERT_EQ(stamped.status, 0) << stamped.err;
  EXPECT_EQ(stamped.err.find("timestamps.txt"), std::string::npos) << stamped.err;
  FolderDataset dataset(dir / "flight");
  ASSERT_TRUE(dataset.hasTimestamps());
  const std::vector<double> stamps = trajectoryStamps(dir / "a.tum");
  ASSERT_EQ(stamps.size(), 3u);
  for (std::size_t k = 0; k < stamps.size(); ++k) EXPECT_NEAR(stamps[k], dataset.timestamp(k), 1e-6) << k;
  EXPECT_GT(stamps[1] - stamps[0], 0.0);
  EXPECT_LT(stamps[1] - stamps[0], 0.9);  // the render's interval, not the index's second

  const std::vector<std::pair<std::string, std::string>> broken = {
      {"1.0\n1.2\n", "it has 2 stamps for 3 images"},
      {"1.0\nsoon\n1.4\n", "line 2 'soon' is not a time"},
      {"1.0\n1.4\n1.2\n", "stamps do not increase at line 3"}};
  for (const auto& [text, message] : broken) {
    {
      std::ofstream file(dir / "flight/timestamps.txt");
      file << text;
    }
    const ToolRun indexed = run(dir, offline + " --output " + (dir / "b.tum"));
    ASSERT_EQ(indexed.status, 0) << indexed.err;
    EXPECT_NE(indexed.err.find("warning: timestamps.txt ignored"), std::string::npos) << indexed.err;
    EXPECT_NE(indexed.err.find(message), std::string::npos) << indexed.err;
    EXPECT_EQ(trajectoryStamps(dir / "b.tum"), (std::vector<double>{0.0, 1.0, 2.0})) << message;
  }
}

// Folders of PNGs (libspng) and of other formats (OpenCV's imgcodecs) alike: decoding goes by
// content, not by the file's name.
TEST(Tools, OfflineReadsPngAndJpegFrames) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  const std::string offline = std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") + " --output ";
  const ToolRun png = run(dir, offline + (dir / "png.tum"));
  ASSERT_EQ(png.status, 0) << png.err;
  EXPECT_EQ(trajectoryLines(dir / "png.tum"), 3u);

  // The same frames as JPEGs, under their .png names.
  for (const char* name : {"0001.png", "0002.png", "0003.png"}) {
    const std::string path = dir / (std::string("flight/Images/") + name);
    std::vector<std::uint8_t> jpeg;
    ASSERT_TRUE(cv::imencode(".jpg", cv::imread(path, cv::IMREAD_UNCHANGED), jpeg));
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  }
  const ToolRun jpeg = run(dir, offline + (dir / "jpeg.tum"));
  ASSERT_EQ(jpeg.status, 0) << jpeg.err;
  EXPECT_EQ(trajectoryLines(dir / "jpeg.tum"), 3u);
}

// A folder of tiny (40 x 30) frames: a clear message with the size, exit status 1.
TEST(Tools, OfflineRefusesTinyFrames) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  for (const char* name : {"0001.png", "0002.png", "0003.png"}) {
    const std::string path = dir / (std::string("flight/Images/") + name);
    ASSERT_TRUE(std::ifstream(path).good()) << path;
    ASSERT_TRUE(cv::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(90))));
  }
  const ToolRun tiny = run(dir, std::string(OEFMT_OFFLINE) + " --quiet --images " + (dir / "flight") +
                                    " --output " + (dir / "tiny.tum"));
  EXPECT_EQ(tiny.status, 1);
  EXPECT_NE(tiny.err.find("0001.png: image of 40x30"), std::string::npos) << tiny.err;
}

// A tilting multirotor's flight (IMU and rangefinder written): levelled by the IMU, the frames
// register as a level camera's, and the rangefinder makes the trajectory metric, from a folder
// and from a bag alike; without them the tilt is read as motion.
TEST(Tools, OfflineLevelsTiltedFramesWithTheImuAndScalesWithTheRangefinder) {
  TempDir dir;
  const ToolRun simulate =
      run(dir, std::string(OEFMT_SIMULATE) + " --quiet --size 256 --track line --frames 40 --length 60 --seed 6 " +
                   "--wobble 8 --wobble-hz 1 --imu --range --bag " + (dir / "flight.bag") + " " + (dir / "flight"));
  ASSERT_EQ(simulate.status, 0) << simulate.err;
  std::ofstream(dir / "size256.yaml") << "registration:\n   size: 256\n";
  const std::string offline = std::string(OEFMT_OFFLINE) + " --config " + (dir / "size256.yaml");
  const ToolRun aided = run(dir, offline + " --images " + (dir / "flight") + " --output " + (dir / "aided.tum"));
  ASSERT_EQ(aided.status, 0) << aided.err;
  EXPECT_NE(aided.err.find("frames levelled with its roll and pitch"), std::string::npos) << aided.err;
  EXPECT_NE(aided.err.find("scale from the rangefinder"), std::string::npos) << aided.err;
  const ToolRun bag = run(dir, offline + " --bag " + (dir / "flight.bag") +
                                   " --imu-topic /imu/data --range-topic /rangefinder/range --output " + (dir / "bag.tum"));
  ASSERT_EQ(bag.status, 0) << bag.err;
  // The same to within the text files' rounding (imu.txt keeps 9 digits of a quaternion).
  EXPECT_LT(largestDifference(poses(dir / "aided.tum"), poses(dir / "bag.tum")), 1e-3);
  const ToolRun unaided = run(dir, offline + " --no-imu --no-range --images " + (dir / "flight") + " --output " +
                                       (dir / "unaided.tum"));
  ASSERT_EQ(unaided.status, 0) << unaided.err;
  // Metric without any alignment of scale (rigid), against the ground truth; and the tilt, read
  // as motion without the IMU, costs many times that.
  const auto ate = [&](const std::string& trajectory, const std::string& options) {
    const ToolRun evaluate = run(dir, std::string(OEFMT_EVALUATE) + " --json-only " + options + " " + trajectory + " " +
                                          (dir / "flight/groundtruth.tum"));
    EXPECT_EQ(evaluate.status, 0) << evaluate.err;
    const auto at = evaluate.out.find("\"rmse\":");
    return at == std::string::npos ? 1e9 : std::stod(evaluate.out.substr(at + 7));
  };
  const double aided_rigid = ate(dir / "aided.tum", "--no-scale");
  EXPECT_LT(aided_rigid, 0.3);
  EXPECT_GT(ate(dir / "unaided.tum", ""), 5.0 * aided_rigid);
  // The trajectory carries the IMU's roll and pitch: not level (the wobble is up to 8 degrees).
  double largest_tilt = 0.0;
  for (const StampedPose& pose : readTum(dir / "aided.tum")) {
    largest_tilt = std::max({largest_tilt, std::fabs(pose.orientation.x()), std::fabs(pose.orientation.y())});
  }
  EXPECT_GT(largest_tilt, 0.02);

  // Bad vehicle data stops the run with one line naming it (exit status 1).
  const auto expectRefused = [&](const std::string& arguments, const std::string& message) {
    const ToolRun refused = run(dir, offline + " --quiet " + arguments + " --output " + (dir / "refused.tum"));
    EXPECT_EQ(refused.status, 1) << arguments;
    EXPECT_NE(refused.err.find(message), std::string::npos) << arguments << ": " << refused.err;
  };
  expectRefused("--bag " + (dir / "flight.bag") + " --imu-topic /camera/camera_info",
                "/camera/camera_info holds sensor_msgs/CameraInfo, not sensor_msgs/Imu");
  expectRefused("--bag " + (dir / "flight.bag") + " --range-topic /nothing", "has no messages on /nothing");
  std::ofstream(dir / "flight/imu.txt", std::ios::app) << "99 0 0\n";
  expectRefused("--images " + (dir / "flight"), "imu.txt' line ");
}

TEST(Tools, OfflineTakesTheCameraMountInTheImusFrameFromTheBagsTf) {
  // One tilted flight turning with its track, twice: the IMU aligned with the body, and mounted
  // upside down and turned a quarter (its messages in its own frame, its mount on /tf_static).
  // Levelled through the mount, both give the same trajectory; without /tf_static the turned
  // IMU's tilt and turn are other ones.
  TempDir dir;
  const std::string simulate = std::string(OEFMT_SIMULATE) +
                               " --quiet --size 256 --track circle --heading track --frames 30 --length 74 --seed 8 "
                               "--tilt --wobble 8 --wobble-hz 1 --imu ";
  ASSERT_EQ(run(dir, simulate + "--bag " + (dir / "aligned.bag") + " " + (dir / "aligned")).status, 0);
  const ToolRun turned =
      run(dir, simulate + "--imu-mount 180,0,90 --bag " + (dir / "turned.bag") + " " + (dir / "turned"));
  ASSERT_EQ(turned.status, 0) << turned.err;
  std::ofstream(dir / "size256.yaml") << "registration:\n   size: 256\n";
  const std::string offline = std::string(OEFMT_OFFLINE) + " --config " + (dir / "size256.yaml") +
                              " --imu-topic /imu/data --bag ";
  const ToolRun aligned = run(dir, offline + (dir / "aligned.bag") + " --output " + (dir / "aligned.tum"));
  ASSERT_EQ(aligned.status, 0) << aligned.err;
  const ToolRun mounted = run(dir, offline + (dir / "turned.bag") + " --output " + (dir / "turned.tum"));
  ASSERT_EQ(mounted.status, 0) << mounted.err;
  EXPECT_NE(mounted.err.find("camera mount from /tf_static: camera_optical in the IMU's imu_link"), std::string::npos)
      << mounted.err;
  EXPECT_LT(largestDifference(poses(dir / "aligned.tum"), poses(dir / "turned.tum")), 1e-6);
  // Levelled, and turning with the track (the gyro's turn is each pair's predicted rotation):
  // accurate against the ground truth.
  const ToolRun evaluate = run(dir, std::string(OEFMT_EVALUATE) + " --json-only " + (dir / "turned.tum") + " " +
                                        (dir / "turned/groundtruth.tum"));
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  const auto rmse = evaluate.out.find("\"rmse\":");
  ASSERT_NE(rmse, std::string::npos) << evaluate.out;
  EXPECT_LT(std::stod(evaluate.out.substr(rmse + 7)), 0.3) << evaluate.out;
  // The same bag without its /tf_static: said, and the frames levelled with a wrong tilt.
  ASSERT_EQ(run(dir, "rosbag filter " + (dir / "turned.bag") + " " + (dir / "untold.bag") +
                         " \"topic != '/tf_static'\"").status,
            0);
  const ToolRun untold = run(dir, offline + (dir / "untold.bag") + " --output " + (dir / "untold.tum"));
  ASSERT_EQ(untold.status, 0) << untold.err;
  EXPECT_NE(untold.err.find("no camera mount in the IMU's frame (imu_link -> camera_optical: the bag has no "
                            "/tf_static): the IMU's frame is taken as the camera body"),
            std::string::npos)
      << untold.err;
  EXPECT_GT(largestDifference(poses(dir / "aligned.tum"), poses(dir / "untold.tum")), 0.05);
}

// scripts/measure_speed.py: a line with the figures of each run, the summaries, and a clear
// error when there is no oefmt_offline to run.
TEST(Tools, MeasureSpeedReportsEveryRun) {
  TempDir dir;
  ASSERT_NO_FATAL_FAILURE(simulateThreeFrames(dir));
  const std::string script = std::string("python3 ") + OEFMT_MEASURE_SPEED;
  const ToolRun speed = run(dir, script + " --offline " + OEFMT_OFFLINE + " --runs 2 --images " +
                                     (dir / "flight"));
  ASSERT_EQ(speed.status, 0) << speed.err;
  for (const char* expected : {"run 1: ", "run 2: ", "ms per frame (3 frames), CPU ", "peak memory ",
                               "all runs: 2 runs, median ", "runs with steal below 2 %: "}) {
    EXPECT_NE(speed.out.find(expected), std::string::npos) << expected << " in\n" << speed.out;
  }
  EXPECT_EQ(speed.out.find("run 3: "), std::string::npos) << speed.out;

  const ToolRun missing = run(dir, script + " --offline " + (dir / "none") + " --images " + (dir / "flight"));
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.err.find("no executable oefmt_offline at " + (dir / "none")), std::string::npos)
      << missing.err;

  // A run that fails: its exit status and oefmt_offline's own message, no Python traceback.
  const ToolRun failed = run(dir, script + " --offline " + OEFMT_OFFLINE + " --images " + (dir / "nowhere"));
  EXPECT_NE(failed.status, 0);
  EXPECT_NE(failed.err.find("measure_speed: oefmt_offline failed (exit status "), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find("nowhere"), std::string::npos) << failed.err;
  EXPECT_EQ(failed.err.find("Traceback"), std::string::npos) << failed.err;
}

// scripts/generalization_benchmark.py --periodic-seeds: the periodic kinds on the seeds asked
// for (in --subset periodic, and among the flights --flights names), and a usage error naming the
// option for anything else.
TEST(Tools, GeneralizationBenchmarkTakesOtherPeriodicSeeds) {
  TempDir dir;
  const std::string script = std::string("python3 ") + OEFMT_GENERALIZATION_BENCHMARK + " --work " + (dir / "work");
  const ToolRun listed = run(dir, script + " --subset periodic --periodic-seeds 67-68 --list");
  ASSERT_EQ(listed.status, 0) << listed.err;
  EXPECT_EQ(std::count(listed.out.begin(), listed.out.end(), '\n'), 8) << "four kinds on two seeds:\n" << listed.out;
  for (const char* expected : {"p-circle-brick-67 ", "--seed 67", "p-circle-tiles-68 ", "--seed 68"}) {
    EXPECT_NE(listed.out.find(expected), std::string::npos) << expected << " in\n" << listed.out;
  }
  EXPECT_EQ(listed.out.find("-66 "), std::string::npos) << "not the default seeds:\n" << listed.out;
  const ToolRun by_name =
      run(dir, script + " --periodic-seeds 67-68 --flights p-eight-ov70-brick-67 --list");
  ASSERT_EQ(by_name.status, 0) << by_name.err;
  EXPECT_NE(by_name.out.find("p-eight-ov70-brick-67 "), std::string::npos) << by_name.out;

  for (const auto& [seeds, message] : std::vector<std::pair<std::string, std::string>>{
           {"67", "--periodic-seeds: expected FIRST-LAST (two whole numbers), got '67'"},
           {"a-b", "--periodic-seeds: expected FIRST-LAST (two whole numbers), got 'a-b'"},
           {"70-67", "--periodic-seeds: the first seed 70 is above the last 67"}}) {
    const ToolRun bad = run(dir, script + " --subset periodic --list --periodic-seeds " + seeds);
    EXPECT_EQ(bad.status, 2) << seeds;
    EXPECT_NE(bad.err.find(message), std::string::npos) << bad.err;
    EXPECT_EQ(bad.err.find("Traceback"), std::string::npos) << bad.err;
  }
}

}  // namespace
}  // namespace oefmt
