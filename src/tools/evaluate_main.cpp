// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_evaluate: compares an estimated trajectory with the ground truth (TUM files): similarity
// alignment, absolute trajectory error, drift per distance, loop error, and an optional plot.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "oefmt/io/dataset.h"
#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/evaluation/evaluation.h"

extern char** environ;

namespace {

const char* const kUsage = R"(usage: oefmt_evaluate [options] ESTIMATE.tum GROUNDTRUTH.tum

Aligns the estimate to the ground truth by least squares (Umeyama; similarity in x-y by default)
and prints the absolute trajectory error (rmse, mean, median, max), the drift (relative position
error per distance travelled, over segments of 10..50 % of the path), the loop error (gap between
the estimate's and the truth's first-to-last displacement) and the errors of the heading steps
(yaw change between consecutive poses) as a table, then one line of JSON.
TUM files: 't x y z qx qy qz qw' per line, '#' comments.

options:
  --match time|index   associate by timestamp (default) or by line index
  --tolerance S        largest time difference of a match [s] (default 0.02)
  --3d                 align and measure in 3-D (default: x-y only)
  --no-scale           rigid alignment (default: with scale, for monocular estimates)
  --segments F,F,...   drift segment lengths as fractions of the path (default 0.1,0.2,0.3,0.4,0.5)
  --heading-threshold DEG  heading steps off by more than this are counted (default 2)
  --plot FILE.png      draw both trajectories (top view) and the error over time
  --title TEXT         plot title
  --aligned FILE.tum   write the aligned, matched estimate
  --json-only          print only the JSON line
  --python EXE         interpreter for the plot (default /usr/bin/python3 if present)
  --plot-script FILE   plot script (default: plot_trajectory.py next to this program, else the
                       source tree's scripts/)
  -h, --help
exit codes: 0 success, 1 unreadable input or too few matches, 2 invalid option, 3 plot failed)";

std::vector<double> fractionList(const std::string& text) {
  const std::vector<double> values = oefmt::tools::numberList("--segments", text);
  for (const double v : values) {
    if (!(v > 0.0 && v <= 1.0)) {
      throw oefmt::InputError("--segments needs fractions in (0, 1] separated by commas, got '" + text + "'");
    }
  }
  return values;
}

std::string defaultPlotScript() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const std::filesystem::path beside = self.parent_path() / "plot_trajectory.py";
    if (std::filesystem::exists(beside)) return beside.string();
  }
  return OEFMT_SOURCE_PLOT_SCRIPT;
}

// Runs a program without a shell (no quoting issues); returns its exit status or -1.
int run(const std::vector<std::string>& command) {
  std::vector<char*> argv;
  for (const std::string& arg : command) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Writes the matched poses as CSV for the plot script.
void writePlotData(const std::string& path, const oefmt::EvaluationResult& result) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw oefmt::DatasetError("cannot write '" + path + "'");
  std::fprintf(file, "t,truth_x,truth_y,truth_z,estimate_x,estimate_y,estimate_z,error\n");
  for (std::size_t k = 0; k < result.errors.size(); ++k) {
    const Eigen::Vector3d& g = result.matched_truth[k].position;
    const Eigen::Vector3d& e = result.aligned_estimate[k].position;
    std::fprintf(file, "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", result.matched_truth[k].stamp, g.x(), g.y(), g.z(),
                 e.x(), e.y(), e.z(), result.errors[k]);
  }
  std::fclose(file);
}

}  // namespace

int main(int argc, char** argv) {
  oefmt::EvaluationOptions options;
  std::string plot, title, aligned_path, python, script;
  bool json_only = false;
  std::vector<std::string> paths;
  try {
    oefmt::tools::Arguments args(argc, argv);
    while (!args.done()) {
      const std::string arg = args.take();
      const auto value = [&]() { return args.value(arg); };
      if (arg == "-h" || arg == "--help") {
        std::puts(kUsage);
        return 0;
      } else if (arg == "--match") {
        const std::string mode = value();
        if (mode != "time" && mode != "index") throw oefmt::InputError("--match must be time or index");
        options.association = mode == "time" ? oefmt::AssociationMode::kTimestamp : oefmt::AssociationMode::kIndex;
      } else if (arg == "--tolerance") {
        options.time_tolerance = args.number(arg);
        if (!(options.time_tolerance >= 0.0)) throw oefmt::InputError("--tolerance needs a number of seconds >= 0");
      } else if (arg == "--3d") {
        options.planar = false;
      } else if (arg == "--no-scale") {
        options.with_scale = false;
      } else if (arg == "--segments") {
        options.drift_segment_fractions = fractionList(value());
      } else if (arg == "--heading-threshold") {
        const double degrees = args.number(arg);
        if (!(degrees > 0.0 && degrees < 180.0)) throw oefmt::InputError("--heading-threshold must be in (0, 180) degrees");
        options.heading_step_threshold = degrees * M_PI / 180.0;
      } else if (arg == "--plot") {
        plot = value();
      } else if (arg == "--title") {
        title = value();
      } else if (arg == "--aligned") {
        aligned_path = value();
      } else if (arg == "--json-only") {
        json_only = true;
      } else if (arg == "--python") {
        python = value();
      } else if (arg == "--plot-script") {
        script = value();
      } else if (!arg.empty() && arg[0] == '-') {
        throw oefmt::InputError("unknown option '" + arg + "' (see --help)");
      } else {
        paths.push_back(arg);
      }
    }
    if (paths.size() != 2) throw oefmt::InputError("expected ESTIMATE.tum and GROUNDTRUTH.tum (see --help)");
  } catch (const oefmt::InputError& e) {
    std::fprintf(stderr, "oefmt_evaluate: %s\n", e.what());
    return 2;
  }

  oefmt::EvaluationResult result;
  try {
    const oefmt::StampedTrajectory estimate = oefmt::readTum(paths[0]);
    const oefmt::StampedTrajectory truth = oefmt::readTum(paths[1]);
    result = oefmt::evaluateTrajectory(estimate, truth, options);
    if (!aligned_path.empty()) {
      oefmt::writeTum(aligned_path, result.aligned_estimate, {"estimate of " + paths[0] + " aligned to " + paths[1]});
    }
  } catch (const std::exception& e) {  // DatasetError, InputError (too few matches)
    std::fprintf(stderr, "oefmt_evaluate: %s\n", e.what());
    if (options.association == oefmt::AssociationMode::kTimestamp) {
      std::fprintf(stderr, "oefmt_evaluate: (if the files' stamps differ, try --match index or a larger --tolerance)\n");
    }
    return 1;
  }
  if (!json_only) {
    std::printf("%s vs %s\n%s", paths[0].c_str(), paths[1].c_str(), oefmt::evaluationTable(result, options).c_str());
  }
  std::printf("%s\n", oefmt::evaluationJson(result, options).c_str());
  std::fflush(stdout);

  if (plot.empty()) return 0;
  if (python.empty()) python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  if (script.empty()) script = defaultPlotScript();
  const std::string data = plot + ".csv";
  try {
    writePlotData(data, result);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "oefmt_evaluate: %s\n", e.what());
    return 3;
  }
  std::vector<std::string> command = {python, script, data, plot};
  if (!title.empty()) command.insert(command.end(), {"--title", title});
  const int status = run(command);
  std::remove(data.c_str());
  if (status != 0) {
    std::fprintf(stderr, "oefmt_evaluate: plotting failed (%s %s exited with %d); python3-matplotlib installed?\n",
                 python.c_str(), script.c_str(), status);
    return 3;
  }
  if (!json_only) std::printf("plot        %s\n", plot.c_str());
  return 0;
}
