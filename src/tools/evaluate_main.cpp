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
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "oefmt/io/dataset.h"
#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/evaluation/evaluation.h"

extern char** environ;

namespace {

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

struct Command {
  oefmt::EvaluationOptions options;
  std::string estimate, truth, plot, title, aligned_path, python, script;
  bool json_only = false;
};

/// Reads the command line into `c`; returns the exit status when the tool is to stop here.
std::optional<int> parse(int argc, char** argv, Command& c) {
  using oefmt::requireInput;
  CLI::App app(R"(Aligns the estimate to the ground truth by least squares (Umeyama; similarity in x-y by default)
and prints the absolute trajectory error (rmse, mean, median, max), the drift (relative position
error per distance travelled, over segments of 10..50 % of the path), the loop error (gap between
the estimate's and the truth's first-to-last displacement) and the errors of the heading steps
(yaw change between consecutive poses) as a table, then one line of JSON.
TUM files: 't x y z qx qy qz qw' per line, '#' comments.)",
               "oefmt_evaluate");
  oefmt::tools::setUpTool(
      app, "exit codes: 0 success, 1 unreadable input or too few matches, 2 invalid option, 3 plot failed");
  app.add_option("ESTIMATE.tum", c.estimate, "estimated trajectory")->type_name("")->required();
  app.add_option("GROUNDTRUTH.tum", c.truth, "ground truth")->type_name("")->required();
  oefmt::tools::addChoice(app, "--match", c.options.association, oefmt::kAssociationModeNames,
                          "associate by timestamp (default) or by line index");
  const CLI::Option* tolerance = oefmt::tools::addNumber(app, "--tolerance", c.options.time_tolerance, "S",
                                                         "largest time difference of a match [s] (default 0.02)");
  app.add_flag_callback("--3d", [&c] { c.options.planar = false; }, "align and measure in 3-D (default: x-y only)");
  app.add_flag_callback("--no-scale", [&c] { c.options.with_scale = false; },
                        "rigid alignment (default: with scale, for monocular estimates)");
  oefmt::tools::addNumberList(app, "--segments", c.options.drift_segment_fractions, "F,F,...",
                              "drift segment lengths as fractions of the path (default 0.1,0.2,0.3,0.4,0.5)");
  app.add_option_function<double>(
         "--heading-threshold",
         [&c](double degrees) {
           requireInput(degrees > 0.0 && degrees < 180.0, "--heading-threshold must be in (0, 180) degrees");
           c.options.heading_step_threshold = degrees * M_PI / 180.0;
         },
         "heading steps off by more than this are counted (default 2)")
      ->type_name("DEG")
      ->check(oefmt::tools::finite());
  app.add_option("--plot", c.plot, "draw both trajectories (top view) and the error over time")->type_name("FILE.png");
  app.add_option("--title", c.title, "plot title")->type_name("TEXT");
  app.add_option("--aligned", c.aligned_path, "write the aligned, matched estimate")->type_name("FILE.tum");
  app.add_flag("--json-only", c.json_only, "print only the JSON line");
  app.add_option("--python", c.python, "interpreter for the plot (default /usr/bin/python3 if present)")
      ->type_name("EXE");
  app.add_option("--plot-script", c.script,
                 "plot script (default: plot_trajectory.py next to this program, else the\n"
                 "source tree's scripts/)")
      ->type_name("FILE");
  app.callback([&c, tolerance] {
    requireInput(tolerance->count() == 0 || c.options.time_tolerance >= 0.0,
                 "--tolerance needs a number of seconds >= 0");
    for (const double v : c.options.drift_segment_fractions) {
      if (!(v > 0.0 && v <= 1.0)) {
        std::ostringstream message;
        message << "--segments needs fractions in (0, 1] separated by commas, got " << v;
        throw oefmt::InputError(message.str());
      }
    }
  });
  return oefmt::tools::parseCommandLine(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  Command command;
  if (const std::optional<int> exit_status = parse(argc, argv, command)) return *exit_status;
  const oefmt::EvaluationOptions& options = command.options;
  oefmt::EvaluationResult result;
  try {
    const oefmt::StampedTrajectory estimate = oefmt::readTum(command.estimate);
    const oefmt::StampedTrajectory truth = oefmt::readTum(command.truth);
    result = oefmt::evaluateTrajectory(estimate, truth, options);
    if (!command.aligned_path.empty()) {
      oefmt::writeTum(command.aligned_path, result.aligned_estimate,
                      {"estimate of " + command.estimate + " aligned to " + command.truth});
    }
  } catch (const std::exception& e) {  // DatasetError, InputError (too few matches)
    std::fprintf(stderr, "oefmt_evaluate: %s\n", e.what());
    if (options.association == oefmt::AssociationMode::kTimestamp) {
      std::fprintf(stderr, "oefmt_evaluate: (if the files' stamps differ, try --match index or a larger --tolerance)\n");
    }
    return 1;
  }
  if (!command.json_only) {
    std::printf("%s vs %s\n%s", command.estimate.c_str(), command.truth.c_str(),
                oefmt::evaluationTable(result, options).c_str());
  }
  std::printf("%s\n", oefmt::evaluationJson(result, options).c_str());
  std::fflush(stdout);

  if (command.plot.empty()) return 0;
  if (command.python.empty()) command.python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  if (command.script.empty()) command.script = defaultPlotScript();
  const std::string data = command.plot + ".csv";
  try {
    writePlotData(data, result);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "oefmt_evaluate: %s\n", e.what());
    return 3;
  }
  std::vector<std::string> plot_command = {command.python, command.script, data, command.plot};
  if (!command.title.empty()) plot_command.insert(plot_command.end(), {"--title", command.title});
  const int status = run(plot_command);
  std::remove(data.c_str());
  if (status != 0) {
    std::fprintf(stderr, "oefmt_evaluate: plotting failed (%s %s exited with %d); python3-matplotlib installed?\n",
                 command.python.c_str(), command.script.c_str(), status);
    return 3;
  }
  if (!command.json_only) std::printf("plot        %s\n", command.plot.c_str());
  return 0;
}
